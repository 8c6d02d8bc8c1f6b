"""stiffknots.checks.check and the warnings of the shape analysis: a chain that is not a
unit-bond chain obeying the bead rule is reported, never analysed in silence."""

import warnings

import numpy as np
import pytest

import stiffknots as sk
from helpers import braid_chain
from stiffknots.analysis import analyse_structure, classify
from stiffknots.chain import Chain
from stiffknots.checks import check
from stiffknots.errors import ChainWarning


@pytest.fixture(scope="module")
def trefoil():
    return braid_chain("3_1", 150)


def moved_bead(x):
    y = x.copy()
    y[10] += [0.3, 0.0, 0.0]
    return y


def touching_beads(x):
    """Bead 40 moved 0.001 from bead 100 (its bonds no longer unit either)."""
    y = x.copy()
    y[40] = y[100] + [0.001, 0.0, 0.0]
    return y


def test_a_model_chain_passes(trefoil):
    c = check(trefoil, knot="3_1")
    assert c.ok and c.problems == ()
    assert c.unit_bonds and c.bead_rule and c.knot_ok and c.knot_found == "3_1"
    assert c.max_bond_error < 1e-9 and c.min_bead_distance >= 1 / np.sqrt(2)
    assert c.min_segment_distance > 0.5
    assert "ok" in str(c) and c.to_dict()["ok"] is True
    assert sk.check is check  # public, one import away
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        classify(trefoil)
        analyse_structure(trefoil)


def test_a_moved_bead_is_reported(trefoil):
    c = check(moved_bead(trefoil))
    assert not c.ok and not c.unit_bonds and c.bead_rule
    assert c.max_bond_error == pytest.approx(0.2524, abs=1e-3)
    assert any(p.startswith("bond 10 has length 1.25") for p in c.problems)


def test_touching_beads_are_reported(trefoil):
    c = check(touching_beads(trefoil))
    assert not c.bead_rule and c.min_bead_distance == pytest.approx(0.001)
    assert any("0.001 apart (the bead rule needs ≥ 0.707107)" in p for p in c.problems)
    # the tube model's quantity too
    assert c.min_segment_distance <= 0.001


def test_knot_type_asked(trefoil):
    c = check(Chain(trefoil), knot="4_1")
    assert not c.ok and c.knot_ok is False and c.knot_found == "3_1"
    assert c.problems == ("its knot type is 3_1, not 4_1",)
    assert check(trefoil, identify=True).knot_found == "3_1"
    assert check(trefoil).knot_found is None  # not asked: not computed


@pytest.mark.parametrize("damage", [moved_bead, touching_beads])
def test_the_analysis_warns_at_the_callers_line(trefoil, damage):
    x = damage(trefoil)
    for analyse in (classify, analyse_structure):
        with pytest.warns(ChainWarning, match="assumes a unit-bond chain obeying the bead rule"
                          ) as rec:
            analyse(x)
        assert len(rec) == 1  # once, not once per inner call
        assert rec[0].filename == __file__  # the user's line, not the package's


def test_the_analysis_is_scale_free(trefoil):
    """A chain in other units with d in the same units is a model chain: no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert classify(3.0 * trefoil, d=3.0 / np.sqrt(2)).label == classify(trefoil).label


def test_open_chains(trefoil):
    x = trefoil[:60]
    c = check(x, closed=False)
    assert c.ok and not c.closed and c.n_beads == 60
    assert check(Chain(x, closed=False)).closed is False
