"""The constraint pieces of the final minimiser (:mod:`stiffknots.engine.polish.pieces`): the
candidates are the close pairs, the tube pieces of two segments have the segment distance as
their minimum (so they are equivalent to the tube rule, §II), and the clearance is the rule's."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine.polish.pieces import (
    _bead_candidates,
    _Cons,
    _min_clearance,
    _tube_candidates,
)
from stiffknots.geometry import seg_dist2

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis"


def fixture_chain(name: str) -> np.ndarray:
    return np.load(DATA / f"{name}.npy")


def seg_dist(x, a, b):
    n = len(x)
    p, q, r, s = x[a], x[(a + 1) % n], x[b], x[(b + 1) % n]
    return float(np.sqrt(seg_dist2(*p, *q, *r, *s)))


def nonbonded(n):
    """Pairs of segments (a, b), a < b, of a closed ring that share no bead."""
    return [(a, b) for a, b in itertools.combinations(range(n), 2)
            if b - a >= 2 and not (a == 0 and b == n - 1)]


def test_bead_candidates_are_the_close_pairs():
    x = fixture_chain("5_2_seed1_r1")
    n = len(x)
    idx, key = _bead_candidates(x, False, 0.9, 0)
    got = {(int(i), int(j)) for i, j in idx}
    want = {(i, j) for i, j in nonbonded(n) if np.linalg.norm(x[i] - x[j]) < 0.9}
    assert got == want and len(got) > 10
    assert np.array_equal(key, idx[:, 0] * n + idx[:, 1])


def test_tube_pieces_have_the_segment_distance_as_minimum():
    x = fixture_chain("5_2_seed1_r1")
    n = len(x)
    reach = 0.9
    ctype, idx, key = _tube_candidates(x, False, reach, 0)
    z = np.zeros(len(key), dtype=np.int64)
    dist = _Cons(ctype, idx, key, np.full(len(key), 0.5), z).evaluate(x)[0]
    checked = 0
    for a, b in nonbonded(n):
        d = seg_dist(x, a, b)
        if d >= reach:
            continue
        sa, sb = {a, (a + 1) % n}, {b, (b + 1) % n}
        mine = [dist[p] for p in range(len(key))
                if set(idx[p][idx[p] >= 0].tolist()) <= sa | sb
                and set(idx[p].tolist()) & sa and set(idx[p].tolist()) & sb]
        assert min(mine) == pytest.approx(d, abs=1e-12)
        checked += 1
    assert checked > 10


@pytest.mark.parametrize("mode", [0, 1])
def test_min_clearance_is_the_rule_on_all_pairs(mode):
    x = fixture_chain("5_2_seed1_r1")
    n = len(x)
    lim = 1 / np.sqrt(2)
    if mode == 0:
        want = min(np.linalg.norm(x[i] - x[j]) for i, j in nonbonded(n)) - lim
    else:
        want = min(seg_dist(x, a, b) for a, b in nonbonded(n)) - lim
    assert _min_clearance(x, mode, lim, False) == pytest.approx(min(want, 1.0), abs=1e-12)
