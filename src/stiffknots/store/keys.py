"""Replica keys and the settings hash: what makes two stored results "the same job".

A replica is identified by its :class:`ReplicaKey` — ``(knot, exclusion, beads, thickness, seed,
replica, settings_hash)`` — the UNIQUE key of the ``replicas`` table. A sweep computes the key of
every job *before* running it and skips those already stored (:meth:`Store.keys
<stiffknots.store.sqlite.Store.keys>`), so every part of the key must be known in advance:

``seed`` is the run's (user) seed and ``replica`` the replica index; the per-replica seed the
engine derives from them (``numpy.random.SeedSequence(seed).spawn(...)[replica]``) is stored
alongside (column ``replica_seed``) but is not part of the key.

Thickness
---------
The thickness (``d`` for the bead model, ``w`` for the tube model) is a float, and floats make
poor keys: ``1/√2`` computed as ``1/np.sqrt(2)``, ``np.sqrt(0.5)`` or ``2**-0.5`` may differ in
the last bit. The key therefore holds :func:`thickness_key` — the value rounded to 12
significant digits and written as text (``"0.707106781187"``) — and :class:`ReplicaKey` holds
the float of that text, so two keys built from any spelling of the same thickness compare
equal. The exact value is kept in the ``thickness`` column (and in the settings). Twelve digits
absorb round-off (~1e-16) yet keep any two intentionally different widths apart.
"""

from __future__ import annotations

import hashlib
import json
import math
import numbers
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from stiffknots._json import to_plain
from stiffknots.width import EXCLUSIONS

__all__ = ["ReplicaKey", "KEY_FIELDS", "settings_hash", "canonical_json", "thickness_key",
           "EXCLUSIONS", "knot_sort_key"]

#: The fields of the unique key, in order.
KEY_FIELDS = ("knot", "exclusion", "beads", "thickness", "seed", "replica", "settings_hash")

_THICKNESS_DIGITS = 12


def canonical_json(settings: Mapping[str, Any]) -> str:
    """The canonical JSON text of a settings mapping (the input of :func:`settings_hash`).

    Keys sorted at every level, no whitespace, floats written by ``repr`` (the shortest text
    that reads back to the same float: ``0.1`` stays ``0.1``), numpy scalars and arrays turned
    into plain Python values (``stiffknots._json.to_plain()``), tuples into lists, non-ASCII
    kept as is.

    Raises
    ------
    ValueError
        ``settings`` is not a mapping, holds NaN or ±inf, or a value JSON cannot write.
    """
    if not isinstance(settings, Mapping):
        raise ValueError(f"settings must be a mapping (a dict of the run's settings), got "
                         f"{type(settings).__name__}")
    plain = to_plain(settings)
    try:
        return json.dumps(plain, sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                          allow_nan=False)
    except ValueError:
        raise ValueError("settings must not contain NaN or infinite numbers (they have no "
                         "canonical JSON form); use None for 'unset'") from None
    except TypeError as e:
        raise ValueError(f"settings must be JSON-able (numbers, strings, booleans, None, "
                         f"lists, dicts, numpy values): {e}") from None


def settings_hash(settings: Mapping[str, Any]) -> str:
    """The 16-hex-digit hash of a run's settings (part of every replica's key).

    ``SHA-256`` of :func:`canonical_json`, first 16 hexadecimal digits (64 bits: a collision
    between two settings of one database has probability ~1e-19 per pair).

    What goes in: **every setting that changes the result and nothing that does not.**

    * in: the problem (``"problem": "anneal"``; required by :meth:`Store.put
      <stiffknots.store.sqlite.Store.put>`, so that two problems never share a key), the number
      of moves, the temperature schedule, the move parameters (delta, multi-bead moves,
      exclusion model and its ``d``/``w``, energy model, curvature limit), the quench fraction,
      the number of chunks, open/closed, the *requested* start (``"all"``, ``"braid"``, …; the
      start each replica actually got is the row's ``start`` column), tempering settings — in
      short ``AnnealSettings.as_dict()`` plus ``problem`` and ``start``;
    * out: the number of workers or machines, progress display, checkpoint folders and
      intervals, ``resume``, output paths, the database path — and the code version (stored in
      the ``version`` column; a new release does not invalidate stored results. A change that
      alters results on purpose should add a setting, e.g. ``"engine": 2``, so that new runs get
      new keys).
    * The knot, the exclusion model, the bead count, the thickness, the seed and the replica
      index are key fields of their own; they may also appear in the settings (harmless).

    ``1`` and ``1.0`` are different JSON and hash differently: build settings the same way
    every time (e.g. always from ``as_dict()``).

    Parameters
    ----------
    settings : mapping
        The run's settings.

    Returns
    -------
    str
        16 lowercase hexadecimal digits.

    Raises
    ------
    ValueError
        See :func:`canonical_json`.
    """
    return hashlib.sha256(canonical_json(settings).encode("utf-8")).hexdigest()[:16]


