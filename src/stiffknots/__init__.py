"""stiffknots: the mechanics of stiff (elastic) knots.

Implements Gallotti & Pierre-Louis, "Stiff knots", Phys. Rev. E (2007): bounds from the bridge
number and braid index, the planar elastica constants, Monte Carlo annealing of knotted chains,
open knots under tension and the restricted-curvature problem, for every knot in KnotInfo.

Everyday objects, one import away::

    import stiffknots as sk
    k = sk.get_knot("5_2")                       # catalogue entry (n, i, braid word, ...)
    sk.closed_bounds(k.bridge_number, k.braid_index)
    res = sk.anneal("4_1", replicas=2)           # verified minimum-energy chains (§VII)
    sk.classify(res.best.coords).label           # 'CB', '4C', '80' or 'other'
    c = sk.load("runs/4_1/best.xyz"); c.epsilon()

Names are imported lazily (numba compiles on first use, and nothing heavy loads on import).
"""

from stiffknots._version import __version__


def _numpy_threads_without_sigterm() -> None:
    """Load numpy with SIGTERM blocked in the importing (main) thread.

    numpy's OpenBLAS starts its pool of threads when it loads, and a thread starts with its
    creator's signal mask. Its threads then never take a process-directed SIGTERM: the kernel
    gives it to the main thread, which holds it back while topoly runs
    (:func:`stiffknots.knots.identify._keep_sigterm`) and takes it after. Loaded otherwise,
    an OpenBLAS thread took a ``kill PID`` sent during a knot check, topoly's own handler
    swallowed it, and the run went on (5 of 5 tries). numpy loaded before stiffknots keeps
    its threads as they are.
    """
    import signal
    import sys
    import threading

    if "numpy" in sys.modules or not hasattr(signal, "pthread_sigmask"):
        return
    if threading.current_thread() is not threading.main_thread():
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    try:
        import numpy  # noqa: F401
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


_numpy_threads_without_sigterm()

_LAZY = {
    # problems (§VII–IX)
    "anneal": "stiffknots.problems.closed",
    "anneal_open": "stiffknots.problems.open_extension",
    "tension_scan": "stiffknots.problems.open_extension",
    "anneal_open_force": "stiffknots.problems.open_force",
    "tightest": "stiffknots.problems.tightest",
    # core objects
    "Chain": "stiffknots.chain",
    "regular_polygon": "stiffknots.chain",
    "load": "stiffknots.formats",
    "save": "stiffknots.formats",
    "get_knot": "stiffknots.knots.catalogue",
    "catalogue": "stiffknots.knots.catalogue",
    "identify": "stiffknots.knots.identify",
    "verify_knot": "stiffknots.knots.identify",
    "knot_summary": "stiffknots.knots.summary",
    # checks and analysis
    "check": "stiffknots.checks",
    "classify": "stiffknots.analysis",
    "group_states": "stiffknots.analysis",
    "analyse_structure": "stiffknots.analysis",
    # theory
    "closed_bounds": "stiffknots.theory.bounds",
    "open_bounds": "stiffknots.theory.bounds",
    "restricted_curvature_bounds": "stiffknots.theory.bounds",
    "elastica_constants": "stiffknots.theory.elastica",
    # engine settings
    "MoveParams": "stiffknots.engine.params",
    "Width": "stiffknots.width",
    "Schedule": "stiffknots.engine.schedules",
    # errors
    "StiffKnotsError": "stiffknots.errors",
    "UserInputError": "stiffknots.errors",
}

__all__ = ["__version__", *sorted(_LAZY)]


def __getattr__(name: str):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module 'stiffknots' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(mod), name)
    globals()[name] = value  # cache: later lookups skip __getattr__
    return value


def __dir__():
    return __all__
