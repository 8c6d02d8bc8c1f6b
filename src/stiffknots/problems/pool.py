"""Independent replicas on all cores (spawned worker processes): Ctrl-C safe, no orphans, live
progress.

A job is a picklable top-level function; each call returns one result. Guarantees:

* **Ctrl-C** reaches the parent only (the workers ignore SIGINT, and hold it blocked from their
  very start until they ignore it): the finished results are kept,
  the running workers are terminated at once (no traceback from a worker, no CPU left
  burning), and the caller learns that the run was interrupted.
* **The parent killed** (``kill -9``): every worker asks the kernel to kill it when its parent
  dies (Linux ``PR_SET_PDEATHSIG``) and, where that is not available, a watchdog thread exits
  the worker within a second of the parent's death.
* **Progress**: a job may call :func:`report` with a small dict (e.g. moves done, best ε); the
  parent's ``on_progress`` receives it while the jobs run.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from stiffknots.errors import WorkerError

_PROGRESS: Callable[[dict], None] | None = None  # set in workers (and in-process runs)


def report(info: dict) -> None:
    """Send a progress record of the running job to the parent (no-op if nobody listens)."""
    if _PROGRESS is not None:
        with contextlib.suppress(Exception):
            _PROGRESS(info)


@contextlib.contextmanager
def reporting_to(callback: Callable[[dict], None] | None):
    """Send the progress records of the jobs run in this process (:func:`report`) to
    ``callback`` while the block runs (e.g. a Dask worker forwarding them to its client)."""
    global _PROGRESS
    old, _PROGRESS = _PROGRESS, callback
    try:
        yield
    finally:
        _PROGRESS = old


def _die_with_parent(parent: int) -> None:
    """Make this process exit when the parent ``parent`` dies."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:  # died before prctl took effect
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(1.0)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


