"""bench/audit_campaign.py: the campaign's fixed order is a permutation of the 249 knots
through 10 crossings (so its chunks, taken in turn, are a uniform random sample), and its
summary counts false verdicts over every chunk with the Wilson interval."""

import json

import pytest

from helpers import load_bench
from stiffknots.sweeps.audit import wilson_interval
from stiffknots.sweeps.plan import resolve_knots


def test_the_order_is_a_fixed_permutation_of_the_knots_through_10():
    mod = load_bench("audit_campaign")
    a, b = mod.order(0), mod.order(0)
    assert a == b
    assert sorted(a) == sorted(resolve_knots(max_crossings=10)) and len(a) == 249
    assert a != mod.order(1) and a != resolve_knots(max_crossings=10)


def test_the_summary_counts_only_audited_verdicts():
    mod = load_bench("audit_campaign")
    rows = {"3_1": {"knot": "3_1", "crossings": 3, "converged": True, "audited": True,
                    "false_verdict": False, "atlas_cpu_seconds": 10.0,
                    "agreeing_starts": ["braid", "cage"]},
            "7_7": {"knot": "7_7", "crossings": 7, "converged": True, "audited": True,
                    "false_verdict": True, "atlas_cpu_seconds": 30.0,
                    "agreeing_starts": ["braid"]},
            "8_13": {"knot": "8_13", "crossings": 8, "converged": False,
                     "atlas_cpu_seconds": 50.0}}
    s = mod.summary(rows)
    assert (s["knots"], s["converged"], s["audited"], s["false"]) == (3, 2, 2, 1)
    assert (s["low"], s["high"]) == wilson_interval(1, 2) and s["rate"] == 0.5
    assert s["false_entries"] == ["7_7"]
    assert s["by_start_families"] == {"one": {"audited": 1, "false": 1},
                                      "several": {"audited": 1, "false": 0}}
    assert s["atlas_cpu_seconds_per_knot"] == 30.0
    assert s["by_crossings"]["8"] == {"knots": 1, "converged": 0, "audited": 0, "false": 0,
                                      "atlas_cpu_seconds": 50.0}


def test_a_first_chunks_file_is_read_as_the_default_search(tmp_path):
    mod = load_bench("audit_campaign")
    old = {"order_seed": 0, "knots": {"7_4": {"knot": "7_4", "crossings": 7}},
           "chunks": [{"knots": ["7_4"]}], "summary": {}}
    p = tmp_path / "c.json"
    p.write_text(json.dumps(old))
    doc = mod._load(p, 0)
    assert doc["searches"] == {mod.DEFAULT: {"atlas_args": [], "knots": old["knots"]}}
    assert doc["chunks"] == [{"knots": ["7_4"], "search": mod.DEFAULT}]
    with pytest.raises(SystemExit, match="order of seed 0"):
        mod._load(p, 1)
