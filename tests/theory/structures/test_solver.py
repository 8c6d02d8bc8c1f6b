"""Tests of the w = 0 solver (stiffknots.theory.structures.solver): Richardson extrapolation,
the discrete levels, the error estimate and the tension multiplier (eq. (26))."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.theory import structures as st


def test_richardson_removes_even_powers():
    Ks = np.array([8, 16, 32, 64])
    v = 3.0 + 2.0 / Ks**2 - 5.0 / Ks**4 + 7.0 / Ks**6
    R = st.richardson(v)
    assert R[-1, 3] == pytest.approx(3.0, abs=1e-13)
    # one order removed leaves an O(K^-4) error, not zero
    assert abs(R[-1, 1] - 3.0) > 1e-8


def test_circular_braid_discrete_levels_are_polygons():
    # the discrete minimiser is the regular K-gon: eps_K = 2 pi^2 i^2 [sin(pi/K)/(pi/K)]^2
    res = st.structure_energy("CB(2)")
    for K, eps in res["details"]["epsilon_K"].items():
        y = math.pi / K
        assert eps == pytest.approx(8.0 * math.pi**2 * (math.sin(y) / y) ** 2, rel=1e-12)


@pytest.mark.parametrize("name", ["80", "PBL(1)", "CB(3)"])
def test_error_covers_successive_extrapolations(name, top_order_diffs):
    res = st.structure_energy(name)
    d_level, d_order = top_order_diffs(res)
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
