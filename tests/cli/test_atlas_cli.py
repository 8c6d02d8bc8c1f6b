"""``stiffknots atlas`` and ``stiffknots db``: the --json shape, bad options (exit 2, one
line), and the sweep process killed (kill -9) or interrupted (Ctrl-C) mid-run, then resumed by
the same command with every replica stored exactly once and no worker left running."""

from __future__ import annotations

import json
import math
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from stiffknots.store import Store
from stiffknots.sweeps import BUDGETS, budget_of, parse_models, plan_sweep, sweep_settings

D = 1 / math.sqrt(2)


def cli(*args, timeout=600):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args], capture_output=True,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


def _error_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip() and "Warning" not in ln
             and "warnings.warn" not in ln]
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("args", [
    (),  # neither --max-crossings nor --knots
    ("--max-crossings", "2"),
    ("--max-crossings", "20"),
    ("--knots", "4_9"),
    ("--knots", "0_1"),
    ("--knots", ","),
    ("--knots", "6_1", "--max-crossings", "5"),
    ("--knots", "3_1", "--models", "soft"),
    ("--knots", "3_1", "--models", "tube", "--w", "1.5"),
    ("--knots", "3_1", "--models", "bead", "--w", "0.5"),
    ("--knots", "3_1", "--budget", "huge"),
    ("--knots", "3_1", "--replicas", "0"),
    ("--knots", "3_1", "--moves", "10"),
    ("--knots", "3_1", "--seed", "-1"),
    ("--knots", "3_1", "--workers", "0"),
    ("--knots", "3_1", "--max-replicas", "1"),  # fewer than the budget's 2
    ("--knots", "3_1", "--scheduler", "not an address"),
])
def test_atlas_bad_options_exit_2_one_line(tmp_path, args):
    rc, out, err = cli("atlas", *args, "--out", str(tmp_path / "a"), "--db",
                       str(tmp_path / "a.db"))
    assert rc == 2, (out, err)
    assert "Traceback" not in err
    assert _error_line(err).startswith("error:")
    assert not (tmp_path / "a.db").exists() or args[-1] == "not an address"


