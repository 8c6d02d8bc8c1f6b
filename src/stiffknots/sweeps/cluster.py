"""Where a sweep runs: a Dask ``LocalCluster`` started in-process, or an existing cluster.

Local (the default)
    ``distributed.LocalCluster`` with one worker *process* per core, one thread each, every
    worker under a nanny: a worker that dies (killed, out of memory) is replaced and the
    scheduler reruns its task on another worker (up to ``distributed.scheduler.allowed-
    failures``, default 3, times per task). No port to configure: the scheduler and its HTTP
    endpoints (the dashboard, when bokeh is installed) listen on free ports of 127.0.0.1
    only. Logs are silenced below ERROR. No memory limit (a job holds a few MB; Dask's
    memory monitor, which polls every worker through psutil, is off). The workers ignore
    SIGINT, so Ctrl-C in the terminal reaches the client only, which stops the
    sweep and closes the cluster; if the client is killed (``kill -9``), every worker exits
    by itself as soon as its parent's pipe closes (``distributed.process``) — nothing is left
    running.
Remote (``scheduler="tcp://host:port"``)
    The client connects to a running scheduler whose workers have stiffknots installed (the
    same version: the jobs are pickled). Results come back to the client, which alone writes
    the store, so the database stays on the client's local disk.

:func:`run_task` is what a worker runs: it builds the (knot, model) problem of a sweep job
(:func:`~stiffknots.sweeps.plan.build_jobs`, once per worker process) and runs that replica's
:class:`~stiffknots.problems.base.Job` through :func:`~stiffknots.problems.base.run_job`
(engine and knot verification), its progress sent to the client as Dask events on
:data:`PROGRESS_TOPIC` (at most one per :data:`PROGRESS_PERIOD` seconds per job). The
problems are built on the workers, not on the client: building computes HOMFLY-PT
polynomials with topoly, whose compiled code closes file descriptor 0 (see
``stiffknots.knots.identify._keep_stdin()``) — harmless in a worker, a hazard beside the
client's sockets — and it spreads the building over the workers.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import re
import shutil
import tempfile
import time
from collections.abc import Iterator
from typing import Any

from stiffknots.errors import UserInputError

__all__ = ["PROGRESS_TOPIC", "PROGRESS_PERIOD", "connect", "run_task", "local_workers",
           "scheduler_address", "IgnoreInterrupt"]

#: The Dask event topic of the jobs' progress records.
PROGRESS_TOPIC = "stiffknots-sweep-progress"
#: Seconds between two progress records of one job.
PROGRESS_PERIOD = 1.0

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ucx|ws|wss)://\S+$|^[\w.\-\[\]:]+:\d+$")

def import_distributed():
    """Import ``distributed`` with SnapPy hidden from its optional compressors.

    ``distributed`` probes ``import snappy`` for python-snappy compression and calls
    ``snappy.compress``; the topology package SnapPy (used by the knot naming of
    :mod:`stiffknots.knots.identify`) has the same module name and no such function, and the
    probe's AttributeError would abort the import. During the import the name ``snappy`` is
    mapped to None (an ImportError for the probe), then restored.
    """
    import sys

    if "distributed.protocol.compression" in sys.modules:
        import distributed

        return distributed
    saved = sys.modules.get("snappy", _MISSING)
    sys.modules["snappy"] = None
    try:
        import distributed
        import distributed.protocol.compression  # noqa: F401
    finally:
        if saved is _MISSING:
            del sys.modules["snappy"]
        else:
            sys.modules["snappy"] = saved
    return distributed


_MISSING = object()



def local_workers(workers: int | None = None) -> int:
    """Worker processes of a local cluster: ``workers``, or one per core."""
    from stiffknots.problems import validate as V

    if workers is None:
        return max(1, os.cpu_count() or 1)
    return V.integer("workers", workers, 1, 1024)


def scheduler_address(scheduler: str) -> str:
    """The address of a Dask scheduler (``tcp://host:port``, ``host:port``), or the address a
    scheduler file names (``dask scheduler --scheduler-file FILE``: JSON with ``address``),
    checked for its form only; UserInputError otherwise."""
    import json
    from pathlib import Path

    address = str(scheduler).strip()
    path = Path(address).expanduser()
    if not _ADDRESS.match(address) and path.is_file():
        try:
            address = str(json.loads(path.read_text())["address"]).strip()
        except (OSError, ValueError, KeyError, TypeError):
            raise UserInputError(f"--scheduler {scheduler!r} is a file but not a Dask "
                                 "scheduler file (JSON with an 'address', written by "
                                 "stiffknots-dask scheduler --scheduler-file FILE)") from None
    if not _ADDRESS.match(address):
        raise UserInputError(f"--scheduler must be a scheduler address such as "
                             f"tcp://host:8786 or a scheduler file, got {scheduler!r}")
    return address


try:
    import_distributed()
    from distributed.diagnostics.plugin import WorkerPlugin as _WorkerPlugin
except ImportError:  # pragma: no cover (distributed is a dependency)
    _WorkerPlugin = object  # type: ignore[assignment,misc]


class IgnoreInterrupt(_WorkerPlugin):  # type: ignore[misc]
    """Worker plugin of the local cluster: the worker process ignores SIGINT (Ctrl-C is the
    client's business; it closes the cluster)."""

    name = "stiffknots-ignore-sigint"

    def setup(self, worker: Any) -> None:
        import os
        import signal
        import threading

        from stiffknots.problems.pool import _die_with_parent

        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        _die_with_parent(os.getppid())  # a killed client (or nanny) takes its workers along


class LoadSnappy(_WorkerPlugin):  # type: ignore[misc]
    """Worker plugin of jobs that name knots by SnapPy (the thin stage's relaxations,
    :func:`stiffknots.knots.identify.identify_details`): SnapPy is imported in the worker's
    main thread. Its PARI library installs signal handlers when it loads, which only the main
    thread may do: imported first in a task's thread, it failed ("signal only works in main
    thread")."""

    name = "stiffknots-load-snappy"

    def setup(self, worker: Any) -> None:
        import threading

        if threading.current_thread() is threading.main_thread():
            from stiffknots.knots.exterior import _snappy

            _snappy()


def local_cluster(n_workers: int, local_directory: str | None = None) -> Any:
    """A ``distributed.LocalCluster`` in this process: ``n_workers`` worker processes under
    nannies, one thread each, HTTP on a free local port, no memory limit; their scratch
    space (and its lock files) in ``local_directory`` (default: Dask's, a
    ``dask-scratch-space`` folder in the system's temporary folder).

    The worker processes are *forked* from this one, which has imported ``distributed``
    safely (:func:`import_distributed`): a spawned process would import it afresh and stop on
    SnapPy's ``snappy`` module.
    """
    import_distributed()
    import dask
    from distributed import LocalCluster

    where = {} if local_directory is None else {"temporary-directory": local_directory}
    with dask.config.set({"distributed.worker.multiprocessing-method": "fork", **where}):
        return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                            dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR,
                            scheduler_port=0, memory_limit=0,
                            **({} if local_directory is None
                               else {"local_directory": local_directory}))


@contextlib.contextmanager
def connect(scheduler: str | None = None, workers: int | None = None,
            timeout: float = 20.0) -> Iterator[Any]:
    """A Dask client: on a new local cluster, or on the scheduler at ``scheduler``.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port``); default: start a local cluster.
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    timeout : float
        Seconds to wait for the scheduler.

    Yields
    ------
    distributed.Client
        Closed (with its local cluster) when the block ends, whatever ends it.

    Raises
    ------
    UserInputError
        A malformed address, or no scheduler answering there.
    """
    import_distributed()
    from distributed import Client

    cluster = None
    scratch = None
    if scheduler is None:
        # the workers' scratch space in a folder of this run, removed with the cluster (Dask's
        # default, /tmp/dask-scratch-space, kept its global.lock and purge.lock after every run)
        scratch = tempfile.mkdtemp(prefix="stiffknots-dask-")
        try:
            cluster = local_cluster(local_workers(workers), local_directory=scratch)
        except BaseException:
            shutil.rmtree(scratch, ignore_errors=True)
            raise
        try:
            client = Client(cluster)
            client.register_plugin(IgnoreInterrupt())
        except BaseException:
            cluster.close()
            shutil.rmtree(scratch, ignore_errors=True)
            raise
    else:
        address = scheduler_address(scheduler)
        try:
            client = Client(address, timeout=f"{timeout}s")
        except (OSError, TimeoutError) as e:
            raise UserInputError(f"--scheduler {address}: no Dask scheduler answers there "
                                 f"({type(e).__name__}: {e})") from None
    try:
        yield client
    finally:
        with contextlib.suppress(Exception):
            client.close(timeout=10)
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close(timeout=10)
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)


