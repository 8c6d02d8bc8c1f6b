"""``stiffknots db``: questions to the results database (:mod:`stiffknots.store.queries`).

``stiffknots db [--db PATH] states K [--model bead] [--json]`` — a knot's ground and
metastable states, per ensemble (model, width, N, settings);
``stiffknots db [--db PATH] grounds [--csv FILE] [--json]`` — every ground state, one row per
knot × model × N × width;
``stiffknots db [--db PATH] census K [--json]`` — a knot's stored census (its distinct states at
each width; ``stiffknots census`` takes it).

An ensemble is converged by the sweeps' rule (:func:`stiffknots.sweeps.ensemble_converged`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import JsonOpt, UserError, dump, out
from stiffknots.report.text import TOUCHING_BELOW, segment_distance_text, touching_note

db_app = typer.Typer(
    no_args_is_help=True, add_completion=False,
    help="Query the results database: a knot's states, every ground state.")


def _width(exclusion: str, thickness: float, beads: int, key: str = "text") -> str:
    from stiffknots.width import Width

    return Width.of(exclusion, float(thickness), int(beads)).as_dict()[key]


def _open(ctx: typer.Context):
    from stiffknots.store import Store

    return Store(ctx.obj["db"], readonly=True)  # a query writes nothing


@db_app.callback()
def db_main(ctx: typer.Context,
            db: Annotated[Path, typer.Option(help="The results database.")
                          ] = Path("results/stiffknots.db")) -> None:
    """Query the results database (default results/stiffknots.db, where `stiffknots atlas`
    writes)."""
    ctx.obj = {"db": db}


@db_app.command("states")
def states(
    ctx: typer.Context,
    knot: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    model: Annotated[str | None, typer.Option(
        help="Only this exclusion model: bead or tube (default: every model stored).")
    ] = None,
    json_: JsonOpt = False,
) -> None:
    """A knot's ground and metastable states, per model, width, N and settings."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.store import describe_knot
    from stiffknots.sweeps import CONVERGENCE_RULE, MODELS, ensemble_converged

    if model is not None and model not in MODELS:
        raise UserError(f"--model must be one of {', '.join(MODELS)}, got {model!r}")
    name = get_knot(knot).name
    with _open(ctx) as store:
        d = describe_knot(store, name, exclusion=model)
    for e in d["ensembles"]:
        e["width"] = _width(e["exclusion"], e["thickness"], e["beads"])
        e["converged"] = ensemble_converged(e)
    d["converged_rule"] = CONVERGENCE_RULE
    if json_:
        dump(d)
        return
    for e in d["ensembles"]:
        s = e["settings"]
        what = " (the searches of an audit: stiffknots audit)" if s.get("problem") == "audit" \
            else ""
        t = Table(title=escape(f"{name} — {e['width']}, {s.get('moves', 0):,} moves/replica, "
                               f"settings {e['settings_hash']}, {e['replicas']} replicas"
                               f"{what}"))
        for col in ("state", "role", "ε min", "ε mean", "replicas", "starts", "min seg dist"):
            t.add_column(col, justify="left" if col in ("state", "role", "starts") else "right")
        for k, st in enumerate([e["ground"], *e["metastable"]]):
            role = ("ground" + (" (converged)" if e["converged"] else "")) if k == 0 \
                else "metastable"
            t.add_row(escape(st["name"]), role, f"{st['epsilon']:.3f}", f"{st['eps_mean']:.3f}",
                      str(st["count"]), escape(", ".join(f"{a} {b}" for a, b in
                                                         st["starts"].items())),
                      segment_distance_text(st["min_segment_distance"]))
        if any(st["min_segment_distance"] < TOUCHING_BELOW
               for st in [e["ground"], *e["metastable"]]):
            t.caption = touching_note()
        out.print(t)
        named = [(("ground" if k == 0 else f"metastable {k}"), st.get("structure"))
                 for k, st in enumerate([e["ground"], *e["metastable"]])]
        if any(v for _, v in named):
            out.print("contact structure of each state's lowest chain (§V B):",
                      highlight=False, markup=False)
            for role, v in named:
                out.print(f"  {role:<13} {v or '—'}", highlight=False, markup=False)
    out.print(f"converged: {CONVERGENCE_RULE}", highlight=False, markup=False)


