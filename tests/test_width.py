"""One Width: built from w or from w/L, the same numbers either way; its text, its dict, its
checks, and the parameters of the engine it makes."""

from __future__ import annotations

import math

import pytest

from stiffknots.engine.params import MoveParams
from stiffknots.errors import InvalidParameter
from stiffknots.width import BEAD_D, MAX_W_OVER_L, Width


def test_built_from_w_or_from_w_over_L_is_one_width():
    a = Width.tube(200, w=0.8)
    b = Width.tube(200, w_over_L=0.004)
    assert a.thickness == pytest.approx(b.thickness, rel=1e-15)
    assert a.w_over_L == pytest.approx(b.w_over_L, rel=1e-15)
    # each keeps the number it was given exactly
    assert a.thickness == 0.8 and b.w_over_L == 0.004
    assert b.thickness == 0.004 * 200


def test_open_chain_length_is_N_minus_1():
    w = Width.tube(101, w_over_L=0.001, closed=False)
    assert w.length == 100 and w.thickness == pytest.approx(0.1)
    assert Width.bead(101, closed=False).w_over_L == pytest.approx(BEAD_D / 100)


def test_text_says_the_model_N_and_w_over_L():
    assert Width.bead(150).text == "bead rule d = 1/√2, N = 150 (w/L ≈ 0.0047)"
    assert Width.tube(150).text == "tube w = 1/√2, N = 150 (w/L = 0.0047)"
    assert Width.tube(150, w=0.6).text == "tube w = 0.6, N = 150 (w/L = 0.004)"
    assert Width.tube(150, w=0.6).short == "tube w = 0.6, N = 150"
    assert str(Width.bead(150)) == Width.bead(150).text


def test_dict_round_trip_and_keys():
    for w in (Width.bead(150), Width.tube(173, w_over_L=0.002), Width.tube(90, w=0.3,
                                                                            closed=False)):
        d = w.as_dict()
        assert Width.from_dict(d) == w
        assert d["text"] == w.text and d["beads"] == w.beads
        assert ("w" in d) == (w.exclusion == "tube") and ("d" in d) == (w.exclusion == "bead")


@pytest.mark.parametrize("make, param", [
    (lambda: Width.tube(150, w=1.0), "w"),            # a tube as wide as a bond
    (lambda: Width.tube(150, w=0.0), "w"),
    (lambda: Width.bead(150, d=float("nan")), "d"),
    (lambda: Width.tube(150, w_over_L=0.0), "w_over_L"),
    (lambda: Width.tube(150, w_over_L=MAX_W_OVER_L * 1.01), "w_over_L"),
    (lambda: Width.tube(150, w_over_L=0.01), "w_over_L"),  # w = 1.5 bonds
    (lambda: Width.tube(150, w=0.5, w_over_L=0.001), "w_over_L"),
    (lambda: Width.of("soft", 0.5, 150), "exclusion"),
    (lambda: Width("tube", 0.6, 150, 0.005), "w_over_L"),  # numbers that disagree
])
def test_refused_widths_name_the_parameter(make, param):
    with pytest.raises(InvalidParameter) as e:
        make()
    assert e.value.param == param


def test_below_one_bond_message_names_N():
    with pytest.raises(InvalidParameter, match=r"below 1/N = 0\.005.*N = 200"):
        Width.tube(200, w_over_L=0.006)


def test_engine_parameters_of_a_width_and_back():
    w = Width.tube(240, w_over_L=0.003)
    p = MoveParams().at_width(w)
    assert (p.exclusion, p.w) == ("tube", w.thickness)
    assert p.width(240) == Width.tube(240, w=w.thickness)
    assert p.width(240).w_over_L == pytest.approx(0.003, rel=1e-15)
    b = MoveParams(exclusion="tube", w=0.3).at_width(Width.bead(150))
    assert (b.exclusion, b.d) == ("bead", BEAD_D)


def test_w_over_L_of_a_tube_is_its_diameter_over_its_length():
    for n in (8, 150, 1000):
        w = Width.tube(n, w_over_L=1 / (2 * n))
        assert math.isclose(w.thickness, 0.5)
