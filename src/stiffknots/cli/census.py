"""``stiffknots census``: the distinct states of each stored knot at its width, counted and
stored (:mod:`stiffknots.store.census`); ``stiffknots db census K`` reads them back."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import JsonOpt, UserError, dump, out, prepare_file


def _width_text(c: dict) -> str:
    from stiffknots.width import Width

    thickness = c.get("thickness")
    if thickness is None:
        thickness = float(c["thickness_key"])
    return Width.of(c["exclusion"], float(thickness), int(c["beads"])).as_dict()["text"]


def census_table(c: dict) -> Table:
    """One census as a table: a row per state, ε above the lowest in per cent."""
    low, n = c["states"][0]["epsilon"], len(c["states"])
    t = Table(title=escape(f"{c['knot']} — {_width_text(c)}: {n} state{'s' * (n != 1)} within "
                           f"{100 * c['params']['window']:g} % of the lowest, from "
                           f"{c['replicas']} replicas"
                           + (f", {c['searches']} searches" if "searches" in c else "")),
              caption=("one state: same class, ε within "
                       f"{100 * c['params']['rel_tol']:g} %, shape distance ≤ "
                       f"{c['params']['max_distance']:g} L (spread: the largest)"))
    for col in ("#", "state", "ε", "above lowest", "replicas", "searches", "spread / L"):
        t.add_column(col, justify="left" if col == "state" else "right")
    for s in c["states"]:
        t.add_row(str(s["state"]), escape(s["name"]), f"{s['epsilon']:.3f}",
                  f"{100 * (s['epsilon'] - low) / abs(low):.2f} %", str(s["count"]),
                  str(s["searches"]), f"{s['spread']:.4f}")
    return t


def print_census(c: dict) -> None:
    """The table, then each state's structure (§V B) on a line of its own."""
    out.print(census_table(c))
    if any(s.get("structure") for s in c["states"]):
        out.print("structure of each state's lowest chain (§V B):", highlight=False,
                  markup=False)
        for s in c["states"]:
            out.print(f"  {s['state']:>2} {s['name']:<8} {s.get('structure') or '—'}",
                      highlight=False, markup=False)


def census(
    knots: Annotated[list[str] | None, typer.Argument(
        help="Knots (3_1 5_2 ...); default: every knot in the database.")] = None,
    db: Annotated[str, typer.Option(
        help="Results database (read: every stored run of the knot at its width, pooled; "
             "written: the census table).")] = "results/stiffknots.db",
    model: Annotated[str, typer.Option(
        help="Exclusion model: tube (the atlas's verdicts) or bead.")] = "tube",
    window: Annotated[float, typer.Option(
        help="States within this fraction of the lowest ε (0.15 = 15 %).")] = 0.15,
    rel_tol: Annotated[float, typer.Option(
        help="ε tolerance within one state, a fraction (0.01 = 1 %).")] = 0.01,
    max_distance: Annotated[float, typer.Option(
        help="Largest shape distance (RMSD after the best superposition, in units of L) "
             "from a state's lowest chain.")] = 0.02,
    json_: JsonOpt = False,
) -> None:
    """Count the distinct states of stored knots: every chain the searches at a knot's width
    ended in (all runs pooled) within --window of the lowest ε, sorted into states by shape
    class, ε and the shape distance (blind to rotation, mirror, direction and bead numbering);
    how many replicas and independent searches ended in each. Stores the census in the
    database (stiffknots db census K reads it). See docs/methods/states.md."""
    from pathlib import Path

    from stiffknots.knots.catalogue import get_knot
    from stiffknots.store import Store, StoreError, save_census, take_census
    from stiffknots.sweeps import MODELS

    if model not in MODELS:
        raise UserError(f"--model must be one of {', '.join(MODELS)}, got {model!r}")
    for name, v, hi in (("--window", window, 10.0), ("--rel-tol", rel_tol, 1.0),
                        ("--max-distance", max_distance, 1.0)):
        if not 0.0 <= v < hi:
            raise UserError(f"{name} must be in [0, {hi:g}), got {v!r}")
    if not db.strip() or not Path(db).is_file():
        raise UserError(f"no results database at {db!r}: take the census of a database a sweep "
                        "wrote (stiffknots atlas --db ...), or give the right --db path")
    path = prepare_file(db, "--db")
    try:
        store = Store(path, create=False)
    except StoreError as e:
        raise UserError(f"--db {db}: {e}") from None
    results = []
    with store:
        stored = store.knots()
        names = [get_knot(k).name for k in knots] if knots else stored
        missing = [k for k in names if k not in stored]
        if missing:
            raise UserError(f"no stored runs of {', '.join(missing)} in {db}")
        for name in names:
            widths = [e for e in store.ensembles(knot=name, exclusion=model)]
            seen = set()
            for e in widths:
                w = (e["beads"], e["thickness_key"])
                if w in seen:
                    continue
                seen.add(w)
                c = take_census(store, name, model, e["beads"], e["thickness"], window=window,
                                rel_tol=rel_tol, max_distance=max_distance)
                save_census(store, c)
                results.append(c)
                if not json_:
                    print_census(c)
    if json_:
        dump({"db": str(path), "model": model, "census": results})
    elif not results:
        out.print(f"no {model} runs of {', '.join(names)} in {db}", highlight=False)
