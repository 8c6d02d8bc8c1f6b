"""Embedding of braid closures as closed unit-bond chains (stiffknots.knots.embedding)."""

import numpy as np
import pytest

from stiffknots.knots.embedding import (
    D_MIN,
    EmbeddingError,
    braid_curve,
    embed_braid,
    embedding_report,
    minimal_beads,
    parse_braid,
    regular_polygon,
)

TREFOIL = [1, 1, 1]
FIG8 = [1, -2, 1, -2]
K5_2 = [1, 1, 1, 2, -1, 2]


def _check_chain(x, n, d_min=D_MIN):
    assert x.shape == (n, 3) and x.dtype == np.float64
    bonds = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    assert np.max(np.abs(bonds - 1.0)) < 1e-10
    # exclusion, brute force: cyclic index distance >= 2
    i, j = np.triu_indices(n, 2)
    keep = (j - i) % n >= 2
    keep &= (i - j) % n >= 2
    d = np.linalg.norm(x[i[keep]] - x[j[keep]], axis=1)
    if d.size == 0:  # a triangle has no pair of non-bonded beads
        return np.inf
    assert d.min() >= d_min
    return d.min()


@pytest.mark.parametrize("word", [TREFOIL, FIG8, K5_2, [1, 1, 1, 1, 1], [-1, -1, -1]])
def test_embed_unit_bonds_and_exclusion(word):
    x = embed_braid(word, n_beads=150)
    _check_chain(x, 150)
    rep = embedding_report(x)
    assert rep.max_bond_error < 1e-10
    assert rep.min_bead_distance >= D_MIN
    assert rep.min_segment_distance >= 0.5


def test_closing_bond_exact_and_other_sizes():
    for n in (60, 151, 400, 1000):
        x = embed_braid(FIG8, n_beads=n)
        assert abs(np.linalg.norm(x[0] - x[-1]) - 1.0) < 1e-10
        _check_chain(x, n)


def test_unknot_is_regular_polygon():
    for n in (3, 10, 150):
        x = embed_braid([], n_beads=n)
        _check_chain(x, n, d_min=0.0 if n < 6 else D_MIN)
        assert np.allclose(x, regular_polygon(n))
        assert np.allclose(np.linalg.norm(x[:, :2], axis=1), 0.5 / np.sin(np.pi / n))


def test_seed_rotates_and_shifts_reproducibly():
    a = embed_braid(K5_2, n_beads=150, seed=7)
    b = embed_braid(K5_2, n_beads=150, seed=7)
    c = embed_braid(K5_2, n_beads=150)
    assert np.array_equal(a, b)
    _check_chain(a, 150)
    # same shape: same sorted pair distances
    da = np.sort(np.linalg.norm(a[:, None] - a[None], axis=2).ravel())
    dc = np.sort(np.linalg.norm(c[:, None] - c[None], axis=2).ravel())
    assert np.allclose(da, dc, atol=1e-9)


def test_parse_braid_knotinfo_string():
    assert parse_braid("[1,-2,1,-2]") == FIG8
    assert parse_braid("{1, 1, 1}") == TREFOIL
    assert parse_braid("") == []
    with pytest.raises(EmbeddingError):
        parse_braid([1, 0, 1])


def test_too_small_raises_with_minimal_n():
    nmin = minimal_beads(FIG8)
    assert 10 < nmin < 150
    embed_braid(FIG8, n_beads=nmin)  # works
    with pytest.raises(EmbeddingError, match=rf"least number of beads that works is {nmin}\b"):
        embed_braid(FIG8, n_beads=nmin - 1)
    with pytest.raises(EmbeddingError, match="too few"):
        embed_braid(FIG8, n_beads=8)


def test_link_and_strand_errors():
    with pytest.raises(EmbeddingError, match="link with 2 components"):
        embed_braid([1, 1], n_beads=100)
    with pytest.raises(EmbeddingError, match="at least 3 strands"):
        embed_braid([1, 2], n_strands=2)


def _writhe(x):
    t = np.roll(x, -1, axis=0) - x
    m = x + 0.5 * t
    d = m[:, None, :] - m[None, :, :]
    r = np.linalg.norm(d, axis=2)
    np.fill_diagonal(r, np.inf)
    c = np.cross(t[:, None, :], t[None, :, :])
    return np.sum(np.einsum("ijk,ijk->ij", c, d) / r**3) / (4 * np.pi)


def test_positive_generator_is_positive_crossing():
    x = braid_curve(TREFOIL, radius=5.0, samples_per_pass=1500)
    assert 2.5 < _writhe(x) < 3.5
    xm = braid_curve([-g for g in TREFOIL], radius=5.0, samples_per_pass=1500)
    assert abs(_writhe(x) + _writhe(xm)) < 1e-9
