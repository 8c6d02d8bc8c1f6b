"""The thin limit ``w = 0`` solved directly: the variational problem of a structure (§V B).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V B: when the tube width ``w -> 0`` a knot
tends to a *structure*, line-braids ``p`` of multiplicity ``m_p`` (``m_p`` strands shrunk onto one
curve, energy ``m_p C/2 int_p kappa^2 ds``) joined at *point-braids* (a braid shrunk to a point:
every strand through it is tangent to one common axis, the bunch rotates freely and costs no
energy) and at plain *multiple points* (strands just cross). Its energy is (eq. (17))

    E_S = sum_p (m_p C / 2) int_p kappa^2 ds,

minimised at fixed total length ``L = sum_p m_p l_p`` through (eq. (18)),
``F_S = sum_p [m_p C/2 int_p kappa^2 + mu m_p int_p ds]``. At equilibrium each ``A_p`` of
(eq. (20)) is constant, the forces balance at every junction, ``sum_{p->B} A_p = 0`` (eq. (24)), and
the curvature vectors of a bunch balance, ``sum_{p in q_B} m_p kappa_p n_p = 0`` (eq. (25)).

This package solves that problem numerically, not through the closed formulas (eq. (27))
and (eq. (28)), which hold only for special structures; those formulas (and Appendix D's
constants) serve as independent checks in the tests.

Modules: :mod:`~.solver` (the discrete problem, its minimisation and the extrapolation to
``K -> inf``), :mod:`~.named` (CB(i), the 80, PBL(n), the 4-fold cage), :mod:`~.shooting`
(the cage checked by shooting), :mod:`~.diagnostics` (what a solution shows) and
:mod:`~.energy` (:func:`structure_energy` by name, with the results it gives).
"""

from stiffknots.theory.structures.energy import STRUCTURE_NAMES, cage_axis_scan, structure_energy
from stiffknots.theory.structures.named import (
    CAGE_SIDES,
    circular_braid,
    eighty,
    four_fold_cage,
    point_braid_loops,
)
from stiffknots.theory.structures.shooting import cage_shooting
from stiffknots.theory.structures.solver import (
    ArcSpec,
    LevelSolution,
    StructureProblem,
    StructureResult,
    richardson,
    solve_structure,
)

__all__ = [
    "ArcSpec",
    "StructureProblem",
    "LevelSolution",
    "StructureResult",
    "STRUCTURE_NAMES",
    "CAGE_SIDES",
    "circular_braid",
    "eighty",
    "point_braid_loops",
    "four_fold_cage",
    "solve_structure",
    "richardson",
    "cage_shooting",
    "cage_axis_scan",
    "structure_energy",
]
