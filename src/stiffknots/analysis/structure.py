"""Line-braids, point-braids, multiple points and the structure graph (paper §V, Figs 5 and 7).

§V B of the paper describes the shape of a knot in the thin limit ``w → 0`` as a *structure*
``{S}``: line-braids (``m`` strands that have shrunk laterally onto one curve; a single string is
a line-braid of multiplicity ``m = 1``) connected at *multiple points* (strands crossing at an
angle, Fig. 4 c) and *point-braids* (a braid shrunk laterally and then in length; the
strands enter and leave it tangentially along one axis, Fig. 4 d). Fig. 5
sketches such a structure; Fig. 7 of the paper marks them on the Monte Carlo
shapes: a line-braid of multiplicity 2 for the trefoil, two point-braids in the 4-fold cage, one
point-braid and three double points in the "80".

At finite width these objects are read off the contact map
(:func:`stiffknots.analysis.contacts.contact_map`):

local multiplicity ``m(s)``
    One plus the number of distinct strands touching bead ``s``: the beads in contact with
    ``s`` are split into strands wherever their indices jump by more than ``max_gap``
    (default: the contact map's ``min_sep``), cyclically for a closed chain
    (:func:`local_multiplicity`).
line-braid
    A maximal stretch of the chain with constant ``m(s) = m >= 2`` and an arc length of at
    least ``min_length``; the stretches of the strands running together are grouped (through
    their contacts) into one :class:`LineBraid` of multiplicity ``m``.
contact zone
    A connected group of contact runs (maximal stretches with ``m(s) >= 2``, linked by their
    contacts). It is a *line-braid* zone when its longest run reaches ``min_length``; a shorter
    zone is a *point-braid* when its strands are tangent (median ``|t_i·t_j|`` over its
    contacts at least ``cos(tangent_angle)``, default 35°) and a *multiple point* otherwise.
structure graph
    Nodes: point-braids, multiple points and the two ends of every line-braid zone (and the two
    free ends of an open chain). Edges: the line-braid zones (multiplicity ``m``) and the free
    arcs between zones (multiplicity 1). A closed chain without contacts, or one lying entirely
    in one line-braid (the circular braid, §VI C), is a single closed edge without nodes.

Default ``min_length``: ``max(3 × cutoff, 0.1 L)``. In the thin limit a line-braid keeps a finite
fraction of the length (its length is ``L (ε_p/ε)^{1/2}``, eq. (28)) while a point-braid
shrinks with ``w``; on the paper's ``N = 150`` chains the point-braids span 5 to 12 bonds, below
``0.1 L = 15``.
"""

from __future__ import annotations

import math
import sys
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots.analysis.contacts import (
    DEFAULT_CONTACT_FACTOR,
    DEFAULT_D,
    DEFAULT_MIN_SEP,
    ContactMap,
    as_coords,
    contact_map,
)
from stiffknots.errors import ChainWarning
from stiffknots.measures import chain_report

__all__ = [
    "DEFAULT_TANGENT_ANGLE",
    "LineBraid",
    "ContactZone",
    "Node",
    "Edge",
    "StructureGraph",
    "Structure",
    "local_multiplicity",
    "line_braids",
    "analyse_structure",
    "structure_graph",
    "structure_name",
    "tangents",
    "cyclic_runs",
]

#: Largest angle (degrees) between the strands of a point-braid; wider contacts are crossings.
DEFAULT_TANGENT_ANGLE = 35.0

#: Bonds within this fraction of their mean count as equal for the analysis (its contacts and
#: lengths do not notice less; chains resampled to unit chords, as in :mod:`.synthetic`, stay
#: within 1e-3). The mean is the unit: the analysis is scale-free when ``d`` scales alike.
ANALYSIS_BOND_TOL = 1e-2


def warn_unless_model_chain(x: np.ndarray, closed: bool, d: float) -> bool:
    """Warn (:class:`~stiffknots.errors.ChainWarning`, at the caller's line outside the
    package) when ``x`` is not a chain of unit (equal) bonds obeying the bead rule at ``d``:
    the analysis assumes one, and on another chain its contacts, braids and shape class mean
    little. True when it is one (no warning)."""
    rep = chain_report(x, closed, d=d, bond_tol=ANALYSIS_BOND_TOL, segments=False, unit=None)
    if not rep["problems"]:
        return True
    _warn_at_user_line("the shape analysis assumes a unit-bond chain obeying the bead rule; "
                       "in this one " + "; ".join(rep["problems"])
                       + " (stiffknots.checks.check reports the chain)")
    return False


