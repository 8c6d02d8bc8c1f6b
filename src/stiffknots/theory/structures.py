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

This module solves that problem numerically, not through the closed formulas (eq. (27))
and (eq. (28)), which hold only for special structures; those formulas (and Appendix D's
constants) serve as independent checks in the tests.

Discretisation
--------------
Line-braid ``p`` has length ``l_p`` (a free variable) and ``K_p = weight_p K`` intervals of
equal length ``h_p = l_p / K_p``; its unknowns are the unit tangents ``t_0 .. t_{K_p}`` at the
nodes ``s_j = j h_p``. The end tangents are not free: at a junction they are ``+-d`` for a
unit *direction* ``d`` of that junction, shared by every strand of a point-braid bunch (its
axis) or by the two arcs of one strand through a multiple point (the strand keeps its tangent:
angles are forbidden, §V B "Structure"). The curve is inextensible: the tangent is a unit
vector at every node and the arc length is ``K_p h_p``; positions are the trapezoidal integral
of the tangent field, ``r_end - r_start = h_p [t_0/2 + t_1 + ... + t_{K_p-1} + t_{K_p}/2]``
(three closure constraints per arc, the junction positions being unknowns), and the energy of
the arc is

    E_p = m_p (C / h_p) sum_j (1 - t_j . t_{j+1}) = m_p (C / 2 h_p) sum_j |t_{j+1} - t_j|^2,

the same bending energy as the paper's Monte Carlo chain (§VII, ``E_d = C sum (1 - u.u')``).
Both the trapezoidal closure and the interval energy are symmetric second-order rules, so the
discrete minimum is ``eps_K = eps + c_1/K^2 + c_2/K^4 + ...`` (a circle of ``K`` sides gives
exactly ``2 pi^2 [sin(pi/K)/(pi/K)]^2``); Richardson extrapolation over ``K, 2K, 4K, ...``
removes these terms one by one. Units: ``C = 1``, ``L = sum_p m_p l_p = 1``, so ``eps = E``.

The minimisation is a constrained problem in ``x = (tangents, lengths, junction positions,
directions)`` with the constraints ``|t|^2 = 1``, closures, total length and gauge fixes. The
coarsest level is minimised by SLSQP (:func:`scipy.optimize.minimize`, analytic gradients)
from a rough start (not the known solution); every level is then polished by Newton's method
on the KKT system with the exact sparse Hessian of the Lagrangian (quadratic convergence, a
tiny proximal shift for exact symmetry modes) and interpolated to the next ``K``. At the
solution the closure multipliers are minus the constant vectors ``A_p`` of (eq. (20)) (the
Euler-Lagrange equation of the arc is ``t'' = -lam_p + nu t``; so (eq. (24)) is the
stationarity in the junction positions), the length multiplier is the tension ``mu``
(``mu = E/L``, (eq. (26)), holds at every ``K`` because the discrete problem is exactly
scale covariant, so it checks the convergence of the KKT solve; the continuum check is the
first integral in :func:`cage_shooting`), and the sign of the reduced Hessian on the
constraint tangent space tells a minimum from a saddle (at coarse levels a saddle is left
along its negative mode).

Structures
----------
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

Results (:func:`structure_energy`, ``K`` up to 256 per unit weight, 512 for the cage)
------------------------------------------------------------------------------------
* ``CB(i)``: ``2 pi^2 i^2`` to ``1e-13`` relative (the discrete minimiser is the regular
  polygon).
* ``80``: ``142.58436822078`` (formula: ``142.584368220781``), error estimate ``2e-10``; circle
  length fraction ``0.372074 = (2 pi^2 / eps_80)^(1/2)``, no force between circle and 8,
  ``|A_8| / mu = alpha_8 = 1.5332``; the energy does not depend on where the circle touches.
* ``PBL(1)``: ``73.3324298`` ``= 4 eps_loop`` to ``6e-10``.
* ``4C``: ``eps*_4C = 126.4724695555 +- 2e-10`` (the shooting of one arc,
  :func:`cage_shooting`, agrees to ``1e-11``), inside the paper's ``(8 pi^2, 129.6)`` and below
  this package's finite-width Monte Carlo (128.4 beads, 126.7 thin tube), so the hierarchy
  (eq. (39)) CB(2) < 4C < 80 < CB(3) < PBL(2) holds. The minimiser has perpendicular axes,
  both perpendicular to ``AB``; ``|AB| = 0.15802 L``; four congruent arcs of length ``L/4``
  (so (eq. (27)) case (iii) applies: ``eps_4C = 16 eps_arc``, ``eps_arc = 7.90449``),
  close to a sphere of radius ``0.0754 L`` (rms deviation 3 %); each arc stays in its own
  quarter wedge around ``AB`` and arcs meet only at ``A`` and ``B`` (two arcs leaving the same
  side separate as ``14.7 s^2 / L``). The reduced Hessian is positive definite (no zero mode
  once the gauge is fixed): a strict local minimum, found from every start tried. Holding the
  axes at ``psi < 90`` degrees costs energy (:func:`cage_axis_scan`: 126.58 at 85, 127.40 at 75,
  129.17 at 60, 131.57 at 45, 134.77 at 30), so perpendicular axes are the optimum.
