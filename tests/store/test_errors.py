"""The store's errors (store/errors): another schema version, foreign files, a key claimed by
two runs."""

from __future__ import annotations

import sqlite3

import pytest

from stiffknots.store import (
    KeyCollisionError,
    SchemaVersionError,
    Store,
    StoreError,
)
from store_support import (
    chain,
    make_row,
)


def test_schema_version_mismatch_is_a_clear_error(tmp_path):
    path = tmp_path / "x.db"
    Store(path).close()
    con = sqlite3.connect(path)
    con.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with pytest.raises(SchemaVersionError, match=r"schema version 99.*reads version 4.*Upgrade"):
        Store(path)
    con = sqlite3.connect(path)
    con.execute("UPDATE meta SET value = '0' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with pytest.raises(SchemaVersionError, match="No migration"):
        Store(path)


def test_foreign_files_are_refused(tmp_path):
    text = tmp_path / "notes.db"
    text.write_text("not a database at all, just some text that is long enough")
    with pytest.raises(StoreError, match="not an SQLite database"):
        Store(text)
    other = tmp_path / "other.db"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    with pytest.raises(StoreError, match="not a stiffknots results database"):
        Store(other)
    with pytest.raises(StoreError, match="no results database"):
        Store(tmp_path / "missing.db", create=False)
    assert not (tmp_path / "missing.db").exists()
    with pytest.raises(StoreError, match="folder"):
        Store(tmp_path)


def test_same_key_from_another_start_is_a_collision(store):
    store.put(make_row(start="braid", replica_seed=11), chain())
    assert store.put(make_row(start="braid", replica_seed=11), chain()) is False
    with pytest.raises(KeyCollisionError, match="start 'braid'.*'cage'"):
        store.put(make_row(start="cage"), chain())
    with pytest.raises(KeyCollisionError, match="replica_seed"):
        store.put(make_row(replica_seed=12), chain())
    assert len(store) == 1
