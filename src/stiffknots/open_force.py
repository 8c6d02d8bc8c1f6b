"""Open knots at fixed force (paper §VIII): anneal E_d − F·Δz and measure the excess length.

The fixed-extension route (:mod:`stiffknots.open_knots`) fixes L_e and measures the tension
μ = E_d/L_e. Here the ends slide along the z axis under a constant pulling force F
(:mod:`stiffknots.engine.force_kernel`: slide and pivot end moves, interleaved with the
interior crankshafts), the energy is E = E_d − F·Δz, and L_e = (N − 1) − Δz is *measured*. At T → 0
the chain minimises ε_e C/L_e + F·L_e, i.e. it settles where the tension μ = E_d/L_e equals
the applied force (force balance, L_e = (ε_e C/F)^½): the result reports F, the measured L_e,
E_d, ε_e = E_d·L_e/C, μ = E_d/L_e and the ratio μ/F.

Each replica is verified at the end: bonds of unit length (1e-10), the end segments exactly on
the z axis, the exclusion rule, the incremental energies E_d and E_d − F·Δz against a
recomputation (1e-9), and the knot type of the closure along z. Units: b = 1, C = 1.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields

import numpy as np

from stiffknots.engine.driver import (
    TRACE_KEYS,
    AnnealSettings,
    Clock,
    EnergyBookkeepingError,
    ReplicaResult,
    TopologyChangedError,
    check_bookkeeping,
    default_workers,
    make_result,
    plan_steps,
    replica_seeds,
)
from stiffknots.engine.force_state import ForceChainState
from stiffknots.engine.pool import run_jobs
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import MoveParams, check_open_clamping
from stiffknots.open_knots import (
    DEFAULT_OPEN_MOVES,
    OpenResult,
    excess_length_for_force,
    open_chain,
)

DEFAULT_END_FRACTION = 0.1
DEFAULT_SLIDE_FRACTION = 0.8
DEFAULT_END_M_MAX = 30


def default_force_schedule() -> Schedule:
    """Geometric cooling 1e-2 → 1e-6 without the relaxation stage (measured, open 3_1, tube
    w = 0.1, F = 0.013, 10 M moves, seeds 1–2: ε_e = 21.1–21.3 — the loop — against 32–36 with
    the default power-law schedule and its relaxation stage, whose hot phase is too short for
    L_e and the loop to form). L_e relaxes slowly (≈ 30 M moves at T = 1e-3 to grow the loop
    from L_e = 35.5 to the balance point ≈ 40): use tens of millions of moves."""
    return Schedule(kind="geometric", t_start=1e-2, t_end=1e-6, relax_fraction=0.0)


class ChainGeometryError(RuntimeError):
    """A run ended with a broken chain (bond length, end clamping or exclusion violated):
    never expected, the moves preserve all three by construction; a bug, never a data point."""


@dataclass
class ForceReplicaResult(ReplicaResult):
    """A replica at fixed force: the :class:`ReplicaResult` fields plus the force-ensemble
    quantities of its best chain (``epsilon`` is ε_e = E_d·L_e/C)."""

    force: float = 0.0
    excess_length: float = 0.0
    extension: float = 0.0
    total_energy: float = 0.0
    trace_excess_length: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def summary(self) -> dict:
        d = super().summary()
        d.pop("trace_excess_length")
        return d


@dataclass
class ForceResult(OpenResult):
    """Replicas of one open knot at fixed force F, best (lowest E_d − F·Δz) first.

    ``excess_length``, ``energy``, ``eps_e`` and ``tension`` (μ = E_d/L_e) are those of the best
    replica; ``force`` is the applied F.
    """

    force: float = 0.0

    @property
    def force_balance(self) -> float:
        """μ/F: 1 at equilibrium at T → 0 (E_d = ε_e C/L_e, −dE_d/dL_e = E_d/L_e = F)."""
        return self.tension / self.force

    def to_dict(self) -> dict:
        d = super().to_dict()
        ok = bool(self.replicas)
        return d | {
            "ensemble": "force",
            "force": self.force,
            "force_balance": self.force_balance if ok else None,
            "extension": self.best.extension if ok else None,
            "total_energy": self.best.total_energy if ok else None,
        }


def pad_open_chain(coords: np.ndarray, n_beads: int) -> np.ndarray:
    """Lengthen both straight ends of an open chain along the z axis to ``n_beads`` beads.

    The added beads continue the clamped end segments (unit bonds on the axis), so the closure
    along z, the excess length and the energy are unchanged; bead 0 is put at z = 0.
    """
    x = np.asarray(coords, dtype=float)
    extra = int(n_beads) - len(x)
    if extra < 0:
        raise ValueError(f"the starting chain has {len(x)} beads, more than n_beads={n_beads}; "
                         "raise n_beads or lower the starting excess length")
    lo, hi = extra // 2, extra - extra // 2
    below = np.zeros((lo, 3))
    below[:, 2] = x[0, 2] - np.arange(lo, 0, -1)
    above = np.zeros((hi, 3))
    above[:, 2] = x[-1, 2] + np.arange(1, hi + 1)
    out = np.vstack([below, x, above])
    out[:, 2] -= out[0, 2]
    out[[0, 1, -2, -1], :2] = 0.0
    return out


def start_chain(knot: str, force: float, n_beads: int | None = None,
                excess_length: int | None = None, seed: int = 0) -> tuple[np.ndarray, int]:
    """The starting chain (an open embedding padded to ``n_beads``) and its excess length.

    Without ``excess_length`` the embedding starts near the L_e the force selects in the thin
    limit, (ε_e C/F)^½ with ε_e the knot's lower bound 2π²n₁² (§VIII); if the embedding needs
    more, larger excess lengths are tried. Without ``n_beads`` each straight end is lengthened
    by ⌈L_e/4⌉ beads, room for the knot to take up more length; longer tails only slow the
    annealing down (the crankshafts spend their moves on straight tails).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import EmbeddingError
    from stiffknots.theory.bounds import open_bounds

    def padded(le: int) -> tuple[np.ndarray, int]:
        x = open_chain(k.name, le, seed=seed)
        n = len(x) + 2 * math.ceil(le / 4) if n_beads is None else n_beads
        return pad_open_chain(x, n), le

    k = get_knot(knot)
    if excess_length is not None:
        return padded(int(excess_length))
    eps = open_bounds(k.bridge_number, k.braid_index).lower or 2 * math.pi**2
    le = max(8, int(round(excess_length_for_force(eps, force))))
    err = None
    for _ in range(6):
        try:
            return padded(le)
        except EmbeddingError as exc:
            err = exc
            le += 5
    raise err


