"""The ``stiffknots`` command line (typer + rich). It only composes library calls."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from stiffknots._version import __version__

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Mechanics of stiff knots (Gallotti & Pierre-Louis, PRE 2007) for every knot in "
    "KnotInfo. Units: bond length 1, bending rigidity C = 1, k_B = 1; ε = E·L/C.",
)
out = Console()
err = Console(stderr=True)

PAPER_KNOTS = ("3_1", "4_1", "5_2", "6_2", "6_3")
JsonOpt = Annotated[bool, typer.Option("--json", help="Print a JSON object for scripts.")]


class UserError(Exception):
    """A mistake of the user: reported as one line on stderr, exit code 2."""


def _dump(obj) -> None:
    def default(x):
        try:
            import numpy as np

            if isinstance(x, np.generic):
                return x.item()
            if isinstance(x, np.ndarray):
                return x.tolist()
        except ImportError:  # pragma: no cover
            pass
        raise TypeError(type(x))

    sys.stdout.write(json.dumps(obj, indent=2, default=default) + "\n")


def _fmt(x, nd=4):
    if x is None:
        return "unknown"
    if isinstance(x, float):
        return f"{x:.{nd}f}"
    return str(x)


def knot_summary(name: str) -> dict:
    """Catalogue data and bounds of one knot (closed, open, restricted curvature)."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import closed_bounds, open_bounds, restricted_curvature_bounds

    k = get_knot(name)
    cb = closed_bounds(k.bridge_number, k.braid_index)
    d = {
        "name": k.name,
        "crossing_number": k.crossing_number,
        "bridge_number": k.bridge_number,
        "braid_index": k.braid_index,
        "braid_word": list(k.braid_word) if k.braid_word else None,
        "torus": k.torus_notation,
        "alternating": k.alternating,
        "n_equals_i": k.n_equals_i,
        "lower_bound": cb.lower,
        "upper_bound": cb.upper,
        "upper_bound_attained_by": cb.attained_by,
        "eps_cb": cb.eps_cb,
        "eps_pbl": cb.eps_pbl,
        "predicted_ground_state": (
            {"shape": "CB", "multiplicity": k.braid_index, "epsilon": cb.eps_cb}
            if cb.exact else None
        ),
    }
    if k.bridge_number is not None and k.bridge_number >= 2:
        ob = open_bounds(k.bridge_number, k.braid_index)
        d["open_tension_bounds"] = {"lower": ob.lower, "upper": ob.upper,
                                    "unit": "mu* L_e^2 / C"}
    rc = restricted_curvature_bounds(k.bridge_number, k.braid_index)
    d["restricted_curvature_bounds"] = {"lower": rc.lower, "upper": rc.upper,
                                        "unit": "L_dagger / R"}
    return d


@app.command()
def knot(name: Annotated[str, typer.Argument(help="Knot name: 4_1, 4.1, K11a1, T(2,3) ...")],
         json_: JsonOpt = False) -> None:
    """A knot's data (KnotInfo), its energy bounds and, when n = i, its ground state."""
    d = knot_summary(name)
    if json_:
        _dump(d)
        return
    t = Table(title=f"knot {d['name']}" + (f" = {d['torus']}" if d["torus"] else ""),
              show_header=False)
    t.add_row("crossing number n_c", str(d["crossing_number"]))
    t.add_row("bridge number n", _fmt(d["bridge_number"]))
    t.add_row("braid index i", _fmt(d["braid_index"]))
    t.add_row("braid word", str(d["braid_word"]))
    t.add_row("alternating", _fmt(d["alternating"]))
    t.add_row("ε lower bound 2π²n² (e:epsilon_sup_n2)", _fmt(d["lower_bound"]))
    t.add_row(f"ε upper bound ({d['upper_bound_attained_by']}) (e:epsilon_ineq_0)",
              _fmt(d["upper_bound"]))
    g = d["predicted_ground_state"]
    t.add_row("ground state", f"circular braid, multiplicity {g['multiplicity']}, "
              f"ε* = {g['epsilon']:.4f}" if g else "not fixed by the bounds (n < i)")
    if "open_tension_bounds" in d:
        ob = d["open_tension_bounds"]
        t.add_row("open knot μ*L_e²/C (e:mu_ineq)", f"[{_fmt(ob['lower'])}, {_fmt(ob['upper'])}]")
    rc = d["restricted_curvature_bounds"]
    t.add_row("restricted curvature L†/R (§IX D)", f"[{_fmt(rc['lower'])}, {_fmt(rc['upper'])}]")
    out.print(t)


