"""An audit of the verdicts: converged ground states searched again, the false ones counted.

A verdict (:mod:`stiffknots.sweeps.convergence`) says that independent searches agree on the
lowest state found — not that no lower state exists. The audit measures how often it is wrong:

1. **Sample.** Of the converged ground states stored (:meth:`Store.ground_states
   <stiffknots.store.sqlite.Store.ground_states>` of the sweeps' own ensembles, problem
   ``anneal``; :func:`~stiffknots.sweeps.convergence.ensemble_converged`), ``sample`` are drawn
   at random with ``seed`` (:func:`sample_entries`): the same seed draws the same entries.
2. **Search again.** Every drawn entry gets ``replicas`` new searches (:func:`audit_budget`):
   another seed (:func:`audit_seed`, never the sweep's), the knot's default starts round-robin
   (braid, cage, 80 where they exist: other funnels than the ones the sweep's replicas fell
   into), the entry's own model, width and N, and ``depth`` times the moves (or, for a Langevin
   bead ensemble, the steps) of one of its replicas. They are stored as replicas of another
   ensemble (problem ``audit``, :data:`AUDIT_PROBLEM`): never mixed into the verdict they
   check, and reused when the same audit runs again (resumable like a sweep). No tube replica
   seeds an audit's bead searches.
3. **Judge.** An entry's verdict is *false* when an audit search reached a state lower than its
   ground by more than :data:`TOLERANCE` (0.1 %, the verdict's own tolerance): ε_audit <
   (1 − 0.001) ε. Every search's knot type is verified, as in a sweep.
4. **Count.** The false-verdict rate with its 95 % Wilson interval
   (:func:`wilson_interval`, SciPy's ``binomtest``), per model and crossing number and in all
   (:func:`summarise`); the rows go to the store's ``audits`` table
   (:meth:`Store.put_audits <stiffknots.store.sqlite.Store.put_audits>`), where ``db
   grounds`` and the atlas pages read them.

An audit that finds no lower state does not prove the ground either: it bounds how often
*these* searches are wrong, at the audit's depth.
"""

from __future__ import annotations

import random
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from stiffknots._version import __version__
from stiffknots.errors import InvalidParameter
from stiffknots.problems import validate as V
from stiffknots.store import Store, settings_hash
from stiffknots.store.keys import canonical_json
from stiffknots.sweeps.budgets import Budget
from stiffknots.sweeps.convergence import ensemble_converged
from stiffknots.sweeps.plan import PROBLEM, sweep_settings
from stiffknots.width import Width

__all__ = ["AUDIT_PROBLEM", "TOLERANCE", "DEFAULT_SAMPLE", "DEFAULT_DEPTH", "DEFAULT_REPLICAS",
           "AuditResult", "audit_seed", "sample_entries", "audit_budget", "wilson_interval",
           "judge", "summarise", "run_audit", "latest_audits"]

#: The problem of an audit's searches (their settings' ``problem``): another ensemble.
AUDIT_PROBLEM = "audit"
#: A verdict is false when an audit search is lower than its ground by more than this
#: fraction (the verdict's own tolerance, :data:`stiffknots.sweeps.convergence.REL_TOL`).
TOLERANCE = 1e-3
#: Entries drawn by default.
DEFAULT_SAMPLE = 20
#: Moves of an audit search, in moves of one of the audited ensemble's replicas.
DEFAULT_DEPTH = 2.0
#: Audit searches per entry (enough for the three default starts once each).
DEFAULT_REPLICAS = 3


def audit_seed(seed: int) -> int:
    """The seed of an audit's searches: derived from the audit's ``seed`` by NumPy's
    ``SeedSequence`` (with a salt), so that it is never a sweep's small seed and two audits
    with different seeds search differently."""
    import numpy as np

    s = int(np.random.SeedSequence([V.seed(seed), 0xA0D17]).generate_state(1, np.uint64)[0])
    return s >> 1  # < 2⁶³, as a stored seed must be


