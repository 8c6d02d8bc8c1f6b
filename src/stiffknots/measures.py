"""Numba-compiled measures of a polygon: bending energy, turning angles, writhe, distances.

Kernels see arrays and numbers only; :class:`stiffknots.chain.Chain` wraps them. The bending
energy is the paper's discrete E_d of §VII (divided by the mean bond length for non-unit
bonds), the writhe the exact Gauss integral of a polygon, and the distances those of the bead
rule and of the tube of §II.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.geometry import seg_dist2
from stiffknots.width import BEAD_D

__all__ = ["BEAD_D", "bending_energy", "chain_report", "min_bead_distance",
           "min_segment_distance", "vertex_terms", "writhe"]


@njit(cache=True)
def vertex_terms(coords, closed):
    """Turning angle, ``1 - cos`` of it and mean adjacent bond length at every bending vertex.

    Closed chains: vertex ``i`` (all ``N``) sits between bonds ``i-1 -> i`` and ``i -> i+1``
    (cyclic). Open chains: interior vertices ``1 .. N-2`` only.
    Returns three arrays (theta, one_minus_cos, mean_bond).
    """
    n = coords.shape[0]
    if closed:
        nv = n
        first = 0
    else:
        nv = n - 2
        first = 1
    theta = np.empty(nv)
    omc = np.empty(nv)
    lbar = np.empty(nv)
    for k in range(nv):
        i = k + first
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        ax = coords[i, 0] - coords[im, 0]
        ay = coords[i, 1] - coords[im, 1]
        az = coords[i, 2] - coords[im, 2]
        bx = coords[ip, 0] - coords[i, 0]
        by = coords[ip, 1] - coords[i, 1]
        bz = coords[ip, 2] - coords[i, 2]
        la = math.sqrt(ax * ax + ay * ay + az * az)
        lb = math.sqrt(bx * bx + by * by + bz * bz)
        cx = ay * bz - az * by
        cy = az * bx - ax * bz
        cz = ax * by - ay * bx
        theta[k] = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)
        # 1 - u_a.u_b computed as |u_a - u_b|^2 / 2 (same value, no cancellation when straight)
        dx = ax / la - bx / lb
        dy = ay / la - by / lb
        dz = az / la - bz / lb
        omc[k] = 0.5 * (dx * dx + dy * dy + dz * dz)
        lbar[k] = 0.5 * (la + lb)
    return theta, omc, lbar


@njit(cache=True)
def bending_energy(coords, closed):
    """Σ_vertices (1 - u_a·u_b) / b̄ (times C outside); = E_d/C of §VII for unit bonds."""
    theta, omc, lbar = vertex_terms(coords, closed)
    e = 0.0
    for k in range(omc.shape[0]):
        e += omc[k] / lbar[k]
    return e


@njit(cache=True, inline="always")
def _cross_into(out, k, ax, ay, az, bx, by, bz):
    """Row k of ``out`` = a × b."""
    out[k, 0] = ay * bz - az * by
    out[k, 1] = az * bx - ax * bz
    out[k, 2] = ax * by - ay * bx


@njit(cache=True)
def writhe(coords, closed):
    """Writhe of a polygon by the exact Gauss integral (Klenin & Langowski, Biopolymers 2000).

    Each pair of non-adjacent segments (p1 p2), (p3 p4) contributes the signed solid angle
    Ω = ±Σ asin(n_k · n_{k+1}) of the quadrilateral of unit normals
    n1 ∝ r13×r14, n2 ∝ r14×r24, n3 ∝ r24×r23, n4 ∝ r23×r13, with sign of (r34×r12)·r13;
    Wr = Σ_{i≠j} Ω_ij / 4π = Σ_{i<j} Ω_ij / 2π. Adjacent segments are coplanar and give 0.
    ``asin(n_a·n_b)`` is evaluated as ``π/2 - atan2(|n_a×n_b|, n_a·n_b)`` for accuracy.
    """
    n = coords.shape[0]
    nseg = n if closed else n - 1
    half_pi = 0.5 * math.pi
    nv = np.empty((4, 3))
    total = 0.0
    for i in range(nseg):
        i2 = i + 1 if i + 1 < n else 0
        p1x, p1y, p1z = coords[i, 0], coords[i, 1], coords[i, 2]
        p2x, p2y, p2z = coords[i2, 0], coords[i2, 1], coords[i2, 2]
        for j in range(i + 2, nseg):
            if closed and i == 0 and j == nseg - 1:
                continue
            j2 = j + 1 if j + 1 < n else 0
            p3x, p3y, p3z = coords[j, 0], coords[j, 1], coords[j, 2]
            p4x, p4y, p4z = coords[j2, 0], coords[j2, 1], coords[j2, 2]
            r13x, r13y, r13z = p3x - p1x, p3y - p1y, p3z - p1z
            r14x, r14y, r14z = p4x - p1x, p4y - p1y, p4z - p1z
            r23x, r23y, r23z = p3x - p2x, p3y - p2y, p3z - p2z
            r24x, r24y, r24z = p4x - p2x, p4y - p2y, p4z - p2z
            _cross_into(nv, 0, r13x, r13y, r13z, r14x, r14y, r14z)  # n1 = r13 × r14
            _cross_into(nv, 1, r14x, r14y, r14z, r24x, r24y, r24z)  # n2 = r14 × r24
            _cross_into(nv, 2, r24x, r24y, r24z, r23x, r23y, r23z)  # n3 = r24 × r23
            _cross_into(nv, 3, r23x, r23y, r23z, r13x, r13y, r13z)  # n4 = r23 × r13
            degenerate = False
            for k in range(4):
                nn = math.sqrt(nv[k, 0] ** 2 + nv[k, 1] ** 2 + nv[k, 2] ** 2)
                if nn <= 1e-300:
                    degenerate = True
                    break
                nv[k, 0] /= nn
                nv[k, 1] /= nn
                nv[k, 2] /= nn
            if degenerate:
                continue
            # sign: (r34 x r12) . r13
            r12x, r12y, r12z = p2x - p1x, p2y - p1y, p2z - p1z
            r34x, r34y, r34z = p4x - p3x, p4y - p3y, p4z - p3z
            sx = r34y * r12z - r34z * r12y
            sy = r34z * r12x - r34x * r12z
            sz = r34x * r12y - r34y * r12x
            s = sx * r13x + sy * r13y + sz * r13z
            if s == 0.0:
                continue
            omega = 0.0
            for k in range(4):
                a = k
                b = (k + 1) % 4
                d = nv[a, 0] * nv[b, 0] + nv[a, 1] * nv[b, 1] + nv[a, 2] * nv[b, 2]
                cx = nv[a, 1] * nv[b, 2] - nv[a, 2] * nv[b, 1]
                cy = nv[a, 2] * nv[b, 0] - nv[a, 0] * nv[b, 2]
                cz = nv[a, 0] * nv[b, 1] - nv[a, 1] * nv[b, 0]
                omega += half_pi - math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), d)
            if s > 0.0:
                total += omega
            else:
                total -= omega
    return total / (2.0 * math.pi)


@njit(cache=True)
def min_bead_distance(coords, closed, min_sep):
    """Minimum distance between beads i, j with index separation >= min_sep (cyclic if closed).

    Returns +inf when no pair qualifies.
    """
    n = coords.shape[0]
    best = np.inf
    for i in range(n):
        for j in range(i + min_sep, n):
            if closed and n - (j - i) < min_sep:
                continue
            dx = coords[i, 0] - coords[j, 0]
            dy = coords[i, 1] - coords[j, 1]
            dz = coords[i, 2] - coords[j, 2]
            d2 = dx * dx + dy * dy + dz * dz
            if d2 < best:
                best = d2
    return math.sqrt(best)


@njit(cache=True)
def min_segment_distance(coords, closed):
    """Minimum distance between segments sharing no bead; +inf when there is no such pair."""
    n = coords.shape[0]
    nseg = n if closed else n - 1
    best = np.inf
    for i in range(nseg):
        i2 = i + 1 if i + 1 < n else 0
        for j in range(i + 2, nseg):
            if closed and i == 0 and j == nseg - 1:
                continue
            j2 = j + 1 if j + 1 < n else 0
            d2 = seg_dist2(
                coords[i, 0], coords[i, 1], coords[i, 2],
                coords[i2, 0], coords[i2, 1], coords[i2, 2],
                coords[j, 0], coords[j, 1], coords[j, 2],
                coords[j2, 0], coords[j2, 1], coords[j2, 2],
            )  # fmt: skip
            if d2 < best:
                best = d2
    return math.sqrt(best)




def chain_report(coords: np.ndarray, closed: bool, d: float = BEAD_D, bond_tol: float = 1e-6,
                 segments: bool = True, unit: float | None = 1.0) -> dict:
    """A chain against the model of the package: unit bonds and the bead rule.

    Parameters
    ----------
    coords : ndarray
        (N, 3) float64 array.
    closed : bool
        Whether bead N−1 is bonded to bead 0.
    d : float
        The bead rule's distance (beads at index distance ≥ 2 no closer than ``d``).
    bond_tol : float
        Largest allowed ``|bond/unit − 1|``.
    segments : bool
        Also measure the smallest distance between segments sharing no bead.
    unit : float or None
        The bond length expected (1); None: the mean bond, i.e. the bonds must be equal (a
        chain in other units, with ``d`` in the same units).

    Returns
    -------
    dict
        With ``n_beads``, ``closed``, ``bond_min``, ``bond_max``, ``max_bond_error``,
        ``worst_bond`` (index of the bond farthest from 1), ``min_bead_distance`` (index
        distance ≥ 2), ``min_segment_distance`` (None unless ``segments``), ``d``,
        ``bond_tol``, ``unit_bonds``, ``bead_rule`` and ``problems`` (one sentence per failed
        check; empty when the chain is a unit-bond chain obeying the bead rule).
    """
    x = np.ascontiguousarray(coords, dtype=np.float64)
    b = np.roll(x, -1, axis=0) - x if closed else np.diff(x, axis=0)
    bonds = np.sqrt((b * b).sum(axis=1))
    u = float(bonds.mean()) if unit is None and len(bonds) else float(unit or 1.0)
    err = np.abs(bonds / u - 1.0)
    worst = int(np.argmax(err)) if len(err) else 0
    max_err = float(err[worst]) if len(err) else 0.0
    dmin = float(min_bead_distance(x, closed, 2))
    seg = float(min_segment_distance(x, closed)) if segments else None
    ok_bonds = max_err <= bond_tol
    rule = not dmin < d * (1.0 - 1e-9)
    problems = []
    if not ok_bonds:
        what = (f"unit bonds: |b − 1| ≤ {bond_tol:g}" if unit is not None else
                f"equal bonds: |b/b̄ − 1| ≤ {bond_tol:g}, mean b̄ = {u:.6g}")
        problems.append(f"bond {worst} has length {bonds[worst]:.6g} ({what})")
    if not rule:
        problems.append(f"two beads at index distance ≥ 2 are {dmin:.6g} apart (the bead rule "
                        f"needs ≥ {d:.6g})")
    return {"n_beads": len(x), "closed": bool(closed),
            "bond_min": float(bonds.min()) if len(bonds) else None,
            "bond_max": float(bonds.max()) if len(bonds) else None,
            "max_bond_error": max_err, "worst_bond": worst, "min_bead_distance": dmin,
            "min_segment_distance": seg, "d": float(d), "bond_tol": float(bond_tol),
            "unit_bonds": bool(ok_bonds), "bead_rule": bool(rule), "problems": problems}
