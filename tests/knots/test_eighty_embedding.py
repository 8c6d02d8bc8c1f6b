"""The "80" start (paper §VII): a figure eight with a circle along one lobe."""

import numpy as np
import pytest

from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.eighty_embedding import (
    EightySpec,
    eighty_chain,
    eighty_curve,
    embed_eighty,
    find_eighty,
)
from stiffknots.knots.embedding import D_MIN, EmbeddingError, embedding_report
from stiffknots.knots.identify import verify_knot


@pytest.mark.parametrize("name", ["5_2", "6_2", "6_3"])
def test_eighty_chain_of_paper_knots(name):
    x = embed_eighty(get_knot(name))
    assert x.shape == (150, 3)
    bonds = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    assert np.max(np.abs(bonds - 1.0)) <= 1e-10
    rep = embedding_report(x)
    assert rep.min_bead_distance >= D_MIN
    assert rep.min_segment_distance >= D_MIN  # also a valid start for the tube model
    ok, found = verify_knot(x, name)
    assert ok, found


def test_paper_80_specs():
    # all three with a plain centre crossing: 5_2 and 6_2 on route B (point-braid of three
    # half-turns, three double points), 6_3 on route X (two half-turns, four double points)
    s52, _ = find_eighty("5_2")
    s62, _ = find_eighty(get_knot("6_2"))
    s63, _ = find_eighty("6_3")
    assert (s52.route, s52.c, s52.k) == ("B", 1, 3)
    assert (s62.route, s62.c, s62.k) == ("B", 1, 3)
    assert (s63.route, s63.c, s63.k) == ("X", 1, 2)
    # route B reaches 6_3 only with two centre half-turns before the clasp
    x = eighty_chain(EightySpec(c=3, k=3, sk=1, over=(-1, 1), j=2))
    assert verify_knot(x, "6_3")[0]


def test_knot_outside_family_raises():
    with pytest.raises(EmbeddingError, match="7_4 has no 80 start"):
        find_eighty(get_knot("7_4"), max_crossings=8)
    with pytest.raises(EmbeddingError, match="not in the searched 80 family"):
        embed_eighty(get_knot("8_19"))  # three-bridge: refused at once


def test_link_spec_raises():
    with pytest.raises(EmbeddingError, match="2-component link"):
        eighty_chain(EightySpec(c=1, k=2))
    with pytest.raises(EmbeddingError, match="2-component link"):
        eighty_chain(EightySpec(c=1, k=1, over=(-1, 1, -1), route="X"))


def test_invalid_specs_raise():
    with pytest.raises(EmbeddingError, match="odd number of half-turns"):
        EightySpec(c=2)
    with pytest.raises(EmbeddingError, match="j = 1"):
        EightySpec(c=3, j=4)
    with pytest.raises(EmbeddingError, match="over"):
        EightySpec(over=(1, 0))
    with pytest.raises(EmbeddingError, match="3 values"):
        EightySpec(k=2, over=(1, -1), route="X")
    with pytest.raises(EmbeddingError, match="route"):
        EightySpec(route="Y")


def test_curve_is_closed_and_smooth():
    poly = eighty_curve(EightySpec())
    steps = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
    assert poly.ndim == 2 and poly.shape[1] == 3
    assert steps.max() < 0.05 and steps.min() > 0.0  # dense, closing step included