@functools.lru_cache(maxsize=8)
def _problem_jobs(knot: str, model: Any, budget: Any, seed: int, settings_text: str,
                  start: str | None = None) -> dict[int, Any]:
    """The jobs of one (knot, model) problem, built once per worker process (and once per
    favoured start of its added replicas)."""
    import json

    from stiffknots.sweeps.plan import build_jobs

    return build_jobs(knot, model, budget, seed, json.loads(settings_text), start)


@functools.lru_cache(maxsize=8)
def _problem(knot: str, model: Any, budget: Any, seed: int, settings_text: str) -> Any:
    """The (knot, model) problem whose searches a continuation leg continues, built once per
    worker process."""
    import json

    from stiffknots.sweeps.plan import build_problem

    return build_problem(knot, model, budget, seed, json.loads(settings_text))


def run_task(job: Any, budget: Any) -> Any:
    """Worker: build the (knot, model) problem of a :class:`~stiffknots.sweeps.plan.SweepJob`
    (:func:`~stiffknots.sweeps.plan.build_jobs`: ClosedAnneal's validation, starts and start
    polynomials; cached per process), run its replica's problem
    :class:`~stiffknots.problems.base.Job` and verify it
    (:func:`~stiffknots.problems.base.run_job`), sending the progress to the client.

    Returns
    -------
    Replica
        The verified replica (its chain, ε, knot check, timings).
    """
    from dataclasses import replace

    from stiffknots.problems.base import run_job
    from stiffknots.problems.pool import reporting_to
    from stiffknots.store import canonical_json

    if job.parent is not None:
        pjob = _leg(job, budget)
    else:
        jobs = _problem_jobs(job.knot, job.model, budget, job.seed,
                             canonical_json(job.settings), job.start)
        pjob = jobs[job.replica]
        pjob = replace(pjob, coords=pjob.coords.copy())  # the cached start stays untouched
    try:
        import_distributed()
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):  # run outside a worker (tests, a debugger)
        worker = None
    last = [-PROGRESS_PERIOD]

    def send(info: dict) -> None:
        now = time.monotonic()
        done, total = int(info.get("done", 0)), int(info.get("total", 0) or 0)
        if worker is None or (now - last[0] < PROGRESS_PERIOD and done < total):
            return
        last[0] = now
        best = info.get("best")
        worker.log_event(PROGRESS_TOPIC, {"job": job.id, "done": done, "total": total,
                                          "best": None if best is None else float(best),
                                          "pid": os.getpid()})

    with reporting_to(send):
        r = run_job(pjob)
    if job.parent is not None:  # a leg keeps its search's start (a seeded one stays seeded)
        r.start = job.parent["start"]
    return r


def _leg(job: Any, budget: Any) -> Any:
    """The problem job of a continuation leg (:mod:`stiffknots.sweeps.legs`): the solver's
    :meth:`~stiffknots.problems.closed.ClosedAnneal.continue_jobs` (basin hops; a Langevin
    bead ensemble's :meth:`~stiffknots.problems.closed.ClosedAnneal.langevin_leg_jobs`) from
    the parent's chain,
    replica number ``job.replica`` (its seed derives from it). A parent whose start is not
    one of the problem's (a seeded replica's ``tube-ground``) is verified against the
    problem's first start: every start is an embedding of the same knot."""
    from types import SimpleNamespace

    from stiffknots.store import canonical_json

    problem = _problem(job.knot, job.model, budget, job.seed, canonical_json(job.settings))
    start = job.parent["start"]
    if start not in problem.codes:
        start = problem.starts[0]
    parent = SimpleNamespace(coords=job.parent["coords"].copy(), start=start)
    legs = (problem.langevin_leg_jobs([parent], job.replica) if budget.langevin(job.model)
            else problem.continue_jobs([parent], job.replica))
    if not legs:
        raise RuntimeError(f"{job.id}: this problem cannot continue a search (a bug in "
                           "stiffknots, please report it)")
    return legs[0]
