"""The atlas's thin stage: every state of every knot's census followed to w = 0, on Dask.

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V A and §VI ask for the ground state in the
thin limit w/L → 0; the atlas's sweep stores states at one finite width. The thin stage

1. takes each knot's **census** at the atlas's tube width from the store
   (:func:`stiffknots.store.take_census`: every stored search there pooled; saved in table
   ``census``);
2. plans one **job per knot**: its census's states (all of them, or the ``states`` lowest),
   followed down the budget's ladder of w/L and by the structure route, the thin-limit ground
   named (:func:`stiffknots.studies.thin_states.follow_census`) — one job, so that two states
   that merge on the way are seen to;
3. skips every job whose key (:func:`run_key`: the knot and width, the census's states by
   their representative chains, the budget, the seed) is stored — a thin stage killed (even
   by ``kill -9``) and run again does only what is left;
4. runs the rest on a Dask cluster (:func:`stiffknots.sweeps.cluster.connect`: a local one by
   default, or ``scheduler``) and writes each job's rows in one transaction as it arrives
   (:func:`stiffknots.store.thin.put_thin`, table ``thin``).

Every relaxation of a branch verifies its knot type (as every run does); a job that raises is
reported as failed, the others go on. Ctrl-C stores what has arrived and cancels the rest.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from stiffknots._version import __version__
from stiffknots.problems import validate as V

__all__ = ["THIN_TOPIC", "ThinJob", "ThinResult", "run_key", "plan_thin", "run_thin",
           "thin_rows_of"]

#: Dask event topic of the workers' progress lines.
THIN_TOPIC = "stiffknots-thin"


@dataclass
class ThinJob:
    """One knot's states to follow: ``census`` (the stored census, the dict of
    :func:`stiffknots.store.census.take_census`), the chosen ``states`` (its rows) and their
    ``starts`` (chains), the run's key."""

    knot: str
    run: str
    census: dict
    states: list[dict]
    starts: list[dict] = field(repr=False, default_factory=list)


@dataclass
class ThinResult:
    """What a thin stage did: ``knots`` asked, ``jobs`` planned, ``skipped`` (stored
    already), ``missing`` (knots with no tube runs stored: nothing to follow, with why),
    ``ran``, ``failed`` (job, error), ``interrupted``, ``wall_seconds`` and the
    ``cpu_seconds`` of the jobs run now."""

    knots: list[str]
    budget: str
    seed: int
    jobs: list[ThinJob] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    missing: list[dict] = field(default_factory=list)
    ran: list[str] = field(default_factory=list)
    failed: list[dict] = field(default_factory=list)
    interrupted: bool = False
    wall_seconds: float = 0.0
    cpu_seconds: float = 0.0
    workers: int = 0

    def to_dict(self) -> dict:
        return {"knots": self.knots, "budget": self.budget, "seed": self.seed,
                "jobs": [j.knot for j in self.jobs], "skipped": self.skipped,
                "missing": self.missing, "ran": self.ran, "failed": self.failed,
                "interrupted": self.interrupted, "wall_seconds": self.wall_seconds,
                "cpu_seconds": self.cpu_seconds, "workers": self.workers,
                "version": __version__}


def run_key(census: dict, states: Sequence[dict], budget: str, seed: int) -> str:
    """The key of a knot's thin job: its knot and width, the census's parameters, the
    representative chain of every state followed, the budget's parameters and the seed."""
    from stiffknots.store import settings_hash
    from stiffknots.studies.thin_states import BUDGETS

    b = BUDGETS[budget]
    return settings_hash({
        "knot": census["knot"], "exclusion": census["exclusion"], "beads": census["beads"],
        "thickness_key": census["thickness_key"], "census": census["census"],
        "representatives": [int(s["representative"]) for s in states],
        "budget": budget, "ladder": {**b, "widths": list(b["widths"])}, "seed": int(seed)})


def _atlas_width(store: Any, knot: str) -> tuple[int, float] | None:
    """(beads, thickness) of the knot's tube runs: the width with the most replicas."""
    ens = store.ensembles(knot=knot, exclusion="tube")
    if not ens:
        return None
    count: dict[tuple[int, str], list] = {}
    for e in ens:
        c = count.setdefault((e["beads"], e["thickness_key"]), [0, e["thickness"]])
        c[0] += e["replicas"]
    (beads, _), (_n, thickness) = max(count.items(), key=lambda kv: kv[1][0])
    return int(beads), float(thickness)