@db_app.command("census")
def census(
    ctx: typer.Context,
    knot: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    json_: JsonOpt = False,
) -> None:
    """A knot's stored census: its distinct states within the window of the lowest ε, at each
    stored width, with the replicas and searches that ended in each (stiffknots census takes
    it)."""
    from stiffknots.cli.census import print_census
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.store import stored_census

    name = get_knot(knot).name
    with _open(ctx) as store:
        got = stored_census(store, name)
    if json_:
        dump({"knot": name, "census": got})
        return
    if not got:
        out.print(f"no census of {name} is stored in {ctx.obj['db']}: take it with "
                  f"stiffknots census {name} --db {ctx.obj['db']}", highlight=False,
                  markup=False)
        return
    for c in got:
        print_census(c)
        out.print(f"taken {c['created']} by stiffknots {c['version']} from {c['replicas']} "
                  f"replicas", highlight=False, markup=False)


@db_app.command("thin")
def thin(
    ctx: typer.Context,
    knot: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    json_: JsonOpt = False,
) -> None:
    """A knot's stored thin stage: every state of its tube census followed to w = 0 (ε*
    extrapolated, and by the structure route), and its thin-limit ground (stiffknots atlas
    --thin computes it)."""
    from stiffknots.cli.thin_table import print_thin
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.store.thin import thin_knots

    name = get_knot(knot).name
    with _open(ctx) as store:
        got = thin_knots(store, name)
    if json_:
        dump({"knot": name, "thin": got[0] if got else None})
        return
    if not got:
        out.print(f"no thin stage of {name} is stored in {ctx.obj['db']}: run stiffknots atlas "
                  f"--knots {name} --models tube --thin --db {ctx.obj['db']}", highlight=False,
                  markup=False)
        return
    print_thin(got[0])


