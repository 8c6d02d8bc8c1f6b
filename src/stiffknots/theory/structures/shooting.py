"""An independent check of the 4-fold cage's energy: shooting on the continuum elastica of one
of its arcs (§V B, §VII)."""

from __future__ import annotations

from typing import Any

import numpy as np

from stiffknots.theory.structures.diagnostics import end_curvature_vectors
from stiffknots.theory.structures.named import four_fold_cage
from stiffknots.theory.structures.solver import LevelSolution, solve_structure

__all__ = ["cage_shooting"]


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
        (default: the finest level of :func:`.structure_energy` ``("4C")``'s solve, recomputed).

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
    k0, _ = end_curvature_vectors(level.tangents(p), h)
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
