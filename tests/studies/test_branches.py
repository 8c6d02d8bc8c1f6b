"""Branches (studies/branches): a state followed down a ladder of w/L keeps its class and
extrapolates to its structure value; a branch that changes class, jumps or merges with another
says so at the width where it happens and is fitted only before it."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from helpers import DATA
from stiffknots.errors import InvalidParameter
from stiffknots.studies.branches import follow_state, follow_states


def _chain(name):
    return np.load(DATA / "analysis" / f"{name}.npy")


def _result(x, eps):
    """What a runner returns for a relaxation: best chain first, its replicas."""
    best = SimpleNamespace(coords=x, epsilon=eps)
    return SimpleNamespace(best=best, replicas=[best], interrupted=False)


def _scripted(chains_by_call):
    """A runner that answers the k-th relaxation with the k-th (chain, ε) and records the
    problems it was given (their N and w/L)."""
    calls = []

    def runner(problem, label):
        x, eps = chains_by_call[len(calls)]
        calls.append((problem, label))
        return _result(x, eps)
    return runner, calls


def _circle_cover(n, turns=2, lift=0.05):
    """A doubly covered circle of N unit-ish bonds, strands apart in z (a 3_1-like CB(2))."""
    t = 2 * math.pi * np.arange(n) / n
    x = np.column_stack([np.cos(turns * t) * (1 + lift * np.cos(3 * t)),
                         np.sin(turns * t) * (1 + lift * np.cos(3 * t)), lift * np.sin(3 * t)])
    return x * n / np.sum(np.linalg.norm(np.diff(np.vstack([x, x[:1]]), axis=0), axis=1))


def test_a_branch_that_stays_in_its_state_is_fitted_to_its_limit():
    """A scripted CB(2) branch: ε_N = 8π² + 40 w/L at N = 100 (no event); the fit, with the
    polygon rule for k, lands within its error of 8π² · (1 + k/N²) − the rule's correction."""
    cage = _chain("4_1_tube_cage")
    widths = (0.004, 0.002, 0.001, 0.0005)
    script = [(cage, 126.0 + 400 * w) for w in widths]
    runner, calls = _scripted(script)
    b = follow_state("4_1", cage, widths=widths, beads=100, measure_k=False, runner=runner)
    assert [c[0].beads for c in calls] == [100] * 4
    assert b["event"] is None and b["shape"] == "4C"
    assert all(p["in_fit"] and p["shape"] == "4C" for p in b["points"])
    assert [p["step"] for p in b["points"]][1:] == pytest.approx([0, 0, 0], abs=1e-6)
    k = b["discretisation"]["k"]
    assert k == pytest.approx((126.0 + 400 * 0.0005) / 6)
    assert b["epsilon_thin"] == pytest.approx(126.0 * (1 + k / 100**2), abs=3 * b["error"])
    assert b["structure_route"]["name"] == "4C"
    assert len(b["chains"]) == 4 and b["parameters"]["beads"] == 100


def test_a_class_change_is_recorded_and_followed_a_jump_ends_the_fit():
    cage, other = _chain("4_1_tube_cage"), _chain("4_1_tube_other")
    widths = (0.004, 0.003, 0.002, 0.001)
    # a continuous class change (the same curve read as another class: step 0) is an event
    # that the fit goes through: the state deformed into another class, and is followed
    runner, _ = _scripted([(cage, 128.9), (cage, 128.2), (cage[::-1], 127.0),
                           (cage, 126.4)])
    b = follow_state("4_1", cage, widths=widths, beads=150, measure_k=False, runner=runner)
    assert b["event"] is None and b["events"] == []
    # the cage's chain followed by the `other`'s: read `other` there, but 0.052 L away — a jump
    runner, _ = _scripted([(cage, 128.9), (cage, 128.2), (other, 127.0)])
    b = follow_state("4_1", cage, widths=(0.004, 0.003, 0.002), beads=150, measure_k=False,
                     runner=runner)
    assert b["event"]["kind"] == "jumped" and b["event"]["w_over_L"] == 0.002
    assert [e["kind"] for e in b["events"]] == ["jumped"]
    assert [p["in_fit"] for p in b["points"]] == [True, True, False]
    # the state ended: no limit of its own; its two points before are kept as `partial`
    assert b["epsilon_thin"] is None and b["partial"]["epsilon_thin"] is not None
    # the same class but another curve, more than 0.03 L away (5_2's cage, also a 4C): a jump
    # (last: the next relaxation would refuse it, a 5_2 is not a 4_1)
    runner, _ = _scripted([(cage, 128.9), (cage, 128.2), (_chain("5_2_tube_cage"), 128.0)])
    b = follow_state("4_1", cage, widths=(0.004, 0.002, 0.001), beads=150, measure_k=False,
                     runner=runner)
    assert b["event"]["kind"] == "jumped" and b["event"]["w_over_L"] == 0.001
    assert [p["in_fit"] for p in b["points"]] == [True, True, False]


