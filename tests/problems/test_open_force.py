"""Open knots at fixed force (problems/open_force) and the width of open chains: the start the
force selects, and a tube given by w/L measured on the open chain's own length N − 1."""

from __future__ import annotations

import math

import pytest

from stiffknots.errors import InvalidParameter, ParameterConflict
from stiffknots.problems.open_extension import (
    DEFAULT_OPEN_W,
    OpenExtension,
    open_params,
)
from stiffknots.problems.open_force import OpenForce
from stiffknots.width import Width


def test_the_start_sits_near_the_excess_length_the_force_selects():
    p = OpenForce("3_1", 0.5, moves=2_000, replicas=1)
    # (ε_e C/F)^½ with ε_e the lower bound 2π² n₁² = 2π² (3_1: n₁ = 1)
    assert p.start_excess_length >= round(math.sqrt(2 * math.pi**2 / 0.5))
    assert p.width() == Width.tube(p.beads, w=DEFAULT_OPEN_W, closed=False)


@pytest.mark.parametrize("make", [
    lambda wl: OpenForce("3_1", 0.5, moves=2_000, replicas=1, w_over_L=wl),
    lambda wl: OpenExtension("3_1", 40, moves=2_000, replicas=1, w_over_L=wl),
])
def test_w_over_L_of_an_open_chain_is_over_its_length(make):
    p = make(0.001)
    assert p.settings.params.exclusion == "tube"
    assert p.settings.params.w == pytest.approx(0.001 * (p.beads - 1), rel=1e-15)
    w = p.width()
    assert not w.closed and w.length == p.beads - 1
    assert w.w_over_L == pytest.approx(0.001, rel=1e-12)


def test_width_options_of_open_knots_are_cross_checked():
    assert open_params().w == DEFAULT_OPEN_W and open_params().exclusion == "tube"
    assert open_params("bead").exclusion == "bead"
    assert open_params("bead", w_over_L=0.001).exclusion == "tube"
    with pytest.raises(ParameterConflict, match="w applies to exclusion tube only"):
        open_params("bead", w=0.1)
    with pytest.raises(ParameterConflict, match="both set the tube's diameter"):
        open_params(w=0.1, w_over_L=0.001)
    with pytest.raises(InvalidParameter, match="w_over_L"):
        open_params(w_over_L=0.5)
    with pytest.raises(InvalidParameter, match=r"below 1/\(N − 1\)"):
        OpenExtension("3_1", 40, moves=2_000, replicas=1, w_over_L=0.1)
