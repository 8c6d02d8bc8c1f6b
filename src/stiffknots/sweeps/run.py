"""Run a sweep: the jobs not yet stored, on Dask, each result stored as soon as it arrives.

:func:`run_sweep` plans every job (:func:`~stiffknots.sweeps.plan.plan_sweep`), drops those
whose key is stored (:func:`~stiffknots.sweeps.plan.pending`), and runs the rest on a Dask
cluster (:func:`~stiffknots.sweeps.cluster.connect`), at most two jobs per worker thread
submitted at a time (in plan order: knot by knot). The workers build each (knot, model)'s
problem and run its replicas (:func:`~stiffknots.sweeps.cluster.run_task`). Every result
comes back to the client, which

1. refuses a replica whose knot type changed (never expected: a bug, never a data point —
   it is reported, not stored);
2. classifies its shape (:func:`stiffknots.analysis.classify`, with d = the model's
   thickness: the bead distance, or the tube diameter);
3. writes it to the store (:meth:`Store.put <stiffknots.store.sqlite.Store.put>`): one
   transaction per row, so a killed client leaves whole rows or none, and a row whose key is
   stored is not written again;
4. once a tube ensemble's replicas have ended, seeds a bead-rule replica from each (a tube
   chain is bead-admissible when w ≥ d; polished under the bead rule,
   :mod:`stiffknots.sweeps.cross`): the tube model's smoother landscape searches the bead
   rule's glassy one better than the bead rule's own Monte Carlo does.

Replicas until converged. With ``max_replicas`` above the budget's replicas, a (knot, model)
whose replicas have all ended without a converged ground state
(:mod:`stiffknots.sweeps.convergence`) gets ``step`` more replicas — fewer where two searches
agree and the rule asks for three, :func:`searches_lacking` — (the budget's moves and
settings: the same ensemble), and so on up to ``max_replicas``; the n = i knots, whose
circular braids two replicas agree on at once, then cost no more than they need. A bead
ensemble that tube replicas seed is judged once its tube ensembles have settled and been
seeded, since its verdict counts the seeded replicas; meanwhile the workers go on with the
next jobs.

Interruption and resumption. Ctrl-C (KeyboardInterrupt) stops the sweep: the results that
have already arrived are stored, the running jobs are cancelled, the cluster is closed and the
result says ``interrupted``. The same sweep run again skips everything stored and runs the
rest. A worker that dies is replaced by its nanny and its job rerun (Dask's scheduler); a job
that kills ``allowed-failures`` workers in a row is reported as failed, as is a job whose
problem cannot be built (an embedding that does not fit) or that raises: the others go on.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from stiffknots._version import __version__
from stiffknots.problems import validate as V
from stiffknots.store import KeyCollisionError, Store, row_from_replica, settings_hash
from stiffknots.sweeps.budgets import Budget
from stiffknots.sweeps.cluster import (
    PROGRESS_TOPIC,
    connect,
    local_workers,
    run_task,
    scheduler_address,
)
from stiffknots.sweeps.convergence import ensemble_converged as converged_with_every_start
from stiffknots.sweeps.cross import SEEDED_START, seed_from_tube, seed_pairs
from stiffknots.sweeps.legs import LEG_REPLICA, leg_job
from stiffknots.sweeps.plan import (
    PROBLEM,
    SweepJob,
    favoured_start,
    pending,
    plan_sweep,
    sweep_settings,
)
from stiffknots.width import Width

__all__ = ["SweepListener", "SweepResult", "run_sweep", "store_replica", "ensemble_converged",
           "expected_todo"]


class SweepListener:
    """What a sweep tells its caller while it runs (every method a no-op here; the command
    line draws a progress bar). Methods may be called from the Dask client's thread."""

    def started(self, result: SweepResult) -> None:
        """The plan is made: ``result.jobs`` planned, ``result.skipped`` stored already."""

    def cluster(self, description: str, threads: int) -> None:
        """Connected to the cluster."""

    def progress(self, job: str, done: int, total: int, best: float | None = None,
                 pid: int | None = None) -> None:
        """A running job's moves ``done`` of ``total``, its lowest ε so far, the process id
        of the worker running it."""

    def finished(self, job: SweepJob, row: dict | None, error: str | None) -> None:
        """A job ended: stored (``row``: its shape, ε, ...) or failed (``error``)."""

    def added(self, jobs: int) -> None:
        """``jobs`` more jobs to run: replicas added to a (knot, model) not yet converged."""

    def seeded(self, entry: dict) -> None:
        """A bead-rule replica seeded from the tube ground was stored
        (:func:`~stiffknots.sweeps.cross.seed_from_tube`'s entry)."""

    def expected(self, jobs: float, settled: int) -> None:
        """The jobs this sweep is now expected to run in all: those planned, and for every
        (knot, model) still open the replicas the settled ones were added on average
        (:func:`expected_todo`) — the basis of an honest time left. ``settled``: how many
        (knot, model) have settled so far; while it is 0, ``jobs`` is the plan alone, a lower
        bound."""


