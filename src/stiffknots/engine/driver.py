"""Annealing driver: one replica = embedding → schedule → quench → verification (paper §VII).

The driver composes the kernel (:mod:`stiffknots.engine.kernel`) with a schedule; it knows
arrays and numbers only. Replicas run in separate processes (one per core) and each result
carries its seed, its parameters and the package version, so that it can be reproduced.

A run is a fixed *plan*: a list of chunks (moves, temperature), made from the settings alone
(:func:`plan_steps`). With the default schedule it has two stages, each ending with a T = 0
quench (see :mod:`stiffknots.engine.schedules`): a low-temperature relaxation of the starting
chain, then the paper's power-law annealing from a hot start; the result is the quenched chain
of lower energy. ``Schedule(kind="tempering")`` runs replica exchange instead
(:mod:`stiffknots.engine.tempering`).

Checkpoints
-----------
A long run can write its whole state to one ``.npz`` file every K chunks and/or every S
seconds (positions, generator state, counters, incremental energy, chunk index, traces, best
chain so far, settings, seed, version) and be resumed from it. The plan depends on the settings
only and the kernel's result does not depend on the order of its cell lists, so a resumed run
ends with *exactly* the chain and energy of an uninterrupted run with the same seed (only the
wall-clock traces differ). A checkpoint is only resumed by a run with the same settings, seed,
replica index, starting chain and package version; anything else is refused.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from stiffknots._version import __version__
from stiffknots.engine.kernel import min_nonadjacent_segment_distance
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import ChainState, MoveParams

CHECKPOINT_FORMAT = 1
QUENCH_CHUNKS = 10


class TopologyChangedError(RuntimeError):
    """A run ended with a knot type different from the one it started with (never expected:
    the moves forbid strand passage by construction; this is a bug, never a data point)."""


class EnergyBookkeepingError(RuntimeError):
    """The incrementally tracked energy differs from the energy recomputed from scratch."""


class RunStopped(RuntimeError):  # noqa: N818 (not an error: a requested stop)
    """A run stopped on request (``stop_after`` chunks) after writing its checkpoint.

    Attributes
    ----------
    checkpoint : path of the checkpoint to resume from.
    step, n_steps : chunks done so far and chunks in the whole plan.
    """

    def __init__(self, checkpoint: Path, step: int, n_steps: int):
        super().__init__(f"stopped after chunk {step}/{n_steps}; resume from {checkpoint}")
        self.checkpoint = checkpoint
        self.step = step
        self.n_steps = n_steps


@dataclass
class AnnealSettings:
    """Everything that defines a replica's run besides its starting chain and seed.

    The defaults (``moves``, :class:`Schedule`, :class:`MoveParams`) are the measured winners of
    bench/RESULTS.md: 30 M moves, of which the first third relaxes the starting chain
    (t = 5e-5 → 1e-7) and the rest anneals from t = 3e-2 with the paper's power law (§VII).
    """

    moves: int = 30_000_000
    schedule: Schedule = field(default_factory=Schedule)
    params: MoveParams = field(default_factory=MoveParams)
    quench_fraction: float = 0.1
    n_chunks: int = 200
    target_epsilon: float | None = None
    closed: bool = True  # False: an open chain clamped on the z axis (paper §VIII)

    def validate(self) -> None:
        if self.moves < 1000:
            raise ValueError(f"moves must be ≥ 1000, got {self.moves}")
        if not 0 <= self.quench_fraction <= 1:
            raise ValueError(f"quench_fraction must be in [0, 1], got {self.quench_fraction}")
        if self.n_chunks < 1:
            raise ValueError(f"n_chunks must be ≥ 1, got {self.n_chunks}")
        self.schedule.validate()

    def as_dict(self) -> dict:
        return {
            "moves": self.moves,
            "schedule": self.schedule.as_dict(),
            "params": self.params.as_dict(),
            "quench_fraction": self.quench_fraction,
            "n_chunks": self.n_chunks,
            "closed": self.closed,
        }


@dataclass
class ReplicaResult:
    """Outcome of one annealing replica (all fields plain data; picklable, JSON-able).

    ``coords``/``epsilon`` are the best quenched chain of the run (the lower of the stages);
    ``stage_epsilon`` gives each stage's quenched ε and ``best_stage`` the winner.
    ``seconds_to_target``/``cpu_seconds_to_target``: wall-clock and CPU seconds until ε first
    fell to ``target_epsilon`` (None: never). ``tempering``: ladder and swap statistics of a
    replica-exchange run (None for annealing).
    """

    replica: int
    seed: int
    epsilon: float
    energy: float
    energy_recomputed: float
    coords: np.ndarray
    acceptance: dict
    trace_moves: np.ndarray
    trace_temperature: np.ndarray
    trace_epsilon: np.ndarray
    trace_seconds: np.ndarray
    wall_time: float
    max_bond_error: float
    exclusion_margin: float
    min_segment_distance: float
    seconds_to_target: float | None = None
    knot: str | None = None
    knot_verified: bool | None = None
    version: str = __version__
    cpu_seconds_to_target: float | None = None
    cpu_time: float | None = None
    stage_epsilon: dict = field(default_factory=dict)
    best_stage: str | None = None
    tempering: dict | None = None
    resumed_from_step: int | None = None
    start: str | None = None  # starting embedding ('braid', 'cage', …), set by the caller

    def summary(self) -> dict:
        d = asdict(self)
        for key in ("coords", "trace_moves", "trace_temperature", "trace_epsilon",
                    "trace_seconds"):
            d.pop(key)
        return d


@dataclass(frozen=True)
class Step:
    """One chunk of a run's plan: ``moves`` attempted at ``temperature`` (0: quench).

    ``last`` marks the last chunk of a stage: the chain after it is a candidate result.
    """

    moves: int
    temperature: float
    stage: str
    last: bool = False


def _split(total: int, parts: int) -> list[int]:
    """``total`` moves in ``parts`` chunks whose sizes differ by at most one."""
    parts = max(1, parts)
    q, r = divmod(total, parts)
    return [q + (1 if c < r else 0) for c in range(parts)]


def plan_steps(settings: AnnealSettings) -> list[Step]:
    """The chunks of an annealing run (relaxation stage if any, annealing stage, quenches).

    ``settings.n_chunks`` annealing chunks and 10 quench chunks in all, shared between the
    stages in proportion to their moves; the moves add up to ``settings.moves`` exactly.
    """
    sch = settings.schedule
    total = int(settings.moves)
    stages = sch.stages
    if stages == ("tempering",):
        raise ValueError("a tempering schedule has no annealing plan (see engine.tempering)")
    if len(stages) == 2:
        fr = {"relax": sch.relax_fraction, "anneal": 1.0 - sch.relax_fraction}
    else:
        fr = {"anneal": 1.0}
    moves = {s: int(total * fr[s]) for s in stages}
    moves["anneal"] = total - sum(v for s, v in moves.items() if s != "anneal")
    nch = settings.n_chunks
    chunks = {"anneal": nch}
    quench = {"anneal": QUENCH_CHUNKS}
    if len(stages) == 2:
        chunks["relax"] = min(max(1, round(nch * fr["relax"])), max(1, nch - 1))
        chunks["anneal"] = max(1, nch - chunks["relax"])
        quench["relax"] = min(max(1, round(QUENCH_CHUNKS * fr["relax"])), QUENCH_CHUNKS - 1)
        quench["anneal"] = QUENCH_CHUNKS - quench["relax"]
    steps: list[Step] = []
    for s in stages:
        nq = int(moves[s] * settings.quench_fraction)
        na = moves[s] - nq
        k = chunks[s]
        sizes = _split(na, k)
        for c, m in enumerate(sizes):
            x = (c + 0.5) / k
            t = sch.relax_temperature(x) if s == "relax" else sch.temperature(x)
            steps.append(Step(m, float(t), s))
        if nq > 0:
            for m in _split(nq, min(quench[s], nq)):
                steps.append(Step(m, 0.0, s))
        steps[-1] = Step(steps[-1].moves, steps[-1].temperature, s, last=True)
    return steps


# ------------------------------------------------------------------------------------------
# checkpoints
# ------------------------------------------------------------------------------------------


def start_digest(coords: np.ndarray) -> str:
    """SHA-256 of the starting chain (float64, C order): ties a checkpoint to its start."""
    return hashlib.sha256(np.ascontiguousarray(coords, dtype=np.float64).tobytes()).hexdigest()


def save_checkpoint(path: str | Path, arrays: dict[str, np.ndarray], meta: dict) -> Path:
    """Write ``arrays`` and the JSON ``meta`` to ``path`` (``.npz``) atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    payload = dict(arrays)
    payload["meta"] = np.array(json.dumps(meta))
    with open(tmp, "wb") as f:
        np.savez(f, **payload)
    os.replace(tmp, path)
    return path


