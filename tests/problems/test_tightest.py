"""The restricted-curvature search (§IX D) on the unknot: a circle, L†/R = 2π."""

from __future__ import annotations

import math

import pytest

from stiffknots.problems.tightest import tightest


@pytest.mark.parametrize("seed", [0, 3])
def test_unknot_tightest_ends_without_a_bookkeeping_alarm(seed):
    # the power energy of the unknot's tight state (a circle of tiny energy) rounds to
    # ≈ 1.3e-9 of E inside a chunk; the 1e-9 check raised EnergyBookkeepingError
    r = tightest("0_1", moves=100_000, replicas=1, seed=seed, workers=1)
    assert r.best.knot == "0_1" and r.best.knot_verified
    assert r.best.length_over_R >= 2 * math.pi * (1 - 1e-9)  # L†/R ≥ 2π n, n = 1