@contextlib.contextmanager
def _ctrl_c_held():
    """Hold Ctrl-C back (SIGINT blocked in this thread) while worker processes are spawned.

    The workers inherit the blocked signal, so that a Ctrl-C to the process group cannot reach
    a worker before its initializer ignores it (a worker still importing printed a
    KeyboardInterrupt traceback); a Ctrl-C meanwhile is delivered here afterwards, not lost.
    CPython's resource tracker starts the same way.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _worker_init(parent: int, progress_queue) -> None:
    global _PROGRESS
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business
    if hasattr(signal, "pthread_sigmask"):  # blocked since the spawn (_ctrl_c_held)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    _die_with_parent(parent)
    if progress_queue is not None:
        _PROGRESS = progress_queue.put


def _drain(q, on_progress: Callable[[dict], None]) -> None:
    """Hand every progress record already in the pipe ``q`` (a ``SimpleQueue``) to
    ``on_progress``.

    A worker's :func:`report` writes its record into the pipe before it returns (a
    ``SimpleQueue`` has no feeder thread), so every record of a job is here by the time the
    job's result has reached this process: a drain after the result sees them all. (With a
    ``multiprocessing.Queue`` a background thread wrote them, sometimes after the result: the
    last records of a run went missing, or reached the next run's callback.)
    """
    while True:
        try:
            if q.empty():
                return
            item = q.get()
        except (OSError, EOFError, ValueError):
            return
        on_progress(item)


def _warm() -> None:
    """Import, in a fresh worker, what every job needs (the engine and its kernels, the knot
    check's compiled topoly code and its table), so that it happens while the parent builds
    its problem."""
    import stiffknots.engine.driver  # noqa: F401
    from stiffknots.knots.topoly_core import compiled, polvalues

    compiled()
    polvalues()


class WorkerPool:
    """Worker processes kept for a whole solve: its rounds run on the same processes.

    A fresh process costs ≈ 3.5 CPU s before its first move (the interpreter, numpy, numba's
    cached kernels, topoly for the knot check) — per round, when every round spawned its own
    (a knot that took 8 rounds spent ≈ 20 s of ≈ 100 s there). :meth:`start` spawns the
    workers and has them import the solvers, so a caller may start the pool before it builds
    its problem (the embeddings, the knot's HOMFLY-PT) and both happen at once; otherwise the
    first :meth:`run` starts it. A job's exception, a dead worker or Ctrl-C stop the pool
    (the running workers are killed); :meth:`close` stops it at the end.

    Parameters
    ----------
    workers : int
        Worker processes (≥ 1).
    """

    def __init__(self, workers: int):
        self.workers = max(1, int(workers))
        self._ex: ProcessPoolExecutor | None = None
        self._q = None
        self.dead = False

    def start(self) -> WorkerPool:
        """Spawn the workers now (they import the solvers in the background)."""
        if self._ex is None and not self.dead:
            ctx = mp.get_context("spawn")
            self._q = ctx.SimpleQueue()  # report() writes synchronously: see _drain
            self._ex = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                           initializer=_worker_init,
                                           initargs=(os.getpid(), self._q))
            with _ctrl_c_held():  # the workers are spawned here, by submit
                for _ in range(self.workers):
                    self._ex.submit(_warm)
        return self

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def run(self, job: Callable[..., Any], arg_list: Sequence[tuple],
            on_done: Callable[[Any], None] | None = None,
            on_progress: Callable[[dict], None] | None = None) -> tuple[list[Any], bool]:
        """``job(*args)`` for every ``args`` on the workers: (results in completion order,
        interrupted); see :func:`run_jobs`."""
        if self.dead:
            raise RuntimeError("this worker pool was stopped (Ctrl-C or an error)")
        self.start()
        sink = on_progress or (lambda info: None)
        results: list[Any] = []
        ok = False
        try:
            with _ctrl_c_held():
                pending = {self._ex.submit(job, *args) for args in arg_list}
            while pending:
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                _drain(self._q, sink)
                for f in done:
                    try:
                        res = f.result()  # re-raises a job's exception here
                    except BrokenProcessPool:
                        raise WorkerError("a worker process died (a crash or the out-of-memory "
                                          "killer) before its replica finished"
                                          + _unguarded_script_hint()) from None
                    results.append(res)
                    if on_done:
                        on_done(res)
            _drain(self._q, sink)
            ok = True
        except KeyboardInterrupt:
            return results, True
        finally:
            if not ok:  # Ctrl-C, a job's exception, a dead worker: the pool stops
                self.close()
        return results, False

    def close(self) -> None:
        """Stop the workers (at once: a running job is killed) and release the queue; once
        (a Ctrl-C during the stop is raised when the stop is complete, and a second close
        finds nothing left to stop)."""
        ex, self._ex = self._ex, None
        q, self._q = self._q, None
        self.dead = True
        try:
            if ex is not None:
                _terminate(ex)
        finally:
            if q is not None:  # not drained: a worker killed mid-write leaves half a record
                q.close()


def run_jobs(job: Callable[..., Any], arg_list: Sequence[tuple], workers: int,
             on_done: Callable[[Any], None] | None = None,
             on_progress: Callable[[dict], None] | None = None,
             isolate: bool = False, pool: WorkerPool | None = None) -> tuple[list[Any], bool]:
    """Run ``job(*args)`` for every ``args`` in ``arg_list`` on ``workers`` processes.

    One worker (or one job) runs in this process, unless ``isolate``: then it runs in a worker
    process too, so that Ctrl-C stops it at once — in this process a compiled kernel sees
    Ctrl-C only when its chunk of moves ends (minutes for a large number of moves). ``pool``
    (a :class:`WorkerPool`, e.g. kept over the rounds of a solve) runs the jobs; without one,
    a pool is started for this call and stopped after it.

    Returns
    -------
    results : list
        The results in completion order.
    interrupted : bool
        True after Ctrl-C.

    Raises
    ------
    Exception
        An exception raised by a job is raised here (the other workers are terminated).
    WorkerError
        A worker that dies (a crash, the out-of-memory killer).
    """
    global _PROGRESS
    results: list[Any] = []
    if not isolate and (workers <= 1 or len(arg_list) <= 1):
        _PROGRESS = on_progress
        try:
            for args in arg_list:
                res = job(*args)
                results.append(res)
                if on_done:
                    on_done(res)
        except KeyboardInterrupt:
            return results, True
        finally:
            _PROGRESS = None
        return results, False
    if pool is not None:
        return pool.run(job, arg_list, on_done, on_progress)
    with WorkerPool(max(1, min(workers, len(arg_list)))) as own:
        return own.run(job, arg_list, on_done, on_progress)


def _unguarded_script_hint() -> str:
    """The likeliest cause of workers that die at once, when it applies: the caller's script
    has no ``if __name__ == "__main__":``. Spawned workers import the main script again; an
    unguarded call then starts the solve once more inside each worker, which multiprocessing
    refuses, so every worker dies before its first job."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if path is None or getattr(main, "__spec__", None) is not None:
        return ""  # an interactive session, or ``python -m`` (a package's guarded __main__)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    if "__main__" in text:
        return ""
    return (f"; {Path(path).name} has no `if __name__ == \"__main__\":` — worker processes "
            "are started with spawn and import the script again, so put the calls of "
            "stiffknots that run replicas under that guard")


def _quiet_wakeup(ex: ProcessPoolExecutor) -> None:
    """Make the executor's wake-up of its manager thread safe against a closed pipe.

    At interpreter exit ``concurrent.futures.process._python_exit`` wakes every manager
    thread still registered, unlocked, while that thread may be closing the same pipe
    (``_ThreadWakeup.wakeup`` checks ``_closed`` and then writes): on a loaded machine, a
    usage error found just after the pool started ended with a "Bad file descriptor"
    traceback after its one-line error although the
    manager thread is joined below. A wake-up that finds the pipe closed has nothing left to
    wake, so its OSError is dropped."""
    wk = getattr(ex, "_executor_manager_thread_wakeup", None)
    if wk is None:
        return
    loud = wk.wakeup

    def wakeup() -> None:
        with contextlib.suppress(OSError, ValueError):
            loud()

    wk.wakeup = wakeup


def _terminate(ex: ProcessPoolExecutor) -> None:
    """Stop the pool now: cancel what has not started, kill the running workers.

    Every step is done even when Ctrl-C (or ``kill PID``) arrives in the middle: the
    interrupt is raised once the pool is stopped. (A Ctrl-C there left the executor shut down
    with workers alive, and the caller's next close met the shut-down executor: "AttributeError:
    'NoneType' object has no attribute 'values'".)"""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    _quiet_wakeup(ex)
    steps = [lambda: ex.shutdown(wait=False, cancel_futures=True),
             *(p.terminate for p in procs), *((lambda p=p: p.join(5)) for p in procs)]
    interrupt: BaseException | None = None
    for step in steps:
        for _ in range(3):  # a step a Ctrl-C cut short is done again
            try:
                step()
                break
            except KeyboardInterrupt as exc:
                interrupt = exc
            except Exception:  # noqa: BLE001 (a worker already gone)
                break
    # and let the executor's manager thread finish before anything else happens: an error
    # that ended the interpreter while it still ran (a usage error found just after the pool
    # started, on a cold start) raced its atexit wake-up against the closing of its pipe
    # ("Bad file descriptor" traceback after the one-line error)
    mgr = getattr(ex, "_executor_manager_thread", None)
    if mgr is not None:
        with contextlib.suppress(Exception):
            mgr.join(5)
    if interrupt is not None:
        raise interrupt