@app.command()
def elastica(
    out_dir: Annotated[Path | None, typer.Option("--out", help="Write elastica.png here.")] = None,
    json_: JsonOpt = False,
) -> None:
    """The planar elastica constants of Appendix D (loop, 8, 80), checked two ways."""
    from stiffknots.theory.elastica import PAPER_VALUES, elastica_constants, plot_elastica

    c = elastica_constants("integrals")
    c2 = elastica_constants("elliptic")
    d = c.as_dict()
    d["eps_cb_i2"] = 2 * math.pi**2 * 4
    d["eps_cb_i3"] = 2 * math.pi**2 * 9
    d["eps_pbl_n2"] = 16 * c.eps_loop
    d["cross_check"] = {k: abs(v - c2.as_dict()[k]) for k, v in c.as_dict().items()}
    d["paper"] = dict(PAPER_VALUES)
    png = None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        png = out_dir / "elastica.png"
        plot_elastica(str(png))
        d["figure"] = str(png)
    if json_:
        _dump(d)
        return
    t = Table(title="planar elastica (Appendix D)")
    for col in ("constant", "computed", "elliptic check |Δ|", "paper"):
        t.add_column(col)
    for k, v in c.as_dict().items():
        t.add_row(k, f"{v:.10f}", f"{d['cross_check'][k]:.1e}", str(PAPER_VALUES[k]))
    out.print(t)
    if png:
        out.print(f"figure: {png}")


@app.command()
def families(
    max_crossings: Annotated[int, typer.Option(help="Largest crossing number (3..13).")] = 10,
    json_: JsonOpt = False,
) -> None:
    """The n = i family (ground state = circular braid) and its fraction (§VI C)."""
    from stiffknots.knots.catalogue import n_equals_i_knots, n_equals_i_statistics

    if not 3 <= max_crossings <= 13:
        raise UserError(f"--max-crossings must be between 3 and 13, got {max_crossings}")
    st = n_equals_i_statistics(max_crossings)
    knots = n_equals_i_knots(max_crossings)
    tot = st["total"]
    d = {
        "max_crossings": max_crossings,
        "total": tot["knots"],
        "n_equals_i": tot["n_equals_i"],
        "unknown": tot["unknown"],
        "fraction": tot["fraction"],
        "by_crossing": st["by_crossing"],
        "knots": [k.name for k in knots],
    }
    if json_:
        _dump(d)
        return
    t = Table(title=f"n = i prime knots, 3 ≤ n_c ≤ {max_crossings}")
    for col in ("n_c", "knots", "n = i", "unknown", "fraction"):
        t.add_column(col, justify="right")
    for c, row in st["by_crossing"].items():
        t.add_row(str(c), str(row["knots"]), str(row["n_equals_i"]), str(row["unknown"]),
                  _fmt(row["fraction"], 3))
    t.add_row("all", str(tot["knots"]), str(tot["n_equals_i"]), str(tot["unknown"]),
              _fmt(tot["fraction"], 3))
    out.print(t)
    out.print("n = i knots: " + ", ".join(d["knots"]))


def _shape_of(coords, params):
    """The shape class of a closed chain (stiffknots.analysis.classify, §VII)."""
    from stiffknots.analysis import classify

    return classify(coords, d=params.w if params.exclusion == "tube" else params.d)


