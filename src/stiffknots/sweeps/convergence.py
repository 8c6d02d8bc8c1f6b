"""When is a (knot, model) converged? One small rule, kept here so it can be swapped.

The rule is the solver's (:func:`stiffknots.problems.base.verdict`): the ground state of an
ensemble — the replicas of one knot, model, width, N and settings (:meth:`Store.states
<stiffknots.store.sqlite.Store.states>`) — is *converged* when at least
:func:`min_searches` independent searches reached it — 3 for the tube model, 2 for the bead
rule (:data:`stiffknots.problems.base.AGREE`) — (a continuation leg counts with
the search it continued, :mod:`stiffknots.sweeps.legs`): the same shape class and
multiplicity (§VII), ε within :data:`REL_TOL` = 0.1 % of the lowest (every replica is
polished to its local minimum, so replicas of one minimum agree far better than that): two
independent searches,
usually from different starts, agreeing on the lowest state found — and at least one of them
the ensemble's own Monte Carlo search, not a bead replica seeded from a tube replica
(:mod:`stiffknots.sweeps.cross`, ``start = "tube-ground"``). It says nothing about states no
replica reached.

Why the seeded replicas confirm but do not certify: they come from the tube model's
landscape, whose funnels lead reproducibly to one bead-rule minimum each, so two of them agree
easily on a state the bead rule's own searches go below. Measured: with seeded replicas
counted like the others, 10_5's bead ensemble "converged" at
203.22 on two seeded replicas, where a bead search of an earlier sweep reached 202.57; the
same route inside ``anneal`` "converged" 7_5 at 183.65 and 6_3 at 163.71, whose bead searches
reach 176.98 and 160.50 (docs/history.md). A seeded replica still lowers the ground where it
is lowest, and agrees with a bead search as a second opinion.

A stored *state* groups replicas of one shape within 1 % (for the tables of metastable
states); the rule counts only those of its members within 0.1 % of its lowest (``eps_all``):
four replicas at one minimum and a fifth 0.13 % above it are converged.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from stiffknots.problems.base import AGREE, agree_for
from stiffknots.store.rows import SEEDED_START  # the start of a seeded replica

__all__ = ["MIN_REPLICAS", "REL_TOL", "RULE", "ensemble_converged", "hits", "is_converged",
           "min_searches", "own_hits", "untried_starts"]


#: Searches that must reach the ground state where the model is not known (the bead rule's).
MIN_REPLICAS = 2
#: Largest relative spread of their ε, (ε_max − ε_min)/ε_min.
REL_TOL = 1e-3


def min_searches(exclusion: str | None) -> int:
    """The independent searches a verdict needs under ``exclusion``: the solver's rule
    (:func:`~stiffknots.problems.base.agree_for`)."""
    return agree_for(exclusion)


#: The rule in words (for reports).
RULE = (f"ground state reached by ≥ {AGREE['tube']} independent searches under the "
        f"tube model, ≥ {AGREE['bead']} under the bead rule (replicas; a "
        f"continuation leg counts with the search it continued; same shape) with ε within "
        f"{REL_TOL:.1%} of the lowest, one of them the model's own search (not seeded from "
        f"a tube replica), after a replica from every default start")


def hits(ground: Mapping[str, Any] | None) -> int:
    """The searches that reached a ground state: its members within :data:`REL_TOL` of its
    lowest ε, each search counted once (its ``eps_by_search``: a continuation leg and the
    search it continued are one search, :mod:`stiffknots.sweeps.legs`); a state without it
    counts its members (``eps_all``), and one without that all its ``count`` members if its
    ``eps_max`` is within the tolerance, else only the lowest one."""
    if not ground:
        return 0
    lo = ground.get("epsilon")
    if lo is None or float(lo) <= 0:
        return 0
    lo = float(lo)
    by_search = ground.get("eps_by_search")
    if by_search is not None:
        return sum(1 for e in by_search.values() if float(e) - lo <= REL_TOL * lo)
    eps = ground.get("eps_all")
    if eps is not None:
        return sum(1 for e in eps if float(e) - lo <= REL_TOL * lo)
    count = int(ground.get("count") or 0)
    hi = ground.get("eps_max")
    if hi is None:
        raise ValueError("a state needs eps_all or eps_max to be judged")
    return count if float(hi) - lo <= REL_TOL * lo else min(count, 1)


def own_hits(ground: Mapping[str, Any] | None) -> int:
    """Of :func:`hits`, the replicas not seeded from a tube replica (by the state's
    ``eps_by_start``; a state without it counts all its hits as the ensemble's own)."""
    if not ground:
        return 0
    by = ground.get("eps_by_start")
    if by is None:
        return hits(ground)
    lo = ground.get("epsilon")
    if lo is None or float(lo) <= 0:
        return 0
    lo = float(lo)
    return sum(1 for st, eps in by.items() if st != SEEDED_START
               for e in eps if float(e) - lo <= REL_TOL * lo)


def is_converged(ground: Mapping[str, Any] | None, exclusion: str | None = None) -> bool:
    """Whether a ground state (a state of :meth:`.Store.states`: ``epsilon`` — the lowest ε —,
    ``eps_all`` and ``eps_by_start``; or a row of :meth:`.Store.ground_states`) satisfies the
    rule of the module docstring: at least :func:`min_searches` hits under its exclusion
    model (``exclusion``, else the row's own ``exclusion``), one of them the ensemble's own
    search."""
    if exclusion is None and ground:
        exclusion = ground.get("exclusion")
    return hits(ground) >= min_searches(exclusion) and own_hits(ground) >= 1


def untried_starts(states: Mapping[str, Any], starts: Sequence[str] | None = None) -> list[str]:
    """The starts from which no stored replica of an ensemble started: ``states`` is a
    :meth:`.Store.states` dict (every state's ``starts`` counts) or a row of
    :meth:`.Store.ground_states` (its ``starts_tried`` and ``start_policy``); ``starts`` the
    starts asked for —
    by default the knot's default starts where the ensemble is a sweep's (its settings'
    ``start`` policy is :data:`~stiffknots.sweeps.plan.START_POLICY`), none otherwise."""
    if "starts_tried" in states:
        tried = set(states.get("starts_tried") or ())
    else:
        tried = set()
        for st in [states.get("ground"), *(states.get("metastable") or [])]:
            if st:
                tried.update((st.get("starts") or {}).keys())
    if starts is None:
        from stiffknots.knots.starts import default_start_names
        from stiffknots.sweeps.plan import START_POLICY

        policy = (states["start_policy"] if "start_policy" in states
                  else (states.get("settings") or {}).get("start"))
        starts = (default_start_names(states["knot"], int(states["beads"]))
                  if policy == START_POLICY else ())
    return [s for s in dict.fromkeys(starts) if s not in tried]


def ensemble_converged(states: Mapping[str, Any], starts: Sequence[str] | None = None) -> bool:
    """The verdict on a whole ensemble (a :meth:`.Store.states` dict or a
    :meth:`.Store.ground_states` row): its ground state satisfies the rule
    (:func:`is_converged`) and every start asked for (:func:`untried_starts`: a sweep's
    ensemble asks for the knot's default starts, the shapes §VII conjectures for it) has had
    a replica — the solver's rule too (:func:`stiffknots.problems.base.verdict`): on 4_1
    braid and cage agree at the cage's 128.384 while every search from the 80 ends lower
    (docs/history.md)."""
    ground = states.get("ground") if "ground" in states else states
    return (is_converged(ground, states.get("exclusion"))
            and not untried_starts(states, starts))
