"""Commands that run studies: ``paper`` (the paper's §VII) and ``bench`` (benchmarks)."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from stiffknots.cli.app import (
    JsonOpt,
    OverwriteOpt,
    ResultsFolder,
    UserError,
    dump,
    err,
    out,
    prepare_out,
    work_starts_note,
)


def bench(
    json_: JsonOpt = False,
    seconds_budget: Annotated[float, typer.Option(
        help="Rough time budget (s): the moves/s timings scale with it, and under 40 s the "
             "time-to-target runs (≈ 15 s each) are skipped; preparing the chains adds "
             "10–50 s.")] = 60.0,
) -> None:
    """Benchmarks: moves per second (N = 150, 1000, 10000), ratio to plain numpy, seconds to
    reach the paper's energies (one core)."""
    from stiffknots.problems import validate as V
    from stiffknots.studies.benchmark import TARGETS, run_benchmarks

    V.number("seconds_budget", seconds_budget, 0, lo_open=True)
    work_starts_note()
    d = run_benchmarks(budget=seconds_budget, log=None if json_ else err.print)
    if json_:
        dump(d)
        return
    t = Table(title="single-bead moves per second (one core)")
    t.add_column("N", justify="right")
    t.add_column("moves/s", justify="right")
    for n, v in d["moves_per_second"].items():
        t.add_row(str(n), f"{v:,.0f}")
    out.print(t)
    out.print(f"plain-numpy ratio at N=150: {d['plain_numpy_ratio']:.0f}×")
    stt = d["seconds_to_target"]
    if "skipped" in stt:
        out.print(f"time to the paper's energies: skipped ({stt['skipped']})")
        return
    t = Table(title="seconds to the target ε, one default replica + final minimiser "
                    "(bead rule, N = 150, one core)")
    for col in ("knot", "target ε", "reached", "median s (CPU)", "worst s (CPU)", "lowest ε",
                "median ε"):
        t.add_column(col, justify="left" if col == "knot" else "right")

    def secs(wall, cpu):
        return "not reached" if wall == float("inf") else f"{wall:.1f} ({cpu:.1f})"

    for k in TARGETS:
        v = stt[k]
        t.add_row(k, f"{v['target']:g}", f"{v['reached']}/{v['seeds']}",
                  secs(v["median_s"], v["median_cpu_s"]), secs(v["worst_s"], v["worst_cpu_s"]),
                  f"{v['final_epsilon_best']:.4f}", f"{v['final_epsilon_median']:.4f}")
    out.print(t)


def paper(
    budget: Annotated[str, typer.Option(
        help="tiny (seconds, smoke test), small (≤ 10 min on 2 cores) or full (paper grade)."
    )] = "small",
    out_dir: Annotated[str, typer.Option(
        "--out", help="Report folder (refused if it holds another run's results, unless "
                      "--overwrite).")] = "results/paper",
    seed: Annotated[int, typer.Option(help="Seed (replica seeds derive from it).")] = 0,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """The paper's Monte Carlo study (§VII): 3_1, 4_1, 5_2, 6_2, 6_3 under the bead rule and
    the tube model; ground and metastable states classified; report.md + report.html."""
    from stiffknots.problems import validate as V
    from stiffknots.studies.paper import BUDGETS, run_paper

    if budget not in BUDGETS:
        raise UserError(f"--budget must be one of {', '.join(BUDGETS)}, got {budget!r}")
    V.seed(seed)
    folder = prepare_out(out_dir, overwrite)
    work_starts_note()
    # the report is written as the study runs: Ctrl-C or an error removes it again
    with ResultsFolder(folder, "paper", doing="running the study"):
        d = run_paper(budget=budget, out_dir=folder, seed=seed,
                      log=None if json_ else out.print)
    if json_:
        dump(d)


def warmup(json_: JsonOpt = False) -> None:
    """Compile and cache the numba kernels now (make does it once after installing)."""
    from stiffknots.studies.warmup import cache_is_cold
    from stiffknots.studies.warmup import warmup as run

    cold = cache_is_cold()
    dt = run(None if json_ else (lambda s: out.print(s, markup=False, highlight=False)))
    if json_:
        dump({"compiled": cold, "seconds": dt, "cache_warm": not cache_is_cold()})
