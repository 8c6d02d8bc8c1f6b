"""Sweeps on a real Dask LocalCluster (2 worker processes): every replica stored exactly once,
a second run skips everything, a worker killed mid-sweep is replaced and its job rerun with
nothing stored twice. (kill -9 and Ctrl-C of the whole sweep: tests/cli/test_atlas_cli.py.)"""

from __future__ import annotations

import os
import signal
import threading
import time

import psutil
import pytest

from stiffknots.store import Store
from stiffknots.sweeps import SweepListener, budget_of, parse_models, plan_sweep, run_sweep

pytestmark = pytest.mark.slow  # each test starts a Dask cluster and anneals (≈ 20–60 s)


class Recorder(SweepListener):
    def __init__(self, on_progress=None):
        self.events: list[tuple] = []
        self.lock = threading.Lock()
        self.on_progress = on_progress

    def started(self, result):
        self.events.append(("started", result.jobs, result.skipped))

    def cluster(self, description, threads):
        self.events.append(("cluster", threads))

    def progress(self, job, done, total, best=None, pid=None):
        with self.lock:
            self.events.append(("progress", job, done, total, pid))
        if self.on_progress is not None:
            self.on_progress(job, done, total, pid)

    def finished(self, job, row, error):
        self.events.append(("finished", job.id, None if row is None else row["shape"], error))

    def kinds(self, kind):
        return [e for e in self.events if e[0] == kind]


def _assert_stored_once(store, jobs):
    keys = store.keys()
    assert keys == {j.key for j in jobs}
    assert store.count() == len(jobs)  # the UNIQUE key makes a second copy impossible
    assert store.check()["ok"]
    for r in store.replicas():
        assert r["knot_verified"] is True
        assert r["version"] and r["settings"]["problem"] == "anneal"
        assert r["shape"] in ("CB", "4C", "80", "other")
        assert r["start"] in ("braid", "cage", "eighty")
        assert r["extra"]["width"].startswith("bead rule d = 1/√2, N = 150")


def test_sweep_stores_every_replica_once_then_skips(tmp_path):
    models = parse_models("bead")
    budget = budget_of("tiny", moves=100_000)
    knots = ["3_1", "4_1", "5_1"]
    jobs = plan_sweep(knots, models, budget, seed=5)
    with Store(tmp_path / "s.db") as st:
        rec = Recorder()
        res = run_sweep(knots, models, budget, st, seed=5, workers=2, listener=rec)
        assert not res.interrupted and not res.failed
        assert (res.jobs, res.skipped, res.ran, res.written) == (6, 0, 6, 6)
        assert res.workers == 2 and res.complete
        assert rec.kinds("cluster") == [("cluster", 2)]
        assert sorted(e[1] for e in rec.kinds("finished")) == sorted(j.id for j in jobs)
        _assert_stored_once(st, jobs)
        # each row is the problem's replica: its seed derived from (5, replica)
        from stiffknots.engine.driver import replica_seeds

        seeds = replica_seeds(5, 2)
        for r in st.replicas():
            assert r["seed"] == 5 and r["replica_seed"] == seeds[r["replica"]]
        first = {r["id"]: r["epsilon"] for r in st.replicas()}

        rec2 = Recorder()
        t0 = time.perf_counter()
        res2 = run_sweep(knots, models, budget, st, seed=5, workers=2, listener=rec2)
        assert (res2.jobs, res2.skipped, res2.ran, res2.written) == (6, 6, 0, 0)
        assert rec2.kinds("cluster") == []  # nothing to run: no cluster started
        assert time.perf_counter() - t0 < 10
        assert {r["id"]: r["epsilon"] for r in st.replicas()} == first


