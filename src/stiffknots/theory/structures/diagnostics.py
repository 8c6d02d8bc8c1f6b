"""What a solved structure shows: per-arc lengths, energies and forces, the balance at its
point-braids (eq. (24), (25)), and the geometry of the 4-fold cage and of the 80 (§V B, §VII)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from stiffknots.geometry import seg_dist2
from stiffknots.theory.structures.solver import LevelSolution, StructureResult

__all__ = ["arc_distance", "cage_details", "common_details", "eighty_details",
           "end_curvature_vectors"]


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


def arc_distance(P: np.ndarray, Q: np.ndarray, trim: float) -> tuple[float, float, float]:
    """Distance between two arcs without a fraction ``trim`` of each at both ends.

    Returns ``(distance, s_P, s_Q)`` with the arc-length fractions of the closest segments.
    """
    nP, nQ = len(P) - 1, len(Q) - 1
    i0, i1 = int(round(trim * nP)), nP - int(round(trim * nP))
    j0, j1 = int(round(trim * nQ)), nQ - int(round(trim * nQ))
    d, i, j = _polyline_distance(np.ascontiguousarray(P), np.ascontiguousarray(Q),
                                 i0, i1, j0, j1)
    return float(d), (i + 0.5) / nP, (j + 0.5) / nQ


def end_curvature_vectors(T: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided second-order curvature vectors ``dt/ds`` at the two ends of an arc."""
    k0 = (-3.0 * T[0] + 4.0 * T[1] - T[2]) / (2.0 * h)
    k1 = (3.0 * T[-1] - 4.0 * T[-2] + T[-3]) / (2.0 * h)
    return k0 - (k0 @ T[0]) * T[0], k1 - (k1 @ T[-1]) * T[-1]


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
            k0, k1 = end_curvature_vectors(T, h)
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


def common_details(res: StructureResult) -> dict[str, Any]:
    """What every solved structure reports: the Richardson table and errors, the solver's
    effort, each arc's length and energy, the tension and the force balance."""
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


def cage_details(res: StructureResult) -> dict[str, Any]:
    """The 4-fold cage's geometry: ``AB``, the angles of its axes, the arcs' distances and
    azimuths about ``AB``, and the sphere they lie near."""
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
                d, si, sj = arc_distance(pts[i], pts[j], trim)
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


def eighty_details(res: StructureResult) -> dict[str, Any]:
    """The 80's geometry: the length fractions of its circle and its 8, the circle's radius,
    the forces on them and how far the curve leaves a plane."""
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