def plan_thin(store: Any, knots: Sequence[str] | None = None, *, budget: str = "small",
              seed: int = 0, states: int | None = None, window: float | None = None
              ) -> ThinResult:
    """Take and save each knot's census at its tube width and plan the jobs not stored (module
    docstring). ``knots``: default every knot with tube runs stored."""
    from stiffknots.store import save_census, take_census
    from stiffknots.store.keys import knot_sort_key
    from stiffknots.store.thin import thin_runs
    from stiffknots.studies.thin_states import BUDGETS

    V.choice("budget", budget, tuple(BUDGETS))
    seed = V.seed(seed)
    if states is not None:
        states = V.integer("states", states, 1, 1000)
    if knots is None:
        knots = sorted({e["knot"] for e in store.ensembles(exclusion="tube")},
                       key=knot_sort_key)
    res = ThinResult(list(knots), budget, seed)
    done = thin_runs(store)
    for knot in knots:
        width = _atlas_width(store, knot)
        if width is None:
            res.missing.append({"knot": knot, "why": "no tube runs stored (run the atlas "
                                                     "first)"})
            continue
        c = take_census(store, knot, "tube", width[0], width[1], window=window)
        save_census(store, c)
        chosen = c["states"][:states] if states else c["states"]
        key = run_key(c, chosen, budget, seed)
        if key in done:
            res.skipped.append(knot)
            continue
        starts = [{"coords": store.coords(s["representative"]), "name": s["name"],
                   "label": s["shape"], "multiplicity": s["multiplicity"],
                   "structure": s["structure"], "epsilon": s["epsilon"],
                   "searches": s["searches"]} for s in chosen]
        res.jobs.append(ThinJob(knot, key, c, chosen, starts))
    return res


def _say_on_worker(knot: str) -> Callable[[str], None]:
    """A ``say`` that sends a worker's progress lines to the client (Dask events)."""
    def say(line: str) -> None:
        try:
            from distributed import get_worker

            get_worker().log_event(THIN_TOPIC, {"knot": knot, "line": line})
        except Exception:  # noqa: BLE001 (outside a worker, or a closing one: no progress)
            pass
    return say


def _thin_task(knot: str, starts: list[dict], budget: str, seed: int) -> dict:
    """A worker's job: :func:`follow_census` of one knot, with its CPU seconds. Its
    relaxations run in the worker's own process (one core: the cluster's workers are the
    parallelism; a Dask worker may not start processes of its own)."""
    from stiffknots.problems.base import solve
    from stiffknots.studies.thin_states import follow_census

    t0 = time.process_time()
    out = follow_census(knot, starts, budget=budget, seed=seed, say=_say_on_worker(knot),
                        runner=lambda p, _label: solve(p, workers=1))
    out["cpu_seconds"] = time.process_time() - t0
    return out


def thin_rows_of(job: ThinJob, out: dict, budget: str, seed: int) -> list[dict]:
    """The ``thin`` table's rows of a finished job (one per state)."""
    now = datetime.now(UTC).isoformat(timespec="seconds")
    c = job.census
    summary = {k: out.get(k) for k in ("ground", "margin", "crossing")}
    rows = []
    for i, (s, r) in enumerate(zip(job.states, out["states"], strict=True)):
        fitted = [j for j, p in enumerate(r["points"]) if p["in_fit"]]
        last = fitted[-1] if fitted else len(r["points"]) - 1
        event = r["event"]["kind"] if r["event"] is not None else None
        details = {
            "points": r["points"],
            "events": r["events"], "fit": r["fit"], "discretisation": r["discretisation"],
            "parameters": r["parameters"], "route": r["structure_route"],
            "shape": r["shape"], "structure": r["structure"], "searches": r["searches"],
            "summary": summary, "thin_point": last}
        rows.append({
            "run": job.run, "created": now, "version": __version__, "knot": job.knot,
            "exclusion": c["exclusion"], "beads": c["beads"],
            "thickness_key": c["thickness_key"], "w_over_L": c["w_over_L"],
            "census": c["census"], "budget": budget, "seed": seed, "state": s["state"],
            "name": s["name"], "representative": s["representative"],
            "epsilon": s["epsilon"], "epsilon_thin": r["epsilon_thin"], "error": r["error"],
            "event": event if event in ("jumped", "merged") else None,
            "shape_thin": r["shape_thin"], "structure_epsilon": r["structure_epsilon"],
            "structure_error": r["structure_error"], "structure_name": r["structure_name"],
            "agree": r["agree"], "ground": out["ground"] == i, "details": details,
            "chain": r["chains"][last], "cpu_seconds": out.get("cpu_seconds")})
    return rows