"""

from __future__ import annotations

import copy
import functools
import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from numba import njit
from scipy.linalg import eigh, null_space
from scipy.optimize import minimize
from scipy.sparse.linalg import spsolve

from stiffknots.geometry import seg_dist2

__all__ = [
    "ArcSpec",
    "Structure",
    "LevelSolution",
    "StructureResult",
    "STRUCTURE_NAMES",
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

#: Names accepted by :func:`structure_energy` (``i``, ``n`` positive integers).
STRUCTURE_NAMES: tuple[str, ...] = ("CB(i)", "80", "4C", "PBL(n)")


# --------------------------------------------------------------------------------------------
# Structure description
# --------------------------------------------------------------------------------------------
@dataclass(eq=False)
class ArcSpec:
    """One line-braid of a structure: a curve from junction ``start`` to junction ``end``.

    Attributes
    ----------
    name : str
        Label used in the results.
    start, end : int
        Junction (node) indices; equal for a closed line-braid.
    start_dir, start_sign : int
        The tangent at ``s = 0`` is ``start_sign * d[start_dir]`` (a unit direction variable).
    end_dir, end_sign : int
        The tangent at ``s = l_p`` is ``end_sign * d[end_dir]``.
    multiplicity : int
        ``m_p``: strands in the line-braid (energy ``m_p C/2 int kappa^2``, length ``m_p l_p``).
    weight : int
        Resolution weight: the arc has ``weight * K`` intervals at level ``K``.
    guess : (M, 3) array
        A rough starting curve from the start node to the end node (any length, any sampling).
    """

    name: str
    start: int
    end: int
    start_dir: int
    start_sign: int
    end_dir: int
    end_sign: int
    multiplicity: int = 1
    weight: int = 1
    guess: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


@dataclass(eq=False)
class Structure:
    """A structure of line-braids joined at point-braids and multiple points (§V B).

    Attributes
    ----------
    name, description : str
        Short name and one-line description.
    node_names : tuple of str
        Junction labels (``"P (point-braid)"``, ``"X (double point)"``...).
    node_guess : (n_nodes, 3) array
        Starting junction positions.
    dir_guess : (n_dirs, 3) array
        Starting directions (bunch axes, strand tangents at multiple points); normalised.
    arcs : tuple of ArcSpec
    fixed_nodes : tuple of int
        Junctions held at their starting position (translation gauge).
    fixed_node_coords : tuple of (int, int)
        ``(node, coordinate)`` pairs held at their starting value (rotation gauge).
    fixed_dirs : tuple of int
        Directions held at their starting value (rotation gauge, or an imposed axis).
    length_relations : tuple of tuple of (int, float)
        Extra linear constraints ``sum coef * l_p = 0`` on the arc lengths.
    """

    name: str
    description: str
    node_names: tuple[str, ...]
    node_guess: np.ndarray
    dir_guess: np.ndarray
    arcs: tuple[ArcSpec, ...]
    fixed_nodes: tuple[int, ...] = ()
    fixed_node_coords: tuple[tuple[int, int], ...] = ()
    fixed_dirs: tuple[int, ...] = ()
    length_relations: tuple[tuple[tuple[int, float], ...], ...] = ()

    def __post_init__(self) -> None:
        self.node_guess = np.asarray(self.node_guess, dtype=float).reshape(-1, 3)
        d = np.asarray(self.dir_guess, dtype=float).reshape(-1, 3)
        self.dir_guess = d / np.linalg.norm(d, axis=1)[:, None]
        for a in self.arcs:
            if not (0 <= a.start < len(self.node_guess) and 0 <= a.end < len(self.node_guess)):
                raise ValueError(f"arc {a.name!r}: node index out of range")
            if not (0 <= a.start_dir < len(d) and 0 <= a.end_dir < len(d)):
                raise ValueError(f"arc {a.name!r}: direction index out of range")
            if a.start_sign not in (-1, 1) or a.end_sign not in (-1, 1):
                raise ValueError(f"arc {a.name!r}: tangent signs must be +1 or -1")
            if a.multiplicity < 1 or a.weight < 1:
                raise ValueError(f"arc {a.name!r}: multiplicity and weight must be >= 1")
            if len(a.guess) < 4:
                raise ValueError(f"arc {a.name!r}: the starting curve needs >= 4 points")


# --------------------------------------------------------------------------------------------
# The discrete problem at one resolution
# --------------------------------------------------------------------------------------------
class _Problem:
    """Index layout, energy, constraints and exact derivatives at base resolution ``K``.

    Unknowns ``x``: per arc its interior tangents ``t_1..t_{K_p-1}`` (3 each) then ``l_p``;
    then the junction positions (3 each) and the directions (3 each).
    Constraints ``c(x) = 0``: ``(|t|^2 - 1)/2`` for every interior tangent and free direction,
    the closure of every arc (3 rows), the total length ``sum m_p l_p - 1``, the extra length
    relations and the gauge fixes.
    """

    def __init__(self, s: Structure, K: int):
        self.s = s
        self.K = K
        self.Kp = [a.weight * K for a in s.arcs]
        off = 0
        self.t_off: list[int] = []
        self.l_idx: list[int] = []
        for kp in self.Kp:
            self.t_off.append(off)
            off += 3 * (kp - 1)
            self.l_idx.append(off)
            off += 1
        self.node_off = off
        off += 3 * len(s.node_guess)
        self.dir_off = off
        off += 3 * len(s.dir_guess)
        self.n = off
        # per arc: variable column of each tangent row and its sign
        self.cols: list[np.ndarray] = []
        self.signs: list[np.ndarray] = []
        for a, kp, to in zip(s.arcs, self.Kp, self.t_off, strict=True):
            cols = np.empty(kp + 1, dtype=np.int64)
            cols[1:kp] = to + 3 * np.arange(kp - 1)
            cols[0] = self.dir_off + 3 * a.start_dir
            cols[kp] = self.dir_off + 3 * a.end_dir
            sg = np.ones(kp + 1)
            sg[0] = a.start_sign
            sg[kp] = a.end_sign
            self.cols.append(cols)
            self.signs.append(sg)
        self.w = [np.r_[0.5, np.ones(kp - 1), 0.5] for kp in self.Kp]
        # constraint rows
        row = 0
        self.norm_cols = np.concatenate(
            [to + 3 * np.arange(kp - 1) for to, kp in zip(self.t_off, self.Kp, strict=True)]
            + [np.array([self.dir_off + 3 * k for k in range(len(s.dir_guess))
                         if k not in s.fixed_dirs], dtype=np.int64)]
        ).astype(np.int64)
        self.norm_row0 = row
        row += len(self.norm_cols)
        self.closure_row0 = row
        row += 3 * len(s.arcs)
        self.length_row = row
        row += 1
        self.rel_row0 = row
        row += len(s.length_relations)
        fix_cols: list[int] = []
        fix_vals: list[float] = []
        for k in s.fixed_nodes:
            for c in range(3):
                fix_cols.append(self.node_off + 3 * k + c)
                fix_vals.append(s.node_guess[k, c])
        for k, c in s.fixed_node_coords:
            fix_cols.append(self.node_off + 3 * k + c)
            fix_vals.append(s.node_guess[k, c])
        for k in s.fixed_dirs:
            for c in range(3):
                fix_cols.append(self.dir_off + 3 * k + c)
                fix_vals.append(s.dir_guess[k, c])
        self.fix_cols = np.array(fix_cols, dtype=np.int64)
        self.fix_vals = np.array(fix_vals)
        self.fix_row0 = row
        row += len(fix_cols)
        self.m = row
        self.mult = np.array([a.multiplicity for a in s.arcs], dtype=float)

    # ---- access ------------------------------------------------------------------------
    def tangents(self, x: np.ndarray, p: int) -> np.ndarray:
        """The ``(K_p + 1, 3)`` tangents of arc ``p`` (end rows are the signed directions)."""
        return x[self.cols[p][:, None] + np.arange(3)] * self.signs[p][:, None]

    def positions(self, x: np.ndarray, p: int) -> np.ndarray:
        """The ``(K_p + 1, 3)`` node positions of arc ``p`` (trapezoidal rule)."""
        a = self.s.arcs[p]
        T = self.tangents(x, p)
        h = x[self.l_idx[p]] / self.Kp[p]
        steps = 0.5 * h * (T[:-1] + T[1:])
        r0 = x[self.node_off + 3 * a.start: self.node_off + 3 * a.start + 3]
        return np.vstack([r0, r0 + np.cumsum(steps, axis=0)])

    def node(self, x: np.ndarray, k: int) -> np.ndarray:
        return x[self.node_off + 3 * k: self.node_off + 3 * k + 3].copy()

    def direction(self, x: np.ndarray, k: int) -> np.ndarray:
        return x[self.dir_off + 3 * k: self.dir_off + 3 * k + 3].copy()

    def lengths(self, x: np.ndarray) -> np.ndarray:
        return x[self.l_idx].copy()

    # ---- energy -----------------------------------------------------------------------
    def arc_energies(self, x: np.ndarray) -> np.ndarray:
        """``E_p = m_p K_p / (2 l_p) sum |t_{j+1} - t_j|^2`` for every arc."""
        out = np.empty(len(self.Kp))
        for p, kp in enumerate(self.Kp):
            D = np.diff(self.tangents(x, p), axis=0)
            out[p] = self.mult[p] * kp / x[self.l_idx[p]] * 0.5 * np.sum(D * D)
        return out

    def energy_grad(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        E = 0.0
        g = np.zeros(self.n)
        for p, kp in enumerate(self.Kp):
            T = self.tangents(x, p)
            ell = x[self.l_idx[p]]
            c = self.mult[p] * kp / ell
            D = np.diff(T, axis=0)
            f = c * 0.5 * np.sum(D * D)
            E += f
            GT = np.zeros_like(T)
            GT[1:] += D
            GT[:-1] -= D
            GT *= c
            np.add.at(g, self.cols[p][:, None] + np.arange(3), GT * self.signs[p][:, None])
            g[self.l_idx[p]] += -f / ell
        return E, g

    # ---- constraints ------------------------------------------------------------------
    def constraints(self, x: np.ndarray) -> np.ndarray:
        s = self.s
        c = np.empty(self.m)
        V = x[self.norm_cols[:, None] + np.arange(3)]
        c[self.norm_row0:self.closure_row0] = 0.5 * (np.sum(V * V, axis=1) - 1.0)
        for p, a in enumerate(s.arcs):
            T = self.tangents(x, p)
            ell = x[self.l_idx[p]]
            rs = x[self.node_off + 3 * a.start: self.node_off + 3 * a.start + 3]
            re_ = x[self.node_off + 3 * a.end: self.node_off + 3 * a.end + 3]
            r = self.closure_row0 + 3 * p
            c[r:r + 3] = re_ - rs - ell / self.Kp[p] * (self.w[p] @ T)
        c[self.length_row] = self.mult @ x[self.l_idx] - 1.0
        for q, rel in enumerate(s.length_relations):
            c[self.rel_row0 + q] = sum(coef * x[self.l_idx[p]] for p, coef in rel)
        c[self.fix_row0:] = x[self.fix_cols] - self.fix_vals
        return c

    def jacobian(self, x: np.ndarray) -> sp.csr_matrix:
        s = self.s
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        # norms
        nn = len(self.norm_cols)
        V = x[self.norm_cols[:, None] + np.arange(3)]
        rows.append(np.repeat(self.norm_row0 + np.arange(nn), 3))
        cols.append((self.norm_cols[:, None] + np.arange(3)).ravel())
        vals.append(V.ravel())
        eye3 = np.arange(3)
        for p, a in enumerate(s.arcs):
            T = self.tangents(x, p)
            ell = x[self.l_idx[p]]
            kp = self.Kp[p]
            r = self.closure_row0 + 3 * p
            # node positions
            for node, sgn in ((a.end, 1.0), (a.start, -1.0)):
                rows.append(r + eye3)
                cols.append(self.node_off + 3 * node + eye3)
                vals.append(np.full(3, sgn))
            # tangents: -(l/K) w_j sign_j I
            coef = -ell / kp * self.w[p] * self.signs[p]
            rows.append(np.tile(r + eye3, kp + 1))
            cols.append((self.cols[p][:, None] + eye3).ravel())
            vals.append(np.repeat(coef, 3))
            # length
            rows.append(r + eye3)
            cols.append(np.full(3, self.l_idx[p]))
            vals.append(-(self.w[p] @ T) / kp)
        rows.append(np.full(len(self.l_idx), self.length_row))
        cols.append(np.array(self.l_idx))
        vals.append(self.mult.copy())
        for q, rel in enumerate(s.length_relations):
            rows.append(np.full(len(rel), self.rel_row0 + q))
            cols.append(np.array([self.l_idx[p] for p, _ in rel]))
            vals.append(np.array([coef for _, coef in rel], dtype=float))
        nf = len(self.fix_cols)
        rows.append(self.fix_row0 + np.arange(nf))
        cols.append(self.fix_cols)
        vals.append(np.ones(nf))
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.m, self.n),
        )

    # ---- Hessian of the Lagrangian E + lam . c ----------------------------------------
    def hessian(self, x: np.ndarray, lam: np.ndarray) -> sp.csr_matrix:
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        e3 = np.arange(3)
        for p, kp in enumerate(self.Kp):
            T = self.tangents(x, p)
            ell = x[self.l_idx[p]]
            c = self.mult[p] * kp / ell
            cp = self.cols[p]
            sg = self.signs[p]
            # tangent-tangent: c * (path Laplacian) (x) I3, with the end signs
            diag = np.full(kp + 1, 2.0 * c)
            diag[0] = diag[-1] = c
            rows.append((cp[:, None] + e3).ravel())
            cols.append((cp[:, None] + e3).ravel())
            vals.append(np.repeat(diag, 3))
            off = -c * sg[:-1] * sg[1:]
            for ra, rb in ((cp[:-1], cp[1:]), (cp[1:], cp[:-1])):
                rows.append((ra[:, None] + e3).ravel())
                cols.append((rb[:, None] + e3).ravel())
                vals.append(np.repeat(off, 3))
            # length-tangent: -G_j / l - (w_j / K_p) lam_closure, times sign_j
            D = np.diff(T, axis=0)
            GT = np.zeros_like(T)
            GT[1:] += D
            GT[:-1] -= D
            GT *= c
            lc = lam[self.closure_row0 + 3 * p: self.closure_row0 + 3 * p + 3]
            HlT = (-GT / ell - np.outer(self.w[p] / kp, lc)) * sg[:, None]
            li = self.l_idx[p]
            tc = (cp[:, None] + e3).ravel()
            rows.append(np.full(tc.size, li))
            cols.append(tc)
            vals.append(HlT.ravel())
            rows.append(tc)
            cols.append(np.full(tc.size, li))
            vals.append(HlT.ravel())
            # length-length
            f = c * 0.5 * np.sum(D * D)
            rows.append(np.array([li]))
            cols.append(np.array([li]))
            vals.append(np.array([2.0 * f / ell**2]))
        # norm multipliers
        nu = lam[self.norm_row0:self.closure_row0]
        nc = (self.norm_cols[:, None] + e3).ravel()
        rows.append(nc)
        cols.append(nc)
        vals.append(np.repeat(nu, 3))
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.n, self.n),
        )

    # ---- building a state -------------------------------------------------------------
    def x_from_curves(self, curves: Sequence[np.ndarray], nodes: np.ndarray,
                      dirs: np.ndarray) -> np.ndarray:
        """Initial unknowns from dense curves: tangents resampled at equal arc length."""
        x = np.zeros(self.n)
        lengths = []
        for p, (crv, kp) in enumerate(zip(curves, self.Kp, strict=True)):
            crv = np.asarray(crv, dtype=float)
            seg = np.diff(crv, axis=0)
            sl = np.linalg.norm(seg, axis=1)
            s_mid = np.cumsum(sl) - 0.5 * sl
            tan = seg / sl[:, None]
            s_nodes = np.linspace(0.0, sl.sum(), kp + 1)[1:-1]
            T = np.column_stack([np.interp(s_nodes, s_mid, tan[:, k]) for k in range(3)])
            T /= np.linalg.norm(T, axis=1)[:, None]
            x[self.t_off[p]: self.t_off[p] + 3 * (kp - 1)] = T.ravel()
            lengths.append(sl.sum())
        lengths = np.array(lengths)
        scale = 1.0 / (self.mult @ lengths)
        x[self.l_idx] = lengths * scale
        x[self.node_off:self.dir_off] = (np.asarray(nodes) * scale).ravel()
        x[self.dir_off:] = np.asarray(dirs).ravel()
        # gauge values are the scaled starting values
        self.fix_vals = x[self.fix_cols].copy()
        return x

    def refine(self, x: np.ndarray, fine: _Problem) -> np.ndarray:
        """Interpolate a solution at ``K`` to ``2K`` (4-point midpoint rule on the tangents)."""
        y = np.zeros(fine.n)
        for p, kp in enumerate(self.Kp):
            T = self.tangents(x, p)
            mid = np.empty((kp, 3))
            mid[:] = 0.5 * (T[:-1] + T[1:])
            if kp >= 3:
                mid[1:-1] = (9.0 * (T[1:-2] + T[2:-1]) - (T[:-3] + T[3:])) / 16.0
            mid /= np.linalg.norm(mid, axis=1)[:, None]
            T2 = np.empty((2 * kp + 1, 3))
            T2[0::2] = T
            T2[1::2] = mid
            y[fine.t_off[p]: fine.t_off[p] + 3 * (2 * kp - 1)] = T2[1:-1].ravel()
            y[fine.l_idx[p]] = x[self.l_idx[p]]
        y[fine.node_off:] = x[self.node_off:]
        fine.fix_vals = self.fix_vals.copy()
        return y

    def renormalise(self, x: np.ndarray) -> None:
        V = x[self.norm_cols[:, None] + np.arange(3)]
        V /= np.linalg.norm(V, axis=1)[:, None]
        x[self.norm_cols[:, None] + np.arange(3)] = V


# --------------------------------------------------------------------------------------------
# Optimisers
# --------------------------------------------------------------------------------------------
def _multipliers(prob: _Problem, x: np.ndarray) -> np.ndarray:
    """Least-squares multipliers: minimise ``|grad E + J^T lam|``."""
    _, g = prob.energy_grad(x)
    J = prob.jacobian(x)
    return spsolve((J @ J.T).tocsc(), -(J @ g))


def _kkt_residual(prob: _Problem, x: np.ndarray, lam: np.ndarray) -> tuple[float, float]:
    _, g = prob.energy_grad(x)
    J = prob.jacobian(x)
    rd = g + J.T @ lam
    scale = max(1.0, float(np.max(np.abs(g))))
    return float(np.max(np.abs(rd)) / scale), float(np.max(np.abs(prob.constraints(x))))


def _newton(prob: _Problem, x: np.ndarray, lam: np.ndarray | None = None, *,
            tol: float = 1e-12, maxiter: int = 40) -> tuple[np.ndarray, np.ndarray, dict]:
    """Newton's method on the KKT system ``grad E + J^T lam = 0``, ``c = 0``.

    Exact sparse Hessian of the Lagrangian, a proximal shift ``1e-10 max|H_ii|`` (so that
    exact symmetry modes, e.g. rotating a circle about its tangent at a junction, leave the
    KKT matrix invertible without moving), backtracking on the KKT residual.
    """
    x = x.copy()
    prob.renormalise(x)
    if lam is None:
        lam = _multipliers(prob, x)
    hist = []
    n = prob.n
    res = sum(_kkt_residual(prob, x, lam))
    for _ in range(maxiter):
        hist.append(res)
        if res < tol:
            break
        _, g = prob.energy_grad(x)
        J = prob.jacobian(x)
        c = prob.constraints(x)
        H = prob.hessian(x, lam)
        shift = 1e-10 * float(np.max(np.abs(H.diagonal())))
        kkt = sp.bmat([[H + shift * sp.identity(n), J.T], [J, None]], format="csc")
        sol = spsolve(kkt, -np.concatenate([g, c]))
        dx, lam_new = sol[:n], sol[n:]
        step = 1.0
        for _ls in range(30):
            xt = x + step * dx
            prob.renormalise(xt)
            lt = lam + step * (lam_new - lam)
            if np.min(xt[prob.l_idx]) <= 0.0:
                step *= 0.5
                continue
            rt = sum(_kkt_residual(prob, xt, lt))
            if rt < res or rt < tol:
                break
            step *= 0.5
        x, lam, res = xt, lt, rt
    return x, lam, {"iterations": len(hist), "residual": res}


def _slsqp(prob: _Problem, x0: np.ndarray, maxiter: int = 600) -> tuple[np.ndarray, dict]:
    """Minimise at the coarsest level with SLSQP from a rough start (analytic gradients)."""

    def fun(x):
        return prob.energy_grad(x)

    cons = {"type": "eq", "fun": prob.constraints,
            "jac": lambda x: prob.jacobian(x).toarray()}
    # the energy ~ 1/l_p is unbounded below for l_p < 0: keep the lengths positive
    bounds = [(None, None)] * prob.n
    for i in prob.l_idx:
        bounds[i] = (1e-3, 1.0)
    r = minimize(fun, x0, jac=True, constraints=[cons], method="SLSQP", bounds=bounds,
                 options={"maxiter": maxiter, "ftol": 1e-14})
    return r.x, {"success": bool(r.success), "message": str(r.message), "nit": int(r.nit)}


# --------------------------------------------------------------------------------------------
# Richardson extrapolation
# --------------------------------------------------------------------------------------------
def richardson(values: Sequence[float], ratio: float = 2.0, orders: int | None = None
               ) -> np.ndarray:
    """Richardson table for ``v_K = v + c_1/K^2 + c_2/K^4 + ...`` at ``K = K_0 ratio^j``.

    Parameters
    ----------
    values : sequence of float
        ``v`` at successive resolutions (each ``ratio`` times finer).
    ratio : float
        Refinement ratio.
    orders : int, optional
        Number of even powers to eliminate (default: all the table allows).

    Returns
    -------
    (n, k+1) array ``R`` with ``R[j, k]`` the value with ``K^-2, ..., K^-2k`` removed using
    levels ``j-k .. j`` (``nan`` where undefined).
    """
    v = np.asarray(values, dtype=float)
    n = len(v)
    k_max = n - 1 if orders is None else min(orders, n - 1)
    R = np.full((n, k_max + 1), np.nan)
    R[:, 0] = v
    for k in range(1, k_max + 1):
        f = ratio ** (2 * k)
        R[k:, k] = R[k:, k - 1] + (R[k:, k - 1] - R[k - 1:-1, k - 1]) / (f - 1.0)
    return R


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------
@dataclass
class LevelSolution:
    """The converged discrete minimiser at one base resolution ``K``."""

    K: int
    epsilon: float
    x: np.ndarray
    lam: np.ndarray
    residual: float
    iterations: int
    problem: _Problem = field(repr=False)

    def positions(self, p: int) -> np.ndarray:
        return self.problem.positions(self.x, p)

    def tangents(self, p: int) -> np.ndarray:
        return self.problem.tangents(self.x, p)

    @property
    def lengths(self) -> np.ndarray:
        return self.problem.lengths(self.x)

    @property
    def tension(self) -> float:
        """``mu``: the multiplier of ``sum m_p l_p = L`` (equals ``E/L``, (eq. (26)))."""
        return float(self.lam[self.problem.length_row])

    def force(self, p: int) -> np.ndarray:
        """Closure multiplier of arc ``p``: ``-A_p``, the constant vector of (eq. (20)) (C = 1)."""
        r = self.problem.closure_row0 + 3 * p
        return self.lam[r:r + 3].copy()


@dataclass
class StructureResult:
    """Extrapolated energy of a structure and the solutions it came from."""

    structure: Structure
    epsilon: float
    error: float
    extrapolation_error: float
    optimiser_error: float
    Ks: list[int]
    epsilons: list[float]
    table: np.ndarray
    levels: list[LevelSolution]
    coarse: dict
    seconds: float
    stability: dict | None = None

    @property
    def best(self) -> LevelSolution:
        return self.levels[-1]


def solve_structure(structure: Structure, Ks: Sequence[int] = (16, 32, 64, 128, 256),
                    *, coarse_K: int | None = None, orders: int = 3,
                    stability_K: int | None = None) -> StructureResult:
    """Minimise a structure's energy (eq. (17)) at fixed length and extrapolate ``K -> inf``.

    Parameters
    ----------
    structure : Structure
    Ks : sequence of int
        Base resolutions, each twice the previous (arc ``p`` has ``weight_p K`` intervals).
    coarse_K : int, optional
        Resolution of the SLSQP search from the rough start (default ``Ks[0] // 2``, at
        least 4); the result is then refined to ``Ks[0]`` and polished by Newton.
    orders : int
        Even powers ``K^-2, K^-4, ...`` removed by Richardson extrapolation.
    stability_K : int, optional
        Level at which to compute the spectrum of the reduced Hessian (dense; keep it small).

    Returns
    -------
    StructureResult
        ``epsilon`` is the extrapolation using all levels; ``extrapolation_error`` the
        larger of its differences to the same-order extrapolation one level coarser and to
        the next-lower-order one; ``optimiser_error`` bounds the KKT residual's effect.
    """
    t0 = time.perf_counter()
    Ks = [int(k) for k in Ks]
    if any(b != 2 * a for a, b in zip(Ks, Ks[1:], strict=False)):
        raise ValueError(f"resolutions must double, got {Ks}")
    kc = coarse_K or max(4, Ks[0] // 2)
    prob = _Problem(structure, kc)
    x = prob.x_from_curves([a.guess for a in structure.arcs], structure.node_guess,
                           structure.dir_guess)
    x, lam, coarse = _coarse_minimum(prob, x)
    # refine up to Ks[0]
    while prob.K < Ks[0]:
        fine = _Problem(structure, 2 * prob.K)
        x = prob.refine(x, fine)
        prob = fine
        if prob.K < Ks[0]:
            x, lam, info = _newton(prob, x)
    levels: list[LevelSolution] = []
    for j, K in enumerate(Ks):
        if j > 0:
            fine = _Problem(structure, K)
            x = prob.refine(x, fine)
            prob = fine
        x, lam, info = _newton(prob, x)
        E = float(prob.energy_grad(x)[0])
        levels.append(LevelSolution(K, E, x, lam, info["residual"], info["iterations"], prob))
    eps = [lv.epsilon for lv in levels]
    R = richardson(eps, 2.0, orders)
    k = R.shape[1] - 1
    best = float(R[-1, k])
    diffs = [abs(best - R[-2, k])] if len(eps) > k + 1 else []
    if k >= 1:
        diffs.append(abs(best - R[-1, k - 1]))
    ext_err = max(diffs) if diffs else float("inf")
    # optimiser: the energy is stationary, so a relative KKT residual r moves it by ~ r E
    opt_err = max(lv.residual for lv in levels) * max(eps)
    stab = None
    if stability_K is not None:
        stab = _stability(levels, stability_K)
    return StructureResult(structure, best, ext_err + opt_err, ext_err, opt_err, Ks, eps, R,
                           levels, coarse, time.perf_counter() - t0, stab)


def _reduced_spectrum(prob: _Problem, x: np.ndarray, lam: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenpairs of the Lagrangian's Hessian on the null space ``Z`` of the constraints."""
    J = prob.jacobian(x).toarray()
    H = prob.hessian(x, lam).toarray()
    Z = null_space(J)
    w, V = eigh(Z.T @ H @ Z)
    return w, V, Z


