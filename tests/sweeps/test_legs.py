"""Continuation legs of a sweep (stiffknots.sweeps.legs): which search a leg continues, a leg
and its search counted once by the verdict, the seeds of far-numbered replicas, and a real
sweep whose unconverged tube ensemble gets a leg (stored once, its search recorded, resumed
without a rerun)."""

from __future__ import annotations

import numpy as np
import pytest

from stiffknots.engine.driver import replica_seeds
from stiffknots.store import Store, search_of
from stiffknots.sweeps.convergence import hits, is_converged
from stiffknots.sweeps.legs import (
    LEG_EXCLUSIONS,
    LEG_REPLICA,
    langevin_leg_parent,
    leg_parent,
    searches,
)


def _row(replica, eps, search=None, start="braid"):
    extra = {} if search is None else {"search": search, "leg_of": search}
    return {"id": replica + 1, "replica": replica, "epsilon": eps, "start": start,
            "extra": extra}


def test_a_leg_belongs_to_the_search_it_continued():
    assert search_of(_row(3, 1.0)) == 3
    assert search_of(_row(LEG_REPLICA, 1.0, search=3)) == 3
    assert search_of({"replica": 5, "extra": None}) == 5


def test_the_leg_continues_the_second_lowest_search():
    rows = [_row(0, 101.0), _row(1, 100.0), _row(2, 100.5), _row(3, 103.0)]
    assert leg_parent(rows)["replica"] == 2  # the second-lowest of four searches
    # a leg of search 2 that went below it: search 2's lowest row is now the leg, and it is
    # the lowest search; the next leg continues search 1 (now second), from its lowest row
    rows.append(_row(LEG_REPLICA, 99.0, search=2))
    assert [r["replica"] for r in searches(rows)] == [LEG_REPLICA, 1, 0, 3]
    assert leg_parent(rows)["replica"] == 1
    # a leg of search 1 that stayed above its parent: search 1 is still represented by
    # replica 1, and a third leg would continue it again (the second-lowest search)
    rows.append(_row(LEG_REPLICA + 1, 100.2, search=1))
    assert leg_parent(rows)["replica"] == 1
    assert leg_parent([_row(0, 5.0)])["replica"] == 0  # one search: continue it
    assert leg_parent([]) is None


def test_langevin_leg_k_continues_the_k_th_lowest_own_search():
    """A Langevin bead leg k continues the (k+1)-th lowest search of the ensemble's own (a
    search seeded from a tube replica cannot certify, so it is not continued), counted round
    again past the last; a leg that went lower moves its search up the ranking."""
    rows = [_row(0, 101.0), _row(1, 100.0), _row(2, 100.5), _row(2_000_000, 99.0,
                                                                    start="tube-ground")]
    assert [langevin_leg_parent(rows, k)["replica"] for k in range(4)] == [1, 2, 0, 1]
    rows.append(_row(LEG_REPLICA, 99.5, search=0))  # leg of search 0, now the lowest own
    assert [langevin_leg_parent(rows, k)["replica"] for k in range(3)] == [LEG_REPLICA, 1, 2]
    assert langevin_leg_parent([_row(2_000_000, 9.0, start="tube-ground")], 0) is None
    assert langevin_leg_parent([], 0) is None


def test_which_ensembles_get_which_legs():
    """The default budget: the tube model 2 basin-hop legs, the Langevin bead rule 4
    Langevin legs, the annealed bead rule none; a custom budget none."""
    from stiffknots.sweeps import budget_of, parse_models

    bead, tube = parse_models("bead,tube")
    d = budget_of("default")
    assert (d.legs_of(tube), d.legs_of(bead)) == (2, 4)
    assert budget_of("default", bead_search="annealing").legs_of(bead) == 0
    assert budget_of("default", moves=100_000).legs_of(bead) == 0
    assert d.as_dict()["bead_legs"] == 4


