"""Thin-limit extrapolation eps(w) = eps* + a w^p on synthetic series of known limit (§V A)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.analysis.extrapolate import extrapolate, fit_power

EPS = 8 * math.pi**2
W = np.array([0.004, 0.002, 0.001, 0.0005])


def test_fit_power_exact_series():
    f = fit_power(W, EPS + 3.0 * W**1.5, p=1.5)
    assert f.epsilon == pytest.approx(EPS, abs=1e-10)
    assert f.a == pytest.approx(3.0, rel=1e-8)
    assert f.chi2 < 1e-16


@pytest.mark.parametrize("p", [2 / 3, 1.0, 2.0])
def test_free_exponent_recovered_without_noise(p):
    a = 0.03 / 0.002**p  # an excess of 0.03 at w = 0.002, as measured for 3_1
    r = extrapolate(W, EPS + a * W**p, 1e-6)
    assert r.p_free
    assert r.p == pytest.approx(p, abs=0.011)
    assert r.epsilon == pytest.approx(EPS, abs=1e-3)


@pytest.mark.parametrize("p", [pytest.param(2 / 3, marks=pytest.mark.slow), 1.0,
                               pytest.param(2.0, marks=pytest.mark.slow)])   # ≈ 7 s each
def test_two_sigma_bar_covers_the_truth(p):
    """200 noisy series: the 2 sigma bar covers the limit in >= 90 % of them."""
    rng = np.random.default_rng(12)
    a = 0.03 / 0.002**p
    sigma = 0.003
    hits = 0
    for _ in range(200):
        eps = EPS + a * W**p + rng.normal(0.0, sigma, W.size)
        r = extrapolate(W, eps, sigma)
        assert r.error > 0
        hits += abs(r.epsilon - EPS) <= 2 * r.error
    assert hits >= 180


def test_residuals_set_the_error_when_sigma_too_small():
    rng = np.random.default_rng(3)
    hits = 0
    for _ in range(200):
        eps = EPS + 10 * W + rng.normal(0.0, 0.003, W.size)
        r = extrapolate(W, eps, 1e-9)  # stated errors far too small: the residuals decide
        hits += abs(r.epsilon - EPS) <= 2 * r.error
    assert hits >= 170


def test_three_points_hold_the_exponent():
    r = extrapolate(W[:3], EPS + 5 * W[:3])
    assert not r.p_free and r.p == 1.0
    assert r.epsilon == pytest.approx(EPS, abs=1e-9)
    assert [f.p for f in r.alternatives] == pytest.approx([2 / 3, 1, 4 / 3, 2])


@pytest.mark.parametrize("bad", [dict(w=[0.001], eps=[1.0]), dict(w=[0.0, 0.1], eps=[1, 2]),
                                 dict(w=[0.1, 0.1], eps=[1, 2]),
                                 dict(w=[0.1, 0.2], eps=[1, float("nan")])])
def test_bad_series_rejected(bad):
    with pytest.raises(ValueError):
        extrapolate(bad["w"], bad["eps"])


def test_fit_range_term_flags_a_series_not_yet_one_power_law():
    """ε* + a w^½ + b w: the local exponent drifts; leaving out the widest points moves the
    limit, and the error says so (covers the truth within 2σ)."""
    w = np.array([0.004, 0.003, 0.002, 0.0014, 0.001, 0.0007, 0.0005, 0.00035, 0.00025])
    eps = EPS + 300 * w**0.5 - 2000 * w
    r = extrapolate(w, eps, 1e-3)
    assert r.range_error > 0 and len(r.range_fits) == 4
    assert abs(r.epsilon - EPS) <= 2 * r.error
    # a pure power law: the range term stays at the noise level
    r2 = extrapolate(w, EPS + 700 * w, 1e-3)
    assert r2.range_error < 0.01 and r2.epsilon == pytest.approx(EPS, abs=0.01)
