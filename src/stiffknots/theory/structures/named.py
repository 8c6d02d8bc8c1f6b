"""The named structures of the thin limit (§V B, §VI A, §VII), as problems for
:func:`~stiffknots.theory.structures.solver.solve_structure`.

``CB(i)``
    :func:`circular_braid`: one closed line-braid of multiplicity ``i``; the minimiser is the
    circle, ``eps_CB = 2 pi^2 i^2`` (eq. (30)).
``80``
    :func:`eighty`: the figure-eight (a closed strand with one double point ``X``) and a circle
    joined tangentially at a point-braid ``P`` on one lobe of the 8 (§VII). Expected
    ``eps_80 = (eps_8^(1/2) + (2 pi^2)^(1/2))^2``.
``PBL(n)``
    :func:`point_braid_loops`: ``2n`` loops at one point-braid, each leaving along ``+-a`` and
    returning along ``-+a`` (§VI A, Fig. 2e), a check of clamped ends:
    ``eps_PBL = 4 n^2 eps_loop`` (eq. (29)).
``4C``
    :func:`four_fold_cage`: two point-braids ``A`` and ``B`` with axes ``a`` and ``b`` joined by
    four arcs of multiplicity 1, one for each pair of sides ``(+-a at A, +-b at B)``: each arc
    is a 3D elastica clamped in position and tangent at both ends. Free: the four arc shapes
    and lengths, ``|AB|`` and the angle between ``a`` and ``b``. The paper (§VII) only bounds
    this energy, ``8 pi^2 < eps*_4C < 129.6``.

The structure has no twist variable. At ``w = 0`` a point-braid has zero length, so the
twists inside it (the "boxes" of the paper's Fig. conjectured_families) cost no energy and
only decide how the strands are connected through it; every cage with given box twists has
the same ``eps*_4C`` (the 4_1 and 5_2 cages share it). Likewise nothing here forbids strands to
pass through each other: the solver minimises over the structure's geometry and the results
report the distances between arcs so that one can check that the minimiser does not change
the knot type.
"""

from __future__ import annotations

import math

import numpy as np

from stiffknots.theory.structures.solver import ArcSpec, StructureProblem

__all__ = ["CAGE_SIDES", "circular_braid", "eighty", "four_fold_cage", "point_braid_loops"]


def circular_braid(i: int) -> StructureProblem:
    """``CB(i)``: one closed line-braid of multiplicity ``i`` (§VI A, (eq. (30))).

    The start is a non-planar wobbly closed curve through a junction ``P`` (held at the origin
    with its tangent fixed along ``x``: the translation and rotation gauge); the minimiser is
    the circle of length ``L/i``, ``eps = 2 pi^2 i^2``.
    """
    if not isinstance(i, int | np.integer) or i < 1:
        raise ValueError(f"the multiplicity i of CB(i) must be an integer >= 1, got {i!r}")
    u = np.linspace(0.0, 2.0 * np.pi, 401)
    # an ellipse with an out-of-plane wobble, through the origin with tangent +x
    crv = np.column_stack([1.6 * np.sin(u), 1.0 - np.cos(u), 0.3 * np.sin(2 * u) ** 2])
    return _one_node(f"CB({i})", f"circular braid: one closed line-braid of multiplicity {i}",
                     "P (a point on the line-braid)",
                     (ArcSpec("braid", 0, 0, 0, 1, 0, 1, multiplicity=int(i), weight=1,
                              guess=crv),))


def _one_node(name: str, description: str, node_name: str, arcs: tuple) -> StructureProblem:
    """A structure of arcs from and to one junction P, fixed at the origin with direction +x
    (the gauge: a rigid motion moves nothing else)."""
    return StructureProblem(name=name, description=description, node_names=(node_name,),
                            node_guess=np.zeros((1, 3)), dir_guess=np.array([[1.0, 0.0, 0.0]]),
                            arcs=arcs, fixed_nodes=(0,), fixed_dirs=(0,))


def _lemniscate(t: np.ndarray) -> np.ndarray:
    d = 1.0 + np.sin(t) ** 2
    return np.column_stack([np.cos(t) / d, np.sin(t) * np.cos(t) / d, np.zeros_like(t)])


