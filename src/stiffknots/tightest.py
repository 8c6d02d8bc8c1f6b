"""The restricted-curvature problem (paper §IX.D): the shortest knot whose curvature ≤ 1/R.

Discrete model
--------------
A closed chain of N unit bonds (length L = N). A turning angle θ between consecutive bonds
is the bend of the circle of radius r = 1/(2 sin(θ/2)) through the three beads (the beads
lie on it at unit chords), so a chain whose largest turning angle is θ* has curvature at most
1/R with R = 1/(2 sin(θ*/2)), and its length in units of R is

    L/R = 2 N sin(θ*/2).

For fixed N the shortest knot in units of R is the chain with the smallest θ*, so the search
minimises the largest turning angle of a chain of the knot type at fixed N:

* a continuation in p of the energy Σ ((1 − cos θ_n)/s)^p: p = 1 is the paper's bending
  energy, annealed as in §VII (a smooth shape of the knot), then p = 2, 4, …, 64, each annealed
  from the previous shape with s = 1 − cos θ₉₀ (θ₉₀ the 90th percentile of the angles, so the
  energies stay of order one). As p grows the sum is dominated by the largest angles and its
  minimum approaches the minimax. A direct start at large p jams: the sharp joints of the
  embedding dominate and nothing else can move (measured: 5_2 stays near L/R ≈ 29–34
  instead of 19.7);
* a ratchet quench: the limit θ_max is lowered to the current largest angle after every
  chunk, and the kernel rejects any move that would bend a joint beyond it (unless it
  straightens it), so θ* never grows again;
* the exclusion (bead or tube) is kept, as a regulariser of the thin knot: it must be small
  compared with R (d/R ≈ 4π d/N for a doubly covered circle), so refining N approaches the
  thin limit.

The bounds are 2π n R ≤ L† ≤ 2π min(7n/3, i) R (§IX.D); for n = i (the trefoil: 4π R) the
minimum is the i-fold covered circle.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from stiffknots._json import json_default
from stiffknots._version import __version__
from stiffknots.engine.driver import (
    TopologyChangedError,
    default_workers,
    replica_seeds,
)
from stiffknots.engine.pool import BestFirst, run_jobs
from stiffknots.engine.state import ChainState, MoveParams

DEFAULT_TIGHT_MOVES = 30_000_000
DEFAULT_POWERS = (1, 2, 4, 8, 16, 32, 64)


def length_over_R(theta_max: float, n_beads: int) -> float:
    """L/R = 2N sin(θ*/2) for a closed chain of N unit bonds with largest turning angle θ*."""
    return float(2.0 * n_beads * np.sin(theta_max / 2.0))


def radius_of_turn(theta: float) -> float:
    """Radius 1/(2 sin(θ/2)) of the circle through three beads at unit chords turning by θ."""
    return float(1.0 / (2.0 * np.sin(theta / 2.0)))


@dataclass
class TightReplica:
    """One replica of the restricted-curvature search (plain data)."""

    replica: int
    seed: int
    theta_max: float
    length_over_R: float
    coords: np.ndarray
    trace_moves: np.ndarray
    trace_theta: np.ndarray
    wall_time: float
    exclusion_margin: float
    min_segment_distance: float
    energy_recomputed: float
    energy_incremental: float
    knot: str | None = None
    knot_verified: bool | None = None
    start: str | None = None  # starting embedding of this replica

    def summary(self) -> dict:
        d = asdict(self)
        for k in ("coords", "trace_moves", "trace_theta"):
            d.pop(k)
        return d


def _tight_job(coords, params, moves, powers, seed, replica, knot_name, start="braid"):
    """Worker: the continuation in p (see the module docstring), then the ratchet quench."""
    from dataclasses import replace

    from stiffknots.engine.kernel import min_nonadjacent_segment_distance, turning_cosines
    from stiffknots.engine.schedules import Schedule
    from stiffknots.knots.identify import verify_knot

    t0 = time.perf_counter()
    n = len(coords)
    n_stages = len(powers) + 1  # the last share of the moves is the ratchet quench
    per_stage = max(1000, moves // n_stages)
    nch = 100
    pos = np.asarray(coords, dtype=float)
    tm, tt = [], []
    done = 0
    state = None
    for k, p in enumerate(powers):
        if p == 1:
            prm = replace(params, energy="bending")
        else:
            # scale: the 90th percentile of the turning angles, so energies are O(1)
            th90 = float(np.percentile(np.arccos(np.clip(turning_cosines(pos), -1, 1)), 90))
            prm = replace(params, energy="power", power=int(p),
                          energy_scale=float(1 - np.cos(max(th90, 1e-3))))
        state = ChainState(pos, prm, seed=seed + 7919 * k)
        e0 = state.energy / n
        sch = Schedule()
        for c in range(nch):
            if p == 1:  # the paper's annealing of the bending energy: a smooth start
                temp = float(sch.temperature((c + 0.5) / nch))
            else:
                temp = e0 * 1e-2 * 1e-3 ** (c / nch)
            state.run(per_stage // nch, temp)
            done += per_stage // nch
        pos = state.pos.copy()
        tm.append(done)
        tt.append(float(np.max(state.turning_angles())))
    # ratchet quench at the highest power: θ_max follows the largest angle down
    cap = float(np.max(state.turning_angles()))
    state.set_max_turn(cap)
    for _ in range(20):
        state.run(per_stage // 20, 0.0)
        done += per_stage // 20
        th = float(np.max(state.turning_angles()))
        if th < cap:
            cap = th
            state.set_max_turn(cap)
        tm.append(done)
        tt.append(th)
    e_rec = state.recomputed_energy()
    if abs(e_rec - state.energy) > 1e-7 * max(1.0, abs(e_rec)):
        from stiffknots.engine.driver import EnergyBookkeepingError

        raise EnergyBookkeepingError(
            f"incremental energy {state.energy!r} differs from recomputed {e_rec!r}")
    theta = float(np.max(state.turning_angles()))
    ok, found = verify_knot(state.pos, knot_name)
    return TightReplica(
        replica=replica, seed=seed, theta_max=theta, length_over_R=length_over_R(theta, n),
        coords=state.pos.copy(), trace_moves=np.asarray(tm), trace_theta=np.asarray(tt),
        wall_time=time.perf_counter() - t0, exclusion_margin=-state.violation(),
        min_segment_distance=float(min_nonadjacent_segment_distance(state.pos)),
        energy_recomputed=e_rec, energy_incremental=state.energy, knot=found,
        knot_verified=bool(ok), start=start)


@dataclass
class TightResult(BestFirst):
    """Replicas of the restricted-curvature search for one knot, best (shortest) first."""

    knot: str
    beads: int
    seed: int
    settings: dict
    replicas: list[TightReplica]
    bounds: dict
    wall_time: float
    interrupted: bool = False
    version: str = __version__
    extra: dict = field(default_factory=dict)

    @property
    def length_over_R(self) -> float:
        return self.best.length_over_R

    def to_dict(self) -> dict:
        return {
            "knot": self.knot,
            "beads": self.beads,
            "seed": self.seed,
            "length_over_R": self.best.length_over_R if self.replicas else None,
            "theta_max": self.best.theta_max if self.replicas else None,
            "R": radius_of_turn(self.best.theta_max) if self.replicas else None,
            "lower_bound": self.bounds.get("lower"),
            "upper_bound": self.bounds.get("upper"),
            "bounds": self.bounds,
        } | self.provenance()

    def save(self, out: str | Path) -> dict[str, Path]:
        from stiffknots.chain import Chain, save

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "result.json").write_text(json.dumps(self.to_dict(), indent=2,
                                                    default=json_default))
        meta = {"knot": self.knot, "seed": self.best.seed,
                "length_over_R": self.best.length_over_R, "version": self.version}
        save(Chain(self.best.coords, closed=True, meta=meta), out / "best.xyz")
        return {"result": out / "result.json", "best_xyz": out / "best.xyz"}


def tightest(knot: str, beads: int = 150, moves: int = DEFAULT_TIGHT_MOVES, replicas: int = 2,
             seed: int = 0, *, exclusion: str = "tube", d: float | None = None,
             w: float | None = 0.25, powers: tuple[int, ...] = DEFAULT_POWERS,
             workers: int | None = None,
             on_replica_done: Callable[[TightReplica], None] | None = None,
             start: str | Sequence[str] = "all") -> TightResult:
    """Minimal length L†/R of ``knot`` under the curvature limit 1/R (paper §IX.D).

    Parameters
    ----------
    knot : knot name.
    beads : N; finer chains approach the thin limit (the exclusion is fixed in bond lengths).
    moves : attempted moves per replica, shared equally by the stages and the final quench.
    replicas, seed, workers : as for :func:`stiffknots.anneal`.
    exclusion, d, w : exclusion model and distances in bond lengths. The thin knot of §IX.D
        has no thickness: the default is a thin tube, w = 0.25 (the paper's bead rule,
        d = 1/√2, is available and gives longer knots at a given N).
    powers : the continuation p = 1 (the bending energy, annealed as in §VII), 2, 4, …, 64
        of the minimax energy Σ((1 − cos θ)/s)^p.
    start : starting embedding(s), as for :func:`stiffknots.anneal`: ``'all'`` (default: every
        start that exists for the knot, round-robin over the replicas), ``'braid'``, ``'cage'``
        (two-box rational knots; see :mod:`stiffknots.knots.starts`) or one per replica.

    Returns
    -------
    TightResult — ``length_over_R`` of the best replica and the bounds 2πn ≤ L†/R ≤
    2π min(7n/3, i).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.starts import resolve_starts, start_chain
    from stiffknots.theory.bounds import restricted_curvature_bounds

    k = get_knot(knot)
    if replicas < 1:
        raise ValueError(f"replicas must be ≥ 1, got {replicas}")
    if not powers or any(int(p) != p or p < 1 for p in powers):
        raise ValueError(f"powers must be integers ≥ 1, got {powers}")
    if moves < 10_000:
        raise ValueError(f"moves must be ≥ 10,000, got {moves}")
    kw: dict = {"exclusion": exclusion}
    if d is not None:
        kw["d"] = d
    if w is not None and exclusion == "tube":
        kw["w"] = w
    params = MoveParams(**kw)
    params.validate(beads)
    per_replica = resolve_starts(k, start, replicas, beads)
    chains = {st: start_chain(k, st, beads) for st in dict.fromkeys(per_replica)}
    seeds = replica_seeds(seed, replicas)
    nw = workers or default_workers(replicas)
    t0 = time.perf_counter()
    args = [(chains[per_replica[r]], params, int(moves), tuple(int(p) for p in powers), s, r,
             k.name, per_replica[r]) for r, s in enumerate(seeds)]
    results, interrupted = run_jobs(_tight_job, args, nw, on_replica_done)
    results.sort(key=lambda r: r.length_over_R)
    bad = [r for r in results if not r.knot_verified]
    if bad:
        raise TopologyChangedError(
            f"{len(bad)} replica(s) of {k.name} ended as {', '.join(str(r.knot) for r in bad)}"
            f"; this is a bug, please report it with seed {seed}")
    b = restricted_curvature_bounds(k.bridge_number, k.braid_index, R=1.0)
    bounds = {"lower": b.lower, "upper": b.upper, "attained_by": b.attained_by}
    settings = {"moves": int(moves), "powers": list(powers), "params": params.as_dict(),
                "start": per_replica}
    return TightResult(knot=k.name, beads=beads, seed=seed, settings=settings,
                       replicas=results, bounds=bounds, wall_time=time.perf_counter() - t0,
                       interrupted=interrupted)