@dataclass
class SweepResult:
    """What a sweep did.

    Attributes
    ----------
    knots : list of str
        The sweep's knots (catalogue names).
    models : list of Width
        The sweep's models.
    budget : ~stiffknots.sweeps.budgets.Budget
        Its replicas and moves.
    seed : int
        Its seed.
    settings_hash : dict
        Model name → the settings hash of its replicas (their store ensembles).
    jobs : int
        Jobs planned.
    skipped : int
        Stored before the sweep began.
    ran : int
        Finished now.
    written : int
        Rows written now (``ran`` minus those another writer stored first).
    failed : list of dict
        ``{"job", "error"}`` per job that failed (not stored).
    interrupted : bool
        Stopped by Ctrl-C (the rest resumes with the same sweep).
    wall_seconds : float
        Of the whole sweep.
    cpu_seconds : float
        The finished replicas' CPU time.
    workers : int
        Worker threads of the cluster.
    scheduler : str
        ``"local"`` or its address.
    max_replicas : int
        The most replicas a (knot, model) may get.
    added : int
        Replicas planned beyond the budget's for (knot, model)s not converged (counted in
        ``jobs``).
    legs : int
        How many of them are continuation legs (:mod:`stiffknots.sweeps.legs`).
    seeded : list of dict
        The bead replicas seeded from the tube ground and written now
        (:mod:`stiffknots.sweeps.cross`): ``knot``, ``model``, ``epsilon``, ``tube_epsilon``.
    """

    knots: list[str]
    models: list[Width]
    budget: Budget
    seed: int
    settings_hash: dict[str, str]
    jobs: int = 0
    skipped: int = 0
    ran: int = 0
    written: int = 0
    failed: list[dict] = field(default_factory=list)
    interrupted: bool = False
    wall_seconds: float = 0.0
    cpu_seconds: float = 0.0
    workers: int = 0
    scheduler: str = "local"
    max_replicas: int = 0
    added: int = 0
    legs: int = 0
    seeded: list[dict] = field(default_factory=list)
    version: str = __version__

    @property
    def todo(self) -> int:
        """Jobs this sweep had to run."""
        return self.jobs - self.skipped

    @property
    def left(self) -> int:
        """Jobs planned and not stored when the sweep ended (stopped, failed, or not run)."""
        return self.todo - self.ran

    @property
    def complete(self) -> bool:
        """Every planned job is stored."""
        return not self.interrupted and not self.failed and self.ran == self.todo

    def to_dict(self) -> dict:
        """The result as plain data (JSON): the attributes, ``left`` and the widths."""
        return {"knots": self.knots, "models": [m.exclusion for m in self.models],
                "widths": {m.exclusion: m.as_dict() for m in self.models},
                "budget": self.budget.as_dict(), "seed": self.seed,
                "settings_hash": self.settings_hash, "jobs": self.jobs,
                "skipped": self.skipped, "ran": self.ran, "left": self.left,
                "written": self.written, "failed": self.failed, "interrupted": self.interrupted,
                "wall_seconds": self.wall_seconds, "cpu_seconds": self.cpu_seconds,
                "workers": self.workers, "scheduler": self.scheduler,
                "max_replicas": self.max_replicas, "added": self.added, "legs": self.legs,
                "seeded": self.seeded, "version": self.version}


