"""A sweep of both models end to end, in the default suite (small enough: one knot, 20,000
moves a replica, a local Dask cluster of two workers): replicas added until converged, bead
replicas seeded from every tube replica, the bead ensemble judged after its tube ensemble
with the seeded replicas confirming but not certifying, a rerun writing nothing. The longer
sweeps (a worker killed, the order of added replicas, resumption) are in
tests/sweeps/test_sweep_dask.py, marked slow; this one keeps the paths that join the models
under CI (the seeding once shadowed the sweep's seed, caught only by the slow tests)."""

from __future__ import annotations

from stiffknots.store import Store
from stiffknots.sweeps import SweepListener, budget_of, ensemble_converged, parse_models, run_sweep
from stiffknots.sweeps.convergence import SEEDED_START
from stiffknots.sweeps.cross import SEEDED_REPLICA


def test_both_models_add_replicas_seed_every_tube_replica_and_judge_bead_after(tmp_path):
    models = parse_models("bead,tube")
    budget = budget_of("tiny", moves=20_000)
    events: list[tuple] = []

    class Rec(SweepListener):
        def finished(self, job, row, error):
            events.append(("finished", job.id, error))

        def seeded(self, entry):
            events.append(("seeded", entry["knot"], entry["tube_replica"]))

        def added(self, jobs):
            events.append(("added", jobs))

    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["4_1"], models, budget, st, seed=3, workers=2, max_replicas=4,
                        listener=Rec())
        assert not res.failed and not res.interrupted and res.complete
        tube = st.replicas(exclusion="tube")
        bead = st.replicas(exclusion="bead")
        native = sorted(r["replica"] for r in bead if r["start"] != SEEDED_START)
        seeded = sorted(r["replica"] for r in bead if r["start"] == SEEDED_START)
        # every tube replica seeded exactly one bead replica, and the listener heard of each
        assert seeded == sorted(SEEDED_REPLICA + r["replica"] for r in tube)
        assert sorted(e[2] for e in events if e[0] == "seeded") == sorted(
            r["replica"] for r in tube)
        assert len(res.seeded) == len(tube)
        # replicas run 0, 1, … with none skipped; each model stopped converged or at the most
        for rows in (native, sorted(r["replica"] for r in tube)):
            assert rows == list(range(len(rows))) and len(rows) in (2, 4)
        for m, n in zip(models, (len(native), len(tube)), strict=True):
            conv = ensemble_converged(st.states("4_1", m.exclusion, m.beads, m.thickness,
                                                res.settings_hash[m.exclusion]))
            assert conv or n == 4, (m.exclusion, n)
            if n == 4:  # added because the first two (with the seeded ones) had not converged
                assert res.added >= 2
        assert sum(e[1] for e in events if e[0] == "added") == res.added
        # every seeded replica: bead-admissible by its polish, at or below its tube start
        by = {r["replica"]: r for r in tube}
        for r in bead:
            if r["start"] == SEEDED_START:
                src = by[r["replica"] - SEEDED_REPLICA]
                assert r["epsilon"] <= src["epsilon"] + 1e-9
                assert r["settings_hash"] == res.settings_hash["bead"]
        n = st.count()
        res2 = run_sweep(["4_1"], models, budget, st, seed=3, workers=2, max_replicas=4)
        assert (res2.ran, res2.seeded, res2.failed) == (0, [], []) and st.count() == n