def sample_entries(store: Store, *, models: Sequence[str] = ("tube",), sample: int =
                   DEFAULT_SAMPLE, seed: int = 0, max_crossings: int | None = None,
                   knots: Sequence[str] | None = None) -> tuple[list[dict], int]:
    """The converged ground states to audit, drawn at random with ``seed``.

    Parameters
    ----------
    store : Store
    models : sequence of str
        Exclusion models whose entries may be drawn (``tube``, ``bead``).
    sample : int
        How many to draw (all of them when fewer are converged).
    seed : int
        The draw's seed (Python's ``random.Random(seed).sample`` over the entries in
        knot-table order).
    max_crossings : int, optional
        Only knots with at most this many crossings.
    knots : sequence of str, optional
        Only these knots (any usual spelling; an unknown name is an error). A knot with no
        converged entry is not drawn.

    Returns
    -------
    (entries, converged)
        The drawn rows of :meth:`Store.ground_states` (in knot-table order), and how many
        converged entries there were to draw from.
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.sweeps.plan import resolve_knots

    sample = V.integer("sample", sample, 1, 100_000)
    only = None if knots is None else set(resolve_knots(knots))
    rows = [r for r in store.ground_states(problem=PROBLEM, structure=False)
            if r["exclusion"] in models and (only is None or r["knot"] in only)
            and (max_crossings is None or get_knot(r["knot"]).crossing_number <= max_crossings)
            and ensemble_converged(r)]
    drawn = sorted(random.Random(V.seed(seed)).sample(range(len(rows)), min(sample, len(rows))))
    return [rows[i] for i in drawn], len(rows)


def audit_budget(settings: Mapping[str, Any], depth: float, replicas: int) -> Budget:
    """The budget of an audit's searches of one ensemble whose replicas ran with
    ``settings``: ``replicas`` searches of ``depth`` × its moves (annealing), or of
    ``depth`` × its steps (a Langevin bead ensemble, schedule kind ``langevin``)."""
    depth = float(depth)
    if not depth >= 0.1 or depth > 1000:
        raise InvalidParameter("depth", depth, "a number of replica budgets in [0.1, 1000]")
    moves = max(1000, round(int(settings["moves"]) * depth))
    langevin = (settings.get("schedule") or {}).get("kind") == "langevin"
    if langevin:
        return Budget("audit", replicas, 1000, bead_search="langevin",
                      bead_steps=moves).validate()
    return Budget("audit", replicas, moves).validate()


def wilson_interval(false: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The Wilson score interval of a rate of ``false`` in ``n`` (SciPy's
    ``binomtest(false, n).proportion_ci(method="wilson")``); (0, 1) when ``n`` = 0."""
    if n <= 0:
        return 0.0, 1.0
    from scipy.stats import binomtest

    ci = binomtest(int(false), int(n)).proportion_ci(confidence, method="wilson")
    return float(ci.low), float(ci.high)


def judge(entry: Mapping[str, Any], audit_ground: Mapping[str, Any] | None) -> bool:
    """Whether ``entry``'s verdict is false: the audit's lowest state (``epsilon``; None when
    no search ended) lies below the entry's ground by more than :data:`TOLERANCE`."""
    if audit_ground is None:
        return False
    return float(audit_ground["epsilon"]) < (1.0 - TOLERANCE) * float(entry["epsilon"])


@dataclass
class AuditResult:
    """What an audit did and found.

    Attributes
    ----------
    audit : str
        The audit's id (16 hex digits of its parameters' hash).
    params : dict
        sample, seed, depth, replicas, models, max_crossings, tolerance (and knots, the
        catalogue names, when the audit was limited to them).
    converged : int
        Converged entries there were to draw from.
    rows : list of dict
        One per audited entry (the ``audits`` table's columns, and ``crossings``,
        ``gap`` — (ε − ε_audit)/ε, positive when the audit went lower).
    summary : dict
        :func:`summarise` of ``rows``.
    failed : list of dict
        Audit searches that failed (job, error).
    interrupted : bool
    wall_seconds, cpu_seconds : float
        This call's wall time, and the CPU seconds of the searches it ran (none when every
        search was stored before).
    search_cpu_seconds : float
        The CPU seconds of every audit search of the drawn entries, stored before or run now
        (what the audit cost).
    """

    audit: str
    params: dict
    converged: int = 0
    rows: list[dict] = field(default_factory=list)
    summary: dict = field(default_factory=dict)
    failed: list[dict] = field(default_factory=list)
    interrupted: bool = False
    wall_seconds: float = 0.0
    cpu_seconds: float = 0.0
    search_cpu_seconds: float = 0.0

    def to_dict(self) -> dict:
        return {"audit": self.audit, "params": self.params, "converged": self.converged,
                "entries": self.rows, "summary": self.summary, "failed": self.failed,
                "interrupted": self.interrupted, "wall_seconds": self.wall_seconds,
                "cpu_seconds": self.cpu_seconds,
                "search_cpu_seconds": self.search_cpu_seconds, "version": __version__}


