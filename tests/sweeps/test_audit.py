"""The audit of the verdicts (sweeps/audit): the draw, the judge, the Wilson interval, and a
real audit of a database where one verdict is planted above a state the searches reach at once
and another below every state of its knot."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from stiffknots.errors import UserInputError
from stiffknots.store import Store
from stiffknots.sweeps import budget_of, parse_models, sweep_settings
from stiffknots.sweeps.audit import (
    AUDIT_PROBLEM,
    audit_budget,
    audit_seed,
    judge,
    run_audit,
    sample_entries,
    summarise,
    wilson_interval,
)
from stiffknots.sweeps.convergence import min_searches
from stiffknots.width import Width

TUBE = parse_models("tube")[0]  # the default tube, w = 1/√2 as the atlas runs it


def _wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval written out (E. B. Wilson, JASA 22, 209 (1927))."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return centre - half, centre + half


@pytest.mark.parametrize(("k", "n"), [(0, 80), (1, 80), (5, 65), (20, 20), (3, 7)])
def test_wilson_interval_is_the_formula(k, n):
    lo, hi = wilson_interval(k, n)
    elo, ehi = _wilson(k, n)
    assert lo == pytest.approx(max(elo, 0.0), abs=1e-12)
    assert hi == pytest.approx(min(ehi, 1.0), abs=1e-12)
    assert lo <= k / n <= hi


def test_no_false_verdict_in_80_bounds_the_rate_below_5_percent():
    # the target: ≤ 2 % with the interval's upper end ≤ 5 % needs n ≥ 80 at k ≤ 1
    assert wilson_interval(0, 80)[1] < 0.05
    assert wilson_interval(1, 80)[1] < 0.07
    assert wilson_interval(0, 0) == (0.0, 1.0)


def test_judge_counts_only_a_state_lower_by_more_than_the_tolerance():
    entry = {"epsilon": 200.0}
    assert judge(entry, {"epsilon": 199.7}) is True          # 0.15 % lower
    assert judge(entry, {"epsilon": 199.9}) is False         # 0.05 %: the same state
    assert judge(entry, {"epsilon": 230.0}) is False         # higher: the verdict held
    assert judge(entry, None) is False                       # no search ended


def test_summary_per_model_and_crossing_number():
    rows = [{"exclusion": "tube", "crossings": c, "false_verdict": f, "searches": s}
            for c, f, s in [(3, 0, 3), (7, 1, 3), (7, 0, 3), (8, 1, 3), (8, 0, 0)]]
    s = summarise(rows)
    assert s["all"]["n"] == 4 and s["all"]["false"] == 2 and s["unsearched"] == 1
    assert s["by_crossings"]["tube/7"] == {"n": 2, "false": 1, "rate": 0.5,
                                           "low": wilson_interval(1, 2)[0],
                                           "high": wilson_interval(1, 2)[1]}
    assert list(s["by_crossings"]) == ["tube/3", "tube/7", "tube/8"]


def test_audit_budget_scales_the_moves_of_the_audited_ensemble():
    tube = sweep_settings(TUBE, budget_of("default"))
    b = audit_budget(tube, 2, 3)
    assert (b.replicas, b.moves, b.bead_search) == (3, 30_000_000, "annealing")
    bead = sweep_settings(Width.bead(150), budget_of("default"))  # Langevin, 10⁶ steps
    b = audit_budget(bead, 3, 2)
    assert (b.bead_search, b.bead_steps) == ("langevin", 3_000_000)
    with pytest.raises(ValueError, match="depth"):
        audit_budget(tube, 0, 3)


def test_the_audit_seed_is_not_the_sweep_seed():
    assert audit_seed(0) != 0 and audit_seed(0) == audit_seed(0) != audit_seed(1)
    assert 0 <= audit_seed(123) < 2 ** 63


def _plant(store: Store, knot: str, epsilon: float, moves: int = 1000, rows: int = 4,
           converged: bool = True) -> None:
    """A sweep-like tube ensemble of ``knot`` whose ground is ``epsilon`` (reached by the
    searches the tube's verdict needs, one from every default start: a converged verdict) —
    the chains are random (the audit reads only ε)."""
    settings = sweep_settings(TUBE, budget_of("tiny", moves=moves))
    starts = ["braid", "cage", "eighty"]
    need = min_searches("tube")
    for r in range(rows):
        eps = epsilon if (r < need and converged) or r == 0 else epsilon * 1.1
        store.put({"knot": knot, "exclusion": "tube", "beads": 150, "thickness": TUBE.thickness,
                   "seed": 0, "replica": r, "settings": settings, "epsilon": eps,
                   "min_segment_distance": 0.8, "wall_seconds": 1.0, "shape": "other",
                   "start": starts[r % 3], "knot_verified": True},
                  np.random.default_rng(r).normal(size=(150, 3)))


def test_the_draw_is_seeded_and_takes_converged_verdicts_only(tmp_path):
    with Store(tmp_path / "a.db") as st:
        for k, eps in [("3_1", 90.0), ("4_1", 130.0), ("5_1", 150.0), ("5_2", 160.0)]:
            _plant(st, k, eps)
        _plant(st, "6_1", 170.0, converged=False)  # one search at the ground: not drawn
        a, n = sample_entries(st, sample=2, seed=4)
        b, _ = sample_entries(st, sample=2, seed=4)
        assert n == 4 and [r["knot"] for r in a] == [r["knot"] for r in b]
        every, _ = sample_entries(st, sample=10, seed=1)
        assert {r["knot"] for r in every} == {"3_1", "4_1", "5_1", "5_2"}
        assert sample_entries(st, sample=10, seed=1, models=("bead",))[0] == []
        assert {r["knot"] for r in sample_entries(st, sample=10, max_crossings=4)[0]} \
            == {"3_1", "4_1"}


def test_the_draw_may_be_limited_to_named_knots(tmp_path):
    with Store(tmp_path / "a.db") as st:
        for k, eps in [("3_1", 90.0), ("4_1", 130.0), ("5_1", 150.0)]:
            _plant(st, k, eps)
        _plant(st, "6_1", 170.0, converged=False)
        named, n = sample_entries(st, sample=10, knots=["4.1", "5_1", "6_1"])
        assert n == 2 and [r["knot"] for r in named] == ["4_1", "5_1"]  # 6_1: not converged
        with pytest.raises(UserInputError, match="7_99"):
            sample_entries(st, knots=["7_99"])
        plain = run_audit(st, sample=10, run=False)
        only = run_audit(st, sample=10, knots=["5_1", "3_1"], run=False)
        assert "knots" not in plain.params and only.params["knots"] == ["3_1", "5_1"]
        assert only.audit != plain.audit and [r["knot"] for r in only.rows] == ["3_1", "5_1"]


def test_audit_knots_on_the_command_line(tmp_path):
    db = tmp_path / "a.db"
    with Store(db) as st:
        _plant(st, "3_1", 90.0)
        _plant(st, "6_1", 170.0, converged=False)
    cmd = [sys.executable, "-m", "stiffknots.cli", "audit", "--db", str(db)]
    p = subprocess.run([*cmd, "--knots", "6_1"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "nothing to audit: no converged tube verdict of 6_1" in p.stdout
    bad = subprocess.run([*cmd, "--knots", "3_1,7_99"], capture_output=True, text=True,
                         timeout=120)
    assert bad.returncode == 2 and "7_99" in bad.stderr


@pytest.mark.slow  # a Dask cluster and four short searches (≈ 30 s)
def test_an_audit_finds_the_planted_false_verdict_and_stores_it(tmp_path):
    db = tmp_path / "atlas.db"
    with Store(db) as st:
        _plant(st, "3_1", 500.0)  # far above every polished 3_1 chain: false
        _plant(st, "4_1", 60.0)   # below 4_1's every state (its bound is 2π²·4 ≈ 79): held
    cmd = [sys.executable, "-m", "stiffknots.cli", "audit", "--db", str(db), "--sample", "5",
           "--replicas", "2", "--depth", "2", "--workers", "1"]
    p = subprocess.run([*cmd, "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    by = {r["knot"]: r for r in d["entries"]}
    assert by["3_1"]["false_verdict"] == 1 and by["3_1"]["audit_epsilon"] < 500 * 0.999
    assert by["4_1"]["false_verdict"] == 0 and by["4_1"]["audit_epsilon"] > 60
    assert by["3_1"]["searches"] == by["4_1"]["searches"] == 2
    s = d["summary"]["all"]
    assert (s["n"], s["false"]) == (2, 1)
    assert (s["low"], s["high"]) == pytest.approx(wilson_interval(1, 2))
    with Store(db, readonly=True) as st:
        stored = st.audits()
        assert {r["knot"]: r["false_verdict"] for r in stored} == {"3_1": 1, "4_1": 0}
        # the audit's searches are another ensemble: the verdicts' ensembles are untouched
        audit_rows = st.replicas(problem=AUDIT_PROBLEM)
        assert len(audit_rows) == 4 and all(r["knot_verified"] for r in audit_rows)
        assert {r["seed"] for r in audit_rows} == {audit_seed(0)}
        assert len(st.replicas(problem="anneal")) == 8
    # db grounds shows the verdicts with the audit beside them
    g = subprocess.run([sys.executable, "-m", "stiffknots.cli", "db", "--db", str(db), "grounds",
                        "--json"], capture_output=True, text=True, timeout=120)
    assert g.returncode == 0, g.stderr
    rows = {r["knot"]: r for r in json.loads(g.stdout)["grounds"]}
    assert rows["3_1"]["epsilon"] == 500.0 and rows["3_1"]["audit"]["false_verdict"] is True
    assert rows["4_1"]["audit"]["false_verdict"] is False
    # the same audit again: its searches are stored, none runs again; the rows are replaced
    p2 = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert p2.returncode == 0, p2.stderr
    assert "tube: 1 of 2 false (50.0 %" in p2.stdout
    with Store(db, readonly=True) as st:
        assert len(st.replicas(problem=AUDIT_PROBLEM)) == 4 and len(st.audits()) == 2