def _coarse_minimum(prob: _Problem, x: np.ndarray, max_escapes: int = 4
                    ) -> tuple[np.ndarray, np.ndarray, dict]:
    """SLSQP + Newton at the coarse level, leaving saddles along negative curvature.

    A start with a symmetry can lead SLSQP to a saddle that keeps it; if the reduced Hessian
    has a negative eigenvalue, the state is pushed along that eigenvector and minimised again.
    """
    escapes = 0
    nit = 0
    start_eps = float(prob.energy_grad(x)[0])
    while True:
        x, info = _slsqp(prob, x)
        nit += info["nit"]
        x, lam, newton = _newton(prob, x)
        w, V, Z = _reduced_spectrum(prob, x, lam)
        if w[0] >= -1e-8 * np.max(np.abs(w)) or escapes >= max_escapes:
            break
        v = Z @ V[:, 0]
        x = x + 0.1 * v / np.max(np.abs(v))
        prob.renormalise(x)
        escapes += 1
    info.update(K=prob.K, nit=nit, start_epsilon=start_eps,
                epsilon=float(prob.energy_grad(x)[0]),
                residual=newton["residual"], saddle_escapes=escapes,
                lowest_reduced_eigenvalue=float(w[0]))
    return x, lam, info


def _stability(levels: list[LevelSolution], K: int) -> dict:
    """Spectrum of the Hessian of the Lagrangian on the tangent space of the constraints."""
    lv = next((lv for lv in levels if lv.K == K), None)
    if lv is None:
        raise ValueError(f"stability_K={K} must be one of the levels {[v.K for v in levels]}")
    w, _, Z = _reduced_spectrum(lv.problem, lv.x, lv.lam)
    scale = float(np.max(np.abs(w)))
    zero_tol = 1e-7 * scale
    return {
        "K": K,
        "lowest": [float(v) for v in w[:6]],
        "largest": float(w[-1]),
        "negative": int(np.sum(w < -zero_tol)),
        "zero_modes": int(np.sum(np.abs(w) <= zero_tol)),
        "dimension": int(Z.shape[1]),
    }


