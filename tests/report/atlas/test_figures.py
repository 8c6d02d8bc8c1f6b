"""Tests of the atlas pictures (stiffknots.report.atlas.figures): thumbnails, the tube of
the 3D view, ε against n²."""

import math

import numpy as np
import pytest

from atlas_support import BEAD_WIDTH
from stiffknots.report.atlas import state_mesh
from stiffknots.report.render import DEFAULT_RADIUS


def test_thumbnails_are_png_files_next_to_the_page(rows, atlas, knots):
    n = 0
    for k in knots:
        imgs = rows[k["name"]]["thumb"]["imgs"]
        assert len(imgs) == len(k["models"])
        for src in imgs:
            data = (atlas.parent / src).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n"
            n += 1
    assert n == 9


def test_eps_figure_has_every_knot_and_the_bounds(atlas, knots, script_json):
    fig = script_json(atlas.read_text(encoding="utf-8"), "eps-data")
    by_model = {}
    for t in fig["data"]:
        model = (t.get("meta") or {}).get("model")
        if model:
            by_model.setdefault(model, []).extend(
                zip(t["customdata"], t["x"], t["y"], strict=True))
            assert t["visible"] == (model == "bead")
    assert {m: len(v) for m, v in by_model.items()} == {"bead": 6, "tube": 3}
    eps = {k["name"]: k for k in knots}
    for cd, x, y in by_model["bead"]:
        k = eps[cd[0]]
        assert abs(x - k["n"] ** 2) <= 0.8 + 1e-12
        assert y == pytest.approx(k["models"]["bead"]["ground"]["epsilon"])
        assert cd[4] == BEAD_WIDTH  # the width goes with every point
    lower = next(t for t in fig["data"] if t["name"].startswith("lower bound"))
    assert lower["y"][1] / lower["x"][1] == pytest.approx(2 * math.pi**2)
    cb = next(t for t in fig["data"] if t["name"].startswith("circular braid"))
    assert sorted(set(np.round(cb["y"], 6))) == pytest.approx(
        [2 * math.pi**2 * 4, 2 * math.pi**2 * 9])


def test_state_mesh_is_a_proper_rotation_of_the_chain(knots):
    x = np.asarray(knots[1]["models"]["bead"]["ground"]["coords"])
    m = state_mesh(x, n_sides=8)
    v = np.asarray(m["v"]).reshape(m["rings"], m["sides"], 3)
    centres = v.mean(axis=1)  # the mitre ellipse is symmetric about its bead
    a = x - x.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ centres)
    rot = u @ vt
    assert np.linalg.det(rot) == pytest.approx(1.0)  # never a mirror image
    assert np.abs(a @ rot - centres).max() < 5e-3
    assert m["t"][0] == 0.0 and 0.99 < m["t"][-1] < 1.0
    assert max(m["aspect"].values()) == pytest.approx(1.8)
    # the tube radius: every vertex at least that far from its bead, the nearest exactly
    for radius, mesh in [(DEFAULT_RADIUS, m), (0.75, state_mesh(x, radius=0.75, n_sides=8))]:
        v = np.asarray(mesh["v"]).reshape(mesh["rings"], mesh["sides"], 3)
        d = np.linalg.norm(v - v.mean(axis=1, keepdims=True), axis=2)
        assert d.min() == pytest.approx(radius, abs=2e-3)
