"""Schema of the results database (SQLite), version 4.

One file (default ``results/stiffknots.db``; ``--db PATH``), journal mode WAL (readers never
block the writer, a killed writer never leaves a half-written row), one row per annealed
replica. Plain SQLite: any SQLite ≥ 3.24 reads it (``sqlite3 results/stiffknots.db``); no
``STRICT`` tables, so old SQLite builds can open it — the column types are enforced by ``CHECK``
constraints and by :meth:`Store.put <stiffknots.store.sqlite.Store.put>` instead.

Versioning
----------
The ``meta`` table holds ``schema_version`` (this module's :data:`SCHEMA_VERSION`), the UTC time
the database was created and the stiffknots version that created it; ``PRAGMA application_id``
is :data:`APPLICATION_ID` (``"SKNT"``). Opening a database of another schema version raises
:class:`~stiffknots.store.errors.SchemaVersionError` naming both versions; a change of the
schema bumps :data:`SCHEMA_VERSION` and adds a migration.

Table ``replicas``
------------------
One row per replica. Key: ``UNIQUE(knot, exclusion, beads, thickness_key, seed, replica,
settings_hash)`` — writing a replica whose key is stored is a no-op (the first write wins).

=====================  ========  ==========================================================
column                 type      meaning
=====================  ========  ==========================================================
id                     INTEGER   row id (primary key, assigned by SQLite)
knot                   TEXT      knot name as the catalogue writes it (``5_2``)  [key]
exclusion              TEXT      exclusion model, ``bead`` or ``tube``  [key]
beads                  INTEGER   number of beads N (≥ 3)  [key]
thickness              REAL      exclusion width: bead distance d (bead) or tube diameter w
                                 (tube), bond length 1; exact value as run
thickness_key          TEXT      the thickness rounded to 12 significant digits, as text
                                 (``0.707106781187``): the key's form of it  [key]
w_over_L               REAL      thickness / contour length (L = N closed, N − 1 open)
seed                   INTEGER   the run's (user) seed, 0 ≤ seed < 2⁶³  [key]
replica                INTEGER   replica index within the run (≥ 0)  [key]
replica_seed           INTEGER   the seed the engine derived for this replica (NULL: unknown)
settings_hash          TEXT      16 hex digits, SHA-256 of the canonical settings JSON  [key]
settings               TEXT      the canonical settings JSON itself (what was hashed)
problem                TEXT      the problem solved (``anneal``, ...); also in the settings
version                TEXT      stiffknots version that computed the replica
epsilon                REAL      final normalised energy ε = E·L/C (ε = E_d·N/C for the chain)
shape                  TEXT      shape class ``CB``, ``4C``, ``80`` or ``other``; NULL: not
                                 classified (then states classify the stored chain)
multiplicity           INTEGER   circular-braid index i for ``CB`` (≥ 1), NULL otherwise
min_segment_distance   REAL      smallest distance between non-adjacent segments of the chain
converged              INTEGER   1 / 0: the run's convergence test passed / failed; NULL: none
start                  TEXT      starting embedding of this replica (``braid``, ``cage``,
                                 ``80``, ...); NULL: unknown
wall_seconds           REAL      wall-clock seconds of the replica's run
cpu_seconds            REAL      CPU seconds of the replica's run (NULL: not measured)
knot_verified          INTEGER   1: the final chain's knot type was checked and equals
                                 ``knot``; 0: checked and differs; NULL: not checked
created                TEXT      UTC time the row was written (ISO 8601)
extra                  TEXT      JSON object of everything else the run reported (energies,
                                 acceptance, bond error, stage energies, tempering, ...)
coords                 BLOB      the final chain: N × 3 float64, little-endian, row-major
                                 (x0 y0 z0 x1 ...), exactly 24·N bytes (CHECK)
coords_sha256          TEXT      SHA-256 (64 hex digits) of ``coords``
=====================  ========  ==========================================================

Indexes: the unique key (also serves look-ups by knot, by knot and model, ...),
``replicas_ensemble`` on ``(knot, exclusion, beads, thickness_key, settings_hash, epsilon)``
(states of one ensemble, in ε order) and ``replicas_settings`` on ``settings_hash`` (a sweep
listing the keys of one settings).

View ``ensembles``: one row per ensemble — replicas of one knot with the same exclusion model,
bead count, thickness and settings, the set whose states are grouped together (see
:meth:`Store.states <stiffknots.store.sqlite.Store.states>`) — with its replica count and its
lowest and mean ε.

Table ``audits`` (version 2)
----------------------------
One row per audited ensemble and audit (:mod:`stiffknots.sweeps.audit`): a converged ground
state searched again by independent searches. Key: ``UNIQUE(audit, knot, exclusion, beads,
thickness_key, settings_hash)`` — an audit run again replaces its rows.

=====================  ========  ==========================================================
column                 type      meaning
=====================  ========  ==========================================================
id                     INTEGER   row id
audit                  TEXT      16 hex digits: the hash of the audit's parameters (``params``)
created                TEXT      UTC time the row was written (ISO 8601)
version                TEXT      stiffknots version of the audit
knot, exclusion,       …         the audited ensemble (as in ``replicas``)
beads, thickness_key,
settings_hash
w_over_L               REAL      its w/L
epsilon                REAL      the ε of its converged ground state
state                  TEXT      that state's name (``CB(i=2)``, ``80``, ...)
audit_settings_hash    TEXT      the settings of the audit's searches (their ensemble in
                                 ``replicas``, problem ``audit``)
audit_seed             INTEGER   the seed of the audit's searches
searches               INTEGER   how many audit searches ended
audit_epsilon          REAL      the lowest ε they reached (NULL: none ended)
audit_state            TEXT      the name of that state
false_verdict          INTEGER   1: a search went lower than ``epsilon`` by more than the
                                 tolerance (the verdict was false); 0: none did
params                 TEXT      the audit's parameters (JSON: sample, seed, depth,
                                 replicas, models, tolerance)
=====================  ========  ==========================================================

Table ``census`` (version 3)
----------------------------
One row per state of a stored census (:mod:`stiffknots.store.census`): the distinct states that
every stored search of a knot at one width (one model, N and thickness; all settings pooled)
found within a window of the lowest ε (:func:`stiffknots.analysis.census`). Key:
``UNIQUE(census, knot, exclusion, beads, thickness_key, state)``; a census of a knot at a width
computed again with the same parameters replaces all its rows.

=====================  ========  ==========================================================
column                 type      meaning
=====================  ========  ==========================================================
id                     INTEGER   row id
census                 TEXT      16 hex digits: the hash of the census's parameters
created                TEXT      UTC time the row was written (ISO 8601)
version                TEXT      stiffknots version that computed it
knot, exclusion,       …         the knot and width (as in ``replicas``)
beads, thickness_key
w_over_L               REAL      its w/L
settings               TEXT      JSON list of the settings hashes of the pooled runs
state                  INTEGER   0, 1, ...: the state's rank by increasing ε (0 = lowest)
name                   TEXT      ``CB(i=2)``, ``4C``, ``80``, ``other``
shape                  TEXT      shape class; ``multiplicity`` INTEGER its braid index (CB)
multiplicity           INTEGER
structure              TEXT      the representative's structure in the words of §V B (NULL:
                                 not read)
epsilon                REAL      the state's lowest ε
eps_max                REAL      its highest ε
count                  INTEGER   replicas (rows) in the state
searches               INTEGER   independent searches that ended in it
representative         INTEGER   ``replicas.id`` of its lowest chain
spread                 REAL      largest shape distance / L of a member from it
replicas               INTEGER   rows pooled when the census was taken
params                 TEXT      the census's parameters (JSON: window, rel_tol,
                                 max_distance, points)
=====================  ========  ==========================================================

Table ``thin`` (version 4)
--------------------------
One row per state of a knot's census followed to w = 0 by the atlas's thin stage
(:mod:`stiffknots.studies.thin_stage`, :func:`stiffknots.studies.thin_states.follow_census`). The
states of one knot are followed in one job and written in one transaction, under the job's
``run`` key (its knot and width, the census's states, budget, seed and version): a thin stage
run again skips every run stored. Key: ``UNIQUE(run, state)``.

=====================  ========  ==========================================================
column                 type      meaning
=====================  ========  ==========================================================
id                     INTEGER   row id
run                    TEXT      16 hex digits: the job's key
created, version       TEXT      UTC time written; stiffknots version
knot, exclusion,       …         the knot and the width its census was taken at (as in
beads, thickness_key             ``replicas``)
w_over_L               REAL      that width's w/L
census                 TEXT      the census's parameters' hash (table ``census``)
budget                 TEXT      ``small`` or ``default``
                                 (:data:`stiffknots.studies.thin_states.BUDGETS`)
seed                   INTEGER   seed of every relaxation
state                  INTEGER   the state's rank in the census (0 = lowest at that width)
name                   TEXT      its name (``CB(i=2)``, ``4C``, ``80``, ``other``)
representative         INTEGER   ``replicas.id`` of the chain it was followed from
epsilon                REAL      its ε at the census's width
epsilon_thin           REAL      ε*_s extrapolated to w = 0 (NULL: the branch jumped or
                                 merged: no limit of its own)
error                  REAL      its error
event                  TEXT      NULL, ``jumped`` or ``merged`` (what ended the fit)
shape_thin             TEXT      its shape class at the thinnest width
structure_epsilon      REAL      ε at w = 0 by the structure route (NULL: none)
structure_error        REAL      its error
structure_name         TEXT      the structure solved
agree                  INTEGER   1 / 0: the two routes agree / do not; NULL: not compared
ground                 INTEGER   1: this state is its knot's thin-limit ground (lowest
                                 ``epsilon_thin`` of the run)
details                TEXT      JSON: the points of the branch (w/L, N, ε), its events,
                                 fit, discretisation and parameters, the structure route
                                 (with the w = 0 curves), the run's margin and crossing
chain                  BLOB      the thinnest chain still in the state: N × 3 float64
beads_thin             INTEGER   its N (CHECK: length(chain) = 24 · beads_thin)
cpu_seconds            REAL      CPU seconds of the knot's job (on every row of the run)
=====================  ========  ==========================================================

Table ``meta``: ``key``/``value`` text pairs (``schema_version``, ``created``,
``created_by``, and ``migrated`` once a database was migrated).

Migrations: a database of an older version opened for writing is migrated in one transaction
(:data:`MIGRATIONS`: version 1 → 2 adds ``audits``, 2 → 3 ``census``, 3 → 4 ``thin``);
opened read-only it is read as it is (:data:`READABLE`: a version-1 database has no audits, a
version-2 one no census, a version-3 one no thin stage).
"""

