"""Basin hops (engine/schedules.py, engine/driver.py): bad hop settings are refused, and runs
keep bonds, exclusion, energy bookkeeping and knot type while each hop restarts from the
lowest polished chain found so far (the plan of the hop stage: test_plans.py)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from helpers import braid_chain
from stiffknots.engine.driver import run_replica
from stiffknots.engine.kernel import energy_chain
from stiffknots.engine.params import MoveParams
from stiffknots.engine.prims import check_state
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.settings import AnnealSettings
from stiffknots.engine.state import ChainState
from stiffknots.errors import InvalidParameter
from stiffknots.knots.identify import homfly_code

HOPS = AnnealSettings(moves=300_000, n_chunks=20,
                      schedule=Schedule(hops=3, hop_fraction=0.3))


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