def run_thin(store: Any, knots: Sequence[str] | None = None, *, budget: str = "small",
             seed: int = 0, states: int | None = None, window: float | None = None,
             scheduler: str | None = None, workers: int | None = None,
             listener: Any = None, run: bool = True) -> ThinResult:
    """The thin stage (module docstring): plan, skip what is stored, run the rest on Dask,
    store each knot's rows as they arrive.

    Parameters
    ----------
    store : Store
        The atlas's database (read: its tube runs; written: ``census`` and ``thin``).
    knots : sequence of str, optional
        Default: every knot with tube runs stored.
    budget : str
        ``small`` (4 widths down to 0.0005) or ``default`` (9 widths down to 0.00025, k
        measured), :data:`stiffknots.studies.thin_states.BUDGETS`.
    seed : int
        Seed of every relaxation.
    states : int, optional
        Follow only the lowest ``states`` states of each census.
    window : float, optional
        The census's window above the lowest ε (default 15 %).
    scheduler, workers
        As :func:`stiffknots.sweeps.cluster.connect`.
    listener
        An object with ``started(result)``, ``cluster(description, threads)``,
        ``line(knot, text)`` and ``finished(knot, rows, error)`` (any may be missing).
    run : bool
        False: plan only.
    """
    t0 = time.perf_counter()
    res = plan_thin(store, knots, budget=budget, seed=seed, states=states, window=window)
    tell = _Tell(listener)
    tell("started", res)
    if not run or not res.jobs:
        res.wall_seconds = time.perf_counter() - t0
        return res
    from stiffknots.store.thin import put_thin
    from stiffknots.sweeps.cluster import LoadSnappy, connect, import_distributed

    with connect(scheduler, workers) as client:
        import_distributed()
        from distributed import as_completed

        client.register_plugin(LoadSnappy())
        threads = sum(client.nthreads().values()) or 1
        res.workers = threads
        tell("cluster", str(scheduler or f"local cluster, {threads} worker processes"), threads)
        client.subscribe_topic(THIN_TOPIC, lambda ev: tell("line", ev[1]["knot"], ev[1]["line"]))
        futures = {}
        for job in res.jobs:
            fut = client.submit(_thin_task, job.knot, job.starts, budget, res.seed,
                                key=f"thin-{job.knot}-{job.run}", pure=False)
            futures[fut.key] = (job, fut)

        def collect(fut: Any) -> None:
            job, _ = futures.pop(fut.key)
            if fut.status != "finished":
                exc = fut.exception() if fut.status == "error" else None
                err = f"{type(exc).__name__}: {exc}" if exc is not None else fut.status
                res.failed.append({"job": job.knot, "error": err})
                tell("finished", job.knot, None, err)
                return
            out = fut.result()
            fut.release()
            rows = thin_rows_of(job, out, budget, res.seed)
            put_thin(store, rows)
            res.ran.append(job.knot)
            res.cpu_seconds += float(out.get("cpu_seconds") or 0.0)
            tell("finished", job.knot, rows, None)

        try:
            for fut in as_completed([f for _, f in futures.values()]):
                collect(fut)
        except KeyboardInterrupt:
            res.interrupted = True
            for _key, (_job, fut) in list(futures.items()):
                if fut.status == "finished":
                    collect(fut)
            if futures:
                client.cancel([f for _, f in futures.values()])
    res.wall_seconds = time.perf_counter() - t0
    return res


class _Tell:
    """Calls a listener's method when it has it (a display never stops the stage)."""

    def __init__(self, listener: Any) -> None:
        self.listener = listener

    def __call__(self, what: str, *args: Any) -> None:
        fn = getattr(self.listener, what, None)
        if fn is not None:
            try:
                fn(*args)
            except Exception:  # noqa: BLE001
                pass
