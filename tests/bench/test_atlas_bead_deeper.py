"""bench/atlas_bead_deeper.py: deeper bead replicas pooled with an atlas's ensemble — every
row of both in the pooled copy, as further independent searches, and the verdicts counted."""

import json
import sqlite3
from dataclasses import replace

import pytest

from helpers import load_bench
from stiffknots.store.sqlite import Store
from stiffknots.sweeps import budget_of, parse_models, run_sweep
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA

pytestmark = pytest.mark.slow  # two sweeps on a local Dask cluster (≈ 30 s)


def test_deeper_replicas_join_the_atlas_ensemble_as_other_searches(tmp_path, capsys):
    mod = load_bench("atlas_bead_deeper")
    models = parse_models("bead,tube")
    lan = replace(budget_of("tiny", moves=50_000, bead_search="langevin"), bead_steps=20_000)
    atlas, deep = tmp_path / "atlas.db", tmp_path / "deep.db"
    with Store(atlas) as st:
        assert not run_sweep(["3_1"], models, lan, st, seed=0, workers=1).failed
    deeper = replace(lan, bead_steps=40_000, replicas=3)
    with Store(deep) as st:
        assert not run_sweep(["3_1"], models[:1], deeper, st, seed=1, workers=1).failed
    out = tmp_path / "deeper.json"
    assert mod.main([str(atlas), str(deep), "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["knots"] == ["3_1"] and d["deeper_steps"] == [40_000] and d["deeper_replicas"] == 3
    con = sqlite3.connect(atlas)
    own = con.execute("SELECT COUNT(*) FROM replicas WHERE exclusion = 'bead' AND replica < ?",
                      (OLDER_SEEDED_REPLICA,)).fetchone()[0]
    seeded = con.execute("SELECT COUNT(*) FROM replicas WHERE exclusion = 'bead' AND "
                         "replica >= ?", (OLDER_SEEDED_REPLICA,)).fetchone()[0]
    assert own == 2 and seeded == 2  # two own replicas, one seeded from each tube replica
    v = d["verdicts"]
    assert v["deeper alone"]["replicas"] == 3
    assert v["atlas alone"]["replicas"] == own + seeded
    # pooled: the atlas's seeded replicas, its own below the cap, the deeper ones — one
    # ensemble (knots 1), each row a search of its own
    assert v["atlas own < 0 + seeded + deeper"]["replicas"] == seeded + 3
    assert v["atlas own < 16 + seeded + deeper"]["replicas"] == own + seeded + 3
    assert all(x["knots"] == 1 for x in v.values())
    low = min(r[0] for r in sqlite3.connect(deep).execute("SELECT epsilon FROM replicas"))
    assert d["per_knot"][0]["deeper"] == pytest.approx(low, rel=1e-12)
    # the pooled copy's rows are the two databases' rows, the deeper ones shifted
    with_deep = mod.pooled_copy(str(atlas), str(deep), str(tmp_path), 16, ["3_1"])
    rows = sorted(r for r in sqlite3.connect(with_deep).execute(
        "SELECT replica, settings_hash FROM replicas WHERE exclusion = 'bead'"))
    assert [r for r, _ in rows if mod.SHIFT <= r < OLDER_SEEDED_REPLICA] == [100, 101, 102]
    assert len({h for _, h in rows}) == 1
    assert "3_1" in capsys.readouterr().out
