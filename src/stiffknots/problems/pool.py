"""Independent replicas on all cores (spawned worker processes), Ctrl-C safe.

A job is a picklable top-level function; each call returns one result. When the user presses
Ctrl-C the finished results are kept and the rest cancelled.
"""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any


def run_jobs(job: Callable[..., Any], arg_list: Sequence[tuple], workers: int,
             on_done: Callable[[Any], None] | None = None) -> tuple[list[Any], bool]:
    """Run ``job(*args)`` for every ``args`` in ``arg_list`` on ``workers`` processes.

    Returns
    -------
    (results in completion order, interrupted) — ``interrupted`` is True after Ctrl-C.
    """
    results: list[Any] = []
    interrupted = False
    if workers <= 1 or len(arg_list) <= 1:
        try:
            for args in arg_list:
                res = job(*args)
                results.append(res)
                if on_done:
                    on_done(res)
        except KeyboardInterrupt:
            interrupted = True
        return results, interrupted
    ex = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"))
    futs = [ex.submit(job, *args) for args in arg_list]
    try:
        for f in as_completed(futs):
            res = f.result()
            results.append(res)
            if on_done:
                on_done(res)
        ex.shutdown(wait=True)
    except KeyboardInterrupt:
        interrupted = True
        for f in futs:
            f.cancel()
        ex.shutdown(wait=False, cancel_futures=True)
    return results, interrupted
