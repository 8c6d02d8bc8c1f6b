"""Continuation legs: a sweep's last replicas continue a search instead of starting a new one.

A (knot, model) of the tube model (:data:`LEG_EXCLUSIONS`) whose fresh replicas (up to the
budget's ``max_replicas``) have not converged gets up to ``budget.legs`` *legs*: each
continues one stored search by the basin hops of the solver
(:meth:`stiffknots.problems.closed.ClosedAnneal.continue_jobs`: reheat to the schedule's
``t_hop``, cool, quench and polish, :data:`~stiffknots.problems.closed.LEG_HOPS` times, each
hop from the lowest polished chain so far) — the way ``anneal``'s later rounds continue its
searches (:func:`stiffknots.problems.base.solve`).

Which search. The verdict asks for independent searches at the lowest state (three under
the tube model, :mod:`stiffknots.sweeps.convergence`). Where the lowest search sits alone, the
search that can confirm it is the *second-lowest*: a leg continues the second-lowest search
(by its lowest replica, a leg of it included), or the lowest where there is no other. If the
leg reaches the lowest state, two searches agree; if it goes below, the next leg continues the
former lowest, now second. Measured on the 249-knot atlas run (tube w = 1/√2, N = 150; one
leg from the second-lowest replica of six near misses whose two lowest searches lay 0.10–0.16 %
apart): 4 of 6 legs ended within 0.1 % of the lowest (10_25, 10_136, 10_165) or below it by
less (10_24, −0.08 %), one stayed where it began (10_28), one went 0.77 % below (9_39)
(docs/history.md).

Langevin legs of the bead rule. A Langevin bead ensemble (the default budget's) still not
converged at its cap gets up to ``budget.bead_legs`` legs
(:meth:`stiffknots.problems.closed.ClosedAnneal.langevin_leg_jobs`: the dynamics from the
parent's polished chain, reheated to T = 2·10⁻³, 3·10⁵ steps, polished); leg k continues the
(k+1)-th lowest of the ensemble's *own* searches (a seeded search cannot certify), ranked when
it is planned: a search's own descent to the bottom of its funnel, so that two searches in
one funnel can meet at its lowest registry. Measured on the 96 unconverged bead ensembles of
the 249-knot atlas (a probe: one leg from each of the four lowest own searches): 9 converged
for 488 CPU s; reheated to 10⁻², 6 converged and 28 grounds went lower alone. The default
budget's legs on that atlas (the same command resumed): 377 legs, 511 CPU s, 153 → 158
verdicts (the atlas's replicas 12 → 16 converted 11 for 1,660 CPU s) — of which two lie above
a deeper search's lowest (docs/history.md).

Searches. Every stored replica belongs to one search: a fresh replica (or a seeded one,
:mod:`stiffknots.sweeps.cross`) is its own, a leg belongs to the search it continued —
``extra["search"]`` (the replica number of the search's first replica) and
``extra["leg_of"]`` (the replica it started from) — and inherits its ``start``, so a leg of a
tube-seeded replica stays a seeded search that confirms but does not certify. The verdict
counts a search once (:func:`stiffknots.sweeps.convergence.hits`): a leg that returns to its
parent's state is no second opinion.

Keys. Leg k of an ensemble is replica :data:`LEG_REPLICA` + k of its key (above every fresh
replica, :data:`~stiffknots.problems.validate.MAX_REPLICAS`, and apart from the seeded
replicas' numbers); its settings, and so its settings hash, are the ensemble's: a leg is one
more search of the same ensemble, with the schedule of a continuation. The parent is chosen
from the replicas stored when the leg is planned, so a resumed sweep plans the same leg.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from stiffknots.store import SEEDED_START, ReplicaKey, Store, search_of
from stiffknots.sweeps.budgets import LEG_EXCLUSIONS

__all__ = ["LEG_REPLICA", "LEG_EXCLUSIONS", "searches", "leg_parent", "langevin_leg_parent",
           "leg_job"]

#: the replica number of an ensemble's first leg (leg k: this + k)
LEG_REPLICA = 1_500_000


def searches(rows: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The lowest row of every search among ``rows``, lowest first (ties by replica)."""
    best: dict[int, Mapping[str, Any]] = {}
    for r in rows:
        s = search_of(r)
        if s not in best or (r["epsilon"], r["replica"]) < (best[s]["epsilon"],
                                                             best[s]["replica"]):
            best[s] = r
    return sorted(best.values(), key=lambda r: (r["epsilon"], r["replica"]))


def leg_parent(rows: Sequence[Mapping[str, Any]]) -> Mapping[str, Any] | None:
    """The row a new leg starts from (module docstring): the lowest row of the second-lowest
    search, or of the lowest where there is one search; None without rows."""
    bests = searches(rows)
    if not bests:
        return None
    return bests[1] if len(bests) > 1 else bests[0]


def langevin_leg_parent(rows: Sequence[Mapping[str, Any]], k: int
                        ) -> Mapping[str, Any] | None:
    """The row Langevin leg ``k`` starts from (module docstring): the lowest row of the
    (k+1)-th lowest own search (not seeded from a tube replica), counted round again past the
    last; None without an own search."""
    own = [r for r in searches(rows) if r["start"] != SEEDED_START]
    return own[k % len(own)] if own else None


def leg_job(store: Store, job: Any, k: int, langevin: bool = False) -> Any:
    """Leg ``k`` of the ensemble of ``job`` (any :class:`~stiffknots.sweeps.plan.SweepJob` of
    it): a SweepJob for replica :data:`LEG_REPLICA` + k whose ``parent`` holds the chain,
    start, replica and search of :func:`leg_parent` over the replicas stored now; None when the
    ensemble has no stored replica."""
    key = job.key
    rows = store.replicas(knot=key.knot, exclusion=key.exclusion, beads=key.beads,
                          thickness=key.thickness, settings_hash=key.settings_hash,
                          seed=key.seed)
    p = langevin_leg_parent(rows, k) if langevin else leg_parent(rows)
    if p is None:
        return None
    parent = {"id": int(p["id"]), "replica": int(p["replica"]), "search": search_of(p),
              "start": p["start"], "epsilon": float(p["epsilon"]),
              "coords": store.coords(int(p["id"]))}
    r = LEG_REPLICA + k
    return replace(job, replica=r, start=None, parent=parent,
                   key=ReplicaKey(key.knot, key.exclusion, key.beads, key.thickness, key.seed,
                                  r, key.settings_hash))
