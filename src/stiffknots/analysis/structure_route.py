"""The structure route for a state read from a chain: its structure graph turned into the w = 0
variational problem, solved, and checked (§V B).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V B: as w → 0 a knot's shape tends to a
*structure* — line-braids joined at point-braids and multiple points — whose energy
(eq. (17)) is minimised at fixed length. :mod:`stiffknots.theory.structures` solves that
problem for a :class:`~stiffknots.theory.structures.StructureProblem`; the named structures
(CB(i), the 80, the 4-fold cage) are written by hand. :func:`structure_problem` writes the
problem of any chain whose structure graph
(:func:`~stiffknots.analysis.structure.analyse_structure`) has point-braids and multiple
points joined by single strands:

* every point-braid and multiple point is a junction, placed at the mean of its beads;
* a point-braid has one unit *direction* (the bunch's axis, from the tangents of its strands);
  every strand passes through it tangent to that axis, with the sign of its own tangent;
* a multiple point gives every strand through it a direction of its own (a strand keeps its
  tangent through a crossing: angles are forbidden, §V B);
* going once round the chain, each stretch between two consecutive passages is an arc of
  multiplicity 1 from the first junction to the second, leaving along the first passage's
  signed direction and arriving along the second's; its start is the chain's own beads
  (scaled to L = 1), so the solver starts at the state itself, not at a rough guess;
* the gauge: junction 0 held at the origin and its first direction along x (after a rotation
  of the start), junction 1's y coordinate held (rotation about that axis).

A chain whose graph has a line-braid of multiplicity m ≥ 2 (the circular braid, the 80's
braid) or no junction at all is not translated: :class:`StructureRouteError` says which; the
named structures solve those (:func:`stiffknots.theory.structures.structure_energy`).

The start matters: the w = 0 problem of one graph can have several stationary points, and the
Newton polish converges to the one nearest the start. Started from 4_1's `other` chain at the
atlas width (w/L = 0.0047) the solver stops at a saddle (ε = 126.204, one negative mode, a
Richardson error of 0.5); from the same state's chain at w/L = 0.00025 it reaches the minimum,
126.1586 (no negative mode, error 2e-10). The route therefore starts from a state's thinnest
chain, and :attr:`ChainStructure.minimum` says whether it reached a converged minimum.

Since the start is the state's own chain, Newton is tried first at the coarse level
(``newton_first``): where it converges to a point with no negative mode, the dense SLSQP search
is skipped (4_1's `other` from its thinnest chain: 166 → 1.8 CPU s, the same 126.158594);
where it does not, SLSQP runs from the start within :data:`COARSE_BUDGET_S` CPU seconds, then
Newton polishes what it reached; a solution that is not a converged minimum is reported as
such, whatever stopped it.

The solution must keep the knot: at w = 0 strands meet only at the junctions. :func:`solve_chain`
measures the smallest distance between points of two different arcs farther than ``near``
(default 0.03 L) from every junction and flags a solution where two arcs came within ``touch``
(default 10⁻³ L) of each other there — strands that passed through each other or merged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots.analysis.structure import analyse_structure, tangents

__all__ = ["COARSE_BUDGET_S", "StructureRouteError", "ChainStructure", "structure_problem",
           "solve_chain"]

#: CPU seconds of the coarse SLSQP search of one chain's graph when Newton from the chain
#: does not converge: SLSQP is dense, its cost grows as the cube of the unknowns (7_6's
#: 10-arc graph cost most of that knot's 5,094 CPU s in the 8-crossing thin stage and ended
#: at a saddle).
COARSE_BUDGET_S = 120.0


class StructureRouteError(ValueError):
    """A structure graph the route cannot translate yet (the message says why)."""


@dataclass
class ChainStructure:
    """The structure route's answer for one chain.

    Attributes
    ----------
    epsilon, error : float
        The w = 0 energy ε (L = 1, C = 1) extrapolated in the resolution, and its error.
    name : str
        The structure in the words of §V B.
    arcs, junctions : int
        Arcs (multiplicity 1) and junctions of the problem.
    min_arc_distance : float
        Smallest distance (/ L) between two arcs away from their ends.
    keeps_knot : bool
        ``min_arc_distance ≥ touch``: no two strands meet outside the junctions.
    negative_modes : int
        Negative eigenvalues of the reduced Hessian at the coarsest resolution: 0 for a
        minimum; more for a saddle (the start was too far from the structure's minimum).
    details : dict
        Resolutions, energies per level, seconds.
    curves : list of dict
        The solution at the finest resolution, arc by arc: ``points`` (K × 3, L = 1) and
        ``multiplicity`` (strands the arc stands for: a line-braid's or a multiple point's
        shared arcs count more than once).
    """

    epsilon: float
    error: float
    name: str
    arcs: int
    junctions: int
    min_arc_distance: float
    keeps_knot: bool
    negative_modes: int
    details: dict
    curves: list = field(default_factory=list)

    @property
    def minimum(self) -> bool:
        """A minimum (no negative mode) whose extrapolation converged (error ≤ 1e-6 ε)."""
        return self.negative_modes == 0 and self.error <= 1e-6 * abs(self.epsilon)

    def to_dict(self) -> dict:
        return {"epsilon": self.epsilon, "error": self.error, "name": self.name,
                "arcs": self.arcs, "junctions": self.junctions,
                "min_arc_distance": self.min_arc_distance, "keeps_knot": self.keeps_knot,
                "negative_modes": self.negative_modes, "minimum": self.minimum,
                "details": self.details}


def _rotation_to(a: np.ndarray, b: np.ndarray | None) -> np.ndarray:
    """An orthogonal matrix taking unit ``a`` to x and (if given) ``b`` into the x–z plane."""
    e1 = a / np.linalg.norm(a)
    ref = b if b is not None else np.array([0.0, 0.0, 1.0])
    v = ref - (ref @ e1) * e1
    if np.linalg.norm(v) < 1e-9:
        ref = np.array([0.0, 1.0, 0.0]) if abs(e1[1]) < 0.9 else np.array([0.0, 0.0, 1.0])
        v = ref - (ref @ e1) * e1
    e3 = v / np.linalg.norm(v)
    e2 = np.cross(e3, e1)
    return np.vstack([e1, e2, e3])   # rows: new x, y, z


def structure_problem(coords: Any, d: float, *, name: str = "chain",
                      **analyse_kw: Any) -> Any:
    """The w = 0 problem of a closed chain's structure (module docstring).

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        A closed chain (unit bonds), e.g. a state's thinnest chain of a branch.
    d : float
        The contact distance its structure is read at (e.g. ``max(w, 0.5)``, as the branches
        read their shapes).
    name : str
        The problem's name.
    **analyse_kw
        Passed to :func:`~stiffknots.analysis.structure.analyse_structure`.

    Returns
    -------
    StructureProblem

    Raises
    ------
    StructureRouteError
        A line-braid of multiplicity ≥ 2 in the graph, no junction, or fewer than two
        passages.
    """
    from stiffknots.theory.structures import ArcSpec, StructureProblem

    x = np.asarray(coords, dtype=float)
    n = len(x)
    s = analyse_structure(x, True, d=d, **analyse_kw)
    g = s.graph
    braids = [e for e in g.edges if e.multiplicity > 1]
    if braids:
        raise StructureRouteError(
            f"the structure {s.name!r} has a line-braid of multiplicity "
            f"{max(e.multiplicity for e in braids)}: the route translates point-braids and "
            "multiple points joined by single strands (the named circular braids and the 80 "
            "are solved by theory.structures)")
    junctions = [nd for nd in g.nodes if nd.kind in ("point-braid", "multiple-point")]
    if not junctions:
        raise StructureRouteError(f"the structure {s.name!r} has no point-braid or multiple "
                                  "point: nothing to translate")
    t = tangents(x, True)
    passages = []                       # (centre bead, junction, zone kind)
    for j, nd in enumerate(junctions):
        for start, length in s.zones[nd.zone].runs:
            passages.append(((start + length // 2) % n, j))
    passages.sort()
    if len(passages) < 2:
        raise StructureRouteError("fewer than two strand passages through the junctions")
    # directions: one per point-braid, one per passage through a multiple point
    dirs: list[np.ndarray] = []
    pb_dir: dict[int, int] = {}
    pas_dir: list[tuple[int, int]] = []          # (direction, sign) of every passage
    for c, j in passages:
        if junctions[j].kind == "point-braid":
            if j not in pb_dir:
                pb_dir[j] = len(dirs)
                dirs.append(t[c].copy())
            k = pb_dir[j]
            pas_dir.append((k, 1 if float(t[c] @ dirs[k]) >= 0 else -1))
        else:
            pas_dir.append((len(dirs), 1))
            dirs.append(t[c].copy())
    for k in pb_dir.values():            # the axis: the signed mean of its strands' tangents
        members = [t[c] * sg for (c, _), (kk, sg) in zip(passages, pas_dir, strict=True)
                   if kk == k]
        m = np.mean(members, axis=0)
        dirs[k] = m / np.linalg.norm(m)
    node_pos = np.array([x[nd.beads].mean(axis=0) for nd in junctions])
    # gauge: junction 0 at the origin, direction 0 along x, junction 1 in the x-z plane
    rot = _rotation_to(dirs[0], node_pos[1] - node_pos[0] if len(junctions) > 1 else None)
    origin = node_pos[0]
    scale = 1.0 / n                      # unit bonds: L = N → 1

    def place(p: np.ndarray) -> np.ndarray:
        return ((p - origin) @ rot.T) * scale

    arcs = []
    lengths = []
    for k, (c0, j0) in enumerate(passages):
        c1, j1 = passages[(k + 1) % len(passages)]
        span = (c1 - c0) % n or n
        idx = (c0 + np.arange(span + 1)) % n
        lengths.append(span)
        guess = place(x[idx])
        guess[0], guess[-1] = place(node_pos[j0]), place(node_pos[j1])
        d0, s0 = pas_dir[k]
        d1, s1 = pas_dir[(k + 1) % len(passages)]
        arcs.append((f"arc {k} ({j0}→{j1})", j0, j1, d0, s0, d1, s1, guess))
    shortest = min(lengths)
    specs = tuple(ArcSpec(a[0], a[1], a[2], a[3], a[4], a[5], a[6], multiplicity=1,
                          weight=max(1, min(8, round(ln / shortest))), guess=a[7])
                  for a, ln in zip(arcs, lengths, strict=True))
    words = {"point-braid": "point-braid", "multiple-point": "multiple point"}
    return StructureProblem(
        name=name,
        description=f"{s.name}, read from a chain ({len(specs)} arcs)",
        node_names=tuple(f"J{j} ({words[nd.kind]})" for j, nd in enumerate(junctions)),
        node_guess=np.array([place(p) for p in node_pos]),
        dir_guess=np.array([(v / np.linalg.norm(v)) @ rot.T for v in dirs]),
        arcs=specs,
        fixed_nodes=(0,),
        fixed_node_coords=((1, 1),) if len(junctions) > 1 else (),
        fixed_dirs=(0,),
    )


def _arcs_apart(lv: Any, n_arcs: int, n_nodes: int, near: float) -> float:
    """Smallest distance between points of two different arcs of a solution, each farther than
    ``near`` from every junction (inf when no such pair)."""
    nodes = np.array([lv.problem.node(lv.x, k) for k in range(n_nodes)])
    pts, owner = [], []
    for p in range(n_arcs):
        q = lv.positions(p)
        far = np.min(np.linalg.norm(q[:, None, :] - nodes[None, :, :], axis=2), axis=1) > near
        pts.append(q[far])
        owner.append(np.full(int(far.sum()), p))
    if not pts:
        return math.inf
    allp, who = np.vstack(pts), np.concatenate(owner)
    best = math.inf
    for a in range(0, len(allp), 512):
        blk = allp[a:a + 512]
        dist = np.linalg.norm(blk[:, None, :] - allp[None, :, :], axis=2)
        dist[who[a:a + 512, None] == who[None, :]] = np.inf
        best = min(best, float(dist.min()))
    return best


def solve_chain(coords: Any, d: float, *, Ks: tuple[int, ...] = (16, 32, 64, 128),
                near: float = 0.03, touch: float = 1e-3, name: str = "chain",
                coarse_budget_s: float | None = COARSE_BUDGET_S, newton_first: bool = True,
                **analyse_kw: Any) -> ChainStructure:
    """The structure route for a chain: :func:`structure_problem`, solved
    (:func:`~stiffknots.theory.structures.solve_structure`) and checked (module docstring).

    Parameters
    ----------
    coords, d, name, **analyse_kw
        As :func:`structure_problem`.
    Ks : tuple of int, default (16, 32, 64, 128)
        Base resolutions (doubling; an arc has up to 8× as many intervals, in proportion to its
        length on the chain).
    near : float, default 0.03
        Points of the solution within this distance (/ L) of a junction are left out of the
        distance check (strands meet there by construction).
    touch : float, default 1e-3
        Two arcs closer than this (/ L) away from their ends: the solution is flagged.
    coarse_budget_s : float or None, default :data:`COARSE_BUDGET_S`
        CPU seconds for the coarse SLSQP search when Newton from the chain does not converge
        (module docstring); ``details["budget_hit"]`` says when it stopped there.
    newton_first : bool, default True
        Newton from the chain before the coarse search (module docstring); False: the search
        first, as before (for comparisons).

    Returns
    -------
    ChainStructure

    Raises
    ------
    StructureRouteError
        The graph cannot be translated (see :func:`structure_problem`).
    """
    from stiffknots.theory.structures import solve_structure

    prob = structure_problem(coords, d, name=name, **analyse_kw)
    res = solve_structure(prob, Ks, stability_K=Ks[0], newton_first=newton_first,
                          coarse_budget_s=coarse_budget_s)
    lv = res.best
    dmin = _arcs_apart(lv, len(prob.arcs), len(prob.node_names), near)
    return ChainStructure(
        epsilon=float(res.epsilon), error=float(res.error), name=prob.description.split(",")[0],
        arcs=len(prob.arcs), junctions=len(prob.node_names), min_arc_distance=float(dmin),
        keeps_knot=bool(dmin >= touch),
        negative_modes=int((res.stability or {}).get("negative", 0)),
        details={"Ks": list(res.Ks), "epsilon_K": [float(e) for e in res.epsilons],
                 "seconds": float(res.seconds), "tension": float(lv.tension),
                 "newton_first": bool(res.coarse.get("newton_first", False)),
                 "budget_hit": bool(res.coarse.get("budget_hit", False)),
                 "coarse_budget_s": coarse_budget_s},
        curves=[{"points": np.asarray(lv.positions(p), dtype=float),
                 "multiplicity": int(prob.arcs[p].multiplicity)}
                for p in range(len(prob.arcs))])
