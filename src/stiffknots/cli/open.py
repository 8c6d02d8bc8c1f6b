"""``stiffknots open``: open knots under tension (§VIII), at fixed extension or fixed force."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from stiffknots.cli.app import JsonOpt, UserError, dump, err, floats, fmt, out


def open_knot(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_1, 5_2 ...")],
    excess_length: Annotated[str | None, typer.Option(
        "--excess-length", help="Excess length(s) L_e in bond lengths, e.g. 40,60,80 "
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
             "⌈L_e/4⌉ beads added to each straight end).")] = None,
    moves: Annotated[int, typer.Option(help="Attempted moves per replica.")] = 30_000_000,
    replicas: Annotated[int, typer.Option(help="Independent replicas (all cores).")] = 2,
    seed: Annotated[int, typer.Option(help="Seed.")] = 0,
    exclusion: Annotated[str, typer.Option(help="bead (paper) or tube.")] = "bead",
    w: Annotated[float | None, typer.Option(help="Tube diameter (tube model).")] = None,
    m_max: Annotated[int, typer.Option(help="Largest sub-chain of a crankshaft move.")] = 60,
    out_dir: Annotated[Path | None, typer.Option("--out", help="Write results here.")] = None,
    json_: JsonOpt = False,
) -> None:
    """Anneal an open knot with its ends clamped on the z axis (paper §VIII); measure μ, ε_e.

    Default ensemble: fixed extension — L_e is fixed, the tension is measured as μ = E/L_e and,
    over several L_e, as −dE/dL_e. With --ensemble force the ends slide along z under the
    force F and L_e is measured (at equilibrium μ = E/L_e = F). --json prints knot, tension,
    excess_length, eps_e, shape of the last point (and force, with --ensemble force), and
    every point.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from stiffknots.engine.params import MoveParams
    from stiffknots.problems.open_extension import anneal_open, excess_length_for_force

    if ensemble not in ("extension", "force"):
        raise UserError(f"--ensemble must be extension or force, got {ensemble!r}")
    if ensemble == "force":
        _open_force(name, excess_length, force, beads, moves, replicas, seed, exclusion, w,
                    m_max, out_dir, json_)
        return
    if beads is not None:
        raise UserError("--beads applies to --ensemble force only (at fixed extension the "
                        "embedding sets N)")
    les = floats(excess_length or "80", "--excess-length")
    if any(v != int(v) or v < 8 for v in les):
        raise UserError(f"--excess-length must be integers ≥ 8 (bond lengths), got {les}")
    forces = floats(force, "--force") if force else []
    if any(f <= 0 for f in forces):
        raise UserError(f"--force must be > 0 (units C/b²), got {forces}")
    if replicas < 1 or moves < 1000:
        raise UserError("--replicas must be ≥ 1 and --moves ≥ 1000")
    kw = {"exclusion": exclusion, "m_max": m_max}
    if w is not None:
        kw["w"] = w
    params = MoveParams(**kw)
    results = []
    plan = [int(v) for v in les]
    with Progress(TextColumn("[bold]open {task.fields[knot]} L_e = {task.fields[le]}"),
                  BarColumn(), TextColumn("{task.completed}/{task.total} replicas"),
                  TimeElapsedColumn(), console=err, transient=True, disable=json_) as prog:
        task = prog.add_task("open", total=replicas, knot=name, le=plan[0])

        def one(le):
            prog.reset(task, total=replicas)
            prog.update(task, le=le)
            r = anneal_open(name, le, moves=moves, replicas=replicas, seed=seed, params=params,
                            on_replica_done=lambda _r: prog.advance(task))
            results.append(r)
            return r

        first = one(plan[0])
        for le in plan[1:]:
            one(le)
        for f in forces:
            le = max(8, int(round(excess_length_for_force(first.eps_e, f))))
            r = one(le)
            r.requested_force = f
    points = []
    for r in results:
        d = r.to_dict()
        p = {k: d[k] for k in ("excess_length", "energy", "eps_e", "tension", "shape",
                               "beads", "knot_verified", "wall_time")}
        p["requested_force"] = getattr(r, "requested_force", None)
        p["min_segment_distance"] = r.best.min_segment_distance
        p["shape_features"] = d["shape_features"]
        points.append(p)
    last = points[-1]
    res0 = results[0]
    summary = {
        "knot": res0.knot, "tension": last["tension"], "excess_length": last["excess_length"],
        "eps_e": last["eps_e"], "shape": last["shape"], "bounds": res0.bounds,
        "points": points, "seed": seed, "moves": moves, "replicas": replicas,
        "params": params.as_dict(), "version": res0.version,
        "units": "bond length b = 1, C = 1: tension in C/b², eps_e = E·L_e/C",
    }
    if len(points) >= 2:
        x = [1 / p["excess_length"] ** 2 for p in points]
        y = [p["tension"] for p in points]
        summary["fit_eps_e"] = sum(a * b for a, b in zip(x, y, strict=True)) / sum(
            a * a for a in x)
    if out_dir is not None:
        summary["files"] = _open_files(out_dir, results, points, summary)
    if json_:
        dump(summary)
        return
    from rich.table import Table

    b = res0.bounds
    t = Table(title=f"open {res0.knot}: ε_e bounds [{fmt(b['eps_e_lower'])}, "
                    f"{fmt(b['eps_e_upper'])}] (§VIII)")
    for col in ("L_e", "N", "F asked", "μ = E/L_e", "ε_e = μL_e²", "shape", "knot", "s"):
        t.add_column(col, justify="right")
    for p in points:
        t.add_row(f"{p['excess_length']:.0f}", str(p["beads"]),
                  "" if p["requested_force"] is None else f"{p['requested_force']:.3g}",
                  f"{p['tension']:.5g}", f"{p['eps_e']:.3f}", p["shape"],
                  "✓" if p["knot_verified"] else "✗", f"{p['wall_time']:.0f}")
    out.print(t)
    if "fit_eps_e" in summary:
        out.print(f"fit μ L_e²/C = {summary['fit_eps_e']:.3f} (2π² = {2 * math.pi ** 2:.3f})")
    if out_dir is not None:
        out.print(f"results in {out_dir}/")


