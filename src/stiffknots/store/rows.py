"""Rows of the ``replicas`` table: validation on the way in, decoding on the way out.

:func:`normalise_row` turns the dict a caller gives :meth:`Store.put
<stiffknots.store.sqlite.Store.put>` into the column values of :mod:`stiffknots.store.schema`
(or raises a :class:`ValueError` that names the field and what would be right);
:func:`decode_row` turns a stored row back into plain Python values; :func:`row_from_replica`
builds the row of an engine result (duck-typed: the store never imports the engine).
"""

from __future__ import annotations

import hashlib
import json
import math
import numbers
from collections.abc import Mapping
from datetime import UTC, datetime
from typing import Any

import numpy as np

from stiffknots._json import to_plain
from stiffknots._version import __version__
from stiffknots.store.keys import EXCLUSIONS, ReplicaKey, canonical_json, settings_hash
from stiffknots.store.schema import COLUMNS
from stiffknots.width import Width

__all__ = ["SHAPES", "REQUIRED", "OPTIONAL", "normalise_row", "decode_row", "coords_blob",
           "blob_coords", "row_from_replica", "search_of"]

#: Shape classes (the labels of :func:`stiffknots.analysis.shapes.classify`).
SHAPES = ("CB", "4C", "80", "other")

#: Fields a row must have.
REQUIRED = ("knot", "exclusion", "beads", "thickness", "seed", "replica", "settings", "epsilon",
            "min_segment_distance", "wall_seconds")

#: Fields a row may have (default in brackets): ``problem`` [``settings["problem"]``],
#: ``settings_hash`` [computed; checked if given], ``w_over_L`` [thickness / L, L = N closed,
#: N − 1 open (``settings["closed"] is False``)], ``replica_seed``, ``version`` [this
#: stiffknots], ``shape``, ``multiplicity``, ``converged``, ``start``, ``cpu_seconds``,
#: ``knot_verified``, ``extra`` [``{}``], ``created`` [now, UTC] — all others None.
OPTIONAL = ("problem", "settings_hash", "w_over_L", "replica_seed", "version", "shape",
            "multiplicity", "converged", "start", "cpu_seconds", "knot_verified", "extra",
            "created")


def _is_int(x: Any) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool | np.bool_)


def _text(row: Mapping, name: str, *, optional: bool = False) -> str | None:
    v = row.get(name)
    if v is None and optional:
        return None
    if not isinstance(v, str) or not v:
        raise ValueError(f"field {name!r} must be a non-empty string, got {v!r}")
    return v


def _int(row: Mapping, name: str, low: int, high: int = 2**63, *,
         optional: bool = False) -> int | None:
    v = row.get(name)
    if v is None and optional:
        return None
    if not _is_int(v):
        raise ValueError(f"field {name!r} must be an integer, got {v!r}")
    if not low <= int(v) < high:
        raise ValueError(f"field {name!r} must be in [{low}, {high}), got {v!r}")
    return int(v)


def _real(row: Mapping, name: str, *, low: float | None = None, strict: bool = False,
          optional: bool = False) -> float | None:
    v = row.get(name)
    if v is None and optional:
        return None
    if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Real):
        raise ValueError(f"field {name!r} must be a number, got {v!r}")
    x = float(v)
    if not math.isfinite(x):
        raise ValueError(f"field {name!r} must be finite, got {v!r}")
    if low is not None and (x < low or (strict and x == low)):
        raise ValueError(f"field {name!r} must be {'>' if strict else '≥'} {low}, got {v!r}")
    return x


def _flag(row: Mapping, name: str) -> int | None:
    v = row.get(name)
    if v is None:
        return None
    if isinstance(v, bool | np.bool_) or (_is_int(v) and int(v) in (0, 1)):
        return int(bool(v))
    raise ValueError(f"field {name!r} must be True, False or None, got {v!r}")


def coords_blob(coords: Any, beads: int) -> bytes:
    """The BLOB of a chain: ``(beads, 3)`` float64, little-endian, row-major.

    Raises
    ------
    ValueError
        Not a real ``(beads, 3)`` array, or not finite.
    """
    try:
        x = np.asarray(coords)
    except Exception as e:  # noqa: BLE001 (anything that is not array-like)
        raise ValueError(f"coords must be an array of shape ({beads}, 3): {e}") from None
    if x.dtype.kind not in "iuf":
        raise ValueError(f"coords must be real numbers, got dtype {x.dtype}")
    if x.shape != (beads, 3):
        raise ValueError(f"coords must have shape (beads, 3) = ({beads}, 3), got {x.shape}")
    x = np.ascontiguousarray(x, dtype="<f8")
    if not np.isfinite(x).all():
        raise ValueError("coords must be finite (the chain has NaN or infinite coordinates)")
    return x.tobytes()


