"""Physics checks of the Monte Carlo engine (paper §VII): energy bookkeeping, bonds, exclusion,
topology preservation, schedules, reproducibility."""

import math

import numpy as np
import pytest

from helpers import braid_chain
from stiffknots.engine import kernel as K
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import ChainState, MoveParams
from stiffknots.knots.identify import identify


def chain(name, n=150):
    return braid_chain(name, n)


def bonds(pos):
    return np.linalg.norm(np.roll(pos, -1, axis=0) - pos, axis=1)


def test_energy_formula_circle():
    n = 150
    r = 0.5 / math.sin(math.pi / n)
    t = 2 * math.pi * np.arange(n) / n
    pos = np.c_[r * np.cos(t), r * np.sin(t), np.zeros(n)]
    st = ChainState(pos)
    assert st.epsilon == pytest.approx(n * n * (1 - math.cos(2 * math.pi / n)), rel=1e-12)
    assert abs(st.epsilon - 2 * math.pi**2) < 0.01  # ε → 2π² (circle)


@pytest.mark.parametrize("m_law", ["uniform", "log", "mixed"])
@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("temperature", [1e-1, 1e-3, 0.0])
def test_incremental_energy_bonds_exclusion(exclusion, temperature, m_law):
    st = ChainState(chain("5_2"), MoveParams(exclusion=exclusion, m_law=m_law), seed=7)
    for _ in range(5):
        st.run(100_000, temperature)
        assert st.energy == pytest.approx(st.recomputed_energy(), rel=1e-10, abs=1e-10)
        assert np.max(np.abs(bonds(st.pos) - 1)) < 1e-10
        assert st.violation() <= 1e-12
    acc = st.acceptance()
    assert acc["single"]["tried"] > 0 and acc["multi"]["tried"] > 0


def test_paper_move_moves_one_bead():
    st = ChainState(chain("3_1"), MoveParams(m_max=1, p_single=1.0), seed=3)
    before = st.pos.copy()
    for _ in range(200):
        prev = st.pos.copy()
        st.run(1, 1.0)
        moved = np.nonzero(np.any(st.pos != prev, axis=1))[0]
        assert len(moved) <= 1
        if len(moved) == 1:  # rotation by ±δ about the axis through the two neighbours
            i = moved[0]
            n = len(prev)
            a, b = prev[(i - 1) % n], prev[(i + 1) % n]
            e = (b - a) / np.linalg.norm(b - a)
            r0 = prev[i] - a - np.dot(prev[i] - a, e) * e
            r1 = st.pos[i] - a - np.dot(st.pos[i] - a, e) * e
            ang = math.acos(np.clip(np.dot(r0, r1) / np.dot(r0, r0), -1, 1))
            assert ang == pytest.approx(math.pi / 100, abs=1e-9)
    assert np.any(st.pos != before)


def test_reproducible_from_seed():
    a = ChainState(chain("4_1"), seed=11)
    b = ChainState(chain("4_1"), seed=11)
    c = ChainState(chain("4_1"), seed=12)
    for s in (a, b, c):
        s.run(200_000, 1e-2)
    assert np.array_equal(a.pos, b.pos)
    assert not np.array_equal(a.pos, c.pos)


def test_rng_uniform():
    u = K.uniforms(K.new_rng_state(5), 200_000)
    assert 0 <= u.min() and u.max() < 1
    assert abs(u.mean() - 0.5) < 0.005 and abs(u.var() - 1 / 12) < 0.002


def test_schedules():
    for kind in ("power", "geometric"):
        s = Schedule(kind=kind, t_start=1e-2, t_end=1e-6)
        x = np.linspace(0, 1, 101)
        t = s.temperature(x)
        assert t[0] == pytest.approx(1e-2) and t[-1] == pytest.approx(1e-6)
        assert np.all(np.diff(t) < 0)
    with pytest.raises(ValueError):
        Schedule(t_start=1e-6, t_end=1e-2).validate()


def test_bad_parameters_clear_errors():
    with pytest.raises(ValueError, match="exclusion"):
        ChainState(chain("3_1"), MoveParams(exclusion="soft"))
    with pytest.raises(ValueError, match="unit length"):
        ChainState(chain("3_1") * 1.1)


