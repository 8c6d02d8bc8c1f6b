"""Tests of the structure route to the thin limit w = 0 (paper §V B, §VI, §VII, Appendix C/D).

The solver never sees the closed formulas: (eq. (30)) 2 pi^2 i^2, the 80's
(eps_8^(1/2) + (2 pi^2)^(1/2))^2 and (eq. (29)) 4 n^2 eps_loop are what it is compared to,
with eps_8 and eps_loop from the Appendix D integrals (stiffknots.theory.elastica).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.theory import elastica_constants
from stiffknots.theory import structures as st

EPS_0 = 2.0 * math.pi**2
EPS_80 = (math.sqrt(56.2198048706607) + math.sqrt(EPS_0)) ** 2  # 142.584368220781


def _top_order_diffs(res: dict) -> tuple[float, float]:
    """Differences of the best extrapolation to the one a level coarser / an order lower."""
    R = np.array([[np.nan if v is None else v for v in row]
                  for row in res["details"]["richardson_table"]])
    k = R.shape[1] - 1
    return abs(R[-1, k] - R[-2, k]), abs(R[-1, k] - R[-1, k - 1])


# ------------------------------------------------------------------------------------------
# Richardson extrapolation
# ------------------------------------------------------------------------------------------
def test_richardson_removes_even_powers():
    Ks = np.array([8, 16, 32, 64])
    v = 3.0 + 2.0 / Ks**2 - 5.0 / Ks**4 + 7.0 / Ks**6
    R = st.richardson(v)
    assert R[-1, 3] == pytest.approx(3.0, abs=1e-13)
    # one order removed leaves an O(K^-4) error, not zero
    assert abs(R[-1, 1] - 3.0) > 1e-8


# ------------------------------------------------------------------------------------------
# Circular braids: eps_CB = 2 pi^2 i^2 (eq. (30))
# ------------------------------------------------------------------------------------------
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


def test_circular_braid_discrete_levels_are_polygons():
    # the discrete minimiser is the regular K-gon: eps_K = 2 pi^2 i^2 [sin(pi/K)/(pi/K)]^2
    res = st.structure_energy("CB(2)")
    for K, eps in res["details"]["epsilon_K"].items():
        y = math.pi / K
        assert eps == pytest.approx(8.0 * math.pi**2 * (math.sin(y) / y) ** 2, rel=1e-12)


# ------------------------------------------------------------------------------------------
# The 80 (§VII)
# ------------------------------------------------------------------------------------------
def test_eighty_energy():
    res = st.structure_energy("80")
    assert res["epsilon"] == pytest.approx(EPS_80, abs=1e-6)
    assert abs(res["epsilon"] - EPS_80) <= res["error"] + 1e-12 * EPS_80
    assert res["error"] < 1e-6
    assert EPS_80 == pytest.approx(elastica_constants().eps_80, abs=1e-9)


def test_eighty_solution_is_two_free_closed_elastica():
    c = elastica_constants()
    d = st.structure_energy("80")["details"]
    # (eq. (28)): L_0 / L = (2 pi^2 / eps_80)^(1/2) (K = 256 level: O(K^-2) accuracy)
    assert d["length_fraction_circle"] == pytest.approx(math.sqrt(EPS_0 / EPS_80), abs=1e-4)
    # no force between the circle and the 8 (§VII); the 8 carries A / mu = alpha_8 (App. D)
    assert d["force_on_circle_over_mu"] < 1e-8
    for f in d["force_8_over_mu"]:
        assert f == pytest.approx(c.alpha_8, abs=1e-3)
    # planar (the circle may only turn about the bunch axis, a zero mode)
    assert d["out_of_plane_extent_over_L"] < 1e-4
    assert d["stability"]["negative"] == 0
    assert d["coarse_search"]["start_epsilon"] > d["coarse_search"]["epsilon"] + 5.0


@pytest.mark.slow
def test_eighty_energy_does_not_depend_on_the_contact_point():
    res = st.solve_structure(st.eighty(contact=0.25), (16, 32, 64, 128, 256), orders=3)
    assert res.epsilon == pytest.approx(EPS_80, abs=1e-6)
    assert res.best.lengths[0] / (res.best.lengths[0] + res.best.lengths[2]) == pytest.approx(
        0.25, abs=1e-12)


# ------------------------------------------------------------------------------------------
# Point-braid and loops (eq. (29)): clamped ends at a point-braid
# ------------------------------------------------------------------------------------------
def test_point_braid_loops():
    res = st.structure_energy("PBL(1)")
    exact = 4.0 * elastica_constants().eps_loop
    assert res["epsilon"] == pytest.approx(exact, abs=1e-6)
    assert abs(res["epsilon"] - exact) <= res["error"] + 1e-12 * exact
    bal = res["details"]["balance"]
    assert all(v < 1e-6 for v in bal.values())


# ------------------------------------------------------------------------------------------
# Convergence of the extrapolation
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["80", "PBL(1)", "CB(3)"])
def test_error_covers_successive_extrapolations(name):
    res = st.structure_energy(name)
    d_level, d_order = _top_order_diffs(res)
    assert res["error"] >= d_level
    assert res["error"] >= d_order


@pytest.mark.parametrize("name", ["80", "PBL(1)"])
def test_discretisation_error_is_clean_k_minus_2(name):
    eps = list(st.structure_energy(name)["details"]["epsilon_K"].values())
    d = np.diff(eps)
    ratios = d[:-1] / d[1:]
    # E_K - E = c/K^2 + O(K^-4): successive differences shrink by 4 (approached from below)
    assert np.all(np.abs(ratios - 4.0) < 0.2)
    assert abs(ratios[-1] - 4.0) < 0.01


def test_tension_is_energy_over_length():
    # (eq. (26)): the multiplier of the length constraint is mu = E / L
    for name in ("80", "PBL(1)"):
        d = st.structure_energy(name)["details"]
        assert d["mu_minus_E_over_L"] == pytest.approx(0.0, abs=1e-8)


# ------------------------------------------------------------------------------------------
# The 4-fold cage
# ------------------------------------------------------------------------------------------
def test_cage_energy():  # a few seconds (cached for the next test)
    res = st.structure_energy("4C")
    eps, err = res["epsilon"], res["error"]
    assert 8.0 * math.pi**2 < eps < 129.6  # (eq. (31)) and the paper's Monte Carlo
    assert err <= 0.3
    d_level, d_order = _top_order_diffs(res)
    assert err >= max(d_level, d_order)
    # the continuum shooting of one arc (an independent method) agrees
    sh = res["details"]["shooting"]
    assert sh["converged"]
    assert sh["epsilon"] == pytest.approx(eps, abs=max(err, 1e-8) + 1e-8)
    # (eq. (26)) from the first integral of (eq. (21)) along the arc
    assert sh["mu"] == pytest.approx(eps, rel=1e-8)


def test_cage_geometry_is_symmetric_and_embedded():
    d = st.structure_energy("4C")["details"]
    assert d["axis_angle_deg"] == pytest.approx(90.0, abs=1e-6)
    assert d["angle_a_AB_deg"] == pytest.approx(90.0, abs=1e-6)
    assert d["angle_b_AB_deg"] == pytest.approx(90.0, abs=1e-6)
    assert np.allclose(d["arc_lengths_over_L"], 0.25, atol=1e-9)
    assert d["stability"]["negative"] == 0
    assert all(v < 1e-8 for v in d["balance"].values())
    # every arc stays inside its own open quarter wedge around AB: no arc crosses another
    intervals = sorted((v["azimuth_min"], v["azimuth_max"])
                       for v in d["arc_azimuths_about_AB_deg"].values())
    for lo, hi in intervals:
        assert hi - lo < 90.0
    for (_, hi), (lo, _) in zip(intervals, intervals[1:], strict=False):
        assert hi < lo
    # arcs meet only at the point-braids
    for pairs in d["arc_distances"].values():
        assert min(p["distance"] for p in pairs.values()) > 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("kw", [dict(start_angle=45.0), dict(start_angle=120.0, twist=0.5),
                                dict(radius=0.5, twist=-0.8)])
def test_cage_other_starts_find_the_same_minimum(kw):
    ref = st.solve_structure(st.four_fold_cage(), (16, 32, 64), orders=2)
    res = st.solve_structure(st.four_fold_cage(**kw), (16, 32, 64), orders=2)
    assert res.epsilon == pytest.approx(ref.epsilon, abs=1e-8)


@pytest.mark.slow
def test_cage_perpendicular_axes_are_optimal():
    free = st.solve_structure(st.four_fold_cage(), (16, 32, 64), orders=2).epsilon
    scan = st.cage_axis_scan(angles=(60.0,), Ks=(16, 32, 64))
    assert scan[0]["epsilon"] > free + 1.0


# ------------------------------------------------------------------------------------------
# Names
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", ["CB(0)", "cb(2)", "5C", "4_1", "CB", "", "PBL(0)", 80])
def test_bad_name(bad):
    with pytest.raises(ValueError) as exc:
        st.structure_energy(bad)
    if isinstance(bad, str):
        for name in ("CB(i)", "'80'", "'4C'"):
            assert name in str(exc.value)


def test_result_is_a_copy():
    a = st.structure_energy("CB(1)")
    a["epsilon"] = 0.0
    assert st.structure_energy("CB(1)")["epsilon"] > 19.0
    assert set(a) >= {"epsilon", "error", "method", "structure", "K", "details"}
