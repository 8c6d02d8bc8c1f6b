"""``stiffknots tightest``: the restricted-curvature problem (§IX D)."""

from __future__ import annotations

from typing import Annotated

import typer

from stiffknots.cli import app as A


def tightest(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    max_curvature: Annotated[float | None, typer.Option(
        help="Curvature limit 1/R in 1/(your length unit): the minimal length L† is then "
             "printed in that unit too (the search itself is scale-free: L†/R).")] = None,
    beads: Annotated[int, typer.Option(help="Resolution N (finer → thinner limit).",
                                       parser=A.count)] = 150,
    moves: A.MovesOpt = 30_000_000,
    replicas: A.ReplicasOpt = 2,
    seed: A.SeedOpt = 0,
    exclusion: Annotated[str, typer.Option(
        help="tube (a thin tube regularising the thin knot, the default) or bead (the "
             "paper's rule d = 1/√2: longer knots at a given N).")] = "tube",
    w: Annotated[float | None, typer.Option(
        help="Tube diameter in bond lengths (tube model; default 0.25).")] = None,
    start: A.StartOpt = "all",
    out_dir: A.OutOpt = None,
    overwrite: A.OverwriteOpt = False,
    json_: A.JsonOpt = False,
) -> None:
    """Shortest knot whose curvature never exceeds 1/R (paper §IX D): L†/R and its bounds."""
    from stiffknots.problems import validate as V
    from stiffknots.problems.base import solve
    from stiffknots.problems.tightest import Tightest, radius_of_turn

    beads, moves = V.beads(beads), V.moves(moves)
    replicas, seed = V.replicas(replicas), V.seed(seed)
    if max_curvature is not None:
        V.number("max_curvature", max_curvature, 0, lo_open=True)
    problem = Tightest(name, beads, moves=moves, replicas=replicas, seed=seed,
                       exclusion=exclusion, w=w, start=start)
    out_dir = A.prepare_out(out_dir, overwrite)
    with A.ReplicaProgress(f"tightest {problem.knot_name}", replicas, disable=json_,
                           unit="power energy") as bars:
        res = solve(problem, on_replica_done=bars.done, on_progress=bars, isolate=True)
    A.check_interrupted(res)
    width = res.width
    d = res.to_dict()
    d["max_curvature"] = max_curvature
    if max_curvature is not None:
        d["length"] = d["length_over_R"] / max_curvature
    if A.emit(res, d, out_dir, f"{res.knot}: L†/R = {res.length_over_R:.3f} ({width.text})",
            "tightest", json_, replicas):
        return
    b = res.bounds
    A.out.print(f"{res.knot}: L†/R = {d['length_over_R']:.4f} at {width.text} (bounds "
              f"[{A.fmt(b['lower'])}, {A.fmt(b['upper'])}], {b['attained_by']}); "
              f"θ* = {d['theta_max']:.5f} rad, R = {radius_of_turn(d['theta_max']):.3f} bonds; "
              "replicas " + ", ".join(f"{r.length_over_R:.4f}" for r in res.replicas)
              + f"; {res.wall_time:.0f} s", markup=False, highlight=False)
    if max_curvature is not None:
        A.out.print(f"with 1/R = {max_curvature:g}: L† = {d['length']:.4g}", markup=False,
                  highlight=False)
    A.finish(res, replicas)
