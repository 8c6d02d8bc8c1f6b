"""``stiffknots open``: open knots under tension (§VIII), at fixed extension or fixed force."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import (
    JsonOpt,
    MovesOpt,
    OutOpt,
    OverwriteOpt,
    ReplicaProgress,
    ReplicasOpt,
    ResultsFolder,
    SeedOpt,
    UserError,
    check_interrupted,
    choice,
    count,
    dump,
    finish,
    floats,
    fmt,
    out,
    prepare_out,
)

UNITS = "bond length b = 1, C = 1: force and tension in C/b², eps_e = E·L_e/C"


def open_knot(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_1, 5_2 ...")],
    excess_length: Annotated[str | None, typer.Option(
        "--excess-length", help="Excess length(s) L_e, whole numbers of bond lengths (the "
        "embedding adds whole bonds), e.g. 40,60,80 "
        "(default 80). With --ensemble force: the starting L_e (one value).")] = None,
    force: Annotated[str | None, typer.Option(
        help="Tension(s) F in C/b². Fixed extension: each is turned into the excess length it "
             "selects, L_e = (ε_e C/F)^½, using ε_e measured at the first --excess-length. "
             "--ensemble force: the applied force(s).")] = None,
    ensemble: Annotated[str, typer.Option(
        help="extension: L_e fixed, tension measured (default); force: the ends slide along "
             "z under the force F (energy E_d − F·Δz), L_e measured.")] = "extension",
    beads: Annotated[int | None, typer.Option(
        help="Beads N of the chain (--ensemble force only; default: the embedding with "
             "⌈L_e/4⌉ beads added to each straight end).", parser=count)] = None,
    moves: MovesOpt = 30_000_000,
    replicas: ReplicasOpt = 2,
    seed: SeedOpt = 0,
    exclusion: Annotated[str, typer.Option(
        help="tube (default: w = 0.05, near the thin limit) or bead (the paper's rule "
             "d = 1/√2: a thick tube for an open knot, its ε_e far above the thin limit; "
             "docs/open-knots.md).")
                         ] = "tube",
    w: Annotated[float | None, typer.Option(
        help="Tube diameter in bond lengths (tube model; default 0.05).")] = None,
    w_over_l: Annotated[float | None, typer.Option(
        "--w-over-L", help="Tube diameter over the chain's length (sets --exclusion tube; "
                           "w = (w/L)·L with L = N − 1 the length of each chain of N beads, "
                           "set by the embedding or --beads).")] = None,
    m_max: Annotated[int | None, typer.Option(
        help="Largest sub-chain of a crankshaft move (default: N/2; at most N − 4).")
                     ] = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """Anneal an open knot with its ends clamped on the z axis (paper §VIII); measure μ, ε_e.

    Default ensemble: fixed extension — L_e is fixed, the tension is measured as μ = E/L_e and,
    over several L_e, as −dE/dL_e. With --ensemble force the ends slide along z under the
    force F and L_e is measured (at equilibrium μ = E/L_e = F). --json prints knot, tension,
    excess_length, eps_e, shape of the last point (and force, with --ensemble force), and
    every point.
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems import validate as V
    from stiffknots.problems.open_extension import open_params

    knot = get_knot(name)  # resolved once
    moves, replicas, seed = V.moves(moves), V.replicas(replicas), V.seed(seed)
    choice("--ensemble", ensemble, ("extension", "force"))
    params = open_params(exclusion, w=w, w_over_L=w_over_l, m_max=m_max)
    forces = floats(force, "--force") if force is not None else []
    les = floats(excess_length, "--excess-length") if excess_length is not None else []
    if ensemble == "force":
        problems, follow = _force_problems(knot, forces, les, beads, moves, replicas, seed,
                                           params, w_over_l)
    else:
        problems, follow = _extension_problems(knot, les or [80.0], forces, beads, moves,
                                               replicas, seed, params, w_over_l)
    n_min = min(p.beads for p in problems)
    if m_max is not None and not 1 <= m_max <= n_min - 4:
        raise UserError(f"--m-max must be an integer in [1, {n_min - 4}] (N − 4 for the open "
                        f"chain of {n_min} beads), got {m_max}")
    out_dir = prepare_out(out_dir, overwrite)
    results, stopped = _run(problems, follow, replicas, json_, w_over_l)
    points = [_point(r) for r in results]
    res0, last = results[0], points[-1]
    # the top level reports the last point: its numbers, and the width they were computed at
    # (every point carries its own: at fixed extension N grows with L_e)
    params = results[-1].settings["params"]
    summary = {
        "knot": res0.knot, "ensemble": ensemble,
        **{k: last[k] for k in ("tension", "excess_length", "eps_e", "shape")},
        "bounds": res0.bounds, "points": points, "seed": seed, "moves": moves,
        "replicas": replicas, "beads": last["beads"], "params": params,
        "width": last["width"], "version": res0.version, "units": UNITS,
        "interrupted": stopped is not None,
    }
    summary["thin_limit"] = _thin_limit(last["eps_e"], res0.bounds, summary["width"]["text"])
    if ensemble == "force":
        summary |= {k: last[k] for k in ("force", "force_balance")}
        summary["start_excess_length"] = res0.settings["start_excess_length"]
    elif len(points) >= 2:
        x = [1 / p["excess_length"] ** 2 for p in points]
        y = [p["tension"] for p in points]
        summary["fit_eps_e"] = sum(a * b for a, b in zip(x, y, strict=True)) / sum(
            a * a for a in x)
        summary["finite_differences"] = finite_differences(points)
    if out_dir is not None:
        summary["files"] = _write(out_dir, knot, results, points, summary)
    if json_:
        dump(summary)
        finish(stopped)
        return
    _table(summary, res0)
    if out_dir is not None:
        out.print(f"results in {out_dir}/", markup=False, highlight=False)
    finish(stopped)


