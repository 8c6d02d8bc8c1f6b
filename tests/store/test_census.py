"""The census of a stored knot at one width (store/census): every run there pooled, the
searches counted once, written and read back, replaced when taken again; the schema's
migration from version 2 (no census table)."""

from __future__ import annotations

import math
import sqlite3

import numpy as np
import pytest

from helpers import DATA
from stiffknots.store import SCHEMA_VERSION, Store, save_census, stored_census, take_census
from store_support import make_row

W = 1 / math.sqrt(2)
SWEEP = {"problem": "anneal", "moves": 15_000_000}
AUDIT = {"problem": "audit", "moves": 30_000_000}


def _tube(name):
    return np.load(DATA / "analysis" / f"4_1_tube_{name}.npy")


def _row(seed, replica, eps, shape, settings=SWEEP, **kw):
    return make_row(knot="4_1", exclusion="tube", thickness=W, seed=seed, replica=replica,
                    epsilon=eps, shape=shape, settings=settings, min_segment_distance=W, **kw)


@pytest.fixture
def filled(tmp_path):
    """4_1 in the tube model: a sweep whose search 0 has a continuation leg (replica 2,
    extra.search = 0) in the `other`, replica 1 in the cage; an audit run (other settings) with
    one more search in the `other`; a bead run (another width)."""
    other, cage = _tube("other"), _tube("cage")
    s = Store(tmp_path / "c.db")
    s.put(_row(0, 0, 128.5660, "other"), other)
    s.put(_row(0, 1, 129.3124, "4C"), cage)
    s.put(_row(0, 2, 128.5649, "other", extra={"search": 0}), np.roll(other, 30, axis=0))
    s.put(_row(7, 0, 128.5650, "other", settings=AUDIT), other[::-1])
    s.put(make_row(knot="4_1", seed=0, replica=0, epsilon=127.9, shape="other"), other)
    yield s
    s.close()


def test_a_census_pools_every_run_at_one_width_and_counts_searches_once(filled):
    c = take_census(filled, "4_1", exclusion="tube")
    assert c["replicas"] == 4 and c["searches"] == 3 and c["counted"] == 4
    assert len(c["settings"]) == 2 and c["beads"] == 150
    assert [s["name"] for s in c["states"]] == ["other", "4C"]
    other, cage = c["states"]
    assert (other["count"], other["searches"]) == (3, 2)   # search 0 (two rows) and the audit
    assert other["epsilon"] == pytest.approx(128.5649) and other["spread"] < 1e-6
    assert (cage["count"], cage["searches"]) == (1, 1)
    assert other["structure"] and cage["structure"]        # read from the chains (§V B)


def test_a_census_is_stored_read_back_and_replaced(filled):
    c = take_census(filled, "4_1", exclusion="tube")
    assert save_census(filled, c) == 2
    [got] = stored_census(filled, "4_1")
    assert got["census"] == c["census"] and got["replicas"] == 4
    assert got["settings"] == c["settings"] and got["params"]["window"] == 0.15
    assert [(s["state"], s["name"], s["searches"]) for s in got["states"]] == [
        (0, "other", 2), (1, "4C", 1)]
    # taken again after a new search found only the cage: replaced whole, not appended
    filled.put(_row(0, 3, 129.3125, "4C"), _tube("cage"))
    save_census(filled, take_census(filled, "4_1", exclusion="tube"))
    [got] = stored_census(filled, "4_1")
    assert [s["count"] for s in got["states"]] == [3, 2] and got["replicas"] == 5
    # another window is another census; the newest is read unless latest=False
    save_census(filled, take_census(filled, "4_1", exclusion="tube", window=0.001))
    assert [len(x["states"]) for x in stored_census(filled, "4_1", latest=False)] in (
        [1, 2], [2, 1])
    assert stored_census(filled, "3_1") == []


def test_a_census_needs_one_width(filled):
    with pytest.raises(ValueError, match="2 widths of 4_1"):
        take_census(filled, "4_1")
    with pytest.raises(ValueError, match="no stored replicas"):
        take_census(filled, "5_2")


def test_a_version_2_database_is_read_as_it_is_and_migrated_to_hold_a_census(tmp_path):
    path = tmp_path / "v2.db"
    with Store(path) as s:
        s.put(_row(0, 0, 128.5660, "other"), _tube("other"))
    con = sqlite3.connect(path)
    con.execute("DROP TABLE census")
    con.execute("DROP TABLE thin")
    con.execute("UPDATE meta SET value = '2' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with Store(path, readonly=True) as s:
        assert s.meta()["schema_version"] == "2" and stored_census(s) == []
        c = take_census(s, "4_1")                    # computing reads only
        with pytest.raises(Exception, match="no census table"):
            save_census(s, c)
    with Store(path) as s:
        assert s.meta()["schema_version"] == str(SCHEMA_VERSION) == "4"
        assert "version 2 → 4" in s.meta()["migrated"] and len(s) == 1
        assert save_census(s, take_census(s, "4_1")) == 1
        assert stored_census(s)[0]["states"][0]["name"] == "other"
