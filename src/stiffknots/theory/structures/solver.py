"""The w = 0 variational problem of a structure (§V B), solved numerically.

A structure is described by a :class:`StructureProblem` (its line-braids as :class:`ArcSpec`,
its junctions, a rough start and the gauge); :func:`solve_structure` minimises its energy
(eq. (17)) at fixed length at doubling resolutions and extrapolates to the continuum. The
named structures are in :mod:`stiffknots.theory.structures.named`.

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
the arc is ::

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
first integral in :func:`~stiffknots.theory.structures.shooting.cage_shooting`), and the sign
of the reduced Hessian on the constraint tangent space tells a minimum from a saddle (at
coarse levels a saddle is left along its negative mode).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.linalg import eigh, null_space
from scipy.optimize import minimize
from scipy.sparse.linalg import spsolve

__all__ = [
    "ArcSpec",
    "DiscreteProblem",
    "LevelSolution",
    "StructureProblem",
    "StructureResult",
    "richardson",
    "solve_structure",
]


# --------------------------------------------------------------------------------------------
# The problem: a structure's line-braids, junctions, start and gauge
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
    guess : ndarray
        Shape ``(M, 3)``: a rough starting curve from the start node to the end node (any length,
        any sampling).
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
class StructureProblem:
    """The w = 0 problem of a structure: line-braids joined at point-braids and multiple points
    (§V B), with the rough start and the gauge :func:`solve_structure` minimises from.

    Attributes
    ----------
    name, description : str
        Short name and one-line description.
    node_names : tuple of str
        Junction labels (``"P (point-braid)"``, ``"X (double point)"``...).
    node_guess : ndarray
        Shape ``(n_nodes, 3)``: starting junction positions.
    dir_guess : ndarray
        Shape ``(n_dirs, 3)``: starting directions (bunch axes, strand tangents at multiple points);
        normalised.
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
class DiscreteProblem:
    """Index layout, energy, constraints and exact derivatives at base resolution ``K``.

    Unknowns ``x``: per arc its interior tangents ``t_1..t_{K_p-1}`` (3 each) then ``l_p``;
    then the junction positions (3 each) and the directions (3 each).
    Constraints ``c(x) = 0``: ``(|t|^2 - 1)/2`` for every interior tangent and free direction,
    the closure of every arc (3 rows), the total length ``sum m_p l_p - 1``, the extra length
    relations and the gauge fixes.
    """

    def __init__(self, s: StructureProblem, K: int):
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

    def refine(self, x: np.ndarray, fine: DiscreteProblem) -> np.ndarray:
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
def _multipliers(prob: DiscreteProblem, x: np.ndarray) -> np.ndarray:
    """Least-squares multipliers: minimise ``|grad E + J^T lam|``."""
    _, g = prob.energy_grad(x)
    J = prob.jacobian(x)
    return spsolve((J @ J.T).tocsc(), -(J @ g))


def _kkt_residual(prob: DiscreteProblem, x: np.ndarray, lam: np.ndarray) -> tuple[float, float]:
    _, g = prob.energy_grad(x)
    J = prob.jacobian(x)
    rd = g + J.T @ lam
    scale = max(1.0, float(np.max(np.abs(g))))
    return float(np.max(np.abs(rd)) / scale), float(np.max(np.abs(prob.constraints(x))))


