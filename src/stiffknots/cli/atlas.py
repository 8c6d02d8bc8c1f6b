"""``stiffknots atlas``: sweep every prime knot through K crossings on Dask, store the results,
write the atlas pages (:mod:`stiffknots.studies.atlas`)."""

from __future__ import annotations

import shlex
import sys
import threading
import time
from typing import Annotated

import typer
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
)
from rich.table import Table

from stiffknots.cli.app import (
    Interrupted,
    JsonOpt,
    SeedOpt,
    UserError,
    choice,
    claim_folder,
    count,
    dump,
    err,
    floats,
    out,
    prepare_file,
)


def _hms(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class SweepProgress:
    """A live bar over the sweep's jobs on stderr: jobs done of planned (a running job counts
    by its moves done), time left, the last job finished. Where stderr is not a terminal (a
    log file, a batch job) the bar is not drawn; a line per finished job says the same
    instead (jobs done of planned, elapsed, time left, the job's result). With ``--json`` the
    same goes to stderr (a sweep takes hours; stdout holds the JSON alone); ``disable`` shows
    nothing (a caller that draws its own). It has every method of
    :class:`stiffknots.sweeps.SweepListener` without being a subclass, so that the command line
    starts without importing Dask.

    Time left is the mean pace so far times the jobs *expected*, not only those planned: a
    (knot, model) not converged gets replicas added, so the plan grows as the sweep goes
    (:func:`stiffknots.sweeps.run.expected_todo`: for every one still open, the mean added
    replicas of the settled ones of its model and crossing number). Until a first (knot,
    model) settles it counts the plan alone and says so ("≥")."""

    def __init__(self, disable: bool = False, console=None):
        console = err if console is None else console
        self.progress = Progress(
            TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("jobs"), TimeElapsedColumn(), TextColumn("ETA {task.fields[eta]}"),
            TextColumn("{task.fields[last]}"), console=console, transient=True,
            # not drawn where stderr is not a terminal (the log lines below say the same; an
            # undrawn live display still printed a blank line, before a one-line error too)
            disable=disable or not console.is_terminal)
        self.log_lines = not disable and not console.is_terminal
        self.t0 = time.monotonic()
        self.task = None
        self.total = 0
        self.done = 0
        self.running: dict[str, float] = {}
        self.lock = threading.Lock()
        self.disable = disable
        self.expect: float | None = None  # jobs expected in all (None: the plan alone)

    def __enter__(self):
        self.progress.__enter__()
        return self

    def __exit__(self, *exc):
        return self.progress.__exit__(*exc)

    def started(self, result) -> None:
        if not self.disable and result.skipped:
            self.progress.console.print(
                f"{result.skipped} of {result.jobs} jobs already stored: skipped",
                highlight=False)
        self.t0 = time.monotonic()
        self.total = result.todo
        self.task = self.progress.add_task("sweep", total=result.todo, last="", eta="–")

    def cluster(self, description: str, threads: int) -> None:
        if self.task is not None:
            self.progress.update(self.task, description=f"sweep ({threads} workers)")

    def time_left(self) -> str:
        """Time left at the mean pace so far over the jobs expected ("≥" before any (knot,
        model) settled: the plan alone), e.g. ``"1:02:03 (≈ 480 jobs)"``; "–" before any
        work is done."""
        done = self.done + sum(self.running.values())
        el = time.monotonic() - self.t0
        if done <= 0 or el <= 0:
            return "–"
        planned = self.expect is None or self.expect <= self.total + 0.5
        total = self.total if planned else self.expect
        left = el * max(total - done, 0.0) / done
        if planned:
            return ("≥ " if self.expect is None else "") + _hms(left)
        return f"{_hms(left)} (≈ {round(total):,} jobs)"

    def expected(self, jobs: float, settled: int) -> None:
        with self.lock:
            self.expect = float(jobs) if settled else None  # None: the plan alone, "≥"
            self._update()

    def _update(self, last: str | None = None) -> None:
        if self.task is None:
            return
        kw = {"completed": min(self.done + sum(self.running.values()), self.total),
              "eta": self.time_left()}
        if last is not None:
            kw["last"] = last
        self.progress.update(self.task, **kw)

    def progress(self, job: str, done: int, total: int, best=None, pid=None) -> None:
        with self.lock:
            if total:
                self.running[job] = min(done / total, 0.999)
            self._update()

    def added(self, jobs: int) -> None:
        with self.lock:
            self.total += jobs
            if self.task is not None:
                self.progress.update(self.task, total=self.total)

    def seeded(self, entry: dict) -> None:
        with self.lock:
            last = (f"{entry['knot']}/{entry['model']}: seeded from tube replica "
                    f"{entry.get('tube_replica', '?')}, ε = {entry['epsilon']:.2f}")
            self._update(escape(last))
            if self.log_lines:
                self.progress.console.print(f"{time.strftime('%H:%M:%S')} {last}",
                                            markup=False, highlight=False, soft_wrap=True)

    def finished(self, job, row, error) -> None:
        with self.lock:
            self.running.pop(job.id, None)
            self.done += 1
            if row is not None:
                shape = f"CB(i={row['multiplicity']})" if row["shape"] == "CB" else row["shape"]
                last = f"{job.id}: ε = {row['epsilon']:.2f} {shape}"
            else:
                last = f"{job.id}: failed"
            self._update(escape(last))
            if self.log_lines:
                el = time.monotonic() - self.t0
                self.progress.console.print(
                    f"{time.strftime('%H:%M:%S')} {self.done}/{self.total} jobs, "
                    f"{_hms(el)} elapsed, ETA {self.time_left()} — {last}",
                    markup=False, highlight=False, soft_wrap=True)


def cluster_options(scheduler: str | None, workers: int | None) -> str | None:
    """Check --scheduler and --workers before any work: the scheduler's address (normalised)
    or None for a local cluster of ``workers`` processes."""
    from stiffknots.sweeps.cluster import local_workers, scheduler_address

    if scheduler is None:
        local_workers(workers)
        return None
    if workers is not None:
        raise UserError("--workers is for the local cluster; a --scheduler has its own")
    return scheduler_address(scheduler)


def _knot_list(text: str | None) -> list[str] | None:
    if text is None:
        return None
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names:
        raise UserError("--knots must be knot names separated by commas, e.g. 3_1,4_1,5_2")
    return names


def atlas(
    max_crossings: Annotated[int | None, typer.Option(
        help="Every prime knot with 3 ≤ n_c ≤ K (3..13); with --knots, a limit on them.")
    ] = None,
    knots: Annotated[str | None, typer.Option(
        help="Only these knots, separated by commas (3_1,4_1,5_2).")] = None,
    crossings: Annotated[str | None, typer.Option(
        help="Only the knots of these crossing numbers, separated by commas (11,12); alone, "
             "every prime knot of them.")] = None,
    sample: Annotated[int | None, typer.Option(
        help="A random sample of N of the knots chosen, drawn with --seed (the same command "
             "draws the same sample, so it resumes).", parser=count)] = None,
    models: Annotated[str, typer.Option(
        help="Exclusion models, separated by commas: bead (the paper's rule d = 1/√2) and/or "
             "tube (diameter --w).")] = "bead,tube",
    budget: Annotated[str, typer.Option(
        help="Replicas × moves per knot and model: tiny (2 × 0.2 M, a smoke test), small "
             "(2 × 5 M), default (2 × 15 M, up to 6 replicas until converged, then up to 2 "
             "continuation legs for the tube model; the bead model's replicas Langevin "
             "dynamics of 10⁶ steps, up to 16, then up to 4 Langevin legs) or full (4 × 60 "
             "M, up to 12, 2 legs; bead Langevin up to 32, 4 legs).")
    ] = "default",
    out_dir: Annotated[str, typer.Option(
        "--out", help="Folder of the atlas pages.")] = "results/atlas",
    db: Annotated[str, typer.Option(
        help="Results database: stored replicas are reused (resume), new ones added.")
    ] = "results/stiffknots.db",
    scheduler: Annotated[str | None, typer.Option(
        help="Address of a running Dask scheduler (tcp://host:8786) or its scheduler "
             "file (--scheduler-file of stiffknots-dask scheduler); default: a local "
             "cluster of one worker process per core.")] = None,
    workers: Annotated[int | None, typer.Option(
        help="Worker processes of the local cluster (default: one per core).")] = None,
    w: Annotated[float | None, typer.Option(
        help="Tube diameter of the tube model (bond units; default 1/√2).")] = None,
    replicas: Annotated[int | None, typer.Option(
        help="Replicas per knot and model instead of the budget's.", parser=count)] = None,
    moves: Annotated[int | None, typer.Option(
        help="Attempted moves per annealing replica instead of the budget's (3e7 works "
             "too); a Langevin bead replica keeps its 10⁶ steps (--bead-steps sets them).",
        parser=count)] = None,
    max_replicas: Annotated[int | None, typer.Option(
        help="Add replicas, 2 at a time, to every knot and model whose ground state has not "
             "converged, up to this many in all, every model (default: the budget's: 6 for "
             "default, 12 for full, the Langevin bead model 16 and 32; none added for tiny "
             "and small, nor with --replicas or --moves).",
        parser=count)] = None,
    bead_search: Annotated[str | None, typer.Option(
        help="How the bead model's replicas search: annealing (the paper's Monte Carlo, "
             "--moves moves) or langevin (Langevin dynamics of 10⁶ steps, every bead moving "
             "at once, as anneal's default). Default: the budget's (langevin for default "
             "and full, annealing for tiny and small).")] = None,
    bead_steps: Annotated[int | None, typer.Option(
        help="Steps of the Langevin dynamics of every bead-model replica instead of 10⁶ (a "
             "deeper search, ≈ 4 CPU s per 10⁶ at N = 150; another ensemble in --db). 3e6 "
             "found lower bead grounds for some knots the default leaves unconverged.",
        parser=count)] = None,
    coarse: Annotated[int | None, typer.Option(
        help="Coarse to fine: every tube replica first anneals its start at this many beads "
             "(fewer than the model's N; the same w in bond units, moves per bead and "
             "cooling) and searches from that chain resampled to N. On the knots whose "
             "verdicts the audit beat, single searches so reached the lowest known states "
             "more often per CPU second than searches of twice the moves; 100 at N = 150. "
             "Another ensemble in --db.", parser=count)] = None,
    seed: SeedOpt = 0,
    stored: Annotated[bool, typer.Option(
        "--stored", help="Run nothing: write the pages from the replicas already in --db "
                         "(a sweep stopped part-way; its knots without results get a row "
                         "that says so). The same command without --stored runs the rest.")
    ] = False,
    thin: Annotated[bool, typer.Option(
        "--thin", help="After the sweep, follow every state of each knot's tube census to "
                       "w = 0 (branches extrapolated and the structure route; a job per "
                       "knot on Dask, resumable): the pages and --json gain the thin-limit "
                       "ground (ε*). Needs tube in --models.")] = False,
    thin_budget: Annotated[str, typer.Option(
        help="The thin stage's ladder: small (w/L 0.004 … 0.0005, 4 widths, ≈ 1 CPU min a "
             "state) or default (0.004 … 0.00025, 9 widths, the polygon constant measured: "
             "≈ 3× longer, the errors smaller).")] = "small",
    thin_states: Annotated[int | None, typer.Option(
        help="Follow only the N lowest states of each census (default: every state within "
             "15 % of the lowest).", parser=count)] = None,
    json_: JsonOpt = False,
) -> None:
    """The atlas: ground and metastable states of every prime knot through K crossings
    (§VII), bead rule and tube, swept on Dask into the results database, tested against the
    paper's families (§VI C, §VII), written as static pages (index.html)."""
    from stiffknots.problems import validate as V
    from stiffknots.studies.atlas import run_atlas
    from stiffknots.sweeps import budget_of, parse_models, resolve_knots

    if max_crossings is None and knots is None and crossings is None:
        raise UserError("give --max-crossings K (every prime knot through K crossings), "
                        "--crossings 11,12 or --knots 3_1,4_1,...")
    # every input is checked before any work; the knot names (the catalogue: seconds) last
    knot_list = _knot_list(knots)
    mods = parse_models(models, w=w)
    if w is not None and "tube" not in [m.exclusion for m in mods]:
        raise UserError("--w is the tube diameter: add tube to --models")
    if bead_search is not None:
        from stiffknots.sweeps.budgets import BEAD_SEARCHES

        choice("--bead-search", bead_search, BEAD_SEARCHES)
        if "bead" not in [m.exclusion for m in mods]:
            raise UserError("--bead-search sets the bead model's search: add bead to --models")
    if bead_steps is not None and "bead" not in [m.exclusion for m in mods]:
        raise UserError("--bead-steps sets the bead model's dynamics: add bead to --models")
    if coarse is not None:
        tubes = [m for m in mods if m.exclusion == "tube"]
        if not tubes:
            raise UserError("--coarse sets the tube model's replicas: add tube to --models")
        V.integer("coarse", coarse, 3, min(m.beads for m in tubes) - 1)
    bud = budget_of(budget, replicas=replicas, moves=moves, bead_search=bead_search,
                    bead_steps=bead_steps, coarse=coarse)
    V.seed(seed)
    if max_replicas is not None:  # None: the budget's (run_sweep)
        V.integer("max_replicas", max_replicas, bud.replicas, V.MAX_REPLICAS)
    if thin:
        choice("--thin-budget", thin_budget, ("small", "default"))
        if "tube" not in [m.exclusion for m in mods]:
            raise UserError("--thin follows the tube model's states to w = 0: add tube to "
                            "--models")
        if stored:
            raise UserError("--thin runs the thin stage and --stored runs nothing: drop one "
                            "(the pages show a stored thin stage either way)")
        if thin_states is not None:
            V.integer("thin_states", thin_states, 1, 1000)
    elif thin_states is not None or thin_budget != "small":
        raise UserError("--thin-budget and --thin-states set the thin stage: add --thin")
    scheduler = cluster_options(scheduler, workers)
    cross = None
    if crossings is not None:
        vals = floats(crossings, "--crossings")
        if any(v != int(v) for v in vals):
            raise UserError(f"--crossings must be whole numbers, got {crossings!r}")
        cross = [int(v) for v in vals]
    names = resolve_knots(knot_list, max_crossings, crossings=cross, sample=sample, seed=seed)
    from pathlib import Path

    # a sweep writes --db: checked writable (a read-only or immutable file lost the first
    # replica); --stored only reads an existing one (read-only media too)
    db = Path(db) if stored and Path(db).is_file() else prepare_file(db, "--db")
    out_dir = claim_folder(out_dir, "--out")  # locked: one atlas at a time writes there
    command = "stiffknots " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    with SweepProgress() as bar:  # on stderr, --json too: stdout holds the JSON alone
        d = run_atlas(names, mods, bud, db=db, out=out_dir, seed=seed, scheduler=scheduler,
                      workers=workers, max_replicas=max_replicas, listener=bar,
                      command=command, run=not stored,
                      thin=thin_budget if thin else None, thin_states=thin_states,
                      thin_listener=ThinLines())
    sw = d["sweep"]
    n_stored = sw["skipped"] + sw["ran"]
    if sw["interrupted"]:
        if json_:
            dump(d)
        raise Interrupted(f"interrupted: {n_stored} of {sw['jobs']} jobs are stored in {db}; "
                          "run the same command to resume")
    th = d.get("thin")
    if th is not None and th["interrupted"]:
        if json_:
            dump(d)
        raise Interrupted(f"interrupted in the thin stage: {len(th['skipped']) + len(th['ran'])}"
                          f" of {len(th['jobs']) + len(th['skipped'])} knots are stored in "
                          f"{db}; run the same command to resume")
    if json_:
        dump(d)
    else:
        _print(d, mods)
    if sw["failed"]:
        for f in sw["failed"]:
            err.print(f"failed: {f['job']}: {f['error']}", highlight=False, markup=False,
                      soft_wrap=True)
        err.print(f"{len(sw['failed'])} of {sw['jobs']} jobs failed (not stored); the atlas "
                  "shows the others", highlight=False)
        raise typer.Exit(1)
    if th is not None and th["failed"]:
        err.print(f"{len(th['failed'])} knots of the thin stage failed (not stored); the atlas "
                  "shows the others", highlight=False)
        raise typer.Exit(1)


class ThinLines:
    """The thin stage's progress, line by line on stderr (each worker's relaxations and each
    knot's verdict as it is stored)."""

    def started(self, res) -> None:
        if res.jobs or res.skipped:
            err.print(f"thin stage ({res.budget}): {len(res.jobs)} knots to follow to w = 0, "
                      f"{len(res.skipped)} stored before", highlight=False, markup=False)
        for m in res.missing:
            err.print(f"thin stage: {m['knot']}: {m['why']}", highlight=False, markup=False)

    def line(self, knot: str, text: str) -> None:
        err.print(f"  {text}", highlight=False, markup=False, soft_wrap=True)

    def finished(self, knot: str, rows, error: str | None) -> None:
        if error is not None:
            err.print(f"thin stage: {knot} failed: {error}", highlight=False, markup=False,
                      soft_wrap=True)
            return
        g = next((r for r in rows if r["ground"]), None)
        if g is None:
            err.print(f"thin stage: {knot} stored: no state reached w = 0 in its own state",
                      highlight=False, markup=False)
        else:
            e = f" ± {g['error']:.2g}" if g["error"] is not None else ""
            err.print(f"thin stage: {knot} stored: thin-limit ground {g['name']}, ε* = "
                      f"{g['epsilon_thin']:.4f}{e}", highlight=False, markup=False)


def _print(d: dict, mods) -> None:
    from stiffknots.studies.atlas import not_converged_text

    sw = d["sweep"]
    t = Table(title=f"{len(d['knots'])} knots — {', '.join(m.text for m in mods)}",
              caption="ground state and ε; ✓ converged, · not; +k metastable states")
    # one cell per model, never cut: the table keeps to 80 columns in a pipe or a log
    for col in ("knot", "n_c", "families"):
        t.add_column(col, justify="right" if col == "n_c" else "left", no_wrap=col == "knot")
    for m in mods:
        t.add_column(f"{m.exclusion}", justify="right", no_wrap=True)
    for e in d["knots"]:
        cells = [e["name"], str(e["crossing_number"]), ",".join(e["families"]) or "—"]
        for m in mods:
            me = e["models"][m.exclusion]
            g = me["ground"]
            cells.append(f"{g['name']} {g['epsilon']:.2f} {'✓' if me['converged'] else '·'} "
                         f"+{len(me['metastable'])}" if g else "—")
        t.add_row(*[escape(c) for c in cells])
    out.print(t)
    fam = d["families"]
    for r in fam["catalogue"]:
        paper = f" (paper: {100 * r['paper']:.0f} %)" if r.get("paper") is not None else ""
        out.print(f"families cover {r['covered']} of {r['knots']} knots with {r['label']} "
                  f"({100 * (r['fraction'] or 0):.0f} %){paper}", highlight=False)
    for g in fam["groups"]:
        if not g["knots"]:  # nothing stored for that group yet
            continue
        out.print(f"{g['label']}: {g['knots']} ground states ({fam['model']}, "
                  f"{fam['width']}): " + ", ".join(f"{k} {v}" for k, v in g["counts"].items())
                  + f"; as the family predicts {g['as_predicted']}, converged "
                  f"{g['converged']}", highlight=False, markup=False)
    nf = fam.get("no_family_structures") or []
    if nf:
        top = "; ".join(f"{g['structure']} {g['count']} ({', '.join(g['knots'][:4])}"
                        + (", …" if g["count"] > 4 else "") + ")" for g in nf[:3])
        out.print(f"in no family: {sum(g['count'] for g in nf)} ground states in {len(nf)} "
                  f"contact structures (§V B); the commonest: {top}", highlight=False,
                  markup=False)
    conv = ", ".join(f"{k} {c['converged']} of {c['knots']} ({100 * d['converged'][k]:.0f} %)"
                     for k, c in d["converged_counts"].items() if c["knots"])
    out.print(f"converged ({fam['rule']}): {conv or 'no results stored yet'}", highlight=False,
              markup=False)
    if any(c["not_converged"] for c in d["converged_counts"].values()):
        out.print(f"not converged: {not_converged_text(d['converged_counts'])}",
                  highlight=False, markup=False, soft_wrap=True)
    missed = [e for e in d["knots"] if e.get("bead_above_tube")]
    if missed:
        out.print("bead-rule ground above the tube's (a tube chain of the same width is "
                  "bead-admissible, so the bead search missed): " + ", ".join(
                      f"{e['name']} {e['bead_above_tube']['bead']:.2f} > "
                      f"{e['bead_above_tube']['tube']:.2f}" for e in missed),
                  highlight=False, markup=False)
    if sw.get("seeded"):
        below = dict.fromkeys(e["knot"] for e in sw["seeded"]
                              if e["bead_epsilon"] is None or e["epsilon"] < e["bead_epsilon"])
        out.print(f"{len(sw['seeded'])} bead-rule replicas seeded from the tube replicas (each "
                  f"polished under the bead rule: start 'tube-ground'); one below every bead "
                  f"search of its own: {', '.join(below) or 'none'}", highlight=False,
                  markup=False)
    legs = (f" ({sw['legs']} of them continuation legs)" if sw.get("legs") else "")
    added = f", {sw['added']} added until converged{legs}" if sw["added"] else ""
    left = f", {sw['left']} not run" if sw["left"] else ""
    out.print(f"jobs: {sw['jobs']} ({sw['skipped']} stored before, {sw['ran']} run now{added}"
              f"{left}, {sw['wall_seconds']:.0f} s wall, {sw['cpu_seconds']:.0f} CPU s)",
              highlight=False)
    if sw["left"] and not sw["failed"]:
        out.print("the same command without --stored runs the jobs not run", highlight=False)
    th = d.get("thin")
    if th is not None:
        out.print(f"thin stage ({th['budget']}): {len(th['ran'])} knots followed to w = 0 now, "
                  f"{len(th['skipped'])} stored before ({th['wall_seconds']:.0f} s wall, "
                  f"{th['cpu_seconds']:.0f} CPU s)", highlight=False)
        for f in th["failed"]:
            err.print(f"thin stage failed: {f['job']}: {f['error']}", highlight=False,
                      markup=False, soft_wrap=True)
    thins = [e for e in d["knots"] if e.get("epsilon_thin") is not None]
    if thins:
        out.print("thin-limit grounds (w → 0): " + "; ".join(
            f"{e['name']} {e['thin_state']} {e['epsilon_thin']:.3f}"
            + (f" ± {e['thin_error']:.2g}" if e["thin_error"] is not None else "")
            for e in thins), highlight=False, markup=False, soft_wrap=True)
    out.print(f"atlas: {d['html']}\ndatabase: {d['db']}", highlight=False, markup=False)
