"""The paper's single-bead move on its own code path (paper §VII).

:func:`run_single_moves` (neighbour lists) and the general loop :func:`run_moves` (cell list)
must give the same chains, draw for draw, in every model; the lists must hold every segment a
move can meet and be rebuilt when anything moved the chain; the shortcuts of the Metropolis
test and of the segment guard must decide exactly as the plain tests; the knot type survives
hot runs of the single-bead kernel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from helpers import braid_chain
from stiffknots.engine import kernel as K
from stiffknots.engine import prims as P
from stiffknots.engine.state import ChainState, MoveParams
from stiffknots.knots.identify import identify
from stiffknots.problems.open_extension import open_chain


def _general_twin(st: ChainState) -> ChainState:
    """A copy of ``st`` (chain, generator, counters) to be run with :func:`run_moves`."""
    tw = ChainState(st.pos, st.params, closed=st.closed)
    tw.rng[:] = st.rng
    tw.counters[:] = st.counters
    tw.fpar[:] = st.fpar
    return tw


def _run_general(st: ChainState, n: int, temperature: float) -> float:
    de = K.run_moves(st.pos, n, temperature, st.ipar, st.fpar, st.head, st.nxt, st.prv,
                     st.bucket, st.newpos, st.counters, st.rng)
    st.energy += de
    return de


def _assert_same(a: ChainState, b: ChainState):
    assert np.array_equal(a.pos, b.pos)
    assert np.array_equal(a.rng, b.rng)
    assert np.array_equal(a.counters, b.counters)


CASES = {
    "bead": (MoveParams(m_max=1, p_single=1.0), True),
    "tube": (MoveParams(m_max=1, p_single=1.0, exclusion="tube", w=0.4), True),
    "power+limit": (MoveParams(m_max=1, p_single=1.0, energy="power", power=4,
                               max_turn=1.2), True),
    "open": (MoveParams(m_max=1, p_single=1.0), False),
}


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("temperature", [1e-4, 1e-2, 1.0, 0.0])
def test_single_kernel_is_the_general_kernel(case, temperature):
    params, closed = CASES[case]
    x = braid_chain("5_2") if closed else open_chain("3_1", 30, seed=0)
    st = ChainState(x, params, seed=4, closed=closed)
    assert st.single_only
    tw = _general_twin(st)
    for n in (1, 7, 30_000, 30_000):
        de = st.run(n, temperature)
        de_tw = _run_general(tw, n, temperature)
        _assert_same(st, tw)
        assert de == de_tw
    assert st.counters[K.C_ACCEPTED] > 0 or temperature == 0.0
    assert st.violation() <= 1e-12


def test_lists_follow_other_kernels_and_replaced_chains():
    """Crankshafts of many beads (another kernel) between single-bead runs, and a chain
    replaced in place: the lists are rebuilt, the chain stays the one of run_moves."""
    st = ChainState(braid_chain("4_1"), MoveParams(m_max=1, p_single=1.0), seed=9)
    tw = _general_twin(st)
    ip, fp = MoveParams(m_max=40, p_single=0.2, l_cap=1.0).arrays()
    scratch = np.empty((40, 3))
    for _ in range(4):
        st.run(20_000, 1e-2)
        _run_general(tw, 20_000, 1e-2)
        _assert_same(st, tw)
        for s in (st, tw):  # big moves that the single kernel does not see
            K.run_moves(s.pos, 3000, 0.3, ip, fp, s.head, s.nxt, s.prv, s.bucket, scratch,
                        s.counters, s.rng)
        _assert_same(st, tw)
    builds = st.nbr_meta[K.NB_BUILDS]
    assert builds >= 4  # one per return after the crankshafts at least
    other = ChainState(braid_chain("4_1", 150), MoveParams(m_max=1, p_single=1.0), seed=2)
    other.run(50_000, 1.0)
    st.pos[:] = other.pos  # a chain replaced in place: rebuild the cell list, then run
    tw.pos[:] = other.pos
    for s in (st, tw):
        P.cell_build(s.pos, s.params.cell, s.head, s.nxt, s.prv, s.bucket)
    st.run(20_000, 1e-2)
    _run_general(tw, 20_000, 1e-2)
    _assert_same(st, tw)
    assert st.nbr_meta[K.NB_BUILDS] > builds


def test_full_lists_fall_back_to_the_cell_list():
    st = ChainState(braid_chain("5_2"), MoveParams(m_max=1, p_single=1.0), seed=5)
    tw = _general_twin(st)
    st.nbr = np.empty(40, dtype=np.int32)  # room for the lists of a few beads only
    st.run(50_000, 1e-2)
    _run_general(tw, 50_000, 1e-2)
    _assert_same(st, tw)
    lengths = st.nbr_row[1::2]
    assert np.any(lengths < 0) and np.any(lengths > 0)


def test_lists_hold_every_segment_within_their_radius():
    st = ChainState(braid_chain("6_2", 200), MoveParams(m_max=1, p_single=1.0), seed=1)
    st.run(100_000, 1e-2)
    st.nbr_meta[K.NB_RADIUS] = 0.0
    st.run(1, 1e-2)  # rebuild now
    radius = st.nbr_meta[K.NB_RADIUS]
    assert radius >= 1.5 + 2 * st.params.delta + K.NBR_SKIN
    n = st.n_beads
    mid = 0.5 * (st.nbr_ref + np.roll(st.nbr_ref, -1, axis=0))
    for i in range(n):
        start, count = st.nbr_row[2 * i], st.nbr_row[2 * i + 1]
        got = set(st.nbr[start:start + count].tolist())
        near = np.flatnonzero(np.linalg.norm(mid - st.nbr_ref[i], axis=1) <= radius - 1e-9)
        want = set(near.tolist()) - {i, (i - 1) % n}
        assert want <= got, i


@njit(cache=True)
def _below_exp_all(u, x):
    """(the kernel's test, the plain test u < exp(−x) with the same libm exp, exp(−x))."""
    out = np.empty((u.shape[0], 2), dtype=np.bool_)
    e = np.empty(u.shape[0])
    for q in range(u.shape[0]):
        out[q, 0] = P._below_exp(u[q], x[q])
        e[q] = math.exp(-x[q])
        out[q, 1] = u[q] < e[q]
    return out, e


def test_exp_shortcut_decides_as_the_plain_test():
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(0, 50, 200_000), rng.uniform(0, 2, 200_000),
                        10.0 ** rng.uniform(-12, 0, 100_000)])
    u = rng.random(x.size)
    e = _below_exp_all(u, x)[1]  # libm's exp, as in the kernel (numpy's may differ by an ulp)
    # and u within a few ulps of e^{−x}, on both sides
    k = rng.integers(-3, 4, x.size)
    u_edge = np.nextafter(e, np.where(k < 0, 0.0, 1.0))
    for _ in range(2):
        u_edge = np.where(np.abs(k) > 1, np.nextafter(u_edge, np.where(k < 0, 0.0, 1.0)),
                          u_edge)
    u_edge = np.where(k == 0, e, u_edge)
    for uu in (u, np.minimum(u_edge, np.nextafter(1.0, 0.0))):
        got = _below_exp_all(uu, x)[0]
        assert np.array_equal(got[:, 0], got[:, 1])
        assert got[:, 1].any() and not got[:, 1].all()