def blob_coords(blob: bytes, beads: int) -> np.ndarray:
    """The ``(beads, 3)`` float64 array of a stored BLOB (a writable copy)."""
    if len(blob) != 24 * beads:
        raise ValueError(f"coords blob has {len(blob)} bytes, expected 24·{beads} = "
                         f"{24 * beads}")
    return np.frombuffer(blob, dtype="<f8").reshape(beads, 3).astype(np.float64)


def normalise_row(row: Mapping[str, Any], coords: Any) -> tuple[dict[str, Any], ReplicaKey]:
    """Check a row and its chain and return the column values and the key.

    Parameters
    ----------
    row : mapping
        :data:`REQUIRED` fields and any of :data:`OPTIONAL` (see
        :mod:`stiffknots.store.schema` for their meaning); anything else belongs in ``extra``.
    coords : array_like, shape (beads, 3)
        The final chain.

    Returns
    -------
    values : dict
        One value per column of ``replicas`` except ``id``.
    key : ReplicaKey

    Raises
    ------
    ValueError
        A field missing, unknown, of the wrong type, not finite or out of range; the settings
        without ``problem`` or a ``settings_hash`` that does not match them; bad coordinates.
    """
    if not isinstance(row, Mapping):
        raise ValueError(f"row must be a mapping of field → value, got {type(row).__name__}")
    missing = [f for f in REQUIRED if row.get(f) is None]
    if missing:
        raise ValueError(f"row lacks required field(s): {', '.join(missing)} (required: "
                         f"{', '.join(REQUIRED)})")
    unknown = sorted(set(row) - set(REQUIRED) - set(OPTIONAL))
    if unknown:
        raise ValueError(f"unknown row field(s): {', '.join(unknown)}; put other results in "
                         f"'extra' (allowed: {', '.join(REQUIRED + OPTIONAL)})")

    settings = row["settings"]
    settings_text = canonical_json(settings)
    h = settings_hash(settings)
    if row.get("settings_hash") is not None and row["settings_hash"] != h:
        raise ValueError(f"settings_hash {row['settings_hash']!r} does not match the settings "
                         f"(their hash is {h!r})")
    problem = row.get("problem") or settings.get("problem")
    if settings.get("problem") is None or settings.get("problem") != problem:
        raise ValueError(f"settings must name the problem (settings['problem'] == "
                         f"{problem!r}), so that two problems never share a key; got "
                         f"settings['problem'] = {settings.get('problem')!r}")
    problem = _text({"problem": problem}, "problem")

    exclusion = row["exclusion"]
    if exclusion not in EXCLUSIONS:
        raise ValueError(f"field 'exclusion' must be one of {EXCLUSIONS}, got {exclusion!r}")
    beads = _int(row, "beads", 3)
    thickness = _real(row, "thickness", low=0.0, strict=True)
    key = ReplicaKey(_text(row, "knot"), exclusion, beads, thickness, _int(row, "seed", 0),
                     _int(row, "replica", 0), h)
    if row.get("w_over_L") is None:
        w_over_l = Width.of(exclusion, thickness, beads,
                            closed=settings.get("closed") is not False).w_over_L
    else:
        w_over_l = _real(row, "w_over_L", low=0.0, strict=True)

    shape = row.get("shape")
    if shape is not None and shape not in SHAPES:
        raise ValueError(f"field 'shape' must be one of {SHAPES} or None, got {shape!r}")
    if shape == "CB":
        mult = _int(row, "multiplicity", 1)
    elif row.get("multiplicity") is not None:
        raise ValueError(f"field 'multiplicity' is the circular-braid index: only a 'CB' shape "
                         f"has one (shape {shape!r}, multiplicity {row['multiplicity']!r})")
    else:
        mult = None

    extra = row.get("extra")
    if extra is None:
        extra = {}
    if not isinstance(extra, Mapping):
        raise ValueError(f"field 'extra' must be a mapping, got {type(extra).__name__}")
    try:
        extra_text = json.dumps(to_plain(extra), sort_keys=True, ensure_ascii=False)
    except TypeError as e:
        raise ValueError(f"field 'extra' must be JSON-able: {e}") from None

    created = row.get("created")
    if created is None:
        created = datetime.now(UTC).isoformat(timespec="milliseconds")
    blob = coords_blob(coords, beads)
    values = {
        "knot": key.knot, "exclusion": exclusion, "beads": beads, "thickness": thickness,
        "thickness_key": key.thickness_key, "w_over_L": w_over_l, "seed": key.seed,
        "replica": key.replica,
        "replica_seed": _int(row, "replica_seed", -(2**63), optional=True),
        "settings_hash": h, "settings": settings_text, "problem": problem,
        "version": _text(row, "version", optional=True) or __version__,
        "epsilon": _real(row, "epsilon"), "shape": shape, "multiplicity": mult,
        "min_segment_distance": _real(row, "min_segment_distance", low=0.0),
        "converged": _flag(row, "converged"), "start": _text(row, "start", optional=True),
        "wall_seconds": _real(row, "wall_seconds", low=0.0),
        "cpu_seconds": _real(row, "cpu_seconds", low=0.0, optional=True),
        "knot_verified": _flag(row, "knot_verified"), "created": _text({"c": created}, "c"),
        "extra": extra_text, "coords": blob,
        "coords_sha256": hashlib.sha256(blob).hexdigest(),
    }
    assert tuple(values) == COLUMNS[1:]
    return values, key


