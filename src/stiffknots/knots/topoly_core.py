"""topoly's compiled HOMFLY-PT code, called without topoly's Python layer.

:func:`topoly.homfly` is three compiled steps wrapped in a Python layer that costs more than
the steps themselves: importing ``topoly`` loads matplotlib, scipy.ndimage, scipy.interpolate
and gemmi (1.2–1.6 s), and each call builds topoly's spatial-graph object (PD code, abstract
graph, canonical codes: ≈ 0.1–0.5 s for a 150-bead chain). The steps are

1. ``topoly_preprocess.chain_read_from_string`` — the polygon as topoly's C chain
   (lines ``id x y z``);
2. ``topoly_preprocess.kmt_reduction_multi([chain], True)`` — the KMT triangle elimination of
   the closed polygon (``ReduceMethod.KMT``), which keeps the knot type;
3. ``topoly_homfly.find_link_homfly_code`` — the diagram's code seen along z (one line per
   crossing), and ``topoly_lmpoly.lmpoly`` — its HOMFLY-PT polynomial in topoly's code.

For one closed polygon (``Closure.CLOSED``, one component, no bridges) ``topoly.homfly``'s
Python layer adds nothing to the answer: it passes the reduced chain's code on (re-encoded
through a PD code, which does not change the polynomial), answers ``ErrTMC`` when the code
has more than ``max_cross`` lines, and ``[[1]]`` for a diagram without crossings — exactly
what :func:`homfly_kmt` does. ``tests/knots/test_topoly_core.py`` checks that both give the
same code for the braid start of every knot through 10 crossings and a perturbed copy of it.

The compiled modules are loaded as submodules of a stand-in ``topoly`` package (its
``__path__`` only), which is removed again at once, so that a later ``import topoly`` runs
topoly's own ``__init__`` and finds these same modules already loaded.
"""

from __future__ import annotations

import sys
import threading
import types
from typing import Any

import numpy as np

__all__ = ["compiled", "homfly_kmt", "kmt_reduce", "polvalues"]

_LOAD_LOCK = threading.Lock()
_CACHE: dict[str, Any] = {}


def _topoly_dir() -> str:
    import importlib.util

    spec = importlib.util.find_spec("topoly")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError("topoly is not installed (pip install topoly)")
    return list(spec.submodule_search_locations)[0]


def compiled() -> tuple[Any, Any, Any]:
    """``(topoly_preprocess, topoly_homfly, topoly_lmpoly)``, loaded once without running
    ``topoly/__init__.py`` (module docstring)."""
    if "modules" in _CACHE:
        return _CACHE["modules"]
    with _LOAD_LOCK:
        if "modules" not in _CACHE:
            _CACHE["modules"] = _load(("topoly_preprocess", "topoly_homfly", "topoly_lmpoly"))
    return _CACHE["modules"]


def polvalues() -> dict:
    """topoly's table of polynomial values (``topoly/polvalues.py``: a module of dictionaries
    only), loaded as :func:`compiled` loads the compiled modules."""
    if "polvalues" not in _CACHE:
        with _LOAD_LOCK:
            if "polvalues" not in _CACHE:
                (mod,) = _load(("polvalues",))
                _CACHE["polvalues"] = mod.polvalues
    return _CACHE["polvalues"]


def _load(names: tuple[str, ...]) -> tuple[Any, ...]:
    import importlib

    if "topoly" in sys.modules:   # the real package is loaded: its submodules are the same
        return tuple(importlib.import_module(f"topoly.{n}") for n in names)
    stub = types.ModuleType("topoly")
    stub.__path__ = [_topoly_dir()]
    stub.__package__ = "topoly"
    sys.modules["topoly"] = stub
    try:
        return tuple(importlib.import_module(f"topoly.{n}") for n in names)
    finally:
        if sys.modules.get("topoly") is stub:
            del sys.modules["topoly"]


def _kmt(x: np.ndarray) -> list:
    """topoly's C chain of the closed polygon ``x``, KMT-reduced (steps 1 and 2)."""
    pre, _, _ = compiled()
    text = "".join(f"{i} {a!r} {b!r} {c!r}\n"
                   for i, (a, b, c) in enumerate(np.asarray(x, dtype=float).tolist(), 1))
    chain, _unread = pre.chain_read_from_string(text.encode())
    return pre.kmt_reduction_multi([chain], True)


def kmt_reduce(x: np.ndarray) -> np.ndarray:
    """The closed polygon ``x`` after topoly's KMT reduction, its vertices in order, as
    ``topoly.reduce_structure(x, reduce_method=KMT, output_type="xyz")`` gives them."""
    (chain,) = _kmt(x)
    return np.array([[a["A"]["x"], a["A"]["y"], a["A"]["z"]] for a in chain], dtype=float)


def homfly_kmt(x: np.ndarray, max_cross: int) -> str | None:
    """topoly's HOMFLY-PT code of the closed polygon ``x`` (shape (N, 3), seen along z) after
    KMT reduction, as ``topoly.homfly(x, closure=CLOSED, reduce_method=KMT, max_cross=...,
    translate=False)`` gives it; None when the reduced diagram has more than ``max_cross``
    crossing lines (topoly's ``ErrTMC``). The caller handles topoly's side effects on
    descriptor 0 and SIGTERM (:mod:`stiffknots.knots.identify`)."""
    _, hom, lm = compiled()
    code = hom.find_link_homfly_code(_kmt(x)).decode().strip()
    if not code:
        return "[[1]]"
    if len(code.split("\n")) > max_cross:
        return None
    out = str(lm.lmpoly(code)).replace("\n", "|").strip()
    return None if ("TMC" in out or "Err" in out) else out
