"""The final minimiser :func:`stiffknots.engine.polish.polish` (paper §VII, §VIII).

Analytic minima (regular polygon, m-covered circle), admissibility (unit bonds, exclusion
rule), monotone energy, topology preservation on annealed tight knots and on random
admissible perturbations of them, the strand-passage guard, and clamped open chains.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine import kernel as K
from stiffknots.engine.polish import PolishResult, passage_guard, polish
from stiffknots.engine.state import ChainState, MoveParams
from stiffknots.knots.identify import close_open_chain_along_z, verify_knot

DATA = Path(__file__).resolve().parent.parent / "data" / "analysis"
D = 1 / math.sqrt(2)
MODE = {"bead": 0, "tube": 1}


# ---- helpers ---------------------------------------------------------------------------------


def regular_polygon(n: int, m: int = 1) -> np.ndarray:
    """The m-covered regular n-gon with unit bonds in the xy plane."""
    r = 0.5 / math.sin(math.pi * m / n)
    t = 2 * math.pi * m * np.arange(n) / n
    return np.c_[r * np.cos(t), r * np.sin(t), np.zeros(n)]


def crankshaft(pos: np.ndarray, rng, n_moves: int, amp: float) -> np.ndarray:
    """Random crankshaft rotations (1–5 beads about the axis through their neighbours): every
    bond keeps its length exactly, the chain leaves its plane."""
    pos = pos.copy()
    n = len(pos)
    for _ in range(n_moves):
        j = int(rng.integers(n))
        m = int(rng.integers(1, 6))
        k = (j + m + 1) % n
        ax = pos[k] - pos[j]
        ax /= np.linalg.norm(ax)
        phi = rng.normal() * amp
        c, s = math.cos(phi), math.sin(phi)
        for q in range(1, m + 1):
            b = (j + q) % n
            r = pos[b] - pos[j]
            pos[b] = pos[j] + r * c + np.cross(ax, r) * s + ax * (r @ ax) * (1 - c)
    return pos


def four_bar(pos: np.ndarray, rng, n_moves: int, amp: float) -> np.ndarray:
    """Random planar moves with exactly unit bonds: bead j+1 turns about bead j, bead j+2 goes
    to the nearer intersection of the unit circles about j+1 and j+3."""
    pos = pos.copy()
    n = len(pos)
    for _ in range(n_moves):
        j = int(rng.integers(n))
        a, b, c, d = j, (j + 1) % n, (j + 2) % n, (j + 3) % n
        phi = rng.normal() * amp
        r = pos[b, :2] - pos[a, :2]
        nb = pos[a, :2] + np.array([r[0] * math.cos(phi) - r[1] * math.sin(phi),
                                    r[0] * math.sin(phi) + r[1] * math.cos(phi)])
        dv = pos[d, :2] - nb
        ln = float(np.linalg.norm(dv))
        if not 1e-9 < ln < 2:
            continue
        mid = nb + dv / 2
        perp = np.array([-dv[1], dv[0]]) / ln * math.sqrt(1 - (ln / 2) ** 2)
        c1, c2 = mid + perp, mid - perp
        pos[b, :2] = nb
        pos[c, :2] = c1 if np.linalg.norm(c1 - pos[c, :2]) < np.linalg.norm(c2 - pos[c, :2]) \
            else c2
    return pos


def bond_error(pos: np.ndarray, closed: bool = True) -> float:
    b = (np.roll(pos, -1, axis=0) - pos) if closed else np.diff(pos, axis=0)
    return float(np.max(np.abs(np.linalg.norm(b, axis=1) - 1.0)))


def assert_admissible(res: PolishResult, exclusion: str, closed: bool = True) -> None:
    assert bond_error(res.pos, closed) <= 1e-10
    assert res.max_bond_error <= 1e-10
    if exclusion != "none":
        assert K.check_state(res.pos, MODE[exclusion], D, D, not closed) <= 1e-12
        assert res.exclusion_margin >= 0.0
    assert res.energy <= res.energy_before


def fixture_chain(name: str) -> np.ndarray:
    return np.load(DATA / f"{name}.npy")


# ---- analytic minima -------------------------------------------------------------------------


@pytest.mark.parametrize("n", [60, 150])
def test_perturbed_polygon_polishes_to_the_regular_polygon(n):
    """Closed chain, exclusion ``bead``: ε → N²(1 − cos 2π/N) (paper §VII) to 1e-9."""
    start = crankshaft(regular_polygon(n), np.random.default_rng(n), 3 * n, 0.05)
    assert bond_error(start) < 1e-12
    exact = n * n * (1 - math.cos(2 * math.pi / n))
    assert start_energy(start) * n > exact * (1 + 1e-3)  # a real perturbation
    res = polish(start)
    assert res.converged, res.reason
    assert res.energy * n == pytest.approx(exact, rel=1e-9)
    assert_admissible(res, "bead")
    assert res.n_active == 0
    assert res.kkt_residual <= 1e-6 * res.grad_norm


def start_energy(pos: np.ndarray, closed: bool = True) -> float:
    return float(K.energy_chain(pos, not closed))


@pytest.mark.parametrize("m", [2, 3])
def test_m_covered_circle_without_exclusion(m):
    """An m-covered circle perturbed in its plane (turning number m) polishes to
    ε = N²(1 − cos 2πm/N) under no exclusion; the guard is off there by default (the m-gon
    crosses itself)."""
    n = 61
    start = four_bar(regular_polygon(n, m), np.random.default_rng(m), 400, 0.05)
    assert bond_error(start) < 1e-12
    exact = n * n * (1 - math.cos(2 * math.pi * m / n))
    assert start_energy(start) * n > exact * 1.2
    res = polish(start, exclusion="none")
    assert res.converged, res.reason
    assert res.energy * n == pytest.approx(exact, rel=1e-9)
    assert_admissible(res, "none")
    assert np.max(np.abs(res.pos[:, 2])) == 0.0  # the in-plane problem stays in the plane


def test_minimum_is_a_fixed_point_and_input_is_untouched():
    """Polishing a polished chain changes nothing beyond rounding; the input array is never
    written."""
    start = crankshaft(regular_polygon(40), np.random.default_rng(0), 100, 0.05)
    keep = start.copy()
    first = polish(start)
    assert np.array_equal(start, keep)
    second = polish(first.pos)
    assert second.energy <= first.energy
    assert second.energy == pytest.approx(first.energy, rel=1e-12)
    assert second.iterations <= 2


# ---- annealed tight knots (bead model, tests/data/analysis) ------------------------------------


def check_knot_polish(pos, knot, exclusion, **kw):
    res = polish(pos, exclusion=exclusion, **kw)
    assert_admissible(res, exclusion)
    ok, found = verify_knot(res.pos, knot)
    assert ok, f"{knot} became {found}"
    return res


@pytest.mark.parametrize("name", ["4_1_seed1_r1", "5_2_seed1_r0"])
def test_annealed_bead_states_fast(name):
    res = check_knot_polish(fixture_chain(name), name[:3], "bead")
    assert res.converged, res.reason
    assert res.energy < res.energy_before  # the MC quench stops short of the minimum
    assert res.n_active > 0  # tight: contacts at exactly d


@pytest.mark.slow
@pytest.mark.parametrize("name", ["3_1_seed1_r0", "4_1_seed0_r0", "5_2_seed1_r1",
                                  "6_2_seed1_r0", "6_3_seed1_r1"])
def test_annealed_bead_states(name):
    res = check_knot_polish(fixture_chain(name), name[:3], "bead")
    assert res.converged, res.reason
    assert res.kkt_residual <= 1e-6 * res.grad_norm


# ---- fuzz: random admissible perturbations ---------------------------------------------------


def mc_perturbed(pos, exclusion, seed, n_moves=3000, temperature=0.005):
    """An admissible perturbation made by the MC kernel itself (exact bonds, exclusion and
    no strand passage by construction)."""
    st = ChainState(pos, MoveParams(exclusion=exclusion), seed=seed)
    st.run(n_moves, temperature)
    return st.pos.copy()


@pytest.mark.parametrize("name,seed", [("4_1_seed1_r1", 1), ("5_2_seed1_r0", 2)])
def test_fuzz_bead_fast(name, seed):
    start = mc_perturbed(fixture_chain(name), "bead", seed)
    check_knot_polish(start, name[:3], "bead")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["4_1_seed1_r1", "4_1_seed1_r0", "5_2_seed1_r0",
                                  "5_2_seed1_r1"])
def test_fuzz_bead(name):
    base = fixture_chain(name)
    for seed in range(4):
        for temperature in (0.005, 0.05):
            start = mc_perturbed(base, "bead", 10 * seed + 3, 5000, temperature)
            check_knot_polish(start, name[:3], "bead", max_iter=100)


@pytest.fixture(scope="session")
def tube_chains():
    """Small-budget annealed tube-model chains of 4_1 and 5_2 (N = 150, w = 1/√2)."""
    import stiffknots

    out = {}
    for knot in ("4_1", "5_2"):
        res = stiffknots.anneal(knot, moves=2_000_000, replicas=1, workers=1,
                                params=MoveParams(exclusion="tube"))
        out[knot] = res.replicas[0].coords
    return out


@pytest.mark.slow
@pytest.mark.parametrize("knot", ["4_1", "5_2"])
def test_annealed_tube_state(tube_chains, knot):
    res = check_knot_polish(tube_chains[knot], knot, "tube")
    assert res.converged, res.reason
    assert res.kkt_residual <= 1e-6 * res.grad_norm
    assert res.n_active > 0


@pytest.mark.slow
@pytest.mark.parametrize("knot", ["4_1", "5_2"])
def test_fuzz_tube(tube_chains, knot):
    for seed in range(3):
        start = mc_perturbed(tube_chains[knot], "tube", seed, 5000, 0.02)
        check_knot_polish(start, knot, "tube", max_iter=100)


# ---- the strand-passage guard ----------------------------------------------------------------


def crossing_loop():
    """A closed 8-bead loop whose segment (0, 1) passes 0.2 above segment (4, 5)."""
    return np.array([
        [-0.5, 0.0, 0.1], [0.5, 0.0, 0.1], [1.5, 0.5, 0.1], [1.5, 1.5, 0.0],
        [0.0, 0.5, -0.1], [0.0, -0.5, -0.1], [-1.5, -1.5, 0.0], [-1.5, -0.5, 0.1],
    ])


def test_guard_rejects_a_step_that_passes_a_strand_through_another():
    old = crossing_loop()
    push = np.zeros_like(old)
    push[[0, 1], 2] = -0.4  # segment (0, 1) dives through segment (4, 5)
    # the end state alone looks harmless: the segments are again 0.2 apart
    assert K.min_nonadjacent_segment_distance(old + push) > 0.1
    assert not passage_guard(old, old + push)
    # shortened, the same motion stops short of the other strand and is accepted
    assert passage_guard(old, old + 0.25 * push)
    # a step that touches the other strand is rejected too
    assert not passage_guard(old, old + 0.5 * push)


def test_guard_accepts_rigid_motions_and_sliding():
    old = crossing_loop()
    # a rigid translation of the whole loop, far larger than the gap
    assert passage_guard(old, old + np.array([3.0, -2.0, 7.0]))
    # the upper strand slides along x, parallel to the lower one, without closing the gap
    slide = np.zeros_like(old)
    slide[[0, 1, 7], 0] = 0.3
    assert passage_guard(old, old + slide)


def test_guard_rejects_a_bead_swept_across_its_neighbours_bond():
    old = crossing_loop()
    mid = 0.5 * (old[7] + old[0])  # middle of the bond (7, 0)
    new = old.copy()
    new[1] = mid + 0.5 * (mid - old[1])  # bead 1's straight path crosses that bond
    assert not passage_guard(old, new)
    assert passage_guard(old, old + 0.25 * (new - old))


def test_polish_never_accepts_a_passage():
    """The polish of a tight state ends with every non-bonded pair of segments apart, and the
    same knot (the guard is on by default for bead and tube)."""
    res = polish(fixture_chain("5_2_seed1_r1"), max_iter=5)
    assert res.strand_gap > 0.0
    assert verify_knot(res.pos, "5_2")[0]


# ---- open clamped chains (§VIII) -------------------------------------------------------------


def open_trefoil():
    from stiffknots.problems.open_extension import open_chain

    return open_chain("3_1", 30)


def check_open(start, res, exclusion):
    assert np.array_equal(res.pos[[0, 1, -2, -1]], start[[0, 1, -2, -1]])  # clamped exactly
    inner = res.pos[1:-1, 2]
    assert np.all(inner > start[0, 2]) and np.all(inner < start[-1, 2])  # inside the slab
    assert_admissible(res, exclusion, closed=False)
    assert verify_knot(close_open_chain_along_z(res.pos), "3_1")[0]
    # L_e is fixed (fixed-extension ensemble)
    assert res.pos[-1, 2] - res.pos[0, 2] == start[-1, 2] - start[0, 2]


def test_open_chain_keeps_its_clamped_ends_and_the_slab_fast():
    start = open_trefoil()
    res = polish(start, closed=False, max_iter=10)
    check_open(start, res, "bead")
    assert res.energy < res.energy_before


@pytest.mark.slow
@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_open_chain_keeps_its_clamped_ends_and_the_slab(exclusion):
    start = open_trefoil()
    res = polish(start, closed=False, exclusion=exclusion, max_iter=500)
    assert res.converged, res.reason
    check_open(start, res, exclusion)
    assert res.energy < 0.5 * res.energy_before


# ---- input validation ------------------------------------------------------------------------


def test_bad_inputs_are_refused_with_a_message():
    good = regular_polygon(20)
    with pytest.raises(ValueError, match="shape"):
        polish(good[:, :2])
    with pytest.raises(ValueError, match="unit length"):
        polish(good * 1.01)
    with pytest.raises(ValueError, match="exclusion"):
        polish(good, exclusion="soft")
    with pytest.raises(ValueError, match="clamp_ends"):
        polish(good, clamp_ends=2)
    with pytest.raises(ValueError, match="z axis"):
        polish(good, closed=False)
    crumpled = four_bar(regular_polygon(20, 3), np.random.default_rng(0), 10, 0.01)
    with pytest.raises(ValueError, match="violates"):
        polish(crumpled, exclusion="bead")


def test_stall_stop_is_the_minimum_to_far_below_its_promise(monkeypatch):
    # a 3_1 circular braid crawls for tens of steps after its energy has settled; the stall
    # stop ends there, converged, at the energy the crawl would reach to ≤ 1e-9 relative
    import stiffknots.engine.polish as P

    x = fixture_chain("3_1_seed1_r0")
    fast = polish(x)
    assert fast.converged and fast.relative_kkt <= P.STALL_KKT
    monkeypatch.setattr(P, "STALL_STEPS", 10**9)  # no stall stop: run to the KKT tolerance
    slow = polish(x)
    assert fast.iterations <= slow.iterations
    assert fast.energy == pytest.approx(slow.energy, rel=1e-9)
    assert fast.energy <= fast.energy_before


@pytest.mark.parametrize("reg", [0.0, 1e-12])
def test_kkt_matrix_is_the_block_matrix(reg):
    """The KKT matrix assembled from the blocks' triplets is [h aᵀ; a −reg·I] entry by
    entry (the polish factorises it; sp.bmat built the same matrix before)."""
    import scipy.sparse as sp

    from stiffknots.engine.polish import _kkt_matrix

    h = sp.random(90, 90, density=0.05, random_state=1, format="csr")
    h = (h + h.T + sp.identity(90)).tocsr()
    a = sp.random(31, 90, density=0.05, random_state=2, format="csr")
    lower = -reg * sp.identity(31) if reg > 0 else None
    want = sp.bmat([[h, a.T], [a, lower]], format="csc")
    got = _kkt_matrix(h, a, reg)
    assert got.format == "csc" and got.shape == (121, 121) and got.nnz == want.nnz
    assert abs(got - want).max() == 0.0


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_jacobian_rows_are_the_constraint_gradients(exclusion):
    """The polish's Jacobian (assembled from triplets) holds ∇(|b_k|² − 1) for every bond
    and ∇g_p for every exclusion piece near contact, by central differences on a tight 5_2
    state, and the six gauge rows where asked for."""
    from stiffknots.engine.polish import EXCLUSIONS, _Problem

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


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("dense_rows", [0, 10**6], ids=["sparse-gram", "dense-gram"])
def test_min_norm_solver_is_the_projection_kkt_solution(monkeypatch, exclusion, dense_rows):
    """The projection's correction dx = Aᵀ(AAᵀ)⁻¹r (dense Cholesky or sparse LU of the Gram
    matrix) equals the solution of the full KKT system [I Aᵀ; A 0][dx; y] = [0; r] it
    replaced, on a tight 5_2 state with pieces near contact and a clamped open end."""
    import scipy.sparse as sp

    import stiffknots.engine.polish as P

    monkeypatch.setattr(P, "DENSE_GRAM_ROWS", dense_rows)
    x = fixture_chain("5_2_seed1_r1")
    for closed, nfix in ((True, 0), (False, 2)):
        prob = P._Problem(len(x), closed, P.EXCLUSIONS.index(exclusion), 1 / np.sqrt(2), nfix,
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
    import stiffknots.engine.polish as P

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