def _is_int(x: Any) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool)


def thickness_key(thickness: Any) -> str:
    """The text of ``thickness`` in the unique key: 12 significant digits (``"0.707106781187"``).

    Raises
    ------
    ValueError
        Not a finite positive number.
    """
    if isinstance(thickness, bool) or not isinstance(thickness, numbers.Real):
        raise ValueError(f"thickness must be a number (d for the bead model, w for the tube "
                         f"model), got {thickness!r}")
    t = float(thickness)
    if not math.isfinite(t) or t <= 0:
        raise ValueError(f"thickness must be finite and > 0, got {thickness!r}")
    return format(t, f".{_THICKNESS_DIGITS}g")


@dataclass(frozen=True, order=True)
class ReplicaKey:
    """The unique key of one stored replica (hashable: use it in sets and dicts).

    Attributes
    ----------
    knot : str
        Knot name as the catalogue writes it (``"5_2"``).
    exclusion : str
        ``"bead"`` or ``"tube"``.
    beads : int
        Number of beads ``N``.
    thickness : float
        ``d`` (bead model) or ``w`` (tube model), rounded to 12 significant digits on
        construction (see the module docstring), so keys from any spelling of one width match.
    seed : int
        The run's seed (0 ≤ seed < 2⁶³).
    replica : int
        Replica index (≥ 0).
    settings_hash : str
        :func:`settings_hash` of the run's settings.
    """

    knot: str
    exclusion: str
    beads: int
    thickness: float
    seed: int
    replica: int
    settings_hash: str

    def __post_init__(self) -> None:
        if not isinstance(self.knot, str) or not self.knot:
            raise ValueError(f"knot must be a non-empty string, got {self.knot!r}")
        if self.exclusion not in EXCLUSIONS:
            raise ValueError(f"exclusion must be one of {EXCLUSIONS}, got {self.exclusion!r}")
        for name in ("beads", "seed", "replica"):
            v = getattr(self, name)
            if not _is_int(v):
                raise ValueError(f"{name} must be an integer, got {v!r}")
            object.__setattr__(self, name, int(v))
        if self.beads < 3:
            raise ValueError(f"beads must be ≥ 3, got {self.beads}")
        if not 0 <= self.seed < 2**63:
            raise ValueError(f"seed must be in [0, 2**63), got {self.seed}")
        if self.replica < 0:
            raise ValueError(f"replica must be ≥ 0, got {self.replica}")
        object.__setattr__(self, "thickness", float(thickness_key(self.thickness)))
        h = self.settings_hash
        if not (isinstance(h, str) and len(h) == 16 and all(c in "0123456789abcdef" for c in h)):
            raise ValueError(f"settings_hash must be 16 lowercase hex digits (settings_hash()), "
                             f"got {h!r}")

    @property
    def thickness_key(self) -> str:
        """The thickness as the key writes it (:func:`thickness_key`)."""
        return thickness_key(self.thickness)

    @classmethod
    def from_row(cls, row: Mapping[str, Any]) -> ReplicaKey:
        """The key of a row (a mapping with the key fields; ``settings_hash`` may be replaced
        by ``settings``, which is then hashed)."""
        missing = [f for f in KEY_FIELDS if f != "settings_hash" and f not in row]
        if missing:
            raise ValueError(f"row lacks the key field(s) {', '.join(missing)}")
        h = row.get("settings_hash")
        if h is None:
            if "settings" not in row:
                raise ValueError("row needs 'settings' (or 'settings_hash')")
            h = settings_hash(row["settings"])
        return cls(row["knot"], row["exclusion"], row["beads"], row["thickness"], row["seed"],
                   row["replica"], h)

    def as_dict(self) -> dict:
        """The key as a plain dict."""
        return {f: getattr(self, f) for f in KEY_FIELDS}


def knot_sort_key(name: str) -> tuple:
    """Sort key of knot names in table order: numbers compare as numbers (``3_1`` < ``10_1``,
    ``K11a2`` < ``K11a10``)."""
    return tuple(int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name))
