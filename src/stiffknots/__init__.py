"""stiffknots: the mechanics of stiff (elastic) knots.

Implements Gallotti & Pierre-Louis, "Stiff knots", Phys. Rev. E (2007): bounds from the bridge
number and braid index, the planar elastica constants, Monte Carlo annealing of knotted chains,
open knots under tension and the restricted-curvature problem, for every knot in KnotInfo.

The top-level functions are imported lazily (numba compiles on first use, not on import).
"""

from stiffknots._version import __version__

__all__ = ["__version__", "anneal", "anneal_open", "anneal_open_force", "tension_scan",
           "tightest"]


def __getattr__(name: str):
    if name == "anneal":
        from stiffknots.annealing import anneal

        return anneal
    if name in ("anneal_open", "tension_scan"):
        from stiffknots import open_knots

        return getattr(open_knots, name)
    if name == "anneal_open_force":
        from stiffknots.open_force import anneal_open_force

        return anneal_open_force
    if name == "tightest":
        from stiffknots.tightest import tightest

        return tightest
    raise AttributeError(f"module 'stiffknots' has no attribute {name!r}")