from __future__ import annotations

__all__ = ["SCHEMA_VERSION", "READABLE", "MIGRATIONS", "APPLICATION_ID", "DDL", "COLUMNS",
           "ROW_COLUMNS", "ENSEMBLE_FIELDS", "AUDIT_COLUMNS", "CENSUS_COLUMNS",
           "THIN_COLUMNS", "WIDTH_FIELDS"]

#: Version of the schema this code writes and reads.
SCHEMA_VERSION = 4
#: The versions a read-only store reads as they are (no migration: it writes nothing).
READABLE = (1, 2, 3, 4)

#: ``PRAGMA application_id`` of a stiffknots results database (the bytes ``"SKNT"``).
APPLICATION_ID = int.from_bytes(b"SKNT", "big")

#: Fields that define a width of a knot: the runs a census pools.
WIDTH_FIELDS = ("knot", "exclusion", "beads", "thickness_key")

#: Fields that define an ensemble: replicas grouped into states together.
ENSEMBLE_FIELDS = ("knot", "exclusion", "beads", "thickness_key", "settings_hash")

_REPLICAS = """
CREATE TABLE IF NOT EXISTS replicas (
    id                   INTEGER PRIMARY KEY,
    knot                 TEXT    NOT NULL CHECK (typeof(knot) = 'text' AND length(knot) > 0),
    exclusion            TEXT    NOT NULL CHECK (exclusion IN ('bead', 'tube')),
    beads                INTEGER NOT NULL CHECK (typeof(beads) = 'integer' AND beads >= 3),
    thickness            REAL    NOT NULL CHECK (typeof(thickness) = 'real' AND thickness > 0),
    thickness_key        TEXT    NOT NULL CHECK (typeof(thickness_key) = 'text'),
    w_over_L             REAL    NOT NULL CHECK (typeof(w_over_L) = 'real' AND w_over_L > 0),
    seed                 INTEGER NOT NULL CHECK (typeof(seed) = 'integer' AND seed >= 0),
    replica              INTEGER NOT NULL CHECK (typeof(replica) = 'integer' AND replica >= 0),
    replica_seed         INTEGER CHECK (replica_seed IS NULL OR typeof(replica_seed) = 'integer'),
    settings_hash        TEXT    NOT NULL CHECK (length(settings_hash) = 16),
    settings             TEXT    NOT NULL,
    problem              TEXT    NOT NULL CHECK (length(problem) > 0),
    version              TEXT    NOT NULL,
    epsilon              REAL    NOT NULL CHECK (typeof(epsilon) = 'real'),
    shape                TEXT    CHECK (shape IS NULL OR shape IN ('CB', '4C', '80', 'other')),
    multiplicity         INTEGER CHECK (CASE WHEN shape IS 'CB'
                                             THEN typeof(multiplicity) = 'integer'
                                                  AND multiplicity >= 1
                                             ELSE multiplicity IS NULL END),
    min_segment_distance REAL    NOT NULL CHECK (typeof(min_segment_distance) = 'real'),
    converged            INTEGER CHECK (converged IS NULL OR converged IN (0, 1)),
    start                TEXT,
    wall_seconds         REAL    NOT NULL CHECK (typeof(wall_seconds) = 'real'
                                                 AND wall_seconds >= 0),
    cpu_seconds          REAL    CHECK (cpu_seconds IS NULL OR (typeof(cpu_seconds) = 'real'
                                                                AND cpu_seconds >= 0)),
    knot_verified        INTEGER CHECK (knot_verified IS NULL OR knot_verified IN (0, 1)),
    created              TEXT    NOT NULL,
    extra                TEXT    NOT NULL DEFAULT '{}',
    coords               BLOB    NOT NULL CHECK (typeof(coords) = 'blob'
                                                 AND length(coords) = 24 * beads),
    coords_sha256        TEXT    NOT NULL CHECK (length(coords_sha256) = 64),
    UNIQUE (knot, exclusion, beads, thickness_key, seed, replica, settings_hash)
)"""

