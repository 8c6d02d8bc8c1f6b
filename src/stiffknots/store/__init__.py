"""Results store: one SQLite database of annealed replicas, their states and the queries on it.

Layer: above :mod:`stiffknots.problems` (which produce the rows) and below the studies and the
command line; it imports only the standard library, numpy, and from stiffknots ``_version``,
``_json`` and (for grouping states) :mod:`stiffknots.analysis` — never the engine.

Public API
----------
:class:`Store`
    ``put``/``put_many`` (idempotent, atomic), ``has``, ``keys``, ``count``, ``replicas``,
    ``get``, ``coords``, ``knots``, ``ensembles``, ``states``, ``ground_states``, ``check``.
:func:`settings_hash`, :class:`ReplicaKey`
    The key of a replica (what a sweep skips when resuming).
:data:`SCHEMA_VERSION`
    The schema (every column documented in :mod:`stiffknots.store.schema`).
:func:`describe_knot`, :func:`ground_table`, :func:`to_csv`
    The questions ``stiffknots db`` answers, as plain data.
:func:`row_from_replica`
    The row of an engine replica result.
:func:`take_census`, :func:`save_census`, :func:`stored_census`
    The distinct states of a knot at one width (:mod:`stiffknots.store.census`).
"""

from stiffknots.store.census import save_census, stored_census, take_census
from stiffknots.store.errors import KeyCollisionError, SchemaVersionError, StoreError
from stiffknots.store.keys import (
    KEY_FIELDS,
    ReplicaKey,
    canonical_json,
    knot_sort_key,
    settings_hash,
    thickness_key,
)
from stiffknots.store.queries import describe_knot, ground_table, to_csv
from stiffknots.store.rows import OPTIONAL, REQUIRED, SEEDED_START, row_from_replica, search_of
from stiffknots.store.schema import SCHEMA_VERSION
from stiffknots.store.sqlite import DEFAULT_PATH, Store

__all__ = ["Store", "DEFAULT_PATH", "ReplicaKey", "KEY_FIELDS", "settings_hash",
           "canonical_json", "thickness_key", "knot_sort_key", "SCHEMA_VERSION", "REQUIRED",
           "OPTIONAL", "SEEDED_START", "row_from_replica", "search_of", "describe_knot",
           "ground_table", "to_csv", "take_census", "save_census", "stored_census",
           "StoreError", "SchemaVersionError", "KeyCollisionError"]
