"""The worker pool kept over the rounds of a solve (``problems.pool.WorkerPool``)."""

from __future__ import annotations

import os

import pytest

from stiffknots.problems.pool import WorkerPool, report, run_jobs


def _pid_after_report(k: int) -> tuple[int, int]:
    report({"replica": k, "done": 1, "total": 1})
    return k, os.getpid()


def _many_reports(k: int, n: int) -> int:
    for j in range(n):
        report({"replica": k, "done": j + 1, "total": n})
    return k


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


def test_every_progress_record_reaches_its_own_run():
    """A job's records are in the parent when its result is: none lost at the end of a run,
    none delivered to the next run's callback. (They used to travel by a background thread
    of the worker and sometimes arrived after the result: 12 of 300 such runs lost a record,
    and CI failed on ``test_rounds_run_on_the_same_worker_processes``.)"""
    with WorkerPool(2).start() as pool:
        lost = []
        for run in range(300):
            seen: list[dict] = []
            pool.run(_many_reports, [(0, 1), (1, 1)], on_progress=seen.append)
            if sorted(r["replica"] for r in seen) != [0, 1]:
                lost.append(run)
        seen = []
        pool.run(_many_reports, [(k, 50) for k in range(20)], on_progress=seen.append)
    assert lost == [], f"runs that lost records: {lost}"
    assert len(seen) == 20 * 50 and sorted({r["replica"] for r in seen}) == list(range(20))


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


def test_a_script_without_main_guard_is_told_why_its_workers_died(tmp_path):
    # the README's Python API pasted into a script: spawned workers import it again and die
    import subprocess
    import sys

    script = tmp_path / "my_study.py"
    script.write_text("import stiffknots as sk\n"
                      "res = sk.anneal('3_1', moves=20_000, replicas=2, rounds=1)\n"
                      "print(res.best.epsilon)\n")
    p = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode != 0
    # the main process's last words; a dead worker's multiprocessing resource tracker (another
    # process) may warn of leaked semaphores on the same stderr after them, in its own time
    lines = [ln for ln in p.stderr.strip().splitlines()
             if "resource_tracker" not in ln and "leaked semaphore" not in ln
             and not ln.startswith("  warnings.warn(")]
    last = lines[-1]
    assert "WorkerError" in last and "my_study.py has no `if __name__" in last


def test_a_closed_pool_survives_the_exit_wakeup_of_a_closing_pipe():
    """At exit Python wakes every executor's manager thread without a lock, while the thread
    may be closing that pipe; the pool's close makes that wake-up harmless. The race, made
    certain: the pipe closed under a wake-up that has not seen it close (the unpatched
    wake-up raises OSError here)."""
    pool = WorkerPool(1).start()
    ex = pool._ex  # noqa: SLF001 (the pool's executor)
    wk = ex._executor_manager_thread_wakeup  # noqa: SLF001
    pool.close()
    writer = wk._writer  # noqa: SLF001
    with pytest.raises(OSError):
        type(wk).wakeup(type("W", (), {"_closed": False, "_writer": _closed_pipe()})())
    wk._closed = False  # noqa: SLF001 (as the exit hook can find it mid-close)
    wk._writer = _closed_pipe()  # noqa: SLF001
    wk.wakeup()  # no exception
    wk._writer, wk._closed = writer, True  # noqa: SLF001


def _closed_pipe():
    import multiprocessing as mp

    r, w = mp.Pipe(duplex=False)
    r.close()
    w.close()
    return w


def test_ctrl_c_while_the_pool_stops_stops_it_whole_and_once(monkeypatch):
    """#40 row 5: Ctrl-C during `anneal 4_1` (1 of 6 tries) ended in "AttributeError:
    'NoneType' object has no attribute 'values'" in pool._terminate: an interrupt that fell
    inside the pool's stop left the pool half-stopped (its executor shut down, its workers
    maybe alive), and the next close stopped the shut-down executor again. A Ctrl-C there is
    now raised once the stop is complete, and a pool is stopped once."""
    import contextlib
    import multiprocessing.process as mpp

    import psutil

    pool = WorkerPool(2).start()
    _, interrupted = pool.run(_pid_after_report, [(0,), (1,)])
    assert not interrupted
    workers = [p.pid for p in pool._ex._processes.values()]  # noqa: SLF001
    real = mpp.BaseProcess.terminate
    calls = []

    def ctrl_c_once(proc):  # the Ctrl-C arrives while the first worker is stopped
        calls.append(proc.pid)
        real(proc)
        if len(calls) == 1:
            raise KeyboardInterrupt

    monkeypatch.setattr(mpp.BaseProcess, "terminate", ctrl_c_once)
    try:
        with pytest.raises(KeyboardInterrupt):
            pool.close()
        pool.close()  # as the caller's `with` does next: nothing to stop, no AttributeError
        assert set(calls) == set(workers)
        alive = [pid for pid in workers
                 if psutil.pid_exists(pid) and psutil.Process(pid).status() != "zombie"]
        assert not alive
    finally:  # a worker left alive would hold the test run at its exit
        for pid in workers:
            with contextlib.suppress(psutil.Error):
                psutil.Process(pid).kill()