def _warn_at_user_line(message: str) -> None:
    """A :class:`~stiffknots.errors.ChainWarning` at the first line outside the package on
    the stack (the user's call, however deep the analysis called us)."""
    level, f = 2, sys._getframe(1)  # stacklevel 2: the caller of this function
    while f is not None and str(f.f_globals.get("__name__", "")).startswith("stiffknots."):
        f, level = f.f_back, level + 1
    warnings.warn(message, ChainWarning, stacklevel=level)


def warn_if_cutoff_misses_contacts(x: np.ndarray, closed: bool, d: float,
                                   cutoff: float) -> None:
    """Warn (:class:`~stiffknots.errors.ChainWarning`) when the contact distance cannot see
    two strands that touch: contacts are read from bead distances, and two strands a
    distance ``d`` apart (touching) have beads up to ``√(d² + b²/4)`` apart (``b``: the
    longest bond), so a cutoff below that misses touching strands wherever their beads are
    staggered — a thin tube (``d ≪ b``) read at ``d`` shows fewer contacts than it has (8_1's
    4-fold cage at w = 0.08, N = 157: "no contacts"). Read such a chain at a larger ``d``
    (e.g. 0.5, as :mod:`stiffknots.studies.thin_limit` does) or resample it to bonds ≲ 2d."""
    bonds = _bond_lengths(x, closed)
    b = float(bonds.max()) if len(bonds) else 0.0
    need = math.sqrt(d * d + b * b / 4.0)
    if cutoff >= need:
        return
    _warn_at_user_line(f"the contact distance {cutoff:.3g} is below {need:.3g}, the distance "
                       f"of the beads of two strands that touch at d = {d:.3g} with bonds of "
                       f"{b:.3g}: contacts are missed; read the chain at a larger d (e.g. "
                       "0.5) or resample it to bonds of at most about 2d")


# --------------------------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------------------------


def tangents(x: np.ndarray, closed: bool = True) -> np.ndarray:
    """Unit tangents at the beads (central differences; one-sided at the ends of an open
    chain)."""
    if closed:
        t = np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0)
    else:
        t = np.empty_like(x)
        t[1:-1] = x[2:] - x[:-2]
        t[0] = x[1] - x[0]
        t[-1] = x[-1] - x[-2]
    norm = np.linalg.norm(t, axis=1)
    norm[norm == 0.0] = 1.0
    return t / norm[:, None]


def cyclic_runs(mask: np.ndarray, closed: bool = True) -> list[tuple[int, int]]:
    """Maximal runs of True in a boolean array, as ``(start, length)``.

    For a closed chain a run may wrap around the end (``start + length > N``); a mask that is
    all True gives ``[(0, N)]``.
    """
    mask = np.asarray(mask, dtype=bool)
    n = mask.shape[0]
    if n == 0 or not mask.any():
        return []
    if mask.all():
        return [(0, n)]
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    diff = np.diff(padded)
    starts = np.flatnonzero(diff == 1)
    ends = np.flatnonzero(diff == -1)
    runs = [(int(s), int(e - s)) for s, e in zip(starts, ends, strict=True)]
    if closed and len(runs) > 1 and mask[0] and mask[-1]:
        first = runs.pop(0)
        last = runs.pop()
        runs.append((last[0], last[1] + first[1]))
    return runs


def _value_runs(values: np.ndarray, closed: bool) -> list[tuple[int, int, int]]:
    """Maximal runs of equal values: ``(start, length, value)``, wrapping if closed."""
    n = values.shape[0]
    change = np.flatnonzero(values[1:] != values[:-1]) + 1
    if change.size == 0:
        return [(0, n, int(values[0]))]
    bounds = np.concatenate([[0], change, [n]])
    runs = [(int(a), int(b - a), int(values[a])) for a, b in zip(bounds[:-1], bounds[1:],
                                                                  strict=True)]
    if closed and len(runs) > 1 and values[0] == values[-1]:
        first = runs.pop(0)
        last = runs.pop()
        runs.append((last[0], last[1] + first[1], last[2]))
    return runs


def _run_beads(start: int, length: int, n: int) -> np.ndarray:
    return (start + np.arange(length)) % n


