"""Tests of the census of a knot's states (stiffknots.analysis.census): the known pairs of
#37 — 4_1's cage against its `other`, 5_2's cage against its 80, two 3_1 circular braids that
differ by an index shift — and the window, the search count and the input checks."""

import json

import numpy as np
import pytest

from stiffknots.analysis.census import census


def _item(x, eps, label, mult=None, search=None, **kw):
    return {"coords": x, "epsilon": eps, "label": label, "multiplicity": mult,
            "search": search, **kw}


def test_4_1_cage_and_other_are_two_states_each_with_its_searches(annealed):
    other, cage = annealed("4_1_tube_other.npy"), annealed("4_1_tube_cage.npy")
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    items = [_item(cage, 129.3124, "4C", search=1),
             _item(other, 128.5649, "other", search=0),
             _item(np.roll(other, 40, axis=0) @ rot.T, 128.5660, "other", search=3),
             _item(cage[::-1], 129.3124, "4C", search=1),       # a leg of search 1 again
             _item(cage + 5.0, 129.3130, "4C", search=2)]
    c = census(items)
    assert [s.name for s in c.states] == ["other", "4C"]
    other_state, cage_state = c.states
    assert (other_state.count, other_state.searches, other_state.representative) == (2, 2, 1)
    assert (cage_state.count, cage_state.searches) == (3, 2)
    assert other_state.spread < 1e-6 and cage_state.spread < 1e-6
    json.dumps(c.to_dict())


def test_5_2_cage_and_80_are_two_states(annealed):
    cage, eighty = annealed("5_2_tube_cage.npy"), annealed("5_2_tube_80.npy")
    c = census([_item(cage, 145.4663, "4C"), _item(eighty, 146.0, "80")])
    assert [s.name for s in c.states] == ["4C", "80"]


def test_two_circular_braids_that_differ_by_an_index_shift_are_one_state(annealed):
    x = annealed("3_1_seed1_r1.npy")
    items = [_item(x, 79.4889, "CB", 2), _item(np.roll(x, 75, axis=0), 79.4889, "CB", 2),
             _item(annealed("3_1_seed1_r0.npy"), 80.306, "CB", 2)]
    c = census(items)
    assert [s.count for s in c.states] == [2, 1]    # the other replica is 1.03 % higher
    assert c.ground.spread < 1e-6
    c = census(items, rel_tol=0.02)
    assert len(c.states) == 1 and c.ground.count == 3 and c.ground.searches == 3
    assert 0.005 < c.ground.spread < 0.01           # the other replica, 0.007 L away


def test_one_class_and_energy_but_another_shape_is_another_state(annealed):
    """Shape class and ε alone would merge these: the shape distance keeps them apart."""
    cage, other = annealed("4_1_tube_cage.npy"), annealed("4_1_tube_other.npy")
    c = census([_item(cage, 129.0, "other"), _item(other, 129.1, "other")])
    assert len(c.states) == 2
    assert len(census([_item(cage, 129.0, "other"), _item(other, 129.1, "other")],
                      max_distance=0.1).states) == 1


def test_the_window_and_the_energy_tolerance(annealed):
    x = annealed("3_1_seed1_r1.npy")
    items = [_item(x, 100.0, "CB", 2), _item(x, 100.5, "CB", 2), _item(x, 104.0, "CB", 2),
             _item(x, 116.0, "CB", 2)]
    c = census(items)
    assert [(s.epsilon, s.count) for s in c.states] == [(100.0, 2), (104.0, 1)]
    assert (c.n_items, c.n_counted) == (4, 3)
    assert len(census(items, window=0.2).states) == 3
    assert [s.count for s in census(items, rel_tol=0.05).states] == [3]
    assert [s.count for s in census(items, rel_tol=0.05, window=0.2).states] == [3, 1]


def test_circular_braids_of_another_index_are_another_state(annealed):
    x = annealed("3_1_seed1_r1.npy")
    c = census([_item(x, 80.0, "CB", 2), _item(x, 80.1, "CB", 3)])
    assert [s.name for s in c.states] == ["CB(i=2)", "CB(i=3)"]


def test_bad_items_are_refused_with_the_reason(annealed):
    x = annealed("3_1_seed1_r1.npy")
    with pytest.raises(ValueError, match="at least one"):
        census([])
    with pytest.raises(ValueError, match="finite"):
        census([_item(x, float("nan"), "CB", 2)])
    with pytest.raises(ValueError, match="'coords' and 'label'"):
        census([{"coords": x, "epsilon": 1.0}])
    with pytest.raises(ValueError, match="multiplicity"):
        census([_item(x, 1.0, "CB")])
    with pytest.raises(ValueError, match="window"):
        census([_item(x, 1.0, "other")], window=-0.1)
