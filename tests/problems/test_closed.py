"""Closed knots (problems/closed): the tube route of the bead rule, the schedules without
basin hops, the langevin schedule's model, and the width a result carries."""

from __future__ import annotations

import numpy as np
import pytest

from stiffknots.problems.closed import anneal


def test_a_result_carries_its_width():
    from stiffknots.width import Width

    res = anneal("3_1", beads=60, moves=20_000, replicas=1, seed=1, rounds=1)
    assert res.width == Width.bead(60)
    d = res.to_dict()
    assert d["width"] == Width.bead(60).as_dict()
    assert Width.bead(60).text in d["thin_limit"]["note"]


def test_bead_rule_searches_after_the_fresh_rounds_take_the_tube_route():
    """With tube_route=True, from the third round on a bead-rule run's new searches anneal
    under the tube rule of diameter w = d and are polished under the bead rule
    (problems.closed.TUBE_ROUTE_FROM);
    the fresh rounds, a tube-rule run, a run without the polish and the default
    (tube_route=False) do not; the settings say so."""
    from stiffknots.problems.closed import TUBE_ROUTE_FROM, ClosedAnneal

    p = ClosedAnneal("5_2", moves=1_000, replicas=2, tube_route=True)
    assert TUBE_ROUTE_FROM == p.fresh_rounds == 2
    bead = p.settings.params
    for j in p.jobs(first=0) + p.jobs(first=2):
        assert j.settings.params.exclusion == "bead" and j.polish_params is None
        assert j.search is None
    for first in (4, 6):
        for j in p.jobs(first=first):
            q = j.settings.params
            assert (q.exclusion, q.w) == ("tube", bead.d)
            assert j.polish_params == bead and "tube rule" in j.search
            assert j.settings.moves == p.settings.moves
            assert j.settings.schedule == p.settings.schedule
    assert p.settings_dict()["tube_route_from_round"] == 3
    from stiffknots.engine.params import MoveParams

    for q in (ClosedAnneal("5_2", moves=1_000, replicas=2),  # the default: off
              ClosedAnneal("5_2", moves=1_000, replicas=2, tube_route=True, polish=False),
              ClosedAnneal("5_2", moves=1_000, replicas=2, tube_route=True,
                           params=MoveParams(exclusion="tube"))):
        assert all(j.polish_params is None for j in q.jobs(first=4))
        assert "tube_route_from_round" not in q.settings_dict()


def test_a_tube_route_replica_ends_bead_admissible_polished_and_verified():
    """A tube-route job: its Monte Carlo holds the tube rule, its polish the bead rule; the
    replica ends with unit bonds, no two beads at index distance ≥ 2 closer than d, its knot
    verified, ε at or below its tube chain's and recomputed from its coordinates."""
    from stiffknots.engine.kernel import energy_chain
    from stiffknots.knots.identify import verify_knot
    from stiffknots.problems.base import run_job
    from stiffknots.problems.closed import ClosedAnneal

    p = ClosedAnneal("4_1", moves=200_000, replicas=2, seed=3, tube_route=True)
    (job, _) = p.jobs(first=4)
    r = run_job(job)
    y = r.coords
    n = len(y)
    assert r.knot_verified and verify_knot(y, "4_1")[0]
    assert r.observables["search"] == job.search
    bonds = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    assert np.max(np.abs(bonds - 1)) < 1e-10
    dist = np.linalg.norm(y[:, None] - y[None], axis=2)
    sep = np.abs(np.arange(n)[:, None] - np.arange(n)[None])
    sep = np.minimum(sep, n - sep)
    d = p.settings.params.d
    assert dist[sep >= 2].min() >= d - 1e-10
    assert r.exclusion_margin >= -1e-10
    assert r.epsilon == pytest.approx(n * energy_chain(y, False), rel=1e-12)
    assert r.epsilon <= r.polish["epsilon_before"] + 1e-9
    # polished under the bead rule, not the tube's: strands press between beads, closer than
    # the tube would allow (0.488 here; the same job polished under the tube rule ends at
    # exactly w = d, 0.70711, and ε 129.312 against 128.459)
    assert r.min_segment_distance < d - 0.1


@pytest.mark.slow  # 40 s each (three rounds of 7_4)
@pytest.mark.parametrize("kind", ["langevin", "tempering"])
def test_schedules_without_hops_run_later_rounds_as_new_searches(kind):
    # a schedule that cannot continue a search (no basin hops) fills the rounds after the
    # fresh ones with new searches (it once failed there on zip(legs, parents)); 7_4 on a
    # budget this small never converges
    from stiffknots.engine.schedules import Schedule

    sch = Schedule(kind=kind, t_end=1e-4, relax_fraction=0.0)
    res = anneal("7_4", moves=2_000 if kind == "langevin" else 20_000, replicas=2, seed=0,
                 rounds=3, schedule=sch)
    assert res.rounds == 3 and len(res.replicas) == 6
    assert all(r.leg == 0 and r.lineage == r.replica for r in res.replicas)
    assert all(r.knot == "7_4" and r.knot_verified and r.polish for r in res.replicas)
    if kind == "langevin":
        assert all(r.langevin["refused_steps"] >= 0 for r in res.replicas)


def test_the_langevin_schedule_is_refused_for_the_tube_model():
    from stiffknots.engine.params import MoveParams
    from stiffknots.engine.schedules import Schedule
    from stiffknots.errors import InvalidParameter

    with pytest.raises(InvalidParameter, match="bead rule"):
        anneal("3_1", schedule=Schedule(kind="langevin"), params=MoveParams(exclusion="tube"))


def test_a_start_the_exclusion_rule_does_not_admit_is_refused_before_any_worker():
    """10_101's braid closure at N = 100 is admissible for the bead rule but brings two
    strands 0.071 closer than the tube's w = 1/√2 where they cross: the tube problem's jobs
    are refused with a message naming the start, N, the rule and the way out (before: a
    ValueError of the engine's chain in the worker, naming neither), and the bead problem's
    are built. At N = 150 the same start is admissible for the tube."""
    import math

    from stiffknots.engine.params import MoveParams
    from stiffknots.engine.prims import check_state
    from stiffknots.errors import EmbeddingError
    from stiffknots.problems.closed import ClosedAnneal

    w = 1 / math.sqrt(2)
    tube = ClosedAnneal("10_101", beads=100, moves=1_000, replicas=1, start="braid",
                        params=MoveParams(exclusion="tube", w=w))
    assert check_state(tube.chains["braid"], 1, w, w, False) > 0.05  # the premise
    with pytest.raises(EmbeddingError, match=r"braid embedding of 10_101 at N = 100 .*"
                                             r"tube of diameter w = 0\.7071.*more beads"):
        tube.jobs()
    bead = ClosedAnneal("10_101", beads=100, moves=1_000, replicas=1, start="braid")
    assert len(bead.jobs()) == 1
    ok = ClosedAnneal("10_101", beads=150, moves=1_000, replicas=1, start="braid",
                      params=MoveParams(exclusion="tube", w=w))
    assert len(ok.jobs()) == 1
