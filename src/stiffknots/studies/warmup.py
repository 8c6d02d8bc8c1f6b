"""Compile the numba kernels once, so that the first real command does not spend a silent
minute compiling (numba caches the machine code next to the sources, ``cache=True``).

``make`` runs this after installing the package; ``stiffknots warmup`` runs it on demand; and
the first command on a cold cache says what it is doing (:func:`cache_is_cold`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

#: kernels whose cached machine code tells whether the cache is warm
_MARKERS = (("engine", "kernel.run_moves"), ("engine", "force_kernel.run_end_moves"),
            ("engine", "prims.energy_chain"))


def cache_is_cold() -> bool:
    """True when the numba cache of the main kernels is missing (a fresh install)."""
    root = Path(__file__).resolve().parents[1]
    for pkg, name in _MARKERS:
        cache = root / pkg / "__pycache__"
        if not any(cache.glob(name + "-*.nbi")) if cache.is_dir() else True:
            return True
    return False


def warmup(log: Callable[[str], None] | None = None) -> float:
    """Run a few tiny problems in this process (closed anneal in both exclusion models and
    with the Langevin schedule, open knots at fixed extension and force, the
    restricted-curvature search, shape analysis, the resampling of a curve and its measures)
    so that numba compiles and caches every kernel
    they use. Returns the seconds it took."""
    from stiffknots.chain import Chain
    from stiffknots.engine.params import MoveParams
    from stiffknots.knots.resample import resample
    from stiffknots.problems.closed import anneal
    from stiffknots.problems.open_extension import anneal_open
    from stiffknots.problems.open_force import anneal_open_force
    from stiffknots.problems.tightest import tightest

    say = log or (lambda s: None)
    t0 = time.perf_counter()
    cold = cache_is_cold()
    say("compiling the numba kernels once (about a minute; later runs start at once) ..."
        if cold else "the numba kernels are compiled already; loading and checking them ...")
    res = anneal("3_1", moves=2_000, replicas=1, rounds=1, workers=1)
    # the tube model's paths of the kernels and of the minimiser
    anneal("3_1", moves=2_000, replicas=1, rounds=1, workers=1,
           params=MoveParams(exclusion="tube"))
    # a curve of the user: resampling (certified), the measures of a chain
    c = resample(Chain(res.best.coords[::2], closed=True), 60, check=False)
    c.epsilon(), c.writhe(), c.min_segment_distance()
    anneal_open("3_1", excess_length=20, moves=2_000, replicas=1, workers=1)
    anneal_open_force("3_1", 0.05, moves=50_000, replicas=1, workers=1)  # end moves too
    tightest("3_1", beads=40, moves=10_000, replicas=1, workers=1)
    # the Langevin schedule's kernel (anneal --schedule langevin)
    from stiffknots.engine.schedules import Schedule

    anneal("3_1", moves=2_000, replicas=1, rounds=1, workers=1,
           schedule=Schedule(kind="langevin", t_end=1e-4))
    dt = time.perf_counter() - t0
    say(f"kernels compiled and cached in {dt:.0f} s" if cold
        else f"kernels loaded from the cache in {dt:.0f} s")
    return dt


if __name__ == "__main__":
    warmup(print)