_ENSEMBLES = """
CREATE VIEW IF NOT EXISTS ensembles AS
SELECT knot, exclusion, beads, thickness_key, min(thickness) AS thickness,
       min(w_over_L) AS w_over_L, settings_hash, min(problem) AS problem,
       count(*) AS replicas, min(epsilon) AS eps_min, avg(epsilon) AS eps_mean
FROM replicas
GROUP BY knot, exclusion, beads, thickness_key, settings_hash"""

_AUDITS = """
CREATE TABLE IF NOT EXISTS audits (
    id                   INTEGER PRIMARY KEY,
    audit                TEXT    NOT NULL CHECK (length(audit) = 16),
    created              TEXT    NOT NULL,
    version              TEXT    NOT NULL,
    knot                 TEXT    NOT NULL,
    exclusion            TEXT    NOT NULL CHECK (exclusion IN ('bead', 'tube')),
    beads                INTEGER NOT NULL,
    thickness_key        TEXT    NOT NULL,
    settings_hash        TEXT    NOT NULL CHECK (length(settings_hash) = 16),
    w_over_L             REAL    NOT NULL,
    epsilon              REAL    NOT NULL,
    state                TEXT,
    audit_settings_hash  TEXT    NOT NULL CHECK (length(audit_settings_hash) = 16),
    audit_seed           INTEGER NOT NULL,
    searches             INTEGER NOT NULL CHECK (searches >= 0),
    audit_epsilon        REAL,
    audit_state          TEXT,
    false_verdict        INTEGER NOT NULL CHECK (false_verdict IN (0, 1)),
    params               TEXT    NOT NULL,
    UNIQUE (audit, knot, exclusion, beads, thickness_key, settings_hash)
)"""

