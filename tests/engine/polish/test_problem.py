"""The final minimiser's problem (:mod:`stiffknots.engine.polish.problem`): its sparse
Jacobian against central differences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis"


def fixture_chain(name: str) -> np.ndarray:
    return np.load(DATA / f"{name}.npy")


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_jacobian_rows_are_the_constraint_gradients(exclusion):
    """The polish's Jacobian (assembled from triplets) holds ∇(|b_k|² − 1) for every bond
    and ∇g_p for every exclusion piece near contact, by central differences on a tight 5_2
    state, and the six gauge rows where asked for."""
    from stiffknots.engine.polish.problem import EXCLUSIONS, _Problem

    x = fixture_chain("5_2_seed1_r1")
    n = len(x)
    prob = _Problem(n, True, EXCLUSIONS.index(exclusion), 1 / np.sqrt(2), 0, False, 0.0)
    cons = prob.candidates(x, 0.3)
    assert len(cons) > 10, "no piece near contact: the test tested nothing"
    _, b = prob.bond_residual(x)
    _, _, wts, direc = cons.evaluate(x)
    jac = prob.jacobian(x, b, cons.idx, wts, direc, rigid=False).toarray()
    assert jac.shape == (n + len(cons), 3 * n)

    def values(y):
        return np.r_[prob.bond_residual(y)[0], cons.evaluate(y)[1]]

    h = 1e-6
    num = np.empty_like(jac)
    for col in range(3 * n):
        e = np.zeros(3 * n)
        e[col] = h
        num[:, col] = (values(x + e.reshape(n, 3)) - values(x - e.reshape(n, 3))) / (2 * h)
    np.testing.assert_allclose(jac, num, atol=1e-6)
    gauge = prob.jacobian(x, b, cons.idx, wts, direc, rigid=True)
    assert gauge.shape == (n + 6 + len(cons), 3 * n)
    np.testing.assert_array_equal(gauge[n:n + 6].toarray(), prob.rigid_rows(x).toarray())
    np.testing.assert_array_equal(gauge[n + 6:].toarray(), jac[n:])