def _extension_problems(knot, les, forces, beads, moves, replicas, seed, params, w_over_l):
    """Fixed extension: one problem per --excess-length, checked now; a --force adds a point
    at the L_e it selects, known once ε_e is measured (``follow``)."""
    from stiffknots.problems import validate as V
    from stiffknots.problems.open_extension import OpenExtension
    from stiffknots.theory.bounds import open_bounds

    if beads is not None:
        raise UserError("--beads applies to --ensemble force only (at fixed extension the "
                        "embedding sets N)")
    problems = [OpenExtension(knot, le, moves, replicas, seed, params=params, w_over_L=w_over_l)
                for le in les]
    k = problems[0].knot
    eps_lo = open_bounds(k.bridge_number, k.braid_index).lower or 2 * math.pi**2
    for f in forces:
        V.number("force", f, 0, lo_open=True)
        _selected_length(f, eps_lo)  # the thin-limit estimate must be in range already
    return problems, forces


def _selected_length(force: float, eps_e: float) -> int:
    """The excess length a force selects, (ε_e C/F)^½, checked against the limits."""
    from stiffknots.errors import InvalidParameter
    from stiffknots.problems import validate as V

    le = math.sqrt(eps_e / force)
    lo, hi = V.MIN_EXCESS_LENGTH, V.MAX_EXCESS_LENGTH
    if not lo <= le <= hi:
        raise InvalidParameter("force", force, f"in [{eps_e / hi**2:.3g}, {eps_e / lo**2:.3g}] "
                               "C/b²", f"the excess length it selects, (ε_e C/F)^½ with "
                               f"ε_e ≈ {eps_e:.4g}, must lie in [{lo}, {hi:,}] bonds")
    return int(round(le))


def _force_problems(knot, forces, les, beads, moves, replicas, seed, params, w_over_l):
    """Fixed force: one problem per --force, every one checked now."""
    from stiffknots.problems.open_force import OpenForce

    if not forces:
        raise UserError("--ensemble force needs --force F (in C/b²)")
    if len(les) > 1:
        raise UserError("with --ensemble force, --excess-length is the starting L_e: one "
                        f"value, got {les}")
    le0 = les[0] if les else None
    return [OpenForce(knot, f, beads, moves, replicas, seed, excess_length=le0, params=params,
                      w_over_L=w_over_l) for f in forces], []


