"""bench/atlas_compare.py: two sweeps' bead ensembles compared cap by cap — the CPU and the
verdicts of each capped copy, and a verdict above the other sweep's lowest state flagged."""

import json
import sqlite3
from dataclasses import replace

import pytest

from helpers import load_bench
from stiffknots.store.sqlite import Store
from stiffknots.sweeps import budget_of, parse_models, run_sweep
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA

pytestmark = pytest.mark.slow  # two sweeps on a local Dask cluster (≈ 30 s)


def _bead_cpu(path, cap):
    with sqlite3.connect(path) as con:
        return con.execute("SELECT SUM(cpu_seconds) FROM replicas WHERE exclusion = 'bead' AND "
                           "(replica < ? OR replica >= ?)", (cap, OLDER_SEEDED_REPLICA)
                           ).fetchone()[0]


def test_two_sweeps_compared_cap_by_cap(tmp_path, capsys, monkeypatch):
    mod = load_bench("atlas_compare")
    models = parse_models("bead,tube")
    lan = replace(budget_of("tiny", moves=50_000, bead_search="langevin"), bead_steps=20_000,
                  replicas=4)
    a, b = tmp_path / "a.db", tmp_path / "b.db"
    with Store(a) as st:
        assert not run_sweep(["3_1"], models, lan, st, seed=0, workers=1).failed
    with Store(b) as st:
        assert not run_sweep(["3_1"], models, replace(lan, bead_steps=40_000), st, seed=0,
                             workers=1).failed
    out = tmp_path / "cmp.json"
    assert mod.main([str(a), str(b), "--bead-caps", "2,4", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["knots"] == ["3_1"]
    for row in d["caps"]:  # each capped copy's CPU: its own replicas below the cap + seeded
        for name, path in (("a", a), ("b", b)):
            assert row[name]["cpu_seconds"] == pytest.approx(_bead_cpu(path, row["cap"]),
                                                             abs=0.1)
            assert row[name]["converged"] + len(row[name]["not_converged"]) == 1
    assert d["caps"][0]["a"]["cpu_seconds"] < d["caps"][1]["a"]["cpu_seconds"]
    assert "bead cap  2" in capsys.readouterr().out
    # B's lowest state 1 % below every replica of A: a verdict of A is then wrong
    low_a = sqlite3.connect(a).execute("SELECT MIN(epsilon) FROM replicas WHERE "
                                       "exclusion = 'bead'").fetchone()[0]
    with sqlite3.connect(b) as con:
        con.execute("UPDATE replicas SET epsilon = ? WHERE id = (SELECT id FROM replicas WHERE "
                    "exclusion = 'bead' ORDER BY epsilon DESC LIMIT 1)", (low_a * 0.99,))
    # (the verdict itself forced: two tiny sweeps need not converge)
    monkeypatch.setattr(mod, "ensemble_converged", lambda g: True)
    d = mod.compare(str(a), str(b), [4])
    assert d["b_lower"] == ["3_1"] and d["b_higher"] == []
    assert d["caps"][0]["a"]["converged"] == 1 and d["caps"][0]["b"]["converged"] == 1
    assert d["caps"][0]["a"]["wrong"] == ["3_1"] and d["caps"][0]["b"]["wrong"] == []