def _bond_lengths(x: np.ndarray, closed: bool) -> np.ndarray:
    if closed:
        return np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    return np.linalg.norm(x[1:] - x[:-1], axis=1)


def _run_arc_length(start: int, length: int, bonds: np.ndarray, n: int, closed: bool) -> float:
    """Arc length of a run of beads: its ``length - 1`` inner bonds, or all bonds when the run
    is the whole closed chain."""
    if closed and length >= n:
        return float(bonds.sum())
    if length <= 1:
        return 0.0
    idx = (start + np.arange(length - 1)) % n
    return float(bonds[idx].sum())


class _UnionFind:
    def __init__(self, n: int) -> None:
        self.parent = np.arange(n)

    def find(self, a: int) -> int:
        p = self.parent
        root = a
        while p[root] != root:
            root = p[root]
        while p[a] != root:
            p[a], a = root, p[a]
        return int(root)

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def _group_runs(runs: list[tuple[int, int]], n: int, cmap: ContactMap) -> list[list[int]]:
    """Group runs into components linked by contacts; returns lists of run indices."""
    run_id = np.full(n, -1, dtype=np.int64)
    for k, (s, ln) in enumerate(runs):
        run_id[_run_beads(s, ln, n)] = k
    uf = _UnionFind(len(runs))
    ra, rb = run_id[cmap.i], run_id[cmap.j]
    ok = (ra >= 0) & (rb >= 0) & (ra != rb)
    for a, b in set(zip(ra[ok].tolist(), rb[ok].tolist(), strict=True)):
        uf.union(a, b)
    groups: dict[int, list[int]] = {}
    for k in range(len(runs)):
        groups.setdefault(uf.find(k), []).append(k)
    return [sorted(g) for g in groups.values()]


# --------------------------------------------------------------------------------------------
# local multiplicity
# --------------------------------------------------------------------------------------------


def local_multiplicity(cmap: ContactMap, max_gap: int | None = None) -> np.ndarray:
    """Local multiplicity ``m(s)``: 1 + the number of distinct strands touching bead ``s``.

    The beads in contact with ``s`` are sorted by index and split into strands wherever two
    consecutive ones are more than ``max_gap`` apart (cyclically for a closed chain), so a strand
    passing by counts once however many of its beads touch ``s`` (§V: the ``m`` strands of a
    line-braid of multiplicity ``m``).

    Parameters
    ----------
    cmap : ContactMap
        From :func:`~stiffknots.analysis.contacts.contact_map`.
    max_gap : int, optional
        Largest index gap inside one strand; default ``cmap.min_sep``.

    Returns
    -------
    ndarray of int, shape (N,)
    """
    if not isinstance(cmap, ContactMap):
        raise ValueError(f"local_multiplicity needs a ContactMap (from contact_map()), got "
                         f"{type(cmap).__name__}")
    gap = cmap.min_sep if max_gap is None else int(max_gap)
    if gap < 1:
        raise ValueError(f"max_gap must be an integer >= 1, got {max_gap!r}")
    n = cmap.n
    m = np.ones(n, dtype=np.int64)
    if cmap.n_contacts == 0:
        return m
    src, dst = cmap.directed()
    same = src[1:] == src[:-1]
    jump = same & (np.diff(dst) > gap)
    breaks = np.bincount(src[1:][jump], minlength=n)
    has = np.bincount(src, minlength=n) > 0
    clusters = np.where(has, 1 + breaks, 0)
    if cmap.closed:
        first_pos = np.flatnonzero(np.concatenate([[True], ~same]))
        last_pos = np.concatenate([first_pos[1:] - 1, [src.size - 1]])
        owner = src[first_pos]
        wrap = dst[first_pos] + n - dst[last_pos]
        merge = (wrap <= gap) & (breaks[owner] >= 1)
        clusters[owner[merge]] -= 1
    return m + clusters


# --------------------------------------------------------------------------------------------
# data classes
# --------------------------------------------------------------------------------------------


@dataclass
class LineBraid:
    """A line-braid (§V B): stretches of the chain with constant multiplicity ``m >= 2`` that
    touch each other.

    Attributes
    ----------
    multiplicity : int
        ``m``, the number of strands running together.
    stretches : list of tuple of int
        The stretches, ``(start, length)`` (bead runs, possibly wrapping for a closed chain).
    length : float
        Mean arc length of the stretches (bond units).
    closed : bool
        True when the braid covers the whole closed chain (no ends): the circular braid.
    """

    multiplicity: int
    stretches: list[tuple[int, int]]
    length: float
    closed: bool = False

    def to_dict(self) -> dict:
        return {"multiplicity": self.multiplicity, "stretches": [list(s) for s in self.stretches],
                "length": self.length, "closed": self.closed}


