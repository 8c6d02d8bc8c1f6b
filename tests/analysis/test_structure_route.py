"""The structure route read from a chain (analysis/structure_route): the graph of an annealed
chain turned into the w = 0 problem of theory.structures and solved — the 4_1 cage read from a
Monte Carlo chain gives ε*_4C of the hand-written cage to 1e-6; graphs with a line-braid are
refused with the reason; the knot check."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from helpers import DATA
from stiffknots.analysis.structure_route import (
    StructureRouteError,
    solve_chain,
    structure_problem,
)

W = 1 / math.sqrt(2)
EPS_4C = 126.4724695555


def _chain(name):
    return np.load(DATA / "analysis" / f"{name}.npy")


def test_the_cage_read_from_a_chain_is_the_4_fold_cage():
    p = structure_problem(_chain("4_1_tube_cage"), W)
    assert p.node_names == ("J0 (point-braid)", "J1 (point-braid)") and len(p.arcs) == 4
    # every arc joins the two point-braids, one per pair of sides (the cage's quadrants)
    sides = set()
    for a in p.arcs:
        assert {a.start, a.end} == {0, 1} and a.multiplicity == 1
        at0 = a.start_sign if a.start == 0 else -a.end_sign     # the side of J0 it uses
        at1 = a.start_sign if a.start == 1 else -a.end_sign
        sides.add((at0, at1))
    assert sides == {(1, 1), (1, -1), (-1, 1), (-1, -1)}
    r = solve_chain(_chain("4_1_tube_cage"), W)
    assert r.epsilon == pytest.approx(EPS_4C, abs=1e-6)
    assert r.error < 1e-6 and r.keeps_knot and r.min_arc_distance > 0.005
    assert r.negative_modes == 0 and r.minimum
    assert r.name == "2 point-braids" and (r.arcs, r.junctions) == (4, 2)


def test_the_4_1_flat_state_solved_at_w_0_lies_below_the_cage():
    """4_1's `other` (a point-braid and two double points), read from its chain at
    w/L = 0.00025 (N = 173, read at d = 0.5): a minimum at 126.1586 — below ε*_4C
    (docs/thin-limit.md); Newton from the chain converges, so no SLSQP search (2 s, not 150)."""
    with warnings.catch_warnings():      # a w = 0.043 chain read at d = 0.5, on purpose
        warnings.simplefilter("ignore")
        r = solve_chain(_chain("4_1_tube_other_thin"), 0.5)
    assert r.name == "point-braid + 2 double points" and (r.arcs, r.junctions) == (6, 3)
    assert r.epsilon == pytest.approx(126.158594, abs=2e-5) and r.error < 1e-6
    assert r.keeps_knot and r.minimum
    assert r.epsilon < EPS_4C - 0.3
    assert r.details["newton_first"] and not r.details["budget_hit"]


def test_newton_from_the_chain_and_the_search_reach_the_same_cage():
    """Newton first (the route's default) and SLSQP first from the same chain: one minimum."""
    from stiffknots.theory.structures import solve_structure

    p = structure_problem(_chain("4_1_tube_cage"), W)
    fast = solve_structure(p, (16, 32, 64), orders=2, newton_first=True)
    slow = solve_structure(p, (16, 32, 64), orders=2)
    assert fast.coarse["newton_first"] and fast.coarse["nit"] == 0
    assert not slow.coarse["newton_first"] and slow.coarse["nit"] > 10
    assert fast.epsilon == pytest.approx(slow.epsilon, abs=1e-9)


@pytest.mark.parametrize("name, words", [("3_1_seed1_r1", "line-braid of multiplicity 2"),
                                         ("5_2_tube_80", "line-braid of multiplicity 2")])
def test_a_line_braid_is_refused_with_the_reason(name, words):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StructureRouteError, match=words):
            structure_problem(_chain(name), W)


def test_a_chain_without_contacts_is_refused():
    t = 2 * math.pi * np.arange(100) / 100
    circle = np.column_stack([np.cos(t), np.sin(t), np.zeros(100)]) * (100 / (2 * math.pi))
    with pytest.raises(StructureRouteError, match="no point-braid or multiple point"):
        structure_problem(circle, W)