def _rate(rows: Sequence[Mapping[str, Any]]) -> dict:
    n = len(rows)
    k = sum(int(r["false_verdict"]) for r in rows)
    lo, hi = wilson_interval(k, n)
    return {"n": n, "false": k, "rate": k / n if n else None, "low": lo, "high": hi}


def summarise(rows: Sequence[Mapping[str, Any]]) -> dict:
    """The false-verdict rate of audited entries with its 95 % Wilson interval: ``all``, per
    model (``by_model``) and per model and crossing number (``by_crossings``, keys
    ``"tube/7"``); each ``{n, false, rate, low, high}``. Entries no audit search reached
    (``searches`` = 0) are left out of the counts and counted in ``unsearched``."""
    done = [r for r in rows if r["searches"] > 0]
    by_model: dict[str, list] = defaultdict(list)
    by_cross: dict[str, list] = defaultdict(list)
    for r in done:
        by_model[r["exclusion"]].append(r)
        by_cross[f"{r['exclusion']}/{r['crossings']}"].append(r)
    return {"all": _rate(done),
            "by_model": {m: _rate(v) for m, v in sorted(by_model.items())},
            "by_crossings": {k: _rate(v) for k, v in sorted(
                by_cross.items(), key=lambda kv: (kv[0].split("/")[0],
                                                  int(kv[0].split("/")[1])))},
            "unsearched": len(rows) - len(done)}


def _groups(store: Store, entries: Sequence[Mapping[str, Any]]) -> dict[tuple, list[dict]]:
    """The entries grouped by the ensemble settings they were searched with (one audit sweep
    each): (exclusion, beads, thickness, settings hash) → entries, each with its
    ``settings``."""
    out: dict[tuple, list[dict]] = defaultdict(list)
    for e in entries:
        settings = _settings_of(store, e)
        out[(e["exclusion"], e["beads"], float(e["thickness"]), e["settings_hash"])].append(
            {**e, "settings": settings})
    return out


def _settings_of(store: Store, entry: Mapping[str, Any]) -> dict:
    rows = store.replicas(knot=entry["knot"], exclusion=entry["exclusion"],
                          beads=entry["beads"], thickness=entry["thickness"],
                          settings_hash=entry["settings_hash"])
    return rows[0]["settings"]


