"""When is a (knot, model) converged? One small rule, kept here so it can be swapped.

The rule is the solver's (:func:`stiffknots.problems.base.verdict`): the ground state of an
ensemble — the replicas of one knot, model, width, N and settings (:meth:`Store.states
<stiffknots.store.sqlite.Store.states>`) — is *converged* when at least
:data:`MIN_REPLICAS` = 2 replicas reached it (same shape class and multiplicity, §VII) with ε
within :data:`REL_TOL` = 0.1 % of each other (every replica is polished to its local minimum,
so replicas of one state agree far better than that): two independent searches, usually from
different starts, agreeing on the lowest state found. It says nothing about states no replica
reached.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["MIN_REPLICAS", "REL_TOL", "RULE", "is_converged"]

#: Replicas that must reach the ground state.
MIN_REPLICAS = 2
#: Largest relative spread of their ε, (ε_max − ε_min)/ε_min.
REL_TOL = 1e-3
#: The rule in words (for reports).
RULE = (f"ground state reached by ≥ {MIN_REPLICAS} replicas (same shape) with ε within "
        f"{REL_TOL:.0%} of each other")


def is_converged(ground: Mapping[str, Any] | None) -> bool:
    """Whether a ground state (a state of :meth:`Store.states`: ``count``, ``epsilon`` — the
    lowest ε —, ``eps_max``) satisfies the rule of the module docstring."""
    if not ground:
        return False
    count = int(ground.get("count") or 0)
    lo, hi = ground.get("epsilon"), ground.get("eps_max", ground.get("epsilon"))
    if count < MIN_REPLICAS or lo is None or hi is None or lo <= 0:
        return False
    return (float(hi) - float(lo)) / float(lo) <= REL_TOL
