"""Helpers shared by the tests: the data folder, the starting chains every engine test uses,
a smooth trefoil, a chain in the fixed-force ensemble."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"


def braid_chain(name: str, n: int = 150) -> np.ndarray:
    """The closure of KnotInfo's braid word of ``name`` as a unit-bond chain of ``n`` beads."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import embed_braid

    k = get_knot(name)
    return embed_braid(k.braid_word, n_strands=k.braid_strands, n_beads=n)


def force_state(coords, params=None, seed: int = 0, force: float = 0.0, **kw):
    """A chain in the fixed-force ensemble (§VIII): ChainState with ``Ensemble("force")``."""
    from stiffknots.engine.params import Ensemble
    from stiffknots.engine.state import ChainState

    return ChainState(coords, params, seed=seed, ensemble=Ensemble("force", force=force, **kw))


def trefoil(n=120, R=2.0):
    """Smooth T(2,3) torus knot."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack(
        [(R + np.cos(3 * t)) * np.cos(2 * t), (R + np.cos(3 * t)) * np.sin(2 * t), np.sin(3 * t)]
    )


BENCH = Path(__file__).resolve().parents[1] / "bench"


def load_bench(name: str):
    """The module of the script ``bench/<name>.py`` (bench/ is no package), imported once;
    bench/ goes on sys.path for the script's own imports of its neighbours."""
    import importlib.util
    import sys

    if name in sys.modules:
        return sys.modules[name]
    if str(BENCH) not in sys.path:
        sys.path.append(str(BENCH))
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def fill_up(folder: Path, leave: int = 0) -> None:
    """Fill the file system of ``folder`` with a file until ``leave`` bytes are free."""
    free = os.statvfs(folder).f_bavail * os.statvfs(folder).f_frsize
    with open(folder / "filler", "wb") as f:
        try:
            f.write(b"\0" * max(free - leave, 0))
        except OSError:
            pass
