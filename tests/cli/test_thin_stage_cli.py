"""The atlas's thin stage on the command line: ``stiffknots db thin K`` reads a stored thin
run (its table, its verdict, ``--json``); ``stiffknots atlas --thin`` follows every state to
w = 0, and survives ``kill -9``: run again, it does only what is left (#37)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from helpers import DATA
from stiffknots.store import Store
from stiffknots.store.thin import put_thin, thin_knots, thin_runs
from stiffknots.studies.thin_stage import plan_thin, thin_rows_of
from store_support import make_row

W = 1 / math.sqrt(2)


def cli(*args, timeout=600):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args], capture_output=True,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


def _state(eps0, eps_thin, route, name):
    pts = [{"w_over_L": w, "beads": 150, "epsilon": eps0 - 500 * (0.0047 - w),
            "epsilon_raw": eps0, "shape": name, "in_fit": True} for w in (0.004, 0.002)]
    chain = np.load(DATA / "analysis" / "4_1_tube_other.npy")
    return {"epsilon_thin": eps_thin, "error": 0.18, "event": None, "events": [],
            "shape_thin": name, "structure_epsilon": route, "structure_error": 1e-9,
            "structure_name": "2 point-braids" if name == "4C" else "point-braid + 2 double "
                                                                  "points",
            "agree": True, "structure_route": {"epsilon": route}, "points": pts,
            "chains": [chain, chain], "fit": {}, "discretisation": {},
            "parameters": {"beads": 150}, "shape": name, "structure": None, "searches": 1}


@pytest.fixture
def db(tmp_path):
    """4_1's tube census (`other` below the cage) and a stored thin run in which the `other`
    is the thin-limit ground (the values measured for 4_1, budget small)."""
    path = tmp_path / "t.db"
    with Store(path) as s:
        for i, (name, eps, shape) in enumerate([("other", 128.5660, "other"),
                                                ("cage", 129.3124, "4C")]):
            s.put(make_row(knot="4_1", exclusion="tube", thickness=W, seed=0, replica=i,
                           epsilon=eps, shape=shape, min_segment_distance=W,
                           settings={"problem": "anneal", "moves": 15_000_000}),
                  np.load(DATA / "analysis" / f"4_1_tube_{name}.npy"))
        (job,) = plan_thin(s).jobs
        out = {"states": [_state(128.566, 126.0281, 126.158594, "other"),
                          _state(129.3124, 126.4142, 126.472470, "4C")],
               "ground": 0, "margin": {"next": 1, "gap": 0.3861, "sigmas": 1.5},
               "crossing": None, "cpu_seconds": 90.0}
        put_thin(s, thin_rows_of(job, out, "small", 0))
    return path


def test_db_thin_shows_the_states_the_ground_and_the_routes(db, tmp_path):
    code, out, err = cli("db", "--db", str(db), "thin", "4_1")
    assert code == 0, err
    assert "every state of the tube census at w/L = 0.0047 followed to w = 0" in out
    assert "0: other ◀" in out and "126.0281 ±" in out and "126.4725" in out
    verdict = " ".join(out.split())
    assert "4_1: thin-limit ground other, ε* = 126.0281 ± 0.18 (structure route 126.1586: " \
           "agree); the next state +0.386 above, 1.5 σ (by the structure route +0.3139)" \
           in verdict
    code, out, err = cli("db", "--db", str(db), "thin", "4_1", "--json")
    d = json.loads(out)["thin"]
    assert d["epsilon_thin"] == pytest.approx(126.0281) and d["thin_shape"] == "other"
    assert [s["name"] for s in d["states"]] == ["other", "4C"] and d["budget"] == "small"
    code, out, err = cli("db", "--db", str(db), "thin", "5_2")
    assert code == 0 and "no thin stage of 5_2 is stored" in out and "--thin" in out


def test_the_verdict_says_why_the_grounds_routes_differ():
    from stiffknots.cli.thin_table import thin_verdict

    g = {"state": 1, "name": "other", "epsilon_thin": 128.422, "error": 0.13,
         "structure_epsilon": 126.4725, "structure_name": "2 point-braids", "agree": False}
    t = {"knot": "6_1", "ground": g, "margin": None, "states": [g], "w_over_L": 0.0047,
         "finite": {"name": "other"}, "crossing": 0.002}
    text = thin_verdict(t)
    assert "(structure route 126.4725: differ: the branch's extrapolation lies 1.54 % above" \
           in text and "upper estimate" in text
    text = thin_verdict({**t, "ground": {**g, "agree": None}})
    assert "126.4725: not compared)" in text and "upper estimate" not in text


@pytest.mark.slow  # ≈ 2 min: a real thin stage, killed and resumed
def test_a_thin_stage_killed_by_kill_9_resumes_and_then_skips(tmp_path):
    db, out = tmp_path / "a.db", tmp_path / "atlas"
    args = [sys.executable, "-m", "stiffknots.cli", "atlas", "--knots", "3_1", "--models",
            "tube", "--budget", "tiny", "--thin", "--thin-states", "1", "--db", str(db),
            "--out", str(out)]
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    seen = []
    t0 = time.monotonic()
    for line in p.stderr:                        # kill -9 once the thin stage is running
        seen.append(line)
        if "w/L = 0.004" in line or time.monotonic() - t0 > 300:
            break
    os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=60)
    assert any("thin stage (small): 1 knots to follow" in ln for ln in seen), "".join(seen)
    with Store(db, readonly=True) as s:
        assert thin_runs(s) == set() and s.count(knot="3_1") >= 2   # the sweep is stored
    code, stdout, err = cli(*args[3:], "--json")
    assert code == 0, err[-3000:]
    d = json.loads(stdout)
    assert d["thin"]["ran"] == ["3_1"] and d["thin"]["skipped"] == []
    (k,) = [e for e in d["knots"] if e["name"] == "3_1"]
    # the trefoil's thin limit: the doubly covered circle, 8π² (eq. (30); small budget)
    assert k["thin_state"] == "CB(i=2)" and k["epsilon_thin"] == pytest.approx(
        8 * np.pi**2, rel=2e-3)
    assert k["thin_states"][0]["structure_epsilon"] == pytest.approx(8 * np.pi**2, rel=1e-6)
    code, stdout, err = cli(*args[3:], "--json")
    d = json.loads(stdout)
    assert d["thin"]["ran"] == [] and d["thin"]["skipped"] == ["3_1"]
    with Store(db, readonly=True) as s:
        assert len(thin_knots(s)) == 1
    page = (out / "knots" / "3_1.html").read_text(encoding="utf-8")
    assert 'id="branch-plot"' in page and "Thin-limit ground: <b>CB(i=2)</b>" in page
