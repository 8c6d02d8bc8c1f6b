"""The one template of every problem: catalogue → jobs → engine → verification → result.

A problem (closed annealing §VII, open knots at fixed extension or fixed force §VIII, the
restricted-curvature search §IX D) is a :class:`Problem`: it validates its inputs once, at its
public boundary, and turns them into :class:`Job` s — one per replica, each with its starting
chain, seed and run settings. :func:`solve` runs the jobs on all cores
(:func:`~stiffknots.problems.pool.run_jobs`), each job in a worker process running the engine
(:func:`~stiffknots.engine.driver.run_replica`, or replica exchange) and verifying its result
(:func:`run_job`), then sorts the replicas best first and packs them into the problem's
:class:`ReplicaSet`.

Verification, in one place, of every replica:

* the engine's own checks (:func:`~stiffknots.engine.driver.make_result`): the energy
  recomputed from scratch equals the incremental one, bonds are unit (1e-10), open chains stay
  clamped, the exclusion rule holds;
* the final minimiser (:func:`~stiffknots.engine.polish.polish`, on by default): the Monte
  Carlo's best chain is taken to the local minimum of E_d with unit bonds and the exclusion
  rule held exactly and no strand passage on the way (its own proof and guard); the replica's
  numbers are those of the polished chain, and ``polish`` records the energy before, the KKT
  residual, the iterations and whether it converged (not applied where the energy is not the
  paper's E_d — the restricted-curvature plan — or where the ends move: the fixed-force
  ensemble);
* the knot type. Every starting chain is checked before any work: its HOMFLY-PT polynomial
  (:func:`~stiffknots.knots.identify.homfly_code`, chiral; an open chain is closed along its z
  axis first) must be the requested knot's in topoly's table, or — for a knot beyond the table
  (13 crossings) — at least computable, the start being that knot by construction (KnotInfo's
  braid word). Every final chain must then have exactly the polynomial of its start: the moves
  cannot change the knot type (nor its chirality), so any difference raises
  :class:`~stiffknots.errors.TopologyChangedError` — a bug, never a data point. The replica's
  ``knot`` is then the one catalogue name that was requested, and ``knot_check`` says how it
  was confirmed.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from stiffknots._version import __version__
from stiffknots.chain import Chain
from stiffknots.engine.driver import (
    AnnealSettings,
    ReplicaResult,
    default_workers,
    polishable,
    replica_seeds,
    run_replica,
)
from stiffknots.engine.langevin import run_langevin_replica
from stiffknots.engine.tempering import run_tempering
from stiffknots.errors import TopologyChangedError, UserInputError
from stiffknots.fileio import write_bytes, write_json
from stiffknots.formats import save
from stiffknots.problems import validate as V
from stiffknots.problems.pool import WorkerPool, run_jobs
from stiffknots.width import Width


@dataclass
class Replica(ReplicaResult):
    """One verified replica: the engine's :class:`ReplicaResult` plus what the problem adds.

    Attributes
    ----------
    knot : str or None
        The requested knot's catalogue name when verified; otherwise the type the invariant
        identifies.
    knot_verified : bool or None
        True when the final chain has the HOMFLY-PT polynomial of its start.
    knot_check : str or None
        How the type was confirmed (module docstring).
    polish : dict or None
        What the final minimiser did (module docstring; None if it was not applied).
    start : str or None
        The starting embedding (``braid``, ``cage``, ``eighty``, ``open``).
    lineage : int or None
        The independent search this replica belongs to: the index of the replica that
        started it from an embedding (its own index for such a replica); a continuation leg
        (basin hops from a finished replica's chain, see :func:`solve`) keeps its parent's.
    leg : int
        0 for a replica started from an embedding, k for the k-th continuation of its
        lineage.
    observables : dict
        Problem-specific numbers (e.g. ``length_over_R`` of §IX D), also
        readable as attributes (``r.length_over_R``).
    wall_time, cpu_time
        The whole replica — Monte Carlo, final minimiser and knot check
        (the Monte Carlo alone: ``traces["seconds"][-1]``; the minimiser: ``polish["seconds"]``).
    """

    knot: str | None = None
    knot_verified: bool | None = None
    start: str | None = None
    lineage: int | None = None
    leg: int = 0
    observables: dict = field(default_factory=dict)
    knot_check: str | None = None
    polish: dict | None = None

    def __getattr__(self, name: str):
        # the problem's observables read as attributes (``r.length_over_R``)
        obs = self.__dict__.get("observables")
        if obs is not None and name in obs:
            return obs[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


@dataclass
class Job:
    """One replica to run: everything a worker process needs (plain, picklable data)."""

    replica: int
    seed: int
    coords: np.ndarray
    settings: AnnealSettings
    knot: str
    start: str = "braid"
    start_code: str = ""  # HOMFLY-PT polynomial of the starting chain (topoly's code)
    polish: bool = True  # run the final minimiser on the best chain
    checkpoint: Path | None = None
    resume: bool = False
    checkpoint_seconds: float | None = None
    lineage: int | None = None  # the search it continues (None: a new one, its own index)
    leg: int = 0  # continuation legs of that search before this one
    #: the exclusion of the final minimiser where it is not the Monte Carlo's: a bead-rule
    #: search annealed under the tube rule (w = d), whose chains the bead rule admits
    #: (:data:`stiffknots.problems.closed.TUBE_ROUTE_FROM`); None: ``settings.params``
    polish_params: Any = None
    #: how the search ran, when not plainly (kept in the replica's ``observables["search"]``)
    search: str | None = None
    #: anneal the start at this many beads first and search from that chain, resampled
    #: (:mod:`stiffknots.problems.coarse`); None: from the start itself
    coarse: int | None = None


DEFAULT_MOVES = AnnealSettings.moves  # 15 M at N = 150: relaxation + annealing (schedules.py)

#: Independent searches that must reach the lowest state before a verdict, per exclusion model
#: (:func:`verdict`; the sweeps' rule too, :mod:`stiffknots.sweeps.convergence`). The tube
#: model's annealing lands in a funnel above the ground often enough that two searches agree
#: on it (8_13: 5 of 16 searches of 5 M moves end at 278.5, the ground is 216.3); a third
#: search removed most such verdicts in the tube atlas through 8 crossings
#: (docs/methods/verdicts.md). The bead rule keeps two: its Langevin ensembles run up to 16
#: replicas and its ground is reported as the lowest state found, an upper bound.
AGREE = {"bead": 2, "tube": 3}


def agree_for(exclusion: str | None) -> int:
    """The searches a verdict needs under ``exclusion`` (:data:`AGREE`; the bead rule's for
    any other)."""
    return AGREE.get(exclusion or "", AGREE["bead"])


def default_moves(n_beads: int) -> int:
    """The default budget of a replica of N beads: 100,000 attempted moves per bead (15 M at
    N = 150, × N/150). The crankshafts' lengths cover every scale of the chain (m up to N/2,
    half of them log-uniform: :class:`~stiffknots.engine.params.MoveParams`), so the moves
    each bead needs do not grow with N: measured, the 3_1 reaches its circular braid to the
    same relative precision at N = 600 on 15 M moves as at N = 150 (docs/methods/search.md)."""
    return max(1_000_000, round(DEFAULT_MOVES * int(n_beads) / 150))


def observe_shape(r: Replica, params) -> None:
    """Classify a closed replica's chain (:func:`stiffknots.analysis.classify`, §VII) with the
    exclusion distance of its run; store ``shape`` ('CB2', '4C', '80', 'other'), ``label``,
    ``multiplicity``, ``shape_reason`` and ``structure`` (its contact structure named, §V B:
    :func:`stiffknots.analysis.structure_name`) in its observables.

    The analysis warns a user who reads a chain where it cannot see every contact (a tube much
    thinner than a bond); here the run itself reads it, with its own width: the warning is
    kept as ``shape_note`` (for a command to say in one plain line where the user chose that
    width), not shown as a Python warning in the middle of the output."""
    import warnings

    from stiffknots.analysis import classify
    from stiffknots.errors import ChainWarning

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always", ChainWarning)
        s = classify(r.coords, d=params.w if params.exclusion == "tube" else params.d)
    for w in seen:
        if not issubclass(w.category, ChainWarning):  # not ours: as it came
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    notes = [str(w.message) for w in seen if issubclass(w.category, ChainWarning)]
    r.observables.update(shape=f"CB{s.multiplicity}" if s.label == "CB" else s.label,
                         label=s.label, multiplicity=s.multiplicity, shape_reason=s.reason,
                         structure=s.structure.get("name"))
    if notes:
        r.observables["shape_note"] = notes[0]


def knot_code(coords: np.ndarray, closed: bool = True) -> str:
    """The HOMFLY-PT polynomial (topoly's chiral code) of a chain; an open chain is closed
    along its z axis first (§VIII)."""
    from stiffknots.knots.identify import homfly_code

    return homfly_code(coords, closed=closed)


def start_code(knot_name: str, coords: np.ndarray, closed: bool, start: str) -> str:
    """The polynomial of a starting chain, after checking that it is the requested knot.

    The answer is kept in the disk cache (``stiffknots._diskcache``) under the chain's exact
    bytes, the knot, the start, the package version and topoly's version: the built-in
    embeddings are deterministic, so every later command on the same knot reads its start's
    polynomial instead of importing topoly (≈ 1.4 s) and computing it in the parent; a chain
    that differs in one bit is computed anew. Every replica's final chain is still computed
    and compared with it (:func:`run_job`).

    Raises
    ------
    EmbeddingError
        If the invariant cannot be computed, or if the table names another knot (never
        cached: it raises every time).
    """
    import hashlib
    from importlib.metadata import PackageNotFoundError, version

    from stiffknots._diskcache import cached, source_key

    x = np.ascontiguousarray(coords, dtype=np.float64)
    try:
        tv = version("topoly")
    except PackageNotFoundError:  # pragma: no cover (a dependency)
        tv = "?"
    key = source_key(knot_name, start, str(bool(closed)), tv,
                     hashlib.sha256(x.tobytes()).hexdigest() + str(x.shape))
    return cached("startcode", key, lambda: _start_code(knot_name, x, closed, start))


def _start_code(knot_name: str, coords: np.ndarray, closed: bool, start: str) -> str:
    """:func:`start_code`, computed."""
    from stiffknots.errors import EmbeddingError, IdentificationError
    from stiffknots.knots.identify import identify_code, normalize_name

    try:
        code = knot_code(coords, closed)
    except IdentificationError as exc:
        raise EmbeddingError(f"the {start} embedding of {knot_name} cannot be checked: {exc}; "
                             "its knot type could not be verified, so it is not run") from None
    names = identify_code(code)
    if names != "unknown" and normalize_name(knot_name) not in names.split("|"):
        raise EmbeddingError(f"the {start} embedding of {knot_name} identifies as {names}: "
                             "this is a bug in stiffknots, please report it")
    return code


def run_job(job: Job) -> Replica:
    """Worker: run the engine on one job and verify the result's knot type (its polynomial
    must be its start's)."""
    from stiffknots.knots.identify import identify_code
    from stiffknots.problems.pool import report

    kw = {"checkpoint": job.checkpoint, "resume": job.resume,
          "checkpoint_every": 10 if job.checkpoint else None,
          "checkpoint_seconds": job.checkpoint_seconds if job.checkpoint else None}
    coarse = None
    if job.coarse is not None:
        from dataclasses import replace

        from stiffknots.problems.coarse import coarse_start

        y, coarse = coarse_start(job.knot, job.start, job.settings, len(job.coords),
                                 job.coarse, job.seed, job.replica)
        if y is not None:
            job = replace(job, coords=y)
    if job.settings.schedule.kind == "tempering":
        raw = run_tempering(job.coords, job.settings, job.seed, job.replica, **kw)
    elif job.settings.schedule.kind == "langevin":
        raw = run_langevin_replica(job.coords, job.settings, job.seed, job.replica,
                                   progress=report, **kw)
    else:
        raw = run_replica(job.coords, job.settings, job.seed, job.replica, progress=report, **kw)
    wall0, cpu0 = time.perf_counter(), time.process_time()  # after the Monte Carlo
    fields, info = (polish_run(vars(raw), job.settings, job.polish_params) if job.polish
                    else (vars(raw), None))
    code = knot_code(fields["coords"], job.settings.closed)
    ok = code == job.start_code
    found = job.knot if ok else identify_code(code)
    check = "HOMFLY-PT polynomial unchanged from the starting chain" if ok else (
        "HOMFLY-PT polynomial differs from the starting chain's")
    # the replica's cost is the whole job: the Monte Carlo (its wall time counts the sessions
    # of a resumed run; alone it is the last entry of traces["seconds"]), the final minimiser
    # (polish["seconds"]) and the knot check — the table's seconds and the store's wall/CPU
    # seconds left the last two out (a polish of 16 s at N = 600 after 2 s of annealing read
    # as a 2 s replica)
    # a coarse stage (its own wall and CPU seconds) is part of the replica's cost too
    pre_wall = coarse.get("wall_seconds", 0.0) if coarse else 0.0
    pre_cpu = coarse.get("cpu_seconds", 0.0) if coarse else 0.0
    fields = dict(fields, wall_time=pre_wall + raw.wall_time + time.perf_counter() - wall0,
                  cpu_time=pre_cpu + (raw.cpu_time or 0.0) + time.process_time() - cpu0)
    obs = {"search": job.search} if job.search else {}
    if coarse is not None:
        obs["coarse"] = coarse
    return Replica(**fields, knot=found, knot_verified=ok, start=job.start,
                   lineage=job.replica if job.lineage is None else job.lineage, leg=job.leg,
                   knot_check=check, polish=info, observables=obs)


def polish_run(fields: dict, settings: AnnealSettings, params: Any = None
               ) -> tuple[dict, dict | None]:
    """The numbers of a run after the final minimiser (:func:`stiffknots.engine.polish.polish`)
    took its best chain to the local minimum; and what the minimiser did. ``params``: the
    exclusion the minimiser holds (default the run's, ``settings.params``; a tube-route
    search of a bead-rule problem passes the bead rule).

    Every number that depends on the chain is recomputed from the polished coordinates (the
    energy from scratch), so the verification that follows applies to the polished chain.
    """
    from stiffknots.engine.polish import polish
    from stiffknots.engine.prims import (
        check_state,
        energy_chain,
        min_nonadjacent_segment_distance,
        turning_cosines,
    )

    if not polishable(settings):
        return fields, None
    p = settings.params if params is None else params
    closed = settings.closed
    res = polish(fields["coords"], closed=closed, exclusion=p.exclusion, d=p.d, w=p.w)
    x = res.pos
    e = float(energy_chain(x, not closed))
    n = len(x)
    le = float(n - 1 - (x[-1, 2] - x[0, 2])) if not closed else None
    out = dict(fields)
    bonds = (np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0)
    mode = 0 if p.exclusion == "bead" else 1
    out.update(
        coords=x, energy=e, energy_recomputed=e, epsilon=e * (n if closed else le),
        max_bond_error=float(np.max(np.abs(np.linalg.norm(bonds, axis=1) - 1.0))),
        exclusion_margin=-float(check_state(x, mode, p.d, p.w, not closed)),
        min_segment_distance=float(min_nonadjacent_segment_distance(x, not closed)),
        max_turn=float(np.max(np.arccos(np.clip(turning_cosines(x, not closed), -1, 1)))))
    if not closed:
        out["total_energy"] = e
    info = {"epsilon_before": fields["epsilon"], "energy_before": res.energy_before,
            "kkt_residual": res.kkt_residual, "relative_kkt": res.relative_kkt,
            "iterations": res.iterations, "converged": res.converged, "reason": res.reason,
            "n_active": res.n_active, "strand_gap": res.strand_gap,
            "gap_force": res.gap_force, "seconds": res.seconds}
    return out, info


@dataclass
class ReplicaSet:
    """The replicas of one problem for one knot, best first, with their provenance.

    Every result of stiffknots is one of these (or a thin subclass adding derived
    properties): ``to_dict`` gives the problem's physics (:meth:`physics`), the bounds, and the
    provenance (seed, settings, version, wall time, each replica's summary); ``save`` writes
    ``result.json``, the best chain (``best.xyz``, ``best.json``), every replica's chain and
    the traces, each file atomically, ``result.json`` last.
    """

    problem: ClassVar[str] = "anneal"
    closed: ClassVar[bool] = True

    knot: str
    beads: int
    seed: int
    settings: dict
    replicas: list[Replica]
    wall_time: float
    interrupted: bool = False
    version: str = __version__
    bounds: dict = field(default_factory=dict)
    converged: bool | None = None
    convergence: str = ""
    rounds: int = 1
    #: the width every number of the result was computed at
    width: Width | None = None

    @property
    def best(self) -> Replica:
        """The best replica (the first); RuntimeError if none finished (e.g. Ctrl-C)."""
        if not self.replicas:
            raise RuntimeError("no replica finished")
        return self.replicas[0]

    def physics(self) -> dict:
        """The problem's own numbers (of the best replica); None where no replica finished."""
        return {"epsilon": self.best.epsilon if self.replicas else None}

    def to_dict(self) -> dict:
        ok = bool(self.replicas) and all(r.knot_verified for r in self.replicas)
        return {"problem": self.problem, "knot": self.knot, "beads": self.beads,
                "seed": self.seed, **self.physics(),
                "width": self.width.as_dict() if self.width is not None else None,
                "bounds": self.bounds, "knot_verified": ok,
                "converged": self.converged, "convergence": self.convergence,
                "rounds": self.rounds,
                "settings": self.settings, "wall_time": self.wall_time,
                "interrupted": self.interrupted, "version": self.version,
                "replicas": [r.summary() for r in self.replicas]}

    def chain_meta(self, r: Replica) -> dict:
        """Metadata stored with a replica's chain file."""
        return {"problem": self.problem, "knot": self.knot, "seed": r.seed,
                "replica": r.replica, "epsilon": r.epsilon, "version": self.version,
                "settings": self.settings}

    def save(self, out: str | Path, overwrite: bool = False) -> dict[str, Path]:
        """Write ``best.xyz``/``best.json``, ``replica_K.xyz`` for every replica,
        ``traces.npz`` and, last, ``result.json`` into ``out`` (each file atomically).

        A folder that holds another run's results (any of these names) is refused — a
        :class:`~stiffknots.errors.UserInputError`, as the command line refuses its
        ``--out`` — unless ``overwrite``: the files of the same names are then replaced (a
        ``replica_K.xyz`` of a larger earlier run stays)."""
        import fnmatch
        import io
        import os

        out = Path(out)
        if not overwrite and out.is_dir():
            old = sorted(n for n in os.listdir(out) if n in _RESULT_NAMES
                         or fnmatch.fnmatchcase(n, "replica_*.xyz"))
            if old:
                raise UserInputError(f"{out} holds the results of another run ({old[0]}); "
                                     "choose another folder or pass overwrite=True")
        out.mkdir(parents=True, exist_ok=True)
        paths: dict[str, Path] = {}
        for r in self.replicas:
            save(Chain(r.coords, closed=self.closed, meta=self.chain_meta(r)),
                 out / f"replica_{r.replica}.xyz")
        if self.replicas:
            best = Chain(self.best.coords, closed=self.closed, meta=self.chain_meta(self.best))
            save(best, out / "best.xyz")
            save(best, out / "best.json")
            paths["best_xyz"] = out / "best.xyz"
            paths["best_json"] = out / "best.json"
            buf = io.BytesIO()
            np.savez_compressed(buf, **{f"r{r.replica}_{k}": v for r in self.replicas
                                        for k, v in r.traces.items()})
            paths["traces"] = write_bytes(out / "traces.npz", buf.getvalue())
        paths["result"] = write_json(out / "result.json", self.to_dict())
        return paths


#: what :meth:`ReplicaSet.save` writes besides ``replica_K.xyz``
_RESULT_NAMES = ("result.json", "best.xyz", "best.json", "traces.npz")


class Problem:
    """A problem of the paper, ready to solve: its inputs validated, its jobs made.

    Subclasses set ``result_type`` and implement :meth:`jobs` (one :class:`Job` per replica),
    :meth:`bounds`, :meth:`settings_dict`, :meth:`sort_key` (lower is better) and, if they
    need it, :meth:`observe` (problem-specific numbers of a finished replica) and
    :meth:`result_fields` (extra fields of the result).
    """

    result_type: ClassVar[type[ReplicaSet]] = ReplicaSet
    knot_name: str
    beads: int
    seed: int
    replicas: int
    #: the most rounds of ``replicas`` replicas :func:`solve` runs until the verdict is
    #: "converged" (1: a fixed budget)
    rounds: int = 1
    #: converged: the lowest state reached by at least ``agree`` replicas …
    agree: int = 2
    #: … of the same shape and value within ``rel_tol`` (relative) of the lowest
    rel_tol: float = 1e-3
    #: rounds of new searches (replicas from the embeddings) before :func:`solve` continues
    #: the lowest searches instead (problems that implement :meth:`continue_jobs`)
    fresh_rounds: int = 2
    #: … and then continues this many of them per round (the lowest that still improve);
    #: the rest of each round's replicas start new searches
    legs_per_round: int = 1

    def continue_jobs(self, parents: list[Replica], first: int) -> list[Job] | None:
        """Jobs that continue the searches of ``parents`` (one job each, replica indices
        ``first`` …), or None if this problem does not continue searches (every round then
        starts new replicas from the embeddings)."""
        return None

    def jobs(self, first: int = 0) -> list[Job]:
        """The jobs of replicas ``first`` … ``first + replicas − 1`` (one round)."""
        raise NotImplementedError

    def state_of(self, r: Replica) -> tuple[str, float]:
        """The state a finished replica reached: (shape label, value); replicas of the same
        label and value within ``rel_tol`` are one state (see :func:`.verdict`)."""
        return "", self.sort_key(r)

    # -- helpers of the subclasses' constructors and jobs -----------------------------------

    def _verdict_rule(self, rounds: int, agree: int, rel_tol: float) -> None:
        """The convergence rule (:func:`verdict`), validated."""
        self.rounds = V.integer("rounds", rounds, 1, V.MAX_ROUNDS)
        self.agree = V.integer("agree", agree, 1, V.MAX_REPLICAS)
        self.rel_tol = V.number("rel_tol", rel_tol, 0, 1, lo_open=True)

    def _setup(self, knot, replicas: int, seed: int, beads: int | None = None) -> None:
        """The knot (a catalogue entry, or a name resolved here), replicas, seed and beads,
        validated."""
        from stiffknots.knots.catalogue import Knot, get_knot

        self.knot = knot if isinstance(knot, Knot) else get_knot(knot)
        self.knot_name = self.knot.name
        self.replicas = V.replicas(replicas)
        self.seed = V.seed(seed)
        if beads is not None:
            self.beads = V.beads(beads)

    #: the start that new searches after the fresh rounds take (:meth:`favour`); None:
    #: every replica takes the per-replica starts round-robin
    favoured: str | None = None
    #: may :func:`solve` favour a start (True where the starts were the default ``'all'``)
    adaptive_starts: bool = False

    def favour(self, start: str) -> None:
        """New searches of the rounds after :attr:`fresh_rounds` start from ``start`` (the
        start of the lowest search so far): the fresh rounds tried every embedding, and a
        search from the embedding whose funnel holds the lowest state is the one likeliest to
        reach it a second time (docs/history.md). Replicas of the fresh rounds
        keep their round-robin starts."""
        if start not in self.starts:
            raise ValueError(f"start {start!r} is not one of this problem's {self.starts}")
        self.favoured = start

    def _start(self, r: int) -> str:
        """The starting embedding of replica r: the per-replica starts round-robin, or the
        favoured start for a replica after the fresh rounds (:meth:`favour`)."""
        if self.favoured is not None and r >= self.fresh_rounds * self.replicas:
            return self.favoured
        return self.starts[r % len(self.starts)]

    def _closed_starts(self, start) -> None:
        """The starting embeddings the replicas take in turn (``self.starts``: replica r, of
        any round, the (r mod k)-th — with ``'all'`` every start of
        :func:`~stiffknots.knots.starts.default_starts`, so that later rounds start from the
        starts the first did not reach; given starts, one per replica of a round), their
        chains and their checked knot polynomials."""
        from stiffknots.knots.starts import default_starts, resolve_starts, start_chain

        if isinstance(start, str) and start == "all":
            self.starts = default_starts(self.knot, self.beads)
        else:
            self.starts = resolve_starts(self.knot, start, self.replicas, self.beads)
        self.chains = {st: start_chain(self.knot, st, self.beads)
                       for st in dict.fromkeys(self.starts)}
        self.codes = {st: start_code(self.knot_name, x, True, st)
                      for st, x in self.chains.items()}

    #: run the final minimiser on every replica's best chain
    polish: bool = True

    def _replica_jobs(self, settings: AnnealSettings, coords: Callable[[int], np.ndarray],
                      start: Callable[[int], str], code: Callable[[int], str],
                      checkpoint_dir=None, resume: bool = False,
                      checkpoint_seconds: float | None = None, first: int = 0,
                      count: int | None = None, polish_params: Any = None,
                      search: str | None = None, coarse: int | None = None) -> list[Job]:
        """One job per replica ``first`` … ``first + count − 1`` (``count``: default
        ``replicas``); replica r's seed is the r-th seed derived from the problem's seed,
        whatever the round it runs in. ``polish_params``, ``search``, ``coarse``: see
        :class:`Job`."""
        n = self.replicas if count is None else count
        seeds = dict(zip(range(first, first + n), replica_seeds(self.seed, first + n, first),
                         strict=True))
        return [Job(replica=r, seed=seeds[r], coords=coords(r), settings=settings,
                    knot=self.knot_name, start=start(r), start_code=code(r),
                    polish=self.polish, polish_params=polish_params, search=search,
                    coarse=coarse, checkpoint=(Path(checkpoint_dir) / f"replica_{r}.ckpt.npz"
                                if checkpoint_dir is not None else None),
                    resume=resume, checkpoint_seconds=checkpoint_seconds)
                for r in range(first, first + n)]

    def bounds(self) -> dict:
        """The paper's bounds on the problem's value (``lower``, ``upper``, ``attained_by``);
        empty when it has none."""
        return {}

    def settings_dict(self) -> dict:
        """The settings of the run as plain data (the result's ``settings``)."""
        raise NotImplementedError

    def width(self) -> Width:
        """The width of the problem's chains: its exclusion model and thickness at its N."""
        return self.settings.params.width(self.beads, closed=self.result_type.closed)

    def sort_key(self, r: Replica) -> float:
        """The value replicas are ranked by, lower is better (default: ε)."""
        return r.epsilon

    def observe(self, r: Replica) -> None:
        """Add problem-specific numbers to a finished replica (parent process)."""

    def result_fields(self, replicas: list[Replica]) -> dict[str, Any]:
        """Extra fields of the result, from the finished replicas (default: none)."""
        return {}


def lineage_bests(problem: Problem, replicas: list[Replica]) -> list[Replica]:
    """The lowest replica of every lineage (independent search), lowest first."""
    best: dict[int, Replica] = {}
    for r in replicas:
        key = lineage_of(r)
        if key not in best or problem.sort_key(r) < problem.sort_key(best[key]):
            best[key] = r
    return sorted(best.values(), key=problem.sort_key)


def lineage_of(r: Replica) -> int:
    """The lineage (independent search) of a replica: see :class:`Replica`."""
    return r.replica if r.lineage is None else r.lineage


def stalled(problem: Problem, replicas: list[Replica], best: Replica) -> bool:
    """Has the search of ``best`` (its lineage's lowest replica) stopped improving? True when
    its latest continuation leg did not go below the lineage's lowest before that leg by more
    than ``problem.rel_tol``: its basin hops no longer find lower minima (the circular braids
    of the n = i knots do this at once: their registry is set by the relaxation, and a new
    search is then the better use of a replica)."""
    mine = sorted((r for r in replicas if lineage_of(r) == lineage_of(best)),
                  key=lambda r: r.leg)
    if len(mine) < 2 or mine[-1].leg == 0:
        return False
    before = min(problem.sort_key(r) for r in mine[:-1])
    return problem.sort_key(mine[-1]) > before - problem.rel_tol * abs(before)


def untried_starts(problem: Problem, replicas: list[Replica]) -> list[str]:
    """The default starts (``start='all'``) from which no replica has started yet; none
    where the user chose the starts."""
    if not getattr(problem, "adaptive_starts", False):
        return []
    tried = {r.start for r in replicas}
    return [s for s in dict.fromkeys(getattr(problem, "starts", ())) if s not in tried]


def tube_route_lineages(replicas: list[Replica]) -> set[int]:
    """The searches (lineages) that began as tube-route searches of a bead-rule run
    (:data:`stiffknots.problems.closed.TUBE_ROUTE_FROM`: their first replica's
    ``observables["search"]``), legs that continued them included."""
    return {lineage_of(r) for r in replicas if r.leg == 0 and r.observables.get("search")}


def verdict(problem: Problem, replicas: list[Replica]) -> tuple[bool, str]:
    """Has the search converged? True when the lowest state — the best replica's shape, and a
    value within ``problem.rel_tol`` of the lowest — was reached by at least
    ``problem.agree`` independent searches, and, where the starts are the defaults
    (``start='all'``), every starting embedding has had a search; and a sentence saying why
    (or why not).

    A search (lineage) is a replica started from an embedding together with the legs that
    continued it (:func:`solve`); it counts once, by its lowest replica: a leg that returns to
    its parent's state is no second opinion, two searches that never shared a chain are.

    The default starts are the shapes §VII conjectures for the knot (braid, cage, 80): each
    is a hypothesis for the ground state, and one not yet tried can hold a lower state. With
    two replicas a round the first round of a knot with three starts tries two; measured on
    4_1 (bead rule, N = 150): braid and cage agreed at the cage's 128.384 after one round
    ("converged"), while six 10⁶-move searches from the 80 all ended lower, at
    127.43–128.27 (docs/history.md).

    Tube-route searches (:func:`tube_route_lineages`) confirm a state but do not certify it:
    at least one of the searches that reached it must be the bead rule's own. Two tube-route
    searches agree easily on the bead minimum below one tube funnel while the bead rule's own
    searches go lower: counted like the others, they "converged" 7_5 at 183.65 and 6_3 at
    163.71, whose bead searches reach 176.98 and 160.50 (docs/history.md)."""
    if not replicas:
        return False, "no replica finished"
    bests = lineage_bests(problem, replicas)
    states = [problem.state_of(r) for r in bests]
    label, value = states[0]
    tol = problem.rel_tol * max(abs(value), 1e-300)
    hit = [lab == label and v - value <= tol for lab, v in states]
    hits = sum(hit)
    name = f"{label}, {value:.6g}" if label else f"{value:.6g}"
    of = (f"{len(bests)} independent searches ({len(replicas)} replicas)"
          if len(bests) < len(replicas) else f"{len(replicas)} replicas")
    routed = tube_route_lineages(replicas)
    own = sum(1 for h, r in zip(hit, bests, strict=True) if h and lineage_of(r) not in routed)
    if hits >= problem.agree and not own:
        return False, (f"the lowest state ({name}) was reached by {hits} of {of} "
                       f"(within {problem.rel_tol:.0e}), all of them tube-route searches: they "
                       "share the tube rule's funnels, so a search of the bead rule's own must "
                       "reach it too")
    untried = untried_starts(problem, replicas)
    if hits >= problem.agree and untried:
        k = len(dict.fromkeys(problem.starts))
        hint = (f" ({k} replicas a round give every start a search in the first)"
                if getattr(problem, "replicas", k) < k else "")
        return False, (f"the lowest state ({name}) was reached by {hits} of {of} "
                       f"(within {problem.rel_tol:.0e}), but no search has started from the "
                       f"{' or '.join(untried)} embedding yet{hint}")
    if hits >= problem.agree:
        return True, (f"the lowest state ({name}) was reached by {hits} of {of} "
                      f"(within {problem.rel_tol:.0e})")
    return False, (f"the lowest state ({name}) was reached by {hits} of {of}; "
                   f"{problem.agree} needed (within {problem.rel_tol:.0e})")


def solve(problem: Problem, *, workers: int | None = None,
          on_replica_done: Callable[[Replica], None] | None = None,
          on_progress: Callable[[dict], None] | None = None,
          isolate: bool = False, pool: WorkerPool | None = None) -> ReplicaSet:
    """Run every job of ``problem`` on ``workers`` processes (default: all cores) and return
    its verified replicas, best first.

    The replicas run in rounds of ``problem.replicas``; after each round the verdict
    (:func:`verdict`) decides: converged — stop; not converged — run another round, up to
    ``problem.rounds`` (easy knots stop early, hard ones get more). The result carries
    ``converged`` and the reason. The first ``problem.fresh_rounds`` rounds start new searches
    from the embeddings; in later rounds, where the problem can (:meth:`Problem.continue_jobs`),
    ``problem.legs_per_round`` replicas continue the lowest searches that still improve
    (:func:`stalled`) — each from its lowest chain, by basin hops — and the others start new
    searches, from the embedding of the lowest search so far where the problem's starts are
    its defaults (:meth:`Problem.favour`): on knots whose minima lie within tenths of a
    percent of each other, a long search walks down to the bottom of its funnel where a short
    one stops anywhere in it, while new searches keep finding other funnels
    (docs/history.md).

    Ctrl-C keeps the finished replicas (``interrupted`` is then True). ``on_progress``
    receives, while the replicas run, records ``{"replica", "done", "total", "epsilon",
    "best"}`` (moves done and planned, current and lowest ε) from the workers. ``isolate``
    runs even a single replica in a worker process, so that Ctrl-C stops it at once (the
    command line does; :func:`~stiffknots.problems.pool.run_jobs`). Every round runs on the
    same worker processes: ``pool`` (a :class:`~stiffknots.problems.pool.WorkerPool` of
    ``workers`` processes, which the caller may have started before it built the problem, and
    closes) or one this call starts when a round first needs a worker and stops at its end.

    Raises
    ------
    CheckpointError
        Before any work, if a job resumes from a corrupt checkpoint or one of another run.
    TopologyChangedError
        If a replica ends with another knot type (never expected: a bug, never a data point).
    """
    nw = workers or default_workers(problem.replicas)
    t0 = time.perf_counter()

    def done(r: Replica) -> None:
        problem.observe(r)
        if on_replica_done is not None:
            on_replica_done(r)

    own = pool is None
    if own:
        pool = WorkerPool(nw)  # started by the first round that needs a worker
    try:
        results, interrupted, converged, reason, rounds = _rounds(
            problem, nw, done, on_progress, isolate, pool)
    finally:
        if own:
            pool.close()
    if not converged and not interrupted and problem.rounds > 1:
        reason += f" after {rounds} rounds (the budget)"
    results.sort(key=problem.sort_key)
    return problem.result_type(
        knot=problem.knot_name, beads=problem.beads, seed=problem.seed,
        settings=problem.settings_dict(), replicas=results,
        wall_time=time.perf_counter() - t0, interrupted=interrupted,
        bounds=problem.bounds(), converged=converged, convergence=reason, rounds=rounds,
        width=problem.width(), **problem.result_fields(results))


def _rounds(problem: Problem, nw: int, done: Callable[[Replica], None],
            on_progress: Callable[[dict], None] | None, isolate: bool, pool: WorkerPool
            ) -> tuple[list[Replica], bool, bool, str, int]:
    """The rounds of :func:`solve`: (replicas, interrupted, converged, reason, rounds)."""
    results: list[Replica] = []
    interrupted = False
    converged, reason, rounds = False, "no replica finished", 0
    for rnd in range(max(1, problem.rounds)):
        later = rnd >= problem.fresh_rounds and bool(results)
        bests = lineage_bests(problem, results) if later else []
        if later and problem.adaptive_starts:
            problem.favour(bests[0].start)
        jobs = problem.jobs(first=rnd * problem.replicas)
        if later:
            parents = [r for r in bests
                       if not stalled(problem, results, r)][:problem.legs_per_round]
            legs = problem.continue_jobs(parents, first=rnd * problem.replicas)
            if legs is None:  # the problem's schedule cannot continue a search (no hops)
                legs, parents = [], []
            for j, par in zip(legs, parents, strict=True):
                j.lineage = lineage_of(par)
                j.leg = 1 + max(r.leg for r in results if lineage_of(r) == j.lineage)
            jobs = legs + jobs[len(legs):]  # new searches fill the round
        V.checkpoints(jobs)  # a corrupt or foreign checkpoint to resume: CheckpointError now
        new, interrupted = run_jobs(run_job, [(j,) for j in jobs], nw, done, on_progress,
                                    isolate=isolate, pool=pool)
        bad = [r for r in new if not r.knot_verified]
        if bad:
            raise TopologyChangedError(
                f"{len(bad)} replica(s) of {problem.knot_name} ended as "
                f"{', '.join(str(r.knot) for r in bad)}; this is a bug in stiffknots, please "
                f"report it with the seed {problem.seed} and the settings")
        results += new
        rounds = rnd + 1
        converged, reason = verdict(problem, results)
        if interrupted or converged:
            break
    return results, interrupted, converged, reason, rounds