def test_a_langevin_leg_reheats_the_parent_chain():
    """ClosedAnneal.langevin_leg_jobs: one job per parent, from its chain, the Langevin
    schedule reheated to 2·10⁻³ (at N = 150) and cooled to the replica's t_end over 0.3 × its
    steps; no such legs under an annealing schedule."""
    from types import SimpleNamespace

    from stiffknots.problems.closed import (
        LANGEVIN_LEG_FRACTION,
        LANGEVIN_LEG_T_START,
        ClosedAnneal,
        langevin_schedule,
    )

    p = ClosedAnneal("3_1", beads=60, replicas=1, schedule=langevin_schedule(60),
                     moves=20_000)
    chain = p.jobs()[0].coords
    jobs = p.langevin_leg_jobs([SimpleNamespace(coords=chain, start=p.starts[0])], 7)
    (j,) = jobs
    assert j.replica == 7 and np.array_equal(j.coords, chain)
    assert j.settings.schedule.kind == "langevin"
    assert j.settings.schedule.t_start == pytest.approx(LANGEVIN_LEG_T_START * (150 / 60) ** 2)
    assert j.settings.schedule.t_end == p.settings.schedule.t_end
    assert j.settings.moves == round(LANGEVIN_LEG_FRACTION * 20_000)
    q = ClosedAnneal("3_1", beads=60, replicas=1, moves=20_000)
    assert q.langevin_leg_jobs([SimpleNamespace(coords=chain, start=q.starts[0])], 7) is None


def test_the_verdict_counts_a_leg_and_its_search_once():
    """Two rows at the lowest state, one a leg of the other's search: one search, not
    converged; a leg of another search at the same state: two searches, converged."""
    from stiffknots.store.sqlite import _eps_by_search

    same = [_row(0, 100.0), _row(LEG_REPLICA, 100.01, search=0), _row(1, 104.0)]
    ground = {"epsilon": 100.0, "eps_all": [100.0, 100.01],
              "eps_by_search": _eps_by_search(same[:2])}
    assert ground["eps_by_search"] == {"0": 100.0}
    assert hits(ground) == 1 and not is_converged(ground)
    assert hits({k: v for k, v in ground.items() if k != "eps_by_search"}) == 2  # by replica
    other = [_row(0, 100.0), _row(LEG_REPLICA, 100.05, search=1)]
    ground = {"epsilon": 100.0, "eps_all": [100.0, 100.05],
              "eps_by_search": _eps_by_search(other)}
    assert hits(ground) == 2 and is_converged(ground)


def test_seeds_of_far_numbered_replicas_are_the_spawned_ones():
    """replica_seeds(seed, n, first): replica r's seed is the r-th child's of
    SeedSequence(seed).spawn, whatever ``first`` (a leg numbered 1,500,000 costs nothing)."""
    assert replica_seeds(7, 6, 3) == replica_seeds(7, 6)[3:]
    ss = np.random.SeedSequence(7).spawn(6)
    assert replica_seeds(7, 6) == [int(s.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
                                   for s in ss]
    far = replica_seeds(7, LEG_REPLICA + 2, LEG_REPLICA)
    assert len(far) == 2 and len(set(far)) == 2 and set(far).isdisjoint(replica_seeds(7, 6))


@pytest.mark.slow  # a Dask cluster and three tube replicas (≈ 30–60 s)
def test_an_unconverged_tube_ensemble_gets_a_leg_stored_once(tmp_path, monkeypatch):
    """The verdict is forced to "not converged" (so that the test does not depend on whether
    two tiny replicas agree): after its two replicas the tube ensemble of 3_1 gets one leg,
    replica LEG_REPLICA, continuing the second-lowest replica's search from its chain; the
    leg is verified, no higher than its parent, and a second sweep runs nothing."""
    from dataclasses import replace

    import stiffknots.sweeps.run as run_mod
    from stiffknots.sweeps import budget_of, parse_models, run_sweep

    assert "tube" in LEG_EXCLUSIONS
    monkeypatch.setattr(run_mod, "ensemble_converged", lambda *a, **k: False)
    budget = replace(budget_of("tiny"), max_replicas=2, legs=1)
    models = parse_models("tube")
    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["3_1"], models, budget, st, seed=3, workers=1)
        assert not res.failed, res.failed
        rows = {r["replica"]: r for r in st.replicas()}
        assert sorted(rows) == [0, 1, LEG_REPLICA]
        leg, fresh = rows[LEG_REPLICA], [rows[0], rows[1]]
        parent = max(fresh, key=lambda r: (r["epsilon"], r["replica"]))  # second of two
        assert leg["extra"]["search"] == parent["replica"] == leg["extra"]["leg_of"]
        assert leg["extra"]["leg_parent_epsilon"] == pytest.approx(parent["epsilon"])
        assert leg["start"] == parent["start"] and leg["knot_verified"] is True
        assert leg["epsilon"] <= parent["epsilon"] * (1 + 1e-9)
        assert leg["settings_hash"] == parent["settings_hash"]  # the same ensemble
        assert res.added == 1 and res.legs == 1 and res.ran == 3
        assert res.to_dict()["legs"] == 1
        n = st.count()
        res2 = run_sweep(["3_1"], models, budget, st, seed=3, workers=1)
        assert (res2.ran, st.count()) == (0, n) and not res2.failed


