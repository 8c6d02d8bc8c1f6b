"""``stiffknots.anneal``: any knot of the catalogue to a verified minimum-energy chain.

Composes catalogue → embedding → engine (replicas on all cores) → verification. Every replica
is verified: energy recomputed from scratch equals the incremental one, bonds are unit, the
exclusion rule holds, and the knot type (HOMFLY-PT via topoly) equals the requested one — a
changed topology raises :class:`~stiffknots.engine.driver.TopologyChangedError`.

Long runs can checkpoint every replica (``checkpoint_dir``) and be resumed (``resume=True``)
with exactly the result of an uninterrupted run (:mod:`stiffknots.engine.driver`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from stiffknots._version import __version__
from stiffknots.engine.driver import (
    AnnealSettings,
    ReplicaResult,
    TopologyChangedError,
    default_workers,
    replica_seeds,
    run_replica,
)
from stiffknots.engine.pool import BestFirst, run_jobs
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import MoveParams

DEFAULT_MOVES = AnnealSettings.moves  # 30 M: relaxation + annealing (schedules.py)


@dataclass
class AnnealResult(BestFirst):
    """Replicas of one knot, best first. ``interrupted`` is True when Ctrl-C stopped the run
    (finished replicas are kept)."""

    knot: str
    beads: int
    seed: int
    settings: dict
    replicas: list[ReplicaResult]
    wall_time: float
    interrupted: bool = False
    version: str = __version__
    bounds: dict = field(default_factory=dict)

    @property
    def epsilon(self) -> float:
        return self.best.epsilon

    def to_dict(self) -> dict:
        return {
            "knot": self.knot,
            "beads": self.beads,
            "seed": self.seed,
            "epsilon": self.best.epsilon if self.replicas else None,
            "knot_verified": all(r.knot_verified for r in self.replicas),
            "settings": self.settings,
            "bounds": self.bounds,
            "wall_time": self.wall_time,
            "interrupted": self.interrupted,
            "version": self.version,
            "replicas": [r.summary() for r in self.replicas],
        }

    def save(self, out: str | Path) -> dict[str, Path]:
        """Write ``result.json``, the best chain as ``best.xyz``/``best.json``, every replica's
        chain as ``replica_K.xyz``, the annealing traces as ``traces.npz``."""
        from stiffknots.chain import Chain, save

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths = {"result": out / "result.json"}
        paths["result"].write_text(json.dumps(self.to_dict(), indent=2, default=_jsonable))
        for r in self.replicas:
            meta = {"knot": self.knot, "seed": r.seed, "epsilon": r.epsilon,
                    "version": self.version, "settings": self.settings}
            save(Chain(r.coords, closed=True, meta=meta), out / f"replica_{r.replica}.xyz")
        best = self.best
        meta = {"knot": self.knot, "seed": best.seed, "epsilon": best.epsilon,
                "version": self.version, "settings": self.settings}
        save(Chain(best.coords, closed=True, meta=meta), out / "best.xyz")
        save(Chain(best.coords, closed=True, meta=meta), out / "best.json")
        paths["best_xyz"] = out / "best.xyz"
        paths["best_json"] = out / "best.json"
        np.savez_compressed(
            out / "traces.npz",
            **{f"r{r.replica}_{k}": getattr(r, f"trace_{k}")
               for r in self.replicas for k in ("moves", "temperature", "epsilon", "seconds")},
        )
        paths["traces"] = out / "traces.npz"
        return paths


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {type(x)}")


def checkpoint_path(checkpoint_dir: str | Path, replica: int) -> Path:
    """The checkpoint file of one replica inside ``checkpoint_dir``."""
    return Path(checkpoint_dir) / f"replica_{replica}.ckpt.npz"


def _replica_job(coords, settings, seed, replica, knot_name, checkpoint_dir=None,
                 resume=False, checkpoint_seconds=None, start="braid"):
    """Worker: anneal one replica (checkpointed if asked) and verify its knot type."""
    from stiffknots.knots.identify import verify_knot

    ck = checkpoint_path(checkpoint_dir, replica) if checkpoint_dir is not None else None
    res = run_replica(coords, settings, seed, replica, checkpoint=ck, resume=resume,
                      checkpoint_every=10, checkpoint_seconds=checkpoint_seconds)
    ok, found = verify_knot(res.coords, knot_name)
    res.knot = found
    res.knot_verified = bool(ok)
    res.start = start
    return res


def anneal(
    knot: str,
    beads: int = 150,
    moves: int = DEFAULT_MOVES,
    replicas: int = 2,
    seed: int = 0,
    *,
    schedule: Schedule | None = None,
    params: MoveParams | None = None,
    workers: int | None = None,
    quench_fraction: float = 0.1,
    target_epsilon: float | None = None,
    on_replica_done: Callable[[ReplicaResult], None] | None = None,
    checkpoint_dir: str | Path | None = None,
    resume: bool = False,
    checkpoint_seconds: float | None = 60.0,
    start: str | Sequence[str] = "all",
) -> AnnealResult:
    """Anneal ``replicas`` independent chains of ``knot`` and return the verified results.

    Parameters
    ----------
    knot : knot name in any usual spelling ('4_1', '4.1', 'K11a1', 'T(2,3)').
    beads : number of beads N (bond length 1, so the chain length L = N).
    moves : attempted moves per replica (annealing plus the final quench).
    replicas : independent replicas; they run in parallel on ``workers`` processes
        (default: all cores).
    seed : user seed; replica seeds are derived from it (recorded in every result).
    schedule, params : cooling schedule and move/exclusion parameters (defaults documented in
        :class:`Schedule` and :class:`MoveParams`).
    quench_fraction : fraction of the moves spent in the final T = 0 quench.
    target_epsilon : if given, each replica records the wall time at which ε first fell below.
    on_replica_done : callback called in the parent process as each replica finishes.
    checkpoint_dir : if given, every replica writes ``replica_K.ckpt.npz`` there every 10
        chunks (of 210), every ``checkpoint_seconds`` seconds and when it ends (positions,
        generator state, counters, energy, chunk index, traces, best chain, settings, seed,
        version).
    resume : continue every replica from its checkpoint in ``checkpoint_dir`` when there is
        one (the call must repeat the same knot, beads, moves, seed and settings; a mismatch
        raises ValueError); the result is exactly that of an uninterrupted run.
    checkpoint_seconds : wall-clock seconds between checkpoints (None: chunks only).
    start : starting embedding: ``'braid'`` (closure of KnotInfo's braid word), ``'cage'``
        (the 4-fold cage of a two-box rational knot [ab], §VII; see
        :mod:`stiffknots.knots.starts`), ``'all'`` (the default: every start that exists for
        the knot, shared round-robin among the replicas), or one start per replica (a
        sequence of ``replicas`` names). Recorded in the settings and in every replica.

    Returns
    -------
    AnnealResult
        Replicas sorted by ε (best first); ε = E_d·N/C (paper §VII).

    Raises
    ------
    UnknownKnotError, EmbeddingError, ValueError
        For a wrong knot name, too few beads (the message gives the minimum), bad parameters.
    TopologyChangedError
        If any replica ends with a different knot type (never expected; see the kernel docs).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.starts import resolve_starts, start_chain
    from stiffknots.theory.bounds import closed_bounds

    k = get_knot(knot)
    if replicas < 1:
        raise ValueError(f"replicas must be ≥ 1, got {replicas}")
    if resume and checkpoint_dir is None:
        raise ValueError("resume=True needs checkpoint_dir (where the checkpoints are)")
    settings = AnnealSettings(moves=int(moves), schedule=schedule or Schedule(),
                              params=params or MoveParams(), quench_fraction=quench_fraction,
                              target_epsilon=target_epsilon)
    settings.validate()
    settings.params.validate(beads)
    per_replica = resolve_starts(k, start, replicas, beads)
    chains = {st: start_chain(k, st, beads) for st in dict.fromkeys(per_replica)}
    seeds = replica_seeds(seed, replicas)
    nw = workers or default_workers(replicas)
    t0 = time.perf_counter()
    results, interrupted = run_jobs(
        _replica_job,
        [(chains[per_replica[r]], settings, s, r, k.name, checkpoint_dir, resume,
          checkpoint_seconds, per_replica[r]) for r, s in enumerate(seeds)],
        nw, on_replica_done)
    results.sort(key=lambda r: r.epsilon)
    bad = [r for r in results if not r.knot_verified]
    if bad:
        raise TopologyChangedError(
            f"{len(bad)} replica(s) of {k.name} ended as {', '.join(r.knot for r in bad)}; "
            "this is a bug in the engine, please report it with the seed "
            f"{seed} and the settings"
        )
    b = closed_bounds(k.bridge_number, k.braid_index)
    bounds = {"lower": b.lower, "upper": b.upper, "attained_by": b.attained_by}
    return AnnealResult(knot=k.name, beads=beads, seed=seed,
                        settings={**settings.as_dict(),
                                  "start": per_replica},
                        replicas=results, wall_time=time.perf_counter() - t0,
                        interrupted=interrupted, bounds=bounds)
