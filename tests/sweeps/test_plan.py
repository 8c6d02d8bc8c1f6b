"""Tests of the sweep's plan (no cluster): budgets, models, knots, keys, what is pending, the
problem's jobs, the starts and the convergence rule."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine.driver import replica_seeds
from stiffknots.errors import InvalidParameter, UnknownKnotError, UserInputError
from stiffknots.store import ReplicaKey, Store, settings_hash
from stiffknots.sweeps import (
    BUDGETS,
    budget_of,
    is_converged,
    params_of,
    parse_models,
    pending,
    plan_sweep,
    resolve_knots,
    sweep_settings,
)
from stiffknots.sweeps.convergence import ensemble_converged, hits
from stiffknots.sweeps.plan import build_jobs, sweep_starts

D = 1 / math.sqrt(2)


def test_budgets_are_documented_and_overridable():
    assert set(BUDGETS) == {"tiny", "small", "default", "full"}
    assert (BUDGETS["small"].replicas, BUDGETS["small"].moves) == (2, 5_000_000)
    d, f = BUDGETS["default"], BUDGETS["full"]
    assert (d.replicas, d.moves, d.max_replicas) == (2, 15_000_000, 6)
    assert (f.replicas, f.moves, f.max_replicas) == (4, 60_000_000, 12)
    # the bead rule's replicas: Langevin dynamics for default and full (bench/RESULTS.md,
    # 2026-12-05), the annealing for the quick budgets
    assert (d.bead_search, d.bead_steps, d.bead_max_replicas) == ("langevin", 1_000_000, 16)
    assert (f.bead_search, f.bead_max_replicas) == ("langevin", 32)
    assert BUDGETS["tiny"].bead_search == BUDGETS["small"].bead_search == "annealing"
    assert BUDGETS["small"].as_dict()["max_replicas"] == 2  # none added
    b = budget_of("small", replicas=3)
    assert (b.name, b.replicas, b.moves) == ("custom", 3, 5_000_000)
    assert budget_of("default") is BUDGETS["default"]
    with pytest.raises(InvalidParameter, match="budget must be one of tiny, small"):
        budget_of("huge")
    with pytest.raises(InvalidParameter, match="replicas"):
        budget_of("tiny", replicas=0)
    with pytest.raises(InvalidParameter, match="moves"):
        budget_of("tiny", moves=10)


def test_models_bead_rule_and_tube_width():
    bead, tube = parse_models("bead, tube")
    assert (bead.exclusion, tube.exclusion) == ("bead", "tube")
    assert bead.thickness == pytest.approx(D) and tube.thickness == pytest.approx(D)
    assert bead.beads == tube.beads == 150
    assert params_of(bead).d == pytest.approx(D) and params_of(bead).exclusion == "bead"
    assert params_of(tube).w == pytest.approx(D) and params_of(tube).exclusion == "tube"
    assert "d = 1/√2, N = 150" in bead.text
    assert bead.as_dict()["w_over_L"] == pytest.approx(D / 150)
    (t,) = parse_models("tube", w=0.5)
    assert t.thickness == 0.5 and params_of(t).w == 0.5 and "w = 0.5" in t.text
    (b,) = parse_models("bead", w=0.5)  # w is the tube's: the bead rule keeps d = 1/√2
    assert b.thickness == pytest.approx(D)
    assert [m.exclusion for m in parse_models("tube,bead,tube")] == ["tube", "bead"]
    for bad in ("soft", "", "bead,soft"):
        with pytest.raises(InvalidParameter, match="models"):
            parse_models(bad)
    with pytest.raises(InvalidParameter):
        parse_models("tube", w=1.5)


def test_resolve_knots():
    assert resolve_knots(max_crossings=4) == ["3_1", "4_1"]
    assert len(resolve_knots(max_crossings=10)) == 249
    assert resolve_knots(["10_1", "4.1", "3_1", "T(2,3)"]) == ["3_1", "4_1", "10_1"]
    assert resolve_knots(["3_1", "5_2"], max_crossings=5) == ["3_1", "5_2"]
    with pytest.raises(UserInputError, match="more than max_crossings"):
        resolve_knots(["6_1"], max_crossings=5)
    with pytest.raises(UnknownKnotError):
        resolve_knots(["4_9"])
    with pytest.raises(UserInputError, match="unknot"):
        resolve_knots(["0_1"])
    with pytest.raises(InvalidParameter, match="max_crossings"):
        resolve_knots(max_crossings=2)
    with pytest.raises(InvalidParameter):
        resolve_knots()


def test_plan_keys_known_in_advance():
    models = parse_models("bead,tube")
    jobs = plan_sweep(["3_1", "4_1"], models, BUDGETS["small"], seed=7)
    assert len(jobs) == 2 * 2 * 2
    assert len({j.key for j in jobs}) == len(jobs)
    assert len({j.task_key for j in jobs}) == len(jobs)
    j = jobs[0]
    assert (j.knot, j.model.exclusion, j.replica, j.seed) == ("3_1", "bead", 0, 7)
    assert j.key == ReplicaKey("3_1", "bead", 150, D, 7, 0, settings_hash(j.settings))
    # the settings: every setting that changes the result (moves, exclusion and its width)
    s = sweep_settings(models[0], BUDGETS["small"])
    assert s["problem"] == "anneal" and s["start"] == "braid,cage,eighty;added:lowest"
    assert s["moves"] == 5_000_000 and s["params"]["exclusion"] == "bead"
    hashes = {m.exclusion: settings_hash(sweep_settings(m, BUDGETS["small"])) for m in models}
    assert hashes["bead"] != hashes["tube"]
    assert settings_hash(sweep_settings(models[0], BUDGETS["default"])) != hashes["bead"]
    (t5,) = parse_models("tube", w=0.5)
    assert settings_hash(sweep_settings(t5, BUDGETS["small"])) != hashes["tube"]
    # knot-major order: all replicas of a knot's models before the next knot
    assert [j.knot for j in jobs] == ["3_1"] * 4 + ["4_1"] * 4
    # more replicas of the same moves reuse the first ones (replica r's seed is fixed)
    more = plan_sweep(["3_1"], models[:1], budget_of("small", replicas=4), seed=7)
    assert {j.key for j in jobs if j.knot == "3_1" and j.model.exclusion == "bead"} < \
        {j.key for j in more}
    assert replica_seeds(7, 2) == replica_seeds(7, 4)[:2]


def test_pending_skips_stored_keys(tmp_path):
    (bead,) = parse_models("bead")
    jobs = plan_sweep(["3_1", "4_1"], [bead], BUDGETS["tiny"], seed=0)
    with Store(tmp_path / "s.db") as st:
        assert pending(jobs, st) == jobs
        for j in jobs[1:3]:
            st.put({"knot": j.knot, "exclusion": "bead", "beads": 150, "thickness": D,
                    "seed": 0, "replica": j.replica, "settings": j.settings, "epsilon": 80.0,
                    "min_segment_distance": 0.6, "wall_seconds": 1.0},
                   np.zeros((150, 3)))
        # another seed and another budget are other keys
        other = plan_sweep(["3_1"], [bead], BUDGETS["small"], seed=1)[0]
        st.put({"knot": "3_1", "exclusion": "bead", "beads": 150, "thickness": D, "seed": 1,
                "replica": 0, "settings": other.settings, "epsilon": 80.0,
                "min_segment_distance": 0.6, "wall_seconds": 1.0}, np.zeros((150, 3)))
        assert pending(jobs, st) == [jobs[0], jobs[3]]


def test_build_jobs_are_the_problems_with_the_keys_settings():
    (bead,) = parse_models("bead")
    b = BUDGETS["tiny"]
    jobs = plan_sweep(["4_1"], [bead], b, seed=3)
    built = build_jobs("4_1", bead, b, 3, jobs[0].settings)
    assert sorted(built) == [0, 1]
    seeds = replica_seeds(3, 2)
    for r, job in built.items():
        assert job.replica == r and job.seed == seeds[r] and job.knot == "4_1"
        assert job.settings.moves == b.moves and job.settings.params.exclusion == "bead"
        assert job.coords.shape == (150, 3) and job.start_code
    assert [built[r].start for r in (0, 1)] == ["braid", "cage"]
    with pytest.raises(RuntimeError, match="differ"):
        build_jobs("4_1", bead, b, 3, {**jobs[0].settings, "moves": 12345})
    # an added replica's favoured start: every replica of the call starts there, the seeds
    # stay the replicas' own
    fav = build_jobs("4_1", bead, replace(b, replicas=4), 3, jobs[0].settings, "cage")
    assert [fav[r].start for r in range(4)] == ["cage"] * 4
    assert fav[1].seed == built[1].seed and np.array_equal(fav[1].coords, built[1].coords)
    assert np.array_equal(fav[2].coords, built[1].coords)
    with pytest.raises(RuntimeError, match="no start 'cage'"):  # 3_1 is no two-box knot
        build_jobs("3_1", bead, b, 3, jobs[0].settings, "cage")


def test_added_replicas_take_the_start_of_the_lowest_stored_before_them(tmp_path):
    """favoured_start: replicas 0-2 keep their round-robin starts; from replica 3 on, the
    start of the lowest replica stored among those planned before it (deterministic: a
    replica stored later, even a lower one, does not change it)."""
    from stiffknots.sweeps.plan import FAVOUR_FROM, favoured_start

    (bead,) = parse_models("bead")
    b = replace(BUDGETS["default"], replicas=6)
    jobs = plan_sweep(["5_2"], [bead], b, seed=0)
    with Store(tmp_path / "s.db") as st:
        assert favoured_start(st, jobs[4], 4) is None  # nothing stored
        for r, (start, eps) in enumerate([("braid", 150.0), ("cage", 142.7), ("eighty", 145.0),
                                          ("braid", 142.0)]):
            st.put({"knot": "5_2", "exclusion": "bead", "beads": 150, "thickness": D,
                    "seed": 0, "replica": r, "settings": jobs[r].settings, "epsilon": eps,
                    "start": start, "min_segment_distance": 0.7, "wall_seconds": 1.0},
                   np.zeros((150, 3)))
        assert FAVOUR_FROM == 3 and favoured_start(st, jobs[2], 2) is None
        assert favoured_start(st, jobs[3], 2) == "cage"  # of replicas 0, 1
        assert favoured_start(st, jobs[4], 4) == "braid"  # replica 3 (142.0) is lowest
        assert favoured_start(st, jobs[5], 3) == "cage"  # replica 3 came later


def test_starts_per_family():
    from stiffknots.knots.catalogue import get_knot

    assert sweep_starts(get_knot("3_1"), 150, 3) == ["braid"] * 3  # n = i: no 80 start
    assert sweep_starts(get_knot("5_2"), 150, 4) == ["braid", "cage", "eighty", "braid"]
    assert sweep_starts(get_knot("8_19"), 150, 2) == ["braid", "braid"]


def test_convergence_rule():
    # the solver's rule: ≥ 2 replicas within 0.1 % of the lowest ε (polished replicas of one
    # minimum agree far better)
    assert is_converged({"count": 2, "epsilon": 100.0, "eps_max": 100.09})
    assert not is_converged({"count": 2, "epsilon": 100.0, "eps_max": 100.2})
    assert not is_converged({"count": 1, "epsilon": 100.0, "eps_max": 100.0})
    assert not is_converged(None) and not is_converged({})
    # a 1 % state of five replicas, four at one minimum and one 0.13 % above (5_1, bead rule,
    # in the atlas): converged — the whole group's spread is not the rule
    five = {"count": 5, "epsilon": 80.7215, "eps_max": 80.8238,
            "eps_all": [80.7215, 80.7215, 80.7215, 80.7215, 80.8238]}
    assert hits(five) == 4 and is_converged(five)
    # two replicas 0.12 % apart and a third 0.5 % above: one hit, not converged
    assert hits({"count": 3, "epsilon": 100.0, "eps_all": [100.0, 100.12, 100.5]}) == 1
    assert not is_converged({"count": 3, "epsilon": 100.0, "eps_all": [100.0, 100.12, 100.5]})
    with pytest.raises(ValueError, match="eps_all or eps_max"):
        is_converged({"count": 3, "epsilon": 100.0})  # the spread unknown: no verdict


def test_seeded_replicas_confirm_a_ground_state_but_do_not_certify_it(tmp_path):
    """Two bead replicas seeded from tube replicas agreeing on the lowest state do not make
    it converged (they share the tube's funnel: 10_5, 7_5, 6_3 in bench/RESULTS.md); one
    seeded replica and one of the ensemble's own searches do. Through the store's states."""
    from stiffknots.sweeps.convergence import SEEDED_START, own_hits
    from stiffknots.sweeps.cross import SEEDED_START as CROSS_START

    assert SEEDED_START == CROSS_START == "tube-ground"
    seeded = {"epsilon": 100.0, "eps_all": [100.0, 100.05],
              "eps_by_start": {SEEDED_START: [100.0, 100.05]}}
    assert hits(seeded) == 2 and own_hits(seeded) == 0 and not is_converged(seeded)
    mixed = {"epsilon": 100.0, "eps_all": [100.0, 100.05, 100.5],
             "eps_by_start": {SEEDED_START: [100.0], "braid": [100.05, 100.5]}}
    assert hits(mixed) == 2 and own_hits(mixed) == 1 and is_converged(mixed)
    far = {"epsilon": 100.0, "eps_all": [100.0, 100.05, 100.5],
           "eps_by_start": {SEEDED_START: [100.0, 100.05], "braid": [100.5]}}
    assert own_hits(far) == 0 and not is_converged(far)  # the own search 0.5 % above
    x = np.load(Path(__file__).resolve().parent.parent / "data" / "analysis"
                / "3_1_seed1_r0.npy")
    with Store(tmp_path / "s.db") as st:
        for replica, start, eps in ((0, "braid", 79.30), (2_000_000, SEEDED_START, 79.0),
                                    (2_000_001, SEEDED_START, 79.01)):
            st.put({"knot": "3_1", "exclusion": "bead", "beads": 150, "thickness": 0.7,
                    "seed": 0, "replica": replica, "settings": {"problem": "anneal", "s": 1},
                    "problem": "anneal",
                    "epsilon": eps, "shape": "CB", "multiplicity": 2, "start": start,
                    "knot_verified": True, "min_segment_distance": 0.7,
                    "wall_seconds": 1.0}, x)
        ground = st.states("3_1")["ground"]
        assert ground["eps_by_start"] == {SEEDED_START: [79.0, 79.01], "braid": [79.30]}
        assert hits(ground) == 2 and not is_converged(ground)
        (row,) = st.ground_states()
        assert row["eps_by_start"] == ground["eps_by_start"] and not is_converged(row)
        st.put({"knot": "3_1", "exclusion": "bead", "beads": 150, "thickness": 0.7,
                "seed": 0, "replica": 1, "settings": {"problem": "anneal", "s": 1},
                "problem": "anneal",
                "epsilon": 79.02, "shape": "CB", "multiplicity": 2, "start": "braid",
                "knot_verified": True, "min_segment_distance": 0.7, "wall_seconds": 1.0}, x)
        assert is_converged(st.states("3_1")["ground"])


def test_the_tube_rule_asks_for_three_searches_and_the_sweep_adds_what_it_lacks(tmp_path):
    """The tube's verdict needs three searches at the ground (8_13's 278.5 funnel drew two of
    two, docs/methods/verdicts.md), the bead rule's two; an unconverged tube ensemble gets as
    many replicas as its ground lacks where two agree — one —, else ``step``."""
    from stiffknots.sweeps.convergence import min_searches
    from stiffknots.sweeps.run import _stored_states, searches_lacking

    assert (min_searches("tube"), min_searches("bead"), min_searches(None)) == (3, 2, 2)
    two = {"epsilon": 278.42, "eps_all": [278.42, 278.54]}
    assert is_converged(two, "bead") and not is_converged(two, "tube")
    assert is_converged({**two, "exclusion": "bead"})  # a ground_states row names its model
    assert not is_converged({**two, "exclusion": "tube"})
    assert is_converged({"epsilon": 216.33, "eps_all": [216.33, 216.36, 216.41]}, "tube")
    x = np.load(Path(__file__).resolve().parent.parent / "data" / "analysis"
                / "3_1_seed1_r0.npy")
    tube = parse_models("tube")[0]
    settings = sweep_settings(tube, budget_of("tiny"))
    h = settings_hash(settings)
    with Store(tmp_path / "s.db") as st:

        def lacking(step):
            return searches_lacking(_stored_states(st, "3_1", tube, h), tube, step)

        assert lacking(2) == 2  # nothing stored

        def put(replica, eps):
            st.put({"knot": "3_1", "exclusion": "tube", "beads": 150,
                    "thickness": tube.thickness, "seed": 0, "replica": replica,
                    "settings": settings, "epsilon": eps, "shape": "CB", "multiplicity": 2,
                    "start": "braid", "knot_verified": True, "min_segment_distance": 0.8,
                    "wall_seconds": 1.0}, x)

        put(0, 79.06)
        put(1, 79.50)
        assert lacking(2) == 2  # one search at the ground: step
        put(2, 79.07)
        assert lacking(2) == 1  # two agree: one more
        assert lacking(1) == 1
        states = st.states("3_1")
        assert not ensemble_converged(states)
        put(3, 79.061)
        assert ensemble_converged(st.states("3_1"))


def test_model_validation():
    with pytest.raises(InvalidParameter):
        parse_models("soft")
    with pytest.raises(InvalidParameter):
        parse_models("bead", beads=4)
    with pytest.raises(InvalidParameter):
        parse_models("tube", w=1.0)


def test_unreachable_scheduler_is_a_user_error():
    from stiffknots.sweeps.cluster import connect, scheduler_address

    with pytest.raises(UserInputError, match="no Dask scheduler answers"):
        with connect("tcp://127.0.0.1:9", timeout=2):
            pass
    assert scheduler_address(" tcp://10.0.0.1:8786 ") == "tcp://10.0.0.1:8786"
    assert scheduler_address("localhost:8786") == "localhost:8786"
    for bad in ("", "not an address", "http//x"):
        with pytest.raises(UserInputError, match="--scheduler"):
            scheduler_address(bad)


def test_a_langevin_bead_search_is_its_own_ensemble_and_leaves_the_tube_alone():
    """bead_search = "langevin": the bead model's replicas are Langevin dynamics of
    ``bead_steps`` steps (another settings hash: another ensemble), up to
    ``bead_max_replicas``; the tube model's settings, hash and replica limit do not move."""
    from stiffknots.sweeps.cluster import run_task

    bead, tube = parse_models("bead,tube")
    base = budget_of("default", bead_search="annealing")
    lan = budget_of("default", bead_search="langevin")
    assert lan is BUDGETS["default"] or lan == BUDGETS["default"]
    assert (base.name, base.bead_search) == ("default", "annealing")
    assert settings_hash(sweep_settings(tube, lan)) == settings_hash(sweep_settings(tube, base))
    s = sweep_settings(bead, lan)
    assert settings_hash(s) != settings_hash(sweep_settings(bead, base))
    assert s["schedule"]["kind"] == "langevin" and s["moves"] == lan.bead_steps
    assert lan.as_dict()["bead_search"] == "langevin"
    assert base.as_dict()["bead_search"] == "annealing" and "bead_steps" not in base.as_dict()
    more = replace(lan, bead_max_replicas=10)
    assert (more.most_replicas(bead), more.most_replicas(tube)) == (10, base.max_replicas)
    assert base.most_replicas(bead) == base.max_replicas
    # a custom budget keeps the search; an unknown search is refused
    assert budget_of("small", replicas=3, bead_search="langevin").bead_search == "langevin"
    with pytest.raises(InvalidParameter, match="bead_search must be annealing or langevin"):
        budget_of("tiny", bead_search="dynamics")
    # deeper dynamics: another bead ensemble, the caps and the tube untouched; refused where
    # the bead search counts Monte Carlo moves
    deep = budget_of("default", bead_steps=3_000_000)
    assert (deep.name, deep.bead_steps, deep.most_replicas(bead)) == ("default", 3_000_000, 16)
    assert sweep_settings(bead, deep)["moves"] == 3_000_000
    assert settings_hash(sweep_settings(bead, deep)) != settings_hash(s)
    assert settings_hash(sweep_settings(tube, deep)) == settings_hash(sweep_settings(tube, lan))
    assert budget_of("default", replicas=4, bead_steps=2_000).bead_steps == 2_000
    with pytest.raises(InvalidParameter, match="bead_steps must be given with a Langevin bead "
                                               "search only .*not with annealing"):
        budget_of("tiny", bead_steps=2_000_000)
    with pytest.raises(InvalidParameter, match=r"bead_steps must be an integer in \[1,000"):
        budget_of("default", bead_steps=10)
    # the job a worker runs is the dynamics (short here), verified, with the key's settings
    tiny = replace(budget_of("tiny", bead_search="langevin"), bead_steps=20_000)
    (job, _) = plan_sweep(["3_1"], [bead], tiny, seed=1)
    r = run_task(job, tiny)
    assert r.knot_verified and r.langevin is not None
    assert job.settings["schedule"]["kind"] == "langevin" and job.settings["moves"] == 20_000
    x = np.asarray(r.coords)
    assert np.allclose(np.linalg.norm(np.roll(x, -1, 0) - x, axis=1), 1.0, atol=1e-6)


