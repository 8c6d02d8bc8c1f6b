"""The census of a knot: every distinct state its searches found near the lowest, and how often.

A *state* is a distinct polished minimum of a knot at one width (#37). Two chains are one
state when all three agree (docs/methods/states.md):

1. the **shape class** and circular-braid index (:func:`~stiffknots.analysis.shapes.classify`);
2. **ε** within ``rel_tol`` (default 1 %) of the state's lowest;
3. the **shape distance** (:func:`~stiffknots.analysis.identity.shape_distance`: RMSD / L
   after the best rotation, mirror, translation, reversal and shift of the bead index) to the
   state's lowest chain within ``max_distance``.

The **structure** (line-braids, point-braids and multiple points, §V B) is recorded — the
representative's — but not compared: the name read from a chain is not stable across replicas
of one state (two 3_1 circular braids at 0.007 L of each other read ``line-braid (m = 2)`` and
``line-braid (m = 2) + point-braid``; two 6_2 80s, 0.009 L apart, a pair of double points and
a triple point), so requiring equal names would split states that are one.

The chains are taken in increasing ``ε``; each joins the lowest state it matches, or opens a
new one (so every state's representative is its lowest chain). Only chains within ``window``
(default 15 %) of the lowest ``ε`` are counted: the census is the low landscape, where the
thin-limit ground state must come from (its branches are followed to w = 0 by #37's later
stages). Each state records how many chains and how many independent *searches* ended in it
(a search's chains — its continuation legs — count once).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from stiffknots._json import to_plain
from stiffknots.analysis.identity import DEFAULT_POINTS, SAME_STATE_DISTANCE, shape_distance
from stiffknots.analysis.states import state_name

__all__ = ["DEFAULT_WINDOW", "CensusState", "Census", "census"]

#: Default window of a census: states within 15 % of the lowest ε.
DEFAULT_WINDOW = 0.15


@dataclass
class CensusState:
    """One state of a census.

    Attributes
    ----------
    label, multiplicity : str, int or None
        Shape class and circular-braid index.
    structure : str or None
        Its structure named in the words of §V B (None: not known).
    epsilon, eps_max : float
        Lowest and highest ε of its chains.
    count : int
        Chains in the state.
    searches : int
        Independent searches that ended in it.
    representative : int
        Index (into the census's input items) of its lowest chain.
    members : list of int
        Indices of its chains, by increasing ε.
    spread : float
        Largest shape distance (/ L) of a member from the representative.
    meta : dict
        The representative's metadata, if its item had any.
    """

    label: str
    multiplicity: int | None
    structure: str | None
    epsilon: float
    eps_max: float
    count: int
    searches: int
    representative: int
    members: list[int]
    spread: float
    meta: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        """``"CB(i=2)"``, ``"4C"``, ``"80"`` or ``"other"``."""
        return state_name(self.label, self.multiplicity)

    def to_dict(self) -> dict:
        return {"name": self.name, "shape": self.label, "multiplicity": self.multiplicity,
                "structure": self.structure, "epsilon": self.epsilon, "eps_max": self.eps_max,
                "count": self.count, "searches": self.searches,
                "representative": self.representative, "members": list(self.members),
                "spread": self.spread, "meta": to_plain(self.meta)}


@dataclass
class Census:
    """The states of a knot within ``window`` of its lowest ε, by increasing ε."""

    states: list[CensusState]
    window: float
    rel_tol: float
    max_distance: float
    n_items: int
    n_counted: int

    @property
    def ground(self) -> CensusState:
        """The lowest state."""
        return self.states[0]

    def to_dict(self) -> dict:
        return {"window": self.window, "rel_tol": self.rel_tol,
                "max_distance": self.max_distance, "n_items": self.n_items,
                "n_counted": self.n_counted, "states": [s.to_dict() for s in self.states]}


def _get(item: Any, key: str, default: Any = None) -> Any:
    if isinstance(item, Mapping):
        return item.get(key, default)
    return getattr(item, key, default)


def _fraction(name: str, value: Any, upper: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(v) and 0.0 <= v < upper):
        raise ValueError(f"{name} must be in [0, {upper:g}), got {value!r}")
    return v


def census(items: Iterable[Any], *, window: float = DEFAULT_WINDOW, rel_tol: float = 0.01,
           max_distance: float = SAME_STATE_DISTANCE,
           points: int = DEFAULT_POINTS) -> Census:
    """The distinct states among a knot's final chains (module docstring).

    Parameters
    ----------
    items : iterable
        Mappings or objects with ``coords`` (``(N, 3)``, a closed chain), ``epsilon`` and
        ``label`` (``"CB"``, ``"4C"``, ``"80"``, ``"other"``; ``multiplicity`` for ``"CB"``);
        optionally ``structure`` (its §V B name, recorded for a representative), ``search`` (a
        hashable naming the independent search it ends; default: each item its own) and
        ``meta`` (kept for a representative). All chains of one knot at one width.
    window : float, default 0.15
        Count only chains with ``ε ≤ (1 + window) · ε_min``.
    rel_tol : float, default 0.01
        Relative ε tolerance within one state.
    max_distance : float, default :data:`~stiffknots.analysis.identity.SAME_STATE_DISTANCE`
        Largest shape distance (/ L) from a state's lowest chain.
    points : int, default 256
        Sample points of the shape distance.

    Returns
    -------
    Census

    Raises
    ------
    ValueError
        No items; an item without finite ``epsilon``, without ``coords`` or ``label``; a
        ``"CB"`` without its multiplicity; a tolerance out of range.
    """
    window = _fraction("window", window, 10.0)
    rel_tol = _fraction("rel_tol", rel_tol, 1.0)
    max_distance = _fraction("max_distance", max_distance, 1.0)
    items = list(items)
    if not items:
        raise ValueError("a census needs at least one chain (coords, epsilon and label)")
    eps = []
    for k, it in enumerate(items):
        e = _get(it, "epsilon")
        try:
            e = float(e)
        except (TypeError, ValueError):
            raise ValueError(f"item {k}: epsilon must be a number, got {e!r}") from None
        if not math.isfinite(e):
            raise ValueError(f"item {k}: epsilon must be finite, got {e!r}")
        if _get(it, "coords") is None or _get(it, "label") is None:
            raise ValueError(f"item {k}: a census item needs 'coords' and 'label'")
        if _get(it, "label") == "CB" and _get(it, "multiplicity") is None:
            raise ValueError(f"item {k}: a 'CB' label needs its 'multiplicity' (braid index)")
        eps.append(e)
    lowest = min(eps)
    limit = lowest + window * abs(lowest)
    order = sorted((k for k in range(len(items)) if eps[k] <= limit),
                   key=lambda k: (eps[k], k))
    groups: list[dict[str, Any]] = []
    for k in order:
        it = items[k]
        key = (_get(it, "label"), _get(it, "multiplicity")
               if _get(it, "label") == "CB" else None)
        structure = _get(it, "structure")
        home = None
        for g in groups:
            if g["key"] != key or eps[k] > g["eps"] + rel_tol * abs(g["eps"]):
                continue
            d = shape_distance(_get(items[g["rep"]], "coords"), _get(it, "coords"),
                               points=points)
            if d <= max_distance:
                home = g
                g["spread"] = max(g["spread"], d)
                break
        if home is None:
            groups.append({"key": key, "eps": eps[k], "structure": structure, "rep": k,
                           "members": [k], "spread": 0.0})
        else:
            home["members"].append(k)
    states = []
    for g in groups:
        members = g["members"]
        searches: set[Hashable] = {(_get(items[m], "search"), ) if _get(items[m], "search")
                                   is not None else ("item", m) for m in members}
        meta = _get(items[g["rep"]], "meta") or {}
        states.append(CensusState(
            label=g["key"][0], multiplicity=(int(g["key"][1]) if g["key"][1] is not None
                                             else None),
            structure=g["structure"], epsilon=eps[g["rep"]],
            eps_max=max(eps[m] for m in members), count=len(members),
            searches=len(searches), representative=g["rep"], members=list(members),
            spread=float(g["spread"]), meta=dict(meta) if isinstance(meta, Mapping) else {}))
    return Census(states, window, rel_tol, max_distance, len(items), len(order))