@dataclass
class ContactZone:
    """A connected group of contact runs: a line-braid, a point-braid or a multiple point.

    Attributes
    ----------
    kind : str
        ``"line-braid"``, ``"point-braid"`` or ``"multiple-point"``.
    runs : list of tuple of int
        The runs of beads in contact, ``(start, length)`` (one per strand passage).
    multiplicity : int
        Largest local multiplicity ``m(s)`` in the zone (strands meeting there).
    length : float
        Arc length of the longest run (bond units).
    alignment : float
        Median ``|t_i·t_j|`` over the zone's contacts (1: tangent strands, 0: perpendicular).
    centre : ndarray
        Mean position of its beads, shape ``(3,)``.
    closed : bool
        The zone is the whole closed chain.
    stretches : dict
        ``int`` to ``float``: for each local multiplicity ``m >= 2`` in the zone, the arc length of
        its longest stretch of constant ``m(s) = m`` along one strand (bond units): a two-strand
        braid that a third strand touches at one bead holds ``{2: 29.0, 3: 0.0}``.
    """

    kind: str
    runs: list[tuple[int, int]]
    multiplicity: int
    length: float
    alignment: float
    centre: np.ndarray
    closed: bool = False
    stretches: dict[int, float] = field(default_factory=dict)

    @property
    def strands(self) -> int:
        """Number of strand passages (runs) through the zone."""
        return len(self.runs)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "runs": [list(r) for r in self.runs],
                "multiplicity": self.multiplicity, "length": self.length,
                "alignment": self.alignment, "centre": self.centre.tolist(),
                "closed": self.closed,
                "stretches": {str(k): v for k, v in self.stretches.items()}}


@dataclass
class Node:
    """A node of the structure graph.

    ``kind``: ``"point-braid"``, ``"multiple-point"``, ``"braid-end"`` (an end of a
    line-braid) or ``"chain-end"`` (a free end of an open chain). ``zone``: index of its contact
    zone (``None`` for chain ends). ``beads``: the beads at the node. ``position``: their mean.
    """

    index: int
    kind: str
    zone: int | None
    beads: list[int]
    position: np.ndarray

    def to_dict(self) -> dict:
        return {"index": self.index, "kind": self.kind, "zone": self.zone,
                "beads": list(self.beads), "position": self.position.tolist()}


@dataclass
class Edge:
    """An edge of the structure graph: a line-braid (``multiplicity >= 2``) or a free arc
    (``multiplicity == 1``).

    ``nodes``: the two end nodes (``(None, None)`` for a closed edge without nodes).
    ``stretches``: its bead runs ``(start, length)``. ``length``: arc length per strand.
    """

    index: int
    kind: str
    multiplicity: int
    nodes: tuple[int | None, int | None]
    stretches: list[tuple[int, int]]
    length: float
    zone: int | None = None

    def to_dict(self) -> dict:
        return {"index": self.index, "kind": self.kind, "multiplicity": self.multiplicity,
                "nodes": list(self.nodes), "stretches": [list(s) for s in self.stretches],
                "length": self.length, "zone": self.zone}


@dataclass
class StructureGraph:
    """The structure ``{S}`` of §V B as a multigraph: line-braids and arcs joined at nodes."""

    nodes: list[Node]
    edges: list[Edge]

    def degree(self, node: int) -> int:
        """Number of edge ends at ``node`` (a self-loop counts twice)."""
        return sum((e.nodes[0] == node) + (e.nodes[1] == node) for e in self.edges)

    def counts(self) -> dict[str, int]:
        """Numbers of nodes and edges by kind."""
        out: dict[str, int] = {}
        for nd in self.nodes:
            out[nd.kind] = out.get(nd.kind, 0) + 1
        for e in self.edges:
            key = "line-braid" if e.kind == "line-braid" else "arc"
            out[key] = out.get(key, 0) + 1
        return out

    def summary(self) -> str:
        """One line, e.g. ``"2 point-braid, 4 arc"``."""
        return ", ".join(f"{v} {k}" for k, v in sorted(self.counts().items())) or "empty"

    def to_dict(self) -> dict:
        return {"nodes": [nd.to_dict() for nd in self.nodes],
                "edges": [e.to_dict() for e in self.edges], "summary": self.summary()}


