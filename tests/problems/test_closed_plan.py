"""What ``anneal`` runs, decided once from its options (problems/closed_plan): the schedule
the options ask for, the N rule, the width, and the cross-checks — before any work."""

from __future__ import annotations

import math

import pytest

from stiffknots.errors import InvalidParameter, ParameterConflict, UnknownKnotError
from stiffknots.knots.catalogue import get_knot
from stiffknots.problems import validate as V
from stiffknots.problems.closed import DEFAULT_ROUNDS, LANGEVIN_ROUNDS
from stiffknots.problems.closed_plan import beads_for_knot, plan_anneal
from stiffknots.width import Width


def test_the_default_search_is_the_langevin_dynamics_of_the_bead_rule():
    p = plan_anneal("3_1")
    assert (p.schedule.kind, p.chosen_by, p.rounds) == ("langevin", "auto", LANGEVIN_ROUNDS)
    assert p.width == Width.bead(150) and p.knot == get_knot("3_1")
    assert p.schedule.t_end == pytest.approx(1e-4)


def test_an_option_of_the_monte_carlo_picks_the_annealing_and_is_named():
    p = plan_anneal("4_1", exclusion="tube", m_max=20, checkpoint_dir="ckpt")
    assert (p.schedule.kind, p.chosen_by, p.rounds) == ("geometric", "monte_carlo",
                                                       DEFAULT_ROUNDS)
    assert p.monte_carlo == ["exclusion", "checkpoint_dir", "m_max"]
    assert p.params.exclusion == "tube" and p.params.m_max == 20
    assert plan_anneal("4_1", w_over_L=0.004).monte_carlo == ["w_over_L"]
    assert plan_anneal("4_1", schedule="power").chosen_by == "named"


def test_w_over_L_sets_the_tube_and_the_N_rule():
    p = plan_anneal("5_2", w_over_L=0.002)
    # the knot's upper bound 2π² i² (i = 3) with a discretisation error below 0.1 %
    n = math.ceil(math.sqrt(18 * math.pi**2 / 6e-3))
    assert p.beads == n == beads_for_knot(get_knot("5_2"), 0.002)
    assert p.width == Width.tube(n, w_over_L=0.002)
    assert p.params.w == 0.002 * n
    assert plan_anneal("5_2", w_over_L=0.002, beads=300).beads == 300


def test_the_problem_is_built_from_the_plan():
    p = plan_anneal(get_knot("3_1"), beads=60, moves=2_000, replicas=1, seed=5,
                    schedule="geometric", rounds=1)
    prob = p.problem()
    assert prob.knot is p.knot and prob.beads == 60 and prob.seed == 5
    assert prob.width() == Width.bead(60)
    assert prob.settings.schedule.kind == "geometric" and prob.rounds == 1


@pytest.mark.parametrize("kw, err, text", [
    ({"w": 0.5}, ParameterConflict, "w applies to exclusion tube only"),
    ({"w": 0.5, "w_over_L": 0.001}, ParameterConflict, "w and w_over_L both set"),
    ({"schedule": "langevin", "exclusion": "tube"}, ParameterConflict,
     "schedule langevin runs the bead rule"),
    ({"schedule": "langevin", "checkpoint_dir": "x"}, ParameterConflict,
     "checkpoint_dir applies to the Monte Carlo schedules"),
    ({"delta": 0.01}, None, None),  # the annealing, chosen by the option
    ({"schedule": "langevin", "delta": 0.01}, ParameterConflict,
     "delta and m_max set the Monte Carlo moves"),
    ({"schedule": "tempering", "relax_fraction": 0.2}, ParameterConflict,
     "relax_fraction applies to the power and geometric"),
    ({"t_start": 1e-5}, ParameterConflict, "t_start must lie above the langevin"),
    ({"m_max": 148}, InvalidParameter, r"m_max must be an integer in \[1, 147\]"),
    ({"coarse": 150}, ParameterConflict, r"coarse must be fewer beads than beads \(150\)"),
    ({"coarse": 4}, InvalidParameter, "coarse must be an integer in"),
    ({"coarse": 100, "w_over_L": 0.002}, ParameterConflict, "coarse keeps the tube's"),
    ({"schedule": "slow"}, InvalidParameter, "schedule must be one of auto"),
    ({"start": "box"}, InvalidParameter, "start must be one of all, braid"),
    ({"exclusion": "soft"}, InvalidParameter, "exclusion must be one of bead, tube"),
    ({"w_over_L": 0.2}, InvalidParameter, r"w_over_L must be a finite number in \(0, 0.125\]"),
])
def test_cross_checks_before_any_work(kw, err, text):
    if err is None:
        assert plan_anneal("4_1", **kw).schedule.kind == "geometric"
        return
    with pytest.raises(err, match=text):
        plan_anneal("4_1", **kw)


def test_an_unknown_knot_is_refused_first():
    with pytest.raises(UnknownKnotError):
        plan_anneal("4_9", beads=3)


def test_rounds_range():
    with pytest.raises(InvalidParameter, match="rounds"):
        plan_anneal("3_1", rounds=V.MAX_ROUNDS + 1)


def test_one_short_search_at_a_time_runs_in_this_process():
    # 1,000 dynamics steps at N = 150: milliseconds, less than a worker costs to start
    assert plan_anneal("3_1", moves=1000, replicas=1).quick()
    assert plan_anneal("3_1", moves=1000, replicas=1, exclusion="tube").quick()
    assert not plan_anneal("3_1", moves=1000, replicas=2).quick()  # two at once: the workers
    assert not plan_anneal("3_1", replicas=1).quick()  # the default 10⁶ steps: seconds
    assert not plan_anneal("3_1", moves=10_000_000, replicas=1, exclusion="tube").quick()
    assert not plan_anneal("3_1", moves=1000, replicas=1, beads=2000).quick()
