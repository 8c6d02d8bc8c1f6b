"""``stiffknots audit``: search a random sample of converged verdicts again and count the false
ones (:mod:`stiffknots.sweeps.audit`)."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import (
    Interrupted,
    JsonOpt,
    UserError,
    count,
    dump,
    err,
    out,
    prepare_file,
)
from stiffknots.cli.atlas import SweepProgress, _knot_list, cluster_options


def _pct(x: float | None) -> str:
    return "—" if x is None else f"{100 * x:.1f} %"


def rate_text(r: dict) -> str:
    """``"2 of 40 false (5.0 %, 95 % interval 1.4–16.5 %)"``."""
    if not r["n"]:
        return "no entry audited"
    return (f"{r['false']} of {r['n']} false ({_pct(r['rate'])}, 95 % interval "
            f"{100 * r['low']:.1f}–{100 * r['high']:.1f} %)")


def audit(
    db: Annotated[str, typer.Option(
        help="Results database whose converged verdicts are audited (written: the audit's "
             "searches, another ensemble, and its rows).")] = "results/stiffknots.db",
    sample: Annotated[int, typer.Option(
        help="Converged entries drawn at random (all of them when fewer).", parser=count)
    ] = 20,
    seed: Annotated[int, typer.Option(
        help="Seed of the draw, and of the audit's searches (derived from it: never a "
             "sweep's seed).")] = 0,
    depth: Annotated[float, typer.Option(
        help="Moves of every audit search, in moves of one replica of the audited entry "
             "(steps for a Langevin bead ensemble); 0.1..1000.")] = 2.0,
    replicas: Annotated[int, typer.Option(
        help="Audit searches per entry, from the knot's default starts round-robin (braid, "
             "cage, 80), with another seed than the sweep's.", parser=count)] = 3,
    models: Annotated[str, typer.Option(
        help="Models whose verdicts are audited, separated by commas: tube and/or bead.")
    ] = "tube",
    max_crossings: Annotated[int | None, typer.Option(
        help="Only knots with at most this many crossings.")] = None,
    knots: Annotated[str | None, typer.Option(
        help="Only these knots, separated by commas (12n_113,12a_801); a knot without a "
             "converged verdict is listed as not audited.")] = None,
    scheduler: Annotated[str | None, typer.Option(
        help="Address of a running Dask scheduler; default: a local cluster.")] = None,
    workers: Annotated[int | None, typer.Option(
        help="Worker processes of the local cluster (default: one per core).")] = None,
    json_: JsonOpt = False,
) -> None:
    """Audit the verdicts of a results database: a seeded random sample of its converged
    ground states, each searched again by independent searches (another seed, every default
    start, --depth times the moves); an entry is false when a search ends lower by more than
    0.1 %. Prints the false-verdict rate with its 95 % Wilson interval per model and crossing
    number, and stores the audit (db grounds and the atlas pages show it). See
    docs/methods/verdicts.md."""
    from pathlib import Path

    from stiffknots.problems import validate as V
    from stiffknots.store import Store, StoreError
    from stiffknots.sweeps import MODELS
    from stiffknots.sweeps.audit import audit_budget, run_audit

    names = sorted({m.strip() for m in models.split(",") if m.strip()})
    bad = [m for m in names if m not in MODELS]
    if not names or bad:
        raise UserError(f"--models must be tube and/or bead separated by commas, got "
                        f"{models!r}")
    audit_budget({"moves": 1000}, depth, replicas)  # --depth, --replicas checked first
    V.integer("sample", sample, 1, 100_000)
    V.seed(seed)
    if max_crossings is not None:
        V.integer("max_crossings", max_crossings, 3, 13)
    knot_list = None
    if knots is not None:
        from stiffknots.sweeps import resolve_knots

        knot_list = resolve_knots(_knot_list(knots))  # an unknown name fails before the db
    scheduler = cluster_options(scheduler, workers)
    if not db.strip():
        raise UserError("--db must name a results database file, got ''")
    if not Path(db).is_file():
        raise UserError(f"no results database at {db}: audit a database a sweep wrote "
                        "(stiffknots atlas --db ...), or give the right --db path")
    path = prepare_file(db, "--db")
    try:  # an empty or foreign file is refused, never given a schema
        store = Store(path, create=False)
    except StoreError as e:
        raise UserError(f"--db {db}: {e}") from None
    with store, SweepProgress() as bar:
        res = run_audit(store, models=names, sample=sample, seed=seed, depth=depth,
                        replicas=replicas, max_crossings=max_crossings, knots=knot_list,
                        scheduler=scheduler,
                        workers=workers, listener=bar)
    d = res.to_dict()
    if res.interrupted:
        if json_:
            dump(d)
        raise Interrupted(f"interrupted: the audit searches that ended are stored in {path}; "
                          "run the same command to resume")
    if json_:
        dump(d)
    else:
        _print(d)
    if res.failed:
        for f in res.failed:
            err.print(f"failed: {f['job']}: {f['error']}", highlight=False, markup=False,
                      soft_wrap=True)
        raise typer.Exit(1)


def _print(d: dict) -> None:
    p = d["params"]
    if not d["entries"]:
        among = f" of {', '.join(p['knots'])}" if p.get("knots") else " in the database"
        out.print(f"nothing to audit: no converged {' or '.join(p['models'])} verdict{among} "
                  "(stiffknots db grounds lists its verdicts)", highlight=False)
        return
    t = Table(title=f"audit {d['audit']}: {len(d['entries'])} of {d['converged']} converged "
                    f"entries, {p['replicas']} searches × {p['depth']:g} replica budgets each",
              caption="false: an audit search ended lower by > 0.1 %")
    for col in ("knot", "model", "verdict", "audit", "runs", "result"):
        t.add_column(col, justify="right" if col == "runs" else "left",
                     no_wrap=col in ("knot", "verdict", "audit", "result"))
    widths: dict[str, float] = {}
    for r in d["entries"]:
        widths.setdefault(r["exclusion"], r["w_over_L"])
        ae = r["audit_epsilon"]
        result = (f"false ({100 * r['gap']:.1f} % lower)" if r["false_verdict"] else "held")
        t.add_row(*[escape(str(c)) for c in (
            r["knot"], r["exclusion"], f"{r['epsilon']:.2f} {r['state']}",
            "—" if ae is None else f"{ae:.2f} {r['audit_state']}", r["searches"], result)])
    out.print(t)
    out.print("widths: " + ", ".join(f"{m} w/L = {v:.5f}" for m, v in widths.items())
              + " (the verdicts' own width, N and settings)", highlight=False)
    s = d["summary"]
    for m, r in s["by_model"].items():
        out.print(f"{m}: {rate_text(r)}", highlight=False)
    for k, r in s["by_crossings"].items():
        out.print(f"  {k.replace('/', ', n_c = ')}: {rate_text(r)}", highlight=False)
    missing = [k for k in p.get("knots") or () if k not in {r["knot"] for r in d["entries"]}]
    if missing:
        out.print(f"not audited (no converged verdict of {' or '.join(p['models'])}): "
                  + ", ".join(missing), highlight=False)
    if s["unsearched"]:
        out.print(f"{s['unsearched']} entries with no audit search ended (not counted)",
                  highlight=False)
    out.print(f"{d['wall_seconds']:.0f} s wall, {d['cpu_seconds']:.0f} CPU s now "
              f"({d['search_cpu_seconds']:.0f} CPU s of audit searches in all); stored as audit "
              f"{d['audit']} (stiffknots db grounds shows it)", highlight=False)