def verify_force_state(state: ForceChainState, where: str = "final") -> None:
    """Raise if the chain is broken or the incremental energies drift (see module docstring)."""
    check_bookkeeping(state)
    rec = state.recomputed_total()
    if abs(rec - state.total_energy) > 1e-9 * max(1.0, abs(rec)):
        raise EnergyBookkeepingError(
            f"{where}: incremental E_d − F·Δz {state.total_energy!r} differs from recomputed "
            f"{rec!r}")
    bonds = np.linalg.norm(np.diff(state.pos, axis=0), axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-10:
        raise ChainGeometryError(f"{where}: bond length off by {np.max(np.abs(bonds - 1)):.3g}")
    try:
        check_open_clamping(state.pos, tol=0.0)
    except ValueError as exc:
        raise ChainGeometryError(f"{where}: {exc}") from None
    v = state.violation()
    if v > 1e-12:
        raise ChainGeometryError(
            f"{where}: the {state.params.exclusion} exclusion rule is violated by {v:.3g}")


def run_force_replica(coords: np.ndarray, settings: AnnealSettings, force: float, seed: int,
                      replica: int = 0, *, end_fraction: float = DEFAULT_END_FRACTION,
                      slide_fraction: float = DEFAULT_SLIDE_FRACTION,
                      end_m_max: int = DEFAULT_END_M_MAX) -> ForceReplicaResult:
    """Anneal one replica at fixed force with the chunk plan of
    :func:`~stiffknots.engine.driver.plan_steps` (relaxation and annealing stages, each ending
    with a quench); the best quenched chain (lowest E_d − F·Δz) is returned, verified."""
    settings.validate()
    if settings.closed:
        raise ValueError("the fixed-force ensemble is for open chains (settings.closed=False)")
    steps = plan_steps(settings)
    kw = {"force": force, "end_fraction": end_fraction, "slide_fraction": slide_fraction,
          "end_m_max": end_m_max}
    state = ForceChainState(coords, settings.params, seed=seed, **kw)
    traces: dict[str, list] = {k: [] for k in TRACE_KEYS}
    trace_le: list[float] = []
    clock = Clock()
    best_pos, best_total, best_stage = None, np.inf, None
    stage_eps: dict[str, float] = {}
    done = 0
    for s in steps:
        state.run(s.moves, s.temperature)
        done += s.moves
        traces["moves"].append(done)
        traces["temperature"].append(s.temperature)
        traces["epsilon"].append(state.epsilon)
        traces["seconds"].append(clock.wall())
        trace_le.append(state.excess_length)
        if s.last:
            stage_eps[s.stage] = state.epsilon
            if state.total_energy < best_total:
                best_pos, best_total, best_stage = state.pos.copy(), state.total_energy, s.stage
    verify_force_state(state, "final chain")
    best = state
    if best_pos is not None and best_stage != steps[-1].stage:
        best = ForceChainState(best_pos, settings.params, seed=0, **kw)
        verify_force_state(best, "best chain")
    base = make_result(replica, seed, settings, best, state.acceptance(), traces, clock,
                       (None, None), stage_epsilon=stage_eps, best_stage=best_stage)
    return ForceReplicaResult(
        **{f.name: getattr(base, f.name) for f in fields(ReplicaResult)},
        force=float(force), excess_length=best.excess_length, extension=best.extension,
        total_energy=best.recomputed_total(), trace_excess_length=np.asarray(trace_le))


def _force_job(coords, settings, force, seed, replica, knot_name, moves_kw):
    """Worker: one replica at fixed force, and the knot type of its closure along z."""
    from stiffknots.knots.identify import close_open_chain_along_z, verify_knot

    res = run_force_replica(coords, settings, force, seed, replica, **moves_kw)
    ok, found = verify_knot(close_open_chain_along_z(res.coords), knot_name, closed=True)
    res.knot = found
    res.knot_verified = bool(ok)
    return res


def anneal_open_force(
    knot: str,
    force: float,
    n_beads: int | None = None,
    moves: int = DEFAULT_OPEN_MOVES,
    replicas: int = 2,
    seed: int = 0,
    *,
    excess_length: int | None = None,
    params: MoveParams | None = None,
    schedule: Schedule | None = None,
    end_fraction: float = DEFAULT_END_FRACTION,
    slide_fraction: float = DEFAULT_SLIDE_FRACTION,
    end_m_max: int = DEFAULT_END_M_MAX,
    workers: int | None = None,
    quench_fraction: float = 0.1,
    on_replica_done: Callable[[ReplicaResult], None] | None = None,
) -> ForceResult:
    """Anneal an open knot at fixed end force F (energy E_d − F·Δz, paper §VIII); measure L_e.

    Parameters
    ----------
    knot : knot name ('3_1', '4_1', …).
    force : F > 0 in C/b².
    n_beads : beads of the chain: the open embedding is lengthened along the axis to this many
        (default: by ⌈L_e/4⌉ beads at each end, see :func:`start_chain`).
    moves, replicas, seed, params, workers, quench_fraction, on_replica_done :
        as for :func:`stiffknots.open_knots.anneal_open`.
    schedule : default :func:`default_force_schedule` (geometric, no relaxation stage).
    excess_length : excess length of the starting embedding (default: near (ε_e C/F)^½ with
        the thin-limit ε_e; see :func:`start_chain`). The annealing moves it.
    end_fraction : fraction of the moves that move an end (slide and pivot moves).
    slide_fraction : fraction of the end moves that are slides (the others are pivots).
    end_m_max : largest number of beads rotated by a pivot move.

    Returns
    -------
    ForceResult — replicas sorted by E_d − F·Δz; ``excess_length`` (measured), ``eps_e``,
    ``tension`` (μ = E_d/L_e), ``force``, ``force_balance`` (μ/F), ``shape()``.

    Raises
    ------
    TopologyChangedError, EnergyBookkeepingError, ChainGeometryError
        If a replica's knot type, energy bookkeeping or chain geometry is wrong (never
        expected: each would be a bug).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import open_bounds

    k = get_knot(knot)
    if not (math.isfinite(force) and force > 0):
        raise ValueError(f"the force must be > 0 (in units of C/b²), got {force}")
    if replicas < 1:
        raise ValueError(f"replicas must be ≥ 1, got {replicas}")
    if not 0 < end_fraction <= 1:
        raise ValueError(f"end_fraction must be in (0, 1], got {end_fraction}")
    if not 0 < slide_fraction <= 1:
        raise ValueError(f"slide_fraction must be in (0, 1] (slides relax L_e), got "
                         f"{slide_fraction}")
    coords, le0 = start_chain(k.name, force, n_beads, excess_length, seed=seed)
    settings = AnnealSettings(moves=int(moves), schedule=schedule or default_force_schedule(),
                              params=params or MoveParams(), quench_fraction=quench_fraction,
                              closed=False)
    settings.validate()
    settings.params.validate(len(coords))
    seeds = replica_seeds(seed, replicas)
    nw = workers or default_workers(replicas)
    t0 = time.perf_counter()
    moves_kw = {"end_fraction": end_fraction, "slide_fraction": slide_fraction,
                "end_m_max": end_m_max}
    results, interrupted = run_jobs(
        _force_job, [(coords, settings, float(force), s, r, k.name, moves_kw)
                     for r, s in enumerate(seeds)], nw, on_replica_done)
    results.sort(key=lambda r: r.total_energy)
    bad = [r for r in results if not r.knot_verified]
    if bad:
        raise TopologyChangedError(
            f"{len(bad)} open replica(s) of {k.name} at force {force} closed along z as "
            f"{', '.join(str(r.knot) for r in bad)}; this is a bug, please report it "
            f"with seed {seed}")
    b = open_bounds(k.bridge_number, k.braid_index)
    return ForceResult(
        knot=k.name, excess_length=results[0].excess_length if results else float("nan"),
        beads=len(coords), seed=seed,
        settings=settings.as_dict() | {"ensemble": "force", "force": float(force),
                                       "start_excess_length": le0} | moves_kw,
        replicas=results, wall_time=time.perf_counter() - t0, interrupted=interrupted,
        bounds={"eps_e_lower": b.lower, "eps_e_upper": b.upper}, force=float(force))
