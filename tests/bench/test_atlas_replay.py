"""bench/atlas_replay.py: a database replayed under a lower cap holds exactly what a sweep with
that cap stores — the replay's premise (replicas are a prefix) — with the same verdicts."""

import pytest

from helpers import load_bench
from stiffknots.store.sqlite import Store
from stiffknots.sweeps import budget_of, parse_models, run_sweep
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA, SEEDED_REPLICA

pytestmark = pytest.mark.slow  # two sweeps on a local Dask cluster (≈ 30–60 s)


@pytest.fixture(scope="module")
def replay_mod():
    return load_bench("atlas_replay")


def _keys(path):
    with Store(path, create=False) as st:
        return sorted((r["knot"], r["exclusion"], r["replica"], round(r["epsilon"], 9))
                      for r in st.replicas())


def test_a_replay_at_a_lower_cap_is_the_sweep_with_that_cap(tmp_path, replay_mod):
    models = parse_models("bead,tube")
    budget = budget_of("tiny", moves=50_000)
    knots = ["4_1", "5_2"]
    big, small = tmp_path / "cap4.db", tmp_path / "cap2.db"
    with Store(big) as st:
        res = run_sweep(knots, models, budget, st, seed=7, workers=2, max_replicas=4)
        assert not res.failed
    with Store(small) as st:
        res = run_sweep(knots, models, budget, st, seed=7, workers=2, max_replicas=2)
        assert not res.failed
    fresh = _keys(big)
    assert max(r for _, ex, r, _ in fresh if r < OLDER_SEEDED_REPLICA) == 3  # the cap was used
    # the replay's database: the cap-4 one without the replicas numbered ≥ 2
    got = replay_mod.replay(str(big), bead_cap=2, tube_cap=2, legs=0)
    want = replay_mod.verdicts(str(small))
    for ex in ("bead", "tube"):
        assert got[ex]["replicas"] == want[ex]["replicas"]
        assert got[ex]["converged"] == want[ex]["converged"]
        assert got[ex]["not_converged"] == want[ex]["not_converged"]
        assert got[ex]["cpu_seconds"] <= replay_mod.verdicts(str(big))[ex]["cpu_seconds"]
    capped = [k for k in fresh if k[2] < 2 or 0 <= k[2] - SEEDED_REPLICA < 2]
    assert capped == _keys(small)
