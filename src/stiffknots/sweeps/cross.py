"""Bead-rule replicas seeded from the tube model's replicas (a sweep's cross-model step).

Every tube-admissible chain of diameter w ≥ d is admissible under the bead rule of distance d
at the same N: beads i, j at index distance ≥ 2 start or end two segments that share no bead
(for j = i + 2: [i − 1, i] and [i + 2, i + 3]; for j ≥ i + 3: [i, i + 1] and [j, j + 1]),
and their distance is at least those segments', ≥ w ≥ d. So every tube replica's end state is
a bead-rule chain, and the bead rule's minimum lies at or below any of them polished under the
bead rule. The bead rule's many contact registries make its Monte Carlo searches glassy: on
10_4 (N = 150, d = w = 1/√2) six bead searches ended at 260.73 or above while the tube
ground, 223.89, polished under the bead rule ends at 210.76 (docs/history.md).
The tube model's smoother landscape is a better search of the bead rule's: a tube annealing,
then a bead-rule polish.

:func:`seed_from_tube` therefore takes, for every knot with a bead ensemble and a tube
ensemble of the same N and w ≥ d, each tube replica of the sweep (its seed) not yet seeded,
polishes it under the bead rule (:func:`stiffknots.engine.polish.polish`: no strand passage,
bonds and the rule held exactly), verifies its knot type and stores it in the bead ensemble
as replica :data:`SEEDED_REPLICA` + r (r: the tube replica's number) with
``start = "tube-ground"`` and, under ``extra``, the tube replica it came from
(``seeded_from``) and the polish's figures. Each is one more search of the bead ensemble — a
tube annealing from its own seed, then a bead-rule polish — with no Monte Carlo of its own;
it can lower the ensemble's ground and confirm a state, but the verdict needs one of the
ensemble's own searches at its ground too (:mod:`stiffknots.sweeps.convergence`: seeded
replicas from one tube funnel agree easily above the bead rule's lowest). Reproducible: a
seeded replica depends only on its tube replica, itself fixed by its key, and a stored key
is never written again; a tube replica seeded under the older rule (only the lowest, as
replica :data:`OLDER_SEEDED_REPLICA`) is not seeded twice.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots._version import __version__
from stiffknots.store import ReplicaKey, Store, row_from_replica, search_of, settings_hash
from stiffknots.sweeps.convergence import SEEDED_START  # its ``start``
from stiffknots.width import Width

__all__ = ["OLDER_SEEDED_REPLICA", "SEEDED_REPLICA", "SEEDED_START", "seed_from_tube", "seed_pairs"]

#: the replica number of tube replica 0's seed in the bead ensemble's key (tube replica r:
#: this + r; above every Monte Carlo replica: a sweep adds at most
#: :data:`stiffknots.problems.validate.MAX_REPLICAS`)
SEEDED_REPLICA = 2_000_000
#: the replica number of the one seeded replica of the older rule (the lowest tube replica)
OLDER_SEEDED_REPLICA = 1_000_000


@dataclass
class _Seeded:
    """A replica result as :func:`~stiffknots.store.row_from_replica` reads one."""

    coords: np.ndarray
    epsilon: float
    min_segment_distance: float
    wall_time: float
    cpu_time: float
    knot_verified: bool
    seed: int
    replica: int
    start: str = SEEDED_START
    version: str = __version__
    seeded_from: dict = field(default_factory=dict)
    polish: dict = field(default_factory=dict)


def seed_pairs(models: Sequence[Width]) -> list[tuple[Width, Width]]:
    """(bead model, tube model) pairs of a sweep whose tube chains are bead-admissible: the
    same N and w ≥ d."""
    return [(b, t) for b in models if b.exclusion == "bead" for t in models
            if t.exclusion == "tube" and t.beads == b.beads and t.thickness >= b.thickness]


def seed_from_tube(store: Store, knots: Sequence[str], models: Sequence[Width],
                   settings: Mapping[str, Mapping[str, Any]], seed: int,
                   budget: str | None = None) -> list[dict]:
    """Store, for every knot and :func:`seed_pairs` pair, a bead replica seeded from each of
    the sweep's tube replicas not yet seeded (module docstring); skip a key stored already.

    Parameters
    ----------
    store : Store
        The sweep's store.
    knots, models
        The sweep's knots and models.
    settings : mapping
        Model name → the settings of its replicas
        (:func:`~stiffknots.sweeps.plan.sweep_settings`): the seeded row joins the bead
        ensemble with the bead model's settings (the same hash).
    seed : int
        The sweep's seed (the key's seed).
    budget : str or None
        The budget's name (kept under ``extra``).

    Returns
    -------
    list of dict
        One entry per tube replica seeded now: ``knot``, ``model``, ``tube_replica``,
        ``written`` (bool), ``epsilon`` (the seeded replica's, or None), ``tube_epsilon`` (its
        start's), ``bead_epsilon`` (the lowest of the bead ensemble's own Monte Carlo
        replicas stored before it, or None) and ``reason`` when nothing was written.
    """
    out = []
    for bead, tube in seed_pairs(models):
        bset = dict(settings[bead.exclusion])
        bh, th = settings_hash(bset), settings_hash(settings[tube.exclusion])
        for knot in knots:
            # this sweep's tube replicas only (its seed): another sweep's would make the bead
            # ensemble depend on which sweep ran first
            rows = store.replicas(knot=knot, exclusion="tube", beads=tube.beads,
                                  thickness=tube.thickness, settings_hash=th, seed=int(seed))
            if not rows:
                continue
            beads = store.replicas(knot=knot, exclusion="bead", beads=bead.beads,
                                   thickness=bead.thickness, settings_hash=bh, seed=int(seed))
            done = {int(((r.get("extra") or {}).get("seeded_from") or {}).get("replica", -1))
                    for r in beads if r["start"] == SEEDED_START}
            searched = [r["epsilon"] for r in beads if r["start"] != SEEDED_START]
            for low in sorted(rows, key=lambda r: r["replica"]):
                key = ReplicaKey(knot, "bead", bead.beads, bead.thickness, int(seed),
                                 SEEDED_REPLICA + int(low["replica"]), bh)
                if int(low["replica"]) in done or store.has(key):
                    continue
                out.append(_seed_one(store, knot, bead, tube, low, key, bset, th,
                                     min(searched, default=None), budget))
    return out


def _seed_one(store: Store, knot: str, bead: Width, tube: Width, low: Mapping[str, Any],
              key: ReplicaKey, bset: Mapping[str, Any], th: str, searched: float | None,
              budget: str | None) -> dict:
    """Polish one stored tube replica ``low`` under the bead rule, verify and store it under
    ``key``; the entry of :func:`seed_from_tube`."""
    from stiffknots.analysis import classify
    from stiffknots.engine.polish import polish
    from stiffknots.knots.identify import verify_knot
    from stiffknots.measures import min_segment_distance

    t0, c0 = time.perf_counter(), time.process_time()
    res = polish(store.coords(low["id"]), exclusion="bead", d=bead.thickness)
    ok, found = verify_knot(res.pos, knot)
    entry = {"knot": knot, "model": bead.exclusion, "tube_replica": int(low["replica"]),
             "tube_epsilon": low["epsilon"], "bead_epsilon": searched, "epsilon": None,
             "written": False}
    if not ok:  # never expected: the polish cannot pass strands (its proof)
        entry["reason"] = (f"TopologyChangedError: the seeded chain ended as {found}; "
                           "not stored")
        return entry
    n = len(res.pos)
    eps = n * res.energy
    rep = _Seeded(
        coords=res.pos, epsilon=eps,
        min_segment_distance=float(min_segment_distance(res.pos, True)),
        wall_time=time.perf_counter() - t0, cpu_time=time.process_time() - c0,
        knot_verified=True, seed=int(low.get("replica_seed") or 0), replica=key.replica,
        seeded_from={"exclusion": "tube", "thickness": tube.thickness, "beads": tube.beads,
                     "seed": low["seed"], "replica": low["replica"], "settings_hash": th,
                     "epsilon": low["epsilon"], "shape": low.get("shape")},
        polish={"epsilon_before": n * res.energy_before, "iterations": res.iterations,
                "converged": res.converged, "kkt_residual": res.kkt_residual,
                "grad_norm": res.grad_norm, "reason": res.reason})
    shape = classify(res.pos, True, d=bead.thickness)
    row, coords = row_from_replica(
        rep, knot=knot, width=bead, seed=key.seed, settings=bset, shape=shape.label,
        multiplicity=shape.multiplicity, problem=bset["problem"],
        extra={"model": bead.exclusion, "budget": budget, "width": bead.text,
               "shape_reason": shape.reason,
               # one search with the tube search it comes from: a tube leg's seed and its
               # parent's are not two opinions (:mod:`stiffknots.sweeps.legs`)
               "search": SEEDED_REPLICA + search_of(low)})
    entry.update(epsilon=eps, written=bool(store.put(row, coords)))
    return entry