@dataclass
class Structure:
    """Everything :func:`analyse_structure` finds on one chain.

    Attributes
    ----------
    contact_map : ContactMap
    multiplicity : ndarray of int
        Local multiplicity ``m(s)``, shape ``(N,)``.
    line_braids : list of LineBraid
    zones : list of ContactZone
    graph : StructureGraph
    length : float
        Contour length ``L``.
    min_length : float
        The line-braid length threshold used.
    params : dict
        The parameters used (cutoff, min_sep, min_length, tangent_angle).
    """

    contact_map: ContactMap
    multiplicity: np.ndarray
    line_braids: list[LineBraid]
    zones: list[ContactZone]
    graph: StructureGraph
    length: float
    min_length: float
    params: dict = field(default_factory=dict)

    def zone_counts(self) -> dict[str, int]:
        """Numbers of contact zones by kind."""
        out = {"line-braid": 0, "point-braid": 0, "multiple-point": 0}
        for z in self.zones:
            out[z.kind] += 1
        return out

    #: the codes of :meth:`bead_kinds`, in order
    BEAD_KINDS = ("free strand", "line-braid", "point-braid", "multiple point")

    def bead_kinds(self) -> np.ndarray:
        """The contact-zone kind each bead lies in, as codes into :attr:`BEAD_KINDS`: 0 on a
        free strand (``m(s) = 1``, no zone), 1 in a line-braid zone, 2 in a point-braid, 3 in
        a multiple point (§V B; the zones of :func:`analyse_structure`, every run of a zone,
        i.e. every strand passing through it). For a picture of the structure: the 3D views
        of the atlas colour the chain by it."""
        n = len(self.multiplicity)
        kinds = np.zeros(n, dtype=np.int8)
        code = {"line-braid": 1, "point-braid": 2, "multiple-point": 3}
        for z in self.zones:
            for start, length in z.runs:
                kinds[_run_beads(start, length, n)] = code[z.kind]
        return kinds

    @property
    def name(self) -> str:
        """The structure in the words of §V B, e.g. ``"2 line-braids (m = 2) + double
        point"`` (:func:`structure_name`)."""
        return structure_name(self.zones, 3.0 * self.contact_map.cutoff)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "params": dict(self.params),
            "length": self.length,
            "n_contacts": self.contact_map.n_contacts,
            "contact_fraction": float(np.mean(self.multiplicity >= 2)),
            "max_multiplicity": int(self.multiplicity.max()),
            "line_braids": [b.to_dict() for b in self.line_braids],
            "zones": [z.to_dict() for z in self.zones],
            "zone_counts": self.zone_counts(),
            "graph": self.graph.to_dict(),
        }


# --------------------------------------------------------------------------------------------
# names
# --------------------------------------------------------------------------------------------

_POINT_WORDS = {2: "double point", 3: "triple point", 4: "quadruple point"}


def _counted(count: int, singular: str, plural: str, suffix: str = "") -> str:
    return (f"{singular}{suffix}" if count == 1 else f"{count} {plural}{suffix}")


def _braid_multiplicity(z: ContactZone, hold: float | None) -> int:
    """The multiplicity of a line-braid zone: the largest ``m`` that one of its strands holds
    constant over at least ``hold`` (in a flat ribbon of three strands the middle one has
    m = 3 and the outer ones m = 2: it is m = 3; a two-strand braid that a third strand
    touches at a bead or two stays m = 2), else the ``m`` of its longest constant stretch;
    without stretches, its largest ``m``."""
    st = getattr(z, "stretches", None) or {}
    if not st:
        return int(z.multiplicity)
    held = [k for k, v in st.items() if hold is not None and v >= hold]
    return max(held) if held else max(st, key=lambda k: (st[k], k))