#: Every column of ``audits``, in table order.
AUDIT_COLUMNS = ("id", "audit", "created", "version", "knot", "exclusion", "beads",
                 "thickness_key", "settings_hash", "w_over_L", "epsilon", "state",
                 "audit_settings_hash", "audit_seed", "searches", "audit_epsilon",
                 "audit_state", "false_verdict", "params")

_CENSUS = """
CREATE TABLE IF NOT EXISTS census (
    id                   INTEGER PRIMARY KEY,
    census               TEXT    NOT NULL CHECK (length(census) = 16),
    created              TEXT    NOT NULL,
    version              TEXT    NOT NULL,
    knot                 TEXT    NOT NULL,
    exclusion            TEXT    NOT NULL CHECK (exclusion IN ('bead', 'tube')),
    beads                INTEGER NOT NULL,
    thickness_key        TEXT    NOT NULL,
    w_over_L             REAL    NOT NULL,
    settings             TEXT    NOT NULL,
    state                INTEGER NOT NULL CHECK (state >= 0),
    name                 TEXT    NOT NULL,
    shape                TEXT    NOT NULL CHECK (shape IN ('CB', '4C', '80', 'other')),
    multiplicity         INTEGER,
    structure            TEXT,
    epsilon              REAL    NOT NULL,
    eps_max              REAL    NOT NULL,
    count                INTEGER NOT NULL CHECK (count >= 1),
    searches             INTEGER NOT NULL CHECK (searches >= 1),
    representative       INTEGER NOT NULL,
    spread               REAL    NOT NULL CHECK (spread >= 0),
    replicas             INTEGER NOT NULL CHECK (replicas >= 1),
    params               TEXT    NOT NULL,
    UNIQUE (census, knot, exclusion, beads, thickness_key, state)
)"""