@njit(cache=True)
def _blocked_both(seg, dseg, w2, lmove):
    """_segment_blocked (with its shortcuts) and the plain test, for rows of
    (new a, new b, old a, old b, v, w)."""
    out = np.empty((seg.shape[0], 2), dtype=np.bool_)
    for q in range(seg.shape[0]):
        s = seg[q]
        mx, my, mz = 0.5 * (s[0] + s[3]), 0.5 * (s[1] + s[4]), 0.5 * (s[2] + s[5])
        mvx, mvy, mvz = 0.5 * (s[12] + s[15]), 0.5 * (s[13] + s[16]), 0.5 * (s[14] + s[17])
        out[q, 0] = P._segment_blocked(s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8],
                                       s[9], s[10], s[11], mx, my, mz, s[12], s[13], s[14],
                                       s[15], s[16], s[17], mvx, mvy, mvz, dseg, w2, lmove)
        out[q, 1] = P._pair_blocked(s[0], s[1], s[2], s[3], s[4], s[5], s[12], s[13], s[14],
                                    s[15], s[16], s[17], s[6], s[7], s[8], s[9], s[10], s[11],
                                    s[12], s[13], s[14], s[15], s[16], s[17], w2, lmove)
    return out


def _unit(v):
    return v / np.linalg.norm(v, axis=1)[:, None]


@pytest.mark.parametrize("w,lmove", [(0.0, 0.03), (0.0, 0.3), (0.4, 0.01), (0.9, 0.2)])
def test_segment_shortcuts_decide_as_the_plain_test(w, lmove):
    rng = np.random.default_rng(7)
    n = 100_000
    a = rng.normal(size=(n, 3)) * 0.3
    b = a + _unit(rng.normal(size=(n, 3)))
    v = rng.normal(size=(n, 3)) * 0.6
    wv = v + _unit(rng.normal(size=(n, 3)))
    # the old segment: the new one moved by less than lmove
    shift = _unit(rng.normal(size=(n, 3))) * rng.uniform(0, lmove, (n, 1))
    seg = np.hstack([a, b, a - shift, b - shift, v, wv])
    dseg = max(w, lmove)
    got = _blocked_both(seg, dseg, w * w, lmove)
    plain = got[:, 1].copy()
    # the plain answer where the midpoints are too far apart for any test to fail is False
    far = np.linalg.norm(0.5 * (v + wv) - 0.5 * (a + b), axis=1) > 1 + dseg
    plain[far] = False
    assert np.array_equal(got[:, 0], plain)
    assert 100 < plain.sum() < n - 100  # both answers occur


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_single_kernel_keeps_the_knot_hot(exclusion):
    st = ChainState(braid_chain("5_2"), MoveParams(m_max=1, p_single=1.0, exclusion=exclusion),
                    seed=11)
    start = identify(st.pos)
    for _ in range(10):
        st.run(200_000, 1.0)
        assert identify(st.pos) == start, "knot type changed"
        assert st.violation() <= 1e-12
    assert st.energy == pytest.approx(st.recomputed_energy(), rel=1e-9)
    assert st.nbr_meta[K.NB_BUILDS] > 1
    assert math.isfinite(st.energy)