# --------------------------------------------------------------------------------------------
# Geometry helpers
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _polyline_distance(P, Q, i0, i1, j0, j1):
    """Minimum distance between segments ``P[i0:i1]`` and ``Q[j0:j1]`` of two polylines."""
    best = np.inf
    bi = -1
    bj = -1
    for i in range(i0, i1):
        for j in range(j0, j1):
            d2 = seg_dist2(P[i, 0], P[i, 1], P[i, 2], P[i + 1, 0], P[i + 1, 1], P[i + 1, 2],
                           Q[j, 0], Q[j, 1], Q[j, 2], Q[j + 1, 0], Q[j + 1, 1], Q[j + 1, 2])
            if d2 < best:
                best = d2
                bi = i
                bj = j
    return np.sqrt(best), bi, bj


def _arc_distance(P: np.ndarray, Q: np.ndarray, trim: float) -> tuple[float, float, float]:
    """Distance between two arcs without a fraction ``trim`` of each at both ends.

    Returns ``(distance, s_P, s_Q)`` with the arc-length fractions of the closest segments.
    """
    nP, nQ = len(P) - 1, len(Q) - 1
    i0, i1 = int(round(trim * nP)), nP - int(round(trim * nP))
    j0, j1 = int(round(trim * nQ)), nQ - int(round(trim * nQ))
    d, i, j = _polyline_distance(np.ascontiguousarray(P), np.ascontiguousarray(Q),
                                 i0, i1, j0, j1)
    return float(d), (i + 0.5) / nP, (j + 0.5) / nQ


