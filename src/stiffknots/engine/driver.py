"""Annealing driver: one replica = embedding → annealing schedule → quench → verification.

The driver composes the kernel (:mod:`stiffknots.engine.kernel`) with a schedule; it knows
arrays and numbers only. Replicas run in separate processes (one per core) and each result
carries its seed, its parameters and the package version, so that it can be reproduced.
"""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from stiffknots._version import __version__
from stiffknots.engine.kernel import min_nonadjacent_segment_distance
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import ChainState, MoveParams


class TopologyChangedError(RuntimeError):
    """A run ended with a knot type different from the one it started with (never expected:
    the moves forbid strand passage by construction; this is a bug, never a data point)."""


class EnergyBookkeepingError(RuntimeError):
    """The incrementally tracked energy differs from the energy recomputed from scratch."""


@dataclass
class AnnealSettings:
    """Everything that defines a replica's run besides its starting chain and seed."""

    moves: int = 20_000_000
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
    """Outcome of one annealing replica (all fields plain data; picklable, JSON-able)."""

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

    def summary(self) -> dict:
        d = asdict(self)
        for key in ("coords", "trace_moves", "trace_temperature", "trace_epsilon",
                    "trace_seconds"):
            d.pop(key)
        return d


def run_replica(coords: np.ndarray, settings: AnnealSettings, seed: int,
                replica: int = 0) -> ReplicaResult:
    """Anneal one chain: ``settings.schedule`` over the moves, then a T = 0 quench.

    The energy is tracked incrementally by the kernel and recomputed from scratch at the end;
    a disagreement above 1e-9 (relative) raises :class:`EnergyBookkeepingError`.
    """
    settings.validate()
    state = ChainState(coords, settings.params, seed=seed, closed=settings.closed)
    n_quench = int(settings.moves * settings.quench_fraction)
    n_anneal = settings.moves - n_quench
    nch = settings.n_chunks
    per = max(1, n_anneal // nch)
    tm, tt, te, ts = [], [], [], []
    t0 = time.perf_counter()
    done = 0
    target = settings.target_epsilon
    t_hit = None
    for c in range(nch):
        temp = float(settings.schedule.temperature((c + 0.5) / nch))
        state.run(per, temp)
        done += per
        now = time.perf_counter() - t0
        tm.append(done)
        tt.append(temp)
        te.append(state.epsilon)
        ts.append(now)
        if target is not None and t_hit is None and state.epsilon <= target:
            t_hit = now
    # quench in a few chunks (T = 0: only moves that do not raise the energy)
    qch = 10 if n_quench >= 10 else max(1, n_quench)
    for _ in range(qch):
        if n_quench == 0:
            break
        state.run(n_quench // qch, 0.0)
        done += n_quench // qch
        now = time.perf_counter() - t0
        tm.append(done)
        tt.append(0.0)
        te.append(state.epsilon)
        ts.append(now)
        if target is not None and t_hit is None and state.epsilon <= target:
            t_hit = now
    wall = time.perf_counter() - t0
    e_rec = state.recomputed_energy()
    if abs(e_rec - state.energy) > 1e-9 * max(1.0, abs(e_rec)):
        raise EnergyBookkeepingError(
            f"incremental energy {state.energy!r} differs from recomputed {e_rec!r}"
        )
    pos = state.pos
    if settings.closed:
        bonds = np.linalg.norm(np.roll(pos, -1, axis=0) - pos, axis=1)
    else:
        bonds = np.linalg.norm(np.diff(pos, axis=0), axis=1)
    return ReplicaResult(
        replica=replica,
        seed=seed,
        # ε = E·N/C (closed, §VII) or ε_e = E·L_e/C (open, §VIII)
        epsilon=e_rec * (state.n_beads if settings.closed else state.excess_length),
        energy=e_rec,
        energy_recomputed=e_rec,
        coords=pos.copy(),
        acceptance=state.acceptance(),
        trace_moves=np.asarray(tm, dtype=np.int64),
        trace_temperature=np.asarray(tt),
        trace_epsilon=np.asarray(te),
        trace_seconds=np.asarray(ts),
        wall_time=wall,
        max_bond_error=float(np.max(np.abs(bonds - 1.0))),
        exclusion_margin=-state.violation(),
        min_segment_distance=float(min_nonadjacent_segment_distance(pos, not settings.closed)),
        seconds_to_target=t_hit,
    )


def replica_seeds(seed: int, replicas: int) -> list[int]:
    """Independent per-replica seeds derived from one user seed (numpy SeedSequence)."""
    ss = np.random.SeedSequence(int(seed))
    return [int(s.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
            for s in ss.spawn(replicas)]


def default_workers(replicas: int) -> int:
    return max(1, min(replicas, os.cpu_count() or 1))
