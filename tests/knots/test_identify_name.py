"""One name per knot: identify_name breaks the HOMFLY-PT ties by the knot complement (SnapPy)
and gives the chirality relative to KnotInfo's diagram; checked on KnotPlot-style curves
(ridgerunner's Rolfsen table, non-unit bonds), on perturbed and resampled embeddings, on every
knot of the catalogue through 10 crossings (slow) and on their mirror images."""

import sys
from pathlib import Path

import numpy as np
import pytest

from helpers import DATA
from stiffknots.formats import load
from stiffknots.knots.catalogue import catalogue, get_knot
from stiffknots.knots.diagram import pd_code
from stiffknots.knots.identify import identify, identify_details, identify_name

RIDGERUNNER = DATA / "curves" / "ridgerunner"
KNOT_FILES = sorted(p for p in RIDGERUNNER.glob("*.vect") if p.stem.count(".") == 1)
MIRROR = np.diag([1.0, 1.0, -1.0])  # z -> -z


def _name(path: Path) -> str:
    return path.stem.replace(".", "_")


def _expected_chirality(name, chir):
    """The mirror's chirality: flipped for chiral knots, None stays None."""
    return {"+": "-", "-": "+", None: None}[chir]


def test_every_prime_knot_through_8_crossings_has_a_file():
    names = {_name(p) for p in KNOT_FILES}
    assert {k.name for k in catalogue(8) if k.crossing_number >= 3} <= names


@pytest.mark.parametrize("path", KNOT_FILES, ids=lambda p: p.stem)
def test_knotplot_style_curves_one_name_and_mirror(path):
    c = load(path)
    want = _name(path)
    name, cands, chir = identify_name(c.coords)
    assert (name, cands) == (want, (want,))
    k = get_knot(want)
    sym = k.raw["symmetry_type"]
    if "amphicheiral" in sym:
        assert chir is None
    else:
        assert chir in "+-"
    m_name, m_cands, m_chir = identify_name(c.coords @ MIRROR)
    assert (m_name, m_cands) == (want, (want,))
    assert m_chir == _expected_chirality(want, chir)


def test_ties_through_10_crossings_are_broken_by_the_volume():
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    import homfly_ties

    ties = homfly_ties.ties(10)
    assert {"|".join(t) for t in ties} == {
        "5_1|10_132", "8_8|10_129", "8_16|10_156", "10_25|10_56", "10_40|10_103",
        "4_1#5_2|9_12"}
    assert all(homfly_ties.split_by(t) == "volume" for t in ties)


def test_details_say_how():
    r = identify_details(load(RIDGERUNNER / "10.132.vect").coords)
    assert r.homfly == "5_1|10_132" and r.name == "10_132"
    assert r.decided_by[-1].startswith("hyperbolic volume")
    assert r.volume == pytest.approx(4.0568602242, abs=1e-8)
    r = identify_details(load(RIDGERUNNER / "5.1.vect").coords)
    assert r.name == "5_1" and r.volume is None and "τ" in r.chirality_by


def test_pd_code_orientation_and_writhe():
    """Our PD code follows KnotInfo/spherogram: the right-handed trefoil (braid [1,1,1], writhe
    +3 in space) has diagram writhe +3, and KnotFloer's τ of KnotInfo's own diagram equals
    KnotInfo's τ column (the sign convention used for torus-knot chirality)."""
    import spherogram
    from knot_floer_homology import pd_to_hfk

    from stiffknots.chain import Chain
    from stiffknots.knots.starts import start_chain

    x = start_chain(get_knot("3_1"), "braid", 60)
    assert Chain(x).writhe() > 2.5
    assert spherogram.Link(pd_code(x)).writhe() == 3
    assert spherogram.Link(pd_code(x @ MIRROR)).writhe() == -3
    for name in ("3_1", "5_1", "7_1", "8_19", "10_124", "5_2", "10_132"):
        k = get_knot(name)
        assert pd_to_hfk(list(k.pd_code))["tau"] == int(k.raw["ozsvath_szabo_tau_invariant"])


