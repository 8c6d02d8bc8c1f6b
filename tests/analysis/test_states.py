"""Tests of the ground and metastable states of a set of chains
(stiffknots.analysis.states)."""

import json
from types import SimpleNamespace

import pytest

from stiffknots.analysis.states import group_states


def test_group_states_picks_lowest_epsilon_as_ground(annealed, manifest):
    items = [{"coords": annealed(m["file"]), "epsilon": m["epsilon"], "meta": {"file": m["file"]}}
             for m in manifest if m["knot"] == "6_3"]
    res = group_states(items)
    assert res.ground.label == "80" and res.ground.eps_min == pytest.approx(166.756, abs=1e-3)
    assert [(s.label, s.multiplicity) for s in res.metastable] == [("CB", 3)]
    assert res.ground.meta == {"file": "6_3_seed1_r1.npy"}
    json.dumps(res.to_dict())


def test_group_states_counts_and_tolerance(annealed):
    x80, x4c = annealed("5_2_seed1_r0.npy"), annealed("4_1_seed1_r0.npy")
    items = [
        {"coords": x80, "epsilon": 150.1},
        {"coords": x80, "epsilon": 148.8},
        {"coords": x4c, "epsilon": 129.6},
        {"coords": x80, "epsilon": 148.9},
        {"coords": x80, "epsilon": 153.0},   # > 1 % above 148.8: a separate 80 state
        SimpleNamespace(coords=x4c, epsilon=130.0),
    ]
    res = group_states(items)
    assert res.ground.label == "4C" and res.ground.count == 2
    assert res.ground.representative == 2 and res.ground.members == [2, 5]
    assert res.ground.eps_mean == pytest.approx(129.8)
    first, second = res.metastable
    assert (first.label, first.count, first.representative) == ("80", 3, 1)
    assert first.eps_min == pytest.approx(148.8) and first.eps_max == pytest.approx(150.1)
    assert (second.label, second.count, second.eps_min) == ("80", 1, 153.0)
    # a looser tolerance merges the two 80 states
    assert [s.count for s in group_states(items, rel_tol=0.05).states] == [2, 4]


def test_group_states_with_given_labels():
    items = [{"label": "CB", "multiplicity": 2, "epsilon": 80.0},
             {"label": "CB", "multiplicity": 3, "epsilon": 181.0},
             {"label": "CB", "multiplicity": 2, "epsilon": 79.5}]
    res = group_states(items)
    assert res.ground.name == "CB(i=2)" and res.ground.count == 2
    assert res.ground.representative == 2
    assert res.metastable[0].name == "CB(i=3)"


@pytest.mark.parametrize(
    "items, kwargs, match",
    [
        ([], {}, "at least one"),
        ([{"label": "80"}], {}, "epsilon must be a number"),
        ([{"label": "80", "epsilon": float("nan")}], {}, "finite"),
        ([{"label": "8", "epsilon": 1.0}], {}, "label must be one of"),
        ([{"label": "CB", "epsilon": 1.0}], {}, "multiplicity"),
        ([{"epsilon": 1.0}], {}, "neither 'coords'"),
        ([{"label": "80", "epsilon": 1.0}], {"rel_tol": -0.1}, "rel_tol"),
    ],
)
def test_group_states_bad_input(items, kwargs, match):
    with pytest.raises(ValueError, match=match):
        group_states(items, **kwargs)