def _run(problems, follow, replicas, quiet, w_over_l=None):
    """Solve every problem in turn with live progress; then the extension points that the
    forces in ``follow`` select (ε_e measured at the first point). Returns the results and
    the result that Ctrl-C stopped (None if none)."""
    from stiffknots.problems.base import solve
    from stiffknots.problems.open_extension import OpenExtension

    results = []

    def one(p, label):
        with ReplicaProgress(label, replicas, disable=quiet) as bars:
            r = solve(p, on_replica_done=bars.done, on_progress=bars, isolate=True)
        if not results:
            check_interrupted(r)
        if r.replicas:
            results.append(r)
        return r

    for p in problems:
        label = (f"open {p.knot_name} F = {p.force:g}" if hasattr(p, "force")
                 else f"open {p.knot_name} L_e = {p.excess_length}")
        r = one(p, label)
        if r.interrupted:
            return results, r  # Ctrl-C: report what finished
    p0 = problems[0]
    for f in follow:
        le = _selected_length(f, results[0].eps_e)
        r = one(OpenExtension(p0.knot, le, p0.settings.moves, p0.replicas, p0.seed,
                              params=p0.settings.params, w_over_L=w_over_l),
                f"open {p0.knot_name} F = {f:g}")
        r.requested_force = f
        if r.interrupted:
            return results, r
    return results, None


def finite_differences(points: list[dict]) -> list[dict]:
    """μ = −dE/dL_e between neighbouring excess lengths next to E/L_e at their geometric
    midpoint (:func:`stiffknots.problems.open_extension.finite_differences`: the
    paper's μ = E/L_e checked by an independent estimate, §VIII); each pair says whether its
    two ends have the same shape (otherwise the difference compares two states)."""
    from stiffknots.problems.open_extension import finite_differences as fds

    pts = sorted(points, key=lambda p: p["excess_length"])
    fd = fds(pts)
    for d, a, b in zip(fd, pts[:-1], pts[1:], strict=True):
        d["ratio"] = d["mu_finite_difference"] / d["mu_E_over_L"]
        d["same_shape"] = a["shape"] == b["shape"]
    return fd


def _point(r) -> dict:
    """One row of the output: the physics of one result, its width and its checks."""
    d = r.to_dict()
    keys = ("excess_length", "energy", "eps_e", "tension", "shape", "beads", "knot_verified",
            "wall_time")
    if "force" in d:
        keys += ("force", "force_balance")
    p = {k: d[k] for k in keys}
    p["requested_force"] = getattr(r, "requested_force", None)
    p["width"] = d["width"]
    p["min_segment_distance"] = r.best.min_segment_distance
    p["shape_features"] = d["shape_features"]
    return p


def _write(out_dir: Path, knot, results, points, summary) -> dict:
    """Every result in its own sub-folder (``Le_<L_e>`` or ``F_<F>``), μ against 1/L_e² with
    the bounds, ``summary.json``, and the manifest last (:class:`ResultsFolder`)."""
    files = {}
    with ResultsFolder(out_dir, "open"):
        _write_points(out_dir, knot, results, points, summary, files)
    return files