def run_audit(store: Store, *, models: Sequence[str] = ("tube",), sample: int = DEFAULT_SAMPLE,
              seed: int = 0, depth: float = DEFAULT_DEPTH, replicas: int = DEFAULT_REPLICAS,
              max_crossings: int | None = None, knots: Sequence[str] | None = None,
              scheduler: str | None = None, workers: int | None = None, listener: Any = None,
              run: bool = True) -> AuditResult:
    """Audit the verdicts of ``store`` (module docstring): draw, search again, judge, count,
    store.

    Parameters
    ----------
    store : Store
        The results database (written: the audit's searches and its rows).
    models, sample, seed, max_crossings, knots
        What to draw (:func:`sample_entries`).
    depth : float
        Moves of each audit search in moves of one of the entry's replicas (≥ 0.1).
    replicas : int
        Audit searches per entry.
    scheduler, workers, listener
        As :func:`~stiffknots.sweeps.run.run_sweep` (a listener is told of each audit sweep:
        one per model and settings).
    run : bool
        False: draw and plan only (nothing runs; the rows judge what is stored).

    Returns
    -------
    AuditResult
    """
    import time

    from stiffknots.knots.catalogue import get_knot
    from stiffknots.sweeps.run import run_sweep

    t0 = time.perf_counter()
    replicas = V.replicas(replicas)
    params = {"sample": int(sample), "seed": V.seed(seed), "depth": float(depth),
              "replicas": replicas, "models": sorted(models), "max_crossings": max_crossings,
              "tolerance": TOLERANCE}
    if knots is not None:  # only when given: the audits without it keep their ids
        from stiffknots.sweeps.plan import resolve_knots

        params["knots"] = resolve_knots(knots)
    audit_budget({"moves": 1000}, depth, replicas)  # a bad depth fails before anything runs
    res = AuditResult(settings_hash(params), params)
    entries, res.converged = sample_entries(store, models=models, sample=sample, seed=seed,
                                            max_crossings=max_crossings, knots=knots)
    search_seed = audit_seed(seed)
    now = datetime.now(UTC).isoformat(timespec="seconds")
    for (exclusion, beads, thickness, _h), group in _groups(store, entries).items():
        model = Width.of(exclusion, thickness, beads)
        budget = audit_budget(group[0]["settings"], depth, replicas)
        knots = [e["knot"] for e in group]
        sweep = run_sweep(knots, [model], budget, store, seed=search_seed, scheduler=scheduler,
                          workers=workers, listener=listener, run=run, problem=AUDIT_PROBLEM)
        res.failed += sweep.failed
        res.cpu_seconds += sweep.cpu_seconds
        h = settings_hash(sweep_settings(model, budget, AUDIT_PROBLEM))
        for e in group:
            # this audit's searches only (its seed): another audit of the same depth shares
            # their settings, and so the ensemble, but is not this audit's opinion
            searched = store.replicas(knot=e["knot"], exclusion=exclusion, beads=beads,
                                      thickness=thickness, settings_hash=h, seed=search_seed)
            res.search_cpu_seconds += sum(float(r["cpu_seconds"] or 0.0) for r in searched)
            low = min(searched, key=lambda r: r["epsilon"]) if searched else None
            g = None if low is None else {"epsilon": low["epsilon"], "name": (
                f"CB(i={low['multiplicity']})" if low["shape"] == "CB" else low["shape"])}
            res.rows.append({
                "audit": res.audit, "created": now, "version": __version__,
                "knot": e["knot"], "exclusion": exclusion, "beads": beads,
                "thickness_key": store_thickness_key(thickness),
                "settings_hash": e["settings_hash"], "w_over_L": e["w_over_L"],
                "epsilon": e["epsilon"], "state": e["state"], "audit_settings_hash": h,
                "audit_seed": search_seed, "searches": len(searched),
                "audit_epsilon": g["epsilon"] if g else None,
                "audit_state": g["name"] if g else None,
                "false_verdict": int(judge(e, g)), "params": canonical_json(params),
                "crossings": get_knot(e["knot"]).crossing_number,
                "gap": ((e["epsilon"] - g["epsilon"]) / e["epsilon"]) if g else None})
        if sweep.interrupted:
            res.interrupted = True
            break
    res.rows.sort(key=lambda r: _order(r))
    if run:
        store.put_audits([{k: v for k, v in r.items() if k not in ("crossings", "gap")}
                          for r in res.rows if r["searches"] > 0])
    res.summary = summarise(res.rows)
    res.wall_seconds = time.perf_counter() - t0
    return res


def _order(row: Mapping[str, Any]) -> tuple:
    from stiffknots.store.keys import knot_sort_key

    return knot_sort_key(row["knot"]), row["exclusion"]


def store_thickness_key(thickness: float) -> str:
    """The store's key form of a thickness (:func:`stiffknots.store.thickness_key`)."""
    from stiffknots.store import thickness_key

    return thickness_key(thickness)


def latest_audits(store: Store) -> dict[tuple, dict]:
    """The newest audit row of every audited ensemble: (knot, exclusion, beads,
    thickness_key, settings_hash) → row (for ``db grounds`` and the atlas pages)."""
    out: dict[tuple, dict] = {}
    for r in store.audits():  # newest first within a knot
        key = (r["knot"], r["exclusion"], r["beads"], r["thickness_key"], r["settings_hash"])
        out.setdefault(key, r)
    return out