def test_unknot_and_the_composite_side_of_a_tie():
    from stiffknots.chain import regular_polygon
    from stiffknots.knots.embedding import embed_braid

    assert identify_name(regular_polygon(20).coords) == ("0_1", ("0_1",), None)
    # 4_1#5_2 (HOMFLY-PT: 4_1#5_2|9_12): the braid words of 4_1 and 5_2 side by side
    a, b = get_knot("4_1"), get_knot("5_2")
    word = list(a.braid_word) + [g + (a.braid_strands - 1) * (1 if g > 0 else -1)
                                 for g in b.braid_word]
    x = embed_braid(word, n_strands=a.braid_strands + b.braid_strands - 1, n_beads=150)
    r = identify_details(x)
    assert r.homfly == "4_1#5_2|9_12"
    assert (r.name, r.candidates, r.chirality, r.volume) == ("4_1#5_2", ("4_1#5_2",), None, None)


def _perturbed(knot, rng):
    """A KnotPlot-like curve: the braid embedding re-sampled at 40-120 random (unequal)
    arclengths, each vertex jittered, in other units. The construction itself is checked: its
    HOMFLY-PT polynomial (chiral) must be the embedding's (else more vertices are used)."""
    from stiffknots.knots.identify import homfly_code
    from stiffknots.knots.resample import _point_at
    from stiffknots.knots.starts import start_chain

    x = start_chain(knot, "braid", 150)
    code = homfly_code(x)
    cum = np.arange(151, dtype=float)  # unit bonds
    for n in (50, 70, 90, 120):
        s = (np.arange(n) + rng.uniform(-0.4, 0.4, size=n)) * (150 / n)
        y = _point_at(x, cum, s) + rng.normal(scale=0.05, size=(n, 3))
        if homfly_code(y) == code:
            step = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
            assert np.ptp(step) > 0.3  # non-unit, unequal bonds
            return y * 1.7
    pytest.skip(f"no coarse version of the {knot.name} embedding kept its type")


@pytest.mark.parametrize("name", [
    pytest.param(k.name, marks=() if k.crossing_number <= 7 else pytest.mark.slow)
    for k in catalogue(8) if k.crossing_number >= 3])   # the 21 knots of 8 crossings: ≈ 60 s
def test_perturbed_embeddings_through_8_crossings(name):
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    y = _perturbed(get_knot(name), rng)
    assert 40 <= len(y) <= 120
    got = identify_name(y)
    assert got[0] == name and got[2] in ("+", None)
    assert identify_name(y @ MIRROR)[2] == _expected_chirality(name, got[2])


@pytest.mark.slow
def test_catalogue_through_10_crossings_with_mirrors():
    """Every knot of the catalogue through 10 crossings, from its own embedding (the closure
    of KnotInfo's braid word) and its mirror image: one name, chirality '+' (KnotInfo's knot)
    and '-' for the mirror (None for amphichiral knots)."""
    from stiffknots.errors import EmbeddingError
    from stiffknots.knots.embedding import minimal_beads
    from stiffknots.knots.starts import start_chain

    bad = []
    for k in catalogue(10):
        if k.crossing_number < 3:
            continue
        try:
            x = start_chain(k, "braid", 150)
        except EmbeddingError:
            x = start_chain(k, "braid", minimal_beads(k.braid_word, k.braid_strands))
        got = identify_name(x)
        mir = identify_name(x @ MIRROR)
        amph = "amphicheiral" in k.raw["symmetry_type"]
        want_chir = (None, None) if amph else ("+", "-")
        if (got[0], mir[0]) != (k.name, k.name) or (got[2], mir[2]) != want_chir:
            bad.append((k.name, got, mir, identify(x)))
    assert not bad, bad