def store_replica(store: Store, job: SweepJob, replica: Any, *, budget: str | None = None
                  ) -> tuple[bool, dict]:
    """Classify a verified replica and write it to ``store`` (one transaction).

    Returns
    -------
    (written, row)
        ``written`` False when the key was stored already; ``row`` as given to the store.
    """
    from stiffknots.analysis import classify

    shape = classify(replica.coords, True, d=job.model.thickness)
    extra = {"model": job.model.exclusion, "budget": budget, "width": job.model.text,
             "shape_reason": shape.reason}
    if job.parent is not None:  # a continuation leg (:mod:`stiffknots.sweeps.legs`)
        extra.update(search=job.parent["search"], leg_of=job.parent["replica"],
                     leg_parent_epsilon=job.parent["epsilon"])
    coarse = (getattr(replica, "observables", None) or {}).get("coarse")
    if coarse is not None:  # its coarse stage (:mod:`stiffknots.problems.coarse`)
        extra["coarse"] = coarse
    row, coords = row_from_replica(
        replica, knot=job.knot, width=job.model, seed=job.seed, settings=job.settings,
        shape=shape.label, multiplicity=shape.multiplicity, problem=job.settings["problem"],
        extra=extra)
    return store.put(row, coords), row


def _stored_states(store: Store, knot: str, model: Width, settings_hash: str) -> dict | None:
    """:meth:`Store.states` of one (knot, model) ensemble; None when nothing is stored."""
    if not store.count(knot=knot, exclusion=model.exclusion, beads=model.beads,
                       thickness=model.thickness, settings_hash=settings_hash):
        return None
    return store.states(knot, model.exclusion, model.beads, model.thickness, settings_hash,
                        structure=False)


def ensemble_converged(store: Store, knot: str, model: Width, settings_hash: str) -> bool:
    """Whether one stored (knot, model) ensemble is converged — its ground state by the rule,
    after a replica from every default start
    (:func:`~stiffknots.sweeps.convergence.ensemble_converged`); False when nothing is
    stored."""
    st = _stored_states(store, knot, model, settings_hash)
    return st is not None and converged_with_every_start(st)


def searches_lacking(st: Mapping[str, Any] | None, model: Width, step: int) -> int:
    """The replicas to add next to one stored, unconverged (knot, model) ensemble (``st``:
    its :meth:`Store.states`, None when nothing is stored): ``step``;
    but where :data:`~stiffknots.sweeps.convergence.MIN_REPLICAS` (two) searches or more
    already agree on its ground state and its model's rule asks for more
    (:func:`~stiffknots.sweeps.convergence.min_searches`: three for the tube), only as many
    as the verdict lacks, at most ``step`` — a tube ensemble whose first two replicas agree
    gets one more, not two. ``step`` while a default start has had no replica (the verdict
    waits for it) or nothing is stored."""
    from stiffknots.sweeps.convergence import MIN_REPLICAS, hits, min_searches, untried_starts

    if st is None:
        return step
    have = hits(st.get("ground"))
    if untried_starts(st) or have < MIN_REPLICAS:
        return step
    return max(1, min(step, min_searches(model.exclusion) - have))


def expected_todo(groups: Mapping[tuple[str, str], dict], todo: int, base: int) -> float:
    """Jobs a sweep is expected to run in all: the ``todo`` planned so far, plus, for every
    (knot, model) not yet settled, the replicas beyond the ``base`` (the budget's) that the
    settled ones *like it* needed on average, less those it already has. A (knot, model) is
    settled when its replicas have ended and no more will be added (converged, or at
    ``max_replicas``). Before any is settled, the plan alone (the estimate can only rise).

    "Like it": the settled ones of the same model and crossing number; where none has
    settled yet, those of the same model and the largest crossing number below it that has
    one; else the same model's; else all. A sweep runs its knots in order of crossing number
    and larger knots tend to need more replicas (the 249-knot atlas run, default budget, own
    replicas a (knot, model): bead 4.7 at 8 crossings, 5.3 at 9, 5.7 at 10), so one mean over
    all settled ones reads low. Replayed on that run's stored replicas
    (``bench/eta_replay.py``): jobs expected after 400, 674, 895 and 1,201 of its 2,256 —
    1,815, 1,501, 1,270, 1,118 by this rule, 1,659, 1,436, 1,240, 1,031 by one mean of a model;
    1,856, 1,582, 1,361, 1,055 followed.

    ``groups`` maps (knot, model) to ``{"replicas": planned so far, "settled": bool}`` and,
    optionally, ``"legs"`` (continuation legs planned so far, counted with the replicas),
    ``"stored"`` and ``"stored_legs"`` (those a resumed sweep found stored: counted where
    more than planned so far) and ``"crossings"`` (the knot's crossing number; without it
    every knot of a model is alike).
    """
    added: dict[tuple[str, int], list[int]] = {}  # (model, crossings) → replicas added
    for (_, model), g in groups.items():
        if g["settled"]:
            added.setdefault((model, g.get("crossings", 0)), []).append(_jobs_of(g) - base)
    if not added:
        return float(todo)
    everyone = [a for v in added.values() for a in v]

    def mean_like(model: str, crossings: int) -> float:
        below = [c for (m, c) in added if m == model and c <= crossings]
        if below:
            v = added[(model, max(below))]
        else:
            v = [a for (m, _), vs in added.items() if m == model for a in vs] or everyone
        return sum(v) / len(v)

    more = sum(max(0.0, base + mean_like(model, g.get("crossings", 0)) - _jobs_of(g))
               for (_, model), g in groups.items() if not g["settled"])
    return todo + more