def _fuzz(name, temperature, moves, params, seed):
    st = ChainState(chain(name), params, seed=seed)
    start = identify(st.pos)
    steps = 10
    for _ in range(steps):
        st.run(moves // steps, temperature)
        assert identify(st.pos) == start, "knot type changed"
    assert st.energy == pytest.approx(st.recomputed_energy(), rel=1e-9)
    assert np.max(np.abs(bonds(st.pos) - 1)) < 1e-10
    return st


@pytest.mark.parametrize("m_law", ["uniform", "log"])
@pytest.mark.parametrize("temperature", [0.5, 1e-3])
def test_topology_preserved_fast(temperature, m_law):
    params = MoveParams(p_single=0.3, m_max=60, l_cap=1.0, phi_max=1.5, m_law=m_law)
    _fuzz("5_2", temperature, 1_000_000, params, seed=1)


@pytest.mark.slow
@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("temperature", [1.0, 1e-3])
def test_topology_fuzz_1e7(exclusion, temperature):
    params = MoveParams(p_single=0.5, m_max=60, l_cap=1.0, phi_max=1.5, exclusion=exclusion)
    _fuzz("5_2", temperature, 10_000_000, params, seed=2)


@pytest.mark.parametrize("m_max", [2, 3, 75, 300, 5000])
def test_crankshaft_length_laws(m_max):
    # every law draws m in [2, m_max]; the uniform law is flat, the log-uniform one puts the
    # same share of draws in every octave of m, whatever m_max (the scale-free rule)
    from stiffknots.engine.prims import _draw_length

    u = (np.arange(200_000) + 0.5) / 200_000
    span = math.log(0.5 * (m_max + 1))
    draws = {law: np.array([_draw_length(x, m_max, law, span) for x in u]) for law in (0, 1, 2)}
    for m in draws.values():
        assert m.min() == 2 and m.max() == m_max
    if m_max >= 300:
        uni, log, mix = draws[0], draws[1], draws[2]
        assert abs(uni.mean() - (m_max + 2) / 2) < 0.01 * m_max
        octaves = [np.mean((log >= 2**k) & (log < 2 ** (k + 1))) for k in range(1, 7)]
        assert np.ptp(octaves) < 0.1 * np.mean(octaves)  # flat in log m
        assert mix.mean() == pytest.approx(0.5 * (uni.mean() + log.mean()), rel=0.01)
        # the cost of a move ∝ m: mean (m_max − 2)/ln((m_max + 1)/2), 0.39 of uniform at 300
        assert log.mean() == pytest.approx((m_max - 2) / span, rel=0.05)
        assert log.mean() < 0.4 * uni.mean()


def test_bad_length_law_is_named():
    with pytest.raises(ValueError, match="m_law"):
        ChainState(chain("3_1"), MoveParams(m_law="cubic"))


def _run_moves_with_cells(state, cell, moves, temperature, seed):
    """``moves`` crankshaft moves of the general kernel on a copy of ``state``'s chain, its
    cell list built with cells of side ``cell``: (chain, counters)."""
    pos = state.pos.copy()
    ipar, fpar = state.ipar.copy(), state.fpar.copy()
    fpar[K.F_CELL] = cell
    head, nxt = np.empty_like(state.head), np.empty_like(state.nxt)
    prv, bucket = np.empty_like(state.prv), np.empty_like(state.bucket)
    K.cell_build(pos, cell, head, nxt, prv, bucket)
    cnt = np.zeros(K.C_NCNT, dtype=np.int64)
    K.run_moves(pos, moves, temperature, ipar, fpar, head, nxt, prv, bucket,
                np.empty_like(state.newpos), cnt, K.new_rng_state(seed))
    return pos, cnt


@pytest.mark.parametrize(("exclusion", "cell"), [
    ("bead", "default"), ("tube", "default"), ("bead", 0.4),
    pytest.param("tube", 0.4, marks=pytest.mark.slow)])  # ≈ 20 s; the three others cover it
def test_crankshaft_scan_meets_every_segment(exclusion, cell):
    # the crankshaft's guard scans only the cells of a box about each moved bead (kernel
    # docstring, Cell list); with cells far larger than the chain every segment lies in the
    # cells scanned — a brute-force scan. The decisions, hence the chains and the counters,
    # must be the same, with the default cells and with small ones (whose scan is the box
    # alone); and the guard must have refused moves for the comparison to test it.
    params = MoveParams(exclusion=exclusion, p_single=0.0, l_cap=1.0, phi_max=1.5)
    st = ChainState(chain("5_2"), params, seed=3)
    st.run(300_000, 1e-4)  # a compact chain: many pairs of strands in contact
    side = st.fpar[K.F_CELL] if cell == "default" else cell
    fast, c_fast = _run_moves_with_cells(st, side, 150_000, 1e-3, seed=11)
    brute, c_brute = _run_moves_with_cells(st, 1e4, 150_000, 1e-3, seed=11)
    refused = c_fast[K.C_ENERGY_OK + 1] - c_fast[K.C_ACCEPTED + 1]
    assert refused > 2_000, refused
    assert np.array_equal(c_fast, c_brute)
    assert np.array_equal(fast, brute)