def load_checkpoint(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """Read a checkpoint written by :func:`save_checkpoint`: (arrays, meta)."""
    with np.load(Path(path), allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if k != "meta"}
        meta = json.loads(str(z["meta"]))
    if meta.get("format") != CHECKPOINT_FORMAT:
        raise ValueError(f"{path}: not a stiffknots checkpoint of format {CHECKPOINT_FORMAT}")
    return arrays, meta


def run_meta(kind: str, settings: AnnealSettings, seed: int, replica: int,
             coords: np.ndarray) -> dict:
    """What identifies a run: a checkpoint is resumed only if all of it matches."""
    return {
        "format": CHECKPOINT_FORMAT,
        "kind": kind,
        "version": __version__,
        "seed": int(seed),
        "replica": int(replica),
        "settings": json.loads(json.dumps(settings.as_dict())),
        "start": start_digest(coords),
    }


def check_resumable(meta: dict, expected: dict, path: Path) -> None:
    """Raise ValueError naming the first field in which a checkpoint differs from the run."""
    for key in ("kind", "version", "seed", "replica", "start", "settings"):
        if meta.get(key) != expected[key]:
            what = "starting chain" if key == "start" else key
            raise ValueError(
                f"checkpoint {path} was written by a different run ({what} differs: "
                f"{meta.get(key)!r} ≠ {expected[key]!r}); delete it or drop resume"
            )


def restore_state(pos: np.ndarray, rng: np.ndarray, counters: np.ndarray, energy: float,
                  settings: AnnealSettings) -> ChainState:
    """A ChainState exactly as it was checkpointed (generator, counters, incremental energy).

    The cell list is rebuilt from the positions; the kernel's decisions do not depend on the
    order of its lists, so the continuation is bit-for-bit the uninterrupted one.
    """
    st = ChainState(pos, settings.params, seed=0, closed=settings.closed)
    st.rng[:] = np.asarray(rng, dtype=np.uint64)
    st.counters[:] = np.asarray(counters, dtype=np.int64)
    st.energy = float(energy)
    return st


class Checkpointer:
    """When to write a checkpoint: every ``every`` chunks and/or every ``seconds`` seconds."""

    def __init__(self, path: str | Path | None, every: int | None = None,
                 seconds: float | None = None):
        self.path = Path(path) if path is not None else None
        if every is not None and every < 1:
            raise ValueError(f"checkpoint_every must be ≥ 1 chunk, got {every}")
        if seconds is not None and seconds <= 0:
            raise ValueError(f"checkpoint_seconds must be > 0, got {seconds}")
        if self.path is not None and every is None and seconds is None:
            every = 10
        self.every = every
        self.seconds = seconds
        self._since = 0
        self._last = time.perf_counter()

    def due(self) -> bool:
        """Count one chunk; True when a checkpoint should be written now."""
        if self.path is None:
            return False
        self._since += 1
        if self.every is not None and self._since >= self.every:
            return True
        return self.seconds is not None and time.perf_counter() - self._last >= self.seconds

    def written(self) -> None:
        self._since = 0
        self._last = time.perf_counter()


class Clock:
    """Wall-clock and CPU seconds of a run, continued across a resume."""

    def __init__(self, wall: float = 0.0, cpu: float = 0.0):
        self.w0 = time.perf_counter() - wall
        self.c0 = time.process_time() - cpu

    def wall(self) -> float:
        return time.perf_counter() - self.w0

    def cpu(self) -> float:
        return time.process_time() - self.c0


def _bonds(pos: np.ndarray, closed: bool) -> np.ndarray:
    if closed:
        return np.linalg.norm(np.roll(pos, -1, axis=0) - pos, axis=1)
    return np.linalg.norm(np.diff(pos, axis=0), axis=1)


def check_bookkeeping(state: ChainState) -> float:
    """The recomputed energy; EnergyBookkeepingError if the incremental one differs."""
    e_rec = state.recomputed_energy()
    if abs(e_rec - state.energy) > 1e-9 * max(1.0, abs(e_rec)):
        raise EnergyBookkeepingError(
            f"incremental energy {state.energy!r} differs from recomputed {e_rec!r}"
        )
    return e_rec


def make_result(replica: int, seed: int, settings: AnnealSettings, best: ChainState,
                acceptance: dict, traces: dict, clock: Clock, hit: tuple, **extra
                ) -> ReplicaResult:
    """Verify ``best`` (bookkeeping, bonds, exclusion) and pack the result."""
    e_rec = check_bookkeeping(best)
    pos = best.pos
    return ReplicaResult(
        replica=replica,
        seed=seed,
        # ε = E·N/C (closed, §VII) or ε_e = E·L_e/C (open, §VIII)
        epsilon=e_rec * (best.n_beads if settings.closed else best.excess_length),
        energy=e_rec,
        energy_recomputed=e_rec,
        coords=pos.copy(),
        acceptance=acceptance,
        trace_moves=np.asarray(traces["moves"], dtype=np.int64),
        trace_temperature=np.asarray(traces["temperature"], dtype=float),
        trace_epsilon=np.asarray(traces["epsilon"], dtype=float),
        trace_seconds=np.asarray(traces["seconds"], dtype=float),
        wall_time=clock.wall(),
        cpu_time=clock.cpu(),
        max_bond_error=float(np.max(np.abs(_bonds(pos, settings.closed) - 1.0))),
        exclusion_margin=-best.violation(),
        min_segment_distance=float(min_nonadjacent_segment_distance(pos, not settings.closed)),
        seconds_to_target=hit[0],
        cpu_seconds_to_target=hit[1],
        **extra,
    )


TRACE_KEYS = ("moves", "temperature", "epsilon", "seconds")


def run_replica(coords: np.ndarray, settings: AnnealSettings, seed: int, replica: int = 0, *,
                checkpoint: str | Path | None = None, checkpoint_every: int | None = None,
                checkpoint_seconds: float | None = None, resume: bool = False,
                stop_after: int | None = None) -> ReplicaResult:
    """Run one replica: the plan of :func:`plan_steps` (or replica exchange), verified.

    Parameters
    ----------
    coords : (N, 3) starting chain (unit bonds, exclusion respected).
    settings : the run's settings; ``Schedule(kind="tempering")`` dispatches to
        :func:`stiffknots.engine.tempering.run_tempering`.
    seed : seed of the kernel's generator.
    replica : index recorded in the result.
    checkpoint : path of a ``.npz`` checkpoint file, written every ``checkpoint_every`` chunks
        and/or every ``checkpoint_seconds`` seconds (default every 10 chunks) and at the end.
    resume : continue from ``checkpoint`` if the file exists (it must come from the same
        settings, seed, replica, starting chain and version); otherwise start afresh.
    stop_after : stop after this many chunks in this call, write the checkpoint and raise
        :class:`RunStopped` (for time-limited batch jobs, and for tests).

    Returns
    -------
    ReplicaResult
        The best quenched chain (the lower-energy stage), traces, timings.

    Raises
    ------
    EnergyBookkeepingError
        If the incremental energy differs from the recomputed one by more than 1e-9 (rel.).
    RunStopped
        If ``stop_after`` chunks were run before the end.
    """
    settings.validate()
    if settings.schedule.kind == "tempering":
        from stiffknots.engine.tempering import run_tempering

        return run_tempering(coords, settings, seed, replica, checkpoint=checkpoint,
                             checkpoint_every=checkpoint_every,
                             checkpoint_seconds=checkpoint_seconds, resume=resume,
                             stop_after=stop_after)
    steps = plan_steps(settings)
    ck = Checkpointer(checkpoint, checkpoint_every, checkpoint_seconds)
    expected = run_meta("anneal", settings, seed, replica, coords)
    traces: dict[str, list] = {k: [] for k in TRACE_KEYS}
    best_pos = None
    best_energy = np.inf
    stage_eps: dict[str, float] = {}
    best_stage = None
    step0 = 0
    done = 0
    hit = (None, None)
    clock = Clock()
    resumed = None
    if resume and ck.path is not None and ck.path.exists():
        arrays, meta = load_checkpoint(ck.path)
        check_resumable(meta, expected, ck.path)
        state = restore_state(arrays["pos"], arrays["rng"], arrays["counters"],
                              float(arrays["energy"]), settings)
        step0 = int(meta["step"])
        done = int(meta["done"])
        traces = {k: list(arrays[f"trace_{k}"]) for k in TRACE_KEYS}
        if "best_pos" in arrays:
            best_pos = arrays["best_pos"]
            best_energy = float(arrays["best_energy"])
        stage_eps = dict(meta["stage_epsilon"])
        best_stage = meta["best_stage"]
        hit = (meta["seconds_to_target"], meta["cpu_seconds_to_target"])
        clock = Clock(meta["wall"], meta["cpu"])
        resumed = step0
    else:
        state = ChainState(coords, settings.params, seed=seed, closed=settings.closed)
    target = settings.target_epsilon

    def save(step: int) -> Path:
        arrays = {"pos": state.pos, "rng": state.rng, "counters": state.counters,
                  "energy": np.float64(state.energy)}
        arrays.update({f"trace_{k}": np.asarray(v) for k, v in traces.items()})
        if best_pos is not None:
            arrays["best_pos"] = best_pos
            arrays["best_energy"] = np.float64(best_energy)
        meta = dict(expected, step=step, n_steps=len(steps), done=done, wall=clock.wall(),
                    cpu=clock.cpu(), stage_epsilon=stage_eps, best_stage=best_stage,
                    seconds_to_target=hit[0], cpu_seconds_to_target=hit[1])
        p = save_checkpoint(ck.path, arrays, meta)
        ck.written()
        return p

    ran = 0
    for i in range(step0, len(steps)):
        s = steps[i]
        state.run(s.moves, s.temperature)
        done += s.moves
        eps = state.epsilon
        traces["moves"].append(done)
        traces["temperature"].append(s.temperature)
        traces["epsilon"].append(eps)
        traces["seconds"].append(clock.wall())
        if target is not None and hit[0] is None and eps <= target:
            hit = (clock.wall(), clock.cpu())
        if s.last:
            stage_eps[s.stage] = eps
            if state.energy < best_energy:
                best_pos, best_energy, best_stage = state.pos.copy(), state.energy, s.stage
        ran += 1
        if i + 1 < len(steps):
            if stop_after is not None and ran >= stop_after:
                raise RunStopped(save(i + 1), i + 1, len(steps))
            if ck.due():
                save(i + 1)
    check_bookkeeping(state)
    if ck.path is not None:
        save(len(steps))
    best = state
    if best_pos is not None and best_stage != steps[-1].stage:
        best = ChainState(best_pos, settings.params, seed=0, closed=settings.closed)
        best.energy = best_energy
    return make_result(replica, seed, settings, best, state.acceptance(), traces, clock, hit,
                       stage_epsilon=stage_eps, best_stage=best_stage,
                       resumed_from_step=resumed)


def replica_seeds(seed: int, replicas: int) -> list[int]:
    """Independent per-replica seeds derived from one user seed (numpy SeedSequence)."""
    ss = np.random.SeedSequence(int(seed))
    return [int(s.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
            for s in ss.spawn(replicas)]


def default_workers(replicas: int) -> int:
    return max(1, min(replicas, os.cpu_count() or 1))