@db_app.command("grounds")
def grounds(
    ctx: typer.Context,
    csv: Annotated[Path | None, typer.Option(help="Also write the table to this CSV file.")
                   ] = None,
    json_: JsonOpt = False,
) -> None:
    """Every ground state: one row per knot × model × N × width (the lowest-ε settings), with
    its verdict and, where `stiffknots audit` searched it again, the audit's finding."""
    from stiffknots.store import ground_table, thickness_key, to_csv
    from stiffknots.sweeps import CONVERGENCE_RULE, is_converged
    from stiffknots.sweeps.audit import latest_audits
    from stiffknots.sweeps.convergence import untried_starts
    from stiffknots.sweeps.plan import PROBLEM

    if csv is not None and csv.is_dir():
        raise UserError(f"--csv {csv} is a folder; give the path of a file")
    with _open(ctx) as store:
        rows = ground_table(store, problem=PROBLEM)  # the sweeps' own (not the audits')
        audits = latest_audits(store)
    for r in rows:
        a = audits.get((r["knot"], r["exclusion"], r["beads"], thickness_key(r["thickness"]),
                        r["settings_hash"]))
        # the newest audit of this verdict (stiffknots audit), None where none was made
        r["audit"] = None if a is None else {
            "audit": a["audit"], "false_verdict": bool(a["false_verdict"]),
            "audit_epsilon": a["audit_epsilon"], "audit_state": a["audit_state"],
            "searches": a["searches"], "depth": a["params"].get("depth"),
            "created": a["created"]}
        r["width"] = _width(r["exclusion"], r["thickness"], r["beads"])
        # ``converged``: the ground state's verdict by the sweeps' rule (the top-level
        # ``converged_rule`` says it in words); the stored flag of its lowest replica (null
        # for a sweep's replicas, which have no verdict of their own) stays as
        # ``replica_converged``
        r["replica_converged"] = r.pop("converged", None)
        # the ensemble's verdict (sweeps.ensemble_converged): the rule, every start tried
        r["untried_starts"] = untried_starts(r)
        r["converged"] = is_converged(r) and not r["untried_starts"]
    path = None
    if csv is not None:
        try:
            path = to_csv(csv, rows)
        except OSError as e:
            raise UserError(f"--csv {csv}: cannot write it ({e.strerror or e})") from None
    if json_:
        dump({"db": str(ctx.obj["db"]), "csv": None if path is None else str(path),
              "converged_rule": CONVERGENCE_RULE, "grounds": rows})
        return
    if not rows:
        out.print(f"no ground states: {ctx.obj['db']} holds no replicas yet (a sweep: "
                  "stiffknots atlas ... --db " + str(ctx.obj["db"]) + ")", highlight=False,
                  markup=False)
        return
    # a model whose rows share one width is named alone in its column, the width said below
    # the table (the table then keeps to 80 columns in a pipe or a log)
    widths: dict[str, set[str]] = {}
    for r in rows:
        widths.setdefault(r["exclusion"], set()).add(r["width"])
    one = {ex: next(iter(w)) for ex, w in widths.items() if len(w) == 1}
    t = Table(title=f"ground states in {ctx.obj['db']}",
              caption="metastable: the lowest other state, (+k) more (stiffknots db states K)")
    audited = any(r["audit"] for r in rows)
    for col in ("knot", "model", "state", "ε", "replicas", "converged",
                *(("audit",) if audited else ()), "metastable"):
        t.add_column(col, justify="right" if col in ("ε", "replicas") else "left",
                     no_wrap=col in ("knot", "state", "ε"))
    for r in rows:
        model = "bead" if r["exclusion"] == "bead" else "tube"
        width = model if r["exclusion"] in one else _width(r["exclusion"], r["thickness"],
                                                           r["beads"], "short")
        meta = [m.strip() for m in (r["metastable"] or "").split(";") if m.strip()]
        meta_text = (meta[0] + (f" (+{len(meta) - 1})" if len(meta) > 1 else "")
                     if meta else "—")
        a = r["audit"]
        audit_cell = ("—" if a is None else "false" if a["false_verdict"] else "held")
        t.add_row(escape(r["knot"]), escape(width), escape(r["state"]),
                  f"{r['epsilon']:.3f}", f"{r['count']}/{r['replicas']}",
                  "yes" if r["converged"] else "no" + ("*" if r["untried_starts"] else ""),
                  *((audit_cell,) if audited else ()), escape(meta_text))
    out.print(t)
    for ex in sorted(one):
        out.print(f"{'bead' if ex == 'bead' else 'tube'}: {one[ex]}", highlight=False,
                  markup=False)
    out.print(f"converged: {CONVERGENCE_RULE}", highlight=False, markup=False)
    untried = [f"{r['knot']} {r['exclusion']}: {', '.join(r['untried_starts'])}"
               for r in rows if r["untried_starts"]]
    if untried:
        out.print("no*: a default start not tried yet — " + "; ".join(untried),
                  highlight=False, markup=False)
    if audited:
        false = [f"{r['knot']} {r['exclusion']} {r['epsilon']:.2f} → "
                 f"{r['audit']['audit_epsilon']:.2f} ({r['audit']['audit_state']})"
                 for r in rows if r["audit"] and r["audit"]["false_verdict"]]
        out.print("audit (stiffknots audit: the verdict searched again; false: a search "
                  "ended lower by > 0.1 %)" + (": lower states found — " + "; ".join(false)
                                               if false else ""),
                  highlight=False, markup=False, soft_wrap=True)
    if path is not None:
        out.print(f"CSV: {path}", highlight=False, markup=False)
