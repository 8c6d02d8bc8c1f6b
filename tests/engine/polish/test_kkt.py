"""The final minimiser's linear algebra (:mod:`stiffknots.engine.polish.kkt`): the KKT matrix,
the min-norm projection, and SuperLU's diagnostics held back on singular matrices."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine.polish import polish

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis"


def fixture_chain(name: str) -> np.ndarray:
    return np.load(DATA / f"{name}.npy")


@pytest.mark.parametrize("reg", [0.0, 1e-12])
def test_kkt_matrix_is_the_block_matrix(reg):
    """The KKT matrix assembled from the blocks' triplets is [h aᵀ; a −reg·I] entry by
    entry (the polish factorises it; sp.bmat built the same matrix before)."""
    import scipy.sparse as sp

    from stiffknots.engine.polish.kkt import _kkt_matrix

    h = sp.random(90, 90, density=0.05, random_state=1, format="csr")
    h = (h + h.T + sp.identity(90)).tocsr()
    a = sp.random(31, 90, density=0.05, random_state=2, format="csr")
    lower = -reg * sp.identity(31) if reg > 0 else None
    want = sp.bmat([[h, a.T], [a, lower]], format="csc")
    got = _kkt_matrix(h, a, reg)
    assert got.format == "csc" and got.shape == (121, 121) and got.nnz == want.nnz
    assert abs(got - want).max() == 0.0


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("dense_rows", [0, 10**6], ids=["sparse-gram", "dense-gram"])
def test_min_norm_solver_is_the_projection_kkt_solution(monkeypatch, exclusion, dense_rows):
    """The projection's correction dx = Aᵀ(AAᵀ)⁻¹r (dense Cholesky or sparse LU of the Gram
    matrix) equals the solution of the full KKT system [I Aᵀ; A 0][dx; y] = [0; r] it
    replaced, on a tight 5_2 state with pieces near contact and a clamped open end."""
    import scipy.sparse as sp

    import stiffknots.engine.polish.kkt as P
    from stiffknots.engine.polish.problem import EXCLUSIONS, _Problem

    monkeypatch.setattr(P, "DENSE_GRAM_ROWS", dense_rows)
    x = fixture_chain("5_2_seed1_r1")
    for closed, nfix in ((True, 0), (False, 2)):
        prob = _Problem(len(x), closed, EXCLUSIONS.index(exclusion), 1 / np.sqrt(2), nfix,
                        False, 0.0)
        cons = prob.candidates(x, 0.3)
        _, _, wts, direc = cons.evaluate(x)
        # independent rows: the bonds and every third piece (neighbouring pieces of one
        # contact can be dependent, where only the regularised systems agree)
        sel = np.arange(0, len(cons), 3)
        assert len(sel) > 5, "no piece near contact: the test tested nothing"
        _, b = prob.bond_residual(x)
        a = prob.jacobian(x, b, cons.idx[sel], wts[sel], direc[sel], rigid=False)
        rhs = a @ np.random.default_rng(1).normal(size=a.shape[1]) * 1e-3  # consistent
        nf3 = 3 * prob.nf
        lu = P._factor_kkt(sp.identity(nf3, format="csr"), a)
        want = lu.solve(np.r_[np.zeros(nf3), rhs])[:nf3].reshape(-1, 3)
        solver = P._MinNormSolver(prob, b, cons.idx[sel], wts[sel], direc[sel])
        got = solver.solve(rhs)
        assert got.shape == (prob.nf, 3)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
        np.testing.assert_allclose(a @ got.ravel(), rhs, rtol=0, atol=1e-12)


@pytest.mark.parametrize("dense_rows", [0, 10**6], ids=["sparse-gram", "dense-gram"])
def test_a_singular_kkt_matrix_prints_nothing(capfd, monkeypatch, dense_rows):
    # a tube-model 3_1 whose polish meets an exactly singular KKT matrix (dependent pieces):
    # SuperLU printed "** On entry to DTRSV parameter number 6 had an illegal value" on C's
    # stdout before raising the error that the regularised retry handles. The projection's
    # Gram matrix AAᵀ is singular there too: factorised sparse (SuperLU) or dense (Cholesky,
    # which raises), it is regularised and the polish converges either way.
    import stiffknots.engine.polish.kkt as P

    monkeypatch.setattr(P, "DENSE_GRAM_ROWS", dense_rows)

    x = np.load(DATA.parent / "polish" / "3_1_tube_singular_kkt.npy")
    singular = []
    real_lu, real_cho = P.splu, P.scipy.linalg.cho_factor

    def counting_lu(k):
        try:
            return real_lu(k)
        except RuntimeError:
            singular.append(("lu", k.shape))
            raise

    def counting_cho(g, **kw):
        try:
            return real_cho(g, **kw)
        except np.linalg.LinAlgError:
            singular.append(("cholesky", g.shape))
            raise

    monkeypatch.setattr(P, "splu", counting_lu)
    monkeypatch.setattr(P.scipy.linalg, "cho_factor", counting_cho)
    r = polish(x, exclusion="tube")
    monkeypatch.undo()
    kinds = {k for k, _ in singular}
    assert kinds >= ({"lu"} if dense_rows == 0 else {"cholesky"}), singular
    assert singular, "the fixture no longer meets a singular matrix"
    out, err = capfd.readouterr()
    assert "On entry to" not in out + err
    assert r.converged and r.energy < r.energy_before
    assert r.max_bond_error < 1e-10 and r.exclusion_margin >= 0


@pytest.mark.slow  # ≈ 20 s
def test_held_diagnostics_restore_the_descriptors_with_threads():
    # threads that factorise at once share one redirection of fds 1 and 2: none may save
    # another's /dev/null and leave the process without its output
    import os
    import threading

    x = np.load(DATA.parent / "polish" / "3_1_tube_singular_kkt.npy")
    before = [os.path.realpath(f"/proc/self/fd/{fd}") for fd in (1, 2)]
    threads = [threading.Thread(target=polish, args=(x,), kwargs={"exclusion": "tube"})
               for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert [os.path.realpath(f"/proc/self/fd/{fd}") for fd in (1, 2)] == before
    assert "/dev/null" not in before
