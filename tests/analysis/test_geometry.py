"""Tests of the small geometric measures of the shape classifier (stiffknots.analysis.geometry):
turning angles and the total curvature κ̄ of eq. (10), turning and winding numbers,
inflections, principal axes."""

import math

import numpy as np
import pytest

from stiffknots.analysis.geometry import (
    arc_lengths,
    axis_winding,
    count_inflections,
    planar_signed_turns,
    principal_axes,
    total_curvature,
    turning_angles,
)
from stiffknots.analysis.synthetic import resample_closed
from stiffknots.chain import regular_polygon
from stiffknots.theory.elastica import eight_curve


@pytest.mark.parametrize("n", [7, 40, 150])
def test_regular_polygon_turns_by_two_pi_over_n(n):
    """A regular n-gon of unit bonds turns by 2π/n at every vertex: κ̄ = 2π, the least total
    curvature of a closed curve (eq. (10), Fenchel); opened, it loses its two end angles."""
    x = regular_polygon(n).coords
    assert np.allclose(arc_lengths(x), 1.0, atol=1e-12) and len(arc_lengths(x)) == n
    assert np.allclose(turning_angles(x), 2.0 * math.pi / n, atol=1e-12)
    assert total_curvature(x) == pytest.approx(2.0 * math.pi, abs=1e-12)
    assert len(arc_lengths(x, closed=False)) == n - 1
    assert len(turning_angles(x, closed=False)) == n - 2
    assert total_curvature(x, closed=False) == pytest.approx(2.0 * math.pi * (n - 2) / n)


def test_circle_and_figure_eight_turning_numbers_and_inflections():
    """The signed turns of a circle sum to ±2π (turning number ±1, sign by orientation) with
    no inflection; the elastica figure eight of Appendix D turns by 0 with two inflections."""
    t = np.linspace(0.0, 2.0 * math.pi, 120, endpoint=False)
    circle = np.column_stack([np.cos(t), np.sin(t)])
    assert planar_signed_turns(circle).sum() == pytest.approx(2.0 * math.pi)
    assert planar_signed_turns(circle[::-1]).sum() == pytest.approx(-2.0 * math.pi)
    assert count_inflections(planar_signed_turns(circle)) == 0
    eight = resample_closed(eight_curve(2001)[:-1], 200)[:, :2]
    turns = planar_signed_turns(eight)
    assert turns.sum() == pytest.approx(0.0, abs=1e-9)
    assert count_inflections(turns) == 2


def test_axis_winding_counts_the_turns_about_the_origin():
    t = np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False)
    circle = np.column_stack([np.cos(t), np.sin(t)])
    w, dphi = axis_winding(circle)
    assert w == pytest.approx(1.0) and np.allclose(dphi, 2.0 * math.pi / 90)
    assert axis_winding(circle[::-1])[0] == pytest.approx(-1.0)
    assert axis_winding(circle + [3.0, 0.0])[0] == pytest.approx(0.0, abs=1e-12)
    twice = np.column_stack([np.cos(2 * t), np.sin(2 * t)])  # a doubly covered circle
    assert axis_winding(twice)[0] == pytest.approx(2.0)


def test_principal_axes_of_a_tilted_ellipse():
    """A planar ellipse (semi-axes 3 and 1) in a tilted plane: the normal of the best-fit plane
    is the plane's, the variances are a²/2 and b²/2, the heights above the plane vanish."""
    t = np.linspace(0.0, 2.0 * math.pi, 400, endpoint=False)
    flat = np.column_stack([3.0 * np.cos(t), np.sin(t), np.zeros_like(t)])
    q, _ = np.linalg.qr(np.random.default_rng(4).normal(size=(3, 3)))
    x = flat @ q.T + np.array([1.0, -2.0, 5.0])
    pa = principal_axes(x)
    assert np.allclose(pa.centroid, [1.0, -2.0, 5.0], atol=1e-12)
    assert abs(pa.normal @ q[:, 2]) == pytest.approx(1.0, abs=1e-12)
    assert abs(pa.axes[0] @ q[:, 0]) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(pa.eigenvalues, [4.5, 0.5, 0.0], atol=1e-12)
    r2, r3 = pa.ratios()
    assert r2 == pytest.approx(1.0 / 9.0) and r3 == pytest.approx(0.0, abs=1e-12)
    inplane, heights = pa.project(x)
    assert np.allclose(heights, 0.0, atol=1e-12)
    assert np.allclose(np.linalg.norm(inplane, axis=1), np.linalg.norm(flat, axis=1))
