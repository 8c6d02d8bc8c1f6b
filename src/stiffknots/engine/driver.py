"""The run loop: one replica = a plan of chunks run on one state, verified (paper §VII).

The driver composes the state (:mod:`stiffknots.engine.state`, any ensemble) with a *plan*: a
fixed list of chunks (moves, temperature) made from the settings alone
(:mod:`stiffknots.engine.plans`). It knows arrays and numbers only. Every ensemble — a closed
chain, an open chain at fixed extension or at fixed force — and every plan runs through this
one loop, with the same checkpoints (:mod:`stiffknots.engine.checkpoints`), traces and
verification; replica exchange (:mod:`stiffknots.engine.tempering`) builds on the same pieces.

With basin hops a stage's candidate is its quenched chain taken to its local minimum by the
final minimiser (``_candidate()``). No step passes a strand through another: the moves are
guarded (:mod:`.kernel`), the minimiser is guarded (:mod:`.polish`), and a hop's restart puts
back a chain this same run reached before by those steps — a jump between two chains of one
passage-free trajectory, so of one knot type (and the type of every result is verified again
by the problems layer).

Energy bookkeeping
------------------
After every chunk the incremental energy is compared with the energy recomputed from scratch
and then replaced by it. The comparison allows 1e-9 of the largest energy the chunk saw
(``|E|`` at its start or end, at least 1): the rounding error of a sum of increments is relative
to the magnitudes summed, and in the power energy of the ``tight`` plan a chunk can start at
E ~ 10¹¹ and end at E ~ 30, so a tolerance relative to the final energy alone fails on
correct runs, while a real bookkeeping error — a joint missed by a move — is of the order of
the joint energies. Inside a chunk the power energy's increments can still dwarf both ends (a
move that bends a joint 3× its neighbours' angle raises its term 3¹⁶-fold and the next move
takes it back), so the power energy is allowed 1e-7 (docs/architecture.md). The replacement
stops rounding errors from accumulating over chunks. It never changes a move's decision
(those depend on energy differences only).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from stiffknots._version import __version__
from stiffknots.engine.checkpoints import (
    Checkpointer,
    check_resumable,
    load_checkpoint,
    restore_state,
    run_meta,
    save_checkpoint,
    state_arrays,
)
from stiffknots.engine.params import MoveParams
from stiffknots.engine.plans import TIGHT_SEED_STRIDE, Step, plan_steps, stage_params
from stiffknots.engine.prims import min_nonadjacent_segment_distance
from stiffknots.engine.settings import AnnealSettings
from stiffknots.engine.state import ChainState, check_open_clamping
from stiffknots.errors import (
    ChainGeometryError,
    EnergyBookkeepingError,
    RunStopped,
)

__all__ = ["AnnealSettings", "Clock", "ReplicaResult", "Step", "plan_steps", "polishable",
           "run_replica", "replica_seeds"]

BOOKKEEPING_RTOL = 1e-9
#: the same for the ``power`` energy of the tight plan: its terms ((1 − cos θ)/s)^p rise so
#: steeply that one move's increment can be ~10⁶ times the chunk's final energy, and its
#: rounding stays far below a missed joint's error, of order E/N (docs/architecture.md)
BOOKKEEPING_RTOL_POWER = 1e-7
HOP_POLISH_ITER = 30  # steps of the final minimiser that ranks a basin hop's chain
TRACE_KEYS = ("moves", "temperature", "epsilon", "seconds")


class _Trace:
    """Read-only attribute ``trace_<key>`` for ``traces[<key>]``."""

    def __set_name__(self, owner, name: str) -> None:
        self.key = name.removeprefix("trace_")

    def __get__(self, obj, owner=None):
        return self if obj is None else obj.traces[self.key]


@dataclass
class ReplicaResult:
    """Outcome of one replica's run (plain data; picklable, JSON-able but for the arrays).

    ``coords``/``epsilon`` are the best quenched chain of the run (the lower of the stages);
    ``stage_epsilon`` gives each stage's quenched ε and ``best_stage`` the winner.
    ``traces`` holds one value per chunk: ``moves`` (done so far), ``temperature``,
    ``epsilon`` (of the state's energy), ``seconds``, and ``excess_length`` (fixed force) or
    ``theta_max`` (``tight`` plan). ``seconds_to_target``/``cpu_seconds_to_target``:
    wall-clock and CPU seconds until ε first fell to ``target_epsilon`` (None: never).
    ``tempering``: ladder and swap statistics of a replica-exchange run (None otherwise).
    ``langevin``: what the dynamics of a ``langevin`` replica did (ε before the projection
    onto unit bonds, refused steps, guard checks; :mod:`stiffknots.engine.langevin`).
    Open chains: ``excess_length``, ``extension`` (Δz), ``force`` and ``total_energy``
    (E_d − F·Δz). ``max_turn``: the largest turning angle of the chain (radians).
    """

    replica: int
    seed: int
    epsilon: float
    energy: float
    energy_recomputed: float
    coords: np.ndarray
    acceptance: dict
    traces: dict
    wall_time: float
    max_bond_error: float
    exclusion_margin: float
    min_segment_distance: float
    max_turn: float = 0.0
    seconds_to_target: float | None = None
    cpu_seconds_to_target: float | None = None
    cpu_time: float | None = None
    stage_epsilon: dict = field(default_factory=dict)
    best_stage: str | None = None
    tempering: dict | None = None
    langevin: dict | None = None
    resumed_from_step: int | None = None
    excess_length: float | None = None
    extension: float | None = None
    force: float | None = None
    total_energy: float | None = None
    version: str = __version__

    # ``r.trace_moves`` … ``r.trace_seconds`` read ``r.traces``
    trace_moves = _Trace()
    trace_temperature = _Trace()
    trace_epsilon = _Trace()
    trace_seconds = _Trace()

    def summary(self) -> dict:
        """Every field but the coordinates and the traces."""
        d = asdict(self)
        d.pop("coords")
        d.pop("traces")
        return d


class Clock:
    """Wall-clock and CPU seconds of a run, continued across a resume."""

    def __init__(self, wall: float = 0.0, cpu: float = 0.0):
        self.w0 = time.perf_counter() - wall
        self.c0 = time.process_time() - cpu

    def wall(self) -> float:
        return time.perf_counter() - self.w0

    def cpu(self) -> float:
        return time.process_time() - self.c0


# ------------------------------------------------------------------------------------------
# verification
# ------------------------------------------------------------------------------------------


def _bonds(pos: np.ndarray, closed: bool) -> np.ndarray:
    if closed:
        return np.linalg.norm(np.roll(pos, -1, axis=0) - pos, axis=1)
    return np.linalg.norm(np.diff(pos, axis=0), axis=1)


def check_bookkeeping(state: ChainState, peak: float = 0.0) -> float:
    """The recomputed energy; EnergyBookkeepingError if the incremental one (or, at fixed
    force, E_d − F·Δz) differs by more than 1e-9 (the ``power`` energy: 1e-7,
    :data:`BOOKKEEPING_RTOL_POWER`) of ``max(1, |E|, peak)`` — ``peak`` the largest ``|E|`` the
    incremental sum went through (module docstring)."""
    e_rec = state.recomputed_energy()
    ref = max(1.0, abs(e_rec), abs(state.energy), peak)
    rtol = BOOKKEEPING_RTOL_POWER if state.params.energy == "power" else BOOKKEEPING_RTOL
    if abs(e_rec - state.energy) > rtol * ref:
        raise EnergyBookkeepingError(
            f"incremental energy {state.energy!r} differs from recomputed {e_rec!r}"
        )
    if state.ensemble.kind == "force":
        rec = state.recomputed_total()
        ref = max(1.0, abs(rec), abs(state.total_energy), peak)
        if abs(rec - state.total_energy) > rtol * ref:
            raise EnergyBookkeepingError(
                f"incremental E_d − F·Δz {state.total_energy!r} differs from recomputed {rec!r}")
    return e_rec


def resync(state: ChainState, peak: float = 0.0) -> None:
    """Check the bookkeeping (:func:`check_bookkeeping`), then replace the incremental
    energies by the recomputed ones so that rounding errors never accumulate."""
    state.energy = check_bookkeeping(state, peak)
    state.total_energy = state.recomputed_total()


def check_chain(state: ChainState, where: str = "final chain") -> None:
    """Raise ChainGeometryError if a bond is off by more than 1e-10, an open chain's clamping
    is broken or the exclusion rule is violated (never expected: the moves keep all three)."""
    err = float(np.max(np.abs(_bonds(state.pos, state.closed) - 1.0)))
    if err > 1e-10:
        raise ChainGeometryError(f"{where}: bond length off by {err:.3g}")
    if not state.closed:
        try:
            # the end moves put the ends exactly on the axis; fixed ends stay as embedded
            check_open_clamping(state.pos, tol=0.0 if state.ensemble.kind == "force" else 1e-9)
        except ValueError as exc:
            raise ChainGeometryError(f"{where}: {exc}") from None
    v = state.violation()
    if v > 1e-12:
        raise ChainGeometryError(
            f"{where}: the {state.params.exclusion} exclusion rule is violated by {v:.3g}")


def make_result(replica: int, seed: int, settings: AnnealSettings, best: ChainState,
                acceptance: dict, traces: dict, clock: Clock, hit: tuple, **extra
                ) -> ReplicaResult:
    """Verify ``best`` (bookkeeping, bonds, clamping, exclusion) and pack the result."""
    e_rec = check_bookkeeping(best)
    check_chain(best)
    pos = best.pos
    closed = best.closed
    open_fields = {} if closed else {
        "excess_length": best.excess_length, "extension": best.extension,
        "force": best.force, "total_energy": best.recomputed_total()}
    return ReplicaResult(
        replica=replica,
        seed=seed,
        # ε = E·N/C (closed, §VII) or ε_e = E·L_e/C (open, §VIII)
        epsilon=e_rec * (best.n_beads if closed else best.excess_length),
        energy=e_rec,
        energy_recomputed=e_rec,
        coords=pos.copy(),
        acceptance=acceptance,
        traces={k: np.asarray(v, dtype=np.int64 if k == "moves" else float)
                for k, v in traces.items()},
        wall_time=clock.wall(),
        cpu_time=clock.cpu(),
        max_bond_error=float(np.max(np.abs(_bonds(pos, closed) - 1.0))),
        exclusion_margin=-best.violation(),
        min_segment_distance=float(min_nonadjacent_segment_distance(pos, not closed)),
        max_turn=float(np.max(best.turning_angles())),
        seconds_to_target=hit[0],
        cpu_seconds_to_target=hit[1],
        **open_fields,
        **extra,
    )


def trace_keys(settings: AnnealSettings) -> tuple[str, ...]:
    """The traces a run records: ``TRACE_KEYS`` plus ``excess_length`` (fixed force) or
    ``theta_max`` (``tight`` plan)."""
    extra = ()
    if settings.ensemble.kind == "force":
        extra = ("excess_length",)
    if settings.plan == "tight":
        extra = extra + ("theta_max",)
    return TRACE_KEYS + extra


def polishable(settings: AnnealSettings) -> bool:
    """Does the final minimiser apply? (the ``anneal`` plan, the paper's energy E_d, ends that
    do not move)"""
    return (settings.plan == "anneal" and settings.params.energy == "bending"
            and settings.ensemble.kind in ("closed", "extension"))


def _candidate(state: ChainState, settings: AnnealSettings,
               polished: bool) -> tuple[np.ndarray, float]:
    """A stage's result as a candidate best: its chain and the energy it is ranked by.

    Without basin hops that is the quenched chain and its total energy. With hops the chain
    is first taken to its local minimum by the final minimiser
    (:func:`stiffknots.engine.polish.polish`: unit bonds and the exclusion rule held, no strand
    passage) and ranked by that minimum: a Monte Carlo quench stops further above its
    minimum than the minima the hops walk between lie apart, so quenched energies would rank
    them by the quench's noise (docs/methods/search.md). The next hop starts from the
    polished chain."""
    pos, energy = state.pos.copy(), float(state.total_energy)
    if not polished:
        return pos, energy
    from stiffknots.engine.polish import polish

    p = state.params
    # at most HOP_POLISH_ITER steps: a minimum is usually reached in 9–17, and an active set
    # that wanders must not stall the run; every iterate is admissible, so a capped polish
    # still ranks an admissible chain by its true energy
    res = polish(pos, closed=state.closed, exclusion=p.exclusion, d=p.d, w=p.w,
                 max_iter=HOP_POLISH_ITER)
    if res.energy < energy:
        return res.pos, float(res.energy)
    return pos, energy


def run_replica(coords: np.ndarray, settings: AnnealSettings, seed: int, replica: int = 0, *,
                checkpoint: str | Path | None = None, checkpoint_every: int | None = None,
                checkpoint_seconds: float | None = None, resume: bool = False,
                stop_after: int | None = None,
                progress: Callable[[dict], None] | None = None) -> ReplicaResult:
    """Run one replica: the plan of :func:`plan_steps` on one state, verified.

    Parameters
    ----------
    coords : ndarray
        (N, 3) starting chain (unit bonds, exclusion respected; open chains clamped).
    settings : AnnealSettings
        The run's settings (ensemble, plan, schedule, moves); a tempering schedule is
        run by :func:`stiffknots.engine.tempering.run_tempering` instead.
    seed : int
        Seed of the kernels' generator.
    replica : int
        Index recorded in the result.
    checkpoint : str or Path or None
        Path of a ``.npz`` checkpoint file, written every ``checkpoint_every`` chunks
        and/or every ``checkpoint_seconds`` seconds (default every 10 chunks) and at the end.
    resume : bool
        Continue from ``checkpoint`` if the file exists (it must come from the same
        settings, seed, replica, starting chain and version); otherwise start afresh.
    stop_after : int or None
        Stop after this many chunks in this call, write the checkpoint and raise
        :class:`RunStopped` (for time-limited batch jobs, and for tests).
    progress : callable or None
        Called after every chunk with ``{"replica", "done", "total", "epsilon",
        "best"}`` (moves done and planned, the current and the lowest ε so far).

    Returns
    -------
    ReplicaResult
        The best quenched chain (the lower-energy stage), traces, timings.

    Raises
    ------
    EnergyBookkeepingError, ChainGeometryError
        If the verification fails (never expected: a bug).
    CheckpointError
        If ``resume`` finds a corrupt checkpoint or one of another run.
    RunStopped
        If ``stop_after`` chunks were run before the end.
    """
    settings.validate()
    if settings.schedule.kind == "tempering":
        raise ValueError("a tempering schedule runs with engine.tempering.run_tempering")
    if settings.schedule.kind == "langevin":
        raise ValueError("a langevin schedule runs with engine.langevin.run_langevin_replica")
    steps = plan_steps(settings)
    keys = trace_keys(settings)
    total = sum(s.moves for s in steps)
    n = len(coords)
    ck = Checkpointer(checkpoint, checkpoint_every, checkpoint_seconds)
    expected = run_meta("anneal", settings, seed, replica, coords)
    traces: dict[str, list] = {k: [] for k in keys}
    best_pos = None
    best_energy = np.inf
    stage_eps: dict[str, float] = {}
    best_stage = None
    step0 = 0
    done = 0
    hit = (None, None)
    clock = Clock()
    resumed = None
    e_ref = 0.0  # energy per bead at the current stage's setup (``tight`` plan)
    cap: float | None = None  # curvature limit of the ratchet (``tight`` plan)
    if resume and ck.path is not None and ck.path.exists():
        arrays, meta = load_checkpoint(ck.path)
        check_resumable(meta, expected, ck.path)
        params = MoveParams(**meta["params"])
        state = restore_state(arrays, settings, params)
        step0 = int(meta["step"])
        done = int(meta["done"])
        traces = {k: list(arrays[f"trace_{k}"]) for k in keys}
        if "best_pos" in arrays:
            best_pos = arrays["best_pos"]
            best_energy = float(arrays["best_energy"])
        stage_eps = dict(meta["stage_epsilon"])
        best_stage = meta["best_stage"]
        hit = (meta["seconds_to_target"], meta["cpu_seconds_to_target"])
        clock = Clock(meta["wall"], meta["cpu"])
        e_ref = float(meta["e_ref"])
        cap = meta["cap"]
        if cap is not None:
            state.set_max_turn(cap)
        resumed = step0
    else:
        state = ChainState(coords, settings.params, seed=seed, ensemble=settings.ensemble)
    target = settings.target_epsilon
    lowest = min(traces["epsilon"]) if traces["epsilon"] else math.inf

    def save(step: int) -> Path:
        arrays = state_arrays(state)
        arrays.update({f"trace_{k}": np.asarray(v) for k, v in traces.items()})
        if best_pos is not None:
            arrays["best_pos"] = best_pos
            arrays["best_energy"] = np.float64(best_energy)
        meta = dict(expected, step=step, n_steps=len(steps), done=done, wall=clock.wall(),
                    cpu=clock.cpu(), stage_epsilon=stage_eps, best_stage=best_stage,
                    seconds_to_target=hit[0], cpu_seconds_to_target=hit[1],
                    params=state.params.as_dict(), e_ref=e_ref, cap=cap)
        p = save_checkpoint(ck.path, arrays, meta)
        ck.written()
        return p

    hopping = settings.schedule.hops > 0 and polishable(settings)
    if hopping and resumed is None:
        # with basin hops the starting chain is the first candidate: a run that continues a
        # search (problems.base.solve) never ends above the chain it was given
        best_pos, best_energy = _candidate(state, settings, True)
        best_stage = "start"
    ran = 0
    for i in range(step0, len(steps)):
        s = steps[i]
        if s.setup is not None:
            energy, power, k = s.setup
            state.reconfigure(stage_params(settings.params, energy, power, state.pos,
                                           state.closed), seed=seed + TIGHT_SEED_STRIDE * k)
            e_ref = state.energy / n
        if s.restore_best and best_pos is not None:
            state.restore(best_pos)
        if s.ratchet and cap is None:
            cap = float(np.max(state.turning_angles()))
            state.set_max_turn(cap)
        temperature = s.temperature if s.t_factor is None else e_ref * s.temperature * s.t_factor
        peak = abs(state.energy)
        state.run(s.moves, temperature)
        resync(state, max(peak, abs(state.energy)))
        done += s.moves
        if s.ratchet:
            th = float(np.max(state.turning_angles()))
            if th < cap:
                cap = th
                state.set_max_turn(cap)
        eps = state.epsilon
        lowest = min(lowest, eps)
        traces["moves"].append(done)
        traces["temperature"].append(temperature)
        traces["epsilon"].append(eps)
        traces["seconds"].append(clock.wall())
        if "excess_length" in traces:
            traces["excess_length"].append(state.excess_length)
        if "theta_max" in traces:
            traces["theta_max"].append(float(np.max(state.turning_angles())))
        if target is not None and hit[0] is None and eps <= target:
            hit = (clock.wall(), clock.cpu())
        if s.last:
            stage_eps[s.stage] = eps
            pos_e = _candidate(state, settings, hopping)
            if pos_e[1] < best_energy:
                best_pos, best_energy, best_stage = pos_e[0], pos_e[1], s.stage
        if progress is not None:
            progress({"replica": replica, "done": done, "total": total, "epsilon": eps,
                      "best": lowest})
        ran += 1
        if i + 1 < len(steps):
            if stop_after is not None and ran >= stop_after:
                raise RunStopped(save(i + 1), i + 1, len(steps))
            if ck.due():
                save(i + 1)
    check_chain(state)
    if ck.path is not None:
        save(len(steps))
    best = state
    # the best candidate, unless it is the final state itself; with hops a candidate is the
    # polished chain, which differs from the final state even when the last stage won
    if best_pos is not None and (best_stage != steps[-1].stage
                                 or not np.array_equal(best_pos, state.pos)):
        best = ChainState(best_pos, state.params, seed=0, ensemble=settings.ensemble)
    return make_result(replica, seed, settings, best, state.acceptance(), traces, clock, hit,
                       stage_epsilon=stage_eps, best_stage=best_stage,
                       resumed_from_step=resumed)


def replica_seeds(seed: int, replicas: int, first: int = 0) -> list[int]:
    """Independent per-replica seeds derived from one user seed (numpy SeedSequence): those
    of replicas ``first`` … ``replicas − 1``. Replica r's is the r-th child's of
    ``SeedSequence(seed).spawn`` (spawn key (r,)), computed without spawning the r before it,
    so a replica numbered 1,500,000 (a sweep's continuation leg) costs as little as replica 0.
    """
    return [int(np.random.SeedSequence(int(seed), spawn_key=(r,))
                .generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
            for r in range(int(first), int(replicas))]


def default_workers(replicas: int) -> int:
    """Worker processes for ``replicas`` replicas: one each, at most the CPU count."""
    return max(1, min(replicas, os.cpu_count() or 1))
