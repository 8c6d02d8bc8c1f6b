"""Synthetic atlas data and a headless Chromium for the tests of the atlas pages.

Used by ``test_atlas.py``, ``test_atlas_browser.py`` and ``scripts/atlas_demo.py``.

The knots are synthetic chains of known shape (:mod:`stiffknots.analysis.synthetic`,
:func:`stiffknots.chain.regular_polygon`), not annealed results; their ``ε`` and minimum segment
distance are measured on the chains themselves, so every number shown matches the tube drawn.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from stiffknots.analysis import synthetic
from stiffknots.chain import Chain, regular_polygon

BEAD_WIDTH = "bead rule d = 1/√2, N = 150"
TUBE_WIDTH = {"w/L": 0.01, "N": 150}
TUBE_RADIUS = 0.75  # w / 2 for w/L = 0.01 and L = N = 150

#: Flags for Debian's chromium, headless, with nothing reaching the network; WebGL through
#: ANGLE on SwiftShader (software), so that plotly's 3D views render without a GPU.
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
]
CHROMIUM_CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser")


def _state(coords, shape, *, multiplicity=None, count=None, converged=True, width=None,
           eps_mean_shift=0.0, radius=None):
    c = Chain(np.asarray(coords, dtype=float), True)
    eps = c.epsilon()
    d = {"shape": shape, "multiplicity": multiplicity, "epsilon": eps,
         "eps_mean": None if count is None else eps + eps_mean_shift, "count": count,
         "converged": converged, "min_segment_distance": c.min_segment_distance(),
         "coords": c.coords}
    if width is not None:
        d["width"] = width
    if radius is not None:
        d["radius"] = radius
    return d


def _structure(coords) -> dict:
    """A state's ``structure`` (named) and ``zones`` (each bead's zone kind), §V B."""
    import warnings

    from stiffknots.analysis.structure import analyse_structure

    with warnings.catch_warnings():  # the synthetic chains need not obey the bead rule
        warnings.simplefilter("ignore")
        st = analyse_structure(coords)
    return {"structure": st.name, "zones": st.bead_kinds().tolist()}


def _wobbly_trefoil(n: int = 150) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * np.pi, 2000, endpoint=False)
    x = np.sin(t) + 2.0 * np.sin(2.0 * t)
    y = np.cos(t) - 2.0 * np.cos(2.0 * t)
    z = -np.sin(3.0 * t) + 0.3 * np.cos(5.0 * t)
    return synthetic.resample_closed(np.column_stack([x, y, z]), n)


def synthetic_thin(chain) -> dict:
    """A knot's thin stage in the page schema: the cage (state 0, the ground at the census's
    width) and an ``other`` state whose branch crosses below it near w/L = 0.002 and is the
    thin-limit ground (both routes agreeing); a third state that merged (no limit)."""
    ladder = (0.004, 0.002, 0.001, 0.0005)

    def pts(eps, out_from=None):
        return [{"w_over_L": w, "epsilon": e, "in_fit": out_from is None or w > out_from}
                for w, e in zip(ladder, eps, strict=True)]

    return {"w_over_L": 0.0047, "budget": "small", "seed": 0, "ground": 1, "crossing": 0.002,
            "states": [
                {"name": "4C", "epsilon": 129.31, "epsilon_thin": 126.41, "error": 0.18,
                 "structure_epsilon": 126.4725, "structure_name": "2 point-braids",
                 "agree": True, "event": None,
                 "points": pts((128.77, 127.48, 126.85, 126.54))},
                {"name": "other", "epsilon": 129.60, "epsilon_thin": 126.03, "error": 0.18,
                 "structure_epsilon": 126.1586,
                 "structure_name": "point-braid + 2 double points", "agree": True,
                 "event": None, "points": pts((128.9, 126.76, 126.24, 126.02))},
                {"name": "80", "epsilon": 140.2, "epsilon_thin": None, "error": None,
                 "structure_epsilon": None, "structure_name": None, "agree": None,
                 "event": "merged", "points": pts((139.0, 137.5, 136.0, 135.1), 0.002)}],
            "chain": {"coords": chain, "w_over_L": 0.0005}}


def synthetic_knots(n_beads: int = 150) -> list[dict]:
    """Six knots in the input schema of :func:`stiffknots.report.atlas.write_atlas`.

    Two models: ``bead`` for all (width given per model) and ``tube`` for three (width given
    per state); 6_2 has no tube results, 4_1 and 5_2 have metastable states, 6_2 is not
    converged and of shape "other".
    """
    n = n_beads
    cb2 = synthetic.torus_braid(2, n)
    cage = synthetic.four_cage(n)
    eighty = synthetic.eight_plus_circle(n)
    return [
        {"name": "3_1", "crossing_number": 3, "n": 2, "i": 2, "families": ["CB"],
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 4,
                      "ground": _state(cb2, "CB", multiplicity=2, count=4), "metastable": []},
             "tube": {"replicas": 2,
                      "ground": _state(regular_polygon(n, 2, amplitude=0.8).coords, "CB",
                                       multiplicity=2, count=2, width=TUBE_WIDTH,
                                       radius=TUBE_RADIUS),
                      "metastable": []}}},
        {"name": "4_1", "crossing_number": 4, "n": 2, "i": 3, "families": ["4C"],
         "thin": synthetic_thin(synthetic.four_cage(n)),
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 8,
                      "ground": {**_state(cage, "4C", count=5, eps_mean_shift=0.4),
                                 **_structure(cage)},
                      "metastable": [_state(eighty, "80", count=3, eps_mean_shift=1.1)]},
             "tube": {"replicas": 4,
                      "ground": _state(synthetic.four_cage(n, offset=1.6), "4C", count=4,
                                       width=TUBE_WIDTH, radius=TUBE_RADIUS),
                      "metastable": []}}},
        {"name": "5_1", "crossing_number": 5, "n": 2, "i": 2, "families": ["CB"],
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 4,
                      "ground": _state(regular_polygon(n, 2, amplitude=0.45).coords, "CB",
                                       multiplicity=2, count=4),
                      "metastable": []},
             "tube": {"replicas": 2,
                      "ground": _state(synthetic.torus_braid(2, n, separation=1.6), "CB",
                                       multiplicity=2, count=2, width=TUBE_WIDTH,
                                       radius=TUBE_RADIUS),
                      "metastable": []}}},
        {"name": "5_2", "crossing_number": 5, "n": 2, "i": 3, "families": ["4C"],
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 8,
                      "ground": _state(synthetic.four_cage(n, offset=0.9), "4C", count=6),
                      "metastable": [
                          _state(synthetic.eight_plus_circle(n, inside=False), "80", count=1),
                          _state(synthetic.torus_braid(3, n), "CB", multiplicity=3,
                                 count=1)]}}},
        {"name": "6_2", "crossing_number": 6, "n": 2, "i": 3,
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 4,
                      "ground": _state(_wobbly_trefoil(n), "other", count=1, converged=False),
                      "metastable": []}}},
        {"name": "8_19", "crossing_number": 8, "n": 3, "i": 3, "families": ["CB"],
         "models": {
             "bead": {"width": BEAD_WIDTH, "replicas": 4,
                      "ground": _state(synthetic.torus_braid(3, n), "CB", multiplicity=3,
                                       count=4),
                      "metastable": []}}},
    ]


def synthetic_catalogue_rows(max_crossings: int = 12) -> list[dict]:
    """One synthetic row per prime knot through ``max_crossings`` (2,977 through 12): the six
    knots of :func:`synthetic_knots` in turn, renamed."""
    import copy

    from stiffknots.knots.catalogue import catalogue

    base = synthetic_knots()
    rows = []
    for j, k in enumerate(kn for kn in catalogue(max_crossings) if kn.crossing_number >= 3):
        d = copy.deepcopy(base[j % len(base)])
        d["name"], d["crossing_number"] = k.name, k.crossing_number
        d.pop("thin", None)
        rows.append(d)
    return rows


def synthetic_families() -> dict:
    """A family-statistics table in the ``families`` schema of the atlas."""
    return {"title": "Ground-state shape families",
            "model": "bead",
            "groups": [{"label": "n_c < 7", "total": 5,
                        "counts": {"CB(2)": 2, "4C": 2, "other": 1}},
                       {"label": "n_c < 9", "total": 6,
                        "counts": {"CB(2)": 2, "4C": 2, "other": 1, "CB(3)": 1}}],
            "note": "Synthetic counts for the tests."}


def find_chromium(install: bool = True) -> str | None:
    """The path of Debian's chromium; installed with apt-get when missing and we are root.

    Returns None if it is missing and could not be installed.
    """
    for c in CHROMIUM_CANDIDATES:
        if Path(c).is_file():
            return c
    found = shutil.which("chromium")
    if found:
        return found
    if not install or not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which(
            "apt-get"):
        return None
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    lock = ["-o", "DPkg::Lock::Timeout=600"]
    for cmd in (["apt-get", *lock, "update", "-qq"],
                ["apt-get", *lock, "install", "-y", "-qq", "chromium"]):
        try:
            subprocess.run(cmd, check=True, env=env, timeout=1500,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        except (subprocess.SubprocessError, OSError):
            return None
    for c in CHROMIUM_CANDIDATES:
        if Path(c).is_file():
            return c
    return shutil.which("chromium")


@contextlib.contextmanager
def chromium_context(executable: str, *, width: int = 1400, height: int = 1000):
    """A Playwright browser context of Debian's chromium with a fresh profile.

    Yields
    ------
    playwright.sync_api.BrowserContext
    """
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="stiffknots-chromium-") as profile, \
            sync_playwright() as p:
        ctx = p.chromium.launch_persistent_context(
            profile, executable_path=executable, headless=True, args=CHROMIUM_ARGS,
            viewport={"width": width, "height": height})
        try:
            yield ctx
        finally:
            ctx.close()
