"""Tests of the cage checked by shooting (stiffknots.theory.structures.shooting): the
continuum elastica of one arc agrees with the discrete solve (§V B, §VII)."""

from __future__ import annotations

import math

import pytest

from stiffknots.theory import structures as st


def test_cage_energy(top_order_diffs):  # a few seconds (cached for the other cage tests)
    res = st.structure_energy("4C")
    eps, err = res["epsilon"], res["error"]
    assert 8.0 * math.pi**2 < eps < 129.6  # (eq. (31)) and the paper's Monte Carlo
    assert err <= 0.3
    d_level, d_order = top_order_diffs(res)
    assert err >= max(d_level, d_order)
    # the continuum shooting of one arc (an independent method) agrees
    sh = res["details"]["shooting"]
    assert sh["converged"]
    assert sh["epsilon"] == pytest.approx(eps, abs=max(err, 1e-8) + 1e-8)
    # (eq. (26)) from the first integral of (eq. (21)) along the arc
    assert sh["mu"] == pytest.approx(eps, rel=1e-8)