def structure_name(zones: list[ContactZone], hold: float | None = None) -> str:
    """Name a structure ``{S}`` (§V B, Figs 5 and 7) by its contact zones, in the paper's
    words: line-braids with their multiplicity ``m``, point-braids, double (triple, …)
    points — e.g. ``"circular line-braid (m = 2)"`` (the trefoil, Fig. 7 a), ``"2
    point-braids"`` (the 4-fold cage, Fig. 7 b), ``"point-braid + 3 double points"`` (the
    80, Fig. 7 c), ``"no contacts"``.

    The line-braids come first (highest ``m`` first; ``circular`` when one covers the whole
    closed chain), then the point-braids (``m`` given when more than two strands meet), then
    the multiple points (by the number of strands meeting). A line-braid's ``m`` is the
    largest local multiplicity one of its strands holds over at least ``hold`` (default of
    :attr:`Structure.name`: three contact distances, the shortest line-braid
    :func:`analyse_structure` allows) — a two-strand braid that a third strand touches at a
    bead or two stays ``m = 2``; a three-strand braid whose strands part and meet again
    (m(s) = 2 and 3 in turn, as on the N = 150 circular braids CB(3)) is ``m = 3`` — or,
    where none is held that long, the one held longest. It names the shapes the
    classifier calls ``other`` (:func:`~stiffknots.analysis.shapes.classify`) and sorts them
    into groups of one structure. At a finite width a point-braid of many crossings can be
    long enough (``min_length``, default 0.1 L) to count as a line-braid, and two double
    points close together as one triple point: the name is that of the chain at its width.

    Parameters
    ----------
    zones : list of ContactZone
        :attr:`Structure.zones`.
    hold : float, optional
        Bond units; None: a line-braid is named by the multiplicity of its longest constant
        stretch.

    Returns
    -------
    str
    """
    parts: list[str] = []
    lines: dict[tuple[bool, int], int] = {}
    points: dict[int, int] = {}
    multis: dict[int, int] = {}
    for z in zones:
        if z.kind == "line-braid":
            key = (bool(z.closed), _braid_multiplicity(z, hold))
            lines[key] = lines.get(key, 0) + 1
        elif z.kind == "point-braid":
            points[int(z.multiplicity)] = points.get(int(z.multiplicity), 0) + 1
        else:
            multis[int(z.multiplicity)] = multis.get(int(z.multiplicity), 0) + 1
    for (closed, m), c in sorted(lines.items(), key=lambda kv: (-kv[0][1], not kv[0][0])):
        first = "circular line-braid" if closed else "line-braid"
        parts.append(_counted(c, first, first + "s", f" (m = {m})"))
    for m, c in sorted(points.items(), key=lambda kv: -kv[0]):
        parts.append(_counted(c, "point-braid", "point-braids",
                              f" (m = {m})" if m > 2 else ""))
    for m, c in sorted(multis.items(), key=lambda kv: -kv[0]):
        word = _POINT_WORDS.get(m, f"{m}-fold point")
        parts.append(_counted(c, word, word + "s"))
    return " + ".join(parts) if parts else "no contacts"


# --------------------------------------------------------------------------------------------
# analysis
# --------------------------------------------------------------------------------------------


def _check_angle(tangent_angle: Any) -> float:
    try:
        a = float(tangent_angle)
    except (TypeError, ValueError):
        raise ValueError(f"tangent_angle must be a number of degrees in (0, 90), got "
                         f"{tangent_angle!r}") from None
    if not 0.0 < a < 90.0:
        raise ValueError(f"tangent_angle must be in (0, 90) degrees, got {tangent_angle!r}")
    return a


def _line_braids(m: np.ndarray, cmap: ContactMap, bonds: np.ndarray, min_length: float,
                 closed: bool) -> list[LineBraid]:
    n = m.shape[0]
    stretches = [(s, ln) for s, ln, v in _value_runs(m, closed)
                 if v >= 2 and _run_arc_length(s, ln, bonds, n, closed) >= min_length]
    if not stretches:
        return []
    out = []
    for group in _group_runs(stretches, n, cmap):
        runs = [stretches[k] for k in group]
        mult = int(m[runs[0][0]])
        lengths = [_run_arc_length(s, ln, bonds, n, closed) for s, ln in runs]
        whole = closed and len(runs) == 1 and runs[0][1] >= n
        out.append(LineBraid(mult, runs, float(np.mean(lengths)), bool(whole)))
    out.sort(key=lambda b: min(s for s, _ in b.stretches))
    return out