def _write_points(out_dir: Path, k, results, points, summary, files: dict) -> None:
    from stiffknots.fileio import write_json
    from stiffknots.report.figures import plot_tension, save_figure
    from stiffknots.report.render import save_chain_png

    for r in results:
        tag = f"F_{r.force:g}" if hasattr(r, "force") else f"Le_{r.excess_length:.0f}"
        sub = out_dir / tag
        saved = {k: str(v) for k, v in r.save(sub).items()}
        saved["png"] = str(save_chain_png(
            r.best.coords, sub / "best.png", closed=False,
            title=f"open {r.knot}, {tag.replace('_', ' = ')}: L_e = {r.best.excess_length:.1f}, "
                  f"ε_e = {r.eps_e:.2f}"))
        files[tag] = saved
    pts = [{"knot": k.name, "L_e": p["excess_length"], "mu": p["tension"],
            "n": k.bridge_number, "i": k.braid_index} for p in points]
    files["tension_png"] = str(save_figure(plot_tension(pts), out_dir / "tension.png"))
    files["summary"] = str(write_json(out_dir / "summary.json", summary))


def _thin_limit(eps_e, bounds, width_text) -> dict:
    """How far ε_e lies from the thin limit (§VIII): exact where the bounds meet (n₁ = i₁,
    e.g. 3_1: 2π²), else the bounds' interval."""
    lo, hi = bounds.get("eps_e_lower"), bounds.get("eps_e_upper")
    if eps_e is None or lo is None:
        return {"epsilon": None, "excess": None, "note": f"computed at {width_text}"}
    if hi is not None and math.isclose(lo, hi, rel_tol=1e-12):
        excess = eps_e / lo - 1.0
        return {"epsilon": lo, "excess": excess,
                "note": f"computed at {width_text}: {100 * excess:+.1f} % from the thin limit "
                        f"ε_e = {lo:.4f} (§VIII, exact: n₁ = i₁)"}
    return {"epsilon": None, "lower": lo, "upper": hi, "excess": None,
            "note": f"computed at {width_text}; the thin limit lies in [{fmt(lo)}, {fmt(hi)}] "
                    "(§VIII bounds); a finite width raises ε_e"}


def _table(summary, res0) -> None:
    b = res0.bounds
    force = summary["ensemble"] == "force"
    wd = summary["width"]
    model = (f"tube w = {wd['w']:g}" if wd["exclusion"] == "tube"
             else f"bead rule d = {wd['d']:.4g}")
    t = Table(title=escape(f"open {res0.knot} ({model}; N and w/L per row): ε_e bounds "
                           f"[{fmt(b['eps_e_lower'])}, {fmt(b['eps_e_upper'])}] (§VIII, thin "
                           "limit)"))
    cols = (("F", "L_e", "N", "w/L", "μ = E/L_e", "μ/F") if force
            else ("L_e", "N", "w/L", "F asked", "μ = E/L_e"))
    for col in (*cols, "ε_e = E·L_e", "shape", "knot", "s"):
        t.add_column(col, justify="right")
    for p in summary["points"]:
        wl = f"{p['width']['w_over_L']:.2g}"
        if force:
            head = (f"{p['force']:.4g}", f"{p['excess_length']:.2f}", str(p["beads"]), wl,
                    f"{p['tension']:.5g}", f"{p['force_balance']:.3f}")
        else:
            asked = p["requested_force"]
            head = (f"{p['excess_length']:.0f}", str(p["beads"]), wl,
                    "" if asked is None else f"{asked:.3g}", f"{p['tension']:.5g}")
        t.add_row(*head, f"{p['eps_e']:.3f}", str(p["shape"]),
                  "✓" if p["knot_verified"] else "✗", f"{p['wall_time']:.0f}")
    out.print(t)
    out.print(f"thin limit (last row): {summary['thin_limit']['note']}", markup=False,
              highlight=False)
    if "fit_eps_e" in summary:
        out.print(f"fit μ L_e²/C = {summary['fit_eps_e']:.3f} (2π² = {2 * math.pi ** 2:.3f})",
                  markup=False, highlight=False)
    for d in summary.get("finite_differences", []):
        out.print(f"μ = −dE/dL_e at L_e ≈ {d['L_e']:.1f}: {d['mu_finite_difference']:.5g} "
                  f"against E/L_e {d['mu_E_over_L']:.5g} (ratio {d['ratio']:.3f}"
                  + ("" if d["same_shape"] else "; the two points differ in shape") + ")",
                  markup=False, highlight=False)
