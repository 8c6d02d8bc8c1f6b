"""The 4-fold-cage start (paper §VII): geometry, knot type, start selection, annealing."""

import subprocess
import sys

import numpy as np
import pytest

from stiffknots.knots.cage_embedding import (
    CageSpec,
    cage_chain,
    cage_curve,
    cage_spec_for,
    embed_cage,
    two_box_conway,
)
from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.embedding import D_MIN, EmbeddingError, embedding_report
from stiffknots.knots.identify import identify
from stiffknots.knots.starts import available_starts, resolve_starts, split_replicas


@pytest.mark.parametrize("text,ab", [("[22]", (2, 2)), ("[32]", (3, 2)), ("[42]", (4, 2)),
                                     ("[3]", None), ("[312]", None), ("[3;3;2]", None),
                                     ("", None), (None, None), ("[2 2]", (2, 2)),
                                     ("[10 2]", (10, 2)), ("[6 6]", (6, 6)),
                                     ("[10 2 1]", None), ("[1 x]", None)])
def test_two_box_conway(text, ab):
    assert two_box_conway(text) == ab


def test_two_box_conway_checks_the_crossing_number():
    """'[11]' is KnotInfo's one-box (2, 11) torus knot 11a_367, not the cage [1 1]."""
    assert two_box_conway("[11]") == (1, 1)
    assert two_box_conway("[11]", 11) is None
    assert two_box_conway("[22]", 4) == (2, 2)
    assert two_box_conway("[10 2]", 12) == (10, 2)


@pytest.mark.parametrize("name,ab", [("11a_367", None), ("11a_247", (9, 2)),
                                     ("12a_803", (10, 2)), ("12a_1166", (8, 4)),
                                     ("12a_1287", (6, 6))])
def test_cage_spec_of_large_knots(name, ab):
    """Twelve-crossing two-box knots (KnotInfo '[10 2]') have a cage; the (2, 11) torus knot
    ('[11]') has none and is not listed in the cage family."""
    from stiffknots.knots.families import families_of

    k = get_knot(name)
    assert ("4C" in families_of(k)) == (ab is not None)
    if ab is None:
        with pytest.raises(EmbeddingError):
            cage_spec_for(k)
    else:
        assert cage_spec_for(k) == CageSpec(*ab)


@pytest.mark.parametrize("name", ["4_1", "5_2", "6_1"])
def test_cage_chain_is_the_knot(name):
    k = get_knot(name)
    x = embed_cage(k, 150)
    rep = embedding_report(x)
    assert x.shape == (150, 3)
    assert rep.max_bond_error < 1e-10
    assert rep.min_bead_distance >= D_MIN
    assert identify(x) == name


def test_cage_has_two_point_braids_at_the_poles():
    # the two boxes sit at opposite ends of the chain's longest axis (the sphere's poles)
    cyc = cage_curve(CageSpec(3, 2))
    assert len(cyc) == 1
    z = cyc[0][:, 2]
    assert z.max() == pytest.approx(1.09, abs=0.02) and z.min() == pytest.approx(-1.09, abs=0.02)


def test_cage_with_link_parity_raises():
    with pytest.raises(EmbeddingError, match="2-component link"):
        cage_chain(CageSpec(3, 3), 150)


def test_cage_outside_the_family_raises():
    with pytest.raises(EmbeddingError, match=r"Conway notation \[3\]"):
        embed_cage(get_knot("3_1"))
    with pytest.raises(EmbeddingError, match="two-box"):
        embed_cage(get_knot("6_2"))


def test_cage_too_few_beads_raises():
    with pytest.raises(EmbeddingError, match="n_beads=30"):
        embed_cage(get_knot("5_2"), 30)


def test_starts_selection():
    assert available_starts(get_knot("3_1")) == ["braid"]
    assert available_starts(get_knot("5_2")) == ["braid", "cage"]
    # 4_1 is of the 80 family too: its 'all' is braid, cage, eighty (default_starts)
    assert resolve_starts(get_knot("4_1"), "all", 4) == ["braid", "cage", "eighty", "braid"]
    assert resolve_starts(get_knot("8_3"), "all", 4) == ["braid", "cage", "braid", "cage"]
    assert resolve_starts(get_knot("3_1"), "all", 2) == ["braid", "braid"]
    assert resolve_starts(get_knot("4_1"), "cage", 2) == ["cage", "cage"]
    assert resolve_starts(get_knot("4_1"), ["cage", "braid"], 2) == ["cage", "braid"]
    with pytest.raises(ValueError, match="start must be one of all, braid"):
        resolve_starts(get_knot("4_1"), "sphere", 2)
    with pytest.raises(ValueError, match="3 starts given for 2"):
        resolve_starts(get_knot("4_1"), ["cage"] * 3, 2)
    with pytest.raises(ValueError):
        split_replicas([], 2)


def test_anneal_records_the_start_of_every_replica():
    from stiffknots import anneal

    res = anneal("4_1", moves=200_000, replicas=2, seed=3, workers=1, rounds=1)
    assert sorted(r.start for r in res.replicas) == ["braid", "cage"]
    assert all(r.knot_verified for r in res.replicas)
    # the starts the replicas take in turn over the rounds (the 80 from the third replica on)
    assert res.settings["start"] == ["braid", "cage", "eighty"]
    assert all(abs(r.energy - r.energy_recomputed) < 1e-9 for r in res.replicas)


def test_cli_start_outside_family_exits_2():
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "anneal", "3_1", "--start",
                        "cage", "--moves", "10000"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 2
    assert len(p.stderr.strip().splitlines()) == 1 and "two-box" in p.stderr
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "anneal", "3_1", "--start",
                        "sphere"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "--start" in p.stderr


@pytest.mark.slow
def test_5_2_cage_start_reaches_the_4_fold_cage_below_the_80():
    # paper §VII: 4C is the ground state of 5_2, the 80 metastable (hierarchy eq. (39));
    # from the braid start the annealing reaches the 80 at ε ≈ 149 (N = 150, bead rule)
    from stiffknots import anneal
    from stiffknots.analysis import classify

    res = anneal("5_2", moves=20_000_000, replicas=2, seed=1, start="cage")
    best = res.best
    assert classify(best.coords).label == "4C"
    assert best.epsilon < 146.0
    assert best.knot_verified
    assert np.isfinite(best.min_segment_distance)
