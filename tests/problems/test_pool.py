"""The worker pool kept over the rounds of a solve (``problems.pool.WorkerPool``)."""

from __future__ import annotations

import os

import pytest

from stiffknots.problems.pool import WorkerPool, report, run_jobs


def _pid_after_report(k: int) -> tuple[int, int]:
    report({"replica": k, "done": 1, "total": 1})
    return k, os.getpid()


def _fail(k: int) -> int:
    raise ValueError(f"job {k} failed")


def test_rounds_run_on_the_same_worker_processes():
    seen: list[dict] = []
    with WorkerPool(2).start() as pool:
        first, stopped = pool.run(_pid_after_report, [(0,), (1,)], on_progress=seen.append)
        assert not stopped and sorted(k for k, _ in first) == [0, 1]
        pids = {p for _, p in first}
        assert os.getpid() not in pids
        second, _ = run_jobs(_pid_after_report, [(2,), (3,), (4,)], 2, pool=pool)
        workers = set(pool._ex._processes)  # noqa: SLF001 (the pool's own processes)
        assert {p for _, p in second} <= workers and pids <= workers and len(workers) == 2
    assert pool.dead and pool._ex is None  # noqa: SLF001
    assert sorted(r["replica"] for r in seen) == [0, 1]  # progress records reached the parent


def test_a_failed_job_stops_the_pool():
    pool = WorkerPool(2)
    with pytest.raises(ValueError, match="job 1 failed"):
        pool.run(_fail, [(1,)])
    assert pool.dead
    with pytest.raises(RuntimeError, match="stopped"):
        pool.run(_pid_after_report, [(0,)])


def test_solve_keeps_one_pool_over_its_rounds():
    """Three rounds of a knot that cannot converge on 20,000 moves, on a pool started before
    the problem was built: every replica is verified, the pool's two processes stay."""
    from stiffknots.problems.base import solve
    from stiffknots.problems.closed import ClosedAnneal

    with WorkerPool(2).start() as pool:
        before = set(pool._ex._processes)  # noqa: SLF001
        problem = ClosedAnneal("7_4", moves=20_000, replicas=2, rounds=3, polish=False)
        res = solve(problem, pool=pool, isolate=True)
        assert set(pool._ex._processes) == before  # noqa: SLF001
    assert res.rounds == 3 and len(res.replicas) == 6
    assert all(r.knot_verified for r in res.replicas)
