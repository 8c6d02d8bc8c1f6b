"""When is a (knot, model) converged? One small rule, kept here so it can be swapped.

The rule is the solver's (:func:`stiffknots.problems.base.verdict`): the ground state of an
ensemble — the replicas of one knot, model, width, N and settings (:meth:`Store.states
<stiffknots.store.sqlite.Store.states>`) — is *converged* when at least
:data:`MIN_REPLICAS` = 2 replicas reached it: the same shape class and multiplicity (§VII),
ε within :data:`REL_TOL` = 0.1 % of the lowest (every replica is polished to its local
minimum, so replicas of one minimum agree far better than that): two independent searches,
usually from different starts, agreeing on the lowest state found. It says nothing about
states no replica reached.

A stored *state* groups replicas of one shape within 1 % (for the tables of metastable
states); the rule counts only those of its members within 0.1 % of its lowest (``eps_all``).
Before 2026-12-02 it asked the whole 1 % group to lie within 0.1 % instead, so four replicas
at one minimum and a fifth 0.13 % above were "not converged" (5_1, bead rule), and the
``db grounds`` table counted the group without its spread at all.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["MIN_REPLICAS", "REL_TOL", "RULE", "hits", "is_converged"]

#: Replicas that must reach the ground state.
MIN_REPLICAS = 2
#: Largest relative spread of their ε, (ε_max − ε_min)/ε_min.
REL_TOL = 1e-3
#: The rule in words (for reports).
RULE = (f"ground state reached by ≥ {MIN_REPLICAS} replicas (same shape) with ε within "
        f"{REL_TOL:.1%} of the lowest")


def hits(ground: Mapping[str, Any] | None) -> int:
    """The replicas of a ground state within :data:`REL_TOL` of its lowest ε (its members'
    ``eps_all``; a state without it counts all its ``count`` members if its ``eps_max`` is
    within the tolerance, else only the lowest one)."""
    if not ground:
        return 0
    lo = ground.get("epsilon")
    if lo is None or float(lo) <= 0:
        return 0
    lo = float(lo)
    eps = ground.get("eps_all")
    if eps is not None:
        return sum(1 for e in eps if float(e) - lo <= REL_TOL * lo)
    count = int(ground.get("count") or 0)
    hi = ground.get("eps_max")
    if hi is None:
        raise ValueError("a state needs eps_all or eps_max to be judged")
    return count if float(hi) - lo <= REL_TOL * lo else min(count, 1)


def is_converged(ground: Mapping[str, Any] | None) -> bool:
    """Whether a ground state (a state of :meth:`Store.states`: ``epsilon`` — the lowest ε —
    and ``eps_all``) satisfies the rule of the module docstring."""
    return hits(ground) >= MIN_REPLICAS
