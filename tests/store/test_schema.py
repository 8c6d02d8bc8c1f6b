"""The store's schema (store/schema): WAL and the version, the blob checked behind the API, the
shape labels."""

from __future__ import annotations

import sqlite3

import pytest

from stiffknots._version import __version__
from stiffknots.store import (
    SCHEMA_VERSION,
    Store,
)
from stiffknots.store.rows import SHAPES
from stiffknots.store.schema import COLUMNS
from store_support import (
    chain,
    make_row,
)


def test_new_database_is_wal_and_versioned(tmp_path):
    path = tmp_path / "a" / "b" / "x.db"
    with Store(path) as s:
        assert s.meta()["schema_version"] == str(SCHEMA_VERSION)
        assert s.meta()["created_by"] == f"stiffknots {__version__}"
        assert len(s) == 0 and s.knots() == []
    con = sqlite3.connect(path)
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    cols = [r[1] for r in con.execute("PRAGMA table_info(replicas)")]
    assert tuple(cols) == COLUMNS
    con.close()
    Store(path).close()  # reopening an existing database works


def test_schema_refuses_a_short_blob_even_behind_the_api(store):
    store.put(make_row(), chain())
    con = sqlite3.connect(store.path)
    with pytest.raises(sqlite3.IntegrityError, match="CHECK"):
        con.execute("UPDATE replicas SET coords = zeroblob(100)")
    con.close()


def test_shape_labels_match_the_classifier():
    from stiffknots.analysis.shapes import LABELS

    assert tuple(SHAPES) == tuple(LABELS)


def _as_version_1(path):
    """Turn a new database into one of schema version 1 (no audits or census table), as the
    releases before the audit wrote it."""
    con = sqlite3.connect(path)
    con.execute("DROP TABLE audits")
    con.execute("DROP TABLE census")
    con.execute("DROP TABLE thin")
    con.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    con.commit()
    con.close()


def test_a_version_1_database_is_read_as_it_is_and_migrated_when_written(tmp_path):
    path = tmp_path / "old.db"
    with Store(path) as s:
        s.put(make_row(), chain())
    _as_version_1(path)
    with Store(path, readonly=True) as s:  # a query writes nothing: no migration
        assert s.meta()["schema_version"] == "1"
        assert len(s) == 1 and s.audits() == []
    with Store(path) as s:  # opened for writing: migrated, its replicas kept
        assert s.meta()["schema_version"] == str(SCHEMA_VERSION) == "4"
        assert "version 1 → 4" in s.meta()["migrated"]
        assert len(s) == 1 and s.audits() == []
    con = sqlite3.connect(path)
    tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    con.close()
    assert {"audits", "census", "thin"} <= tables


def test_audit_rows_round_trip_and_replace_their_key(tmp_path):
    row = {"audit": "0123456789abcdef", "created": "2026-12-06T10:00:00+00:00",
           "version": "test", "knot": "3_1", "exclusion": "tube", "beads": 150,
           "thickness_key": "0.707106781187", "settings_hash": "a" * 16, "w_over_L": 0.0047,
           "epsilon": 100.0, "state": "CB(i=2)", "audit_settings_hash": "b" * 16,
           "audit_seed": 7, "searches": 3, "audit_epsilon": 90.0, "audit_state": "CB(i=2)",
           "false_verdict": 1, "params": {"sample": 1, "depth": 2}}
    with Store(tmp_path / "a.db") as s:
        assert s.put_audits([row]) == 1
        s.put_audits([{**row, "audit_epsilon": 100.0, "false_verdict": 0}])
        got = s.audits()
        assert len(got) == 1
        assert got[0]["false_verdict"] == 0 and got[0]["params"] == {"sample": 1, "depth": 2}
        assert s.audits(knot="4_1") == []
        with pytest.raises(ValueError, match="lacks audit_seed"):
            s.put_audits([{k: v for k, v in row.items() if k != "audit_seed"}])