def _zones(x: np.ndarray, m: np.ndarray, cmap: ContactMap, bonds: np.ndarray,
           min_length: float, cos_tan: float, closed: bool) -> list[ContactZone]:
    n = x.shape[0]
    runs = cyclic_runs(m >= 2, closed)
    if not runs:
        return []
    t = tangents(x, closed)
    run_id = np.full(n, -1, dtype=np.int64)
    for k, (s, ln) in enumerate(runs):
        run_id[_run_beads(s, ln, n)] = k
    pair_align = np.abs(np.einsum("ij,ij->i", t[cmap.i], t[cmap.j]))
    pair_run = run_id[cmap.i]
    # the longest stretch of constant m(s) = m ≥ 2 in every contact run (each lies in one)
    longest: dict[int, dict[int, float]] = {}
    for s, ln, v in _value_runs(m, closed):
        if v >= 2:
            best = longest.setdefault(int(run_id[s]), {})
            best[v] = max(best.get(v, 0.0), _run_arc_length(s, ln, bonds, n, closed))
    zones = []
    for group in _group_runs(runs, n, cmap):
        zr = [runs[k] for k in group]
        beads = np.concatenate([_run_beads(s, ln, n) for s, ln in zr])
        length = max(_run_arc_length(s, ln, bonds, n, closed) for s, ln in zr)
        sel = np.isin(pair_run, group)
        align = float(np.median(pair_align[sel])) if sel.any() else 1.0
        whole = closed and len(zr) == 1 and zr[0][1] >= n
        if whole or length >= min_length:
            kind = "line-braid"
        elif align >= cos_tan:
            kind = "point-braid"
        else:
            kind = "multiple-point"
        stretches: dict[int, float] = {}
        for k in group:
            for v, a in longest.get(k, {}).items():
                stretches[v] = max(stretches.get(v, 0.0), a)
        zones.append(ContactZone(kind, zr, int(m[beads].max()), float(length), align,
                                 x[beads].mean(axis=0), bool(whole),
                                 dict(sorted(stretches.items()))))
    zones.sort(key=lambda z: min(s for s, _ in z.runs))
    return zones


def _graph(x: np.ndarray, zones: list[ContactZone], m: np.ndarray, bonds: np.ndarray,
           closed: bool) -> StructureGraph:
    n = x.shape[0]
    nodes: list[Node] = []
    edges: list[Edge] = []
    # node attached to the first / last bead of every contact run
    first_node: dict[int, int] = {}
    last_node: dict[int, int] = {}
    for zi, z in enumerate(zones):
        if z.kind != "line-braid":
            beads = sorted(int(b) for s, ln in z.runs for b in _run_beads(s, ln, n))
            nodes.append(Node(len(nodes), z.kind, zi, beads, x[beads].mean(axis=0)))
            for s, ln in z.runs:
                first_node[s] = last_node[(s + ln - 1) % n] = nodes[-1].index
            continue
        if z.closed:
            edges.append(Edge(len(edges), "line-braid", z.multiplicity, (None, None),
                              list(z.runs), z.length, zi))
            continue
        # two ends: orient every run against the longest one
        ref = max(z.runs, key=lambda r: r[1])
        pa, pb = x[ref[0]], x[(ref[0] + ref[1] - 1) % n]
        ends: tuple[list[int], list[int]] = ([], [])
        for s, ln in z.runs:
            e = (s + ln - 1) % n
            direct = np.linalg.norm(x[s] - pa) + np.linalg.norm(x[e] - pb)
            swapped = np.linalg.norm(x[s] - pb) + np.linalg.norm(x[e] - pa)
            a_end, b_end = (s, e) if direct <= swapped else (e, s)
            ends[0].append(a_end)
            ends[1].append(b_end)
        ids = []
        for side in ends:
            nodes.append(Node(len(nodes), "braid-end", zi, sorted(side),
                              x[side].mean(axis=0)))
            ids.append(nodes[-1].index)
        for (s, ln), a_end in zip(z.runs, ends[0], strict=True):
            e = (s + ln - 1) % n
            first_node[s] = ids[0] if a_end == s else ids[1]
            last_node[e] = ids[0] if a_end == e else ids[1]
        lengths = [_run_arc_length(s, ln, bonds, n, closed) for s, ln in z.runs]
        edges.append(Edge(len(edges), "line-braid", z.multiplicity, (ids[0], ids[1]),
                          list(z.runs), float(np.mean(lengths)), zi))
    # free arcs (m = 1) between contact runs
    free = m < 2
    if not closed:
        ends_nodes = []
        for b in (0, n - 1):
            if free[b]:
                nodes.append(Node(len(nodes), "chain-end", None, [b], x[b].copy()))
                ends_nodes.append(nodes[-1].index)
            else:
                ends_nodes.append(None)
    for s, ln in cyclic_runs(free, closed):
        e = (s + ln - 1) % n
        if closed and ln >= n:
            edges.append(Edge(len(edges), "arc", 1, (None, None), [(s, ln)],
                              float(bonds.sum())))
            continue
        if closed:
            u = last_node.get((s - 1) % n)
            v = first_node.get((e + 1) % n)
        else:
            u = last_node.get(s - 1) if s > 0 else ends_nodes[0]
            v = first_node.get(e + 1) if e < n - 1 else ends_nodes[1]
        # the arc includes the bonds joining it to its nodes
        full = ln + (1 if (closed or s > 0) else 0) + (1 if (closed or e < n - 1) else 0)
        start = (s - 1) % n if (closed or s > 0) else s
        length = _run_arc_length(start, min(full, n), bonds, n, closed) if full > 1 else 0.0
        edges.append(Edge(len(edges), "arc", 1, (u, v), [(s, ln)], length))
    return StructureGraph(nodes, edges)


