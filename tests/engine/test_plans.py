"""Plans (:mod:`stiffknots.engine.plans`): the chunks of a run add up to its moves, stages end
where they should, and basin hops each restart once from the best chain and cool geometrically
(§VII)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from stiffknots.engine.plans import plan_steps
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.settings import AnnealSettings

SMALL = AnnealSettings(moves=300_000, n_chunks=20)
HOPS = AnnealSettings(moves=300_000, n_chunks=20,
                      schedule=Schedule(hops=3, hop_fraction=0.3))


def test_plan_adds_up():
    steps = plan_steps(SMALL)
    assert sum(s.moves for s in steps) == SMALL.moves
    assert len(steps) == SMALL.n_chunks + 10
    assert [s.stage for s in steps if s.last] == ["relax", "anneal"]
    plain = plan_steps(replace(SMALL, schedule=Schedule(relax_fraction=0.0)))
    assert len(plain) == SMALL.n_chunks + 10 and {s.stage for s in plain} == {"anneal"}
    assert all(s.temperature == 0.0 for s in plain[-10:])


def test_the_plan_of_the_hops():
    steps = plan_steps(HOPS)
    assert sum(s.moves for s in steps) == HOPS.moves
    assert [s.stage for s in steps if s.last] == ["relax", "anneal", "hop1", "hop2", "hop3"]
    sch = HOPS.schedule
    for k in (1, 2, 3):
        mine = [s for s in steps if s.stage == f"hop{k}"]
        # a hop starts from the best chain so far, once, at its first chunk
        assert mine[0].restore_best and not any(s.restore_best for s in mine[1:])
        hot = [s.temperature for s in mine if s.temperature > 0]
        # geometric from t_hop (odd hops) or t_hop/4 (even: a milder hop) down to t_end,
        # each chunk at the temperature of its midpoint
        top = sch.t_hop if k % 2 else sch.t_hop / 4
        mid = (np.arange(len(hot)) + 0.5) / len(hot)
        assert np.allclose(hot, top * (sch.t_end / top) ** mid, rtol=1e-12)
        assert np.all(np.diff(hot) < 0) and mine[-1].temperature == 0.0  # cools, quenches
        assert sum(s.moves for s in mine) == pytest.approx(0.1 * HOPS.moves, abs=2)
    assert not any(s.restore_best for s in steps if not s.stage.startswith("hop"))
    # without hops the plan is the one it always was
    plain = plan_steps(replace(HOPS, schedule=Schedule()))
    assert len(plain) == HOPS.n_chunks + 10
    assert [s.stage for s in plain if s.last] == ["relax", "anneal"]
