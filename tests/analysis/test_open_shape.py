"""Tests of the shape of an open knot under tension (stiffknots.analysis.open_shape, paper
§VIII): the loop's circle and its distance to the line of the ends.

The recognition of the tangent loop itself (a loop, a straight line, a loop the axis pierces)
is tested with the open extension problem, tests/problems/test_open_extension.py.
"""

import math

import numpy as np
import pytest

from stiffknots.analysis.open_shape import open_shape


def _loop(radius, axis_distance, n_loop=90):
    """A planar circle in the xz plane, its centre ``axis_distance`` from the z axis, with
    straight tails along the z axis (the line of the clamped ends)."""
    t = np.linspace(0.0, 2.0 * math.pi, n_loop, endpoint=False)
    circle = np.column_stack([axis_distance - radius * np.cos(t), np.zeros_like(t),
                              60.0 + radius * np.sin(t)])
    tails = np.column_stack([np.zeros(40), np.zeros(40), np.linspace(0.0, 120.0, 40)])
    return np.vstack([tails[:20], circle, tails[20:]])


@pytest.mark.parametrize("ratio", [1.0, 0.75])
def test_the_fit_recovers_the_loop_and_its_distance_to_the_axis(ratio):
    """The circle of the loop is recovered (its radius and centre to 1 %: the tail beads
    within reach of the circle count as loop beads), and D/R is reported as it is: 1 in the
    thin limit (the circle touches the line, §VIII), below 1 where a finite thickness pulls
    the centre towards the axis."""
    s = open_shape(_loop(12.0, ratio * 12.0))
    f = s["features"]
    assert s["label"] == "loop", s
    assert f["radius"] == pytest.approx(12.0, rel=0.01)
    assert f["axis_distance_over_radius"] == pytest.approx(ratio, abs=0.01)
    assert f["planarity"] < 1e-12 and f["roundness"] < 0.05
    assert f["coverage"] == 1.0 and f["normal_z"] < 1e-12


def test_the_shape_does_not_depend_on_turns_about_the_axis_or_shifts_along_it():
    x = _loop(12.0, 12.0)
    a = 0.7
    rot = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                    [0.0, 0.0, 1.0]])
    ref = open_shape(x)["features"]
    for y in (x @ rot.T, x + [0.0, 0.0, 25.0]):
        f = open_shape(y)["features"]
        assert f.keys() == ref.keys()
        for k, v in ref.items():
            assert f[k] == pytest.approx(v, rel=1e-9, abs=1e-12), k