#: Every column of ``census``, in table order.
CENSUS_COLUMNS = ("id", "census", "created", "version", "knot", "exclusion", "beads",
                  "thickness_key", "w_over_L", "settings", "state", "name", "shape",
                  "multiplicity", "structure", "epsilon", "eps_max", "count", "searches",
                  "representative", "spread", "replicas", "params")

_THIN = """
CREATE TABLE IF NOT EXISTS thin (
    id                   INTEGER PRIMARY KEY,
    run                  TEXT    NOT NULL CHECK (length(run) = 16),
    created              TEXT    NOT NULL,
    version              TEXT    NOT NULL,
    knot                 TEXT    NOT NULL,
    exclusion            TEXT    NOT NULL CHECK (exclusion IN ('bead', 'tube')),
    beads                INTEGER NOT NULL,
    thickness_key        TEXT    NOT NULL,
    w_over_L             REAL    NOT NULL,
    census               TEXT    NOT NULL CHECK (length(census) = 16),
    budget               TEXT    NOT NULL,
    seed                 INTEGER NOT NULL CHECK (seed >= 0),
    state                INTEGER NOT NULL CHECK (state >= 0),
    name                 TEXT    NOT NULL,
    representative       INTEGER NOT NULL,
    epsilon              REAL    NOT NULL,
    epsilon_thin         REAL,
    error                REAL,
    event                TEXT    CHECK (event IS NULL OR event IN ('jumped', 'merged')),
    shape_thin           TEXT,
    structure_epsilon    REAL,
    structure_error      REAL,
    structure_name       TEXT,
    agree                INTEGER CHECK (agree IS NULL OR agree IN (0, 1)),
    ground               INTEGER NOT NULL CHECK (ground IN (0, 1)),
    details              TEXT    NOT NULL,
    chain                BLOB    NOT NULL CHECK (length(chain) = 24 * beads_thin),
    beads_thin           INTEGER NOT NULL CHECK (beads_thin >= 3),
    cpu_seconds          REAL,
    UNIQUE (run, state)
)"""

#: Every column of ``thin``, in table order.
THIN_COLUMNS = ("id", "run", "created", "version", "knot", "exclusion", "beads",
                "thickness_key", "w_over_L", "census", "budget", "seed", "state", "name",
                "representative", "epsilon", "epsilon_thin", "error", "event", "shape_thin",
                "structure_epsilon", "structure_error", "structure_name", "agree", "ground",
                "details", "chain", "beads_thin", "cpu_seconds")

#: version → the statements that migrate a database of that version to the next one.
MIGRATIONS: dict[int, tuple[str, ...]] = {1: (_AUDITS,), 2: (_CENSUS,), 3: (_THIN,)}

#: The statements that create an empty database (run in one transaction, idempotent).
DDL: tuple[str, ...] = (
    "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
    _REPLICAS,
    "CREATE INDEX IF NOT EXISTS replicas_ensemble ON replicas "
    "(knot, exclusion, beads, thickness_key, settings_hash, epsilon)",
    "CREATE INDEX IF NOT EXISTS replicas_settings ON replicas (settings_hash)",
    _ENSEMBLES,
    _AUDITS,
    _CENSUS,
    _THIN,
)

#: Every column of ``replicas``, in table order.
COLUMNS = ("id", "knot", "exclusion", "beads", "thickness", "thickness_key", "w_over_L", "seed",
           "replica", "replica_seed", "settings_hash", "settings", "problem", "version",
           "epsilon", "shape", "multiplicity", "min_segment_distance", "converged", "start",
           "wall_seconds", "cpu_seconds", "knot_verified", "created", "extra", "coords",
           "coords_sha256")

#: The columns a query returns for a row (all but the chain itself).
ROW_COLUMNS = tuple(c for c in COLUMNS if c != "coords")
