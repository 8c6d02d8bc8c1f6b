"""The census of a knot at one width: its distinct states near the lowest, computed and kept.

:func:`take_census` reads the stored chains of a knot at one width and sorts them into states
(:func:`stiffknots.analysis.census`: shape class, ε within a tolerance, shape distance to the
state's lowest chain); :func:`save_census` writes the result into the ``census`` table
(:mod:`stiffknots.store.schema`); :func:`stored_census` reads it back, one census per
knot and width. A census pools every run stored at one width of a knot (all settings: a sweep,
an audit's deeper searches). A search is one (settings, seed,
:func:`~stiffknots.store.rows.search_of`) triple: a sweep's continuation legs and seeded
replicas count once, with the search they belong to.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from datetime import UTC, datetime
from typing import Any

from stiffknots._version import __version__
from stiffknots.store.keys import canonical_json
from stiffknots.store.rows import search_of
from stiffknots.store.schema import ENSEMBLE_FIELDS, WIDTH_FIELDS

__all__ = ["census_params", "take_census", "save_census", "stored_census"]


def census_params(window: float, rel_tol: float, max_distance: float,
                  points: int) -> tuple[dict[str, Any], str]:
    """The parameters of a census and their 16-hex-digit hash (the ``census`` column)."""
    params = {"window": float(window), "rel_tol": float(rel_tol),
              "max_distance": float(max_distance), "points": int(points)}
    return params, hashlib.sha256(canonical_json(params).encode()).hexdigest()[:16]


def take_census(store: Any, knot: str, exclusion: str | None = None, beads: int | None = None,
                thickness: float | None = None, *, window: float | None = None,
                rel_tol: float = 0.01, max_distance: float | None = None,
                points: int | None = None, structure: bool = True) -> dict[str, Any]:
    """The census of a knot at one width: every stored search there, pooled (nothing is
    written).

    Parameters
    ----------
    store : Store
    knot, exclusion, beads, thickness
        Select exactly one width of the knot: one model, N and thickness. The runs stored
        there under every settings (an atlas's sweep, an audit's deeper searches, an
        `anneal`) are pooled: a state any of them found is in the census.
    window, rel_tol, max_distance, points
        As :func:`stiffknots.analysis.census` (defaults: 15 %, 1 %, 0.02 L, 256 points).
    structure : bool, default True
        Name each state's structure from its representative chain (§V B).

    Returns
    -------
    dict
        ``knot``, ``exclusion``, ``beads``, ``thickness``, ``thickness_key``, ``w_over_L``,
        ``settings`` (the pooled settings hashes), ``replicas``, ``searches`` (independent
        searches pooled), ``counted`` (rows within the window), ``census`` (the parameters'
        hash), ``params``, ``version`` and ``states``: by increasing ε, each with ``state``
        (rank), ``name``, ``shape``, ``multiplicity``, ``structure``, ``epsilon``,
        ``eps_max``, ``count``, ``searches``, ``representative`` (row id), ``seed``,
        ``start``, ``settings_hash``, ``spread`` and ``ids``.

    Raises
    ------
    ValueError
        No stored run matches, or several widths do (the message lists them); bad
        parameters.
    """
    from stiffknots.analysis.census import DEFAULT_WINDOW, census
    from stiffknots.analysis.identity import DEFAULT_POINTS, SAME_STATE_DISTANCE
    from stiffknots.analysis.shapes import classify

    window = DEFAULT_WINDOW if window is None else window
    max_distance = SAME_STATE_DISTANCE if max_distance is None else max_distance
    points = DEFAULT_POINTS if points is None else points
    filters = {"knot": knot, "exclusion": exclusion, "beads": beads, "thickness": thickness}
    ens = store.ensembles(**filters)
    if not ens:
        given = ", ".join(f"{k}={v!r}" for k, v in filters.items() if v is not None)
        raise ValueError(f"no stored replicas with {given}")
    widths = {tuple(e[f] for f in WIDTH_FIELDS) for e in ens}
    if len(widths) > 1:
        listed = "; ".join(f"exclusion={w[1]} beads={w[2]} thickness={w[3]}"
                           for w in sorted(widths))
        raise ValueError(f"{len(widths)} widths of {knot} are stored; choose one with "
                         f"exclusion, beads or thickness: {listed}")
    rows = [r for e in ens for r in store.replicas(**{f: e[f] for f in ENSEMBLE_FIELDS})]
    items = []
    for r in rows:
        x = store.coords(r["id"])
        label, mult = r["shape"], r["multiplicity"]
        if label is None:
            sh = classify(x, True, d=r["thickness"])
            label, mult = sh.label, sh.multiplicity
        items.append({"coords": x, "epsilon": r["epsilon"], "label": label,
                      "multiplicity": mult,
                      "search": (r["settings_hash"], r["seed"], search_of(r))})
    c = census(items, window=window, rel_tol=rel_tol, max_distance=max_distance,
               points=points)
    params, key = census_params(c.window, c.rel_tol, c.max_distance, points)
    states = []
    for rank, s in enumerate(c.states):
        rep = rows[s.representative]
        states.append({
            "state": rank, "name": s.name, "shape": s.label, "multiplicity": s.multiplicity,
            "structure": (store._structure_name(rep["id"], rep["thickness"])
                          if structure else None),
            "epsilon": s.epsilon, "eps_max": s.eps_max, "count": s.count,
            "searches": s.searches, "representative": rep["id"], "seed": rep["seed"],
            "start": rep["start"], "settings_hash": rep["settings_hash"], "spread": s.spread,
            "ids": [rows[m]["id"] for m in s.members]})
    first = rows[0]
    return {**{f: first[f] for f in ("knot", "exclusion", "beads", "thickness",
                                     "thickness_key", "w_over_L")},
            "settings": sorted({e["settings_hash"] for e in ens}),
            "replicas": len(rows), "searches": len({it["search"] for it in items}),
            "counted": c.n_counted, "census": key, "params": params,
            "version": __version__, "states": states}


def save_census(store: Any, c: Mapping[str, Any]) -> int:
    """Write a census of :func:`take_census` into the store (replacing the stored census of
    that knot and width with the same parameters). Returns the rows written."""
    now = datetime.now(UTC).isoformat(timespec="seconds")
    rows = [{"census": c["census"], "created": now, "version": c["version"],
             **{f: c[f] for f in WIDTH_FIELDS}, "w_over_L": c["w_over_L"],
             "settings": c["settings"],
             **{k: s[k] for k in ("state", "name", "shape", "multiplicity", "structure",
                                  "epsilon", "eps_max", "count", "searches",
                                  "representative", "spread")},
             "replicas": c["replicas"], "params": c["params"]} for s in c["states"]]
    return store.put_census(rows)


def stored_census(store: Any, knot: str | list[str] | None = None,
                  exclusion: str | None = None, *,
                  latest: bool = True) -> list[dict[str, Any]]:
    """Stored censuses, one dict per (census, knot and width) — with ``latest`` only the
    newest census of each knot and width — in knot-table order: ``knot``, ``exclusion``,
    ``beads``, ``thickness_key``, ``w_over_L``, ``settings``, ``census``, ``params``,
    ``created``, ``version``, ``replicas`` and ``states`` (the stored rows, by rank)."""
    out: dict[tuple, dict[str, Any]] = {}
    for r in store.census_rows(knot, exclusion):
        width = tuple(r[f] for f in WIDTH_FIELDS)
        key = width if latest else (*width, r["census"])
        c = out.get(key)
        if c is None:
            c = out[key] = {**{f: r[f] for f in WIDTH_FIELDS}, "w_over_L": r["w_over_L"],
                            "settings": r["settings"],
                            "census": r["census"], "params": r["params"],
                            "created": r["created"], "version": r["version"],
                            "replicas": r["replicas"], "states": []}
        if r["census"] != c["census"]:
            continue                                  # an older census of this ensemble
        c["states"].append({k: r[k] for k in ("state", "name", "shape", "multiplicity",
                                              "structure", "epsilon", "eps_max", "count",
                                              "searches", "representative", "spread")})
    return list(out.values())
