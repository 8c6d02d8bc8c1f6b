"""``stiffknots census`` and ``stiffknots db census``: a census taken, stored and read back;
bad options and missing databases (exit 2, one line)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from helpers import DATA
from stiffknots.store import Store

W = 1 / math.sqrt(2)


def cli(*args, timeout=300):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args], capture_output=True,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


@pytest.fixture
def db(tmp_path):
    """4_1 in the tube model: 3 searches in the `other`, 2 in the cage (one also far above the
    window); 5_2: a cage and an 80."""
    path = tmp_path / "s.db"
    other, cage = (np.load(DATA / "analysis" / f"4_1_tube_{n}.npy") for n in ("other", "cage"))
    rows = [("4_1", 0, 128.5650, "other", other), ("4_1", 1, 129.3124, "4C", cage),
            ("4_1", 2, 128.5649, "other", np.roll(other, 11, axis=0)),
            ("4_1", 3, 129.3125, "4C", cage[::-1]), ("4_1", 4, 128.5660, "other", -other),
            ("4_1", 5, 160.0, "4C", cage),
            ("5_2", 0, 145.4663, "4C", np.load(DATA / "analysis" / "5_2_tube_cage.npy")),
            ("5_2", 1, 149.2074, "80", np.load(DATA / "analysis" / "5_2_tube_80.npy"))]
    with Store(path) as st:
        for knot, r, eps, shape, x in rows:
            st.put({"knot": knot, "exclusion": "tube", "beads": 150, "thickness": W,
                    "seed": 0, "replica": r, "settings": {"problem": "anneal"},
                    "epsilon": eps, "min_segment_distance": W, "wall_seconds": 1.0,
                    "shape": shape, "start": "braid"}, x)
    return path


def test_census_is_taken_stored_and_read_back(db):
    rc, out, err = cli("census", "--db", str(db), "--json")
    assert rc == 0, err
    d = json.loads(out)
    by_knot = {c["knot"]: c for c in d["census"]}
    c41 = by_knot["4_1"]
    assert [(s["name"], s["count"], s["searches"]) for s in c41["states"]] == [
        ("other", 3, 3), ("4C", 2, 2)]
    assert c41["replicas"] == 6 and c41["counted"] == 5 and c41["w_over_L"] == pytest.approx(
        W / 150)
    assert [s["name"] for s in by_knot["5_2"]["states"]] == ["4C", "80"]
    rc, out, err = cli("db", "--db", str(db), "census", "4.1")
    assert rc == 0, err
    assert "other" in out and "4C" in out and "0.58 %" in out and "w/L = 0.0047" in out
    rc, out, _ = cli("db", "--db", str(db), "census", "4_1", "--json")
    got = json.loads(out)["census"]
    assert len(got) == 1 and [s["searches"] for s in got[0]["states"]] == [3, 2]
    # a table for people, one per knot
    rc, out, err = cli("census", "5_2", "--db", str(db), "--window", "0.01")
    assert rc == 0, err
    assert "5_2 — tube w = 1/√2, N = 150 (w/L = 0.0047): 1 state within 1 %" in out
    rc, out, err = cli("db", "--db", str(db), "census", "7_2")
    assert rc == 0 and "no census of 7_2 is stored" in out


@pytest.mark.slow  # the same refusals run in tests/cli/test_probe.py's matrix
def test_census_refuses_what_it_cannot_do_in_one_line(db, tmp_path):
    for args, words in [
            (("census", "--db", str(tmp_path / "none.db")), "no results database"),
            (("census", "--db", str(db), "--window", "-1"), "--window must be in"),
            (("census", "3_1", "--db", str(db)), "no stored runs of 3_1")]:
        rc, out, err = cli(*args)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert rc == 2 and len(lines) == 1 and words in lines[0], (args, err)
