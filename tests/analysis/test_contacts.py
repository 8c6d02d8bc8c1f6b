"""Tests of the contact map (stiffknots.analysis.contacts): non-adjacent beads within the
contact distance, cyclic separation on a closed chain, bad input."""

import math

import numpy as np
import pytest

from stiffknots.analysis.contacts import DEFAULT_D, contact_map, index_separation
from stiffknots.analysis.synthetic import random_compact_chain
from stiffknots.chain import regular_polygon


def test_contact_map_matches_brute_force():
    x = random_compact_chain(120, seed=5)
    cm = contact_map(x)
    n = len(x)
    d = np.linalg.norm(x[:, None] - x[None], axis=2)
    i, j = np.triu_indices(n, 1)
    sep = np.minimum(j - i, n - (j - i))
    want = {(a, b) for a, b in zip(i, j, strict=True)
            if sep[(a * (2 * n - a - 1)) // 2 + b - a - 1] >= 5 and d[a, b] <= math.sqrt(2)}
    got = set(zip(cm.i.tolist(), cm.j.tolist(), strict=True))
    assert got == want
    assert cm.cutoff == pytest.approx(math.sqrt(2.0)) == pytest.approx(2 * DEFAULT_D)
    assert np.all(index_separation(cm.i, cm.j, n) >= cm.min_sep)
    assert np.allclose(cm.dist, d[cm.i, cm.j])
    m = cm.matrix()
    assert m.sum() == 2 * cm.n_contacts and np.array_equal(m, m.T)


def test_contact_separation_cyclic_for_closed_plain_for_open():
    x = regular_polygon(40).coords  # beads 0 and 39 are bonded (closed) or far in index (open)
    closed = contact_map(x, closed=True, cutoff=2.5)
    opened = contact_map(x, closed=False, cutoff=2.5)
    assert closed.n_contacts == 0
    pairs = set(zip(opened.i.tolist(), opened.j.tolist(), strict=True))
    assert (0, 39) in pairs and (0, 38) in pairs and (1, 39) in pairs
    assert all(j - i >= 5 for i, j in pairs)


def test_contact_cutoff_and_factor():
    x = regular_polygon(150, 2).coords  # covers 1.0 apart
    assert contact_map(x, factor=1.5).n_contacts > 0
    assert contact_map(x, cutoff=0.9).n_contacts == 0
    assert contact_map(x, d=0.5, factor=2.2).cutoff == pytest.approx(1.1)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"coords": np.zeros((10, 2))}, "shape"),
        ({"coords": np.full((10, 3), np.nan)}, "finite"),
        ({"coords": np.zeros((3, 3))}, "at least 4"),
        ({"coords": "abc"}, "numbers"),
        ({"min_sep": 1}, "min_sep"),
        ({"min_sep": 80}, "no possible contact"),
        ({"d": -1.0}, "d must be"),
        ({"factor": 0}, "factor must be"),
        ({"cutoff": float("inf")}, "cutoff must be"),
    ],
)
def test_contact_map_bad_input(kwargs, match):
    args = {"coords": regular_polygon(100).coords}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        contact_map(args.pop("coords"), **args)
