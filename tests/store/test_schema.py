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