def test_resolve_knots_by_crossing_number_and_sample():
    n11 = resolve_knots(crossings=[11])
    assert len(n11) == 552 and all(n.startswith("11") for n in n11)
    assert len(resolve_knots(crossings=[11, 12])) == 552 + 2176
    assert resolve_knots(["3_1", "11a_1", "12n_1"], crossings=[11, 12]) == ["11a_1", "12n_1"]
    assert resolve_knots(max_crossings=10, crossings=[3, 4]) == ["3_1", "4_1"]
    s = resolve_knots(crossings=[11, 12], sample=100, seed=3)
    assert len(s) == 100 == len(set(s))
    assert s == resolve_knots(crossings=[11, 12], sample=100, seed=3)  # resumable
    assert s != resolve_knots(crossings=[11, 12], sample=100, seed=4)
    assert set(s) <= set(resolve_knots(crossings=[11, 12]))
    assert resolve_knots(["3_1", "4_1"], sample=5) == ["3_1", "4_1"]  # fewer: all of them
    for bad in ({"crossings": [2]}, {"crossings": [14]}, {"crossings": []},
                {"max_crossings": 10, "crossings": [11]},
                {"crossings": [11], "sample": 0}):
        with pytest.raises(UserInputError):
            resolve_knots(**bad)


def test_a_coarse_stage_is_the_tube_models_own_ensemble_and_runs_in_the_worker():
    """budget.coarse = N0: the tube replicas' settings gain ``coarse`` (another ensemble);
    the bead model's and every budget without it keep their settings and hashes (the stored
    replicas of earlier sweeps keep their keys). The job a worker runs anneals its start at
    N0 first (problems.coarse), stores what the stage did, and is verified as any replica."""
    from stiffknots.sweeps.cluster import run_task

    bead, tube = parse_models("bead,tube")
    base = budget_of("tiny")
    co = budget_of("tiny", coarse=75)
    assert (co.name, co.coarse, co.as_dict()["coarse"]) == ("tiny", 75, 75)
    assert "coarse" not in base.as_dict() and "coarse" not in sweep_settings(tube, base)
    assert sweep_settings(tube, co)["coarse"] == 75
    assert settings_hash(sweep_settings(tube, co)) != settings_hash(sweep_settings(tube, base))
    assert settings_hash(sweep_settings(bead, co)) == settings_hash(sweep_settings(bead, base))
    assert budget_of("default", replicas=3, coarse=100).coarse == 100  # a custom budget too
    with pytest.raises(InvalidParameter, match="coarse must be an integer"):
        budget_of("tiny", coarse=2)
    # seed 0: its 100,000-move coarse chain resamples (seed 1's is refused by the
    # resampling's certificate, and the replica then searches from its start, saying why)
    (job,) = plan_sweep(["3_1"], [tube], replace(co, replicas=1), seed=0)
    r = run_task(job, replace(co, replicas=1))
    assert r.knot_verified
    c = r.observables["coarse"]
    assert c["used"] and c["beads"] == 75 and c["moves"] == 100_000
    assert r.cpu_time >= c["cpu_seconds"] > 0  # the stage is part of the replica's cost