def analyse_structure(coords: Any, closed: bool = True, *, d: float = DEFAULT_D,
                      factor: float = DEFAULT_CONTACT_FACTOR, cutoff: float | None = None,
                      min_sep: int = DEFAULT_MIN_SEP, min_length: float | None = None,
                      tangent_angle: float = DEFAULT_TANGENT_ANGLE) -> Structure:
    """Contacts, local multiplicity, line-braids, contact zones and the structure graph.

    Parameters
    ----------
    coords, closed
        The chain (bead positions, shape (N, 3)) and whether it is closed.
    d, factor, cutoff, min_sep
        Contact rule, see :func:`~stiffknots.analysis.contacts.contact_map`.
    min_length : float, optional
        Shortest line-braid (arc length, bond units); default ``max(3 × cutoff, 0.1 L)``.
    tangent_angle : float, default 35
        Largest angle (degrees) between the strands of a point-braid (§V B: strands leave a
        point-braid tangentially); contacts at wider angles are multiple points.

    Returns
    -------
    Structure

    Warns
    -----
    ChainWarning
        If the chain is not a unit-bond chain obeying the bead rule at ``d`` (bonds within
        ``ANALYSIS_BOND_TOL`` of 1); :func:`stiffknots.checks.check` reports it in full.
    """
    x = as_coords(coords, closed)
    cmap = contact_map(x, closed, d=d, factor=factor, cutoff=cutoff, min_sep=min_sep)
    if warn_unless_model_chain(x, closed, float(d)):  # one warning for a chain that is not
        warn_if_cutoff_misses_contacts(x, closed, float(d), cmap.cutoff)
    bonds = _bond_lengths(x, closed)
    total = float(bonds.sum())
    if min_length is None:
        min_len = max(3.0 * cmap.cutoff, 0.1 * total)
    else:
        try:
            min_len = float(min_length)
        except (TypeError, ValueError):
            raise ValueError(f"min_length must be a non-negative number (bond units), got "
                             f"{min_length!r}") from None
        if not math.isfinite(min_len) or min_len < 0.0:
            raise ValueError(f"min_length must be a non-negative finite number, got "
                             f"{min_length!r}")
    angle = _check_angle(tangent_angle)
    cos_tan = math.cos(math.radians(angle))
    m = local_multiplicity(cmap)
    braids = _line_braids(m, cmap, bonds, min_len, closed)
    zones = _zones(x, m, cmap, bonds, min_len, cos_tan, closed)
    graph = _graph(x, zones, m, bonds, closed)
    params = {"cutoff": cmap.cutoff, "min_sep": cmap.min_sep, "min_length": min_len,
              "tangent_angle": angle}
    return Structure(cmap, m, braids, zones, graph, total, min_len, params)


def line_braids(coords: Any, closed: bool = True, **kwargs: Any) -> list[LineBraid]:
    """The line-braids of a chain (keyword arguments as :func:`analyse_structure`)."""
    return analyse_structure(coords, closed, **kwargs).line_braids


def structure_graph(coords: Any, closed: bool = True, **kwargs: Any) -> StructureGraph:
    """The structure graph of a chain (keyword arguments as :func:`analyse_structure`)."""
    return analyse_structure(coords, closed, **kwargs).graph
