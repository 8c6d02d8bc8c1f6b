"""The thin-limit ground state's pieces (studies/thin_states): the structure route of a
followed state — the chain's own graph where it can be translated, the named structure of its
class where it cannot — and the input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers import DATA
from stiffknots.errors import InvalidParameter
from stiffknots.studies.thin_states import structure_route, thin_limit_states


def _branch(chain, label, mult, w_over_L=0.00025, beads=173):
    pts = [{"w_over_L": w_over_L, "w": w_over_L * beads, "in_fit": True}]
    return {"knot": "k", "points": pts, "chains": [chain],
            "start": {"label": label, "multiplicity": mult}}


def test_a_cage_branch_is_solved_from_its_own_chain():
    x = np.load(DATA / "analysis" / "4_1_tube_cage_thin.npy")
    r = structure_route(_branch(x, "4C", None))
    assert r["epsilon"] == pytest.approx(126.4724695555, abs=1e-6)
    assert r["minimum"] and r["keeps_knot"] and r["note"] is None
    assert "w/L = 0.00025 solved at w = 0 (4 arcs, 2 junctions)" in r["method"]


def test_a_circular_braid_falls_back_to_its_named_structure_and_says_why():
    x = np.load(DATA / "analysis" / "3_1_seed1_r1.npy")
    r = structure_route(_branch(x, "CB", 2, w_over_L=0.0047, beads=150))
    assert r["epsilon"] == pytest.approx(8 * math.pi**2, rel=1e-9) and r["name"] == "CB(2)"
    assert "line-braid of multiplicity 2" in r["note"] and r["minimum"] is True


def test_an_other_state_without_a_translatable_graph_has_no_route():
    x = np.load(DATA / "analysis" / "3_1_seed1_r1.npy")
    r = structure_route(_branch(x, "other", None, w_over_L=0.0047, beads=150))
    assert r["epsilon"] is None and r["note"].startswith("no structure route")


def test_a_route_stopped_at_its_budget_gives_no_number(monkeypatch):
    """The coarse search stopped before a minimum (here: a budget of 0 s, SLSQP first): what
    Newton reached from there is no structure's energy, so the route reports none, and why."""
    import functools

    import stiffknots.analysis.structure_route as sr

    monkeypatch.setattr(sr, "solve_chain", functools.partial(
        sr.solve_chain, coarse_budget_s=0.0, newton_first=False))
    x = np.load(DATA / "analysis" / "4_1_tube_cage_thin.npy")
    r = structure_route(_branch(x, "other", None))
    assert r["epsilon"] is None and r["minimum"] is False
    assert r["note"].startswith("no structure route: the coarse search stopped at its 0 CPU s "
                                "budget without a converged minimum")


@pytest.mark.parametrize("kw", [dict(budget="huge"), dict(states=0), dict(seed=-1)])
def test_bad_input_is_refused_before_any_work(kw):
    with pytest.raises(InvalidParameter):
        thin_limit_states("3_1", **kw)


def test_route_difference_says_why_two_routes_differ():
    from stiffknots.studies.thin_states import route_difference

    # agreeing, not compared, or no structure value: nothing to explain
    assert route_difference(126.41, 126.4725, "2 point-braids", True) is None
    assert route_difference(174.1, 169.2, "point-braid (m = 3) + point-braid", None) is None
    assert route_difference(None, 142.58, "80", False) is None
    # point-braid states above their w = 0 solution: the measured slow approach (6_1's cage,
    # 8_2's 80 in bench/thin_deep.json)
    why = route_difference(128.422, 126.4725, "2 point-braids", False)
    assert "1.54 % above" in why and "upper estimate" in why and "point-braids" in why
    assert "upper estimate" in route_difference(144.46, 142.5844, "80", False)
    # another structure above: not asymptotic yet; below: not this branch's structure
    assert "asymptotic" in route_difference(178.5, 177.6529, "CB(3)", False)
    assert "not this branch's limit" in route_difference(125.0, 126.4725, "2 point-braids",
                                                         False)


def test_routes_agree_within_twice_the_error_unless_the_error_decides_nothing():
    from stiffknots.studies.thin_states import MAX_COMPARED_ERROR, routes_agree, too_wide

    cage = {"epsilon": 126.4725, "keeps_knot": True, "minimum": True}
    assert routes_agree(126.41, 0.18, cage) is True          # 4_1's cage, small ladder
    assert routes_agree(128.42, 0.13, cage) is False         # 6_1's `other`
    assert routes_agree(126.9, 0.01, cage) is True           # within 0.5 % of ε
    # 8_3 at the default ladder: 114.5 ± 15.2 lies "within twice its error" of the cage, an
    # agreement that decides nothing — not compared, and the reason says so
    assert routes_agree(114.53, 15.23, cage) is None
    why = too_wide(114.53, 15.23)
    assert "not compared" in why and "13 %" in why
    assert too_wide(126.41, 0.18) is None
    edge = MAX_COMPARED_ERROR * 126.0
    assert routes_agree(126.0, edge, cage) is True and routes_agree(126.0, 1.01 * edge,
                                                                    cage) is None
    # no structure value, a saddle, strands that meet: not compared
    assert routes_agree(126.41, 0.18, {"epsilon": None}) is None
    assert routes_agree(126.41, 0.18, {**cage, "minimum": False}) is None
    assert routes_agree(126.41, 0.18, {**cage, "keeps_knot": False}) is None
    assert routes_agree(None, None, cage) is None
