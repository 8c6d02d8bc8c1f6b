"""Errors of the results store. All are :class:`ValueError` s: a wrong path, a foreign or newer
file, a key collision are user-facing problems that the command line reports in one line."""

from __future__ import annotations

__all__ = ["StoreError", "SchemaVersionError", "KeyCollisionError"]


class StoreError(ValueError):
    """The database cannot be used: not an SQLite file, not a stiffknots database, missing."""


class SchemaVersionError(StoreError):
    """The database was written with another schema version than this code reads."""


class KeyCollisionError(StoreError):
    """Two different runs claim the same key (a setting that changes the result is missing
    from the settings hash)."""
