"""Coarse-to-fine replicas (problems/coarse): the coarse stage's settings are the fine ones
at N0 (moves per bead, thermal excess per stage, m_max, the rule in bond units), its chain
comes back at N beads with unit bonds, the rule held and the knot type of the start, and a
stage that cannot run says why and leaves the start alone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.engine.params import MoveParams
from stiffknots.problems.coarse import coarse_seed, coarse_settings, coarse_start

W = 1 / math.sqrt(2)


def _settings(moves=20_000, beads=60):
    from stiffknots.problems.closed import ClosedAnneal

    p = ClosedAnneal("3_1", beads=beads, moves=moves, replicas=1, start="braid",
                     params=MoveParams(exclusion="tube", w=W))
    return p


def test_coarse_settings_are_the_fine_ones_at_fewer_beads():
    s = _settings(moves=150_000, beads=150).settings
    c = coarse_settings(s, 150, 100)
    assert c.moves == 100_000  # the same moves per bead
    f = (150 / 100) ** 2  # the same thermal excess δε ≈ N²T per stage
    for name in ("t_start", "t_end", "t_relax", "t_relax_end", "t_hop"):
        assert getattr(c.schedule, name) == pytest.approx(getattr(s.schedule, name) * f)
    assert c.schedule.relax_fraction == s.schedule.relax_fraction
    assert c.params.m_max == 50 and s.params.m_max == 75
    assert (c.params.exclusion, c.params.w, c.params.d) == ("tube", s.params.w, s.params.d)
    assert coarse_seed(7, 100) == coarse_seed(7, 100) != coarse_seed(7, 90) != 7


def test_the_coarse_chain_comes_back_at_n_with_its_knot_type_and_the_rule_held():
    from stiffknots.engine.prims import check_state, energy_closed
    from stiffknots.problems.base import knot_code

    p = _settings()
    (job,) = p.jobs()
    y, info = coarse_start("3_1", "braid", job.settings, 60, 40, seed=3)
    assert info["used"] and info["beads"] == 40 and info["moves"] == round(20_000 * 40 / 60)
    assert y.shape == (60, 3)
    assert np.allclose(np.linalg.norm(np.roll(y, -1, 0) - y, axis=1), 1.0, atol=1e-9)
    assert check_state(y, 1, W, W, False) <= 1e-12
    assert knot_code(y) == job.start_code  # the chiral HOMFLY-PT polynomial of the start
    assert info["epsilon"] > 0 and info["cpu_seconds"] > 0 and np.isfinite(energy_closed(y))
    # reproducible from the seed
    y2, _ = coarse_start("3_1", "braid", job.settings, 60, 40, seed=3)
    assert np.array_equal(y, y2)


def test_a_start_not_admissible_at_n0_is_built_at_the_next_n0_that_admits_it():
    """10_101's braid closure at N0 = 100 brings two strands 0.071 closer than the tube's w;
    at 105 it is admissible: the stage runs there and says so."""
    from stiffknots.engine.prims import check_state
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.starts import start_chain
    from stiffknots.problems.closed import ClosedAnneal

    assert check_state(start_chain(get_knot("10_101"), "braid", 100), 1, W, W, False) > 0.05
    p = ClosedAnneal("10_101", beads=150, moves=2_000, replicas=1, start="braid",
                     params=MoveParams(exclusion="tube", w=W))
    (job,) = p.jobs()
    y, info = coarse_start("10_101", "braid", job.settings, 150, 100, seed=3)
    assert (info["asked"], info["beads"]) == (100, 105)
    # used, or refused by the resampling's certificate after so short a search: either way
    # the stage ran at 105 and says what it did
    assert info["used"] == (y is not None) and ("reason" in info) != info["used"]


def test_a_stage_that_cannot_run_leaves_the_start_and_says_why():
    p = _settings()
    (job,) = p.jobs()
    # 10_58's braid needs 83 beads: none of N0' = 70, 75 (< N = 80) embeds it
    y, info = coarse_start("10_58", "braid", job.settings, 80, 70, seed=3)
    assert y is None and not info["used"]
    assert info["reason"] == ("no admissible braid embedding for the tube rule at N0 = 70 … 79 "
                              "(in steps of 5)")
    with pytest.raises(ValueError, match="3 ≤ N0 < N = 60"):
        coarse_start("3_1", "braid", job.settings, 60, 60, seed=3)


def test_a_replica_with_a_coarse_stage_is_verified_and_counts_its_cost():
    from dataclasses import replace

    from stiffknots.problems.base import run_job

    p = _settings()
    (job,) = p.jobs()
    r = run_job(replace(job, coarse=40))
    assert r.knot_verified and r.observables["coarse"]["used"]
    assert r.cpu_time >= r.observables["coarse"]["cpu_seconds"]
    plain = run_job(job)
    assert "coarse" not in plain.observables
    from stiffknots.problems.closed import ClosedAnneal

    with pytest.raises(Exception, match="coarse must be an integer"):
        ClosedAnneal("3_1", beads=60, moves=1_000, coarse=60,
                     params=MoveParams(exclusion="tube", w=W))
    q = ClosedAnneal("3_1", beads=60, moves=1_000, replicas=2, coarse=40, start="braid",
                     params=MoveParams(exclusion="tube", w=W))
    assert all(j.coarse == 40 for j in q.jobs()) and q.settings_dict()["coarse_per_replica"] == 40