@pytest.mark.slow  # a Dask cluster, two bead replicas, a tube one and its seed (≈ 30–60 s)
def test_an_unconverged_langevin_bead_ensemble_gets_langevin_legs(tmp_path, monkeypatch):
    """The verdict forced to "not converged": after its two Langevin replicas the bead
    ensemble of 3_1 gets two Langevin legs, leg k continuing the (k+1)-th lowest own search
    (the seeded replica not), each verified, in the ensemble's settings hash; a second sweep
    runs nothing."""
    from dataclasses import replace

    import stiffknots.sweeps.run as run_mod
    from stiffknots.sweeps import budget_of, parse_models, run_sweep

    monkeypatch.setattr(run_mod, "ensemble_converged", lambda *a, **k: False)
    budget = replace(budget_of("tiny", moves=50_000, bead_search="langevin"), bead_steps=20_000,
                     bead_max_replicas=2, bead_legs=2)
    models = parse_models("bead,tube")
    with Store(tmp_path / "s.db") as st:
        res = run_sweep(["3_1"], models, budget, st, seed=5, workers=1)
        assert not res.failed, res.failed
        bead = {r["replica"]: r for r in st.replicas(exclusion="bead")}
        legs = [bead[LEG_REPLICA], bead[LEG_REPLICA + 1]]
        own = sorted((bead[0], bead[1]), key=lambda r: (r["epsilon"], r["replica"]))
        # leg 0 continued the lowest own search; leg 1 the second-lowest at its planning
        assert legs[0]["extra"]["leg_of"] == own[0]["replica"]
        ranked = searches([bead[0], bead[1], legs[0]])  # the own searches when leg 1 was planned
        assert legs[1]["extra"]["leg_of"] == ranked[1]["replica"]
        for leg in legs:
            assert leg["knot_verified"] is True and leg["start"] != "tube-ground"
            assert leg["settings_hash"] == own[0]["settings_hash"]
        assert not any(r["replica"] >= LEG_REPLICA for r in st.replicas(exclusion="tube"))
        assert res.legs == 2
        n = st.count()
        res2 = run_sweep(["3_1"], models, budget, st, seed=5, workers=1)
        assert (res2.ran, st.count()) == (0, n) and not res2.failed
    # bench/atlas_replay.py keeps the first b bead legs (--bead-legs): 2, 1, 0 of them
    from helpers import load_bench

    replay = load_bench("atlas_replay").replay
    kept = [replay(str(tmp_path / "s.db"), 16, None, 0, b)["bead"]["replicas"]
            for b in (None, 2, 1, 0)]
    assert kept == [len(bead), len(bead), len(bead) - 1, len(bead) - 2]