def decode_row(names: tuple[str, ...], values: tuple) -> dict[str, Any]:
    """A stored row as plain Python values: settings and extra parsed, flags as bool/None."""
    d = dict(zip(names, values, strict=True))
    for name in ("settings", "extra"):
        if name in d and d[name] is not None:
            d[name] = json.loads(d[name])
    for name in ("converged", "knot_verified"):
        if name in d and d[name] is not None:
            d[name] = bool(d[name])
    return d


_RESULT_FIELDS = {  # ReplicaResult attribute → row field
    "replica": "replica", "seed": "replica_seed", "epsilon": "epsilon",
    "min_segment_distance": "min_segment_distance", "wall_time": "wall_seconds",
    "cpu_time": "cpu_seconds", "knot_verified": "knot_verified", "version": "version",
    "start": "start",
}
_RESULT_SKIP = {"coords", "trace_moves", "trace_temperature", "trace_epsilon", "trace_seconds",
                "knot"}


def row_from_replica(result: Any, *, knot: str, width: Width, seed: int,
                     settings: Mapping[str, Any],
                     shape: str | None = None, multiplicity: int | None = None,
                     converged: bool | None = None,
                     **fields: Any) -> tuple[dict[str, Any], np.ndarray]:
    """The row and chain of an engine replica result (duck-typed, e.g. ``ReplicaResult``).

    The result's ``replica``, ``epsilon``, ``min_segment_distance``, ``wall_time`` (→
    ``wall_seconds``), ``cpu_time`` (→ ``cpu_seconds``), ``knot_verified``, ``version``,
    ``start`` and its own ``seed`` (→ ``replica_seed``; the key's ``seed`` is the run's seed,
    given here) become columns; every other attribute of ``result.summary()`` (or of its
    ``__dict__``) except the chain and the traces goes into ``extra``.

    Parameters
    ----------
    result : object
        With the attributes above and ``coords``.
    knot, seed, settings
        The key fields the result does not carry.
    width : Width
        The exclusion model, its thickness, N and w/L (the key's ``exclusion``, ``thickness``
        and ``beads``, and the row's ``w_over_L``).
    shape, multiplicity, converged
        Optional classification and convergence verdict.
    **fields
        Further row fields (``problem``, ``created``, ...).

    Returns
    -------
    (row, coords)
        Ready for :meth:`Store.put <stiffknots.store.sqlite.Store.put>`.
    """
    coords = np.asarray(result.coords)
    summary = result.summary() if hasattr(result, "summary") else dict(vars(result))
    row: dict[str, Any] = {"knot": knot, "exclusion": width.exclusion,
                           "thickness": width.thickness, "beads": width.beads,
                           "w_over_L": width.w_over_L, "seed": seed, "settings": settings,
                           "shape": shape, "multiplicity": multiplicity, "converged": converged}
    extra = {}
    for name, value in summary.items():
        if name in _RESULT_FIELDS:
            row[_RESULT_FIELDS[name]] = value
        elif name not in _RESULT_SKIP:
            extra[name] = value
    row["extra"] = {**extra, **dict(fields.pop("extra", {}) or {})}
    row.update(fields)
    return row, coords


#: the ``start`` of a bead replica seeded from a tube replica (:mod:`stiffknots.sweeps.cross`):
#: such a search confirms a state but does not certify it (:mod:`stiffknots.sweeps.convergence`)
SEEDED_START = "tube-ground"


def search_of(row: Mapping[str, Any]) -> int:
    """The search (independent search of an ensemble) a stored replica belongs to: its
    ``extra["search"]`` where it has one — a sweep's continuation leg, the search it continued
    (:mod:`stiffknots.sweeps.legs`); a seeded replica, the tube search it comes from — else
    its own replica number."""
    extra = row.get("extra") or {}
    s = extra.get("search") if isinstance(extra, Mapping) else None
    return int(s) if s is not None else int(row["replica"])
