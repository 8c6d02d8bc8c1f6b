"""``stiffknots thin-limit``: every state of a knot followed to w → 0 and the thin-limit ground
state (§V A), next to the structure route at w = 0 (§V B)
(:mod:`stiffknots.studies.thin_states`)."""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import (
    JsonOpt,
    OutOpt,
    OverwriteOpt,
    ReplicaProgress,
    ResultsFolder,
    SeedOpt,
    UserError,
    choice,
    dump,
    err,
    out,
    prepare_out,
)


def thin_limit(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    budget: Annotated[str, typer.Option(
        help="default (9 widths w/L = 0.004 … 0.00025, the discretisation measured on every "
             "branch: minutes per state on 2 cores) or small (4 widths 0.004 … 0.0005, the "
             "polygon rule for the discretisation: about a minute per state).")
    ] = "default",
    states: Annotated[int | None, typer.Option(
        help="Follow only the lowest N states of the census (default: every state within "
             "15 % of the lowest).")] = None,
    seed: SeedOpt = 0,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """The thin-limit ground state of a knot (§V A): its states at the atlas width (tube model,
    w/L = 0.0047, three independent searches) sorted into a census, every state followed down
    to w/L = 0.00025 by continuation and extrapolated to its own ε* at w/L → 0 with an error
    bar; beside it the structure route: the state's own structure graph solved at w = 0 (or
    the named CB(i), 80 or 4-fold cage where the graph has a line-braid). Says which state is
    the ground in the thin limit, by how much and how sure, and where the branches cross.
    See docs/thin-limit.md."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems import validate as V
    from stiffknots.problems.base import solve
    from stiffknots.studies.thin_states import BUDGETS, thin_limit_states

    choice("--budget", budget, tuple(BUDGETS))
    V.seed(seed)
    if states is not None:
        V.integer("states", states, 1, 1000)
    knot = get_knot(name)  # resolved once; a wrong name: one line before any work
    out_path = prepare_out(out_dir, overwrite)

    def runner(problem, label):
        reps = problem.replicas * getattr(problem, "rounds", 1)
        with ReplicaProgress(label, reps, disable=json_) as bars:
            res = solve(problem, on_replica_done=bars.done, on_progress=bars, isolate=True)
        return res

    def say(line: str) -> None:
        if not json_:
            err.print(line, markup=False, highlight=False)

    try:
        with _stdout_to_stderr(json_):
            res = thin_limit_states(knot, budget, seed, states=states, runner=runner, say=say)
    except KeyboardInterrupt:
        from stiffknots.cli.app import Interrupted

        raise Interrupted("interrupted: the states are not all followed to w = 0; nothing to "
                          "report") from None
    chains = [st.pop("chains") for st in res["states"]]
    if out_path is not None:
        res["files"] = _write(out_path, res, chains)
    if json_:
        dump(res)
        return
    _table(res)
    if out_path is not None:
        out.print(f"results in {out_path}/ (result.json, branches.png, each state's chains)",
                  markup=False, highlight=False)


@contextlib.contextmanager
def _stdout_to_stderr(active: bool):
    """With ``--json``, stdout carries the JSON object only: while the runs go, file
    descriptor 1 (inherited by the worker processes) points at stderr. (At w/L ≲ 3e-4 the
    final minimiser's sparse solver has printed BLAS complaints, "On entry to DGEMV parameter
    number 2 had an illegal value", on the workers' stdout; the results were unaffected.)"""
    if not active:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def _write(path, res, chains) -> dict:
    from stiffknots.chain import Chain
    from stiffknots.fileio import write_json
    from stiffknots.formats import save
    from stiffknots.report.figures import plot_branches, save_figure

    files: dict = {}
    with ResultsFolder(path, "thin-limit"):
        for i, (st, xs) in enumerate(zip(res["states"], chains, strict=True)):
            for p, x in zip(st["points"], xs, strict=True):
                f = path / f"state_{i}_w_over_L_{p['w_over_L']:g}.xyz"
                save(Chain(x, closed=True), f)
                files[f"state {i} w/L {p['w_over_L']:g}"] = str(f)
        files["png"] = str(save_figure(plot_branches(res), path / "branches.png"))
        files["result"] = str(write_json(path / "result.json", res | {"files": dict(files)}))
    return files


def _num(x, fmt=".4f") -> str:
    return "—" if x is None else format(x, fmt)


def _table(res) -> None:
    c = res["census"]
    t = Table(title=escape(f"{res['knot']}: every state followed to w → 0 (tube model; census "
                           f"at {c['width']['text']}, {res['budget']} budget, seed "
                           f"{res['seed']})"),
              caption="ε*_s: the state's own limit w/L → 0, ± one standard error")
    for col in ("#", "state", "ε at w/L 0.0047", "ε*_s", "±", "structure route", "agree",
                "event"):
        t.add_column(col, justify="left" if col in ("state", "event") else "right")
    for i, st in enumerate(res["states"]):
        evs = st.get("events") or ([st["event"]] if st["event"] else [])
        t.add_row(str(i) + (" *" if i == res["ground"] else ""), escape(st["shape"]),
                  f"{st['epsilon']:.3f}", _num(st["epsilon_thin"]), _num(st["error"], ".2g"),
                  (f"{st['structure_epsilon']:.4f}"
                   if st["structure_epsilon"] is not None else "—"),
                  {True: "yes", False: "NO", None: "—"}[st["agree"]],
                  escape("; ".join(f"{e['kind']} at w/L {e['w_over_L']:g}: {e['detail']}"
                                   for e in evs) or "—"))
    out.print(t)
    n = res["states"][0]["points"][0]["beads"] if res["states"] else None
    out.print(f"ladder: w/L {', '.join(f'{w:g}' for w in res['parameters']['widths'])} at "
              f"N = {n}; census: {c['replicas']} replicas, "
              f"{'converged' if c['converged'] else 'NOT converged'} ({c['convergence']})",
              markup=False, highlight=False)
    for i, st in enumerate(res["states"]):
        r = st["structure_route"]
        out.print(f"  state {i}: structure at the atlas width (§V B) {st['structure'] or '—'}; "
                  f"route at w = 0: " + (r["method"] if r["method"] else "none")
                  + (f" — {r['note']}" if r["note"] else ""), markup=False, highlight=False)
    g = res["ground"]
    if g is None:
        out.print("no state has two points in its branch: no thin limit", markup=False,
                  highlight=False)
        return
    st = res["states"][g]
    line = (f"thin-limit ground state: {g} ({st['shape']}), ε* = {st['epsilon_thin']:.4f} ± "
            f"{st['error']:.2g}")
    m = res["margin"]
    if m is not None:
        sure = (f"{m['sigmas']:.1f} combined errors" if m["sigmas"] is not None else "—")
        line += (f", below state {m['next']} ({res['states'][m['next']]['shape']}) by "
                 f"{m['gap']:.4f} ({sure}"
                 + ("; too close to call" if m["sigmas"] is not None and m["sigmas"] < 2
                    else "") + ")")
    out.print(line, markup=False, highlight=False)
    for i, st_i in enumerate(res["states"]):
        if st_i.get("difference"):  # why the routes differ, or why they are not compared
            head = "routes differ — " if st_i.get("agree") is False else ""
            out.print(f"  state {i}: {head}{st_i['difference']}", markup=False,
                      highlight=False)
    if g != 0:
        where = (f"; the branches cross above w/L = {res['crossing']:g}"
                 if res["crossing"] is not None else "")
        out.print(f"the thin-limit ground is not the ground at the atlas width (state 0, "
                  f"{res['states'][0]['shape']}){where}", markup=False, highlight=False)
    elif len(res["states"]) > 1:
        out.print("the same state is the ground at the atlas width and in the thin limit",
                  markup=False, highlight=False)


__all__ = ["thin_limit", "UserError"]
