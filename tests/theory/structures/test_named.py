"""Tests of the named structures (stiffknots.theory.structures.named) solved at w = 0 (paper
§V B, §VI, §VII, Appendix C/D).

The solver never sees the closed formulas: (eq. (30)) 2 pi^2 i^2, the 80's
(eps_8^(1/2) + (2 pi^2)^(1/2))^2 and (eq. (29)) 4 n^2 eps_loop are what it is compared to,
with eps_8 and eps_loop from the Appendix D integrals (stiffknots.theory.elastica).
"""

from __future__ import annotations

import math

import pytest

from stiffknots.theory import elastica_constants
from stiffknots.theory import structures as st

EPS_0 = 2.0 * math.pi**2
EPS_80 = (math.sqrt(56.2198048706607) + math.sqrt(EPS_0)) ** 2  # 142.584368220781


@pytest.mark.parametrize("i", [1, 2, 3])
def test_circular_braid(i):
    res = st.structure_energy(f"CB({i})")
    exact = EPS_0 * i * i
    assert res["epsilon"] == pytest.approx(exact, rel=1e-6)
    assert abs(res["epsilon"] - exact) <= res["error"] + 1e-12 * exact
    assert res["error"] < 1e-6 * exact
    d = res["details"]
    # the start was a wobbly non-planar ellipse, not the circle
    assert d["coarse_search"]["start_epsilon"] > 1.05 * d["coarse_search"]["epsilon"]
    # a circle: every arc is free of force, A_p = 0 (App. C case i)
    assert d["arcs"]["braid"]["force_A_over_mu"] < 1e-8
    assert d["stability"]["negative"] == 0


def test_eighty_energy():
    res = st.structure_energy("80")
    assert res["epsilon"] == pytest.approx(EPS_80, abs=1e-6)
    assert abs(res["epsilon"] - EPS_80) <= res["error"] + 1e-12 * EPS_80
    assert res["error"] < 1e-6
    assert EPS_80 == pytest.approx(elastica_constants().eps_80, abs=1e-9)


@pytest.mark.slow
def test_eighty_energy_does_not_depend_on_the_contact_point():
    res = st.solve_structure(st.eighty(contact=0.25), (16, 32, 64, 128, 256), orders=3)
    assert res.epsilon == pytest.approx(EPS_80, abs=1e-6)
    assert res.best.lengths[0] / (res.best.lengths[0] + res.best.lengths[2]) == pytest.approx(
        0.25, abs=1e-12)


def test_point_braid_loops():
    res = st.structure_energy("PBL(1)")
    exact = 4.0 * elastica_constants().eps_loop
    assert res["epsilon"] == pytest.approx(exact, abs=1e-6)
    assert abs(res["epsilon"] - exact) <= res["error"] + 1e-12 * exact
    bal = res["details"]["balance"]
    assert all(v < 1e-6 for v in bal.values())


@pytest.mark.slow
@pytest.mark.parametrize("kw", [dict(start_angle=45.0), dict(start_angle=120.0, twist=0.5),
                                dict(radius=0.5, twist=-0.8)])
def test_cage_other_starts_find_the_same_minimum(kw):
    ref = st.solve_structure(st.four_fold_cage(), (16, 32, 64), orders=2)
    res = st.solve_structure(st.four_fold_cage(**kw), (16, 32, 64), orders=2)
    assert res.epsilon == pytest.approx(ref.epsilon, abs=1e-8)


def test_newton_first_from_a_rough_start_falls_back_to_the_search():
    """The cage's rough start is no stationary point Newton reaches: with ``newton_first`` the
    coarse search still runs and finds the same minimum."""
    ref = st.solve_structure(st.four_fold_cage(), (8, 16), orders=1)
    res = st.solve_structure(st.four_fold_cage(), (8, 16), orders=1, newton_first=True)
    assert not res.coarse["newton_first"] and res.coarse["nit"] > 10
    assert res.epsilon == pytest.approx(ref.epsilon, abs=1e-9)


def test_the_coarse_search_stops_at_its_time_budget():
    """Past ``coarse_budget_s`` SLSQP stops after its iteration and no escape is tried (the
    same start without a budget takes > 10 iterations: the test above)."""
    res = st.solve_structure(st.four_fold_cage(), (8, 16), orders=1, coarse_budget_s=0.0)
    assert res.coarse["budget_hit"] and res.coarse["nit"] == 1
    assert res.coarse["saddle_escapes"] == 0 and not res.coarse["success"]