def test_a_continuous_change_of_class_is_recorded_and_fitted_through(monkeypatch):
    """The classifier's verdict changes along the branch while the curve moves by less than
    a jump: recorded as 'changed class', the fit goes on (6_1's `other` becoming a cage)."""
    import stiffknots.studies.branches as br

    cage = _chain("4_1_tube_cage")
    reads = iter([("other", "other", None, "s"), ("other", "other", None, "s"),
                  ("4C", "4C", None, "s"), ("4C", "4C", None, "s")])
    start = [True]

    def fake_read(x, w):
        if start[0]:                      # the start chain: read as `other`
            start[0] = False
            return ("other", "other", None, "s")
        return next(reads)
    monkeypatch.setattr(br, "_read", fake_read)
    runner, _ = _scripted([(cage, 128.9), (cage, 128.2), (cage, 127.6), (cage, 127.0)])
    b = follow_state("4_1", cage, widths=(0.004, 0.003, 0.002, 0.001), beads=150,
                     measure_k=False, runner=runner)
    assert b["event"] is None and all(p["in_fit"] for p in b["points"])
    assert [(e["kind"], e["w_over_L"]) for e in b["events"]] == [("changed class", 0.002)]
    assert b["events"][0]["detail"].startswith("other → 4C")
    assert b["structure_route"]["name"] == "4C"   # the class it became


def test_two_branches_that_meet_at_one_width_merge_there():
    other = _chain("4_1_tube_other")
    widths = (0.004, 0.002, 0.001)
    # branch 0: the `other` at 128.1, 127.0, 126.5; branch 1, another start of the same
    # class, 0.6 % higher at 0.004, then the first's curve (renumbered) and ε at 0.002
    script = [(other, 128.1), (other, 127.0), (other, 126.5),
              (other, 128.9), (np.roll(other, 17, axis=0), 127.0), (other, 126.5)]
    runner, _ = _scripted(script)
    r = follow_states("4_1", [{"coords": other, "tag": "other"},
                              {"coords": other + 1.0, "tag": "copy"}],
                      widths=widths, beads=150, measure_k=False, runner=runner)
    first, second = r["branches"]
    assert first["event"] is None
    assert second["event"] == {"kind": "merged", "w_over_L": 0.002, "detail": "with other"}
    assert [p["in_fit"] for p in second["points"]] == [True, False, False]
    assert second["epsilon_thin"] is None and r["ground"] == 0
    assert second["partial"]["epsilon_thin"] is None       # one point before the merger


def test_bad_ladders_are_refused():
    with pytest.raises(InvalidParameter):
        follow_state("3_1", _circle_cover(60), widths=(0.002, 0.002))


def test_a_branch_that_jumped_into_another_does_not_make_that_one_a_merger():
    """6_1's case: state 0 jumps into the cage that state 1 follows continuously; state 1 keeps
    its own branch (and limit), state 0 ends."""
    cage, other = _chain("4_1_tube_cage"), _chain("4_1_tube_other")
    script = [(other, 128.1), (cage, 127.0), (cage, 126.5),       # state 0: jumps at 0.002
              (cage, 128.9), (cage, 127.0), (cage, 126.5)]        # state 1: the cage
    runner, _ = _scripted(script)
    r = follow_states("4_1", [{"coords": other, "tag": "other"}, {"coords": cage, "tag": "cage"}],
                      widths=(0.004, 0.002, 0.001), beads=150, measure_k=False, runner=runner)
    first, second = r["branches"]
    assert first["event"]["kind"] == "jumped" and first["epsilon_thin"] is None
    assert second["event"] is None and second["epsilon_thin"] is not None
    assert r["ground"] == 1