@app.command()
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

    from stiffknots.annealing import DEFAULT_MOVES
    from stiffknots.annealing import anneal as run
    from stiffknots.engine.schedules import Schedule
    from stiffknots.engine.state import MoveParams

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
        _dump(d)
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
    out.print(f"best ε = {res.best.epsilon:.4f}; bounds [{_fmt(b['lower'])}, {_fmt(b['upper'])}]"
              f" ({b['attained_by']}); wall time {res.wall_time:.1f} s"
              + (" [interrupted]" if res.interrupted else ""))
    if res.interrupted and checkpoint is not None:
        out.print(f"resume with: stiffknots anneal {name} ... --checkpoint {checkpoint} --resume")
    if out_dir is not None:
        out.print(f"results in {out_dir}/ (result.json, best.xyz, best.json, best.png)")


@app.command()
def bench(
    json_: JsonOpt = False,
    seconds_budget: Annotated[float, typer.Option(help="Rough total time budget (s).")] = 60.0,
) -> None:
    """Benchmarks: moves per second (N = 150, 1000, 10000), ratio to plain numpy, seconds to
    reach the paper's energies (one core)."""
    from stiffknots.engine.benchmark import run_benchmarks

    d = run_benchmarks(budget=seconds_budget, log=None if json_ else err.print)
    if json_:
        _dump(d)
        return
    t = Table(title="single-bead moves per second (one core)")
    t.add_column("N", justify="right")
    t.add_column("moves/s", justify="right")
    for n, v in d["moves_per_second"].items():
        t.add_row(str(n), f"{v:,.0f}")
    out.print(t)
    out.print(f"plain-numpy ratio at N=150: {d['plain_numpy_ratio']:.0f}×")
    for k, v in d["seconds_to_target"].items():
        out.print(f"{k}: {v}")


@app.command()
def paper(
    budget: Annotated[str, typer.Option(
        help="tiny (seconds, smoke test), small (≤ 10 min on 2 cores) or full (paper grade)."
    )] = "small",
    out_dir: Annotated[Path, typer.Option("--out", help="Report folder.")] = Path("results/paper"),
    seed: Annotated[int, typer.Option(help="Seed (replica seeds derive from it).")] = 0,
    json_: JsonOpt = False,
) -> None:
    """The paper's Monte Carlo study (§VII): 3_1, 4_1, 5_2, 6_2, 6_3 under the bead rule and
    the tube model; ground and metastable states classified; report.md + report.html."""
    from stiffknots.studies.paper import BUDGETS, run_paper

    if budget not in BUDGETS:
        raise UserError(f"--budget must be one of {', '.join(BUDGETS)}, got {budget!r}")
    d = run_paper(budget=budget, out_dir=out_dir, seed=seed, log=None if json_ else out.print)
    if json_:
        _dump(d)


@app.command()
def version() -> None:
    """Print the package version."""
    out.print(__version__)


# commands of the open-knot and restricted-curvature problems (§VIII, §IX.D)
from stiffknots import cli_open  # noqa: E402,F401


def main() -> None:
    """Entry point: user mistakes → one line on stderr and exit code 2, never a traceback."""
    from stiffknots.knots.catalogue import UnknownKnotError

    try:
        app(standalone_mode=False)
    except (UserError, UnknownKnotError, ValueError) as e:
        # ValueError: EmbeddingError and parameter validation; one line whatever the width
        err.print(f"error: {e}", highlight=False, markup=False, soft_wrap=True)
        raise SystemExit(2) from None
    except typer.Abort:
        err.print("aborted")
        raise SystemExit(130) from None
    except KeyboardInterrupt:
        err.print("interrupted")
        raise SystemExit(130) from None
    except Exception as e:  # click usage errors (typer vendors click: no import of it here)
        if callable(getattr(e, "show", None)) and isinstance(getattr(e, "exit_code", None), int):
            e.show()
            raise SystemExit(e.exit_code) from None
        raise


if __name__ == "__main__":
    # ``python -m stiffknots.cli``: run the imported module's app, on which cli_open has
    # registered ``open`` and ``tightest`` (this file's own copy, ``__main__``, has not)
    from stiffknots.cli import main as _main

    _main()
