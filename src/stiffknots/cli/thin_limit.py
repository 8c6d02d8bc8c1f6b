"""``stiffknots thin-limit``: ε*_w over a series of w/L, extrapolated to w → 0 (§V A), next to
the structure route at w = 0 (§V B)."""

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
        help="small (a few minutes: the widest width annealed, the others by continuation) "
             "or default (up to ~15 min per knot on 2 cores: every width also annealed "
             "afresh, the discretisation coefficient measured).")] = "small",
    seed: SeedOpt = 0,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """ε*_w of a knot in the tube model over a series of w/L (e.g. 0.004 … 0.0005), each point
    annealed or continued from the previous width and polished, corrected for the
    discretisation and extrapolated to w/L → 0 with an error bar; compared with the
    structure route (CB(i) = 2π²i², the 80, the 4-fold cage) at w = 0."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems import validate as V
    from stiffknots.problems.base import solve
    from stiffknots.studies.thin_limit import BUDGET_NAMES, plot, thin_limit

    choice("--budget", budget, BUDGET_NAMES)
    V.seed(seed)
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
            res = thin_limit(knot, budget, seed, runner=runner, say=say)
    except KeyboardInterrupt:
        from stiffknots.cli.app import Interrupted

        raise Interrupted("interrupted: the thin-limit series is incomplete; nothing to "
                          "report") from None
    chains = res.pop("chains")
    if out_path is not None:
        res["files"] = _write(out_path, res, chains, plot)
    if json_:
        dump(res)
        return
    _table(res)
    if out_path is not None:
        out.print(f"results in {out_path}/ (result.json, thin_limit.png, chains)",
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


def _write(path, res, chains, plot) -> dict:
    from stiffknots.chain import Chain
    from stiffknots.fileio import write_json
    from stiffknots.formats import save

    files = {}
    with ResultsFolder(path, "thin-limit"):
        for wl, x in chains.items():
            p = path / f"chain_w_over_L_{wl}.xyz"
            save(Chain(x, closed=True), p)
            files[wl] = str(p)
        files["png"] = str(plot(res, path / "thin_limit.png"))
        files["result"] = str(write_json(path / "result.json", res | {"files": dict(files)}))
    return files


def _table(res) -> None:
    t = Table(title=escape(f"{res['knot']}: ε*_w in the tube model ({res['budget']} budget, "
                           f"seed {res['seed']})"))
    for col in ("w/L", "N", "ε_N", "ε corr.", "σ", "shape", "route", "conv.", "fit"):
        t.add_column(col, justify="right", no_wrap=True)
    for p in res["points"]:
        t.add_row(f"{p['w_over_L']:g}", str(p["beads"]), f"{p['epsilon_raw']:.4f}",
                  f"{p['epsilon']:.4f}", f"{p['sigma']:.1g}", str(p["shape"]),
                  {"anneal": "anneal", "continuation": "cont."}[p["route"]],
                  "yes" if p["converged"] else "NO", "yes" if p["in_fit"] else "no")
    out.print(t)
    d = res["discretisation"]
    out.print(f"discretisation: ε = ε_N (1 + k/N²), k = {d['k']:.3f} ± {d['k_error']:.3f}"
              + (f" (measured at N = {d['check_beads']})" if "k_measured" in d else
                 " (polygon rule ε/6)") + f": ± {d['error']:.2g} on ε*",
              markup=False, highlight=False)
    f = res["fit"]
    if f is None or res["epsilon_thin"] is None:
        out.print("fewer than two points of the thinnest shape: no extrapolation",
                  markup=False, highlight=False)
        return
    pr = f" (1σ range {f['p_range'][0]:.2f}–{f['p_range'][1]:.2f})" if f["p_range"] else ""
    out.print(f"fit ε(w) = ε* + a (w/L)^p: p = {f['p']:.2f}{pr}, a = {f['a']:.4g}, "
              f"χ²/dof = {f['chi2']:.3g}/{f['dof']}", markup=False, highlight=False)
    out.print(f"thin limit w/L → 0 ({res['shape']}): ε* = {res['epsilon_thin']:.4f} ± "
              f"{res['error']:.2g} (fit: statistical {f['stat_error']:.2g}, exponent "
              f"{f['exponent_error']:.2g}, fit range {f['range_error']:.2g}; discretisation "
              f"{d['error']:.2g})", markup=False, highlight=False)
    s = res["structure"]
    if s is not None:
        out.print(f"structure route at w = 0: {s['name']} = {s['epsilon']:.6f}; difference "
                  f"{s['difference']:+.4f} ({s['in_error_bars']:.1f} error bars)",
                  markup=False, highlight=False)
    if not res["series_decreasing"]:
        out.print("note: ε does not decrease along the series as w/L decreases",
                  markup=False, highlight=False)


__all__ = ["thin_limit", "UserError"]
