"""The thin stage's table (store/thin, schema version 4): a job's rows written whole and
replaced, read back with their chain, summarised per knot; a version-3 database read as it is
and migrated when written; the thin stage's plan skips the jobs stored (studies/thin_stage)."""

from __future__ import annotations

import math
import sqlite3

import numpy as np
import pytest

from helpers import DATA
from stiffknots.store import SCHEMA_VERSION, Store
from stiffknots.store.thin import put_thin, thin_chain, thin_knots, thin_rows, thin_runs
from stiffknots.studies.thin_stage import plan_thin, run_key, thin_rows_of
from store_support import make_row

W = 1 / math.sqrt(2)
SWEEP = {"problem": "anneal", "moves": 15_000_000}


def _tube(name):
    return np.load(DATA / "analysis" / f"4_1_tube_{name}.npy")


@pytest.fixture
def store(tmp_path):
    """4_1 in the tube model: one search in the `other`, one in the cage."""
    s = Store(tmp_path / "t.db")
    for i, (name, eps, shape) in enumerate([("other", 128.5660, "other"),
                                            ("cage", 129.3124, "4C")]):
        s.put(make_row(knot="4_1", exclusion="tube", thickness=W, seed=0, replica=i,
                       epsilon=eps, shape=shape, settings=SWEEP, min_segment_distance=W),
              _tube(name))
    yield s
    s.close()


def _branch(eps0, eps_thin, route, *, event=None, n=150):
    """What follow_census returns for one state (the fields the thin stage stores)."""
    pts = [{"w_over_L": w, "w": w * n, "beads": n, "epsilon": eps0 - 1000 * (0.004 - w),
            "epsilon_raw": eps0, "shape": "other", "in_fit": event is None or w > 0.001}
           for w in (0.004, 0.002, 0.001)]
    chains = [np.roll(_tube("other"), k, axis=0) for k in range(3)]
    return {"epsilon_thin": eps_thin, "error": None if eps_thin is None else 0.1,
            "event": None if event is None else {"kind": event, "w_over_L": 0.001},
            "events": [], "shape_thin": "other", "structure_epsilon": route,
            "structure_error": 1e-8, "structure_name": "2 point-braids", "agree": True,
            "structure_route": {"epsilon": route, "curves": [{"points": [[0, 0, 0], [1, 0, 0]],
                                                              "multiplicity": 2}]},
            "points": pts, "chains": chains, "fit": {"k": 1.0}, "discretisation": {},
            "parameters": {"beads": n}, "shape": "x", "structure": "y", "searches": 1}


def _finish(store, job, grounds=(126.03, 126.41)):
    out = {"states": [_branch(s["epsilon"], e, e + 0.1) for s, e in zip(job.states, grounds,
                                                                        strict=True)],
           "ground": int(np.argmin(grounds)), "margin": {"gap": abs(grounds[1] - grounds[0]),
                                                         "next": 1, "sigmas": 2.7},
           "crossing": None, "cpu_seconds": 12.5}
    rows = thin_rows_of(job, out, "small", 0)
    assert put_thin(store, rows) == len(job.states)
    return rows


def test_the_plan_takes_the_census_and_skips_a_stored_job(store):
    res = plan_thin(store, budget="small")
    (job,) = res.jobs
    assert res.knots == ["4_1"] and [s["name"] for s in job.states] == ["other", "4C"]
    assert job.census["w_over_L"] == pytest.approx(W / 150)
    assert np.array_equal(job.starts[1]["coords"], _tube("cage"))
    assert job.run == run_key(job.census, job.states, "small", 0)
    assert run_key(job.census, job.states, "default", 0) != job.run
    assert run_key(job.census, job.states[:1], "small", 0) != job.run
    _finish(store, job)
    assert thin_runs(store) == {job.run}
    again = plan_thin(store, budget="small")
    assert again.jobs == [] and again.skipped == ["4_1"]
    assert len(plan_thin(store, budget="small", states=1).jobs) == 1   # another job
    assert plan_thin(store, ["3_1"]).missing[0]["knot"] == "3_1"


def test_a_jobs_rows_round_trip_are_replaced_and_summarised(store):
    (job,) = plan_thin(store).jobs
    rows = _finish(store, job, grounds=(126.41, 126.03))   # the second state is the ground
    got = thin_rows(store, "4_1")
    assert [r["state"] for r in got] == [0, 1] and [r["ground"] for r in got] == [False, True]
    assert got[1]["epsilon_thin"] == pytest.approx(126.03) and got[1]["agree"] is True
    assert got[0]["details"]["route"]["curves"][0]["multiplicity"] == 2
    assert got[0]["details"]["thin_point"] == 2 and got[0]["cpu_seconds"] == 12.5
    assert np.array_equal(thin_chain(store, got[0]["id"]), rows[0]["chain"])
    (k,) = thin_knots(store)
    assert (k["thin_shape"], k["epsilon_thin"], k["thin_error"]) == ("4C", 126.03, 0.1)
    assert k["finite"]["name"] == "other" and k["margin"]["sigmas"] == 2.7
    assert k["thin_structure"] == "2 point-braids"
    _finish(store, job, grounds=(126.0, 126.5))             # the same job again: replaced
    assert [r["ground"] for r in thin_rows(store)] == [True, False]
    with pytest.raises(ValueError, match="chain must be"):
        put_thin(store, [{**rows[0], "chain": np.zeros((2, 3))}])
    with pytest.raises(ValueError, match="lacks budget"):
        put_thin(store, [{k: v for k, v in rows[0].items() if k != "budget"}])


def test_a_version_3_database_is_read_as_it_is_and_migrated_to_hold_the_thin_stage(tmp_path):
    path = tmp_path / "v3.db"
    with Store(path) as s:
        s.put(make_row(knot="4_1", exclusion="tube", thickness=W, seed=0, replica=0,
                       epsilon=128.566, shape="other", settings=SWEEP,
                       min_segment_distance=W), _tube("other"))
    con = sqlite3.connect(path)
    con.execute("DROP TABLE thin")
    con.execute("UPDATE meta SET value = '3' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with Store(path, readonly=True) as s:
        assert s.meta()["schema_version"] == "3"
        assert thin_rows(s) == [] and thin_knots(s) == [] and thin_runs(s) == set()
    with Store(path) as s:
        assert s.meta()["schema_version"] == str(SCHEMA_VERSION) == "4"
        assert "version 3 → 4" in s.meta()["migrated"] and len(s) == 1
        (job,) = plan_thin(s).jobs
        rows = thin_rows_of(job, {"states": [_branch(128.566, None, None, event="jumped")],
                                  "ground": None, "margin": None, "crossing": None}, "small", 0)
        put_thin(s, rows)
        (k,) = thin_knots(s)
        assert k["ground"] is None and k["epsilon_thin"] is None
        assert k["states"][0]["event"] == "jumped"
        # the chain kept is the last still in the state (the jump came at w/L = 0.001)
        assert k["states"][0]["details"]["thin_point"] == 1
