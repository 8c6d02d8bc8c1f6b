"""The checks of the public parameters (problems/validate): ranges, the N rule and the width
of a problem from its options."""

from __future__ import annotations

import math

import pytest

from stiffknots.errors import InvalidParameter, ParameterConflict
from stiffknots.problems import validate as V
from stiffknots.width import Width


def test_ranges_name_the_parameter_and_what_is_allowed():
    assert V.integer("n", 4.0, 1, 10) == 4
    with pytest.raises(InvalidParameter, match=r"n must be an integer in \[1, 10\], got 11"):
        V.integer("n", 11, 1, 10)
    with pytest.raises(InvalidParameter, match="x must be a finite number > 0"):
        V.number("x", 0.0, 0, lo_open=True)
    with pytest.raises(InvalidParameter):
        V.number("x", float("inf"))
    with pytest.raises(InvalidParameter):
        V.integer("n", True)
    assert V.beads(8) == 8 and V.moves(1_000) == 1_000
    with pytest.raises(InvalidParameter, match="beads must be an integer in"):
        V.beads(7)


def test_the_N_rule_bounds_the_discretisation_error():
    # ε/(6N²) ≤ rel_error: the smallest such N
    for eps, rel in ((8 * math.pi**2, 1e-3), (18 * math.pi**2, 2e-3)):
        n = V.beads_for_width(0.001, eps, rel)
        assert eps / (6 * n**2) <= rel < eps / (6 * (n - 1) ** 2)
    with pytest.raises(InvalidParameter, match="or give --beads"):
        V.beads_for_width(0.1, 8 * math.pi**2)


def test_problem_width_cross_checks():
    assert V.width(150) == Width.bead(150)
    assert V.width(150, "tube") == Width.tube(150)
    assert V.width(150, "bead", w_over_L=0.002) == Width.tube(150, w_over_L=0.002)
    assert V.width(150, "tube", w=0.4, default_w=None).thickness == 0.4
    with pytest.raises(ParameterConflict) as e:
        V.width(150, "tube", w=0.5, w_over_L=0.001)
    assert e.value.message(lambda p: "--" + p) == (
        "--w and --w_over_L both set the tube's diameter; give one")
    with pytest.raises(ParameterConflict, match="w applies to exclusion tube only"):
        V.width(150, "bead", w=0.5)
    with pytest.raises(InvalidParameter, match="w_over_L must be a number in"):
        V.width(150, "tube", default_w=None)


