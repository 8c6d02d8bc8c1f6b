"""The start table (#39): every knot's starting chains built and their knot type verified —
on a fixed sample of 11- and 12-crossing knots, a planted wrong start, and the disk cache."""

import dataclasses
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from stiffknots.knots import start_table as st
from stiffknots.knots.catalogue import get_knot

#: fixed sample: alternating and non-alternating, 3 to 6 braid strands, a two-box 12-crossing
#: knot (KnotInfo writes its Conway notation '[10 2]') and the (2, 11) torus knot ('[11]')
SAMPLE = ("11a_1", "11a_367", "11n_34", "11n_184", "12a_803", "12a_1166", "12n_242",
          "12n_492")


@pytest.mark.parametrize("name", SAMPLE)
def test_braid_start_of_large_knots_is_verified(name):
    r = st.check_start(name, "braid")
    assert r.status == "verified", r
    assert r.found == name and r.crossings == int(name[:2])


@pytest.mark.parametrize("name,status", [("12a_803", "verified"), ("12a_1166", "verified"),
                                         ("11a_367", "absent"), ("12n_242", "absent")])
def test_cage_start_where_the_knot_has_two_boxes(name, status):
    r = st.check_start(name, "cage")
    assert r.status == status, r
    if status == "absent":
        assert "Conway notation" in r.reason and r.found is None


def test_a_start_of_another_knot_fails_with_the_reason():
    """A catalogue entry given the braid word of another knot: its chain is built, named as
    that knot, and the row says so — never counted as verified."""
    k = get_knot("11a_1")
    other = get_knot("11a_2")
    planted = dataclasses.replace(k, braid_word=other.braid_word)
    r = st.check_start(planted, "braid")
    assert r.status == "failed"
    assert r.found == "11a_2" and "not 11a_1" in r.reason


def test_unknown_family_is_refused():
    with pytest.raises(ValueError, match="braid, cage, eighty"):
        st.check_start("3_1", "tube")
    with pytest.raises(ValueError):
        st.start_table(knots=["3_1"], families=("braid", "ideal"))


def test_table_is_cached_and_summarised(tmp_path, monkeypatch):
    monkeypatch.setenv("STIFFKNOTS_CACHE", str(tmp_path))
    knots = ["12a_803", "11a_367", "5_2"]
    rows = st.start_table(knots=knots, families=("braid", "cage"))
    assert [(r.knot, r.family) for r in rows] == [(k, f) for k in knots
                                                  for f in ("braid", "cage")]
    assert any(tmp_path.glob("start-table-*.pkl"))
    calls = []
    real = st._chunk_rows
    monkeypatch.setattr(st, "_chunk_rows", lambda *a: calls.append(a) or real(*a))
    again = st.start_table(knots=knots, families=("braid", "cage"))
    assert again == rows and calls == []  # read from the cache, nothing rebuilt
    s = st.summarise(rows)
    assert s["knots"] == 3 and s["failed"] == [] and s["another_family"] == 2
    assert s["by_crossing"][11]["families"]["cage"] == {"verified": 0, "tie": 0, "absent": 1,
                                                        "failed": 0, "tube_ok": 0}
    assert s["by_crossing"][12]["families"]["cage"]["verified"] == 1
    # every verified chain here is admissible for the tube (segments ≥ 1/√2 apart)
    assert all(r.segment_distance >= 2 ** -0.5 for r in rows if r.status == "verified")
    assert s["not_tube"] == [] and s["by_crossing"][12]["families"]["braid"]["tube_ok"] == 1


def test_starts_command(tmp_path):
    env = {**os.environ, "STIFFKNOTS_CACHE": str(tmp_path)}
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "starts", "--max-crossings",
                        "5", "--families", "braid,cage", "--workers", "1", "--json"],
                       capture_output=True, text=True, timeout=600, env=env)
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["knots"] == 4 and d["failed"] == [] and d["n_beads"] == 150
    assert d["by_crossing"]["5"]["families"]["cage"]["verified"] == 1  # 5_2 = [32]
    for bad in (["--families", "braid,ideal"], ["--crossings", "14"],
                ["--max-crossings", "2"]):
        q = subprocess.run([sys.executable, "-m", "stiffknots.cli", "starts", *bad],
                           capture_output=True, text=True, timeout=600, env=env)
        assert q.returncode == 2 and q.stderr.strip().startswith("error:"), q.stderr


def test_a_braid_too_long_for_n_is_laid_out_by_a_cyclic_rotation():
    """12a_1202's word (18 letters on 7 strands) does not fit in 150 beads as given; a cyclic
    rotation of it — a conjugate braid, the same closure — does, and the chain is 12a_1202."""
    from stiffknots.knots.embedding import D_MIN, DEFAULT_GAP, _embed_checked, embed_braid

    k = get_knot("12a_1202")
    assert _embed_checked(list(k.braid_word), 7, 150, D_MIN, DEFAULT_GAP) is None
    x = embed_braid(k.braid_word, n_strands=7, n_beads=150)
    assert x.shape == (150, 3)
    r = st.check_start(k, "braid")
    assert r.status == "verified" and r.found == "12a_1202"


def test_braid_start_of_12a_32_is_admissible_for_the_tube():
    """12a_32's braid closure at the default strand spacing keeps beads 0.91 apart but
    segments only 0.695 where strands cross — the tube model refused it; a wider spacing
    keeps every segment pair ≥ 1/√2 apart, and the chain is 12a_32."""
    from stiffknots.knots.embedding import (
        D_MIN,
        DEFAULT_GAP,
        _embed_checked,
        embed_braid,
        embedding_report,
    )

    k = get_knot("12a_32")
    plain = _embed_checked(list(k.braid_word), k.braid_strands, 150, D_MIN, DEFAULT_GAP)
    assert embedding_report(plain).min_segment_distance < D_MIN
    x = embed_braid(k.braid_word, n_strands=k.braid_strands, n_beads=150)
    rep = embedding_report(x)
    assert rep.min_segment_distance >= D_MIN and rep.min_bead_distance >= D_MIN
    assert rep.max_bond_error < 1e-10
    assert st.check_start(k, "braid").status == "verified"


@pytest.mark.parametrize("name", ["3_1", "5_2", "8_19", "10_123"])
def test_braid_starts_through_10_crossings_keep_their_layout(name):
    """Through 10 crossings every braid start was admissible for the tube already: the same
    chain as the word laid out at the default spacing."""
    from stiffknots.knots.embedding import D_MIN, DEFAULT_GAP, _embed_checked, embed_braid

    k = get_knot(name)
    plain = _embed_checked(list(k.braid_word), k.braid_strands, 150, D_MIN, DEFAULT_GAP)
    assert np.array_equal(embed_braid(k.braid_word, n_strands=k.braid_strands, n_beads=150),
                          plain)
