"""``stiffknots anneal``: a closed knot to its minimum-energy chain (§VII)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from stiffknots.cli.app import JsonOpt, UserError, dump, err, fmt, out


def _shape_of(coords, params):
    """The shape class of a closed chain (stiffknots.analysis.classify, §VII)."""
    from stiffknots.analysis import classify

    return classify(coords, d=params.w if params.exclusion == "tube" else params.d)


def anneal(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    beads: Annotated[int, typer.Option(help="Number of beads N (bond length 1).")] = 150,
    moves: Annotated[int | None, typer.Option(
        help="Attempted moves per replica (default: 30,000,000).")] = None,
    replicas: Annotated[int, typer.Option(help="Independent replicas (all cores).")] = 2,
    seed: Annotated[int, typer.Option(help="Seed (replica seeds derive from it).")] = 0,
    exclusion: Annotated[str, typer.Option(help="bead (paper, d=1/√2) or tube (w=1/√2).")] = "bead",
    schedule: Annotated[str, typer.Option(
        help="power (paper), geometric or tempering (replica exchange).")] = "power",
    t_start: Annotated[float | None, typer.Option(
        help="Initial temperature (units of C) (default: 3e-2).")] = None,
    t_end: Annotated[float | None, typer.Option(
        help="Final temperature before the quench (default: 1e-6).")] = None,
    relax_fraction: Annotated[float | None, typer.Option(
        help="Fraction of the moves first relaxing the embedding at low T (default: 0.4; "
             "0 = plain annealing).")] = None,
    delta: Annotated[float, typer.Option(help="Single-bead rotation angle (rad).")] = math.pi / 100,
    m_max: Annotated[int | None, typer.Option(
        help="Largest sub-chain of a crankshaft move (default: 75 ≥ N/2 at N = 150).")] = None,
    checkpoint: Annotated[Path | None, typer.Option(
        "--checkpoint", help="Write a checkpoint of every replica to this folder.")] = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Continue from the checkpoints in --checkpoint (same arguments).")
    ] = False,
    start: Annotated[str, typer.Option(
        help="Starting embedding: all (braid and cage where they exist, shared among the "
             "replicas), braid (closure of KnotInfo's braid word), cage (4-fold cage of a "
             "two-box rational knot [ab]: 4_1, 5_2, 6_1, ...) or eighty (an 8 plus a circle)."
    )] = "all",
    out_dir: Annotated[Path | None, typer.Option("--out", help="Write results here.")] = None,
    json_: JsonOpt = False,
) -> None:
    """Anneal a knot to its minimum-energy chain (paper §VII), with verified knot type."""
    from dataclasses import replace

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from stiffknots.engine.params import MoveParams
    from stiffknots.engine.schedules import Schedule
    from stiffknots.problems.closed import DEFAULT_MOVES
    from stiffknots.problems.closed import anneal as run

    moves = DEFAULT_MOVES if moves is None else moves
    if beads < 8:
        raise UserError(f"--beads must be ≥ 8, got {beads}")
    if replicas < 1:
        raise UserError(f"--replicas must be ≥ 1, got {replicas}")
    if moves < 1000:
        raise UserError(f"--moves must be ≥ 1000, got {moves}")
    if resume and checkpoint is None:
        raise UserError("--resume needs --checkpoint DIR (the folder of the checkpoints)")
    from stiffknots.knots.starts import STARTS

    if start != "all" and start not in STARTS:
        raise UserError(f"--start must be all or one of {', '.join(STARTS)}, got {start!r}")
    given = {"t_start": t_start, "t_end": t_end, "relax_fraction": relax_fraction}
    sch = replace(Schedule(), kind=schedule, **{k: v for k, v in given.items() if v is not None})
    params = replace(MoveParams(), exclusion=exclusion, delta=delta,
                     **({} if m_max is None else {"m_max": m_max}))
    with Progress(TextColumn("[bold]annealing {task.fields[knot]}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total} replicas"), TimeElapsedColumn(),
                  console=err, transient=True, disable=json_) as prog:
        task = prog.add_task("anneal", total=replicas, knot=name)
        res = run(name, beads=beads, moves=moves, replicas=replicas, seed=seed, schedule=sch,
                  params=params, on_replica_done=lambda r: prog.advance(task),
                  checkpoint_dir=checkpoint, resume=resume, start=start)
    if not res.replicas:
        err.print("interrupted before any replica finished"
                  + (f"; resume with --checkpoint {checkpoint} --resume" if checkpoint else ""))
        raise SystemExit(130)
    d = res.to_dict()
    d["knot"] = res.best.knot
    shape = _shape_of(res.best.coords, params)
    d["shape"], d["multiplicity"] = shape.label, shape.multiplicity
    d["shape_reason"] = shape.reason
    if checkpoint is not None:
        d["checkpoint_dir"] = str(checkpoint)
    if out_dir is not None:
        from stiffknots.report.render import save_chain_png

        paths = res.save(out_dir)
        png = Path(out_dir) / "best.png"
        save_chain_png(res.best.coords,
                       png, title=f"{res.knot}: ε = {res.best.epsilon:.3f} (N = {beads})")
        d["files"] = {k: str(v) for k, v in paths.items()} | {"png": str(png)}
    if json_:
        dump(d)
        return
    t = Table(title=f"{res.knot}, N = {beads}, {moves:,} moves/replica, {exclusion} exclusion")
    for col in ("replica", "seed", "start", "ε", "knot", "min seg dist", "acc single",
                "acc multi", "s"):
        t.add_column(col, justify="right")
    for r in res.replicas:
        t.add_row(str(r.replica), str(r.seed), str(r.start), f"{r.epsilon:.4f}",
                  r.knot + (" ✓" if r.knot_verified else " ✗"),
                  f"{r.min_segment_distance:.3f}", f"{r.acceptance['single']['rate']:.3f}",
                  f"{r.acceptance['multi']['rate']:.3f}", f"{r.wall_time:.1f}")
    out.print(t)
    b = res.bounds
    out.print(f"shape of the best chain: {shape.label}"
              + (f" (i = {shape.multiplicity})" if shape.label == "CB" else "")
              + f" — {shape.reason}")
    out.print(f"best ε = {res.best.epsilon:.4f}; bounds [{fmt(b['lower'])}, {fmt(b['upper'])}]"
              f" ({b['attained_by']}); wall time {res.wall_time:.1f} s"
              + (" [interrupted]" if res.interrupted else ""))
    if res.interrupted and checkpoint is not None:
        out.print(f"resume with: stiffknots anneal {name} ... --checkpoint {checkpoint} --resume")
    if out_dir is not None:
        out.print(f"results in {out_dir}/ (result.json, best.xyz, best.json, best.png)")
