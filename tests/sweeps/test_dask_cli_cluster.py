"""A sweep on a cluster started from the command line as on several machines (#39): a
``stiffknots-dask scheduler`` and two workers (``stiffknots-dask worker``, and the line
dask-jobqueue writes in a batch job, ``python -m stiffknots.sweeps.dask_worker``), the atlas pointed
at the scheduler, one worker (nanny and worker process) killed with SIGKILL mid-sweep as a
lost machine is — its job runs again on the other, every replica is stored exactly once."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from stiffknots.store import Store
from stiffknots.sweeps import budget_of, parse_models, plan_sweep

SWEEP = ("--knots", "3_1,4_1", "--models", "bead", "--replicas", "2", "--moves", "2000000")


def _dask(*args, log: Path, module: str = "stiffknots.sweeps.dask_cli") -> subprocess.Popen:
    """``python -m MODULE ARGS`` in its own process group (killed as a whole, as a machine)."""
    return subprocess.Popen([sys.executable, "-m", module, *args],
                            stdout=subprocess.DEVNULL, stderr=open(log, "w"),
                            start_new_session=True)


def _rows(db: Path) -> int:
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return con.execute("SELECT count(*) FROM replicas").fetchone()[0]
    except sqlite3.OperationalError:  # the schema is being created
        return 0


def _wait(cond, what: str, timeout: float = 120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = cond()
        if v:
            return v
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


def _client(address: str):
    from stiffknots.sweeps.cluster import import_distributed

    return import_distributed().Client(address, timeout=30)


def _workers(address: str) -> int:
    with _client(address) as c:
        return len(c.scheduler_info()["workers"])


def _busy_worker_group(address: str) -> int | None:
    """The process group of a worker the scheduler says is running a task, or None."""
    with _client(address) as c:
        busy = [w for w, keys in c.processing().items() if keys]
        if not busy:
            return None
        pid = c.run(os.getpid, workers=busy[:1])[busy[0]]
    return os.getpgid(pid)


@pytest.mark.slow  # a scheduler, two workers and four bead replicas (≈ 1 min)
def test_command_line_cluster_survives_a_killed_worker(tmp_path):
    sf = tmp_path / "scheduler.json"
    procs = [_dask("scheduler", "--scheduler-file", str(sf), "--port", "0",
                   "--no-dashboard", log=tmp_path / "scheduler.log")]
    try:
        address = _wait(lambda: sf.exists() and json.loads(sf.read_text() or "{}")
                        .get("address"), "the scheduler file")
        # one worker as a machine's shell starts it, one as dask-jobqueue's job script does
        # (python -m WORKER_COMMAND SCHEDULER --name --nthreads --memory-limit, extra args)
        procs.append(_dask("worker", "--scheduler-file", str(sf), "--nthreads", "1",
                           "--nworkers", "1", "--no-dashboard", log=tmp_path / "worker0.log"))
        procs.append(_dask(address, "--name", "dummy-name", "--nthreads", "1",
                           "--memory-limit", "4GiB", "--nworkers", "1",
                           module="stiffknots.sweeps.dask_worker",
                           log=tmp_path / "worker1.log"))
        _wait(lambda: _workers(address) == 2, "two workers")
        db = tmp_path / "r.db"
        sweep = subprocess.Popen(
            [sys.executable, "-m", "stiffknots.cli", "atlas", *SWEEP, "--scheduler", str(sf),
             "--db", str(db), "--out", str(tmp_path / "atlas"), "--json"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            # the first replica stored, then a worker running one of the three left
            _wait(lambda: _rows(db) >= 1 or sweep.poll() is not None, "a first row", 400)
            group = _wait(lambda: _busy_worker_group(address), "a busy worker")
            assert sweep.poll() is None and _rows(db) < 4, "the kill came too late"
            lost = next(p for p in procs[1:] if p.pid == group)
            os.killpg(group, signal.SIGKILL)  # its nanny and its worker process at once
            lost.wait(30)
            out, err = sweep.communicate(timeout=600)
        finally:
            if sweep.poll() is None:
                sweep.kill()
        assert sweep.returncode == 0, err[-3000:]
        assert _workers(address) == 1  # the lost worker did not come back
        sw = json.loads(out)["sweep"]
        assert sw["scheduler"] == address and not sw["failed"] and not sw["interrupted"]
        assert sw["ran"] == 4 and sw["written"] == 4
        jobs = plan_sweep(["3_1", "4_1"], parse_models("bead"),
                          budget_of("default", replicas=2, moves=2_000_000), seed=0)
        with Store(db, create=False) as st:
            assert st.keys() == {j.key for j in jobs}
            assert st.count() == 4 and st.check()["ok"]  # every replica stored once
            assert all(r["knot_verified"] for r in st.replicas())
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait(30)


def test_scheduler_option_takes_an_address_or_a_scheduler_file(tmp_path):
    from stiffknots.errors import UserInputError
    from stiffknots.sweeps.cluster import scheduler_address

    f = tmp_path / "scheduler.json"
    f.write_text(json.dumps({"type": "Scheduler", "address": "tcp://10.0.0.7:8786"}))
    assert scheduler_address(str(f)) == "tcp://10.0.0.7:8786"
    assert scheduler_address(" tcp://host:8786 ") == "tcp://host:8786"
    (tmp_path / "other.json").write_text("{}")
    for bad in (str(tmp_path / "other.json"), "not an address", str(tmp_path / "none.json")):
        with pytest.raises(UserInputError):
            scheduler_address(bad)
