"""Ground state and metastable states from a set of annealed chains (paper §VII).

"Repeated simulations with the same knot provide us with the ground state and sometimes also
with metastable states" (§VII); for ``5_2`` the 4-fold cage is the ground state and the 80
metastable (eq. (39)). :func:`group_states` sorts a set of final chains into states:
same shape class (:func:`~stiffknots.analysis.shapes.classify`; a circular braid's index is
part of its class) and same normalised energy ``ε`` within a relative tolerance. The state with
the lowest ``ε`` is the ground state, the others are metastable.

Energy clustering: within one class the chains are sorted by ``ε``; a chain joins the current
state while its ``ε`` is within ``rel_tol`` (default 1 %) of the state's lowest ``ε``, otherwise
it opens a new state. Annealed replicas of the same state at ``N = 150`` spread by ≲ 1 % (e.g.
80s of ``6_2`` at 155.1 and 156.1), while the gaps between states are several per cent
(CB(2) 79.5, 4C 128.4, 80 ≈ 149–156, CB(3) ≈ 181).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots._json import to_plain
from stiffknots.analysis.shapes import LABELS, Shape, classify

__all__ = ["StateGroup", "StateGroups", "group_states", "state_name"]


def state_name(label: str, multiplicity: int | None) -> str:
    """A state's name from its shape class: ``"CB(i=2)"``, ``"4C"``, ``"80"`` or
    ``"other"``."""
    return f"CB(i={multiplicity})" if label == "CB" else label


@dataclass
class StateGroup:
    """One state: chains of the same class with ``ε`` within the tolerance.

    Attributes
    ----------
    label : str
        Shape class (``"CB"``, ``"4C"``, ``"80"``, ``"other"``).
    multiplicity : int or None
        Circular-braid index for ``"CB"``.
    count : int
        Number of chains in the state.
    eps_min, eps_mean, eps_max : float
        Their normalised energies.
    representative : int
        Index (into the input items) of the chain with the lowest ``ε``.
    members : list of int
        Indices of all its chains, by increasing ``ε``.
    meta : dict
        Metadata of the representative (if the item had any).
    reason : str
        The classifier's reason for the representative.
    """

    label: str
    multiplicity: int | None
    count: int
    eps_min: float
    eps_mean: float
    eps_max: float
    representative: int
    members: list[int]
    meta: dict = field(default_factory=dict)
    reason: str = ""

    @property
    def name(self) -> str:
        """``"CB(i=2)"``, ``"4C"``, ``"80"`` or ``"other"``."""
        return state_name(self.label, self.multiplicity)

    def to_dict(self) -> dict:
        return {"name": self.name, "label": self.label, "multiplicity": self.multiplicity,
                "count": self.count, "eps_min": self.eps_min, "eps_mean": self.eps_mean,
                "eps_max": self.eps_max, "representative": self.representative,
                "members": list(self.members), "meta": to_plain(self.meta),
                "reason": self.reason}


@dataclass
class StateGroups:
    """All states of a set of chains, by increasing lowest ``ε``.

    ``ground`` is the first (lowest ``ε``), ``metastable`` the others.
    """

    states: list[StateGroup]
    rel_tol: float
    n_items: int

    @property
    def ground(self) -> StateGroup:
        return self.states[0]

    @property
    def metastable(self) -> list[StateGroup]:
        return self.states[1:]

    def to_dict(self) -> dict:
        return {"rel_tol": self.rel_tol, "n_items": self.n_items,
                "ground": self.ground.to_dict(),
                "metastable": [s.to_dict() for s in self.metastable]}




def _get(item: Any, key: str, default: Any = None) -> Any:
    if isinstance(item, Mapping):
        return item.get(key, default)
    return getattr(item, key, default)


def _item_class(k: int, item: Any, classify_kwargs: dict) -> tuple[str, int | None, str]:
    shape = _get(item, "shape")
    if isinstance(shape, Shape):
        return shape.label, shape.multiplicity, shape.reason
    label = _get(item, "label")
    if label is not None:
        if label not in LABELS:
            raise ValueError(f"item {k}: label must be one of {LABELS}, got {label!r}")
        mult = _get(item, "multiplicity")
        if label == "CB" and mult is None:
            raise ValueError(f"item {k}: a 'CB' label needs its 'multiplicity' (braid index)")
        return label, (int(mult) if label == "CB" else None), "given"
    coords = _get(item, "coords")
    if coords is None:
        raise ValueError(f"item {k} has neither 'coords' nor a 'label'/'shape'; each item "
                         f"needs coords (N, 3) and epsilon")
    s = classify(coords, True, **classify_kwargs)
    return s.label, s.multiplicity, s.reason


def group_states(items: Iterable[Any], rel_tol: float = 0.01,
                 **classify_kwargs: Any) -> StateGroups:
    """Group annealed chains into a ground state and metastable states (§VII).

    Parameters
    ----------
    items : iterable
        Mappings or objects (e.g. :class:`~stiffknots.engine.driver.ReplicaResult`) with
        ``coords`` (``(N, 3)``, a closed chain) and ``epsilon``; optionally ``label`` (and
        ``multiplicity`` for ``"CB"``) or ``shape`` (a :class:`Shape`) to skip classification,
        and ``meta`` (a dict kept for the representative).
    rel_tol : float, default 0.01
        Relative ``ε`` tolerance within one state (see the module docstring).
    **classify_kwargs
        Passed to :func:`~stiffknots.analysis.shapes.classify` (``d``, ``factor``, ...).

    Returns
    -------
    StateGroups
        ``.ground`` (lowest ``ε``) and ``.metastable``, each a :class:`StateGroup` with
        count, ``ε`` min/mean/max and the index of a representative chain.

    Raises
    ------
    ValueError
        No items, an item without ``epsilon`` or with a non-finite one, bad coordinates or
        labels, ``rel_tol`` not in ``[0, 1)``.
    """
    try:
        tol = float(rel_tol)
    except (TypeError, ValueError):
        raise ValueError(f"rel_tol must be a number in [0, 1), got {rel_tol!r}") from None
    if not 0.0 <= tol < 1.0:
        raise ValueError(f"rel_tol must be in [0, 1) (a relative tolerance, 0.01 = 1 %), got "
                         f"{rel_tol!r}")
    items = list(items)
    if not items:
        raise ValueError("group_states needs at least one item (coords and epsilon)")
    eps = np.empty(len(items))
    classes: list[tuple[str, int | None, str]] = []
    for k, item in enumerate(items):
        e = _get(item, "epsilon")
        try:
            e = float(e)
        except (TypeError, ValueError):
            raise ValueError(f"item {k}: epsilon must be a number, got {e!r}") from None
        if not math.isfinite(e):
            raise ValueError(f"item {k}: epsilon must be finite, got {e!r}")
        eps[k] = e
        classes.append(_item_class(k, item, classify_kwargs))
    by_class: dict[tuple[str, int | None], list[int]] = {}
    for k, (lab, mult, _) in enumerate(classes):
        by_class.setdefault((lab, mult), []).append(k)
    states: list[StateGroup] = []
    for (lab, mult), idx in by_class.items():
        idx = sorted(idx, key=lambda q: (eps[q], q))
        groups: list[list[int]] = []
        for q in idx:
            if groups and eps[q] <= eps[groups[-1][0]] + tol * abs(eps[groups[-1][0]]):
                groups[-1].append(q)
            else:
                groups.append([q])
        for g in groups:
            e = eps[g]
            rep = g[0]
            meta = _get(items[rep], "meta") or {}
            states.append(StateGroup(lab, mult, len(g), float(e.min()), float(e.mean()),
                                     float(e.max()), rep, list(g),
                                     dict(meta) if isinstance(meta, Mapping) else {},
                                     classes[rep][2]))
    states.sort(key=lambda s: (s.eps_min, s.representative))
    return StateGroups(states, tol, len(items))
