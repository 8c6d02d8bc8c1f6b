"""``stiffknots tightest``: the restricted-curvature problem (§IX D)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from stiffknots.cli.app import JsonOpt, UserError, dump, err, fmt, out


def tightest(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    max_curvature: Annotated[float | None, typer.Option(
        help="Curvature limit 1/R in 1/(your length unit): the minimal length L† is then "
             "printed in that unit too (the search itself is scale-free: L†/R).")] = None,
    beads: Annotated[int, typer.Option(help="Resolution N (finer → thinner limit).")] = 150,
    moves: Annotated[int, typer.Option(help="Attempted moves per replica.")] = 30_000_000,
    replicas: Annotated[int, typer.Option(help="Independent replicas (all cores).")] = 2,
    seed: Annotated[int, typer.Option(help="Seed.")] = 0,
    exclusion: Annotated[str, typer.Option(help="bead (d = 1/√2) or tube.")] = "bead",
    start: Annotated[str, typer.Option(
        help="Starting embedding: all (every start that exists for the knot), braid or cage "
             "(two-box rational knots [ab]: 4_1, 5_2, ...).")] = "all",
    out_dir: Annotated[Path | None, typer.Option("--out", help="Write results here.")] = None,
    json_: JsonOpt = False,
) -> None:
    """Shortest knot whose curvature never exceeds 1/R (paper §IX.D): L†/R and its bounds."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from stiffknots.problems.tightest import radius_of_turn
    from stiffknots.problems.tightest import tightest as run

    if max_curvature is not None and max_curvature <= 0:
        raise UserError(f"--max-curvature must be > 0, got {max_curvature}")
    if beads < 8 or replicas < 1:
        raise UserError("--beads must be ≥ 8 and --replicas ≥ 1")
    from stiffknots.knots.starts import STARTS

    if start != "all" and start not in STARTS:
        raise UserError(f"--start must be all or one of {', '.join(STARTS)}, got {start!r}")
    with Progress(TextColumn("[bold]tightest {task.fields[knot]}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total} replicas"), TimeElapsedColumn(),
                  console=err, transient=True, disable=json_) as prog:
        task = prog.add_task("tight", total=replicas, knot=name)
        res = run(name, beads, moves=moves, replicas=replicas, seed=seed, exclusion=exclusion,
                  on_replica_done=lambda _r: prog.advance(task), start=start)
    d = res.to_dict()
    d["max_curvature"] = max_curvature
    if max_curvature is not None:
        d["length"] = d["length_over_R"] / max_curvature
    if out_dir is not None:
        from stiffknots.report.render import save_chain_png

        paths = res.save(out_dir)
        png = Path(out_dir) / "best.png"
        save_chain_png(res.best.coords, png,
                       title=f"{res.knot}: L†/R = {res.length_over_R:.3f} (N = {beads})")
        d["files"] = {k: str(v) for k, v in paths.items()} | {"png": str(png)}
    if json_:
        dump(d)
        return
    b = res.bounds
    out.print(f"{res.knot}: L†/R = {d['length_over_R']:.4f}  (bounds [{fmt(b['lower'])}, "
              f"{fmt(b['upper'])}], {b['attained_by']}); θ* = {d['theta_max']:.5f} rad, "
              f"R = {radius_of_turn(d['theta_max']):.3f} bonds; replicas "
              + ", ".join(f"{r.length_over_R:.4f}" for r in res.replicas)
              + f"; {res.wall_time:.0f} s")
    if max_curvature is not None:
        out.print(f"with 1/R = {max_curvature:g}: L† = {d['length']:.4g}")