def eighty(contact: float = 0.5) -> StructureProblem:
    """``80``: the figure-eight plus a circle joined at a point-braid (§VII).

    The 8 is one closed strand with a double point ``X`` (a multiple point where its two
    strands cross; its two directions there are free) and the point-braid ``P`` on one lobe,
    where the circle touches it tangentially; the circle is a closed line-braid through ``P``
    with the bunch's axis as tangent. The start is a lemniscate of Bernoulli and a circle of the
    wrong size, not the solution. Three arcs carry the 8 (``P -> X``, the far lobe
    ``X -> X``, ``X -> P``), one the circle.

    Parameters
    ----------
    contact : float
        Where ``P`` sits on its lobe: ``l(P->X) / (l(P->X) + l(X->P))`` in ``(0, 1)``, imposed as
        a linear length relation (0.5: the apex). In the continuum the energy does not depend
        on it (the circle and the 8 exert no force on each other, §VII), so it only fixes
        this neutral mode.
    """
    if not 0.0 < contact < 1.0:
        raise ValueError(f"contact must lie in (0, 1), got {contact}")
    # lemniscate: apex (1, 0) at t = 0 with tangent +y, double point at t = pi/2, 3pi/2
    t_c = 0.5 * np.pi * (1.0 - 2.0 * contact)  # roughly the contact point on the right lobe

    def tangent(t: float) -> np.ndarray:
        d = (_lemniscate(np.array([t + 1e-6])) - _lemniscate(np.array([t - 1e-6])))[0]
        return d / np.linalg.norm(d)

    p_arc1 = _lemniscate(np.linspace(t_c, 0.5 * np.pi, 300))
    lobe = _lemniscate(np.linspace(0.5 * np.pi, 1.5 * np.pi, 600))
    p_arc3 = _lemniscate(np.linspace(1.5 * np.pi, 2.0 * np.pi + t_c, 300))
    P = _lemniscate(np.array([t_c]))[0]
    tP = tangent(t_c)
    nP = np.array([tP[1], -tP[0], 0.0])  # outward normal of the right lobe
    R = 0.3  # a circle of the wrong size: l_0 / l_8 = 0.36 (the solution has 0.59)
    th = np.linspace(0.0, 2.0 * np.pi, 600)
    circ = (P + R * nP - R * np.cos(th)[:, None] * nP + R * np.sin(th)[:, None] * tP
            + 0.05 * np.sin(th)[:, None] ** 2 * np.array([0.0, 0.0, 1.0]))  # out of plane
    shift = -P
    nodes = np.vstack([P, np.zeros(3)]) + shift
    arcs = (
        ArcSpec("8: P->X", 0, 1, 0, 1, 1, 1, weight=1, guess=p_arc1 + shift),
        ArcSpec("8: lobe X->X", 1, 1, 1, 1, 2, 1, weight=2, guess=lobe + shift),
        ArcSpec("8: X->P", 1, 0, 2, 1, 0, 1, weight=1, guess=p_arc3 + shift),
        ArcSpec("0: circle", 0, 0, 0, 1, 0, 1, weight=2, guess=circ + shift),
    )
    return StructureProblem(
        name="80",
        description="80: a figure-eight (double point X) and a circle joined at a "
                    "point-braid P",
        node_names=("P (point-braid)", "X (double point of the 8)"),
        node_guess=nodes,
        dir_guess=np.vstack([tP, tangent(0.5 * np.pi), tangent(1.5 * np.pi)]),
        arcs=arcs,
        fixed_nodes=(0,),
        fixed_dirs=(0,),
        length_relations=(((0, 1.0 - contact), (2, -contact)),),
    )


