"""``stiffknots anneal``: a closed knot to its minimum-energy chain (§VII)."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import (
    CheckpointOpt,
    JsonOpt,
    OutOpt,
    OverwriteOpt,
    PolishOpt,
    ReplicaProgress,
    ReplicasOpt,
    ResumeOpt,
    SeedOpt,
    StartOpt,
    check_interrupted,
    claim_checkpoint,
    count,
    emit,
    finish,
    fmt,
    option_name,
    out,
    prepare_out,
)
from stiffknots.report.text import TOUCHING_BELOW, segment_distance_text, touching_note

#: the N from which an unconverged run suggests ``--coarse`` (docs/methods/search.md)
COARSE_HINT_FROM = 300

#: what a bead-rule run that ended without a verdict says next
BEAD_HINT = ("the bead rule's minima lie within tenths of a percent of each other (strands "
             "sink between each other's beads where they cross), so its independent searches "
             "rarely meet; the tube model (--exclusion tube: a smooth tube of the same "
             "diameter, its ε above the bead rule's) converges more often. A verdict is a "
             "statistical statement: another --seed checks it (docs/methods/verdicts.md)")
#: … and an unconverged run of the Monte Carlo
LANGEVIN_HINT = ("The Langevin dynamics (--schedule langevin, the default: every bead moves "
                 "at every step) searches other funnels (docs/methods/search.md)")
#: … and an unconverged run of the dynamics
ANNEALING_HINT = ("The paper's Monte Carlo annealing (--schedule geometric) searches other "
                  "funnels, lower for some knots of the 80 and CB families "
                  "(docs/methods/search.md)")

#: what each schedule given by name runs
_NOTES = {"langevin": "annealing by Langevin dynamics (--schedule langevin)",
          "geometric": "the paper's Monte Carlo annealing, §VII, geometric cooling "
                       "(--schedule geometric)",
          "power": "the paper's Monte Carlo annealing, §VII, power-law cooling "
                   "(--schedule power)",
          "tempering": "Monte Carlo replica exchange (--schedule tempering)"}


def schedule_note(plan) -> str:
    """A sentence saying which search runs and why (:attr:`.AnnealPlan.chosen_by`)."""
    if plan.chosen_by == "auto":
        return ("annealing by Langevin dynamics (--schedule auto: the bead rule's default; "
                "the paper's Monte Carlo annealing, §VII: --schedule geometric)")
    if plan.chosen_by == "monte_carlo":
        given = ", ".join("--exclusion tube" if p == "exclusion" else option_name(p)
                          for p in plan.monte_carlo)
        return ("the paper's Monte Carlo annealing, §VII, geometric cooling (--schedule auto "
                f"with {given}: an option of the Monte Carlo)")
    return _NOTES[plan.schedule.kind]


def anneal(
    name: Annotated[str, typer.Argument(help="Knot name: 3_1, 4_1, 5_2 ...")],
    beads: Annotated[int | None, typer.Option(
        help="Number of beads N (bond length 1); default 150, or with --w-over-L the N rule "
             "(discretisation error below 0.1 %).", parser=count, show_default=False)] = None,
    moves: Annotated[int | None, typer.Option(
        help="Per replica: dynamics steps of the langevin schedule (default 1,000,000 at "
             "any N), attempted moves of the Monte Carlo schedules (default 15,000,000 at "
             "N = 150, scaled as N); 1e6 works too.", parser=count)] = None,
    replicas: ReplicasOpt = 2,
    rounds: Annotated[int | None, typer.Option(
        help="Most rounds of --replicas replicas: after each round the run stops if the "
             "lowest state (shape, ε within 0.1 %) was reached by 2 independent searches (3 "
             "with --exclusion tube, whose funnels above the ground two searches share "
             "too often); "
             "with the Monte Carlo schedules rounds after the second continue the lowest "
             "searches by basin hops while they improve; 1 = a fixed budget (default: 64 "
             "with the langevin schedule, 8 with the others).",
        show_default=False)] = None,
    seed: SeedOpt = 0,
    exclusion: Annotated[str, typer.Option(help="bead (paper, d=1/√2) or tube.")] = "bead",
    w: Annotated[float | None, typer.Option(help="Tube diameter (tube model; default 1/√2).")
                 ] = None,
    w_over_l: Annotated[float | None, typer.Option(
        "--w-over-L", help="Tube diameter over length (sets --exclusion tube, w = (w/L)·N); "
                           "without --beads, N = ⌈(ε/(6·0.001))^½⌉ with ε the knot's upper "
                           "bound (discretisation error ≈ ε/(6N²) below 0.1 %).")] = None,
    schedule: Annotated[str, typer.Option(
        help="auto (default): langevin for the bead rule, geometric where a Monte Carlo "
             "option is given (--exclusion tube, --w, --w-over-L, --tube-route, "
             "--checkpoint, --relax-fraction, --delta, --m-max, --coarse); langevin "
             "(annealing by guarded Langevin dynamics of the whole chain, the peer LAMMPS's "
             "search; for the bead rule it converges more often than the Monte Carlo, "
             "docs/methods/search.md); geometric (the paper's Monte Carlo annealing, §VII, "
             "geometric cooling); power (the paper's power law; use it with --t-start "
             "3e-2); tempering (replica exchange).")] = "auto",
    t_start: Annotated[float | None, typer.Option(
        help="Initial temperature (units of C) (default: 0.1).")] = None,
    t_end: Annotated[float | None, typer.Option(
        help="Final temperature before the quench (default: 1e-6; langevin 1e-4).")] = None,
    relax_fraction: Annotated[float | None, typer.Option(
        help="Fraction of the moves first relaxing the embedding at low T (default: 0.4; "
             "0 = plain annealing).")] = None,
    delta: Annotated[float | None, typer.Option(
        help="Single-bead rotation angle (rad) of the Monte Carlo moves.",
        show_default="π/100 ≈ 0.0314")] = None,
    m_max: Annotated[int | None, typer.Option(
        help="Largest sub-chain of a crankshaft move (default: N/2, a whole loop).")] = None,
    checkpoint: CheckpointOpt = None,
    resume: ResumeOpt = False,
    start: StartOpt = "all",
    polish: PolishOpt = True,
    tube_route: Annotated[bool, typer.Option(
        "--tube-route/--no-tube-route",
        help="Bead rule: new searches from the third round on anneal under the tube rule "
             "(w = d, whose chains the bead rule admits) and are then polished under the "
             "bead rule; they confirm a state but do not certify it (docs/methods/verdicts.md)."
             )] = False,
    from_file: Annotated[str | None, typer.Option(
        "--from", help="Start every replica from the curve in this file (any format of "
                       "`stiffknots identify`; resampled to --beads unit bonds, knot type "
                       "checked); NAME is then checked against it.")] = None,
    coarse: Annotated[int | None, typer.Option(
        help="Coarse to fine: first anneal at this many beads (e.g. 150; two rounds, the "
             "same exclusion and seed), then start every replica from its lowest chain, "
             "resampled to --beads. At large N a fresh search can miss the ground that a search "
             "at N = 150 finds (docs/methods/search.md).", parser=count)] = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """Anneal a knot to its minimum-energy chain (paper §VII), with verified knot type."""
    from stiffknots.engine.driver import default_workers
    from stiffknots.problems import validate as V
    from stiffknots.problems.base import solve
    from stiffknots.problems.closed_plan import plan_anneal
    from stiffknots.problems.pool import WorkerPool

    plan = plan_anneal(name, beads=beads, moves=moves, replicas=replicas, seed=seed,
                       exclusion=exclusion, w=w, w_over_L=w_over_l, schedule=schedule,
                       rounds=rounds, t_start=t_start, t_end=t_end,
                       relax_fraction=relax_fraction, delta=delta, m_max=m_max,
                       checkpoint_dir=checkpoint, resume=resume, start=start, polish=polish,
                       tube_route=tube_route, initial=from_file, coarse=coarse)
    # every input is checked (and the folders claimed) before any work
    checkpoint = claim_checkpoint(checkpoint, resume)
    out_dir = prepare_out(out_dir, overwrite)
    replicas, rounds, beads = plan.replicas, plan.rounds, plan.beads
    # the workers start now and import the solvers while this process builds the problem —
    # except for one short search at a time, which runs here (a worker costs more than it)
    coarse_d = fine_start = None
    quick = plan.quick()
    pool = WorkerPool(default_workers(replicas))
    with pool if quick else pool.start():
        if plan.coarse is not None:
            problem = plan.coarse_problem()
            with ReplicaProgress(f"anneal {problem.knot_name}, coarse stage N = {plan.coarse}",
                                 replicas * problem.rounds, disable=json_) as bars:
                cres = solve(problem, on_replica_done=bars.done, on_progress=bars,
                             isolate=True, pool=pool)
            check_interrupted(cres, None)
            cs = plan.coarse_start(cres)
            fine_start, coarse_d = cs.chain, cs.info
        problem = plan.problem(fine_start)
        if resume:  # a corrupt or foreign checkpoint of any round: one line, before any note
            # (the rounds that start new searches; a continuation's start is known only then)
            for rnd in range(min(rounds, problem.fresh_rounds)):
                V.checkpoints(problem.jobs(first=rnd * replicas))
        with ReplicaProgress(f"anneal {problem.knot_name}", replicas * rounds,
                             disable=json_) as bars:
            res = solve(problem, on_replica_done=bars.done, on_progress=bars,
                        isolate=not quick, pool=pool)
    hint = f"the same command and --resume (checkpoints in {checkpoint})" if checkpoint else None
    check_interrupted(res, hint)
    schedule, width = plan.schedule.kind, res.width
    d = res.to_dict()
    obs = res.best.observables
    d["shape"], d["multiplicity"] = obs["label"], obs["multiplicity"]
    d["shape_reason"] = obs["shape_reason"]
    d["structure"] = obs.get("structure")
    d["schedule"], d["schedule_choice"] = schedule, schedule_note(plan)
    d["max_rounds"] = rounds
    if coarse_d is not None:
        d["coarse"] = coarse_d
    if checkpoint is not None:
        d["checkpoint_dir"] = str(checkpoint)
    if emit(res, d, out_dir, f"{res.knot}: ε = {res.best.epsilon:.3f} ({width.text})",
            "anneal", json_, replicas, hint):
        return
    unit = "dynamics steps" if schedule == "langevin" else "moves"
    t = Table(title=escape(f"{res.knot}, {width.text}, {res.settings['moves']:,} "
                           f"{unit}/replica"))
    # the seeds (64-bit) are in --json and result.json: the table keeps to 80 columns, and ε
    # and the replica are never cut
    for col in ("replica", "start", "ε", "shape", "knot", "min seg dist", "acc single",
                "acc multi", "s"):
        t.add_column(col, justify="right", no_wrap=col in ("replica", "ε"))
    notes = []
    if any(r.leg for r in res.replicas):
        notes.append("↳k: basin hops that continue the search of replica k")
    if any(r.observables.get("search") for r in res.replicas):
        notes.append("ᵗ: annealed under the tube rule w = d, polished under the bead rule")
    if any(r.min_segment_distance < TOUCHING_BELOW for r in res.replicas):
        notes.append(touching_note())
    t.caption = "; ".join(notes) or None
    for r in res.replicas:
        tag = "ᵗ" if r.observables.get("search") else ""
        t.add_row(str(r.replica), f"↳{r.lineage}" if r.leg else f"{r.start}{tag}",
                  f"{r.epsilon:.4f}",
                  r.observables["shape"],
                  escape(str(r.knot)) + (" ✓" if r.knot_verified else " ✗"),
                  segment_distance_text(r.min_segment_distance),
                  *((f"{r.acceptance['single']['rate']:.3f}",
                     f"{r.acceptance['multi']['rate']:.3f}") if r.langevin is None
                    else ("–", "–")),  # no Monte Carlo moves
                  f"{r.wall_time:.1f}")
    out.print(t)
    if coarse_d is not None:
        out.print(f"coarse stage: N = {coarse_d['beads']}, ε = {coarse_d['epsilon']:.4f} "
                  f"({coarse_d['shape']}, {coarse_d['width']['text']}; "
                  f"{'converged' if coarse_d['converged'] else 'not converged'}), its lowest "
                  f"chain resampled to N = {beads} started every replica above"
                  + ("" if coarse_d["epsilon"] == coarse_d["lowest_epsilon"] else
                     f" (its lowest, ε = {coarse_d['lowest_epsilon']:.4f}, does not resample "
                     "with its knot type certified and the exclusion rule held — strands that "
                     "touch or nearly touch where they cross: the lowest chain that does)"),
                  markup=False, highlight=False)
    b = res.bounds
    out.print(f"search: {d['schedule_choice']}", markup=False, highlight=False)
    out.print(f"shape of the best chain: {obs['label']}"
              + (f" (i = {obs['multiplicity']})" if obs["label"] == "CB" else "")
              + f" — {obs['shape_reason']}", markup=False, highlight=False)
    if obs.get("structure"):
        out.print(f"its contact structure (§V B): {obs['structure']}", markup=False,
                  highlight=False)
    out.print(("converged: " if res.converged else "NOT converged: ") + res.convergence,
              markup=False, highlight=False)
    if (not res.converged and beads >= COARSE_HINT_FROM and fine_start is None
            and plan.initial is None):
        out.print(f"at N = {beads} a fresh search can miss the ground that a search at "
                  "N = 150 finds: try --coarse 150 (docs/methods/search.md)",
                  markup=False, highlight=False)
    if not res.converged and width.exclusion == "bead" and rounds > 1:
        out.print(BEAD_HINT + ". " + (ANNEALING_HINT if schedule == "langevin"
                                      else LANGEVIN_HINT),
                  markup=False, highlight=False)
    below = (res.thin_limit.get("excess") or 0.0) < 0
    where = ("below the thin limit of its shape: the discretisation of N beads lowers ε more "
             "than the width raises it" if below
             else "a finite width: the thin limit w/L → 0 lies below")
    out.print(f"best ε = {res.best.epsilon:.4f} at {width.text} ({where}); "
              f"bounds [{fmt(b['lower'])}, {fmt(b['upper'])}] "
              f"({b['attained_by']}); wall time {res.wall_time:.1f} s",
              markup=False, highlight=False)
    out.print(f"thin limit: {res.thin_limit['note']}", markup=False, highlight=False)
    if out_dir is not None:
        out.print(f"results in {out_dir}/ (result.json, best.xyz, best.json, best.png)",
                  markup=False, highlight=False)
    finish(res, replicas, hint)