def test_atlas_bad_paths_exit_2(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    rc, _, err = cli("atlas", "--knots", "3_1", "--out", str(f), "--db", str(tmp_path / "a.db"))
    assert rc == 2 and _error_line(err).startswith("error: --out")
    rc, _, err = cli("atlas", "--knots", "3_1", "--out", str(tmp_path / "o"), "--db",
                     str(tmp_path))
    assert rc == 2 and _error_line(err).startswith("error: --db")
    rc, _, err = cli("atlas", "--knots", "3_1", "--out", str(tmp_path / "o"), "--db", str(f))
    assert rc == 2 and "not an SQLite database" in _error_line(err)


@pytest.mark.slow  # a real sweep (≈ 30 s); test_db_states_and_grounds runs one in the default
def test_atlas_json_shape(tmp_path):
    """A tiny sweep of one knot (2 replicas on 2 workers), then the pages and the JSON."""
    out, db = tmp_path / "atlas", tmp_path / "r.db"
    rc, stdout, err = cli("atlas", "--knots", "3_1", "--models", "bead", "--budget", "tiny",
                          "--workers", "2", "--out", str(out), "--db", str(db), "--json")
    assert rc == 0, err
    d = json.loads(stdout)
    # the progress still goes to stderr with --json (a line per job where it is no terminal):
    # a sweep of hours is not silent, and stdout holds the JSON alone
    assert "2/2 jobs, " in err and "3_1/bead/r0: ε = " in err and "3_1/bead/r1: ε = " in err
    assert d["db"] == str(db) and d["html"] == str(out / "index.html")
    assert (out / "index.html").exists() and (out / "knots" / "3_1.html").exists()
    assert (out / "families.json").exists() and (out / "atlas.json").exists()
    (k,) = d["knots"]
    assert {"name", "n", "i", "crossing_number", "shape", "multiplicity", "epsilon",
            "converged", "models"} <= set(k)
    assert (k["name"], k["n"], k["i"], k["crossing_number"]) == ("3_1", 2, 2, 3)
    assert k["families"] == ["n=i", "80"] and k["model"] == "bead"
    m = k["models"]["bead"]
    assert m["replicas"] == 2 and m["width"]["d"] == pytest.approx(D)
    assert m["width"]["beads"] == 150 and "d = 1/√2, N = 150" in m["width"]["text"]
    g = m["ground"]
    assert k["shape"] == g["shape"] and k["epsilon"] == g["epsilon"]
    assert k["multiplicity"] == g["multiplicity"] and k["converged"] == m["converged"]
    assert g["count"] + sum(s["count"] for s in m["metastable"]) == 2
    assert isinstance(k["converged"], bool)
    with Store(db, create=False) as st:  # its contact structure, named from its chain
        from stiffknots.analysis import analyse_structure

        best = min(st.replicas(knot="3_1"), key=lambda r: r["epsilon"])
        assert g["structure"] == analyse_structure(st.coords(best["id"]), d=D).name
    assert k["epsilon"] >= 8 * math.pi**2  # above the lower bound 2π²n² (n = 2)
    sw = d["sweep"]
    assert (sw["jobs"], sw["skipped"], sw["ran"], sw["failed"]) == (2, 0, 2, [])
    assert sw["budget"] == {"name": "tiny", "replicas": 2, "moves": 200_000,
                           "max_replicas": 2, "legs": 0, "bead_search": "annealing"}
    fam = d["families"]
    assert [r["label"] for r in fam["catalogue"]][:2] == ["n_c < 7", "n_c < 9"]
    assert fam["catalogue"][0]["fraction"] == 1.0
    with Store(db, create=False) as st:
        assert st.count() == 2
        assert {r["seed"] for r in st.replicas()} == {0}
    # the same command again: nothing to run, the same answer
    rc, stdout2, err = cli("atlas", "--knots", "3_1", "--models", "bead", "--budget", "tiny",
                           "--workers", "2", "--out", str(out), "--db", str(db), "--json")
    assert rc == 0, err
    d2 = json.loads(stdout2)
    assert (d2["sweep"]["skipped"], d2["sweep"]["ran"]) == (2, 0)
    assert d2["knots"][0]["epsilon"] == k["epsilon"]
    # --stored: a knot not yet swept gets its row and page, nothing runs, the rest is counted
    rc, stdout3, err = cli("atlas", "--knots", "3_1,4_1", "--models", "bead", "--budget",
                           "tiny", "--out", str(out), "--db", str(db), "--stored", "--json")
    assert rc == 0, err
    d3 = json.loads(stdout3)
    sw3 = d3["sweep"]
    assert (sw3["jobs"], sw3["skipped"], sw3["ran"], sw3["left"]) == (4, 2, 0, 2)
    assert [e["name"] for e in d3["knots"]] == ["3_1", "4_1"]
    assert d3["knots"][1]["models"]["bead"]["ground"] is None
    assert (out / "knots" / "4_1.html").exists()
    assert d3["converged"]["bead"] == float(k["converged"])  # over the knots with results
    # the knots not converged are listed (the target: "list the others"), 4_1 — no
    # results — is not among them
    assert d3["converged_counts"]["bead"]["not_converged"] == ([] if k["converged"] else ["3_1"])
    page = (out / "index.html").read_text()
    assert "not converged" in page and ("bead none of 1" if k["converged"]
                                        else "bead 1 of 1: 3_1") in page
    with Store(db, create=False) as st:
        assert st.count() == 2
    rc, text, err = cli("atlas", "--knots", "3_1,4_1", "--models", "bead", "--budget", "tiny",
                        "--out", str(out), "--db", str(db), "--stored")
    assert rc == 0, err
    flat = " ".join(text.split())
    assert "2 not run" in flat and f"bead {int(k['converged'])} of 1" in flat, flat
    assert ("not converged: bead 1 of 1: 3_1" in flat) == (not k["converged"]), flat


def test_atlas_stored_on_an_empty_database(tmp_path):
    # before the first sweep: every planned knot gets its row, nothing runs (it said
    # "error: default_model 'bead' is not among the models []")
    out, db = tmp_path / "pages", tmp_path / "new.db"
    rc, stdout, err = cli("atlas", "--max-crossings", "4", "--out", str(out), "--db", str(db),
                          "--stored", "--json")
    assert rc == 0, err
    d = json.loads(stdout)
    assert [e["name"] for e in d["knots"]] == ["3_1", "4_1"]
    assert all(m["ground"] is None for e in d["knots"] for m in e["models"].values())
    assert d["converged"] == {"bead": None, "tube": None}
    assert d["sweep"]["ran"] == 0 and d["sweep"]["left"] == d["sweep"]["jobs"]
    assert (out / "index.html").exists() and (out / "knots" / "4_1.html").exists()
    rc, text, err = cli("atlas", "--max-crossings", "4", "--out", str(out), "--db", str(db),
                        "--stored")
    assert rc == 0, err
    assert "no results stored yet" in " ".join(text.split())


def test_atlas_names_the_structures_of_the_knots_in_no_family(tmp_path):
    """7_4 is in no conjectured family: the summary and families.json name its ground
    state's contact structure (§V B) and group it."""
    from stiffknots.analysis.synthetic import four_cage

    bead, = parse_models("bead")
    db, out = tmp_path / "s.db", tmp_path / "pages"
    with Store(db) as st:
        st.put({"knot": "7_4", "exclusion": "bead", "beads": 150, "thickness": bead.thickness,
                "seed": 0, "replica": 0, "settings": sweep_settings(bead, BUDGETS["small"]),
                "epsilon": 171.2, "min_segment_distance": 0.5, "wall_seconds": 1.0,
                "shape": "other", "start": "braid"}, four_cage())
    args = ("atlas", "--knots", "7_4", "--models", "bead", "--budget", "small", "--out",
            str(out), "--db", str(db), "--stored")
    rc, text, err = cli(*args)
    assert rc == 0, err
    flat = " ".join(text.split())
    assert ("in no family: 1 ground states in 1 contact structures (§V B); the commonest: "
            "2 point-braids 1 (7_4)") in flat, flat
    fam = json.loads((out / "families.json").read_text())
    assert fam["no_family_structures"][0]["knots"] == ["7_4"]
    assert fam["knots"][0]["structure"] == "2 point-braids"


# -- the results database ------------------------------------------------------------------


def _synthetic_db(path: Path) -> Path:
    """Rows of 3_1 (bead: 2 CB; tube: 1 CB) and 4_1 (bead: 4C + 80) as a sweep stores them."""
    bead, tube = parse_models("bead,tube")
    with Store(path) as st:
        for knot, model, r, eps, shape, mult in [
                ("3_1", bead, 0, 79.1, "CB", 2), ("3_1", bead, 1, 79.15, "CB", 2),
                ("3_1", tube, 0, 80.2, "CB", 2),
                ("4_1", bead, 0, 128.4, "4C", None), ("4_1", bead, 1, 147.0, "80", None)]:
            st.put({"knot": knot, "exclusion": model.exclusion, "beads": 150,
                    "thickness": model.thickness, "seed": 0, "replica": r,
                    "settings": sweep_settings(model, BUDGETS["small"]), "epsilon": eps,
                    "min_segment_distance": 0.6, "wall_seconds": 1.0, "shape": shape,
                    "multiplicity": mult, "start": "braid"}, np.zeros((150, 3)) + r)
    return path


def test_db_states_and_grounds(tmp_path):
    db = _synthetic_db(tmp_path / "s.db")
    rc, out, err = cli("db", "--db", str(db), "states", "3.1", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["knot"] == "3_1" and d["replicas"] == 3 and len(d["ensembles"]) == 2
    bead = next(e for e in d["ensembles"] if e["exclusion"] == "bead")
    assert bead["ground"]["name"] == "CB(i=2)" and bead["ground"]["count"] == 2
    assert bead["converged"] is True and "N = 150" in bead["width"]
    tube = next(e for e in d["ensembles"] if e["exclusion"] == "tube")
    assert tube["converged"] is False  # one replica
    rc, out, _ = cli("db", "--db", str(db), "states", "3_1", "--model", "tube", "--json")
    assert [e["exclusion"] for e in json.loads(out)["ensembles"]] == ["tube"]
    rc, out, err = cli("db", "--db", str(db), "states", "4_1")
    assert rc == 0 and "4C" in out and "metastable" in out
    csv = tmp_path / "g" / "grounds.csv"
    rc, out, err = cli("db", "--db", str(db), "grounds", "--csv", str(csv), "--json")
    assert rc == 0, err
    g = json.loads(out)
    assert [(r["knot"], r["exclusion"], r["state"]) for r in g["grounds"]] == [
        ("3_1", "bead", "CB(i=2)"), ("3_1", "tube", "CB(i=2)"), ("4_1", "bead", "4C")]
    # every row's verdict under "converged" (it was null there, the verdict under a per-row
    # "converged_rule" while the top level's is the rule in words)
    assert [r["converged"] for r in g["grounds"]] == [True, False, False]
    assert isinstance(g["converged_rule"], str)
    assert csv.read_text().splitlines()[0].startswith("knot,exclusion,beads")
    import csv as csvmod

    with open(csv, newline="") as f:
        table = list(csvmod.DictReader(f))
    assert [r["converged"] for r in table] == ["true", "false", "false"]
    assert len(csv.read_text().splitlines()) == 4
    rc, out, err = cli("db", "--db", str(db), "grounds")
    assert rc == 0 and "CB(i=2)" in out
    # 4_1's bead ensemble has had no replica from its cage or its 80: not converged, and why
    assert g["grounds"][2]["untried_starts"] == ["cage", "eighty"]
    assert "no*: a default start not tried yet — 4_1 bead: cage, eighty" in out
    # one width per model: named once below the table, every row on one line of ≤ 80 columns
    lines = out.splitlines()
    assert "bead: bead rule d = 1/√2, N = 150 (w/L ≈ 0.0047)" in lines
    assert any(ln.startswith("tube: tube w = 1/√2, N = 150") for ln in lines)
    rows = [ln for ln in lines if ln.startswith("│")]
    assert len(rows) == 3 and all(len(ln) <= 80 for ln in lines)
    assert "80 147.00 ×1" in rows[2]  # 4_1 bead: its metastable 80


def test_db_states_shows_a_touching_crossing(tmp_path):
    """A bead-rule state whose strands touch where they cross sits at the polish's strand
    gap (1e-4): the table prints it as 1.0e-04 (not 0.000) and says what it means."""
    bead, = parse_models("bead")
    db = tmp_path / "t.db"
    with Store(db) as st:
        for r, eps, gap in [(0, 250.68, 1e-4), (1, 266.62, 0.457)]:
            st.put({"knot": "10_6", "exclusion": "bead", "beads": 150,
                    "thickness": bead.thickness, "seed": 0, "replica": r,
                    "settings": sweep_settings(bead, BUDGETS["small"]), "epsilon": eps,
                    "min_segment_distance": gap, "wall_seconds": 1.0, "shape": "other",
                    "multiplicity": None, "start": "braid"}, np.zeros((150, 3)) + r)
    rc, out, err = cli("db", "--db", str(db), "states", "10_6")
    assert rc == 0, err
    text = " ".join(out.split())
    assert "1.0e-04" in text and "0.457" in text and "0.000" not in text
    assert "two strands touch where they cross" in text
    rc, out, err = cli("db", "--db", str(_synthetic_db(tmp_path / "s.db")), "states", "3_1")
    assert rc == 0 and "touch" not in out  # no note where nothing touches


def test_db_states_names_each_states_contact_structure(tmp_path):
    """Below the table: the §V B structure of every state's lowest chain, in table order
    (ground first); a chain the analysis cannot read shows a dash."""
    from stiffknots.analysis.synthetic import four_cage, torus_braid

    bead, = parse_models("bead")
    db = tmp_path / "t.db"
    with Store(db) as st:
        for r, (eps, shape, x) in enumerate([(79.1, "CB", torus_braid(2, 150, separation=0.9)),
                                             (90.0, "4C", four_cage()),
                                             (99.0, "other", np.zeros((150, 3)))]):
            st.put({"knot": "3_1", "exclusion": "bead", "beads": 150,
                    "thickness": bead.thickness, "seed": 0, "replica": r,
                    "settings": sweep_settings(bead, BUDGETS["small"]), "epsilon": eps,
                    "min_segment_distance": 0.5, "wall_seconds": 1.0, "shape": shape,
                    "multiplicity": 2 if shape == "CB" else None, "start": "braid"}, x)
    rc, out, err = cli("db", "--db", str(db), "states", "3_1")
    assert rc == 0, err
    lines = [" ".join(ln.split()) for ln in out.splitlines()]
    k = next(i for i, ln in enumerate(lines) if ln.startswith("contact structure"))
    assert lines[k + 1:k + 4] == ["ground circular line-braid (m = 2)",
                                  "metastable 1 2 point-braids", "metastable 2 —"]
    rc, out, err = cli("db", "--db", str(db), "states", "3_1", "--json")
    assert rc == 0, err
    e = json.loads(out)["ensembles"][0]
    assert [s["structure"] for s in (e["ground"], *e["metastable"])] == [
        "circular line-braid (m = 2)", "2 point-braids", None]


@pytest.mark.parametrize("args", [
    ("states", "3_1"),  # no database there
    ("states", "5_2"),  # nothing stored for it
    ("states", "4_9"),  # not a knot
    ("states", "3_1", "--model", "soft"),
    ("grounds", "--csv", "."),
])
def test_db_mistakes_exit_2(tmp_path, args):
    db = tmp_path / "s.db" if args != ("states", "3_1") else tmp_path / "none.db"
    if db.name == "s.db":
        _synthetic_db(db)
    rc, out, err = cli("db", "--db", str(db), *args)
    assert rc == 2, (out, err)
    assert _error_line(err).startswith("error:")
    assert not (tmp_path / "none.db").exists()  # a query never creates a database


# -- kill -9 and Ctrl-C of the whole sweep ---------------------------------------------------

SWEEP = ("--knots", "3_1,4_1", "--models", "bead", "--replicas", "2", "--moves", "2000000",
         "--workers", "2")


def _start(tmp_path):
    return subprocess.Popen(
        [sys.executable, "-m", "stiffknots.cli", "atlas", *SWEEP, "--out",
         str(tmp_path / "atlas"), "--db", str(tmp_path / "r.db"), "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _rows(db: Path) -> int:
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return con.execute("SELECT count(*) FROM replicas").fetchone()[0]
    except sqlite3.OperationalError:  # the schema is being created
        return 0


def _wait_rows(proc, db: Path, at_least: int, timeout: float = 400) -> int:
    t0 = time.time()
    while time.time() - t0 < timeout:
        n = _rows(db)
        if n >= at_least:
            return n
        if proc.poll() is not None:
            raise AssertionError(f"the sweep ended (rc {proc.returncode}) before storing "
                                 f"{at_least} rows: {proc.stderr.read()[-2000:]}")
        time.sleep(0.1)
    raise AssertionError("timed out waiting for rows")


def _descendants(pid: int) -> list[psutil.Process]:
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def _gone(procs: list[psutil.Process], timeout: float = 30) -> list[int]:
    """The processes still running after ``timeout`` seconds."""
    _, alive = psutil.wait_procs(procs, timeout=timeout)
    return [p.pid for p in alive if p.status() != psutil.STATUS_ZOMBIE]


def _check_resumed(tmp_path, before: int):
    rc, out, err = cli("atlas", *SWEEP, "--out", str(tmp_path / "atlas"), "--db",
                       str(tmp_path / "r.db"), "--json")
    assert rc == 0, err
    sw = json.loads(out)["sweep"]
    assert sw["skipped"] == before and sw["ran"] == 4 - before and not sw["failed"]
    # the budget the command builds from SWEEP's options (the default's, its bead replicas
    # Langevin dynamics, with --replicas and --moves)
    jobs = plan_sweep(["3_1", "4_1"], parse_models("bead"),
                      budget_of("default", replicas=2, moves=2_000_000), seed=0)
    with Store(tmp_path / "r.db", create=False) as st:
        assert st.keys() == {j.key for j in jobs}
        assert st.count() == 4 and st.check()["ok"]


@pytest.mark.slow
def test_kill_9_mid_sweep_then_resume(tmp_path):
    proc = _start(tmp_path)
    try:
        before = _wait_rows(proc, tmp_path / "r.db", 1)
        kids = _descendants(proc.pid)
        assert kids, "no worker processes (the local cluster forks them from the sweep)"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL
    assert not _gone(kids), "worker processes outlived the killed sweep"
    before = _rows(tmp_path / "r.db")
    assert 1 <= before < 4, "the kill came too late to test a resume"
    with Store(tmp_path / "r.db", create=False) as st:
        assert st.check()["ok"]  # whole rows only
    _check_resumed(tmp_path, before)


@pytest.mark.slow
@pytest.mark.parametrize(("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_ctrl_c_mid_sweep_exits_130_then_resume(tmp_path, sig, code):
    """Ctrl-C, or ``kill PID`` (SIGTERM: a batch system's stop) to the sweep alone: the same
    stop — what arrived stored, the cluster closed, one line, exit 130 or 143 — and the same
    command resumes."""
    proc = _start(tmp_path)
    try:
        _wait_rows(proc, tmp_path / "r.db", 1)
        kids = _descendants(proc.pid)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]  # the progress lines, then the stop
    assert lines[-1].startswith("interrupted: ")
    assert "run the same command to resume" in err
    d = json.loads(out)
    assert d["sweep"]["interrupted"] and d["html"] is None
    assert not _gone(kids, 15), "worker processes outlived the interrupted sweep"
    before = _rows(tmp_path / "r.db")
    assert before == d["sweep"]["ran"] and 1 <= before < 4
    _check_resumed(tmp_path, before)


def test_progress_lines_where_stderr_is_not_a_terminal():
    """In a log file (no terminal) the bar is not drawn: every finished job prints a line with
    the jobs done of planned, the elapsed time and the time left, and its result."""
    import io
    from types import SimpleNamespace

    from rich.console import Console

    from stiffknots.cli.atlas import SweepProgress

    buf = io.StringIO()
    bar = SweepProgress(console=Console(file=buf, force_terminal=False, width=200))
    with bar:
        bar.started(SimpleNamespace(skipped=1, jobs=4, todo=3))
        bar.finished(SimpleNamespace(id="3_1/bead/r1"),
                     {"shape": "CB", "multiplicity": 2, "epsilon": 79.0182}, None)
        bar.added(2)
        bar.finished(SimpleNamespace(id="4_1/bead/r0"), None, "boom")
        bar.seeded({"knot": "4_1", "model": "bead", "epsilon": 127.4567, "tube_replica": 1})
    lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()]
    assert lines[0] == "1 of 4 jobs already stored: skipped"
    # nothing settled yet: the time left counts the plan alone, and says it is a lower bound
    assert " 1/3 jobs, 0:00:00 elapsed, ETA ≥ 0:00:00 — 3_1/bead/r1: ε = 79.02 CB(i=2)" in lines[1]
    assert " 2/5 jobs, " in lines[2] and lines[2].endswith("4_1/bead/r0: failed")
    assert lines[3].endswith("4_1/bead: seeded from tube replica 1, ε = 127.46")
    assert len(lines) == 4
    # disabled (a caller that draws its own): nothing at all; on a terminal the bar, not the
    # lines
    quiet = io.StringIO()
    bar = SweepProgress(disable=True, console=Console(file=quiet, force_terminal=False))
    with bar:
        bar.started(SimpleNamespace(skipped=1, jobs=4, todo=3))
        bar.finished(SimpleNamespace(id="3_1/bead/r1"), None, "x")
    assert quiet.getvalue() == ""
    assert not SweepProgress(console=Console(file=io.StringIO(), force_terminal=True)).log_lines
    # every method a sweep calls (SweepProgress is no subclass: the CLI starts without Dask)
    from stiffknots.sweeps import SweepListener

    hooks = [k for k, v in vars(SweepListener).items() if callable(v) and not k.startswith("_")]
    assert len(hooks) == 7 and all(callable(getattr(SweepProgress, k)) for k in hooks)


def test_time_left_counts_the_replicas_still_to_be_added():
    """The time left is the mean pace times the jobs expected (planned + the replicas that
    unconverged knots will get, from the settled ones' mean), not the plan alone: 1 job of
    3 planned done in 100 s with 10 expected leaves 900 s, not 200 s."""
    import io
    import time
    from types import SimpleNamespace

    from rich.console import Console

    from stiffknots.cli.atlas import SweepProgress

    buf = io.StringIO()
    bar = SweepProgress(console=Console(file=buf, force_terminal=False, width=200))
    with bar:
        bar.started(SimpleNamespace(skipped=0, jobs=3, todo=3))
        bar.t0 = time.monotonic() - 100.0
        bar.expected(10.0, 1)
        bar.finished(SimpleNamespace(id="3_1/bead/r0"),
                     {"shape": "CB", "multiplicity": 2, "epsilon": 79.0182}, None)
        bar.expected(3.0, 2)  # everything settled as planned: the plan is the estimate
        bar.finished(SimpleNamespace(id="3_1/bead/r1"),
                     {"shape": "CB", "multiplicity": 2, "epsilon": 79.0182}, None)
    lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()]
    assert "1/3 jobs, 0:01:40 elapsed, ETA 0:15:00 (≈ 10 jobs) — 3_1/bead/r0" in lines[0]
    assert "2/3 jobs, 0:01:40 elapsed, ETA 0:00:50 — 3_1/bead/r1" in lines[1]
    # nothing settled yet (a sweep's first estimate): the plan alone, a lower bound
    bar.expected(3.0, 0)
    assert bar.time_left().startswith("≥ ")


def test_expected_todo_adds_the_settled_mean_to_every_open_knot():
    """expected_todo: the plan until a (knot, model) settles; then each open one is expected
    to need the settled ones' mean replicas beyond the budget's, less those it has."""
    from stiffknots.sweeps.run import expected_todo

    open_ = {"replicas": 2, "settled": False}
    assert expected_todo({("a", "bead"): dict(open_), ("b", "bead"): dict(open_)}, 4, 2) == 4
    groups = {("a", "bead"): {"replicas": 6, "settled": True},   # 4 added
              ("b", "bead"): {"replicas": 2, "settled": True},   # converged at once
              ("c", "bead"): {"replicas": 2, "settled": False},  # expects 2 more
              ("d", "bead"): {"replicas": 4, "settled": False},  # has them already
              ("e", "bead"): {"replicas": 6, "settled": False}}  # more than the mean: 0
    assert expected_todo(groups, 20, 2) == 22.0


def test_expected_todo_takes_the_mean_of_knots_like_the_open_one():
    """expected_todo: an open (knot, model) expects what settled ones of its model and crossing
    number needed; without those, the largest smaller crossing number's; then the model's;
    then all settled ones'."""
    from stiffknots.sweeps.run import expected_todo

    groups = {("3_1", "bead"): {"replicas": 2, "settled": True, "crossings": 3},    # +0
              ("8_1", "bead"): {"replicas": 6, "settled": True, "crossings": 8},    # +4
              ("8_2", "bead"): {"replicas": 8, "settled": True, "crossings": 8},    # +6
              ("3_1", "tube"): {"replicas": 2, "settled": True, "crossings": 3},    # +0
              ("8_3", "bead"): {"replicas": 2, "settled": False, "crossings": 8},   # 8's: 5
              ("9_1", "bead"): {"replicas": 4, "settled": False, "crossings": 9},   # 8's: 3 more
              ("8_3", "tube"): {"replicas": 2, "settled": False, "crossings": 8}}   # tube 3's: 0
    assert expected_todo(groups, 10, 2) == 18.0
    groups[("4_1", "bead")] = {"replicas": 2, "settled": False, "crossings": 4}  # 3's: 0
    assert expected_todo(groups, 10, 2) == 18.0
    # a model none of whose knots settled: the mean of all settled ones ((0+4+6+0)/4)
    groups[("9_1", "wide")] = {"replicas": 2, "settled": False, "crossings": 9}
    assert expected_todo(groups, 10, 2) == 20.5
    # the mean over all of a model's settled knots, where crossing numbers are not given:
    # bead 10/3 beyond the budget's for each open bead knot
    flat = {k: {"replicas": g["replicas"], "settled": g["settled"]} for k, g in groups.items()
            if k[1] != "wide"}
    assert abs(expected_todo(flat, 10, 2) - (10 + 10 / 3 + (10 / 3 - 2) + 10 / 3)) < 1e-12


def test_expected_todo_counts_what_a_resumed_sweep_found_stored():
    """A (knot, model) not judged again yet (a bead ensemble waiting for its tube one) counts
    the replicas and legs stored, not the budget's replicas it starts with."""
    from stiffknots.sweeps.run import expected_todo

    groups = {("9_1", "bead"): {"replicas": 2, "settled": True, "crossings": 9},        # +0
              ("9_2", "bead"): {"replicas": 6, "settled": True, "crossings": 9},        # +4
              ("9_3", "bead"): {"replicas": 2, "settled": False, "crossings": 9,
                                "stored": 6},                                           # 0
              ("9_4", "bead"): {"replicas": 2, "settled": False, "crossings": 9,
                                "stored": 2, "stored_legs": 0}}                         # 2
    assert expected_todo(groups, 0, 2) == 2.0
    groups[("9_2", "bead")]["stored_legs"] = 2  # a settled one's stored legs count too
    assert expected_todo(groups, 0, 2) == 3.0  # mean (0 + 6) / 2 = 3: 9_3 0, 9_4 3
