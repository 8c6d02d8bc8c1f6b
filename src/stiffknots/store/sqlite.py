"""The results store on SQLite: :class:`Store`.

Concurrency and safety
----------------------
* Every :class:`Store` opens its own connection; any number of processes may open the same file
  and write at once. The database is in WAL mode: readers never wait for the writer, writers
  queue (``busy_timeout``, default 60 s) and each write is one ``BEGIN IMMEDIATE … COMMIT``
  transaction, so a writer killed at any moment (``kill -9``) leaves the whole row or nothing;
  ``synchronous = FULL`` makes a committed row survive a power cut too.
* A Store may be shared by threads (a lock serialises its connection) and survives ``fork``
  (a child process opens a connection of its own on first use) and pickling (it pickles as its
  path, e.g. to a Dask worker). WAL needs a local file system: workers on other machines send
  their results to one process (the Dask client) that writes them.
* Writes are idempotent: a row whose key (:class:`~stiffknots.store.keys.ReplicaKey`) is stored
  is not written again (:meth:`Store.put` returns False), so a resumed sweep may rewrite
  whatever it is unsure of. If the stored row under that key has another ``start`` or
  ``replica_seed``, the two runs differ in something the settings hash does not cover:
  :class:`~stiffknots.store.errors.KeyCollisionError`.

States
------
Rows are grouped into states per *ensemble*: one knot, one exclusion model, one bead count,
one thickness (its key text) and one settings hash (:data:`~.schema.ENSEMBLE_FIELDS`).
Replicas of different seeds and starts of one run configuration are pooled;
rows that differ in N, width, model or any setting are never mixed into one state. Within an
ensemble the rule is that of :func:`stiffknots.analysis.states.group_states` (called with the
stored shape labels): same shape class and multiplicity, ε within ``rel_tol`` of the state's
lowest ε. A row stored without a shape is classified from its chain
(:func:`stiffknots.analysis.shapes.classify` with ``d`` = its thickness) when states are asked
for; nothing is written back.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sqlite3
import threading
import time
from collections import Counter, defaultdict
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from stiffknots._version import __version__
from stiffknots.store.errors import KeyCollisionError, SchemaVersionError, StoreError
from stiffknots.store.keys import (
    KEY_FIELDS,
    ReplicaKey,
    canonical_json,
    knot_sort_key,
    thickness_key,
)
from stiffknots.store.keys import settings_hash as hash_settings
from stiffknots.store.rows import blob_coords, decode_row, normalise_row, search_of
from stiffknots.store.schema import (
    APPLICATION_ID,
    AUDIT_COLUMNS,
    CENSUS_COLUMNS,
    COLUMNS,
    DDL,
    ENSEMBLE_FIELDS,
    MIGRATIONS,
    READABLE,
    ROW_COLUMNS,
    SCHEMA_VERSION,
    WIDTH_FIELDS,
)

__all__ = ["Store", "DEFAULT_PATH"]

#: Where :class:`Store` puts the database when no path is given (relative to the current
#: directory).
DEFAULT_PATH = Path("results") / "stiffknots.db"

_SQLITE_MAGIC = b"SQLite format 3\x00"

#: Filters the queries accept: column name → SQL column.
_FILTERS = {"knot": "knot", "exclusion": "exclusion", "beads": "beads",
            "thickness": "thickness_key", "thickness_key": "thickness_key", "seed": "seed",
            "replica": "replica", "settings_hash": "settings_hash", "problem": "problem",
            "shape": "shape", "multiplicity": "multiplicity", "start": "start",
            "version": "version", "converged": "converged", "knot_verified": "knot_verified"}

_INSERT = (f"INSERT INTO replicas ({', '.join(COLUMNS[1:])}) "
           f"VALUES ({', '.join(':' + c for c in COLUMNS[1:])}) "
           f"ON CONFLICT (knot, exclusion, beads, thickness_key, seed, replica, settings_hash) "
           f"DO NOTHING")
_KEY_WHERE = ("knot = ? AND exclusion = ? AND beads = ? AND thickness_key = ? AND seed = ? "
              "AND replica = ? AND settings_hash = ?")


def _os_error(fn) -> str | None:
    """The operating system's words for why ``fn()`` failed; None if it did not."""
    try:
        fn()
    except OSError as e:
        return e.strerror or type(e).__name__
    return None


def _probe(folder: Path) -> None:
    """Create and remove a file in ``folder`` (the -wal and -shm files go there)."""
    probe = folder / f".stiffknots-probe-{os.getpid()}"
    os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
    os.unlink(probe)


def _open_for(path: Path, doing: str) -> None:
    """Open the database file as SQLite would (and, for writing, its folder): an OSError
    names what stands in the way."""
    with open(path, "r+b" if doing == "writing" else "rb"):
        pass
    if doing == "writing":
        _probe(path.parent)


def _no_space(path: Path) -> bool:
    try:
        return os.statvfs(path.parent).f_bavail == 0
    except OSError:
        return False


def _key_params(key: ReplicaKey) -> tuple:
    return (key.knot, key.exclusion, key.beads, key.thickness_key, key.seed, key.replica,
            key.settings_hash)


