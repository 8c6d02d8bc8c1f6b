"""bench/search_schedules.py: the reference of a knot is the lowest ε the campaign stored for a
knot whose verdict was beaten (never a knot whose verdict held), a search lower than the
reference becomes the reference, and failed searches are counted, not averaged."""

import json

import pytest

from helpers import load_bench


def test_references_are_the_lowest_stored_state_of_the_beaten_verdicts(tmp_path):
    mod = load_bench("search_schedules")
    camp = {"searches": {
        "default": {"knots": {
            "9_38": {"epsilon": 279.69, "false_verdict": True, "audit_epsilon": 274.26},
            "3_1": {"epsilon": 79.06, "false_verdict": False, "audit_epsilon": 79.06}}},
        "30M": {"knots": {
            "9_38": {"epsilon": 274.09, "false_verdict": False, "audit_epsilon": 274.20},
            "10_58": {"epsilon": 365.18, "false_verdict": True, "audit_epsilon": 309.31}}}}}
    p = tmp_path / "c.json"
    p.write_text(json.dumps(camp))
    assert mod.references(p) == {"9_38": 274.09, "10_58": 309.31}


def test_summary_counts_hits_against_the_lowest_found_and_skips_failures():
    mod = load_bench("search_schedules")
    rows = [
        {"knot": "9_38", "variant": "base", "seed": 1, "epsilon": 284.0, "cpu_s": 15.0},
        {"knot": "9_38", "variant": "base", "seed": 2, "epsilon": 274.3, "cpu_s": 15.0},
        # lower than the reference: the new reference, a hit
        {"knot": "9_38", "variant": "coarse100", "seed": 1, "epsilon": 274.0, "cpu_s": 33.0},
        {"knot": "9_38", "variant": "coarse75", "seed": 1, "epsilon": None, "error": "x"},
    ]
    s = mod.summarise(rows, {"9_38": 274.09})
    assert s["reference"] == {"9_38": 274.0}
    base, coarse = s["variants"]["base"], s["variants"]["coarse100"]
    # 274.3 is 0.11 % above 274.0: not within the verdict's 0.1 %
    assert (base["runs"], base["hits"], base["failed"]) == (2, 0, 0)
    assert base["cpu_s_per_hit"] is None and base["cpu_s_per_search"] == 15.0
    assert (coarse["runs"], coarse["hits"], coarse["cpu_s_per_hit"]) == (1, 1, 33.0)
    assert s["variants"]["coarse75"]["runs"] == 0  # only a failure: shown, not averaged
    assert s["variants"]["coarse75"]["failed"] == 1
    assert base["median_gap"] == pytest.approx(((284.0 + 274.3) / 2) / 274.0 - 1.0)
