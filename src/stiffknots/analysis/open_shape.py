"""The shape of an open knot under tension (paper §VIII): the open trefoil is a planar circle
tangent to the straight line of its ends (μ* = 2π²C/L_e², Fig. 9)."""

from __future__ import annotations

import numpy as np

__all__ = ["open_shape"]


def _fit_circle(pts: np.ndarray):
    """Plane (SVD) and circle (algebraic least squares in the plane) through ``pts``."""
    c0 = pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(pts - c0, full_matrices=False)
    e1, e2, normal = vt
    u = (pts - c0) @ e1
    v = (pts - c0) @ e2
    a = np.column_stack([u, v, np.ones_like(u)])
    sol, *_ = np.linalg.lstsq(a, u * u + v * v, rcond=None)
    cu, cv = sol[0] / 2, sol[1] / 2
    radius = float(np.sqrt(max(sol[2] + cu * cu + cv * cv, 1e-300)))
    return c0 + cu * e1 + cv * e2, radius, normal, e1, e2


def open_shape(coords: np.ndarray, axis_distance: float = 2.0) -> dict:
    """Recognise the open trefoil's shape: a planar circular loop tangent to the straight ends.

    The beads farther than ``axis_distance`` from the z axis (the line of the clamped ends)
    give a first plane (SVD) and circle (algebraic least squares); every bead within
    0.1 R + 1 of that circle, in its plane, is then a loop bead, and the fit is repeated on
    them. The shape is ``"loop"`` when all hold:

    * planarity: RMS distance of loop beads from the plane < 0.1 R;
    * roundness: RMS deviation from the circle < 0.05 R;
    * closure: the loop beads cover ≥ 90 % of the circle's angles (in 10° bins);
    * tangency: the z axis lies in the loop's plane (``|n·ẑ| < 0.25``) and passes at distance
      D from the centre with ``|D/R − 1| < 0.5``. In the thin limit D/R → 1 (the circle touches
      the line, paper §VIII); a finite thickness makes the string wrap part of the circle,
      which pulls the circle's centre towards the axis; D/R is reported so the trend shows.

    Otherwise ``"other"``. Returns ``{"label", "features"}``.
    """
    x = np.asarray(coords, dtype=float)
    rho = np.hypot(x[:, 0], x[:, 1])
    off = x[rho > axis_distance]
    feats: dict = {"loop_beads": 0}
    if len(off) < 12:
        return {"label": "other", "features": feats}
    centre, radius, normal, e1, e2 = _fit_circle(off)
    rel = x - centre
    h = rel @ normal
    r_in = np.hypot(rel @ e1, rel @ e2)
    near = (np.abs(r_in - radius) < 0.1 * radius + 1.0) & (np.abs(h) < 0.1 * radius + 1.0)
    loop = x[near]
    if len(loop) < 12:
        return {"label": "other", "features": feats}
    centre, radius, normal, e1, e2 = _fit_circle(loop)
    rel = loop - centre
    u, v, h = rel @ e1, rel @ e2, rel @ normal
    dev = np.hypot(u, v) - radius
    ang = np.arctan2(v, u)
    coverage = len(np.unique(np.floor((ang + np.pi) / (np.pi / 18)))) / 36
    axis_dist = float(np.hypot(centre[0], centre[1]))
    feats = {
        "loop_beads": int(len(loop)),
        "radius": radius,
        "planarity": float(np.sqrt(np.mean(h**2))) / radius,
        "roundness": float(np.sqrt(np.mean(dev**2))) / radius,
        "coverage": float(coverage),
        "normal_z": float(abs(normal[2])),
        "axis_distance_over_radius": axis_dist / radius,
    }
    ok = (feats["planarity"] < 0.1 and feats["roundness"] < 0.05 and coverage >= 0.9
          and feats["normal_z"] < 0.25 and abs(feats["axis_distance_over_radius"] - 1) < 0.5)
    return {"label": "loop" if ok else "other", "features": feats}