def _where(filters: Mapping[str, Any]) -> tuple[str, list]:
    """SQL ``WHERE`` clause and parameters of query filters (scalars or collections)."""
    clauses, params = [], []
    for name, value in filters.items():
        if name not in _FILTERS:
            raise ValueError(f"unknown filter {name!r}; allowed: {', '.join(_FILTERS)}")
        if value is None:
            continue
        col = _FILTERS[name]
        values = list(value) if isinstance(value, list | tuple | set | frozenset) else [value]
        if name == "thickness":
            values = [thickness_key(v) for v in values]
        elif name in ("converged", "knot_verified"):
            values = [int(bool(v)) for v in values]
        if not values:
            clauses.append("0")
        elif len(values) == 1:
            clauses.append(f"{col} = ?")
        else:
            clauses.append(f"{col} IN ({', '.join('?' * len(values))})")
        params.extend(values)
    return (" WHERE " + " AND ".join(clauses)) if clauses else "", params


class Store:
    """The results database: one row per replica (schema in :mod:`stiffknots.store.schema`).

    Parameters
    ----------
    path : str or Path, optional
        The database file; default :data:`DEFAULT_PATH` (``results/stiffknots.db`` in the
        current directory). Parent folders are created.
    create : bool, default True
        Create the database if the file does not exist; False: raise :class:`StoreError`
        (for read-only tools that must not leave an empty database behind).
    readonly : bool, default False
        Open for reading only (queries): nothing is written, not even the schema into an
        empty file; a database on read-only media opens too. Implies ``create=False``.
    timeout : float, default 60
        Seconds a write waits for other writers (``busy_timeout``).

    Raises
    ------
    StoreError
        Not an SQLite file, not a stiffknots database, missing or empty (``create=False``), a
        file system without WAL support, or a file that cannot be opened for writing (or, with
        ``readonly``, for reading): the message says why in the operating system's words
        (read-only file system, operation not permitted, no space left on device).
    SchemaVersionError
        Written with another schema version.

    Examples
    --------
    >>> with Store("results/stiffknots.db") as db:             # doctest: +SKIP
    ...     db.put(row, coords)                                 # True, then False
    ...     db.states("5_2")["ground"]["name"]                  # '4C'
    """

    def __init__(self, path: str | os.PathLike | None = None, *, create: bool = True,
                 timeout: float = 60.0, readonly: bool = False) -> None:
        self._path = Path(DEFAULT_PATH if path is None else path)
        self._readonly = bool(readonly)
        self._create = bool(create) and not self._readonly
        self._timeout = float(timeout)
        self._lock = threading.RLock()
        self._abandoned: list[sqlite3.Connection] = []
        self._con: sqlite3.Connection | None = None
        self._pid = os.getpid()
        self._version = SCHEMA_VERSION  # a read-only store may read an older one
        self._con = self._connect()

    # ---- connection ------------------------------------------------------------------------

    @property
    def path(self) -> Path:
        """The database file."""
        return self._path

    def _connect(self) -> sqlite3.Connection:
        path = self._path
        if path.exists():
            if path.is_dir():
                raise StoreError(f"{path} is a folder; give the path of a database file")
            if path.stat().st_size > 0:
                with open(path, "rb") as f:
                    if f.read(16) != _SQLITE_MAGIC:
                        raise StoreError(f"{path} is not an SQLite database (not a stiffknots "
                                         f"results file); give another --db path")
            elif not self._create:  # a query must not write the schema into it
                raise StoreError(f"{path} is empty: no results database yet (run a sweep "
                                 f"first, or give the right --db path)")
        elif not self._create:
            raise StoreError(f"no results database at {path} (run a sweep first, or give the "
                             f"right --db path)")
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
        if self._readonly:
            return self._connect_readonly()
        created = not path.exists()
        try:
            con = sqlite3.connect(str(path), timeout=self._timeout, isolation_level=None,
                                  check_same_thread=False)
        except sqlite3.Error as e:
            raise self._cannot("writing", e) from None
        try:
            con.execute(f"PRAGMA busy_timeout = {int(self._timeout * 1000)}")
            self._setup(con)
            # a database that opens but cannot be written (a read-only or immutable file, an
            # existing schema: nothing was written yet) fails here, not at its first row
            con.execute("BEGIN IMMEDIATE")
            try:
                con.execute("UPDATE meta SET value = value WHERE key = 'schema_version'")
            finally:
                con.execute("ROLLBACK")
        except sqlite3.DatabaseError as e:
            con.close()
            self._forget(created)
            raise self._cannot("writing", e) from None
        except BaseException:
            con.close()
            self._forget(created)
            raise
        return con

    def _forget(self, created: bool) -> None:
        """A database this open created and could not set up (a full disk): its files go,
        not an empty database and 0-byte -wal and -shm files. Only while the file is still
        empty (never a database another process has written meanwhile)."""
        try:
            if not created or self._path.stat().st_size > 0:
                return
            self._path.unlink()
        except OSError:
            return
        for suffix in ("-wal", "-shm", "-journal"):
            with contextlib.suppress(OSError):
                os.unlink(f"{self._path}{suffix}")

    def _connect_readonly(self) -> sqlite3.Connection:
        """A connection that reads only (``mode=ro``). A WAL database on read-only media
        without its ``-shm`` file cannot be opened so: nothing can change it there, and it is
        opened as immutable."""
        from urllib.parse import quote

        path = self._path
        uri = f"file:{quote(str(path.resolve()))}?mode=ro"
        con = None
        try:
            try:
                con = sqlite3.connect(uri, uri=True, timeout=self._timeout,
                                      isolation_level=None, check_same_thread=False)
                version = self._schema_version(con)
            except sqlite3.OperationalError:
                if con is not None:
                    con.close()
                if _os_error(lambda: _probe(path.parent)) is None:
                    raise  # a writable folder: not the read-only media case
                con = sqlite3.connect(uri + "&immutable=1", uri=True, timeout=self._timeout,
                                      isolation_level=None, check_same_thread=False)
                version = self._schema_version(con)
            con.execute(f"PRAGMA busy_timeout = {int(self._timeout * 1000)}")
        except sqlite3.DatabaseError as e:
            if con is not None:
                con.close()
            raise self._cannot("reading", e) from None
        except BaseException:
            if con is not None:
                con.close()
            raise
        if version is None:
            con.close()
            raise StoreError(f"{path} holds no results database yet (no tables); run a sweep "
                             "first, or give the right --db path")
        if version not in READABLE:
            con.close()
            self._check_version(version)
        self._version = version
        return con

    def _cannot(self, doing: str, e: sqlite3.Error) -> StoreError:
        """The error of a database that SQLite could not open or set up: why, in the words of
        the operating system where it has them (a read-only file system, an immutable file, no
        space left on the device), else SQLite's (a damaged file)."""
        path = self._path
        why = _os_error(lambda: _open_for(path, doing))
        if why is not None or (doing == "writing" and _no_space(path)):
            return StoreError(f"{path}: cannot open the results database for {doing} "
                              f"({why or 'No space left on device'}; SQLite: {e})")
        text = str(e).lower()
        if any(w in text for w in ("readonly", "unable to open", "disk is full", "disk i/o")):
            return StoreError(f"{path}: cannot open the results database for {doing} ({e})")
        return StoreError(f"{path} is not a usable SQLite database: {e}")

    def _setup(self, con: sqlite3.Connection) -> None:
        """WAL mode, the pragmas and the schema. Switching a new file to WAL and creating the
        schema take locks for which SQLite does not always wait (``database is locked`` at
        once when several processes open a new database together, seen under load): the
        setup is retried until ``timeout``."""
        deadline = time.monotonic() + self._timeout
        while True:
            try:
                mode = con.execute("PRAGMA journal_mode = WAL").fetchone()[0]
                if str(mode).lower() != "wal":
                    raise StoreError(f"{self._path}: SQLite could not switch to WAL mode "
                                     f"(journal mode {mode!r}); put the database on a local "
                                     "file system")
                con.execute("PRAGMA synchronous = FULL")
                con.execute("PRAGMA foreign_keys = ON")
                self._init_schema(con)
                return
            except sqlite3.OperationalError as e:
                if "locked" not in str(e) or time.monotonic() > deadline:
                    raise
                if con.in_transaction:
                    con.rollback()
                time.sleep(0.05)

    def _schema_version(self, con: sqlite3.Connection) -> int | None:
        tables = {r[0] for r in con.execute(
            "SELECT name FROM sqlite_master WHERE type IN ('table', 'view')")}
        if "meta" not in tables:
            if tables:
                raise StoreError(f"{self._path} is an SQLite database but not a stiffknots "
                                 f"results database (tables: {', '.join(sorted(tables))})")
            return None
        row = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
        if row is None:
            raise StoreError(f"{self._path}: the meta table has no schema_version (not a "
                             f"stiffknots results database, or a damaged one)")
        try:
            return int(row[0])
        except ValueError:
            raise StoreError(f"{self._path}: schema_version {row[0]!r} is not an integer") \
                from None

    def _init_schema(self, con: sqlite3.Connection) -> None:
        version = self._schema_version(con)
        if version is None:
            con.execute("BEGIN IMMEDIATE")
            try:
                version = self._schema_version(con)  # another process may have created it
                if version is None:
                    for statement in DDL:
                        con.execute(statement)
                    now = datetime.now(UTC).isoformat(timespec="seconds")
                    con.executemany("INSERT INTO meta (key, value) VALUES (?, ?)",
                                    [("schema_version", str(SCHEMA_VERSION)),
                                     ("created", now),
                                     ("created_by", f"stiffknots {__version__}")])
                    con.execute(f"PRAGMA application_id = {APPLICATION_ID}")
                    version = SCHEMA_VERSION
                con.execute("COMMIT")
            except BaseException:
                if con.in_transaction:
                    con.execute("ROLLBACK")
                raise
        if version in MIGRATIONS:
            version = self._migrate(con)
        self._check_version(version)

    def _migrate(self, con: sqlite3.Connection) -> int:
        """Migrate an older database to :data:`SCHEMA_VERSION`, one version at a time, in one
        transaction (:data:`~stiffknots.store.schema.MIGRATIONS`); its replicas are kept as
        they are. Returns the version reached."""
        con.execute("BEGIN IMMEDIATE")
        try:
            version = self._schema_version(con)  # another process may have migrated it
            start = version
            while version in MIGRATIONS:
                for statement in MIGRATIONS[version]:
                    con.execute(statement)
                version += 1
            if version != start:
                now = datetime.now(UTC).isoformat(timespec="seconds")
                con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'",
                            (str(version),))
                con.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                            ("migrated", f"{now}: version {start} → {version} by "
                                         f"stiffknots {__version__}"))
            con.execute("COMMIT")
        except BaseException:
            if con.in_transaction:
                con.execute("ROLLBACK")
            raise
        return version

    def _check_version(self, version: int) -> None:
        if version != SCHEMA_VERSION:
            newer = version > SCHEMA_VERSION
            raise SchemaVersionError(
                f"{self._path} has results-database schema version {version}; this stiffknots "
                f"({__version__}) reads version {SCHEMA_VERSION}. "
                + ("Upgrade stiffknots to read it, or give another --db path."
                   if newer else
                   "No migration from that version exists; give another --db path."))

    def _conn(self) -> sqlite3.Connection:
        if self._con is None:
            raise StoreError(f"the results database {self._path} is closed")
        if os.getpid() != self._pid:
            # A forked child must not use its parent's connection; keep it referenced (closing
            # it here could disturb the parent) and open a connection of its own.
            self._abandoned.append(self._con)
            self._pid = os.getpid()
            self._con = self._connect()
        return self._con

    def close(self) -> None:
        """Close the connection (idempotent)."""
        with self._lock:
            if self._con is not None and os.getpid() == self._pid:
                self._con.close()
            self._con = None

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __reduce__(self):
        return (self.__class__, (str(self._path),), None)

    def __repr__(self) -> str:
        return f"Store({str(self._path)!r})"

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        """One write transaction (``BEGIN IMMEDIATE``): committed whole or rolled back."""
        with self._lock:
            con = self._conn()
            con.execute("BEGIN IMMEDIATE")
            try:
                yield con
                con.execute("COMMIT")
            except sqlite3.OperationalError as e:
                with contextlib.suppress(sqlite3.Error):
                    if con.in_transaction:
                        con.execute("ROLLBACK")
                text = str(e).lower()
                if "full" in text or "readonly" in text or "disk i/o" in text:
                    why = "no space left on the device" if "full" in text else str(e)
                    raise StoreError(f"{self._path}: cannot write the results database ({why}; "
                                     f"SQLite: {e}): this row was not stored, the rows stored "
                                     "before are kept") from None
                raise
            except BaseException:
                if con.in_transaction:
                    con.execute("ROLLBACK")
                raise

    def _query(self, sql: str, params: Iterable = ()) -> list[tuple]:
        with self._lock:
            return self._conn().execute(sql, tuple(params)).fetchall()

    # ---- writing ---------------------------------------------------------------------------

    def _insert(self, con: sqlite3.Connection, values: dict, key: ReplicaKey) -> bool:
        if con.execute(_INSERT, values).rowcount == 1:
            return True
        old = con.execute(f"SELECT id, start, replica_seed FROM replicas WHERE {_KEY_WHERE}",
                          _key_params(key)).fetchone()
        for name, stored in zip(("start", "replica_seed"), old[1:], strict=True):
            new = values[name]
            if stored is not None and new is not None and stored != new:
                raise KeyCollisionError(
                    f"key {key} is stored (row {old[0]}) with {name} {stored!r}, this row has "
                    f"{new!r}: the two runs differ in a setting that the settings hash does not "
                    f"cover — put it in the settings")
        return False

    def put(self, row: Mapping[str, Any], coords: Any) -> bool:
        """Store one replica and its chain, in one transaction; a stored key is a no-op.

        Parameters
        ----------
        row : mapping
            The fields of :data:`stiffknots.store.rows.REQUIRED` (``knot``, ``exclusion``,
            ``beads``, ``thickness``, ``seed``, ``replica``, ``settings``, ``epsilon``,
            ``min_segment_distance``, ``wall_seconds``) and any of
            :data:`~stiffknots.store.rows.OPTIONAL`; ``settings["problem"]`` must name the
            problem. Meaning of each: :mod:`stiffknots.store.schema`.
        coords : array_like, shape (beads, 3)
            The final chain (stored bit-exactly as float64).

        Returns
        -------
        bool
            True if the row was written, False if its key was already stored (nothing
            written; the first write wins).

        Raises
        ------
        ValueError
            A missing, unknown or bad field, non-finite numbers, coords not ``(beads, 3)``.
        KeyCollisionError
            The key is stored with another ``start`` or ``replica_seed``.
        """
        values, key = normalise_row(row, coords)
        with self._write() as con:
            return self._insert(con, values, key)

    def put_many(self, items: Iterable[tuple[Mapping[str, Any], Any]]) -> int:
        """Store several replicas in one transaction (all or none); stored keys are skipped.

        Every row is validated before anything is written.

        Parameters
        ----------
        items : iterable of (row, coords)

        Returns
        -------
        int
            Number of rows written.
        """
        checked = [normalise_row(row, coords) for row, coords in items]
        with self._write() as con:
            return sum(self._insert(con, values, key) for values, key in checked)

    # ---- keys and rows ---------------------------------------------------------------------

    def has(self, key: ReplicaKey) -> bool:
        """Whether a replica with this key is stored."""
        if not isinstance(key, ReplicaKey):
            raise ValueError(f"has() needs a ReplicaKey, got {type(key).__name__}")
        return bool(self._query(f"SELECT 1 FROM replicas WHERE {_KEY_WHERE}",
                                _key_params(key)))

    def keys(self, **filters: Any) -> set[ReplicaKey]:
        """The keys of the stored replicas (e.g. for a sweep to skip stored jobs).

        Parameters
        ----------
        **filters
            Column = value (or a list of values): ``knot``, ``exclusion``, ``beads``,
            ``thickness`` (compared by its 12-digit key), ``seed``, ``replica``,
            ``settings_hash``, ``problem``, ``shape``, ``start``, ``version``, ...
        """
        where, params = _where(filters)
        cols = ", ".join("thickness_key" if f == "thickness" else f for f in KEY_FIELDS)
        return {ReplicaKey(k, e, b, float(t), s, r, h)
                for k, e, b, t, s, r, h in self._query(f"SELECT {cols} FROM replicas{where}",
                                                       params)}

    def count(self, **filters: Any) -> int:
        """Number of stored replicas (filters as in :meth:`keys`)."""
        where, params = _where(filters)
        return int(self._query(f"SELECT count(*) FROM replicas{where}", params)[0][0])

    def __len__(self) -> int:
        return self.count()

    def replicas(self, **filters: Any) -> list[dict[str, Any]]:
        """Stored rows without their chains, ordered by ensemble then ε.

        Parameters
        ----------
        **filters
            As in :meth:`keys`.

        Returns
        -------
        list of dict
            Every column of :mod:`~stiffknots.store.schema` except ``coords``; ``settings``
            and ``extra`` parsed, ``converged``/``knot_verified`` as bool or None.
        """
        where, params = _where(filters)
        rows = self._query(f"SELECT {', '.join(ROW_COLUMNS)} FROM replicas{where} ORDER BY "
                           f"{', '.join(ENSEMBLE_FIELDS)}, epsilon, id", params)
        return [decode_row(ROW_COLUMNS, r) for r in rows]

    def get(self, id: int) -> dict[str, Any]:
        """One stored row (without its chain) by id; ValueError if there is none."""
        rows = self._query(f"SELECT {', '.join(ROW_COLUMNS)} FROM replicas WHERE id = ?",
                           (int(id),))
        if not rows:
            raise ValueError(f"no replica with id {id} in {self._path}")
        return decode_row(ROW_COLUMNS, rows[0])

    def coords(self, id: int, *, verify: bool = True) -> np.ndarray:
        """The chain of a stored replica: ``(beads, 3)`` float64, bit-exact as written.

        Raises
        ------
        ValueError
            No such id.
        StoreError
            ``verify`` and the blob's length or SHA-256 is wrong (a damaged database).
        """
        rows = self._query("SELECT coords, coords_sha256, beads FROM replicas WHERE id = ?",
                           (int(id),))
        if not rows:
            raise ValueError(f"no replica with id {id} in {self._path}")
        blob, digest, beads = rows[0]
        if verify and (len(blob) != 24 * beads
                       or hashlib.sha256(blob).hexdigest() != digest):
            raise StoreError(f"{self._path}: the chain of replica {id} is damaged (length or "
                             f"checksum wrong)")
        return blob_coords(blob, beads)

    def knots(self) -> list[str]:
        """The knots with stored replicas, in table order (``3_1``, ``4_1``, ..., ``10_1``)."""
        return sorted((r[0] for r in self._query("SELECT DISTINCT knot FROM replicas")),
                      key=knot_sort_key)

    def ensembles(self, **filters: Any) -> list[dict[str, Any]]:
        """The ensembles (sets of replicas grouped into states together) matching the filters.

        Returns
        -------
        list of dict
            ``knot``, ``exclusion``, ``beads``, ``thickness_key``, ``thickness``,
            ``w_over_L``, ``settings_hash``, ``problem``, ``replicas`` (count), ``eps_min``,
            ``eps_mean``; in knot-table order.
        """
        where, params = _where(filters)
        names = ("knot", "exclusion", "beads", "thickness_key", "thickness", "w_over_L",
                 "settings_hash", "problem", "replicas", "eps_min", "eps_mean")
        rows = self._query(
            f"SELECT {', '.join(ENSEMBLE_FIELDS)}, min(thickness), min(w_over_L), "
            f"min(problem), count(*), min(epsilon), avg(epsilon) FROM replicas{where} "
            f"GROUP BY {', '.join(ENSEMBLE_FIELDS)}", params)
        out = [dict(zip(names, (r[0], r[1], r[2], r[3], r[5], r[6], r[4], r[7], r[8], r[9],
                                r[10]), strict=True)) for r in rows]
        return sorted(out, key=_ensemble_order)

    # ---- states ----------------------------------------------------------------------------

    def states(self, knot: str, exclusion: str | None = None, beads: int | None = None,
               thickness: float | None = None, settings_hash: str | None = None, *,
               rel_tol: float = 0.01, structure: bool = True) -> dict[str, Any]:
        """Ground state and metastable states of one ensemble of a knot.

        The filters must select exactly one ensemble (one exclusion model, bead count,
        thickness and settings hash); see the module docstring for the grouping rule.

        Parameters
        ----------
        knot : str
        exclusion, beads, thickness, settings_hash : optional
            Needed only when the knot has several ensembles.
        rel_tol : float, default 0.01
            Relative ε tolerance of one state (:func:`~stiffknots.analysis.group_states`).
        structure : bool, default True
            Name every state's contact structure (``structure``, from its representative
            chain at the ensemble's thickness: :func:`~stiffknots.analysis.structure_name`,
            ≈ 1 ms a state); False leaves it None (a sweep's convergence checks).

        Returns
        -------
        dict
            The ensemble's fields, ``settings``, ``replicas`` (count), ``rel_tol``,
            ``classified`` (rows classified from their chains now), ``ground`` (a state) and
            ``metastable`` (states by increasing ε). A state: ``name`` (``"CB(i=2)"``,
            ``"4C"``, ...), ``structure`` (its line-braids, point-braids and multiple points
            in the words of §V B: ``"2 line-braids (m = 2) + double point"``), ``shape``,
            ``multiplicity``, ``epsilon`` (lowest), ``eps_mean``,
            ``eps_max``, ``count``, ``representative`` (row id of the lowest-ε replica) and
            its ``seed``, ``replica``, ``start``, ``min_segment_distance``, ``converged``,
            ``knot_verified``; ``converged_count``; ``eps_all`` (every member's ε,
            increasing); ``starts`` (start → count); ``eps_by_start`` (start → its members'
            ε, increasing); ``eps_by_search`` (search → its members' lowest ε; a sweep's
            continuation leg belongs to the search it continued:
            :func:`~stiffknots.store.rows.search_of`); ``ids``.

        Raises
        ------
        ValueError
            No replica matches, or several ensembles do (the message lists them).
        """
        filters = {"knot": knot, "exclusion": exclusion, "beads": beads,
                   "thickness": thickness, "settings_hash": settings_hash}
        ens = self.ensembles(**filters)
        if not ens:
            given = ", ".join(f"{k}={v!r}" for k, v in filters.items() if v is not None)
            known = self.knots()
            raise ValueError(f"no stored replicas with {given}"
                             + (f"; stored knots: {', '.join(known)}" if known
                                else f"; {self._path} is empty"))
        if len(ens) > 1:
            lines = "; ".join(f"exclusion={e['exclusion']} beads={e['beads']} "
                              f"thickness={e['thickness_key']} "
                              f"settings_hash={e['settings_hash']} ({e['replicas']} replicas)"
                              for e in ens)
            raise ValueError(f"{len(ens)} ensembles of {knot} match; choose one with exclusion, "
                             f"beads, thickness or settings_hash: {lines}")
        e = ens[0]
        rows = self.replicas(**{f: e[f] for f in ENSEMBLE_FIELDS})
        return self._group(rows, rel_tol, structure)

    def _structure_name(self, id: int, thickness: float) -> str | None:
        """The contact structure of a stored chain, named (§V B); None for a chain that is
        not a unit-bond chain obeying the bead rule at ``thickness`` (the analysis assumes
        one: on another its contacts mean little)."""
        from stiffknots.analysis.structure import ANALYSIS_BOND_TOL, analyse_structure
        from stiffknots.measures import chain_report

        x = self.coords(id)
        with np.errstate(all="ignore"):
            rep = chain_report(x, True, d=thickness, bond_tol=ANALYSIS_BOND_TOL,
                               segments=False, unit=None)
        if rep["problems"]:
            return None
        return analyse_structure(x, True, d=thickness).name

    def _group(self, rows: list[dict[str, Any]], rel_tol: float,
               structure: bool = True) -> dict[str, Any]:
        """States of the rows of one ensemble (see :meth:`states`)."""
        from stiffknots.analysis.states import group_states

        items, classified = [], 0
        for r in rows:
            label, mult = r["shape"], r["multiplicity"]
            if label is None:
                from stiffknots.analysis.shapes import classify

                s = classify(self.coords(r["id"]), True, d=r["thickness"])
                label, mult = s.label, s.multiplicity
                classified += 1
            items.append({"label": label, "multiplicity": mult, "epsilon": r["epsilon"]})
        groups = group_states(items, rel_tol)
        states = []
        for g in groups.states:
            members = [rows[k] for k in g.members]
            rep = rows[g.representative]
            states.append({
                "name": g.name,
                "structure": (self._structure_name(rep["id"], rep["thickness"])
                              if structure else None),
                "shape": g.label, "multiplicity": g.multiplicity,
                "epsilon": g.eps_min, "eps_mean": g.eps_mean, "eps_max": g.eps_max,
                "count": g.count, "representative": rep["id"], "seed": rep["seed"],
                "replica": rep["replica"], "start": rep["start"],
                "min_segment_distance": rep["min_segment_distance"],
                "converged": rep["converged"], "knot_verified": rep["knot_verified"],
                "converged_count": sum(m["converged"] is True for m in members),
                "eps_all": sorted(float(m["epsilon"]) for m in members),
                "starts": dict(Counter(m["start"] or "unknown" for m in members)),
                "eps_by_start": {st: sorted(float(m["epsilon"]) for m in members
                                            if (m["start"] or "unknown") == st)
                                 for st in dict.fromkeys(m["start"] or "unknown"
                                                         for m in members)},
                "ids": [m["id"] for m in members],
                "eps_by_search": _eps_by_search(members),
            })
        first = rows[0]
        return {"knot": first["knot"], "exclusion": first["exclusion"], "beads": first["beads"],
                "thickness": first["thickness"], "thickness_key": first["thickness_key"],
                "w_over_L": first["w_over_L"], "settings_hash": first["settings_hash"],
                "problem": first["problem"], "settings": first["settings"],
                "replicas": len(rows), "rel_tol": groups.rel_tol, "classified": classified,
                "ground": states[0], "metastable": states[1:]}

    def ground_states(self, knot: str | list[str] | None = None,
                      exclusion: str | None = None, beads: int | None = None,
                      thickness: float | None = None, problem: str | None = None,
                      settings_hash: str | None = None, *,
                      rel_tol: float = 0.01, structure: bool = True) -> list[dict[str, Any]]:
        """The ground state of every knot × exclusion × beads × thickness (a flat table).

        States are grouped per ensemble (module docstring); when one knot × exclusion × beads ×
        thickness has several settings, the row shows the ensemble whose ground state has the
        lowest ε (``settings_hash``; ``n_settings`` says how many there were). The filters
        (``knot`` — one name or a list —, ``exclusion``, ``beads``, ``thickness``, ``problem``,
        ``settings_hash``) select the rows first; ``structure=False`` leaves the ground
        state's ``structure`` None (see :meth:`states`).

        Returns
        -------
        list of dict
            One per knot × exclusion × beads × thickness, in knot-table order: ``knot``,
            ``exclusion``, ``beads``, ``thickness``, ``w_over_L``, ``state`` (name),
            ``structure`` (its contact structure named, :meth:`states`), ``shape``,
            ``multiplicity``, ``epsilon``, ``eps_mean``, ``count``, ``eps_all``, ``replicas``,
            ``n_states``, ``metastable`` (``"80 147.30 ×3; CB(i=3) 181.20 ×1"``), ``id``,
            ``seed``, ``replica``, ``start``, ``min_segment_distance``, ``converged``,
            ``knot_verified``, ``settings_hash``, ``n_settings``, ``problem``, ``version``,
            ``start_policy`` (the settings' ``start``) and ``starts_tried`` (the starts of
            the ensemble's replicas).
        """
        rows = self.replicas(knot=knot, exclusion=exclusion, beads=beads, thickness=thickness,
                             problem=problem, settings_hash=settings_hash)
        by_ensemble: dict[tuple, list[dict]] = defaultdict(list)
        for r in rows:
            by_ensemble[tuple(r[f] for f in ENSEMBLE_FIELDS)].append(r)
        by_model: dict[tuple, list[dict]] = defaultdict(list)
        for ens_key, ens_rows in by_ensemble.items():
            by_model[ens_key[:4]].append(self._group(ens_rows, rel_tol, False))
        table = []
        for groups in by_model.values():
            best = min(groups, key=lambda g: (g["ground"]["epsilon"], -g["replicas"],
                                              g["settings_hash"]))
            gs = best["ground"]
            named = (self._structure_name(gs["representative"], best["thickness"])
                     if structure else None)
            version = next(r["version"] for r in by_ensemble[
                tuple(best[f] for f in ENSEMBLE_FIELDS)] if r["id"] == gs["representative"])
            table.append({
                "knot": best["knot"], "exclusion": best["exclusion"], "beads": best["beads"],
                "thickness": best["thickness"], "w_over_L": best["w_over_L"],
                "state": gs["name"], "structure": named, "shape": gs["shape"],
                "multiplicity": gs["multiplicity"],
                "epsilon": gs["epsilon"], "eps_mean": gs["eps_mean"], "count": gs["count"],
                "eps_all": gs["eps_all"], "eps_by_start": gs["eps_by_start"],
                "eps_by_search": gs["eps_by_search"],
                "replicas": best["replicas"], "n_states": 1 + len(best["metastable"]),
                "metastable": "; ".join(f"{s['name']} {s['epsilon']:.2f} ×{s['count']}"
                                        for s in best["metastable"]),
                "id": gs["representative"], "seed": gs["seed"], "replica": gs["replica"],
                "start": gs["start"], "min_segment_distance": gs["min_segment_distance"],
                "converged": gs["converged"], "knot_verified": gs["knot_verified"],
                "settings_hash": best["settings_hash"], "n_settings": len(groups),
                "problem": best["problem"], "version": version,
                "start_policy": (best["settings"] or {}).get("start"),
                "starts_tried": sorted({k for st in [gs, *best["metastable"]]
                                        for k in (st.get("starts") or {})}),
            })
        return sorted(table, key=_ensemble_order)

    # ---- maintenance -----------------------------------------------------------------------

    def check(self) -> dict[str, Any]:
        """Check the whole database: SQLite's ``integrity_check`` and every stored chain.

        Returns
        -------
        dict
            ``ok`` (bool), ``integrity`` (SQLite's messages; ``["ok"]`` when sound), ``rows``,
            ``bad_coords`` (ids whose blob length or SHA-256 is wrong), ``bad_settings`` (ids
            whose settings do not hash to their ``settings_hash``).
        """
        with self._lock:
            con = self._conn()
            integrity = [r[0] for r in con.execute("PRAGMA integrity_check")]
            bad_coords, bad_settings, n = [], [], 0
            for id_, beads, blob, digest, h, settings in con.execute(
                    "SELECT id, beads, coords, coords_sha256, settings_hash, settings "
                    "FROM replicas"):
                n += 1
                if (not isinstance(blob, bytes) or len(blob) != 24 * beads
                        or hashlib.sha256(blob).hexdigest() != digest):
                    bad_coords.append(id_)
                try:
                    if hash_settings(json.loads(settings)) != h:
                        bad_settings.append(id_)
                except ValueError:
                    bad_settings.append(id_)
        return {"ok": integrity == ["ok"] and not bad_coords and not bad_settings,
                "integrity": integrity, "rows": n, "bad_coords": bad_coords,
                "bad_settings": bad_settings}

    def meta(self) -> dict[str, str]:
        """The ``meta`` table (``schema_version``, ``created``, ``created_by``)."""
        return dict(self._query("SELECT key, value FROM meta"))

    # ---- audits ----------------------------------------------------------------------------

    def put_audits(self, rows: Iterable[Mapping[str, Any]]) -> int:
        """Write audit rows (:mod:`stiffknots.sweeps.audit`; the columns of
        :data:`~stiffknots.store.schema.AUDIT_COLUMNS` but ``id``), in one transaction; a row
        whose key (audit, ensemble) is stored replaces it. Returns the rows written."""
        cols = AUDIT_COLUMNS[1:]
        sql = (f"INSERT OR REPLACE INTO audits ({', '.join(cols)}) "
               f"VALUES ({', '.join(':' + c for c in cols)})")
        rows = [dict(r) for r in rows]
        for r in rows:
            missing = [c for c in cols if c not in r]
            if missing:
                raise ValueError(f"an audit row lacks {', '.join(missing)}")
            if not isinstance(r["params"], str):
                r["params"] = canonical_json(r["params"])
        with self._write() as con:
            con.executemany(sql, [{c: r[c] for c in cols} for r in rows])
        return len(rows)

    def audits(self, knot: str | list[str] | None = None, exclusion: str | None = None,
               audit: str | None = None) -> list[dict[str, Any]]:
        """Stored audit rows (``params`` decoded), in knot-table order then newest first;
        none in a version-1 database read as it is."""
        if self._version < 2:
            return []
        where, params = _in_where((("knot", knot), ("exclusion", exclusion), ("audit", audit)))
        out = []
        for r in self._query(f"SELECT {', '.join(AUDIT_COLUMNS)} FROM audits{where}", params):
            d = dict(zip(AUDIT_COLUMNS, r, strict=True))
            d["params"] = json.loads(d["params"])
            out.append(d)
        out.sort(key=lambda d: d["created"], reverse=True)
        out.sort(key=lambda d: knot_sort_key(d["knot"]))
        return out


    # ---- census ----------------------------------------------------------------------------

    def put_census(self, rows: Iterable[Mapping[str, Any]]) -> int:
        """Write the rows of one or more censuses (the columns of
        :data:`~stiffknots.store.schema.CENSUS_COLUMNS` but ``id``; :mod:`stiffknots.store.census`)
        in one transaction. The rows stored under each (census, knot and width) written are
        deleted first: a census computed again replaces the old one whole. Returns the rows
        written."""
        cols = CENSUS_COLUMNS[1:]
        rows = [dict(r) for r in rows]
        for r in rows:
            missing = [c for c in cols if c not in r]
            if missing:
                raise ValueError(f"a census row lacks {', '.join(missing)}")
            if not isinstance(r["params"], str):
                r["params"] = canonical_json(r["params"])
            if not isinstance(r["settings"], str):
                r["settings"] = json.dumps(sorted(r["settings"]))
        if self._version < 3:
            raise StoreError(f"{self._path} is a schema-version-{self._version} database "
                             "opened read-only: it has no census table (open it for writing "
                             "to migrate it)")
        keys = {tuple(r[c] for c in ("census", *WIDTH_FIELDS)) for r in rows}
        where = " AND ".join(f"{c} = ?" for c in ("census", *WIDTH_FIELDS))
        sql = (f"INSERT INTO census ({', '.join(cols)}) "
               f"VALUES ({', '.join(':' + c for c in cols)})")
        with self._write() as con:
            for k in keys:
                con.execute(f"DELETE FROM census WHERE {where}", k)
            con.executemany(sql, [{c: r[c] for c in cols} for r in rows])
        return len(rows)

    def census_rows(self, knot: str | list[str] | None = None,
                    exclusion: str | None = None) -> list[dict[str, Any]]:
        """Stored census rows (``params`` and ``settings`` decoded), in knot-table order, then
        width, newest census first, then state; none in a database of schema version < 3 read
        as it is."""
        if self._version < 3:
            return []
        where, params = _in_where((("knot", knot), ("exclusion", exclusion)))
        out = []
        for r in self._query(f"SELECT {', '.join(CENSUS_COLUMNS)} FROM census{where}", params):
            d = dict(zip(CENSUS_COLUMNS, r, strict=True))
            d["params"] = json.loads(d["params"])
            d["settings"] = json.loads(d["settings"])
            out.append(d)
        out.sort(key=lambda d: d["state"])
        out.sort(key=lambda d: d["created"], reverse=True)
        out.sort(key=lambda d: (knot_sort_key(d["knot"]), d["exclusion"], d["beads"],
                                float(d["thickness_key"])))
        return out


def _in_where(pairs: Iterable[tuple[str, Any]]) -> tuple[str, list]:
    """``WHERE col IN (...) AND ...`` for the (column, value or list of values) pairs whose
    value is not None, and its parameters (the audits' and the census's filters)."""
    clauses, params = [], []
    for col, value in pairs:
        if value is None:
            continue
        values = list(value) if isinstance(value, list | tuple) else [value]
        clauses.append(f"{col} IN ({', '.join('?' * len(values))})")
        params.extend(values)
    return (" WHERE " + " AND ".join(clauses)) if clauses else "", params


def _eps_by_search(members: Iterable[Mapping[str, Any]]) -> dict[str, float]:
    """A state's members by search (:func:`~stiffknots.store.rows.search_of`): search →
    the lowest ε of its members in the state (keys as text, for JSON)."""
    out: dict[str, float] = {}
    for m in members:
        k = str(search_of(m))
        out[k] = min(out.get(k, float("inf")), float(m["epsilon"]))
    return out


def _ensemble_order(d: Mapping[str, Any]) -> tuple:
    return (knot_sort_key(d["knot"]), d["exclusion"], d["beads"], float(d["thickness"]),
            d.get("settings_hash", ""))