def _curvature_vectors(T: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided second-order curvature vectors ``dt/ds`` at the two ends of an arc."""
    k0 = (-3.0 * T[0] + 4.0 * T[1] - T[2]) / (2.0 * h)
    k1 = (3.0 * T[-1] - 4.0 * T[-2] + T[-3]) / (2.0 * h)
    return k0 - (k0 @ T[0]) * T[0], k1 - (k1 @ T[-1]) * T[-1]


# --------------------------------------------------------------------------------------------
# The structures
# --------------------------------------------------------------------------------------------
def circular_braid(i: int) -> Structure:
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


def _one_node(name: str, description: str, node_name: str, arcs: tuple) -> Structure:
    """A structure of arcs from and to one junction P, fixed at the origin with direction +x
    (the gauge: a rigid motion moves nothing else)."""
    return Structure(name=name, description=description, node_names=(node_name,),
                     node_guess=np.zeros((1, 3)), dir_guess=np.array([[1.0, 0.0, 0.0]]),
                     arcs=arcs, fixed_nodes=(0,), fixed_dirs=(0,))


def _lemniscate(t: np.ndarray) -> np.ndarray:
    d = 1.0 + np.sin(t) ** 2
    return np.column_stack([np.cos(t) / d, np.sin(t) * np.cos(t) / d, np.zeros_like(t)])


def eighty(contact: float = 0.5) -> Structure:
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
    return Structure(
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


def point_braid_loops(n: int) -> Structure:
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
                   start_angle: float = 90.0, twist: float = 0.0) -> Structure:
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
    return Structure(
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


# --------------------------------------------------------------------------------------------
# Diagnostics
# --------------------------------------------------------------------------------------------
def _bunch_balance(lv: LevelSolution) -> dict[str, float]:
    """Residual of (eq. (25)) and (eq. (24)) at every point-braid, relative to their terms.

    Bunch torque: a strand end with outward tangent ``sigma a`` contributes ``sigma m kappa n``;
    force: closure multipliers ``A_p`` summed with ``+`` at the end, ``-`` at the start.
    """
    s, prob = lv.problem.s, lv.problem
    out: dict[str, float] = {}
    for k, name in enumerate(s.node_names):
        if "point-braid" not in name:
            continue
        torque = np.zeros(3)
        size = 0.0
        force = np.zeros(3)
        fsize = 0.0
        for p, a in enumerate(s.arcs):
            T = lv.tangents(p)
            h = lv.lengths[p] / prob.Kp[p]
            k0, k1 = _curvature_vectors(T, h)
            A = lv.force(p)
            if a.start == k:
                torque -= a.multiplicity * a.start_sign * k0
                size += a.multiplicity * np.linalg.norm(k0)
                force -= A
                fsize += np.linalg.norm(A)
            if a.end == k:
                torque += a.multiplicity * a.end_sign * k1
                size += a.multiplicity * np.linalg.norm(k1)
                force += A
                fsize += np.linalg.norm(A)
        out[f"{name}: |sum m kappa n| / sum |m kappa n|"] = float(
            np.linalg.norm(torque) / max(size, 1e-300))
        out[f"{name}: |sum A_p| / sum |A_p|"] = float(np.linalg.norm(force) / max(fsize, 1e-300))
    return out


def _common_details(res: StructureResult) -> dict[str, Any]:
    lv = res.best
    arcs = res.structure.arcs
    E_p = lv.problem.arc_energies(lv.x)
    ell = lv.lengths
    return {
        "richardson_table": [[None if math.isnan(v) else float(v) for v in row]
                             for row in res.table],
        "epsilon_K": dict(zip(res.Ks, res.epsilons, strict=True)),
        "extrapolation_error": res.extrapolation_error,
        "optimiser_error": res.optimiser_error,
        "kkt_residual": max(v.residual for v in res.levels),
        "newton_iterations": [v.iterations for v in res.levels],
        "coarse_search": res.coarse,
        "seconds": res.seconds,
        "arcs": {
            a.name: {
                "multiplicity": a.multiplicity,
                "length": float(ell[p]),
                "energy": float(E_p[p]),
                # eps_p = E_p l_p / (m_p C): normalised energy of the line-braid (App. C)
                "epsilon_p": float(E_p[p] * ell[p] / a.multiplicity),
                "force_A_over_mu": float(np.linalg.norm(lv.force(p)) / lv.tension),
            } for p, a in enumerate(arcs)
        },
        "tension_mu": lv.tension,
        "mu_minus_E_over_L": lv.tension - lv.epsilon,
        "balance": _bunch_balance(lv),
        "stability": res.stability,
    }


def _cage_details(res: StructureResult) -> dict[str, Any]:
    lv = res.best
    prob = lv.problem
    A = prob.node(lv.x, 0)
    B = prob.node(lv.x, 1)
    a = prob.direction(lv.x, 0)
    b = prob.direction(lv.x, 1)
    ab = B - A
    dAB = float(np.linalg.norm(ab))
    e = ab / dAB

    def line_angle(u, v):
        return math.degrees(math.acos(min(1.0, abs(float(u @ v)))))

    pts = [lv.positions(p) for p in range(len(res.structure.arcs))]
    names = [s.name for s in res.structure.arcs]
    dist = {}
    for trim in (0.05, 0.15):
        d_pairs = {}
        for i in range(4):
            for j in range(i + 1, 4):
                d, si, sj = _arc_distance(pts[i], pts[j], trim)
                d_pairs[f"{names[i]} / {names[j]}"] = {"distance": d, "s_i": si, "s_j": sj}
        dist[f"without {trim:.0%} of each end"] = d_pairs
    # azimuth of every arc about the axis AB, in the frame (a_perp, e x a_perp)
    e1 = a - (a @ e) * e
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(e, e1)
    sectors = {}
    for p, P in enumerate(pts):
        rel = P[1:-1] - A
        az = np.degrees(np.unwrap(np.arctan2(rel @ e2, rel @ e1)))
        rho = np.linalg.norm(rel - np.outer(rel @ e, e), axis=1)
        sectors[names[p]] = {"azimuth_min": float(az.min()), "azimuth_max": float(az.max()),
                             "min_distance_to_axis_AB": float(rho.min())}
    return {
        "AB_over_L": dAB,
        "axis_angle_deg": line_angle(a, b),
        "angle_a_AB_deg": line_angle(a, e),
        "angle_b_AB_deg": line_angle(b, e),
        "arc_lengths_over_L": [float(v) for v in lv.lengths],
        "arc_distances": dist,
        "arc_azimuths_about_AB_deg": sectors,
        "sphere_fit": _sphere_fit(np.vstack(pts)),
    }


def _sphere_fit(P: np.ndarray) -> dict[str, float]:
    """Least-squares sphere through all arc points (the MC picture: a cage around a sphere)."""
    A = np.column_stack([2.0 * P, np.ones(len(P))])
    rhs = np.sum(P * P, axis=1)
    sol, *_ = np.linalg.lstsq(A, rhs, rcond=None)
    c = sol[:3]
    R = math.sqrt(sol[3] + c @ c)
    dev = np.linalg.norm(P - c, axis=1) - R
    return {"radius_over_L": R, "rms_deviation_over_R": float(np.sqrt(np.mean(dev**2)) / R)}


def _eighty_details(res: StructureResult) -> dict[str, Any]:
    lv = res.best
    ell = lv.lengths
    l8 = float(ell[0] + ell[1] + ell[2])
    circ = lv.positions(3)
    pts = np.vstack([lv.positions(p) for p in range(4)])
    normal = np.linalg.svd(pts - pts.mean(axis=0))[2][-1]
    z_extent = float(np.ptp(pts @ normal))
    return {
        "length_fraction_circle": float(ell[3]),
        "length_fraction_eight": l8,
        "contact_fraction_on_lobe": float(ell[0] / (ell[0] + ell[2])),
        "circle_radius_over_L": float(np.max(np.linalg.norm(circ - circ.mean(axis=0), axis=1))),
        "force_on_circle_over_mu": float(np.linalg.norm(lv.force(3)) / lv.tension),
        "force_8_over_mu": [float(np.linalg.norm(lv.force(p)) / lv.tension) for p in range(3)],
        "out_of_plane_extent_over_L": z_extent,
    }


def cage_shooting(level: LevelSolution | None = None) -> dict[str, Any]:
    """Independent check of the cage: shooting on the continuum elastica of one arc.

    At the cage's minimiser (perpendicular axes, both perpendicular to ``AB``; see
    :func:`four_fold_cage`) the four arcs are images of one another under the mirror planes
    through ``AB``, so the structure reduces to one arc of length ``L/4`` with
    ``eps_4C = 4 E_arc L / C``. In the frame ``A = 0``, ``a = x``, ``B = (0, 0, -d)``, ``b = y``,
    the arc leaving ``A`` along ``+x`` and entering ``B`` along ``-y`` solves the twist-free
    3D elastica with a constant force ``N`` (``-A_p`` of (eq. (20))),

        t'' = -N + (N.t - kappa^2) t,    r' = t,

    from ``r(0) = 0``, ``t(0) = x``, ``t'(0) = (0, k_y, k_z)``. The four unknowns
    ``(k_y, k_z, N_x, N_y)`` (``N = -A_p``) are fixed by ``r_x(l) = r_y(l) = 0`` and
    ``t(l) = -y``;
    ``N_z = 0`` is (eq. (24)) at ``A`` (the four images of ``N`` sum to ``(0, 0, 4 N_z)``),
    which is also the stationarity in ``d``; (eq. (25)) holds by the mirror symmetry.
    Integration by DOP853 (rtol 1e-13), root by :func:`scipy.optimize.fsolve`.

    Parameters
    ----------
    level : LevelSolution, optional
        A discrete cage solution whose end curvature and force start the root search
        (default: the finest level of :func:`structure_energy` ``("4C")``'s solve, recomputed).

    Returns
    -------
    dict
        ``epsilon`` (``4 E_arc`` at ``L = 1``), ``AB_over_L`` (``d``), ``curvature_at_A``
        (``|t'(0)|``), ``force_over_mu``, ``mu`` (from the first integral
        ``mu = kappa^2/2 - N.t``, constant along the arc), ``mu_spread`` (its variation along
        the arc, a check of the integration), ``residual`` (boundary conditions).
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import fsolve

    if level is None:
        level = solve_structure(four_fold_cage(), (16, 32, 64)).best
    prob = level.problem
    A = prob.node(level.x, 0)
    B = prob.node(level.x, 1)
    ex = prob.direction(level.x, 0)
    ez = (A - B) / np.linalg.norm(A - B)
    ex = ex - (ex @ ez) * ez
    ex /= np.linalg.norm(ex)
    ey = np.cross(ez, ex)
    Rm = np.vstack([ex, ey, ez])  # rows: the shooting frame
    # the arc leaving +a whose end tangent is -y in this frame
    p = next(q for q, a in enumerate(prob.s.arcs)
             if a.start_sign > 0 and (Rm @ level.tangents(q)[-1])[1] < 0)
    ell = float(level.lengths[p])
    h = ell / prob.Kp[p]
    k0, _ = _curvature_vectors(level.tangents(p), h)
    k0 = Rm @ k0
    N0 = Rm @ level.force(p)
    u0 = np.array([k0[1], k0[2], N0[0], N0[1]])

    def rhs(_s, y, N):
        t, tp = y[3:6], y[6:9]
        k2 = tp @ tp
        return np.concatenate([t, tp, -N + (N @ t - k2) * t, [0.5 * k2]])

    def shoot(u):
        N = np.array([u[2], u[3], 0.0])
        y0 = np.zeros(10)
        y0[3] = 1.0
        y0[7], y0[8] = u[0], u[1]
        sol = solve_ivp(rhs, (0.0, ell), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                        args=(N,), dense_output=True)
        return sol, N

    def resid(u):
        sol, _ = shoot(u)
        y = sol.y[:, -1]
        return np.array([y[0], y[1], y[3], y[5]])

    u, _info, ier, msg = fsolve(resid, u0, xtol=1e-14, full_output=True)
    sol, N = shoot(u)
    ss = np.linspace(0.0, ell, 201)
    Y = sol.sol(ss)
    k2 = np.sum(Y[6:9] ** 2, axis=0)
    mu_s = 0.5 * k2 + N @ Y[3:6]  # (eq. (21)) with A_p = -N
    E_arc = float(sol.y[9, -1])
    eps = 4.0 * E_arc  # four congruent arcs, L = 4 l = 1
    return {
        "epsilon": eps,
        "AB_over_L": float(-sol.y[2, -1]),
        "curvature_at_A": float(np.hypot(u[0], u[1])),
        "curvature_vector_at_A": [0.0, float(u[0]), float(u[1])],
        "force": [float(v) for v in N],
        "force_over_mu": float(np.linalg.norm(N) / np.mean(mu_s)),
        "mu": float(np.mean(mu_s)),
        "mu_spread": float(np.ptp(mu_s)),
        "end_tangent": [float(v) for v in sol.y[3:6, -1]],
        "residual": float(np.max(np.abs(resid(u)))),
        "converged": ier == 1,
        "message": str(msg),
    }


def cage_axis_scan(angles: Sequence[float] = (30.0, 45.0, 60.0, 75.0, 90.0),
                   Ks: Sequence[int] = (16, 32, 64)) -> list[dict[str, Any]]:
    """Cage energy with the angle between the point-braid axes held fixed.

    For each angle ``psi`` the axis ``b`` is held at ``psi`` to ``a`` (both held; ``B`` free),
    everything else is minimised as in :func:`solve_structure` and extrapolated over ``Ks``
    (two Richardson orders). Slow: SLSQP at the coarse level needs up to about a minute per
    angle.

    Returns
    -------
    list of dict
        Per angle: ``axis_angle_deg``, ``epsilon``, ``error``, ``angle_a_AB_deg``,
        ``angle_b_AB_deg``, ``AB_over_L``, ``arc_lengths_over_L``, ``negative_modes`` (of the
        reduced Hessian at ``Ks[0]``; 0 for a local minimum of the constrained problem).
    """
    out = []
    for psi in angles:
        res = solve_structure(four_fold_cage(axis_angle=float(psi)), Ks, orders=2,
                              stability_K=Ks[0])
        d = _cage_details(res)
        out.append({
            "axis_angle_deg": float(psi),
            "epsilon": res.epsilon,
            "error": res.error,
            "angle_a_AB_deg": d["angle_a_AB_deg"],
            "angle_b_AB_deg": d["angle_b_AB_deg"],
            "AB_over_L": d["AB_over_L"],
            "arc_lengths_over_L": d["arc_lengths_over_L"],
            "negative_modes": res.stability["negative"] if res.stability else None,
        })
    return out


# --------------------------------------------------------------------------------------------
# Public entry
# --------------------------------------------------------------------------------------------
_CB = re.compile(r"^CB\((\d+)\)$")
_PBL = re.compile(r"^PBL\((\d+)\)$")

# (resolutions, Richardson orders, level of the stability check)
_CB_LEVELS = (16, 32, 64, 128, 256)
_EIGHTY_LEVELS = (16, 32, 64, 128, 256)
_PBL_LEVELS = (16, 32, 64, 128, 256)
_CAGE_LEVELS = (16, 32, 64, 128, 256, 512)


def _method(res: StructureResult) -> str:
    w = [a.weight for a in res.structure.arcs]
    return (
        "line-braids as unit tangents at equally spaced nodes (weight*K intervals per arc, "
        f"weights {w}), energy m/h sum(1 - t.t'), trapezoidal closure; SLSQP at K="
        f"{res.coarse['K']} from a rough start, then Newton-KKT with the exact sparse Hessian "
        f"at K = {', '.join(map(str, res.Ks))}; Richardson extrapolation in 1/K^2 "
        f"({res.table.shape[1] - 1} orders); error = |difference to the extrapolation one level "
        "coarser and one order lower| + KKT residual x eps"
    )


def _result_dict(res: StructureResult, details: dict[str, Any]) -> dict[str, Any]:
    return {
        "epsilon": res.epsilon,
        "error": res.error,
        "method": _method(res),
        "structure": res.structure.description,
        "K": list(res.Ks),
        "details": details,
    }


@functools.lru_cache(maxsize=32)
def _structure_energy(name: str) -> dict[str, Any]:
    m = _CB.match(name)
    if m and int(m.group(1)) >= 1:
        i = int(m.group(1))
        res = solve_structure(circular_braid(i), _CB_LEVELS, orders=3, stability_K=16)
        return _result_dict(res, _common_details(res) | {"closed_form": 2.0 * math.pi**2 * i * i})
    m = _PBL.match(name)
    if m and int(m.group(1)) >= 1:
        n = int(m.group(1))
        res = solve_structure(point_braid_loops(n), _PBL_LEVELS, orders=3, stability_K=16)
        return _result_dict(res, _common_details(res))
    if name == "80":
        res = solve_structure(eighty(), _EIGHTY_LEVELS, orders=3, stability_K=16)
        return _result_dict(res, _common_details(res) | _eighty_details(res))
    if name == "4C":
        res = solve_structure(four_fold_cage(), _CAGE_LEVELS, orders=3, stability_K=16)
        return _result_dict(res, _common_details(res) | _cage_details(res)
                            | {"shooting": cage_shooting(res.best)})
    raise ValueError(
        f"unknown structure {name!r}: the names are 'CB(i)' (i = 1, 2, 3, ...), '80', '4C' "
        "and 'PBL(n)' (n = 1, 2, ...)"
    )


def structure_energy(name: str) -> dict[str, Any]:
    """Normalised energy ``eps = E L / C`` of a structure at ``w = 0``, solved directly (§V B).

    Parameters
    ----------
    name : str
        ``"CB(i)"`` (circular braid of multiplicity ``i >= 1``), ``"80"``, ``"4C"`` (the
        4-fold cage) or ``"PBL(n)"`` (point-braid and ``2n`` loops).

    Returns
    -------
    dict
        ``epsilon`` (extrapolated), ``error`` (extrapolation + optimiser estimate), ``method``,
        ``structure`` (short description), ``K`` (base resolutions), ``details`` (Richardson
        table, per-arc lengths/energies/forces, tension check ``mu = E/L``, balance residuals
        of (eq. (24)) and (eq. (25)), reduced-Hessian spectrum, and per structure: cage
        geometry and arc distances; the 80's length fractions and contact force). Cached;
        seconds for CB, PBL and 80, about a minute for 4C on one core.

    Raises
    ------
    ValueError
        For any other name, listing the accepted ones.
    """
    if not isinstance(name, str):
        raise ValueError(f"structure name must be a string, got {name!r}")
    return copy.deepcopy(_structure_energy(name.strip()))
