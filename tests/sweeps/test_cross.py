"""Bead replicas seeded from the tube replicas (stiffknots.sweeps.cross)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine.kernel import energy_chain
from stiffknots.knots.identify import verify_knot
from stiffknots.measures import min_segment_distance
from stiffknots.store import Store, settings_hash
from stiffknots.sweeps import budget_of
from stiffknots.sweeps.cross import (
    OLDER_SEEDED_REPLICA,
    SEEDED_REPLICA,
    SEEDED_START,
    seed_from_tube,
    seed_pairs,
)
from stiffknots.sweeps.plan import sweep_settings
from stiffknots.width import Width

DATA = Path(__file__).resolve().parent.parent / "data"
D = 2 ** -0.5


def _row(knot, model, settings, replica, x, start="braid"):
    n = len(x)
    return {"knot": knot, "exclusion": model.exclusion, "beads": n,
            "thickness": model.thickness, "seed": 0, "replica": replica,
            "settings": settings, "problem": "anneal", "epsilon": n * energy_chain(x, False),
            "shape": "other", "start": start, "knot_verified": True,
            "min_segment_distance": float(min_segment_distance(x, True)), "wall_seconds": 1.0}


def _models():
    """The bead and tube models of a sweep at one width, and their replicas' settings."""
    bead, tube = Width.of("bead", D, 150), Width.of("tube", D, 150)
    return bead, tube, {m.exclusion: sweep_settings(m, budget_of("tiny")) for m in (bead, tube)}


def test_seed_pairs_need_the_same_beads_and_a_tube_at_least_as_wide():
    bead, tube = Width.of("bead", D, 150), Width.of("tube", D, 150)
    assert seed_pairs([bead, tube]) == [(bead, tube)]
    assert seed_pairs([bead, Width.of("tube", 0.5, 150)]) == []  # w < d: not bead-admissible
    assert seed_pairs([bead, Width.of("tube", D, 300)]) == []
    assert seed_pairs([bead]) == [] and seed_pairs([tube]) == []


def _check_bead_admissible_3_1(y):
    n = len(y)
    bonds = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    assert np.max(np.abs(bonds - 1)) < 1e-10
    dist = np.linalg.norm(y[:, None] - y[None], axis=2)
    idx = np.arange(n)
    sep = np.abs(idx[:, None] - idx[None])
    sep = np.minimum(sep, n - sep)
    assert dist[sep >= 2].min() >= D - 1e-10  # the bead rule
    assert verify_knot(y, "3_1")[0]


def test_every_tube_replica_seeds_a_bead_replica_polished_under_the_bead_rule(tmp_path):
    """A store with two tube replicas of 3_1 (tube-admissible chains, w = 1/√2), one of
    another sweep, and one bead replica: each of the sweep's tube replicas seeds a bead
    replica (SEEDED_REPLICA + its number) that ends bead-admissible with unit bonds, keeps the
    knot, lies at or below its tube ε, joins the bead ensemble (its settings hash) and is
    written once; the other sweep's tube replica seeds nothing."""
    bead, tube, settings = _models()
    x_tube = np.load(DATA / "polish" / "3_1_tube_singular_kkt.npy")
    x_bead = np.load(DATA / "analysis" / "3_1_seed1_r0.npy")
    rng = np.random.default_rng(3)
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    worse = x_tube[::-1] @ rot.T  # the same chain reversed and rotated
    with Store(tmp_path / "s.db") as st:
        st.put(_row("3_1", tube, settings["tube"], 0, x_tube), x_tube)
        st.put(_row("3_1", tube, settings["tube"], 1, worse), worse)
        other = _row("3_1", tube, settings["tube"], 0, worse)
        other["seed"] = 7  # another sweep's: unused
        st.put(other, worse)
        st.put(_row("3_1", bead, settings["bead"], 0, x_bead), x_bead)
        out = seed_from_tube(st, ["3_1"], [bead, tube], settings, seed=0, budget="tiny")
        assert [(e["tube_replica"], e["written"]) for e in out] == [(0, True), (1, True)], out
        assert out[0]["bead_epsilon"] == pytest.approx(150 * energy_chain(x_bead, False))
        rows = {r["replica"]: r for r in st.replicas(exclusion="bead")
                if r["start"] == SEEDED_START}
        assert sorted(rows) == [SEEDED_REPLICA, SEEDED_REPLICA + 1]
        for r, x in ((0, x_tube), (1, worse)):
            row = rows[SEEDED_REPLICA + r]
            assert row["knot_verified"] is True and row["seed"] == 0
            assert row["settings_hash"] == settings_hash(settings["bead"])
            assert row["extra"]["seeded_from"]["replica"] == r
            assert row["extra"]["seeded_from"]["seed"] == 0
            y = st.coords(row["id"])
            _check_bead_admissible_3_1(y)
            tube_eps = len(y) * energy_chain(x, False)
            assert row["epsilon"] == pytest.approx(len(y) * energy_chain(y, False), rel=1e-12)
            assert row["epsilon"] <= tube_eps + 1e-9
            assert row["extra"]["polish"]["epsilon_before"] == pytest.approx(tube_eps,
                                                                             rel=1e-9)
        ens = st.states("3_1", "bead", 150, D, settings_hash(settings["bead"]))
        assert ens["replicas"] == 3
        # written once: a second pass skips the stored keys
        assert seed_from_tube(st, ["3_1"], [bead, tube], settings, seed=0) == []
        assert st.count(exclusion="bead") == 3
        # a tube replica added later is seeded, the others not again
        st.put(_row("3_1", tube, settings["tube"], 2, x_tube), x_tube)
        out = seed_from_tube(st, ["3_1"], [bead, tube], settings, seed=0)
        assert [(e["tube_replica"], e["written"]) for e in out] == [(2, True)]


def test_a_tube_replica_seeded_under_the_older_rule_is_not_seeded_again(tmp_path):
    """Before every tube replica seeded one, only the lowest did, as replica SEEDED_REPLICA
    whatever its number: a tube replica named by a stored seeded row's ``seeded_from`` is
    skipped (no search counted twice), the others are seeded."""
    bead, tube, settings = _models()
    x_tube = np.load(DATA / "polish" / "3_1_tube_singular_kkt.npy")
    with Store(tmp_path / "s.db") as st:
        st.put(_row("3_1", tube, settings["tube"], 0, x_tube), x_tube)
        st.put(_row("3_1", tube, settings["tube"], 1, x_tube), x_tube)
        old = _row("3_1", bead, settings["bead"], OLDER_SEEDED_REPLICA, x_tube,
                   start=SEEDED_START)
        old["extra"] = {"seeded_from": {"replica": 1}}
        st.put(old, x_tube)
        out = seed_from_tube(st, ["3_1"], [bead, tube], settings, seed=0)
        assert [(e["tube_replica"], e["written"]) for e in out] == [(0, True)]
        assert st.count(exclusion="bead") == 2


def test_nothing_is_seeded_without_a_tube_ensemble(tmp_path):
    bead, tube, settings = _models()
    x_bead = np.load(DATA / "analysis" / "3_1_seed1_r0.npy")
    with Store(tmp_path / "s.db") as st:
        st.put(_row("3_1", bead, settings["bead"], 0, x_bead), x_bead)
        assert seed_from_tube(st, ["3_1"], [bead, tube], settings, seed=0) == []
        assert st.count() == 1