def test_killed_worker_is_replaced_and_nothing_stored_twice(tmp_path):
    models = parse_models("bead")
    budget = budget_of("tiny", moves=1_500_000)
    knots = ["3_1", "4_1"]
    jobs = plan_sweep(knots, models, budget, seed=0)
    killed: list[tuple[str, int]] = []

    def kill_one(job, done, total, pid):
        # the first progress record of a running job: kill the worker process running it
        if killed or done >= total or pid is None:
            return
        killed.append((job, pid))
        os.kill(pid, signal.SIGKILL)

    with Store(tmp_path / "s.db") as st:
        rec = Recorder(kill_one)
        res = run_sweep(knots, models, budget, st, seed=0, workers=2, listener=rec)
        assert killed, "no worker was killed: the test did not test anything"
        job, pid = killed[0]
        assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == "zombie"
        assert not res.failed and not res.interrupted
        assert (res.ran, res.written) == (4, 4)
        _assert_stored_once(st, jobs)
        # the killed worker's job ran again, in another worker process, from the start
        mine = [e for e in rec.kinds("progress") if e[1] == job]
        assert mine[0][4] == pid
        rerun = [e for e in mine if e[4] != pid]
        assert rerun and rerun[0][2] <= mine[0][2] < rerun[-1][2] == rerun[-1][3]
        assert [e[3] for e in rec.kinds("finished") if e[1] == job] == [None]  # no error


def test_sweep_on_an_existing_scheduler(tmp_path):
    """--scheduler: the client connects to a running cluster (here one started beside it)."""
    from stiffknots.sweeps.cluster import local_cluster

    models = parse_models("tube")
    budget = budget_of("tiny", moves=50_000)
    with local_cluster(1) as cluster, Store(tmp_path / "s.db") as st:
        res = run_sweep(["3_1"], models, budget, st, seed=1,
                        scheduler=cluster.scheduler_address)
        assert res.scheduler == cluster.scheduler_address and res.workers == 1
        assert (res.ran, res.written, res.failed) == (2, 2, [])
        assert {r["exclusion"] for r in st.replicas()} == {"tube"}
        assert {r["thickness"] for r in st.replicas()} == {models[0].thickness}


def test_both_models_seed_a_bead_replica_from_every_tube_replica(tmp_path):
    """With both models at one width the sweep seeds a bead replica from each tube replica
    once the tube ensemble's replicas have ended (stiffknots.sweeps.cross): each joins the
    bead ensemble and lies at or below its tube start; the bead ensemble is judged with them
    (no bead replica added when the seeded ones make it converged); a rerun writes nothing."""
    from stiffknots.analysis import group_states
    from stiffknots.sweeps import is_converged
    from stiffknots.sweeps.cross import SEEDED_REPLICA, SEEDED_START

    models = parse_models("bead,tube")
    budget = budget_of("tiny", moves=50_000)
    rec = Recorder()
    seeded = []
    rec.seeded = seeded.append
    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["3_1"], models, budget, st, seed=2, workers=2, listener=rec,
                        max_replicas=4)
        assert not res.failed and not res.interrupted
        tube = {r["replica"]: r for r in st.replicas(exclusion="tube")}
        assert sorted(e["tube_replica"] for e in res.seeded) == sorted(tube)
        assert seeded == res.seeded
        rows = st.replicas(exclusion="bead")
        seeded_rows = [r for r in rows if r["start"] == SEEDED_START]
        assert sorted(r["replica"] for r in seeded_rows) == sorted(SEEDED_REPLICA + k for k in tube)
        for row in seeded_rows:
            assert row["settings_hash"] == res.settings_hash["bead"]
            src = tube[row["replica"] - SEEDED_REPLICA]
            assert row["extra"]["seeded_from"]["epsilon"] == src["epsilon"]
            assert row["epsilon"] <= src["epsilon"] + 1e-9
        # the bead verdict after its first two replicas counted the seeded ones
        first = [r for r in rows if r["replica"] < 2 or r["start"] == SEEDED_START]
        states = group_states([{"label": r["shape"], "multiplicity": r["multiplicity"],
                                "epsilon": r["epsilon"]} for r in first], 0.01).states
        g = states[0]
        agreed = is_converged({"count": g.count, "epsilon": g.eps_min,
                               "eps_all": [first[k]["epsilon"] for k in g.members]})
        native = [r for r in rows if r["start"] != SEEDED_START]
        assert len(native) == 2 or not agreed, (agreed, len(native))
        n = st.count()
        assert st.check()["ok"]
        res2 = run_sweep(["3_1"], models, budget, st, seed=2, workers=2, max_replicas=4)
        assert (res2.ran, res2.seeded, res2.failed) == (0, [], []) and st.count() == n


