"""Basin hops (engine/schedules.py, engine/driver.py): the plan of the hop stage, and runs that
keep bonds, exclusion, energy bookkeeping and knot type while each hop restarts from the
lowest polished chain found so far."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from helpers import braid_chain
from stiffknots.engine.driver import AnnealSettings, plan_steps, run_replica
from stiffknots.engine.kernel import energy_chain
from stiffknots.engine.params import MoveParams
from stiffknots.engine.prims import check_state
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import ChainState
from stiffknots.errors import InvalidParameter
from stiffknots.knots.identify import homfly_code

HOPS = AnnealSettings(moves=300_000, n_chunks=20,
                      schedule=Schedule(hops=3, hop_fraction=0.3))


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


@pytest.mark.parametrize("kw, match", [
    ({"hops": 3}, "hop_fraction"),                                   # no moves for them
    ({"hops": 3, "hop_fraction": 0.7, "relax_fraction": 0.4}, "hop_fraction"),  # none left
    ({"hops": -1}, "hops"),
    ({"hops": 2, "hop_fraction": 0.2, "t_hop": 1e-7}, "t_hop"),      # not above t_end
])
def test_bad_hop_settings_are_refused(kw, match):
    with pytest.raises(InvalidParameter, match=match):
        Schedule(**kw).validate()


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_hops_keep_the_chain_admissible_and_the_knot(exclusion):
    x = braid_chain("5_2")
    params = MoveParams(exclusion=exclusion)
    settings = replace(HOPS, params=params)
    res = run_replica(x, settings, seed=3)
    y = res.coords
    assert np.max(np.abs(np.linalg.norm(np.roll(y, -1, 0) - y, axis=1) - 1)) < 1e-8
    mode = 0 if exclusion == "bead" else 1
    assert check_state(y, mode, params.d, params.w, False) <= 1e-12
    assert res.energy == pytest.approx(float(energy_chain(y, False)), rel=1e-12)
    assert homfly_code(y) == homfly_code(x)
    # the result is the lowest candidate: each stage's chain is polished before it is
    # ranked, and polishing never raises the energy, so it lies at or below every quench
    assert res.best_stage in ("relax", "anneal", "hop1", "hop2", "hop3")
    assert res.epsilon <= min(res.stage_epsilon.values()) + 1e-9


def test_restore_puts_back_a_chain_with_its_energy():
    x = braid_chain("3_1")
    st = ChainState(x, seed=0)
    e0 = st.energy
    st.run(20_000, 1e-3)
    assert st.energy != e0
    st.restore(x)
    assert np.array_equal(st.pos, x) and st.energy == pytest.approx(e0, rel=1e-12)
    assert st.recomputed_energy() == pytest.approx(st.energy, rel=1e-12)
    st.run(20_000, 1e-4)  # and the moves go on from it, bookkeeping exact
    assert st.recomputed_energy() == pytest.approx(st.energy, rel=1e-9)
    with pytest.raises(ValueError, match="shape"):
        st.restore(x[:-1])
