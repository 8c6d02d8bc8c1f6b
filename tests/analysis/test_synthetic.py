"""Tests of the synthetic chains (stiffknots.analysis.synthetic): unit bonds, as the analysis
assumes, and the geometry each one stands for."""

import math

import numpy as np
import pytest

from stiffknots.analysis.geometry import (
    arc_lengths,
    axis_winding,
    count_inflections,
    planar_signed_turns,
    principal_axes,
)
from stiffknots.analysis.synthetic import (
    eight_plus_circle,
    four_cage,
    random_compact_chain,
    resample_closed,
    torus_braid,
)
from stiffknots.chain import Chain


@pytest.mark.parametrize("make", [
    lambda: torus_braid(2), lambda: torus_braid(3, 300), lambda: eight_plus_circle(),
    lambda: eight_plus_circle(inside=False), lambda: four_cage(), lambda: four_cage(300),
    lambda: random_compact_chain(150, seed=1),
], ids=["CB(2)", "CB(3)", "80", "80-outside", "4C", "4C-300", "random"])
def test_every_chain_is_closed_with_unit_bonds(make):
    """The analysis reads contacts at the bead rule of unit bonds: every synthetic chain has
    bonds of length 1 to 1e-3 (stiffknots.analysis.structure.ANALYSIS_BOND_TOL is 1e-2)."""
    x = make()
    assert x.ndim == 2 and x.shape[1] == 3 and x.dtype == float
    assert np.abs(arc_lengths(x, closed=True) - 1.0).max() < 1e-3


def test_resampled_circle_is_the_regular_polygon():
    """Beads equally spaced in arc length on a circle form the regular n-gon: with unit bonds
    its circumradius is 1 / (2 sin(π/n))."""
    t = np.linspace(0.0, 2.0 * math.pi, 5000, endpoint=False)
    x = resample_closed(np.column_stack([np.cos(t), np.sin(t)]), 60)
    r = np.linalg.norm(x - x.mean(axis=0), axis=1)
    assert np.allclose(r, 1.0 / (2.0 * math.sin(math.pi / 60)), rtol=1e-5)
    with pytest.raises(ValueError, match="n must be an integer"):
        resample_closed(np.column_stack([np.cos(t), np.sin(t)]), 3)


@pytest.mark.parametrize("i", [2, 3])
def test_torus_braid_is_an_i_times_covered_circle(i):
    """CB(i) (§VI A): the chain winds i times about its axis with no inflection, and its
    energy is close to the circular braid's ε = 2π² i² (eq. (30))."""
    x = torus_braid(i, 100 * i)
    pa = principal_axes(x)
    p, _ = pa.project(x)
    assert abs(axis_winding(p)[0]) == pytest.approx(i)
    assert count_inflections(planar_signed_turns(p)) == 0
    assert Chain(x).epsilon() == pytest.approx(2.0 * math.pi**2 * i * i, rel=0.01)