def _jobs_of(g: Mapping[str, Any]) -> int:
    """The replicas and legs a (knot, model) of :func:`expected_todo` has planned or, where a
    resumed sweep has not judged it again yet, stored."""
    return (max(g["replicas"], g.get("stored", 0))
            + max(g.get("legs", 0), g.get("stored_legs", 0)))


def run_sweep(knots: Sequence[str], models: Sequence[Width], budget: Budget, store: Store, *,
              seed: int = 0, scheduler: str | None = None, workers: int | None = None,
              max_replicas: int | None = None, step: int = 2,
              listener: SweepListener | None = None, run: bool = True,
              problem: str = PROBLEM) -> SweepResult:
    """Run every job of knots × models × replicas that ``store`` lacks; store each result.

    Parameters
    ----------
    knots : sequence of str
        Catalogue names (:func:`~stiffknots.sweeps.plan.resolve_knots`).
    models : sequence of Width
        E.g. :func:`~stiffknots.sweeps.models.parse_models` ``("bead,tube")``.
    budget : Budget
        Replicas and moves (:mod:`stiffknots.sweeps.budgets`).
    store : Store
        The results database (written by this process only).
    seed : int
        The sweep's seed; replica r of every (knot, model) gets the r-th seed derived from it.
    scheduler : str, optional
        Address of a running Dask scheduler; default: a local cluster.
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    max_replicas : int, optional
        Replicas are added, ``step`` at a time, to every (knot, model) not converged once its
        replicas have ended (:func:`ensemble_converged`: the ground state's rule, and a
        replica from every default start), up to ``max_replicas`` in all.
        Default: per model, the budget's (:meth:`Budget.most_replicas
        <stiffknots.sweeps.budgets.Budget.most_replicas>`; its replicas when None: nothing
        added). The
        added replicas have the budget's moves and settings: they join the same ensemble, and
        a resumed sweep skips them too.
    step : int
        Most replicas added at a time (fewer where the ground state lacks fewer searches for
        its verdict: :func:`searches_lacking`).
    listener : SweepListener, optional
        Told of the plan, the progress and each finished job.
    run : bool
        False: plan and count only — what is stored (``skipped``) and what is still to run
        (``left``: the planned replicas not stored, and the next ``step`` replicas of every
        (knot, model) whose replicas have ended unconverged; more may follow them) — and
        start no cluster (the pages of a sweep stopped part-way).
    problem : str
        What the replicas are for (:func:`~stiffknots.sweeps.plan.sweep_settings`): a sweep's
        own ensembles (``"anneal"``), or an audit's searches (:mod:`stiffknots.sweeps.audit`),
        which no tube replica seeds — an audit's opinion is its own searches'.

    Returns
    -------
    SweepResult
        ``interrupted`` after Ctrl-C (the results that arrived are stored).

    Raises
    ------
    UserInputError
        Bad parameters, an unreachable scheduler — before any job runs.
    """
    listener = listener or SweepListener()
    t0 = time.perf_counter()
    if scheduler is None:  # a bad count or address is an error before anything starts
        local_workers(workers)
    else:
        scheduler_address(scheduler)
    if max_replicas is not None:
        max_replicas = V.integer("max_replicas", max_replicas, budget.replicas,
                                 V.MAX_REPLICAS)
    #: model name → the most replicas of its ensembles
    most = {m.exclusion: (budget.most_replicas(m) if max_replicas is None else max_replicas)
            for m in models}
    max_r = max(most.values(), default=budget.replicas)
    step = V.integer("step", step, 1, V.MAX_REPLICAS)
    jobs = plan_sweep(knots, models, budget, seed, problem)
    res = SweepResult(list(knots), list(models), budget, int(seed),
                      {m.exclusion: settings_hash(sweep_settings(m, budget, problem))
                       for m in models},
                      jobs=len(jobs), scheduler=scheduler or "local", max_replicas=max_r)
    todo = pending(jobs, store)
    res.skipped = len(jobs) - len(todo)
    # per (knot, model): its model, replicas planned so far, jobs not yet ended
    groups: dict[tuple[str, str], dict] = {}

    def crossings(knot: str) -> int:
        from stiffknots.knots.catalogue import get_knot

        return get_knot(knot).crossing_number

    for j in jobs:
        if j.group not in groups:  # (the catalogue looked up once a knot and model)
            groups[j.group] = {"knot": j.knot, "model": j.model, "replicas": budget.replicas,
                               "open": 0, "settled": False, "crossings": crossings(j.knot),
                               "legs": 0}
    for j in todo:
        groups[j.group]["open"] += 1
    # what a resumed sweep has stored already (fresh replicas, legs), for the jobs expected
    # only: a (knot, model) not yet judged again still counts its stored replicas
    by_model = {(m.exclusion, m.beads, res.settings_hash[m.exclusion]): m.exclusion for m in models}
    stored_keys = (store.keys(settings_hash=sorted(res.settings_hash.values()),
                              seed=[res.seed]) if jobs else set())
    for k in stored_keys:
        g = groups.get((k.knot, by_model.get((k.exclusion, k.beads, k.settings_hash))))
        if g is None:
            continue
        if k.replica < V.MAX_REPLICAS:
            g["stored"] = g.get("stored", 0) + 1
        elif LEG_REPLICA <= k.replica < LEG_REPLICA + V.MAX_REPLICAS:
            g["stored_legs"] = g.get("stored_legs", 0) + 1

    def extend(g: dict) -> list[SweepJob]:
        """The replicas to add to a (knot, model) whose replicas have all ended."""
        top = most[g["model"].exclusion]
        while g["replicas"] < top:
            st = _stored_states(store, g["knot"], g["model"],
                                res.settings_hash[g["model"].exclusion])
            if st is not None and converged_with_every_start(st):
                break
            n = min(top, g["replicas"] + searches_lacking(st, g["model"], step))
            more = plan_sweep([g["knot"]], [g["model"]], replace(budget, replicas=n),
                              seed, problem)[g["replicas"]:]
            more = [replace(j, start=favoured_start(store, j, g["replicas"])) for j in more]
            g["replicas"] = n
            new = pending(more, store)
            res.jobs += len(more)
            res.skipped += len(more) - len(new)
            res.added += len(more)
            if new:
                g["open"] += len(new)
                return new
        legs = budget.legs_of(g["model"])
        while g["legs"] < legs and not ensemble_converged(
                store, g["knot"], g["model"], res.settings_hash[g["model"].exclusion]):
            template = plan_sweep([g["knot"]], [g["model"]], replace(budget, replicas=1),
                                  seed, problem)[0]
            leg = leg_job(store, template, g["legs"], langevin=budget.langevin(g["model"]))
            if leg is None:
                break
            g["legs"] += 1
            res.jobs += 1
            res.added += 1
            res.legs += 1
            if pending([leg], store):
                g["open"] += 1
                return [leg]
            res.skipped += 1
        g["settled"] = True
        return []

    def expect() -> None:
        listener.expected(expected_todo(groups, res.todo, budget.replicas),
                          sum(1 for g in groups.values() if g["settled"]))

    settings = {m.exclusion: sweep_settings(m, budget, problem) for m in res.models}
    # bead model → the tube models whose replicas seed it (:mod:`stiffknots.sweeps.cross`);
    # none in an audit
    tubes_of: dict[str, list[str]] = {}
    for b, t in (seed_pairs(res.models) if problem == PROBLEM else ()):
        tubes_of.setdefault(b.exclusion, []).append(t.exclusion)
    early: list[dict] = []  # seeded before the listener was told the plan

    def seed_knot(knot: str) -> None:
        """Seed the knot's bead ensembles from its tube replicas that have ended
        (:mod:`stiffknots.sweeps.cross`; those seeded already are skipped)."""
        if not run or res.interrupted or not tubes_of:
            return
        for e in seed_from_tube(store, [knot], res.models, settings, res.seed, budget.name):
            if e["written"]:
                res.seeded.append(e)
                if not started:
                    early.append(e)
                else:
                    listener.seeded(e)
            elif e.get("reason"):
                res.failed.append({"job": f"{knot}/{e['model']}/{SEEDED_START}",
                                   "error": e["reason"]})

    def decide(g: dict) -> list[SweepJob]:
        """The jobs to add to a (knot, model) whose replicas have all ended. A bead ensemble
        that tube replicas seed waits for them: its verdict counts the seeded replicas, so it
        is judged only once its tube ensembles have settled (and have been seeded); the
        settling of a tube ensemble judges the bead ensembles waiting on it."""
        tubes = [groups[(g["knot"], t)] for t in tubes_of.get(g["model"].exclusion, ())]
        if any(not t["settled"] for t in tubes):
            g["waiting"] = True
            return []
        g["waiting"] = False
        new = extend(g)
        if g["model"].exclusion == "tube":
            seed_knot(g["knot"])  # its replicas so far: the bead verdict will count them
            if g["settled"]:
                for b in groups.values():
                    if b["knot"] == g["knot"] and b.get("waiting") and b["open"] == 0:
                        new += decide(b)
        return new

    started = False
    # replicas added to a (knot, model) run before the jobs of later knots, so that the knots
    # are finished in the order planned: a sweep stopped after an hour has whole answers for
    # the knots it reached, not two replicas of every knot (the results do not depend on the
    # order: every replica's seed and settings are its key's)
    feed: deque[SweepJob] = deque(todo)
    for g in reversed(list(groups.values())):
        if g["open"] == 0 and not g["settled"] and not g.get("waiting"):
            feed.extendleft(reversed(decide(g)))
    listener.started(res)
    started = True
    for e in early:
        listener.seeded(e)
    expect()
    if not run:
        res.wall_seconds = time.perf_counter() - t0
        return res

    if feed:
        with connect(scheduler, workers) as client:
            from stiffknots.sweeps.cluster import import_distributed

            import_distributed()
            from distributed import as_completed

            threads = sum(client.nthreads().values()) or 1
            res.workers = threads
            listener.cluster(str(scheduler or f"local cluster, {threads} worker processes"),
                             threads)
            client.subscribe_topic(PROGRESS_TOPIC, lambda ev: _progress(listener, ev))
            limit = max(4, 2 * threads)
            inflight: dict[str, tuple[SweepJob, Any]] = {}
            ac = as_completed()

            def fail(sj: SweepJob, error: str) -> None:
                res.failed.append({"job": sj.id, "error": error})
                listener.finished(sj, None, error)

            def top_up() -> None:
                while len(inflight) < limit and feed:
                    sj = feed.popleft()
                    b = replace(budget, replicas=groups[sj.group]["replicas"])
                    fut = client.submit(run_task, sj, b, key=sj.task_key)
                    inflight[fut.key] = (sj, fut)
                    ac.add(fut)

            def collect(fut: Any) -> None:
                sj, _ = inflight.pop(fut.key)
                g = groups[sj.group]
                g["open"] -= 1
                if fut.status != "finished":
                    exc = fut.exception() if fut.status == "error" else None
                    fail(sj, f"{type(exc).__name__}: {exc}" if exc is not None else fut.status)
                else:
                    r = fut.result()
                    fut.release()
                    if not r.knot_verified:
                        fail(sj, f"TopologyChangedError: the replica ended as {r.knot} (a bug in "
                                 f"stiffknots, please report it with seed {sj.seed}); not stored")
                    else:
                        try:
                            written, row = store_replica(store, sj, r, budget=budget.name)
                        except KeyCollisionError as e:
                            fail(sj, f"KeyCollisionError: {e}")
                        else:
                            res.ran += 1
                            res.written += int(written)
                            res.cpu_seconds += float(r.cpu_time or 0.0)
                            listener.finished(sj, row, None)
                if g["open"] == 0 and not res.interrupted:
                    new = decide(g)
                    if new:
                        feed.extendleft(reversed(new))
                        listener.added(len(new))
                    expect()

            try:
                top_up()
                for fut in ac:
                    collect(fut)
                    top_up()
            except KeyboardInterrupt:
                res.interrupted = True
                for _key, (_sj, fut) in list(inflight.items()):
                    if fut.status == "finished":  # arrived meanwhile: keep it
                        collect(fut)
                futures = [f for _, f in inflight.values()]
                if futures:
                    client.cancel(futures)
    for k in res.knots:  # tube replicas stored before this sweep and not yet seeded
        seed_knot(k)
    res.wall_seconds = time.perf_counter() - t0
    return res


def _progress(listener: SweepListener, event: Any) -> None:
    try:
        _, msg = event
        listener.progress(msg["job"], int(msg["done"]), int(msg["total"]), msg.get("best"),
                          msg.get("pid"))
    except Exception:  # noqa: BLE001 (a progress display never stops a sweep)
        pass