def point_braid_loops(n: int) -> StructureProblem:
    """``PBL(n)``: ``2n`` loops at one point-braid (§VI A, Fig. knot_transformations e).

    Each loop leaves the point-braid ``P`` along one side of its axis and returns along the
    opposite tangent (``n`` loops on each side, so that every strand goes straight through
    ``P``); expected ``eps = 4 n^2 eps_loop`` (eq. (29)). A test of clamped ends: the
    loops meet ``P`` with curvature, like the arcs of the cage.
    """
    if not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"the bridge number n of PBL(n) must be an integer >= 1, got {n!r}")
    u = np.linspace(0.0, 2.0 * np.pi, 400)
    arcs = []
    for k in range(2 * n):
        side = 1 if k % 2 == 0 else -1
        phi = np.pi * (k // 2) / n + 0.3 * k
        e1 = np.array([0.0, np.cos(phi), np.sin(phi)])
        # balloon: leaves P along side * x, returns along -side * x
        y = u * (2.0 * np.pi - u) / (2.0 * np.pi)
        xx = np.sin(u) * (1.0 - np.cos(u)) * 0.5
        crv = side * y[:, None] * np.array([1.0, 0.0, 0.0]) + xx[:, None] * e1
        arcs.append(ArcSpec(f"loop {k + 1} ({'+' if side > 0 else '-'}a)", 0, 0, 0, side, 0,
                            -side, weight=1, guess=crv))
    return _one_node(f"PBL({n})", f"point-braid and {2 * n} loops", "P (point-braid)",
                     tuple(arcs))


#: The four arcs of the cage: (side of A's axis a, side of B's axis b) where each arc leaves.
CAGE_SIDES: tuple[tuple[int, int], ...] = ((1, 1), (1, -1), (-1, 1), (-1, -1))


def four_fold_cage(axis_angle: float | None = None, *, radius: float = 1.0,
                   start_angle: float = 90.0, twist: float = 0.0) -> StructureProblem:
    """``4C``: the 4-fold cage, two point-braids joined by four arcs (§VII, Fig. MC_braids b).

    Point-braid ``A`` (held at the origin, axis ``a`` held along ``x``: the gauge) and
    point-braid ``B`` (position and axis ``b`` free, ``B_y = 0`` fixing the rotation about
    ``a``). Each strand passes through ``A`` tangent to ``a`` and through ``B`` tangent to
    ``b``: arc ``(sa, sb)`` leaves ``A`` on the ``sa a`` side (tangent ``sa a``) and enters ``B``
    from the ``sb b`` side (tangent ``-sb b``), one arc for each of the four pairs of sides, so
    that two arcs leave every side of each point-braid. Each arc is a 3D elastica clamped in
    position and tangent at both ends (multiplicity 1).

    The start is rough: arcs on a sphere with ``A`` and ``B`` at the poles, each sweeping a
    quarter of the azimuth linearly in the polar angle, with the axes ``start_angle`` apart.

    There is no twist variable: at ``w = 0`` the twists inside a point-braid cost nothing and
    only decide how the strands are connected through it, so every cage with given box twists
    (the 4_1 and the 5_2 among them) has this one energy.

    The sides are assigned one arc per pair ``(+-a, +-b)`` (the four quadrants of the cage
    around ``AB``). The other assignment allowed by "two arcs on each side", two arcs
    ``(+a, +b)`` and two ``(-a, -b)``, is not a cage: its minimiser lets one pair shrink and
    the other merge into a doubly covered circle, ``eps -> 8 pi^2`` (the circular braid of
    closed 2-braids).

    Parameters
    ----------
    axis_angle : float, optional
        If given (degrees), ``b`` is held at this angle to ``a`` (a constrained problem used to
        scan the energy against the angle); by default the angle is free.
    radius : float
        Sphere radius of the start (scale free; only the shape matters).
    start_angle : float
        Angle between the axes in the start (degrees), when ``axis_angle`` is None.
    twist : float
        Extra rotation (radians) of the start's arcs about ``AB`` growing along each arc, a
        perturbation used to test that different starts find the same minimum.
    """
    ang = math.radians(axis_angle if axis_angle is not None else start_angle)
    phi = np.linspace(0.0, np.pi, 500)
    arcs = []
    for sa, sb in CAGE_SIDES:
        a0 = 0.0 if sa > 0 else np.pi
        # b = (cos ang, sin ang, 0); the side +b has azimuth ang, -b has ang + pi
        cands = np.array([ang, ang + np.pi, ang - np.pi, ang + 2 * np.pi, ang - 2 * np.pi])
        if sb < 0:
            cands = cands + np.pi
        a1 = cands[np.argmin(np.abs(cands - a0))]
        f = phi / np.pi
        alpha = a0 + (a1 - a0) * f + twist * np.sin(np.pi * f)
        crv = radius * np.column_stack([np.sin(phi) * np.cos(alpha),
                                        np.sin(phi) * np.sin(alpha),
                                        np.cos(phi) - 1.0])
        arcs.append(ArcSpec(f"arc ({'+' if sa > 0 else '-'}a, {'+' if sb > 0 else '-'}b)",
                            0, 1, 0, sa, 1, -sb, weight=1, guess=crv))
    b = np.array([math.cos(ang), math.sin(ang), 0.0])
    return StructureProblem(
        name="4C",
        description="4-fold cage: point-braids A and B joined by four arcs of multiplicity 1",
        node_names=("A (point-braid)", "B (point-braid)"),
        node_guess=np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -2.0 * radius]]),
        dir_guess=np.vstack([[1.0, 0.0, 0.0], b]),
        arcs=tuple(arcs),
        fixed_nodes=(0,),
        fixed_node_coords=() if axis_angle is not None else ((1, 1),),
        fixed_dirs=(0, 1) if axis_angle is not None else (0,),
    )
