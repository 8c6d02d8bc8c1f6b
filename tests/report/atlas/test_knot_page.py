"""Tests of the page of one knot (stiffknots.report.atlas.knot_page): its states and the
data of their 3D views."""

import html
import re

import numpy as np
import pytest

from atlas_support import TUBE_RADIUS
from stiffknots.report.atlas import format_width, write_atlas
from stiffknots.report.atlas.knot_page import THIN_RADIUS
from stiffknots.report.render import DEFAULT_RADIUS
from stiffknots.theory import closed_bounds


def test_knot_pages_show_every_state(atlas, knots, script_json):
    for k in knots:
        text = (atlas.parent / "knots" / f"{k['name']}.html").read_text(encoding="utf-8")
        plain = html.unescape(re.sub(r"<[^>]+>", " ", text))
        states = script_json(text, "states-data")
        n_states = 0
        for _model, m in k["models"].items():
            width = format_width(m.get("width") or m["ground"].get("width"))
            for s in [m["ground"], *m["metastable"]]:
                n_states += 1
                assert f"{s['epsilon']:.2f}" in plain
                assert f"{s['min_segment_distance']:.3f}" in plain
                assert f"{s['count']} / {m['replicas']}" in plain
                assert width in plain
        # the thin-limit ground's chain, a finite-width chain at its own w/L (§V A, #37)
        n_thin = int(bool(k.get("thin")))
        assert len(states) == n_states + n_thin
        for st in states:
            assert len(st["v"]) == st["rings"] * st["sides"] * 3
            assert len(st["t"]) == st["rings"] == 150
            assert " at " in st["caption"]
            assert ("ε = " in st["caption"]) != st["label"].startswith("thin limit")
        if n_thin:
            assert "ε* = 126.03 ± 0.18 (w → 0)" in states[-1]["caption"]
            assert "at w/L = 0.0005" in states[-1]["caption"]
        b = closed_bounds(k["n"], k["i"])
        assert f"{b.lower:.2f} ≤ ε* ≤ {b.upper:.2f}" in plain


def test_the_drawing_radius_reaches_the_3d_view(atlas, script_json):
    text = (atlas.parent / "knots" / "4_1.html").read_text(encoding="utf-8")
    states = script_json(text, "states-data")
    assert [s["label"].split(" — ")[0] for s in states] == ["bead", "bead", "tube",
                                                            "thin limit"]
    for s, radius in zip(states, [DEFAULT_RADIUS, DEFAULT_RADIUS, TUBE_RADIUS, THIN_RADIUS],
                         strict=True):
        v = np.asarray(s["v"]).reshape(s["rings"], s["sides"], 3)
        d = np.linalg.norm(v - v.mean(axis=1, keepdims=True), axis=2)
        assert d.min() == pytest.approx(radius, abs=2e-3)


def test_zones_reach_the_3d_view_and_bad_ones_are_refused(tmp_path, atlas, knots,
                                                           script_json):
    """A state's zones (each bead's contact-zone kind, §V B) travel with its mesh, one code a
    ring, and the page offers the colouring; zones that do not fit the chain are refused."""
    text = (atlas.parent / "knots" / "4_1.html").read_text(encoding="utf-8")
    states = script_json(text, "states-data")
    ground = next(k for k in knots if k["name"] == "4_1")["models"]["bead"]["ground"]
    assert states[0]["zones"] == list(ground["zones"]) and len(states[0]["zones"]) == \
        states[0]["rings"]
    assert states[1]["zones"] is None  # the 80 was given none
    assert 'id="colour-select"' in text and "multiple point" in text
    plain = (atlas.parent / "knots" / "3_1.html").read_text(encoding="utf-8")
    assert 'id="colour-select"' not in plain  # no state of 3_1 has zones
    x = np.asarray(ground["coords"])
    n = len(x)
    # too few; a code out of range; not integers; a string
    for zones in ([0] * (n - 1), [0] * (n - 1) + [4], [0.5] * n, "0" * n):
        bad = {**knots[0], "models": {"bead": {"width": "w", "ground": {
            "epsilon": 1.0, "coords": x, "zones": zones}}}}
        with pytest.raises(ValueError, match=rf"zones must be {n} integers \(one per bead"):
            write_atlas(tmp_path, [bad])
    lone = {**knots[0], "models": {"bead": {"width": "w", "ground": {
        "epsilon": 1.0, "zones": [0] * n}}}}
    with pytest.raises(ValueError, match="need the state's coords"):
        write_atlas(tmp_path, [lone])
