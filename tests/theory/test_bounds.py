"""Tests of the energy bounds of closed, open and restricted-curvature knots."""

from __future__ import annotations

import math

import pytest

from stiffknots.theory import (
    closed_bounds,
    elastica_constants,
    eps_e,
    minimize_pbl_arc_ansatz,
    open_bounds,
    pbl_arc_length,
    restricted_curvature_bounds,
    self_consistency_limit,
    tension_from_energy,
    tension_from_eps_e,
    thick_knot_bound,
)

PI2 = math.pi**2


def test_trefoil_exact():
    b = closed_bounds(2, 2)  # 3_1
    assert b.exact
    assert b.lower == pytest.approx(8 * PI2, rel=1e-15)
    assert b.upper == pytest.approx(8 * PI2, rel=1e-15)
    assert b.attained_by == "CB"


def test_figure_eight_knot():
    b = closed_bounds(2, 3)  # 4_1
    assert not b.exact
    assert b.lower == pytest.approx(8 * PI2)
    assert b.upper == pytest.approx(18 * PI2)
    assert b.attained_by == "CB"
    assert b.eps_pbl == pytest.approx(16 * elastica_constants().eps_loop)
    lo, hi = b.energy_bounds(length=2.0, C=3.0)
    assert lo == pytest.approx(8 * PI2 * 1.5) and hi == pytest.approx(18 * PI2 * 1.5)


def test_pbl_when_i_exceeds_alpha_n():
    alpha = elastica_constants().alpha
    for n in (1, 2, 3, 5):
        i = math.ceil(alpha * n) + 1
        b = closed_bounds(n, i)
        assert i > alpha * n
        assert b.attained_by == "PBL"
        assert b.upper == pytest.approx(4 * n * n * elastica_constants().eps_loop)
        assert b.upper == pytest.approx(2 * PI2 * alpha**2 * n * n)
        assert b.upper < b.eps_cb
    # crossover: i <= alpha n -> CB
    assert closed_bounds(2, 3).attained_by == "CB"  # 3 < 3.85
    assert closed_bounds(2, 4).attained_by == "PBL"  # 4 > 3.85
    assert closed_bounds(1, 1).upper == pytest.approx(2 * PI2)  # unknot: the circle


def test_unknown_data_gives_none():
    b = closed_bounds(None, 3)
    assert b.lower is None and b.eps_pbl is None and b.attained_by is None
    assert b.eps_cb == pytest.approx(18 * PI2) and b.upper == b.eps_cb and not b.exact
    b = closed_bounds(2, None)
    assert b.eps_cb is None and b.lower == pytest.approx(8 * PI2) and b.attained_by is None
    b = closed_bounds(None, None)
    assert b.lower is None and b.upper is None
    o = open_bounds(None, None)
    assert o.lower is None and o.upper is None and o.n1 is None


@pytest.mark.parametrize("n,i", [(0, 1), (3, 2), (-1, None), (None, 0), (2.0, 3), (True, 2)])
def test_invalid_input(n, i):
    with pytest.raises(ValueError):
        closed_bounds(n, i)


def test_open_trefoil_exact():
    o = open_bounds(2, 2)
    assert (o.n1, o.i1) == (1, 1)
    assert o.exact
    assert o.lower == pytest.approx(2 * PI2) and o.upper == pytest.approx(2 * PI2)
    lo, hi = o.tension_bounds(L_e=2.0)
    assert lo == pytest.approx(2 * PI2 / 4) and hi == pytest.approx(2 * PI2 / 4)


def test_open_bounds_use_alpha_squared():
    c = elastica_constants()
    o = open_bounds(3, 6)  # n1 = 2, i1 = 5 > alpha n1: PBL, with alpha^2 (misprint fixed)
    assert o.attained_by == "PBL"
    assert o.upper == pytest.approx(2 * PI2 * c.alpha**2 * 4)
    assert o.upper == pytest.approx(16 * c.eps_loop)
    o = open_bounds(3, 4)  # n1 = 2, i1 = 3 -> CB
    assert o.attained_by == "CB" and o.upper == pytest.approx(18 * PI2)
    o = open_bounds(1, 1)
    assert o.lower == 0.0 and o.upper == 0.0 and o.exact


def test_restricted_curvature():
    r = restricted_curvature_bounds(2, 2, R=0.5)
    assert r.exact and r.lower == pytest.approx(2 * math.pi) and r.upper == pytest.approx(
        2 * math.pi)
    r = restricted_curvature_bounds(3, 8, R=1.0)  # 8 > 7 -> PBL
    assert r.attained_by == "PBL" and r.upper == pytest.approx(14 * math.pi)
    r = restricted_curvature_bounds(3, 7)
    assert r.attained_by == "CB" and r.upper == pytest.approx(14 * math.pi)
    with pytest.raises(ValueError):
        restricted_curvature_bounds(2, 3, R=0.0)


@pytest.mark.parametrize("n,R", [(1, 1.0), (2, 1.0), (3, 0.25)])
def test_pbl_arc_ansatz_minimum(n, R):
    res = minimize_pbl_arc_ansatz(n, R)
    assert res.R1 == pytest.approx(R, rel=1e-9)
    assert res.R2 == pytest.approx(R, rel=1e-9)
    assert res.theta == pytest.approx(math.pi / 3, rel=1e-9)
    assert res.length == pytest.approx(2 * n * R * 7 * math.pi / 3, rel=1e-12)
    assert res.length == pytest.approx(restricted_curvature_bounds(n, 10 * n, R).l_pbl)
    # the geometric relation of the ansatz
    assert res.R1 * math.cos(res.theta) == pytest.approx(res.R2 * (1 - math.cos(res.theta)))
    # any admissible point is longer
    assert pbl_arc_length(1.3 * R, R, n)[0] > res.length
    assert pbl_arc_length(R, 1.3 * R, n)[0] > res.length


def test_thick_and_self_consistency():
    assert thick_knot_bound(10.0) == pytest.approx(200.0)
    assert self_consistency_limit(2) == pytest.approx(1 / (4 * math.pi))
    with pytest.raises(ValueError):
        thick_knot_bound(0.0)


def test_tension_relations():
    E, L_e, C = 3.0, 2.0, 1.5
    mu = tension_from_energy(E, L_e)
    assert mu == pytest.approx(1.5)
    e = eps_e(E, L_e, C)
    assert e == pytest.approx(4.0)
    assert tension_from_eps_e(e, L_e, C) == pytest.approx(mu)  # (eq. (41))
