"""resample: N unit bonds on the user's polygon, knot type kept (condition, certificate,
HOMFLY-PT check), thickness w = (w/L)·N."""

import numpy as np
import pytest

from helpers import DATA
from stiffknots.chain import Chain, regular_polygon
from stiffknots.errors import InvalidParameter
from stiffknots.formats import load
from stiffknots.knots.identify import homfly_code
from stiffknots.knots.resample import (
    ResampleError,
    minimal_resample_beads,
    resample,
    separation_distance,
)

RIDGERUNNER = DATA / "curves" / "ridgerunner"


@pytest.mark.parametrize("stem,n", [("3.1", 150), ("8.18", 150), ("10.132", 120), ("5.2", 60)])
def test_unit_bonds_same_polynomial(stem, n):
    c = load(RIDGERUNNER / f"{stem}.vect")
    r = resample(c, n, w_over_L=0.005)
    assert r.closed and r.n_beads == n
    assert np.max(np.abs(r.bond_lengths() - 1.0)) <= 1e-12
    assert r.meta["homfly"] == homfly_code(c.coords)  # chiral: identical, mirror included
    assert r.meta["a_max"] < r.meta["D_2l"]
    assert r.meta["w"] == pytest.approx(0.005 * n) and r.meta["tube_fits"] in (True, False)
    assert r.meta["resampled_from"] == c.n_beads


def test_too_few_beads_refused_with_the_smallest_that_works():
    c = load(RIDGERUNNER / "8.18.vect")
    nmin = minimal_resample_beads(c.coords)
    assert 20 < nmin < 150
    with pytest.raises(ResampleError, match=f">= {nmin}"):
        resample(c, 8)  # neither the sufficient condition nor the Δ-moves hold
    assert resample(c, nmin, check=False).n_beads == nmin
    # below the condition's N, a resampling whose every Δ-move is certified is accepted, and
    # the polynomial check (check=True) confirms the type
    try:
        r = resample(c, nmin - 5)
    except ResampleError:
        pass
    else:
        assert r.n_beads == nmin - 5 and r.meta["homfly"]


def test_separation_distance_of_a_circle():
    # points of a circle of radius R at arclength >= λ are >= 2R sin(λ/2R) apart
    c = regular_polygon(400)
    R = c.coords[0, 0]
    lam = 40.0
    D = separation_distance(c.coords, lam)
    assert D <= 2 * R * np.sin(lam / (2 * R)) + 1e-9
    assert D > 2 * R * np.sin((lam - lam / 4 - 1) / (2 * R)) - 1e-9


def test_bad_arguments():
    c = Chain(regular_polygon(30).coords[:10], closed=False)
    with pytest.raises(ValueError, match="open"):
        resample(c, 20)
    with pytest.raises(InvalidParameter, match="n_beads"):
        resample(regular_polygon(30), 2)
    with pytest.raises(InvalidParameter, match="w_over_L"):
        resample(regular_polygon(30), 20, w_over_L=-1)


@pytest.mark.parametrize("t", [0.25, 0.75])
def test_a_slid_unit_chain_resamples_to_unit_bonds(t):
    # a 5_2 chain slid by a fraction of a bond along itself has near-unit bonds; its equal
    # chords came out unit only to ≈ 10⁻¹¹ (Brent's root of the closing step) and resample()
    # raised "bonds not unit after resampling"
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import embed_braid

    k = get_knot("5_2")
    x = embed_braid(k.braid_word, n_strands=k.braid_strands, n_beads=150)
    y = (1 - t) * x + t * np.roll(x, -1, axis=0)
    c = resample(Chain(y, closed=True), 150)
    bonds = np.linalg.norm(np.roll(c.coords, -1, axis=0) - c.coords, axis=1)
    assert np.max(np.abs(bonds - 1.0)) <= 1e-12
    assert c.meta["homfly"] == homfly_code(x)


def test_touching_strands_are_a_clear_error_not_a_search_failure():
    """A bead-rule 4_1 whose strands touch where they cross (10⁻⁴ apart, ε 127.5445): no
    number of beads certifies its resampling, and the error says so (it was the bead search's
    "no number of beads up to 20000 satisfies the condition")."""
    from stiffknots.knots.resample import ResampleError, resample

    x = np.load(DATA / "resample" / "4_1_bead_touching.npy")
    assert Chain(x, True).min_segment_distance() < 2e-4
    with pytest.raises(ResampleError, match="touching strands.*|none up to 20,000"):
        resample(Chain(x, True), 300)


def test_a_repeated_point_in_the_certification_is_no_division_by_zero():
    """A bead-rule 4_1 (ε 127.4595) resampled to 300 beads: the certification met a polygon
    edge of zero length and divided by zero; now the error names the beads it needs."""
    from stiffknots.knots.resample import ResampleError, resample

    x = np.load(DATA / "resample" / "4_1_bead_other.npy")
    with pytest.raises(ResampleError, match=r"an integer >= \d+ for this curve"):
        resample(Chain(x, True), 300)