def _open_force(name, excess_length, force, beads, moves, replicas, seed, exclusion, w, m_max,
                out_dir, json_) -> None:
    """``stiffknots open --ensemble force``: one fixed-force anneal per --force value."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from stiffknots.engine.params import MoveParams
    from stiffknots.problems.open_force import anneal_open_force

    if not force:
        raise UserError("--ensemble force needs --force F (in C/b²)")
    forces = floats(force, "--force")
    if any(not (f > 0 and math.isfinite(f)) for f in forces):
        raise UserError(f"--force must be > 0 (units C/b²), got {forces}")
    le0 = None
    if excess_length is not None:
        les = floats(excess_length, "--excess-length")
        if len(les) != 1 or les[0] != int(les[0]) or les[0] < 8:
            raise UserError("with --ensemble force, --excess-length is the starting L_e: one "
                            f"integer ≥ 8, got {les}")
        le0 = int(les[0])
    if (beads is not None and beads < 8) or replicas < 1 or moves < 1000:
        raise UserError("--beads must be ≥ 8, --replicas ≥ 1 and --moves ≥ 1000")
    kw = {"exclusion": exclusion, "m_max": m_max}
    if w is not None:
        kw["w"] = w
    params = MoveParams(**kw)
    results = []
    with Progress(TextColumn("[bold]open {task.fields[knot]} F = {task.fields[f]}"),
                  BarColumn(), TextColumn("{task.completed}/{task.total} replicas"),
                  TimeElapsedColumn(), console=err, transient=True, disable=json_) as prog:
        task = prog.add_task("open", total=replicas, knot=name, f=forces[0])
        for f in forces:
            prog.reset(task, total=replicas)
            prog.update(task, f=f)
            results.append(anneal_open_force(
                name, f, n_beads=beads, moves=moves, replicas=replicas, seed=seed,
                excess_length=le0, params=params,
                on_replica_done=lambda _r: prog.advance(task)))
    keys = ("force", "tension", "force_balance", "excess_length", "energy", "eps_e", "shape",
            "beads", "knot_verified", "wall_time")
    points = []
    for r in results:
        d = r.to_dict()
        p = {k: d[k] for k in keys}
        p["min_segment_distance"] = r.best.min_segment_distance
        p["shape_features"] = d["shape_features"]
        points.append(p)
    last = points[-1]
    res0 = results[0]
    summary = {
        "knot": res0.knot, "ensemble": "force", "force": last["force"],
        "tension": last["tension"], "force_balance": last["force_balance"],
        "excess_length": last["excess_length"], "eps_e": last["eps_e"], "shape": last["shape"],
        "bounds": res0.bounds, "points": points, "seed": seed, "moves": moves,
        "replicas": replicas, "beads": res0.beads, "start_excess_length":
            res0.settings["start_excess_length"], "params": params.as_dict(),
        "version": res0.version,
        "units": "bond length b = 1, C = 1: force and tension in C/b², eps_e = E·L_e/C",
    }
    if out_dir is not None:
        import json

        from stiffknots._json import json_default
        from stiffknots.knots.catalogue import get_knot
        from stiffknots.report.figures import plot_tension, save_figure
        from stiffknots.report.render import save_chain_png

        out_dir = Path(out_dir)
        files = {}
        for r in results:
            sub = out_dir / f"F_{r.force:g}"
            r.save(sub)
            save_chain_png(r.best.coords, sub / "best.png", closed=False,
                           title=f"open {r.knot}, F = {r.force:g}: L_e = "
                                 f"{r.excess_length:.1f}, ε_e = {r.eps_e:.2f}")
            files[f"F_{r.force:g}"] = str(sub)
        kk = get_knot(res0.knot)
        pts = [{"knot": r.knot, "L_e": r.excess_length, "mu": r.tension,
                "n": kk.bridge_number, "i": kk.braid_index} for r in results]
        files["tension_png"] = str(save_figure(plot_tension(pts), out_dir / "tension.png"))
        (out_dir / "summary.json").write_text(json.dumps(summary, indent=2,
                                                         default=json_default))
        files["summary"] = str(out_dir / "summary.json")
        summary["files"] = files
    if json_:
        dump(summary)
        return
    from rich.table import Table

    b = res0.bounds
    t = Table(title=f"open {res0.knot} at fixed force: ε_e bounds [{fmt(b['eps_e_lower'])}, "
                    f"{fmt(b['eps_e_upper'])}] (§VIII)")
    for col in ("F", "L_e", "μ = E/L_e", "μ/F", "ε_e = E·L_e", "shape", "knot", "s"):
        t.add_column(col, justify="right")
    for p in points:
        t.add_row(f"{p['force']:.4g}", f"{p['excess_length']:.2f}", f"{p['tension']:.5g}",
                  f"{p['force_balance']:.3f}", f"{p['eps_e']:.3f}", p["shape"],
                  "✓" if p["knot_verified"] else "✗", f"{p['wall_time']:.0f}")
    out.print(t)
    if out_dir is not None:
        out.print(f"results in {out_dir}/")


def _open_files(out_dir: Path, results, points, summary) -> dict:
    import json

    from stiffknots.report.figures import plot_tension, save_figure
    from stiffknots.report.render import save_chain_png

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    files = {}
    for r in results:
        sub = out_dir / f"Le_{int(r.excess_length)}"
        r.save(sub)
        png = sub / "best.png"
        save_chain_png(r.best.coords, png, closed=False,
                       title=f"open {r.knot}, L_e = {r.excess_length:.0f}: ε_e = {r.eps_e:.2f}")
        files[f"Le_{int(r.excess_length)}"] = str(sub)
    k = results[0]
    from stiffknots.knots.catalogue import get_knot

    kk = get_knot(k.knot)
    pts = [{"knot": k.knot, "L_e": p["excess_length"], "mu": p["tension"], "n": kk.bridge_number,
            "i": kk.braid_index} for p in points]
    fig = save_figure(plot_tension(pts), out_dir / "tension.png")
    files["tension_png"] = str(fig)
    (out_dir / "summary.json").write_text(json.dumps(
        {k2: v for k2, v in summary.items() if k2 != "files"}, indent=2, default=float))
    files["summary"] = str(out_dir / "summary.json")
    return files
