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
    UserError,
    check_interrupted,
    choice,
    claim_checkpoint,
    count,
    emit,
    finish,
    fmt,
    out,
    prepare_out,
    tube_only,
    width_of,
)
from stiffknots.report.text import TOUCHING_BELOW, segment_distance_text, touching_note


def _thin_beads(name: str, w_over_l: float) -> int:
    """The N rule of ``--w-over-L`` (:func:`stiffknots.problems.validate.beads_for_width`)
    with the knot's upper bound as the energy estimate."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems import validate as V
    from stiffknots.theory.bounds import closed_bounds

    k = get_knot(name)
    b = closed_bounds(k.bridge_number, k.braid_index)
    eps = b.upper if b.upper is not None else 4 * b.lower
    return V.beads_for_width(w_over_l, eps)


#: the N from which an unconverged run suggests ``--coarse`` (bench/RESULTS.md, sixth session)
COARSE_HINT_FROM = 300

#: what an adaptive bead-rule run that ended without a verdict says next (the defaults surveys
#: of both models and both engines, bench/RESULTS.md, seventh to ninth sessions)
BEAD_HINT = ("the bead rule's minima lie within tenths of a percent of each other (strands "
             "sink between each other's beads where they cross), so its independent searches "
             "rarely meet: with the defaults (N = 150, the langevin schedule, up to 64 rounds) "
             "33 of the 35 prime knots through 8 crossings converge. The tube model "
             "(--exclusion tube: a smooth tube of the same diameter; its ε lies above the "
             "bead rule's) converges for 33 of 35. A verdict is a statistical statement: "
             "another seed found a lower state for 15 of 66 verdicts of the defaults (by "
             "0.15-23 %: 7_7 233.97 against 189.92) and 5 of 65 tube verdicts (8_13: 216.4 "
             "against 278.5); another --seed checks it")
#: … and an unconverged run of the Monte Carlo (bench/RESULTS.md, eighth and ninth sessions)
LANGEVIN_HINT = ("The Langevin dynamics (--schedule langevin, the default: every bead moves "
                 "at every step) converges for 33 of the 35 and ends lower than the "
                 "annealing's searches on 11 of them (8_11: 209.6 against 251.0)")
#: … and an unconverged run of the dynamics (bench/RESULTS.md, eighth session)
ANNEALING_HINT = ("The paper's Monte Carlo annealing (--schedule geometric) searches other "
                  "funnels: it ends lower than the dynamics on knots of the 80 and CB "
                  "families (6_3: 160.50 against 162.17; 7_3, 8_1, 8_17)")


def pick_schedule(schedule: str, monte_carlo: list[str], rounds: int | None
                  ) -> tuple[str, int, str]:
    """The schedule ``--schedule`` runs, its rounds and a sentence saying what ran and why.

    ``auto`` (the default) is the langevin schedule — the better search of the bead rule
    (bench/RESULTS.md, ninth session: with its 64 rounds 33 of the 35 prime knots through 8
    crossings converge, with the annealing's 8 rounds 23, in about the same time for the
    35) — unless an option of the Monte Carlo is given (``monte_carlo``: the tube model,
    checkpoints, the moves' parameters …), which then runs the paper's annealing
    (geometric). ``rounds`` None: :data:`~stiffknots.problems.closed.LANGEVIN_ROUNDS` for langevin,
    :data:`~stiffknots.problems.closed.DEFAULT_ROUNDS` for the others."""
    from stiffknots.problems.closed import DEFAULT_ROUNDS, LANGEVIN_ROUNDS

    if schedule == "auto" and not monte_carlo:
        kind, note = "langevin", ("annealing by Langevin dynamics (--schedule auto: the bead "
                                  "rule's default; the paper's Monte Carlo annealing, §VII: "
                                  "--schedule geometric)")
    elif schedule == "auto":
        kind, note = "geometric", ("the paper's Monte Carlo annealing, §VII, geometric cooling "
                                   f"(--schedule auto with {', '.join(monte_carlo)}: an option "
                                   "of the Monte Carlo)")
    else:
        kind, note = schedule, _NOTES[schedule]
    if rounds is None:
        rounds = LANGEVIN_ROUNDS if kind == "langevin" else DEFAULT_ROUNDS
    return kind, rounds, note


#: what each schedule given by name runs (:func:`pick_schedule`)
_NOTES = {"langevin": "annealing by Langevin dynamics (--schedule langevin)",
          "geometric": "the paper's Monte Carlo annealing, §VII, geometric cooling "
                       "(--schedule geometric)",
          "power": "the paper's Monte Carlo annealing, §VII, power-law cooling "
                   "(--schedule power)",
          "tempering": "Monte Carlo replica exchange (--schedule tempering)"}


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
             "lowest state (shape, ε within 0.1 %) was reached by 2 independent searches; "
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
             "search; bead rule: 33 of the 35 prime knots through 8 crossings converge, the "
             "Monte Carlo's 23); geometric (the paper's Monte Carlo annealing, §VII, "
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
             "bead rule; they confirm a state but do not certify it (measured: lower grounds "
             "for some knots, higher for as many).")] = False,
    from_file: Annotated[str | None, typer.Option(
        "--from", help="Start every replica from the curve in this file (any format of "
                       "`stiffknots identify`; resampled to --beads unit bonds, knot type "
                       "checked); NAME is then checked against it.")] = None,
    coarse: Annotated[int | None, typer.Option(
        help="Coarse to fine: first anneal at this many beads (e.g. 150; two rounds, the "
             "same exclusion and seed), then start every replica from its lowest chain, "
             "resampled to --beads. At large N a fresh search can miss the ground: 7_4, tube, "
             "N = 600: 228.8 fresh, 163.9 from its N = 150 ground.", parser=count)] = None,
    out_dir: OutOpt = None,
    overwrite: OverwriteOpt = False,
    json_: JsonOpt = False,
) -> None:
    """Anneal a knot to its minimum-energy chain (paper §VII), with verified knot type."""
    from dataclasses import replace

    from stiffknots.engine.driver import default_workers
    from stiffknots.engine.params import MoveParams
    from stiffknots.engine.schedules import SCHEDULES, Schedule
    from stiffknots.knots.starts import STARTS
    from stiffknots.problems import validate as V
    from stiffknots.problems.base import solve
    from stiffknots.problems.closed import ClosedAnneal
    from stiffknots.problems.pool import WorkerPool

    replicas, seed = V.replicas(replicas), V.seed(seed)
    if w_over_l is not None:
        if w is not None:
            raise UserError("--w and --w-over-L both set the tube's diameter; give one")
        exclusion = "tube"  # as `relax --w-over-L`
        if beads is None:
            beads = _thin_beads(name, w_over_l)
        w = V.w_over_L(w_over_l, V.beads(beads)) * beads
    beads = V.beads(150 if beads is None else beads)
    if moves is not None:
        moves = V.moves(moves)
    choice("--start", start, ("all", *STARTS))
    choice("--exclusion", exclusion, ("bead", "tube"))
    choice("--schedule", schedule, ("auto", *SCHEDULES))
    tube_only(w, exclusion)
    monte_carlo = [opt for opt, given in (
        ("--w-over-L" if w_over_l is not None else "--exclusion tube", exclusion == "tube"),
        ("--tube-route", tube_route),
        ("--checkpoint", checkpoint is not None), ("--relax-fraction", relax_fraction is not None),
        ("--delta", delta is not None), ("--m-max", m_max is not None),
        ("--coarse", coarse is not None)) if given]
    schedule, rounds, chosen = pick_schedule(schedule, monte_carlo, rounds)
    rounds = V.integer("rounds", rounds, 1, V.MAX_ROUNDS)
    if schedule in ("tempering", "langevin") and relax_fraction is not None:
        raise UserError("--relax-fraction applies to the power and geometric schedules "
                        f"({schedule} has no relaxation stage)")
    if schedule == "langevin":
        if exclusion != "bead" or tube_route:
            raise UserError("--schedule langevin runs the bead rule (its dynamics holds beads "
                            "apart, not tubes): drop --exclusion tube, --w, --w-over-L and "
                            "--tube-route")
        if checkpoint is not None:
            raise UserError("--checkpoint applies to the Monte Carlo schedules (a langevin "
                            "replica takes seconds)")
        if delta is not None or m_max is not None:
            raise UserError("--delta and --m-max set the Monte Carlo moves; the langevin "
                            "schedule has none (drop them, or give --schedule geometric)")
        if t_end is None:
            from stiffknots.problems.closed import langevin_schedule

            t_end = langevin_schedule(beads).t_end
            if t_start is not None and t_end >= t_start:
                raise UserError(f"--t-start must lie above the langevin schedule's final "
                                f"temperature {t_end:g} (or give --t-end), got {t_start:g}")
    given = {"t_start": t_start, "t_end": t_end, "relax_fraction": relax_fraction}
    sch = replace(Schedule().for_beads(beads), kind=schedule,
                  **{k: v for k, v in given.items() if v is not None})
    params = replace(MoveParams(), exclusion=exclusion,
                     **({} if delta is None else {"delta": delta}),
                     **({} if m_max is None else {"m_max": m_max}),
                     **({} if w is None else {"w": w}))
    if m_max is not None and not 1 <= m_max <= beads - 3:
        raise UserError(f"--m-max must be an integer in [1, {beads - 3}] (N − 3 for --beads "
                        f"{beads}), got {m_max}")
    if coarse is not None:
        coarse = V.beads(coarse, "coarse")
        if coarse >= beads:
            raise UserError(f"--coarse must be fewer beads than --beads ({beads}), got "
                            f"{coarse}")
        if from_file is not None:
            raise UserError("--coarse and --from both give the starting chain; give one")
        if w_over_l is not None:
            raise UserError("--coarse keeps the tube's diameter w in bond units (a thicker "
                            "knot at fewer beads); give --w, not --w-over-L")
    initial = None
    if from_file is not None:
        from stiffknots.errors import ChainFormatError
        from stiffknots.formats import load

        if not from_file.strip():
            raise UserError("--from must name a curve file, got ''")
        try:
            initial = load(from_file)
        except ChainFormatError as exc:
            raise UserError(f"--from {exc}") from None
        if not initial.closed:
            raise UserError(f"--from {from_file}: the curve was read as open; anneal takes a "
                            "closed curve (a knot)")
    # every input is checked (and the folders claimed) before any work
    checkpoint = claim_checkpoint(checkpoint, resume)
    out_dir = prepare_out(out_dir, overwrite)
    from stiffknots.knots.catalogue import get_knot

    get_knot(name)  # an unknown name fails here, before any worker process has started
    # the workers start now and import the solvers while this process builds the problem
    coarse_d = None
    with WorkerPool(default_workers(replicas)).start() as pool:
        if coarse is not None:
            initial, coarse_d = _coarse_stage(name, coarse, replicas, seed, params, start,
                                              polish, json_, pool, beads)
        problem = ClosedAnneal(name, beads=beads, moves=moves, replicas=replicas, seed=seed,
                               schedule=sch, params=params, checkpoint_dir=checkpoint,
                               resume=resume, start=start, rounds=rounds, initial=initial,
                               polish=polish, tube_route=tube_route)
        if resume:  # a corrupt or foreign checkpoint of any round: one line, before any note
            # (the rounds that start new searches; a continuation's start is known only then)
            for rnd in range(min(rounds, problem.fresh_rounds)):
                V.checkpoints(problem.jobs(first=rnd * replicas))
        with ReplicaProgress(f"anneal {problem.knot_name}", replicas * rounds,
                             disable=json_) as bars:
            res = solve(problem, on_replica_done=bars.done, on_progress=bars, isolate=True,
                        pool=pool)
    hint = f"the same command and --resume (checkpoints in {checkpoint})" if checkpoint else None
    check_interrupted(res, hint)
    width = width_of(params, beads)
    d = res.to_dict()
    obs = res.best.observables
    d["shape"], d["multiplicity"] = obs["label"], obs["multiplicity"]
    d["shape_reason"] = obs["shape_reason"]
    d["structure"] = obs.get("structure")
    d["width"] = width
    d["schedule"], d["schedule_choice"], d["max_rounds"] = schedule, chosen, rounds
    if coarse_d is not None:
        d["coarse"] = coarse_d
    if checkpoint is not None:
        d["checkpoint_dir"] = str(checkpoint)
    if emit(res, d, out_dir, f"{res.knot}: ε = {res.best.epsilon:.3f} ({width['text']})",
            "anneal", json_, replicas, hint):
        return
    unit = "dynamics steps" if schedule == "langevin" else "moves"
    t = Table(title=escape(f"{res.knot}, {width['text']}, {res.settings['moves']:,} "
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
    out.print(f"search: {chosen}", markup=False, highlight=False)
    out.print(f"shape of the best chain: {obs['label']}"
              + (f" (i = {obs['multiplicity']})" if obs["label"] == "CB" else "")
              + f" — {obs['shape_reason']}", markup=False, highlight=False)
    if obs.get("structure"):
        out.print(f"its contact structure (§V B): {obs['structure']}", markup=False,
                  highlight=False)
    out.print(("converged: " if res.converged else "NOT converged: ") + res.convergence,
              markup=False, highlight=False)
    if not res.converged and beads >= COARSE_HINT_FROM and coarse is None and initial is None:
        out.print(f"at N = {beads} a fresh search can miss the ground (7_4, tube, N = 600: "
                  "228.8 fresh, 163.9 from its N = 150 ground): try --coarse 150",
                  markup=False, highlight=False)
    if not res.converged and params.exclusion == "bead" and rounds > 1:
        out.print(BEAD_HINT + ". " + (ANNEALING_HINT if schedule == "langevin"
                                      else LANGEVIN_HINT),
                  markup=False, highlight=False)
    below = (res.thin_limit.get("excess") or 0.0) < 0
    where = ("below the thin limit of its shape: the discretisation of N beads lowers ε more "
             "than the width raises it" if below
             else "a finite width: the thin limit w/L → 0 lies below")
    out.print(f"best ε = {res.best.epsilon:.4f} at {width['text']} ({where}); "
              f"bounds [{fmt(b['lower'])}, {fmt(b['upper'])}] "
              f"({b['attained_by']}); wall time {res.wall_time:.1f} s",
              markup=False, highlight=False)
    out.print(f"thin limit: {res.thin_limit['note']}", markup=False, highlight=False)
    if out_dir is not None:
        out.print(f"results in {out_dir}/ (result.json, best.xyz, best.json, best.png)",
                  markup=False, highlight=False)
    finish(res, replicas, hint)


def _coarse_stage(name: str, beads: int, replicas: int, seed: int, params, start: str,
                  polish: bool, quiet: bool, pool, fine_beads: int) -> tuple:
    """``--coarse``: anneal ``name`` at ``beads`` beads (default moves and schedule for that
    N, two rounds: every default start tried; the fine run's move parameters — exclusion,
    diameter in bond units, δ — with the default m_max of that N; the same seed) and return
    its lowest chain that can be resampled to ``fine_beads`` with its knot type certified (the
    start of the fine run, its exclusion rule held) and what to report of it. A bead-rule
    chain whose strands touch at a crossing (4_1's `other` states: 10⁻⁴ apart) cannot be: the
    next lowest is taken, and the report says so."""
    from dataclasses import replace

    from stiffknots.chain import Chain
    from stiffknots.knots.resample import ResampleError, resample
    from stiffknots.problems.base import solve
    from stiffknots.problems.closed import ClosedAnneal

    params = replace(params, m_max=None)
    problem = ClosedAnneal(name, beads=beads, replicas=replicas, seed=seed, params=params,
                           start=start, rounds=2, polish=polish)
    with ReplicaProgress(f"anneal {problem.knot_name}, coarse stage N = {beads}",
                         replicas * 2, disable=quiet) as bars:
        res = solve(problem, on_replica_done=bars.done, on_progress=bars, isolate=True,
                    pool=pool)
    check_interrupted(res, None)
    for r in res.replicas:  # lowest first
        try:
            x = resample(Chain(r.coords, True), fine_beads)
        except ResampleError:
            continue
        # the fine run's rule must hold on the resampled chain (new beads near a touching
        # crossing come closer than d to the other strand)
        if (x.min_bead_distance() >= params.d if params.exclusion == "bead"
                else x.min_segment_distance() >= params.w):
            break
    else:
        raise UserError(f"--coarse {beads}: none of the {len(res.replicas)} coarse chains of "
                        f"{res.knot} resamples to {fine_beads} beads with its knot type "
                        "certified and the exclusion rule held (strands touch where they "
                        "cross); run without --coarse")
    obs = r.observables
    info = {"beads": beads, "epsilon": r.epsilon, "shape": obs["shape"],
            "lowest_epsilon": res.best.epsilon, "replica": r.replica,
            "converged": res.converged, "convergence": res.convergence,
            "width": width_of(params, beads), "replicas": len(res.replicas),
            "wall_time": res.wall_time}
    return Chain(r.coords, True), info
