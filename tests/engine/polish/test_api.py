"""The final minimiser's entry point :func:`stiffknots.engine.polish.polish` (§VII, §VIII).

Analytic minima (regular polygon, m-covered circle), admissibility (unit bonds, exclusion
rule), monotone energy, topology preservation on annealed tight knots and on random
admissible perturbations of them, no strand passage along the polish, and clamped open
chains.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine import kernel as K
from stiffknots.engine.polish import PolishResult, polish
from stiffknots.engine.state import ChainState, MoveParams
from stiffknots.knots.identify import close_open_chain_along_z, verify_knot

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis"
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


# ---- no strand passage along the polish -------------------------------------------------------


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


