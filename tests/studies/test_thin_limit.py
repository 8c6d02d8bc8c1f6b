"""The thin-limit study's pieces that run in seconds: its input checks, the structure value
of a shape (§V B, eq. (30)) and the figure."""

from __future__ import annotations

import math

import pytest

from stiffknots.errors import InvalidParameter, UserInputError
from stiffknots.studies import thin_limit as tl


@pytest.mark.parametrize("kwargs", [dict(budget="huge"), dict(widths=[0.002]),
                                    dict(widths=[0.002, 0.002]), dict(beads=400),
                                    dict(widths=[0.2, 0.1]), dict(seed=-3)])
def test_bad_input_raises_before_any_work(kwargs):
    with pytest.raises(InvalidParameter):
        tl.thin_limit("3_1", **kwargs)


def test_unknown_knot():
    with pytest.raises(UserInputError):
        tl.thin_limit("3_9")


def test_structure_value_of_shapes():
    s = tl.structure_value("CB", 2)
    assert s["name"] == "CB(2)"
    assert s["epsilon"] == pytest.approx(8 * math.pi**2, rel=1e-9)
    assert "method" in s
    assert tl.structure_value("other", None) is None
    assert tl.structure_value("CB", None) is None


def test_figure(tmp_path):
    pts = [{"w_over_L": w, "beads": 100, "epsilon": 8 * math.pi**2 + 7e3 * w**2,
            "sigma": 1e-3, "shape": "CB2", "in_fit": True} for w in (0.004, 0.002, 0.001)]
    pts.append({"w_over_L": 0.0005, "beads": 100, "epsilon": 80.0, "sigma": 1e-3,
                "shape": "other", "in_fit": False})
    res = {"knot": "3_1", "points": pts, "epsilon_thin": 8 * math.pi**2, "error": 1e-3,
           "fit": {"epsilon": 8 * math.pi**2, "a": 7e3, "p": 2.0},
           "structure": {"name": "CB(2)", "epsilon": 8 * math.pi**2}}
    p = tl.plot(res, tmp_path / "t.png")
    assert p.exists() and p.stat().st_size > 1000