def _newton(prob: DiscreteProblem, x: np.ndarray, lam: np.ndarray | None = None, *,
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


def _slsqp(prob: DiscreteProblem, x0: np.ndarray, maxiter: int = 600,
           deadline: float | None = None) -> tuple[np.ndarray, dict]:
    """Minimise at the coarsest level with SLSQP from a rough start (analytic gradients);
    stopped after the iteration that passes ``deadline`` (a :func:`time.process_time` time)."""

    def stop(_r):
        if deadline is not None and time.process_time() > deadline:
            raise StopIteration

    def fun(x):
        return prob.energy_grad(x)

    cons = {"type": "eq", "fun": prob.constraints,
            "jac": lambda x: prob.jacobian(x).toarray()}
    # the energy ~ 1/l_p is unbounded below for l_p < 0: keep the lengths positive
    bounds = [(None, None)] * prob.n
    for i in prob.l_idx:
        bounds[i] = (1e-3, 1.0)
    r = minimize(fun, x0, jac=True, constraints=[cons], method="SLSQP", bounds=bounds,
                 options={"maxiter": maxiter, "ftol": 1e-14}, callback=stop)
    timed_out = deadline is not None and time.process_time() > deadline
    return r.x, {"success": bool(r.success) and not timed_out,
                 "message": "stopped at the time budget" if timed_out else str(r.message),
                 "nit": int(r.nit), "budget_hit": timed_out}


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
    ndarray
        (n, k+1) array ``R`` with ``R[j, k]`` the value with ``K^-2, ..., K^-2k`` removed
        using levels ``j-k .. j`` (``nan`` where undefined).
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
    problem: DiscreteProblem = field(repr=False)

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

    structure: StructureProblem
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


def solve_structure(structure: StructureProblem, Ks: Sequence[int] = (16, 32, 64, 128, 256),
                    *, coarse_K: int | None = None, orders: int = 3,
                    stability_K: int | None = None, newton_first: bool = False,
                    coarse_budget_s: float | None = None) -> StructureResult:
    """Minimise a structure's energy (eq. (17)) at fixed length and extrapolate ``K -> inf``.

    Parameters
    ----------
    structure : StructureProblem
    Ks : sequence of int
        Base resolutions, each twice the previous (arc ``p`` has ``weight_p K`` intervals).
    coarse_K : int, optional
        Resolution of the SLSQP search from the rough start (default ``Ks[0] // 2``, at
        least 4); the result is then refined to ``Ks[0]`` and polished by Newton.
    orders : int
        Even powers ``K^-2, K^-4, ...`` removed by Richardson extrapolation.
    stability_K : int, optional
        Level at which to compute the spectrum of the reduced Hessian (dense; keep it small).
    newton_first : bool
        Try Newton from the start before SLSQP at the coarse level (for starts close to the
        structure, such as a chain's own geometry; ``_coarse_minimum``).
    coarse_budget_s : float, optional
        CPU seconds allowed to the coarse SLSQP search (default: no limit); past it the
        search stops and ``coarse["budget_hit"]`` says so (``_coarse_minimum``).

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
    prob = DiscreteProblem(structure, kc)
    x = prob.x_from_curves([a.guess for a in structure.arcs], structure.node_guess,
                           structure.dir_guess)
    x, lam, coarse = _coarse_minimum(prob, x, newton_first=newton_first,
                                     budget_s=coarse_budget_s)
    # refine up to Ks[0]
    while prob.K < Ks[0]:
        fine = DiscreteProblem(structure, 2 * prob.K)
        x = prob.refine(x, fine)
        prob = fine
        if prob.K < Ks[0]:
            x, lam, info = _newton(prob, x)
    levels: list[LevelSolution] = []
    for j, K in enumerate(Ks):
        if j > 0:
            fine = DiscreteProblem(structure, K)
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


def _reduced_spectrum(prob: DiscreteProblem, x: np.ndarray, lam: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenpairs of the Lagrangian's Hessian on the null space ``Z`` of the constraints."""
    J = prob.jacobian(x).toarray()
    H = prob.hessian(x, lam).toarray()
    Z = null_space(J)
    w, V = eigh(Z.T @ H @ Z)
    return w, V, Z


def _coarse_minimum(prob: DiscreteProblem, x: np.ndarray, max_escapes: int = 4,
                    newton_first: bool = False, budget_s: float | None = None
                    ) -> tuple[np.ndarray, np.ndarray, dict]:
    """SLSQP + Newton at the coarse level, leaving saddles along negative curvature.

    A start with a symmetry can lead SLSQP to a saddle that keeps it; if the reduced Hessian
    has a negative eigenvalue, the state is pushed along that eigenvector and minimised again.

    With ``newton_first`` (a start close to the structure, e.g. a chain's own geometry), Newton
    is tried first: if it converges (KKT residual ≤ 1e-10) to a point whose reduced Hessian has
    no negative eigenvalue, that point is a strict local minimum of the discrete problem near
    the start (on the stored 8-crossing states, the one SLSQP reached too) and the dense
    SLSQP (whose cost grows as the cube of the unknowns: minutes for 10 arcs) is skipped;
    otherwise the usual path runs from the start.

    ``budget_s`` bounds the CPU seconds (of this process) of the SLSQP searches, all escapes
    together: past it the search stops after its current iteration, Newton polishes what it
    has, no further escape is tried and ``budget_hit`` says so — the result is then whatever
    Newton reaches, its spectrum reported as usual (a saddle or an unconverged level is
    flagged downstream, never called a minimum).
    """
    deadline = None if budget_s is None else time.process_time() + budget_s
    escapes = 0
    nit = 0
    start_eps = float(prob.energy_grad(x)[0])
    if newton_first:
        xn, lam, newton = _newton(prob, x, maxiter=15)   # quadratic: a near start needs < 10
        if newton["residual"] <= 1e-10:
            w = _reduced_spectrum(prob, xn, lam)[0]
            if w[0] >= -1e-8 * np.max(np.abs(w)):
                return xn, lam, {
                    "success": True, "message": "Newton from the start", "K": prob.K,
                    "nit": 0, "newton_first": True, "budget_hit": False,
                    "start_epsilon": start_eps,
                    "epsilon": float(prob.energy_grad(xn)[0]),
                    "residual": newton["residual"], "saddle_escapes": 0,
                    "lowest_reduced_eigenvalue": float(w[0])}
    while True:
        x, info = _slsqp(prob, x, deadline=deadline)
        nit += info["nit"]
        x, lam, newton = _newton(prob, x)
        w, V, Z = _reduced_spectrum(prob, x, lam)
        if w[0] >= -1e-8 * np.max(np.abs(w)) or escapes >= max_escapes or info["budget_hit"]:
            break
        v = Z @ V[:, 0]
        x = x + 0.1 * v / np.max(np.abs(v))
        prob.renormalise(x)
        escapes += 1
    info.update(K=prob.K, nit=nit, newton_first=False, start_epsilon=start_eps,
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