def test_a_job_that_cannot_be_built_is_reported_not_stored(tmp_path):
    """8_19 does not fit in 20 beads: its replicas fail (the worker's EmbeddingError), the
    sweep goes on and stores nothing for them."""
    from stiffknots.width import Width

    model = Width.of("bead", parse_models("bead")[0].thickness, 20)
    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["8_19"], [model], budget_of("tiny"), st, workers=1)
        assert len(res.failed) == 2 and res.ran == 0 and not res.interrupted
        assert all("EmbeddingError" in f["error"] for f in res.failed)
        assert st.count() == 0


def test_replicas_added_until_converged(tmp_path):
    """max_replicas: a (knot, model) whose first replicas disagree gets 2 more; one whose
    first replicas agree gets none; the same sweep again runs nothing."""
    from stiffknots.analysis import group_states
    from stiffknots.sweeps import is_converged

    models = parse_models("bead")
    budget = budget_of("tiny")
    with Store(tmp_path / "s.db") as st:
        rec = Recorder()
        rec.added = lambda n: rec.events.append(("added", n))
        rec.expected = lambda n, settled: rec.events.append(("expected", n, settled))
        res = run_sweep(["3_1", "7_4"], models, budget, st, seed=0, workers=2,
                        max_replicas=4, listener=rec)
        assert not res.failed and res.added > 0, "nothing added: the test tested nothing"
        assert res.jobs == 4 + res.added and res.ran == res.jobs and res.max_replicas == 4
        assert sum(e[1] for e in rec.kinds("added")) == res.added
        # the jobs expected: the plan before anything settled, every job run once all settled
        expected = [e[1] for e in rec.kinds("expected")]
        assert expected[0] == 4 and expected[-1] == res.todo == res.ran
        # at the start nothing has settled (the progress bar marks that estimate "≥"); at
        # the end both (knot, model) have
        settled = [e[2] for e in rec.kinds("expected")]
        assert settled[0] == 0 and settled[-1] == 2 and settled == sorted(settled)
        for knot in ("3_1", "7_4"):
            rows = st.replicas(knot=knot)
            first = [{"label": r["shape"], "multiplicity": r["multiplicity"],
                      "epsilon": r["epsilon"]} for r in rows if r["replica"] < 2]
            g = group_states(first, 0.01).states[0]
            agreed = is_converged({"count": g.count, "epsilon": g.eps_min,
                                   "eps_all": [first[k]["epsilon"] for k in g.members]})
            assert len(rows) == (2 if agreed else 4), knot
            assert sorted(r["replica"] for r in rows) == list(range(len(rows)))
            if len(rows) == 4:  # replica 3 started from the lowest of replicas 0 and 1
                by = {r["replica"]: r for r in rows}
                assert by[3]["start"] == min((by[0], by[1]), key=lambda r: r["epsilon"])["start"]
            assert len({r["settings_hash"] for r in rows}) == 1  # one ensemble
        n = st.count()
        res2 = run_sweep(["3_1", "7_4"], models, budget, st, seed=0, workers=2,
                         max_replicas=4)
        assert (res2.ran, res2.workers, st.count()) == (0, 0, n)
        # the added replicas count as stored (or are not needed: the 4 agree by now)
        assert res2.skipped == res2.jobs and res2.jobs in (4, res.jobs)


def test_added_replicas_run_before_later_knots(tmp_path):
    """The knots finish in the order planned: the replicas added to 7_4 (its first two
    disagree at the tiny budget) run before the first replicas of the knots after it, so a
    sweep stopped early has whole answers for the knots it reached."""
    import sqlite3

    models = parse_models("bead")
    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["7_4", "3_1", "5_1", "5_2"], models, budget_of("tiny"), st, seed=0,
                        workers=1, max_replicas=4)
        assert not res.failed and res.added > 0, "nothing added: the test tested nothing"
    con = sqlite3.connect(tmp_path / "s.db")
    order = list(con.execute("SELECT knot, replica FROM replicas ORDER BY rowid"))
    con.close()
    # 4 jobs are submitted at a time (7_4 r0, r1, 3_1 r0, r1); 7_4 r0 ends → 5_1 r0 is
    # submitted; 7_4 r1 ends → 7_4's added replicas go first, ahead of 5_1 r1 and 5_2 (they
    # went after them, at the end of the plan, before)
    assert order.index(("7_4", 2)) < order.index(("5_1", 1)), order
    assert order.index(("7_4", 3)) < order.index(("5_2", 0)), order
