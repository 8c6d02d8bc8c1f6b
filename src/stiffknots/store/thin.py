"""The thin stage's rows: every state of a knot's census followed to w = 0, kept.

The atlas's thin stage (:mod:`stiffknots.studies.thin_stage`) follows the states of one knot in one
job; :func:`put_thin` writes the job's rows in one transaction (a killed writer leaves the
whole job or none of it), :func:`thin_runs` lists the jobs stored (what a thin stage run
again skips), :func:`thin_rows` reads them back and :func:`thin_knots` gives one summary per
knot (its thin-limit ground by both routes beside its ground at the census's width). Table
``thin`` of :mod:`stiffknots.store.schema` (version 4).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from stiffknots.store.errors import StoreError
from stiffknots.store.keys import canonical_json, knot_sort_key
from stiffknots.store.schema import THIN_COLUMNS

__all__ = ["put_thin", "thin_runs", "thin_rows", "thin_chain", "thin_knots"]

_READ = tuple(c for c in THIN_COLUMNS if c != "chain")


def _need_table(store: Any) -> None:
    if store._version < 4:
        raise StoreError(f"{store.path} is a schema-version-{store._version} database opened "
                         "read-only: it has no thin table (open it for writing to migrate it)")


def put_thin(store: Any, rows: Iterable[Mapping[str, Any]]) -> int:
    """Write the rows of one or more thin-stage jobs (the columns of
    :data:`~stiffknots.store.schema.THIN_COLUMNS` but ``id`` and ``beads_thin``; ``chain`` an
    (N, 3) array, ``details`` a dict) in one transaction; the rows stored under each ``run``
    written are replaced. Returns the rows written."""
    cols = THIN_COLUMNS[1:]
    out = []
    for r in rows:
        r = dict(r)
        chain = np.ascontiguousarray(np.asarray(r.pop("chain"), dtype="<f8"))
        if chain.ndim != 2 or chain.shape[1] != 3 or len(chain) < 3:
            raise ValueError(f"a thin row's chain must be (N ≥ 3, 3), got {chain.shape}")
        r["chain"], r["beads_thin"] = chain.tobytes(), len(chain)
        if not isinstance(r["details"], str):
            r["details"] = canonical_json(r["details"])
        for c in ("agree", "ground"):
            if r.get(c) is not None:
                r[c] = int(bool(r[c]))
        missing = [c for c in cols if c not in r]
        if missing:
            raise ValueError(f"a thin row lacks {', '.join(missing)}")
        out.append({c: r[c] for c in cols})
    _need_table(store)
    sql = f"INSERT INTO thin ({', '.join(cols)}) VALUES ({', '.join(':' + c for c in cols)})"
    with store._write() as con:
        for run in {r["run"] for r in out}:
            con.execute("DELETE FROM thin WHERE run = ?", (run,))
        con.executemany(sql, out)
    return len(out)


def thin_runs(store: Any) -> set[str]:
    """The keys of the thin-stage jobs stored (none in a database older than version 4)."""
    if store._version < 4:
        return set()
    return {r[0] for r in store._query("SELECT DISTINCT run FROM thin")}


def thin_rows(store: Any, knot: str | list[str] | None = None,
              exclusion: str | None = None) -> list[dict[str, Any]]:
    """Stored thin rows (``details`` decoded, ``agree`` and ``ground`` as bools or None; no
    chain: :func:`thin_chain`), in knot-table order, newest run first, then state."""
    from stiffknots.store.sqlite import _in_where

    if store._version < 4:
        return []
    where, params = _in_where((("knot", knot), ("exclusion", exclusion)))
    out = []
    for r in store._query(f"SELECT {', '.join(_READ)} FROM thin{where}", params):
        d = dict(zip(_READ, r, strict=True))
        d["details"] = json.loads(d["details"])
        d["agree"] = None if d["agree"] is None else bool(d["agree"])
        d["ground"] = bool(d["ground"])
        out.append(d)
    out.sort(key=lambda d: d["state"])
    out.sort(key=lambda d: d["created"], reverse=True)
    out.sort(key=lambda d: knot_sort_key(d["knot"]))
    return out


def thin_chain(store: Any, id: int) -> np.ndarray:
    """The thinnest chain of a thin row (N × 3)."""
    rows = store._query("SELECT chain, beads_thin FROM thin WHERE id = ?", (int(id),))
    if not rows:
        raise KeyError(f"no thin row with id {id}")
    blob, n = rows[0]
    return np.frombuffer(blob, dtype="<f8").reshape(int(n), 3).copy()


def thin_knots(store: Any, knot: str | list[str] | None = None,
               exclusion: str | None = None) -> list[dict[str, Any]]:
    """One summary per knot: its newest thin run (``run``, ``budget``, ``seed``, width and
    ``states``: the rows), the thin-limit ground (``ground``: its row; ``epsilon_thin``,
    ``thin_error``, ``thin_structure``, ``thin_shape``, ``agree``), the finite-width ground
    (``finite``: state 0) and ``margin``/``crossing`` of the run; in knot-table order."""
    by_knot: dict[str, dict[str, Any]] = {}
    for r in thin_rows(store, knot, exclusion):
        s = by_knot.get(r["knot"])
        if s is None:
            s = by_knot[r["knot"]] = {
                "knot": r["knot"], "run": r["run"], "created": r["created"],
                "version": r["version"], "budget": r["budget"], "seed": r["seed"],
                "exclusion": r["exclusion"], "beads": r["beads"],
                "thickness_key": r["thickness_key"], "w_over_L": r["w_over_L"],
                "census": r["census"], "cpu_seconds": r["cpu_seconds"], "states": []}
        if r["run"] == s["run"]:
            s["states"].append(r)
    out = []
    for s in by_knot.values():
        g = next((r for r in s["states"] if r["ground"]), None)
        finite = next((r for r in s["states"] if r["state"] == 0), None)
        summary = (g or finite or {}).get("details", {}).get("summary", {})
        s.update(ground=g, finite=finite, margin=summary.get("margin"),
                 crossing=summary.get("crossing"),
                 epsilon_thin=None if g is None else g["epsilon_thin"],
                 thin_error=None if g is None else g["error"],
                 thin_shape=None if g is None else g["name"],
                 thin_structure=None if g is None else (g["structure_name"] or g["name"]),
                 agree=None if g is None else g["agree"])
        out.append(s)
    return out

