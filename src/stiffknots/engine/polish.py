"""Precise final minimiser ("polish") of the constrained discrete problem (paper §VII, §VIII).

The Monte Carlo engine ends near a local minimum of the discrete bending energy (§VII)

    E_d = Σ_joints (1 − u_n·u_{n+1}),    |u_n| = |r_{n+1} − r_n| = 1        (C = 1)

but only to the resolution of its last moves. :func:`polish` finds that local minimum to
machine precision while holding the constraints *exactly*: every bond has unit length, and the
exclusion rule — ``bead`` (beads at index distance ≥ 2 at least ``d`` apart, the paper's rule)
or ``tube`` (segments that share no bead at least ``w`` apart, the tube of §II) — holds at
every accepted iterate. Contacts are inequality constraints with multipliers μ ≥ 0: the contact
forces of the variational analysis of §V.B. Open chains (§VIII) keep their clamped ends
(beads 0, 1, N−2, N−1 by default) bit-for-bit, so the excess length L_e is unchanged.

Constraint pieces
-----------------
Written with the raw bond vectors b_n = r_{n+1} − r_n, E = Σ (1 − b_n·b_{n+1}) equals E_d on
the unit-bond manifold and is a quadratic form in the positions; the bonds are c_k = |b_k|² − 1
= 0. Every exclusion constraint is a *piece*: the vector v = Σ_i w_i r_i between two closest
points (barycentric weights on at most four beads) with g = |v|² − T² ≥ 0, T = limit + τ,
τ = 10⁻¹³ (so the final margin is ≥ 0 in floating point). ``bead`` pieces are bead pairs. In
the ``tube`` model the segment distance is split into vertex–vertex, vertex–segment and (both
closest points interior) segment–segment pieces; their minimum is the segment distance, so
they are equivalent to the rule, and strands in parallel contact get one smooth piece per
touching vertex instead of one kinked one. The Hessians are exact: isotropic (⊗ I₃) for E,
the bonds and vertex–vertex pieces, and 12 × 12 blocks (central differences of the analytic
gradients of the point–line and line–line distances) for the others.

The bead rule with d = 1/√2 lets two segments *touch* (crossing at right angles at their
midpoints, all four beads exactly d apart; any other crossing brings a pair closer), and tight
bead-model knots press strands into that configuration: the infimum is a non-embedded chain,
and near it the four bead pairs and the crossing form a nearly flat, degenerate contact. With
the guard on and a rule that does not separate strands by itself (``bead``, ``none``), segments
that share no bead are therefore also kept ≥ ``min_gap`` apart (distance-form pieces g = D − T,
whose multipliers are the forces that press the strands through each other); the energy then
exceeds the touching limit by ≈ ``gap_force``·min_gap.

Method: a feasible sequential quadratic programme (SQP)
-------------------------------------------------------
One iteration, from an admissible x:

1. *Candidates*: every piece within a margin of its limit (an O(N²) numba scan; the margin
   follows the recent step length, at most 2·max_step + 0.05).
2. *QP*: minimise ∇E·dx + ½ dxᵀ(∇²L + σI)dx, L = E − Σ λ_k c_k − Σ μ_p g_p, subject to the
   linearised bonds (= 0), pieces (≥ 0) and six sparse gauge rows that remove the rigid
   motions (one, rotation about z, for a clamped open chain). A primal active-set method
   (Nocedal & Wright, Alg. 16.3) starts from dx = 0 with the tight pieces, adds one blocking
   piece or drops the most negative multiplier at a time, and follows directions of
   non-positive curvature until a piece blocks (inertia control). The base KKT matrix
   [H Aᵀ; A 0] is factorised once (sparse LU); working-set changes go through a bordered
   inverse of the Schur complement J_W K⁻¹ J_Wᵀ. σ ≥ 0 is raised only when the subproblem
   is unbounded; an unbounded direction is first tried as a negative-curvature step.
3. *Projection*: the trial x + α·dx goes back onto the bonds (to ~10⁻¹³) and the violated
   pieces (to their target) by min-norm Gauss–Newton corrections (chord iterations):
   dx = Aᵀ(AAᵀ)⁻¹r, the Gram matrix AAᵀ assembled bead by bead in a compiled kernel and
   factorised by dense Cholesky (sparse LU for long chains; :class:`_MinNormSolver`).
4. *Acceptance*: the exclusion rule on *all* pairs (an O(N²) check, independent of the
   candidates), the strand gap, no energy increase (Armijo where resolvable in floating
   point) and the passage guard below; otherwise α is halved.

Convergence is measured by the KKT residual: with A the Jacobian of the bonds and of the
pieces within 10⁻⁸ of their limit, restricted to the free beads,

    kkt_residual = min_{λ, μ ≥ 0} ‖∇E − Aᵀ(λ, μ)‖₂,

the part of the energy gradient that no combination of bond tensions and pushing contact
forces balances; it vanishes exactly at a KKT point (away from contacts it is the gradient
projected on the tangent space of the bond manifold). The run has converged when
kkt_residual ≤ tol·‖∇E‖₂, or when the exact model predicts no decrease that E can resolve
(|ΔE| < 10⁻¹³·E) and kkt_residual ≤ 10⁻⁶·‖∇E‖₂.

No strand passage (proof)
-------------------------
Every accepted step x → x' is realised by the straight-line motion r_i(t) = r_i + t(r'_i −
r_i), t ∈ [0, 1], of every bead. For segments a = (a, a+1) and b = (b, b+1) and points at
parameters s and u on them, p_a − p_b moves with velocity (1−s)Δr_a + sΔr_{a+1} −
(1−u)Δr_b − uΔr_{b+1}, a convex combination of the four differences Δr_i − Δr_j (i ∈ a,
j ∈ b); so every |p_a − p_b| is L-Lipschitz in t with L = max |Δr_i − Δr_j| ≤ δ_a + δ_b
(δ = the larger displacement of a segment's two beads: a point of a segment moves at most as
fast as the faster of its ends), and so is their minimum, the segment distance D(t). On any
interval [t₀, t₁], D(t) ≥ (D(t₀) + D(t₁) − L(t₁ − t₀))/2. A step is accepted only if, for
every pair of segments that share no bead,

    D(0) + D(1) − L > 2η,                                     η = 10⁻⁹ (``GUARD_FLOOR``),

or, failing that, the same inequality holds on every sub-interval of a bisection of [0, 1]
(at most 2^guard_depth pieces; D computed at the new nodes). Then D(t) > η > 0 for all t:
no two such segments meet at any time. (The floor η makes the certificate immune to
rounding: at a true crossing the computed D can be 10⁻¹⁷ rather than 0.) Two segments that
share bead k could only meet elsewhere by folding back (collinear and overlapping), i.e. with
the far end of one on the other: the same certificate is required for r_{k+1} against
[r_{k−1}, r_k] and for r_{k−1} against [r_k, r_{k+1}] (both rules keep these distances
positive at every admissible state). So the polygon stays embedded along the whole motion — an
isotopy — and its knot type cannot change; this is the Lipschitz argument of
:mod:`stiffknots.engine.kernel` applied to straight-line motions (with the relative
displacement, and on sub-intervals). For an open chain the knot type is that of the closure
along the z-axis rays beyond the clamped end segments: each free bead must end strictly inside
the slab z_0 < z < z_{N−1}, and z is linear in t, so the whole path stays in the slab and no
segment touches a ray. Pairs with D(1) > δ_a + δ_b + η are skipped by a screen on segment
midpoints, so the guard is one O(N²) pass of cheap tests plus a few bisections.

With ``exclusion="none"`` the chain may self-intersect (e.g. an m-covered circle), so the guard
is off by default there (``guard=None``); pass ``guard=True`` to keep it.

The ``@njit`` kernels see arrays and numbers only; :func:`polish` validates its inputs and
composes them with scipy's sparse LU and LAPACK's Cholesky.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import math
import os
import sys
import threading
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numba import njit
from scipy.sparse.linalg import splu
from threadpoolctl import threadpool_limits

from stiffknots.engine.kernel import energy_chain
from stiffknots.geometry import _clamp01, seg_dist2
from stiffknots.geometry import seg_params as _seg_params

log = logging.getLogger(__name__)

EXCLUSIONS = ("bead", "tube", "none")
TAU = 1e-13  # active contacts are held at limit + TAU, so the final margin is ≥ 0 in floats
ACTIVE_TOL = 1e-8  # a contact within this distance of its limit counts as active
BOND_TOL_IN = 1e-8  # input bonds must be unit to this (the output is unit to ~1e-14)
BOND_TOL_OUT = 1e-13  # the projection stops when every bond is unit to this
#: the stall test of :meth:`_Polisher.run`: over the last STALL_STEPS accepted steps E fell by
#: ≤ STALL_REL·E while the KKT residual is ≤ STALL_KKT·‖∇E‖ — converged (3_1 at N = 150: the
#: energy is settled to 1e-11 after ~30 steps and the next 60 gained 4e-11 of E more)
STALL_STEPS = 8
STALL_REL = 1e-10
STALL_KKT = 1e-6
GUARD_FLOOR = 1e-9  # the guard certifies that strands stay this far apart (≫ rounding)


# --------------------------------------------------------------------------------------------
# compiled kernels (arrays and numbers only)
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _point_seg_t(pos, v, a, a1):
    """Parameter of the point of segment [r_a, r_a1] closest to bead v."""
    ex = pos[a1, 0] - pos[a, 0]
    ey = pos[a1, 1] - pos[a, 1]
    ez = pos[a1, 2] - pos[a, 2]
    ee = ex * ex + ey * ey + ez * ez
    if ee <= 1e-300:
        return 0.0
    t = ((pos[v, 0] - pos[a, 0]) * ex + (pos[v, 1] - pos[a, 1]) * ey
         + (pos[v, 2] - pos[a, 2]) * ez) / ee
    return _clamp01(t)


@njit(cache=True)
def _energy_grad(pos, is_open):
    """E = Σ_joints (1 − b_{n−1}·b_n) with raw bond vectors, and its gradient (N, 3)."""
    n = pos.shape[0]
    g = np.zeros((n, 3))
    e = 0.0
    lo = 1 if is_open else 0
    hi = n - 1 if is_open else n
    for v in range(lo, hi):
        a = v - 1 if v > 0 else n - 1
        c = v + 1 if v < n - 1 else 0
        f = 0.0
        for q in range(3):
            f += (pos[v, q] - pos[a, q]) * (pos[c, q] - pos[v, q])
        e += 1.0 - f
        for q in range(3):
            u = pos[v, q] - pos[a, q]  # b_{v-1}
            w = pos[c, q] - pos[v, q]  # b_v
            # ∂f/∂r_a = −w, ∂f/∂r_v = w − u, ∂f/∂r_c = u; E = Σ (1 − f)
            g[a, q] += w
            g[v, q] -= w - u
            g[c, q] -= u
    return e, g


@njit(cache=True)
def _bead_candidates(pos, is_open, reach, nfix):
    """Bead pairs at (cyclic) index distance ≥ 2 closer than ``reach``, not both clamped.

    Returns (idx (M, 2), key (M,)).
    """
    n = pos.shape[0]
    r2 = reach * reach
    cnt = 0
    for pas in range(2):
        if pas == 1:
            idx = np.empty((cnt, 2), dtype=np.int64)
            key = np.empty(cnt, dtype=np.int64)
            cnt = 0
        for i in range(n):
            fi = nfix <= i < n - nfix
            for j in range(i + 2, n):
                if not is_open and i == 0 and j == n - 1:
                    continue
                if not fi and not (nfix <= j < n - nfix):
                    continue
                dx = pos[i, 0] - pos[j, 0]
                dy = pos[i, 1] - pos[j, 1]
                dz = pos[i, 2] - pos[j, 2]
                if dx * dx + dy * dy + dz * dz < r2:
                    if pas == 1:
                        idx[cnt, 0] = i
                        idx[cnt, 1] = j
                        key[cnt] = i * n + j
                    cnt += 1
    return idx, key


@njit(cache=True)
def _tube_candidates(pos, is_open, reach, nfix):
    """Tube-model constraint pieces within ``reach``, for segments that share no bead.

    For every such pair closer than ``reach``: the segment–segment piece (type 2) when both
    closest points are interior, and the four vertex–segment pieces (type 1; type 0,
    vertex–vertex, when the foot of the perpendicular is an end bead). Returns
    (ctype (M,), idx (M, 4), key (M,)), possibly with duplicate keys.
    """
    n = pos.shape[0]
    nseg = n - 1 if is_open else n
    r2 = reach * reach
    big = n * n
    cap = 64
    ctype = np.empty(cap, dtype=np.int64)
    idx = np.full((cap, 4), -1, dtype=np.int64)
    key = np.empty(cap, dtype=np.int64)
    m = 0
    for a in range(nseg):
        a1 = a + 1 if a < n - 1 else 0
        afix = not (nfix <= a < n - nfix) and not (nfix <= a1 < n - nfix)
        for b in range(a + 2, nseg):
            if not is_open and a == 0 and b == n - 1:
                continue
            b1 = b + 1 if b < n - 1 else 0
            if afix and not (nfix <= b < n - nfix) and not (nfix <= b1 < n - nfix):
                continue
            mx = 0.5 * (pos[a, 0] + pos[a1, 0] - pos[b, 0] - pos[b1, 0])
            my = 0.5 * (pos[a, 1] + pos[a1, 1] - pos[b, 1] - pos[b1, 1])
            mz = 0.5 * (pos[a, 2] + pos[a1, 2] - pos[b, 2] - pos[b1, 2])
            lim = reach + 1.0 + 1e-6
            if mx * mx + my * my + mz * mz > lim * lim:
                continue
            dd = seg_dist2(pos[a, 0], pos[a, 1], pos[a, 2], pos[a1, 0], pos[a1, 1], pos[a1, 2],
                           pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2])
            if dd >= r2:
                continue
            if m + 5 > cap:
                cap *= 2
                ct2 = np.empty(cap, dtype=np.int64)
                id2 = np.full((cap, 4), -1, dtype=np.int64)
                ke2 = np.empty(cap, dtype=np.int64)
                ct2[:m] = ctype[:m]
                id2[:m] = idx[:m]
                ke2[:m] = key[:m]
                ctype = ct2
                idx = id2
                key = ke2
            s, t = _seg_params(pos[a, 0], pos[a, 1], pos[a, 2], pos[a1, 0], pos[a1, 1],
                               pos[a1, 2], pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0],
                               pos[b1, 1], pos[b1, 2])
            if 0.0 < s < 1.0 and 0.0 < t < 1.0:
                ctype[m] = 2
                idx[m, 0] = a
                idx[m, 1] = a1
                idx[m, 2] = b
                idx[m, 3] = b1
                key[m] = 2 * big + a * n + b
                m += 1
            for q in range(4):
                if q == 0:
                    v, s0, s1, sg = a, b, b1, b
                elif q == 1:
                    v, s0, s1, sg = a1, b, b1, b
                elif q == 2:
                    v, s0, s1, sg = b, a, a1, a
                else:
                    v, s0, s1, sg = b1, a, a1, a
                tt = _point_seg_t(pos, v, s0, s1)
                px = pos[v, 0] - (1.0 - tt) * pos[s0, 0] - tt * pos[s1, 0]
                py = pos[v, 1] - (1.0 - tt) * pos[s0, 1] - tt * pos[s1, 1]
                pz = pos[v, 2] - (1.0 - tt) * pos[s0, 2] - tt * pos[s1, 2]
                if px * px + py * py + pz * pz >= r2:
                    continue
                if tt <= 0.0 or tt >= 1.0:
                    e = s0 if tt <= 0.0 else s1
                    i = v if v < e else e
                    j = e if v < e else v
                    ctype[m] = 0
                    idx[m, 0] = i
                    idx[m, 1] = j
                    idx[m, 2] = -1
                    idx[m, 3] = -1
                    key[m] = i * n + j
                else:
                    ctype[m] = 1
                    idx[m, 0] = v
                    idx[m, 1] = s0
                    idx[m, 2] = s1
                    idx[m, 3] = -1
                    key[m] = big + v * n + sg
                m += 1
    return ctype[:m].copy(), idx[:m].copy(), key[:m].copy()


@njit(cache=True)
def _eval_constraints(pos, ctype, idx, wts, vec):
    """Fill the weights (M, 4) and closest-point vectors (M, 3) of the constraints at ``pos``
    (closest-point parameters re-optimised) and return their lengths (M,)."""
    m = ctype.shape[0]
    out = np.empty(m)
    for p in range(m):
        i0 = idx[p, 0]
        i1 = idx[p, 1]
        i2 = idx[p, 2]
        i3 = idx[p, 3]
        wts[p, 0] = 0.0
        wts[p, 1] = 0.0
        wts[p, 2] = 0.0
        wts[p, 3] = 0.0
        if ctype[p] == 0:
            wts[p, 0] = 1.0
            wts[p, 1] = -1.0
        elif ctype[p] == 1:
            t = _point_seg_t(pos, i0, i1, i2)
            wts[p, 0] = 1.0
            wts[p, 1] = -(1.0 - t)
            wts[p, 2] = -t
        else:
            s, t = _seg_params(pos[i0, 0], pos[i0, 1], pos[i0, 2], pos[i1, 0], pos[i1, 1],
                               pos[i1, 2], pos[i2, 0], pos[i2, 1], pos[i2, 2], pos[i3, 0],
                               pos[i3, 1], pos[i3, 2])
            wts[p, 0] = 1.0 - s
            wts[p, 1] = s
            wts[p, 2] = -(1.0 - t)
            wts[p, 3] = -t
        s2 = 0.0
        for q in range(3):
            x = 0.0
            for k in range(4):
                if idx[p, k] >= 0:
                    x += wts[p, k] * pos[idx[p, k], q]
            vec[p, q] = x
            s2 += x * x
        out[p] = math.sqrt(s2)
    return out


@njit(cache=True)
def _line_grad(q, grad):
    """Signed distance f = n̂·(q0 − q2) of the lines through segments (q0, q1) and (q2, q3)
    (n̂ ∝ e_a × e_b), and its gradient (4, 3) in ``grad``; f is the segment distance while
    both closest points are interior."""
    ea = q[1] - q[0]
    eb = q[3] - q[2]
    c = np.cross(ea, eb)
    m = math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    nh = c / m
    dl = q[0] - q[2]
    f = nh[0] * dl[0] + nh[1] * dl[1] + nh[2] * dl[2]
    par = dl - f * nh  # the part of Δ in the plane of e_a and e_b
    gea = np.cross(eb, par) / m
    geb = np.cross(par, ea) / m
    for k in range(3):
        grad[0, k] = nh[k] - gea[k]
        grad[1, k] = gea[k]
        grad[2, k] = -nh[k] - geb[k]
        grad[3, k] = geb[k]
    return f


@njit(cache=True)
def _ptline_grad(q, grad):
    """Distance D = |Δ − (Δ·ê)ê| of point q0 from the line through (q1, q2) (Δ = q0 − q1),
    and its gradient (3, 3) in ``grad``; D is the vertex–segment distance while the foot of
    the perpendicular is interior."""
    e = q[2] - q[1]
    ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2]
    dl = q[0] - q[1]
    t = (dl[0] * e[0] + dl[1] * e[1] + dl[2] * e[2]) / ee
    perp = dl - t * e
    d = math.sqrt(perp[0] * perp[0] + perp[1] * perp[1] + perp[2] * perp[2])
    for k in range(3):
        u = perp[k] / d
        grad[0, k] = u
        grad[1, k] = -(1.0 - t) * u
        grad[2, k] = -t * u
    return d


@njit(cache=True)
def _piece_hessians(pos, ctype, idx, form, out):
    """Exact Hessians (12 × 12, beads idx[p, 0..3] × xyz) of the vertex–segment (type 1) and
    segment–segment (type 2) pieces: of D² (form 0) or D (form 1), by central differences of
    the analytic gradients of the point–line and line–line distances."""
    m = ctype.shape[0]
    for p in range(m):
        for a in range(12):
            for b in range(12):
                out[p, a, b] = 0.0
        if ctype[p] == 0:
            continue
        nb = 4 if ctype[p] == 2 else 3
        q = np.empty((nb, 3))
        for k in range(nb):
            for c in range(3):
                q[k, c] = pos[idx[p, k], c]
        g0 = np.empty((nb, 3))
        gp = np.empty((nb, 3))
        gm = np.empty((nb, 3))
        if nb == 4:
            f0 = _line_grad(q, g0)
        else:
            f0 = _ptline_grad(q, g0)
        sg = 1.0
        if nb == 4 and f0 < 0.0:
            sg = -1.0  # D = |f|
        h = 1e-6 * min(1.0, abs(f0) * 1e3) if abs(f0) < 1e-3 else 1e-6
        for k in range(nb):
            for c in range(3):
                old = q[k, c]
                q[k, c] = old + h
                if nb == 4:
                    _line_grad(q, gp)
                else:
                    _ptline_grad(q, gp)
                q[k, c] = old - h
                if nb == 4:
                    _line_grad(q, gm)
                else:
                    _ptline_grad(q, gm)
                q[k, c] = old
                col = 3 * k + c
                for k2 in range(nb):
                    for c2 in range(3):
                        d2 = sg * (gp[k2, c2] - gm[k2, c2]) / (2.0 * h)  # ∇²D
                        row = 3 * k2 + c2
                        if form[p] == 0:  # ∇²(D²) = 2 ∇D ∇Dᵀ + 2 D ∇²D
                            d2 = 2.0 * sg * g0[k2, c2] * sg * g0[k, c] \
                                + 2.0 * abs(f0) * d2
                        out[p, row, col] = d2
        for a in range(12):  # symmetrise the difference quotients
            for b in range(a + 1, 12):
                v = 0.5 * (out[p, a, b] + out[p, b, a])
                out[p, a, b] = v
                out[p, b, a] = v


@njit(cache=True)
def _min_clearance(pos, mode, lim, is_open):
    """Min over the exclusion constraints of (distance − lim), capped at 1 (exact below).

    mode 0: bead pairs at (cyclic) index distance ≥ 2; mode 1: segments sharing no bead.
    """
    n = pos.shape[0]
    best = 1.0
    if mode == 0:
        for i in range(n):
            for j in range(i + 2, n):
                if not is_open and i == 0 and j == n - 1:
                    continue
                dx = pos[i, 0] - pos[j, 0]
                dy = pos[i, 1] - pos[j, 1]
                dz = pos[i, 2] - pos[j, 2]
                v = math.sqrt(dx * dx + dy * dy + dz * dz) - lim
                if v < best:
                    best = v
        return best
    nseg = n - 1 if is_open else n
    for a in range(nseg):
        a1 = a + 1 if a < n - 1 else 0
        ha = _half_length(pos, a, a1)
        for b in range(a + 2, nseg):
            if not is_open and a == 0 and b == n - 1:
                continue
            b1 = b + 1 if b < n - 1 else 0
            hb = _half_length(pos, b, b1)
            mx = 0.5 * (pos[a, 0] + pos[a1, 0] - pos[b, 0] - pos[b1, 0])
            my = 0.5 * (pos[a, 1] + pos[a1, 1] - pos[b, 1] - pos[b1, 1])
            mz = 0.5 * (pos[a, 2] + pos[a1, 2] - pos[b, 2] - pos[b1, 2])
            if math.sqrt(mx * mx + my * my + mz * mz) - ha - hb - lim >= best:
                continue
            dd = seg_dist2(pos[a, 0], pos[a, 1], pos[a, 2], pos[a1, 0], pos[a1, 1], pos[a1, 2],
                           pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2])
            v = math.sqrt(dd) - lim
            if v < best:
                best = v
    return best


@njit(cache=True)
def _seg_dist_at(old, new, t, a, a1, b, b1):
    """Distance of segments (a, a1) and (b, b1) at time t of the straight-line motion."""
    u = 1.0 - t
    return math.sqrt(seg_dist2(
        u * old[a, 0] + t * new[a, 0], u * old[a, 1] + t * new[a, 1],
        u * old[a, 2] + t * new[a, 2], u * old[a1, 0] + t * new[a1, 0],
        u * old[a1, 1] + t * new[a1, 1], u * old[a1, 2] + t * new[a1, 2],
        u * old[b, 0] + t * new[b, 0], u * old[b, 1] + t * new[b, 1],
        u * old[b, 2] + t * new[b, 2], u * old[b1, 0] + t * new[b1, 0],
        u * old[b1, 1] + t * new[b1, 1], u * old[b1, 2] + t * new[b1, 2]))


@njit(cache=True, inline="always")
def _rel_disp(old, new, i, j):
    """|Δr_i − Δr_j|: the relative displacement of beads i and j over the step."""
    s = 0.0
    for q in range(3):
        x = (new[i, q] - old[i, q]) - (new[j, q] - old[j, q])
        s += x * x
    return math.sqrt(s)


@njit(cache=True, inline="always")
def _half_length(pos, a, a1):
    """Half the length of segment (a, a1) of ``pos``."""
    return 0.5 * math.sqrt((pos[a1, 0] - pos[a, 0]) ** 2 + (pos[a1, 1] - pos[a, 1]) ** 2
                           + (pos[a1, 2] - pos[a, 2]) ** 2)


@njit(cache=True)
def _pair_clear(old, new, a, a1, b, b1, lip, max_depth):
    """No passage of segments (a, a1) and (b, b1) along the step old → new, whose relative
    displacement is at most ``lip``: a rigid relative motion (lip = 0) keeps the distance;
    D(1) > lip or D(0) + D(1) > lip (plus the floor) clears the pair at once (the distance is
    lip-Lipschitz along the step); otherwise :func:`_path_clear` bisects the step."""
    if lip == 0.0:
        return True
    d1 = _seg_dist_at(old, new, 1.0, a, a1, b, b1)
    if d1 - lip > GUARD_FLOOR:
        return True
    d0 = _seg_dist_at(old, new, 0.0, a, a1, b, b1)
    if d0 + d1 - lip > 2.0 * GUARD_FLOOR:
        return True
    return _path_clear(old, new, a, a1, b, b1, d0, d1, lip, max_depth)


@njit(cache=True)
def _path_clear(old, new, a, a1, b, b1, d0, d1, lip, max_depth):
    """Certify D(t) > GUARD_FLOOR on [0, 1] for the segment pair, D lip-Lipschitz in t.

    On an interval [t0, t1] with D(t0) + D(t1) − lip·(t1 − t0) > 2·GUARD_FLOOR the Lipschitz
    bound keeps D > GUARD_FLOOR; otherwise the interval is bisected (at most ``max_depth``
    levels). A point is the segment (v, v); returns False when no certificate is found.
    """
    st0 = np.empty(max_depth + 2)
    st1 = np.empty(max_depth + 2)
    sd0 = np.empty(max_depth + 2)
    sd1 = np.empty(max_depth + 2)
    sdp = np.empty(max_depth + 2, dtype=np.int64)
    top = 0
    st0[0] = 0.0
    st1[0] = 1.0
    sd0[0] = d0
    sd1[0] = d1
    sdp[0] = 0
    while top >= 0:
        t0 = st0[top]
        t1 = st1[top]
        e0 = sd0[top]
        e1 = sd1[top]
        dep = sdp[top]
        top -= 1
        if e0 + e1 - lip * (t1 - t0) > 2.0 * GUARD_FLOOR:
            continue
        if dep >= max_depth or e0 <= GUARD_FLOOR or e1 <= GUARD_FLOOR:
            return False
        tm = 0.5 * (t0 + t1)
        em = _seg_dist_at(old, new, tm, a, a1, b, b1)
        if em <= GUARD_FLOOR:
            return False
        top = _push(st0, st1, sd0, sd1, sdp, top, tm, t1, em, e1, dep + 1)
        top = _push(st0, st1, sd0, sd1, sdp, top, t0, tm, e0, em, dep + 1)
    return True


@njit(cache=True, inline="always")
def _push(st0, st1, sd0, sd1, sdp, top, t0, t1, e0, e1, dep):
    """Push the sub-interval [t0, t1] (distances e0, e1, depth dep) on the bisection stack."""
    top += 1
    st0[top] = t0
    st1[top] = t1
    sd0[top] = e0
    sd1[top] = e1
    sdp[top] = dep
    return top


@njit(cache=True)
def _passage_ok(old, new, is_open, nfix, zlo, zhi, max_depth):
    """The strand-passage guard of the module docstring for the straight-line motion
    ``old`` → ``new``: True if no two segments that share no bead can meet along it, no two
    bonded segments can fold onto each other, and (open chains) every free bead ends strictly
    inside the slab zlo < z < zhi. O(N²) cheap screens; close pairs are certified by
    :func:`_path_clear`."""
    n = old.shape[0]
    disp = np.empty(n)
    for i in range(n):
        disp[i] = math.sqrt((new[i, 0] - old[i, 0]) ** 2 + (new[i, 1] - old[i, 1]) ** 2
                            + (new[i, 2] - old[i, 2]) ** 2)
    if is_open:
        for i in range(nfix, n - nfix):
            if not (zlo < new[i, 2] < zhi):
                return False
    nseg = n - 1 if is_open else n
    # segments that share no bead
    for a in range(nseg):
        a1 = a + 1 if a < n - 1 else 0
        da = disp[a] if disp[a] > disp[a1] else disp[a1]
        ha = _half_length(new, a, a1)
        for b in range(a + 2, nseg):
            if not is_open and a == 0 and b == n - 1:
                continue
            b1 = b + 1 if b < n - 1 else 0
            db = disp[b] if disp[b] > disp[b1] else disp[b1]
            bound = da + db  # ≥ the relative Lipschitz constant below
            if bound == 0.0:
                continue
            hb = _half_length(new, b, b1)
            mx = 0.5 * (new[a, 0] + new[a1, 0] - new[b, 0] - new[b1, 0])
            my = 0.5 * (new[a, 1] + new[a1, 1] - new[b, 1] - new[b1, 1])
            mz = 0.5 * (new[a, 2] + new[a1, 2] - new[b, 2] - new[b1, 2])
            if math.sqrt(mx * mx + my * my + mz * mz) - ha - hb - bound > GUARD_FLOOR:
                continue  # D_after > bound + floor ≥ lip + floor
            lip = max(_rel_disp(old, new, a, b), _rel_disp(old, new, a, b1),
                      _rel_disp(old, new, a1, b), _rel_disp(old, new, a1, b1))
            if not _pair_clear(old, new, a, a1, b, b1, lip, max_depth):
                return False
    # bonded segments (k-1, k) and (k, k+1): no fold-back
    lo = 1 if is_open else 0
    hi = n - 1 if is_open else n
    for k in range(lo, hi):
        km = k - 1 if k > 0 else n - 1
        kp = k + 1 if k < n - 1 else 0
        for side in range(2):
            if side == 0:
                v, s0 = kp, km  # bead k+1 against segment (k-1, k)
            else:
                v, s0 = km, kp  # bead k-1 against segment (k, k+1)
            lip = max(_rel_disp(old, new, v, s0), _rel_disp(old, new, v, k))
            if not _pair_clear(old, new, v, v, s0, k, lip, max_depth):
                return False
    return True


# --------------------------------------------------------------------------------------------
# the problem: sparse assembly around the kernels
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PolishResult:
    """Outcome of :func:`polish`.

    Attributes
    ----------
    pos : (N, 3) the polished chain (a new array; the input is untouched).
    energy_before, energy : E_d = Σ (1 − u_n·u_{n+1}) of the input and of ``pos`` (paper §VII;
        ε = E_d·N for a closed chain).
    kkt_residual : min over bond tensions λ and contact forces μ ≥ 0 of ‖∇E − Aᵀ(λ, μ)‖₂ at
        ``pos`` (free beads only; A: Jacobian of the bonds and of the contacts within 10⁻⁸ of
        their limit). Zero at a KKT point; see the module docstring.
    grad_norm : ‖∇E‖₂ over the free beads (the scale of ``kkt_residual``).
    iterations : accepted SQP steps.
    converged : kkt_residual ≤ tol·grad_norm, or no step can lower E by more than its
        floating-point resolution and kkt_residual ≤ 10⁻⁶·grad_norm.
    reason : why the iteration stopped.
    n_active : exclusion constraints within 10⁻⁸ of their limit at the end (bead pairs; in
        the tube model vertex–vertex, vertex–segment and segment–segment contact pieces).
    max_bond_error : max_k | |r_{k+1} − r_k| − 1 |.
    exclusion_margin : min over the exclusion constraints of (distance − limit) (≥ 0; capped
        at 1; +inf for ``exclusion="none"``).
    strand_gap : min distance between segments that share no bead (capped at 1).
    gap_force : Σ of the multipliers of the strand-gap pieces (the force pressing strands
        through each other, C per bond length); the energy exceeds the touching limit
        (min_gap → 0) by ≈ gap_force·min_gap. Zero when no gap piece is active.
    seconds : wall time.
    """

    pos: np.ndarray
    energy_before: float
    energy: float
    kkt_residual: float
    grad_norm: float
    iterations: int
    converged: bool
    reason: str
    n_active: int
    max_bond_error: float
    exclusion_margin: float
    strand_gap: float
    gap_force: float
    seconds: float

    @property
    def relative_kkt(self) -> float:
        """kkt_residual / grad_norm."""
        return self.kkt_residual / self.grad_norm if self.grad_norm > 0 else 0.0


class _Cons:
    """A list of constraint pieces: type (0 vertex–vertex, 1 vertex–segment, 2
    segment–segment), beads (M, 4; −1 unused), key (identity across iterations), limit (M,)
    and form (M,): 0 = squared, g = |v|² − T², 1 = distance, g = |v| − T (T = limit + τ)."""

    def __init__(self, ctype, idx, key, lim, form):
        self.ctype, self.idx, self.key, self.lim, self.form = ctype, idx, key, lim, form
        self.target = lim + TAU

    def __len__(self):
        return len(self.key)

    def sub(self, sel):
        return _Cons(self.ctype[sel], self.idx[sel], self.key[sel], self.lim[sel],
                     self.form[sel])

    @staticmethod
    def concat(parts):
        parts = [q for q in parts if len(q)]
        if not parts:
            z = np.empty(0, dtype=np.int64)
            return _Cons(z, np.empty((0, 4), dtype=np.int64), z, np.empty(0), z)
        return _Cons(*(np.concatenate([getattr(q, f) for q in parts])
                       for f in ("ctype", "idx", "key", "lim", "form")))

    def evaluate(self, pos):
        """(dist, g, weights (M, 4), direction (M, 3)): ∇_{r_idx[p,k]} g_p = w[p,k]·dir[p]."""
        m = len(self)
        wts = np.zeros((m, 4))
        vec = np.zeros((m, 3))
        if not m:
            return np.zeros(0), np.zeros(0), wts, vec
        dist = _eval_constraints(pos, self.ctype, self.idx, wts, vec)
        sq = self.form == 0
        g = np.where(sq, dist ** 2 - self.target ** 2, dist - self.target)
        safe = np.where(dist > 0, dist, 1.0)
        direc = np.where(sq[:, None], 2.0 * vec, vec / safe[:, None])
        return dist, g, wts, direc


class _Problem:
    """The constrained problem at fixed settings: index maps, candidates, sparse assembly."""

    def __init__(self, n, closed, mode, limit, nfix, zrot_row, gap):
        self.n = n
        self.closed = closed
        self.is_open = not closed
        self.mode = mode  # 0 bead, 1 tube, 2 none
        self.limit = limit
        self.gap = gap  # strand gap (bead/none with the guard on), 0: none
        self.nfix = nfix
        self.free = np.arange(nfix, n - nfix)
        self.nf = self.free.size
        fmap = -np.ones(n, dtype=np.int64)
        fmap[self.free] = np.arange(self.nf)
        self.fmap = fmap
        # bonds touching a free bead
        ks = np.arange(n if closed else n - 1)
        k1 = (ks + 1) % n
        keep = (fmap[ks] >= 0) | (fmap[k1] >= 0)
        self.bk = ks[keep]
        self.bk1 = k1[keep]
        # joints (bead v between a and c)
        js = np.arange(n) if closed else np.arange(1, n - 1)
        self.ja = (js - 1) % n
        self.jv = js
        self.jc = (js + 1) % n
        self.nrigid = 6 if closed else (1 if zrot_row else 0)

    # ---- constraints -------------------------------------------------------------------
    def candidates(self, pos, margin):
        """The constraint pieces within ``margin`` of their limit."""
        parts = []
        big = self.n * self.n
        if self.mode == 0:
            pairs, key = _bead_candidates(pos, self.is_open, self.limit + margin, self.nfix)
            idx = np.full((len(key), 4), -1, dtype=np.int64)
            idx[:, :2] = pairs
            z = np.zeros(len(key), dtype=np.int64)
            parts.append(_Cons(z, idx, key, np.full(len(key), self.limit), z))
        elif self.mode == 1:
            ctype, idx, key = _tube_candidates(pos, self.is_open, self.limit + margin,
                                               self.nfix)
            key, first = np.unique(key, return_index=True)
            z = np.zeros(len(key), dtype=np.int64)
            parts.append(_Cons(ctype[first], idx[first], key, np.full(len(key), self.limit),
                               z))
        if self.gap > 0:
            ctype, idx, key = _tube_candidates(pos, self.is_open, self.gap + margin,
                                               self.nfix)
            key, first = np.unique(key, return_index=True)
            one = np.ones(len(key), dtype=np.int64)
            parts.append(_Cons(ctype[first], idx[first], key + 3 * big,
                               np.full(len(key), self.gap), one))
        return _Cons.concat(parts)

    def bond_residual(self, pos):
        b = pos[self.bk1] - pos[self.bk]
        return np.einsum("ij,ij->i", b, b) - 1.0, b

    # ---- sparse matrices (free coordinates, interleaved x, y, z) --------------------------
    def _triplets(self, rows, beads, vecs):
        """Rows with 3-vector entries on beads → (row, column, value) triplets over the free
        coordinates (interleaved x, y, z); clamped beads dropped."""
        f = self.fmap[beads]
        ok = f >= 0
        rows, f, vecs = rows[ok], f[ok], vecs[ok]
        return (np.repeat(rows, 3), (3 * f[:, None] + np.arange(3)).ravel(), vecs.ravel())

    def jacobian(self, pos, b, idx, wts, direc, rigid=True):
        """[bond rows; rigid rows (if ``rigid``); constraint rows], as CSR, assembled from
        the blocks' triplets in one go (the same matrix as stacking the blocks, tested)."""
        nb = len(self.bk)
        rows = np.arange(nb)
        parts = [self._triplets(np.r_[rows, rows], np.r_[self.bk1, self.bk],
                                np.r_[2 * b, -2 * b])]
        top = nb
        if rigid and self.nrigid:
            g = self.rigid_rows(pos).tocoo()
            parts.append((g.row + top, g.col, g.data))
            top += g.shape[0]
        m = len(idx)
        if m:
            beads = idx.ravel()
            vecs = (wts[:, :, None] * direc[:, None, :]).reshape(-1, 3)
            ok = beads >= 0
            r, c, v = self._triplets(np.repeat(np.arange(m), 4)[ok], beads[ok], vecs[ok])
            parts.append((r + top, c, v))
            top += m
        r, c, v = (np.concatenate(x) for x in zip(*parts, strict=True))
        return sp.csr_matrix((v, (r, c)), shape=(top, 3 * self.nf))

    def rigid_rows(self, pos):
        """Six sparse gauge rows that remove the rigid motions (closed chains): bead 0 does not
        move, bead 1 moves only along b_0 = r_1 − r_0, and the bead farthest from that line
        does not leave the plane it spans with it; E, the bonds and the exclusion rule are
        invariant under rigid motions, so this fixes nothing physical. A clamped open chain
        keeps one zero mode, the rotation about z: one free bead does not move azimuthally."""
        p = pos[self.free]
        if self.closed:
            e1 = p[1] - p[0]
            e1 = e1 / np.linalg.norm(e1)
            rel = p - p[0]
            perp = rel - np.outer(rel @ e1, e1)
            far = int(np.argmax(np.linalg.norm(perp, axis=1)))
            nrm = np.cross(e1, perp[far])
            nrm /= np.linalg.norm(nrm)
            t2 = np.cross(nrm, e1)
            beads = [0, 0, 0, 1, 1, far]
            vecs = [np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], nrm, t2, nrm]
        else:
            rho = np.hypot(p[:, 0], p[:, 1])
            far = int(np.argmax(rho))
            beads = [far]
            vecs = [np.array([-p[far, 1], p[far, 0], 0.0]) / rho[far]]
        rows = np.repeat(np.arange(len(beads)), 3)
        cols = (3 * np.array(beads)[:, None] + np.arange(3)).ravel()
        return sp.csr_matrix((np.concatenate(vecs), (rows, cols)),
                             shape=(len(beads), 3 * self.nf))

    def hessian(self, pos, lam, cons, wts, mu):
        """Hessian of the Lagrangian ∇²E − Σ λ_k ∇²c_k − Σ μ_p ∇²g_p (free coordinates).

        E, the bonds and the vertex–vertex pieces are isotropic (an N_f × N_f matrix ⊗ I₃,
        exact); vertex–segment and segment–segment pieces add their exact 12 × 12 blocks.
        """
        fm = self.fmap
        ja, jv, jc = self.ja, self.jv, self.jc
        ones = np.ones(len(jv))
        # E = Σ (1 − b_{v−1}·b_v): (v,v) +2, (v,a) −1, (v,c) −1, (a,c) +1 (symmetrised)
        r = [jv, jv, ja, jv, jc, ja, jc]
        c = [jv, ja, jv, jc, jv, jc, ja]
        v = [2 * ones, -ones, -ones, -ones, -ones, ones, ones]
        # −λ_k ∇²(|b_k|² − 1): 2 on the diagonal, −2 off it
        k, k1 = self.bk, self.bk1
        r += [k, k1, k, k1]
        c += [k, k1, k1, k]
        v += [-2 * lam, -2 * lam, 2 * lam, 2 * lam]
        iso = np.zeros(0, dtype=bool)
        if len(cons):
            idx = cons.idx
            coef = np.where(cons.form == 0, -2.0 * mu, 0.0)
            iso = (cons.ctype == 0) & (coef != 0)  # vertex–vertex: −2μ w wᵀ ⊗ I, exact
            for s in range(4):
                for t in range(4):
                    ok = (idx[:, s] >= 0) & (idx[:, t] >= 0) & iso
                    r.append(idx[ok, s])
                    c.append(idx[ok, t])
                    v.append(coef[ok] * wts[ok, s] * wts[ok, t])
        r = np.concatenate(r)
        c = np.concatenate(c)
        v = np.concatenate(v)
        fr, fc = fm[r], fm[c]
        ok = (fr >= 0) & (fc >= 0)
        m = sp.coo_matrix((v[ok], (fr[ok], fc[ok])), shape=(self.nf, self.nf)).tocsr()
        h = sp.kron(m, sp.identity(3), format="csr")
        other = np.flatnonzero((mu != 0) & (cons.ctype != 0)) if len(cons) else []
        if len(other):
            h = h + self._piece_blocks(pos, cons.sub(other), mu[other])
        return h

    def _piece_blocks(self, pos, cons, mu):
        """−μ_p ∇²g_p for vertex–segment and segment–segment pieces (exact second
        derivatives of the point–line and line–line distances, :func:`_piece_hessians`)."""
        m = len(cons)
        hloc = np.empty((m, 12, 12))
        _piece_hessians(pos, cons.ctype, cons.idx, cons.form, hloc)
        hloc *= -mu[:, None, None]
        fm = self.fmap
        beads = np.where(cons.idx >= 0, cons.idx, 0)
        f = np.where(cons.idx >= 0, fm[beads], -1)  # (m, 4) free index or −1
        gi = (3 * f[:, :, None] + np.arange(3)).reshape(m, 12)
        ok = np.repeat(f >= 0, 3, axis=1)
        rows = np.broadcast_to(gi[:, :, None], (m, 12, 12))
        cols = np.broadcast_to(gi[:, None, :], (m, 12, 12))
        keep = ok[:, :, None] & ok[:, None, :] & (hloc != 0.0)
        n3 = 3 * self.nf
        return sp.coo_matrix((hloc[keep], (rows[keep], cols[keep])), shape=(n3, n3)).tocsr()


def _kkt_matrix(h, a, reg=0.0):
    """[h aᵀ; a −reg·I] as CSC, assembled from the blocks' triplets in one go: the same
    matrix as ``sp.bmat([[h, a.T], [a, -reg·I]])`` (tested), without bmat's per-call
    overhead, which cost more than the factorisation in the polish (profile in
    bench/RESULTS.md)."""
    n, m = h.shape[0], a.shape[0]
    hc, ac = h.tocoo(), a.tocoo()
    rows = [hc.row, ac.col, ac.row + n]
    cols = [hc.col, ac.row + n, ac.col]
    vals = [hc.data, ac.data, ac.data]
    if reg > 0:
        d = np.arange(n, n + m)
        rows.append(d)
        cols.append(d)
        vals.append(np.full(m, -reg))
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n + m, n + m))


def _solve_kkt(h, a, rhs_top, rhs_bot, reg=0.0):
    """Solve [h aᵀ; a −reg·I][x; y] = [rhs_top; rhs_bot]; returns (x, y) or None."""
    n = h.shape[0]
    k = _kkt_matrix(h, a, reg)
    try:
        lu = _splu(k)
        z = lu.solve(np.r_[rhs_top, rhs_bot])
    except RuntimeError:
        return None
    if not np.all(np.isfinite(z)):
        return None
    return z[:n], z[n:]


@njit(cache=True)
def _row_entries(n, fmap, bk, bk1, b, idx, wts, direc):
    """The rows of A = [bond rows; piece rows] (free beads only), grouped by bead: bead v's
    entries are ``row[start[v]:start[v + 1]]`` with 3-vectors ``vec[...]`` (A's block of that
    row on bead v). Bond k: +2b_k on bead k + 1, −2b_k on bead k (∇(|b_k|² − 1)); piece p:
    w[p, s]·dir[p] on bead idx[p, s] (:meth:`_Cons.evaluate`)."""
    nb = bk.shape[0]
    m = idx.shape[0]
    cnt = np.zeros(n + 1, dtype=np.int64)
    for r in range(nb):
        if fmap[bk[r]] >= 0:
            cnt[bk[r] + 1] += 1
        if fmap[bk1[r]] >= 0:
            cnt[bk1[r] + 1] += 1
    for i in range(m):
        for s in range(4):
            v = idx[i, s]
            if v >= 0 and fmap[v] >= 0:
                cnt[v + 1] += 1
    start = np.cumsum(cnt)
    fill = start[:n].copy()
    row = np.empty(start[n], dtype=np.int64)
    vec = np.empty((start[n], 3))
    for r in range(nb):
        for v, sg in ((bk1[r], 2.0), (bk[r], -2.0)):
            if fmap[v] >= 0:
                e = fill[v]
                row[e] = r
                for c in range(3):
                    vec[e, c] = sg * b[r, c]
                fill[v] += 1
    for i in range(m):
        for s in range(4):
            v = idx[i, s]
            if v >= 0 and fmap[v] >= 0:
                e = fill[v]
                row[e] = nb + i
                for c in range(3):
                    vec[e, c] = wts[i, s] * direc[i, c]
                fill[v] += 1
    return start, row, vec


@njit(cache=True)
def _gram_dense(nrows, start, row, vec, reg):
    """G = A Aᵀ + reg·I (dense) from :func:`_row_entries`: G_ij = Σ_v A_iv·A_jv."""
    g = np.zeros((nrows, nrows))
    for v in range(start.shape[0] - 1):
        for p in range(start[v], start[v + 1]):
            for q in range(start[v], start[v + 1]):
                g[row[p], row[q]] += (vec[p, 0] * vec[q, 0] + vec[p, 1] * vec[q, 1]
                                      + vec[p, 2] * vec[q, 2])
    for i in range(nrows):
        g[i, i] += reg
    return g


@njit(cache=True)
def _gram_triplets(start, row, vec):
    """The (i, j, A_iv·A_jv) triplets of G = A Aᵀ (duplicates to be summed)."""
    tot = 0
    for v in range(start.shape[0] - 1):
        k = start[v + 1] - start[v]
        tot += k * k
    ri = np.empty(tot, dtype=np.int64)
    ci = np.empty(tot, dtype=np.int64)
    val = np.empty(tot)
    t = 0
    for v in range(start.shape[0] - 1):
        for p in range(start[v], start[v + 1]):
            for q in range(start[v], start[v + 1]):
                ri[t] = row[p]
                ci[t] = row[q]
                val[t] = vec[p, 0] * vec[q, 0] + vec[p, 1] * vec[q, 1] + vec[p, 2] * vec[q, 2]
                t += 1
    return ri, ci, val


@njit(cache=True)
def _apply_at(n, fmap, start, row, vec, y, out):
    """out[f(v)] = Σ_rows A_rv·y_r = (Aᵀy) on every free bead v (out: (N_f, 3))."""
    for v in range(n):
        f = fmap[v]
        if f < 0:
            continue
        for c in range(3):
            out[f, c] = 0.0
        for p in range(start[v], start[v + 1]):
            for c in range(3):
                out[f, c] += vec[p, c] * y[row[p]]


#: G = A Aᵀ of the projection is factorised densely (LAPACK Cholesky) up to this many rows
#: (bonds + held pieces), as a sparse LU above: 0.25 ms dense at 200 rows, 1.9 ms at 400
#: (N = 150 runs ≈ 150–250 rows; the sparse KKT's factorisation cost ≈ 1 ms with its assembly)
DENSE_GRAM_ROWS = 320


class _MinNormSolver:
    """The min-norm correction of the projection: dx = Aᵀ(AAᵀ)⁻¹r solves A dx = r with the
    least ‖dx‖ (the KKT system [I Aᵀ; A 0] of the projection, reduced to its Schur complement
    G = AAᵀ: symmetric positive definite when the rows are independent). Dependent rows (two
    contacts holding the same motion) get G + reg·I, reg = 10⁻¹², 10⁻⁹ in turn — the dual
    regularisation [I Aᵀ; A −reg·I] the full KKT system used. Dense Cholesky up to
    :data:`DENSE_GRAM_ROWS` rows, sparse LU of G above."""

    def __init__(self, prob, b, idx, wts, direc):
        self.p = prob
        self.nrows = len(prob.bk) + len(idx)
        self.start, self.row, self.vec = _row_entries(prob.n, prob.fmap, prob.bk, prob.bk1, b,
                                                      idx, wts, direc)
        self.solve_g = self._factor()

    def _factor(self):
        nr = self.nrows
        if nr <= DENSE_GRAM_ROWS:
            for reg in (0.0, 1e-12, 1e-9):
                g = _gram_dense(nr, self.start, self.row, self.vec, reg)
                try:
                    c = scipy.linalg.cho_factor(g, check_finite=False)
                except np.linalg.LinAlgError:
                    continue
                if np.all(np.isfinite(c[0])) and np.all(np.diag(c[0]) > 0.0):
                    return lambda r, c=c: scipy.linalg.cho_solve(c, r, check_finite=False)
            return None
        ri, ci, val = _gram_triplets(self.start, self.row, self.vec)
        for reg in (0.0, 1e-12, 1e-9):
            d = np.arange(nr)
            g = sp.csc_matrix((np.r_[val, np.full(nr, reg)], (np.r_[ri, d], np.r_[ci, d])),
                              shape=(nr, nr))
            try:
                lu = _splu(g)
            except RuntimeError:
                continue
            if np.all(np.isfinite(lu.solve(np.ones(nr)))):
                return lu.solve
        return None

    def solve(self, rhs):
        """dx (N_f, 3) with A dx = rhs and the least norm."""
        y = self.solve_g(rhs)
        out = np.empty((self.p.nf, 3))
        _apply_at(self.p.n, self.p.fmap, self.start, self.row, self.vec, y, out)
        return out


class _SchurInverse:
    """The inverse of S_WW = J_W K⁻¹ J_Wᵀ for a working set W that changes a few pieces at a
    time: bordering updates (O(|W|²)) on additions and removals, a fresh inverse every 64
    changes. If S_WW is numerically singular (dependent pieces: several contacts holding the
    same motion), S_WW + εI with ε = 10⁻¹²·max|S_ii| is inverted instead: it lets the
    linearised pieces move by ε·μ, which the projection removes."""

    def __init__(self):
        self.order = np.zeros(0, dtype=np.int64)
        self.inv = np.zeros((0, 0))
        self.changes = 0
        self.eps = 0.0

    def _fresh(self, sel, block):
        smat = block(sel, sel)
        self.order = sel
        self.changes = 0
        self.eps = 0.0
        eye = np.eye(len(sel))
        try:
            self.inv = np.linalg.inv(smat)
            ok = np.abs(self.inv @ smat - eye).max() < 1e-6 if len(sel) else True
        except np.linalg.LinAlgError:
            ok = False
        if not ok:  # dependent pieces: a tiny shift
            self.eps = 1e-12 * max(float(np.max(np.abs(np.diag(smat)))), 1e-300)
            self.inv = np.linalg.inv(smat + self.eps * eye)
        return sel

    def sync(self, sel, block):
        """Bring the inverse to the working set ``sel`` (sorted indices); returns the
        order of its rows (a permutation of ``sel``)."""
        cur = self.order
        in_cur = set(cur.tolist())
        in_sel = set(sel.tolist())
        added = [a for a in sel.tolist() if a not in in_cur]
        removed = [r for r in cur.tolist() if r not in in_sel]
        nchange = len(added) + len(removed)
        if self.changes + nchange > 64 or nchange > 16 or not cur.size:
            return self._fresh(sel, block)
        inv = self.inv
        for r in removed:
            k = int(np.flatnonzero(cur == r)[0])
            piv = inv[k, k]
            if abs(piv) < 1e-300:
                return self._fresh(sel, block)
            col = np.delete(inv[:, k], k)
            row = np.delete(inv[k, :], k)
            inv = np.delete(np.delete(inv, k, axis=0), k, axis=1)
            inv -= np.outer(col, row) / piv
            cur = np.delete(cur, k)
        for a in added:
            sv = block(cur, np.array([a]))[:, 0]
            c = float(block(np.array([a]), np.array([a]))[0, 0]) + self.eps
            isv = inv @ sv
            gam = c - float(sv @ isv)
            if abs(gam) <= 1e-12 * max(abs(c), 1e-300):
                return self._fresh(sel, block)
            m = cur.size
            grown = np.empty((m + 1, m + 1))
            grown[:m, :m] = inv + np.outer(isv, isv) / gam
            grown[:m, m] = -isv / gam
            grown[m, :m] = -isv / gam
            grown[m, m] = 1.0 / gam
            inv = grown
            cur = np.append(cur, a)
        self.order = cur
        self.inv = inv
        self.changes += nchange
        return cur


_LIBC: list = []
_HELD_LOCK = threading.Lock()
_HELD: list = []  # the saved (stdout, stderr) descriptors while diagnostics are held back
_HELD_COUNT = [0]  # threads inside _superlu_diagnostics_held


def _libc():
    """The C library (for fflush), or None where it cannot be loaded."""
    if not _LIBC:
        try:
            _LIBC.append(ctypes.CDLL(None))
        except OSError:  # pragma: no cover - every POSIX system has one
            _LIBC.append(None)
    return _LIBC[0]


@contextlib.contextmanager
def _superlu_diagnostics_held():
    """Hold back what SuperLU prints while it factorises.

    On an exactly singular matrix (dependent constraint pieces, e.g. several tube pieces
    holding the same motion) SuperLU's factorisation prints LAPACK-style lines such as
    ``** On entry to DTRSV parameter number 6 had an illegal value`` on C's standard output
    and then raises ``RuntimeError: Factor is exactly singular``, which the callers handle
    (a retry with a tiny dual regularisation). The lines said nothing a user could act on and
    read like a failure of the result, so C's standard output and error point at the null
    device for the factorisation alone (C's buffers are flushed on both sides of it)."""
    libc = _libc()
    if libc is None:  # pragma: no cover
        yield
        return
    # the file descriptors are the process's: threads that factorise at once share one
    # redirection (the first in saves and redirects, the last out restores), never save
    # each other's /dev/null
    with _HELD_LOCK:
        if not _HELD:
            for f in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):
                    f.flush()
            libc.fflush(None)
            null = os.open(os.devnull, os.O_WRONLY)
            saved = (os.dup(1), os.dup(2))
            os.dup2(null, 1)
            os.dup2(null, 2)
            os.close(null)
            _HELD.append(saved)
        _HELD_COUNT[0] += 1
    try:
        yield
    finally:
        with _HELD_LOCK:
            _HELD_COUNT[0] -= 1
            if not _HELD_COUNT[0]:
                saved = _HELD.pop()
                libc.fflush(None)
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)


def _splu(k):
    """``splu(k)`` with SuperLU's diagnostics held back (:func:`_superlu_diagnostics_held`);
    a singular matrix still raises RuntimeError."""
    with _superlu_diagnostics_held():
        return splu(k)


def _factor_kkt(h, a):
    """Sparse LU of [h aᵀ; a 0] (with a tiny dual regularisation if it is singular)."""
    for reg in (0.0, 1e-12, 1e-9):
        try:
            lu = _splu(_kkt_matrix(h, a, reg))
        except RuntimeError:
            continue
        test = lu.solve(np.ones(h.shape[0] + a.shape[0]))
        if np.all(np.isfinite(test)):
            return lu
    return None


def _solve_kkt_robust(h, a, rhs_top, rhs_bot):
    """:func:`_solve_kkt`, with a growing dual regularisation if the matrix is singular
    (dependent constraints)."""
    for reg in (0.0, 1e-12, 1e-9):
        out = _solve_kkt(h, a, rhs_top, rhs_bot, reg)
        if out is not None:
            return out
    return None


class _Polisher:
    def __init__(self, prob: _Problem, max_step: float, guard: bool, zlo: float, zhi: float,
                 max_depth: int):
        self.p = prob
        self.max_step = max_step
        self.guard = guard
        self.zlo = zlo
        self.zhi = zhi
        self.max_depth = max_depth
        self.margin = 2.0 * max_step + 0.05

    # ---- measures ------------------------------------------------------------------------
    def energy(self, pos):
        return float(energy_chain(pos, self.p.is_open))

    def grad_free(self, pos):
        e, g = _energy_grad(pos, self.p.is_open)
        return e, g[self.p.free].ravel()

    def clearance(self, pos):
        """Min over the exclusion rule of (distance − limit) (capped at 1; inf for none)."""
        if self.p.mode == 2:
            return math.inf
        return float(_min_clearance(pos, self.p.mode, self.p.limit, self.p.is_open))

    def strand_gap(self, pos):
        """Min distance between segments that share no bead (capped at 1)."""
        return float(_min_clearance(pos, 1, 0.0, self.p.is_open))

    def passage_ok(self, old, new):
        return bool(_passage_ok(old, new, self.p.is_open, self.p.nfix, self.zlo, self.zhi,
                                self.max_depth))

    def step_ok(self, old, new):
        p = self.p
        if p.is_open:
            inner = new[p.nfix:p.n - p.nfix, 2]
            if np.any(inner <= self.zlo) or np.any(inner >= self.zhi):
                return False
        if p.mode != 2 and self.clearance(new) < 0.0:
            return False
        if p.gap > 0 and self.strand_gap(new) < p.gap:
            return False
        return not self.guard or self.passage_ok(old, new)

    # ---- multipliers and the KKT residual ------------------------------------------------
    def kkt(self, pos):
        """(residual, ‖∇E‖, λ, active keys, μ) at ``pos``: least-squares multipliers with
        μ ≥ 0 over the pieces within ACTIVE_TOL of their limit (active-set NNLS)."""
        p = self.p
        _, g = self.grad_free(pos)
        gn = float(np.linalg.norm(g))
        cons = p.candidates(pos, 1e-3)
        dist, _, wts, direc = cons.evaluate(pos)
        act = np.flatnonzero(dist - cons.lim <= ACTIVE_TOL)
        _, b = p.bond_residual(pos)
        nb = len(p.bk)
        mu = np.zeros(0)
        for _ in range(100):
            a = p.jacobian(pos, b, cons.idx[act], wts[act], direc[act], rigid=False)
            out = _solve_kkt_robust(sp.identity(a.shape[1], format="csr"), a, g,
                                    np.zeros(a.shape[0]))
            if out is None:
                return math.inf, gn, np.zeros(nb), cons.key[act], np.zeros(len(act))
            _, nu = out
            mu = nu[nb:]
            if not len(mu) or mu.min() >= -1e-14 * max(1.0, float(np.abs(mu).max())):
                break
            act = np.delete(act, int(np.argmin(mu)))
        res = g - a.T @ nu
        return float(np.linalg.norm(res)), gn, nu[:nb], cons.key[act], np.clip(mu, 0.0, None)

    # ---- projection onto the bonds and the held pieces ------------------------------------
    def project(self, pos, cons, hold, max_it=25):
        """Min-norm projection onto c = 0 and g_p = 0 for the held and the violated pieces:
        Gauss–Newton with the factorisation reused while the held set does not change (chord
        method; the corrections are small, so it converges fast), refactorised when it does
        or when the residual stops shrinking. Stops when every bond is unit to ~1e-13 and
        every piece is at least its target up to τ/2."""
        p = self.p
        y = pos.copy()
        hold = hold.copy()
        lu = None
        held = None
        last = math.inf
        for _ in range(max_it):
            c, b = p.bond_residual(y)
            dist, g, wts, direc = cons.evaluate(y)
            bond_ok = not len(c) or np.max(np.abs(c)) <= 2 * BOND_TOL_OUT
            # one-sided: every piece at least its target (limit + τ) up to τ/2
            if bond_ok and (not len(dist) or np.min(dist - cons.target) >= -0.5 * TAU):
                return y
            hold |= g < 0.0
            sel = np.flatnonzero(hold)
            rhs = -np.r_[c, g[sel]]
            size = float(np.max(np.abs(rhs)))
            if size > 1e3 * last:
                return None  # diverging: the step was too long for the linearisation
            if lu is None or not np.array_equal(sel, held) or size > 0.25 * last:
                lu = _MinNormSolver(p, b, cons.idx[sel], wts[sel], direc[sel])
                if lu.solve_g is None:
                    return None
                held = sel
            last = size
            dx = lu.solve(rhs)
            if not np.all(np.isfinite(dx)) or np.max(np.abs(dx)) > 0.5:
                return None
            y[p.free] += dx
        return None

    # ---- one SQP step --------------------------------------------------------------------
    def qp_step(self, pos, g, lam, mu_of, sigma, margin):
        """Solve the QP by a primal active-set method (Nocedal & Wright, Alg. 16.3).

        Starts at dx = 0 (feasible: every piece has g ≥ 0 there) with the tight pieces as
        working set and adds one blocking piece or drops the most negative multiplier per
        iteration; a direction of non-positive curvature is followed until a piece blocks
        (inertia control). The base KKT matrix [H Aᵀ; A 0] (A: bonds and rigid rows) is
        factorised once; working-set changes go through the dense Schur complement
        S = J K⁻¹ Jᵀ over the candidate pieces. Returns (dx (nf, 3), λ, μ (per candidate),
        working set, candidates, predicted decrease, ∇E·dx, dxᵀ(H + σI)dx, clean, direction
        of non-positive curvature or None) or None; ``clean`` is False when the subproblem is
        unbounded along such a direction or does not finish.
        """
        p = self.p
        cons = p.candidates(pos, margin)
        dist, gval, wts, direc = cons.evaluate(pos)
        # the projection restores feasibility exactly, so the QP asks for a tangential step:
        # no bond correction, and pieces at (or within τ below) their target stay put
        gq = np.maximum(gval, 0.0)
        key = cons.key
        mu = np.array([mu_of.get(int(k), 0.0) for k in key]) if len(key) else np.zeros(0)
        _, b = p.bond_residual(pos)
        h = p.hessian(pos, lam, cons, wts, mu)
        if sigma > 0:
            h = h + sigma * sp.identity(h.shape[0])
        nb = len(p.bk)
        nm = len(key)
        n = h.shape[0]
        a0 = p.jacobian(pos, b, cons.idx[:0], wts[:0], direc[:0], rigid=True)
        na = a0.shape[0]
        lu = _factor_kkt(h, a0)
        if lu is None:
            return None
        u0 = lu.solve(np.r_[-g, np.zeros(na)])
        if nm:
            jall = p.jacobian(pos, b, cons.idx, wts, direc, rigid=False)[nb:]
            ju0 = jall @ u0[:n]
            vcols = np.zeros((n + na, nm), order="F")  # K⁻¹ [J_pᵀ; 0], on demand
            sv = np.zeros((nm, nm), order="F")  # J_p K⁻¹ J_qᵀ, columns on demand (dense)
            have = np.zeros(nm, dtype=bool)
        scale = np.where(cons.form == 0, 2.0 * cons.target, 1.0) if nm else np.zeros(0)
        work = gq <= 1e-12 * scale  # tight pieces (a distance within ~1e-12 of its target)
        dx = np.zeros(n)
        nu_b = np.zeros(nb)
        nu_c = np.zeros(nm)
        clean = True
        lin = gq.copy()
        ncdir = None
        schur = _SchurInverse()
        n_inner = 0
        for _ in range(4 * nm + 20):
            n_inner += 1
            sel = np.flatnonzero(work)
            if sel.size:
                need = sel[~have[sel]]
                if need.size:
                    rhs_cols = np.zeros((n + na, need.size))
                    for j, r in enumerate(need.tolist()):  # column j: J's row r (CSR)
                        lo, hi = jall.indptr[r], jall.indptr[r + 1]
                        np.add.at(rhs_cols[:, j], jall.indices[lo:hi], jall.data[lo:hi])
                    vcols[:, need] = lu.solve(rhs_cols)
                    sv[:, need] = jall @ vcols[:n, need]
                    have[need] = True
                # inverse of the Schur complement J_W K⁻¹ J_Wᵀ, kept up to date (its blocks
                # read from the dense columns: no sparse row indexing in the inner loop)
                sel = schur.sync(sel, lambda rows, cols: sv[np.ix_(rows, cols)])
                y = schur.inv @ (ju0[sel] + gq[sel])
                z = u0 - vcols[:, sel] @ y
            else:
                y = np.zeros(0)
                z = u0
            step = z[:n] - dx
            if np.max(np.abs(step)) > 1e-14 * max(1.0, float(np.max(np.abs(dx)))):
                hs = h @ step
                cs = float(step @ hs)
                alpha = 1.0
                if not cs > 0.0:
                    # non-positive curvature inside the working set: follow the direction
                    # downhill until a piece blocks (inertia control); unbounded otherwise
                    if float((g + h @ dx) @ step) > 0.0:
                        step = -step
                    smax = float(np.max(np.linalg.norm(step.reshape(-1, 3), axis=1)))
                    alpha = 1.0 / smax if smax > 0 else 0.0  # at most one bond length
                block = np.zeros(0, dtype=np.int64)
                if nm:
                    js = jall @ step
                    cand = np.flatnonzero(~work & (js < 0.0))
                    if cand.size:
                        ratios = np.maximum(lin[cand], 0.0) / -js[cand]
                        k = int(np.argmin(ratios))
                        if ratios[k] < alpha:
                            alpha = float(ratios[k])
                            # every piece that blocks at the same length (symmetric starts)
                            block = cand[ratios <= alpha * (1.0 + 1e-9) + 1e-300]
                if not cs > 0.0 and np.size(block) == 0:
                    clean = False
                    ncdir = step.reshape(-1, 3)
                    break
                dx = dx + alpha * step
                if nm:
                    lin = gq + jall @ dx
                if block.size:
                    work[block] = True
                    continue
                # full step: the multipliers of this working set are the QP's if all ≥ 0
            nu_b = -z[n:n + nb]
            nu_c = np.zeros(nm)
            nu_c[sel] = -y
            if not sel.size:
                break
            k = int(np.argmin(nu_c[sel]))
            tol_nu = -1e-12 * max(1e-300, float(np.max(np.abs(nu_c))))
            if nu_c[sel][k] >= tol_nu:
                break
            work[sel[k]] = False  # release the piece with the most negative multiplier
        else:
            clean = False
        log.debug("  QP: %d candidates, %d in the working set, %d inner iterations", nm,
                  int(work.sum()), n_inner)
        curv = float(dx @ (h @ dx))
        gd = float(g @ dx)
        pred = -(gd + 0.5 * (curv - sigma * float(dx @ dx)))
        return dx.reshape(-1, 3), nu_b, nu_c, work, cons, pred, gd, curv, clean, ncdir

    def curvature_step(self, x, e, direction, cons, length):
        """Line search along a direction of non-positive curvature (either sign, longest
        first); returns (y, E(y)) for the first admissible trial that lowers E, or
        (None, e)."""
        p = self.p
        dmax = float(np.max(np.linalg.norm(direction, axis=1)))
        if not dmax > 0.0 or not np.isfinite(dmax):
            return None, e
        _, g = self.grad_free(x)
        sgn = -1.0 if float(g @ direction.ravel()) > 0.0 else 1.0
        unit = sgn * direction / dmax
        t = length
        none = np.zeros(len(cons), dtype=bool)
        for _ in range(8):
            for sg in (1.0, -1.0):
                y = x.copy()
                y[p.free] += sg * t * unit
                y = self.project(y, cons, none)
                if y is not None and self.step_ok(x, y):
                    ey = self.energy(y)
                    if ey < e - 1e-13 * max(1.0, abs(e)):
                        return y, ey
                    log.debug("    curvature trial t=%.2e: dE=%.3e", sg * t, ey - e)
                else:
                    log.debug("    curvature trial t=%.2e: %s", sg * t,
                              "projection failed" if y is None else "inadmissible")
            t *= 0.5
        return None, e

    def run(self, pos, max_iter, tol):
        p = self.p
        x = pos
        e = self.energy(x)
        res, gn, lam, akeys, amu = self.kkt(x)
        mu_of = dict(zip(akeys.tolist(), amu.tolist(), strict=True))
        sigma = 0.0
        it = 0
        nc_tries = 0
        reset_at = -1
        last_step = self.max_step
        reason = "max_iter reached"
        converged = False
        hist = [e]  # E after every accepted step
        while True:
            if res <= tol * gn:
                converged = True
                reason = "KKT residual below tol"
                break
            if len(hist) > STALL_STEPS and hist[-1 - STALL_STEPS] - e <= STALL_REL * abs(e) \
                    and res <= STALL_KKT * gn:
                # the last steps crawl: E is settled far below the 1e-6 the minimiser
                # promises, and the KKT residual is already within it
                converged = True
                reason = (f"stalled at the minimum (E changed by ≤ {STALL_REL:g}·E over "
                          f"{STALL_STEPS} steps, KKT residual ≤ {STALL_KKT:g}·‖∇E‖)")
                break
            if it >= max_iter:
                break
            margin = min(self.margin, 4.0 * last_step + 0.02)
            out = self.qp_step(x, self.grad_free(x)[1], lam, mu_of, sigma, margin)
            if out is None:
                reason = "KKT system could not be solved"
                break
            dx, nu_b, nu_c, act, cons, pred, gd, curv, clean, ncdir = out
            rounding = 1e-13 * max(1.0, abs(e))
            log.debug("it %d E %.15g kkt %.3e sigma %.1e pred %.3e gd %.3e curv %.3e nact %d "
                      "clean %s", it, e, res, sigma, pred, gd, curv, int(np.sum(act)), clean)
            if abs(pred) < rounding and abs(gd) < rounding and sigma > 1e-8 \
                    and reset_at != it:
                # below the resolution of E only because σ damps the step: look again with
                # the exact model (once per iterate)
                reset_at = it
                sigma = 0.0
                continue
            if clean and sigma <= 1e-8 and abs(pred) < rounding and abs(gd) < rounding:
                # the exact model sees no decrease E can resolve: stationary to rounding
                converged = res <= 1e-6 * gn
                reason = ("stationary to rounding (model decrease below the resolution of E)"
                          if converged else "stalled: no resolvable decrease, KKT residual "
                          "above 1e-6·‖∇E‖")
                break
            dmax = float(np.max(np.linalg.norm(dx, axis=1)))
            if not clean or pred <= 0.0 or gd >= 0.0 or dmax > 1.0:
                # negative curvature: first try to descend along it, else convexify (H + σI)
                # and solve again
                if ncdir is not None and nc_tries < 3:
                    nc_tries += 1
                    y, ey = self.curvature_step(x, e, ncdir, cons,
                                                min(self.max_step, 4.0 * last_step))
                    if y is not None:
                        log.debug("  negative-curvature step: E %.15g -> %.15g", e, ey)
                        it += 1
                        x, e = y, ey
                        res, gn, lam, akeys, amu = self.kkt(x)
                        mu_of = dict(zip(akeys.tolist(), amu.tolist(), strict=True))
                        continue
                sigma = max(10.0 * sigma, 1e-6)
                if sigma > 1e6:
                    converged = res <= 1e-6 * gn
                    reason = ("no descent direction left (KKT residual ≤ 1e-6·‖∇E‖)"
                              if converged else "no descent direction found")
                    break
                continue
            nc_tries = 0
            alpha = min(1.0, self.max_step / dmax) if dmax > 0 else 1.0
            accepted = False
            fails = [0, 0, 0]
            for _ls in range(40):
                y = x.copy()
                y[p.free] += alpha * dx
                y = self.project(y, cons, np.zeros(len(cons), dtype=bool))
                if y is None:
                    fails[0] += 1
                elif not self.step_ok(x, y):
                    fails[1] += 1
                else:
                    ey = self.energy(y)
                    armijo = ey <= e + 1e-4 * alpha * gd
                    if armijo or (ey <= e and -alpha * gd < rounding):
                        accepted = True
                        break
                    fails[2] += 1
                    if -alpha * gd < 0.1 * rounding and curv >= 0.0:
                        break  # shorter steps cannot lower E by a resolvable amount
                alpha *= 0.5
                if alpha * dmax < 1e-15:
                    break
            log.debug("  alpha %.3e dmax %.3e accepted %s fails (projection, admissibility, "
                      "energy) %s", alpha, dmax, accepted, fails)
            if not accepted:
                if sigma <= 1e-8 and abs(gd) < rounding and abs(pred) < rounding:
                    converged = res <= 1e-6 * gn
                    reason = ("stationary to rounding (model decrease below the resolution of "
                              "E)" if converged else "stalled: line search failed")
                    break
                if sigma < 1e4:
                    sigma = max(10.0 * sigma, 1e-4)
                    continue
                reason = "line search failed"
                break
            it += 1
            last_step = max(alpha * dmax, 1e-3)
            x = y
            e = ey
            hist.append(e)
            lam = nu_b
            pos_mu = nu_c > 0
            mu_of = dict(zip(cons.key[pos_mu].tolist(), nu_c[pos_mu].tolist(), strict=True))
            if alpha * dmax >= 0.999 * min(dmax, self.max_step):
                sigma = sigma * 0.1 if sigma > 1e-10 else 0.0
            res, gn, _, _, _ = self.kkt(x)
        return x, e, it, converged, reason


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------


def _validate(pos, closed, exclusion, d, w, clamp_ends, max_iter, tol, max_step):
    x = np.array(pos, dtype=np.float64, order="C", copy=True)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"pos must have shape (N, 3), got {x.shape}")
    n = x.shape[0]
    if n < 8:
        raise ValueError(f"a chain needs at least 8 beads, got {n}")
    if not np.all(np.isfinite(x)):
        raise ValueError("pos contains NaN or infinite coordinates")
    if exclusion not in EXCLUSIONS:
        raise ValueError(f"unknown exclusion {exclusion!r}; allowed: {', '.join(EXCLUSIONS)}")
    if not 0 < d < 1 or not 0 < w < 1:
        raise ValueError(f"d and w must lie in (0, 1) bond lengths, got d={d}, w={w}")
    if int(max_iter) != max_iter or max_iter < 0:
        raise ValueError(f"max_iter must be an integer ≥ 0, got {max_iter}")
    if not tol > 0:
        raise ValueError(f"tol must be > 0, got {tol}")
    if not 0 < max_step <= 1:
        raise ValueError(f"max_step must be in (0, 1], got {max_step}")
    bonds = np.linalg.norm((np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0),
                           axis=1)
    err = float(np.max(np.abs(bonds - 1.0)))
    if err > BOND_TOL_IN:
        raise ValueError(f"bonds must have unit length to {BOND_TOL_IN:g} (worst {err:.2e})")
    nfix = 0
    if closed:
        if clamp_ends not in (None, 0):
            raise ValueError("clamp_ends applies to open chains only (closed=False)")
    else:
        nfix = 2 if clamp_ends is None else int(clamp_ends)
        if nfix != clamp_ends and clamp_ends is not None:
            raise ValueError(f"clamp_ends must be an integer, got {clamp_ends}")
        if nfix < 2 or n - 2 * nfix < 2:
            raise ValueError(f"clamp_ends must be ≥ 2 and leave ≥ 2 free beads, got {nfix} "
                             f"for N = {n}")
        ends = x[[0, 1, -2, -1]]
        if np.max(np.abs(ends[:, :2])) > 1e-9:
            raise ValueError("an open chain needs beads 0, 1, N−2, N−1 on the z axis")
        if ends[1, 2] <= ends[0, 2] or ends[3, 2] <= ends[2, 2]:
            raise ValueError("an open chain's end segments must point along −z (first) and "
                             "+z (last)")
        inner = x[1:-1, 2]
        if np.any(inner <= x[0, 2]) or np.any(inner >= x[-1, 2]):
            raise ValueError("every bead but the end beads must lie strictly between z_0 and "
                             "z_{N−1} (the closure rays run along z beyond the ends)")
    return x, nfix


def polish(
    pos,
    *,
    closed: bool = True,
    exclusion: str = "bead",
    d: float = float(1 / np.sqrt(2)),
    w: float = float(1 / np.sqrt(2)),
    clamp_ends: int | None = None,
    max_iter: int = 200,
    tol: float = 1e-10,
    max_step: float = 0.25,
    guard: bool | None = None,
    min_gap: float = 1e-4,
    guard_depth: int = 20,
) -> PolishResult:
    """Minimise the bending energy E_d of a unit-bond chain under its exclusion rule exactly.

    Finds the local minimum of E_d = Σ_joints (1 − u_n·u_{n+1}) (paper §VII) reached by a
    descent path from the input, with unit bonds and the exclusion rule held at every accepted
    iterate and no strand passage along the way (see the module docstring for the method, the
    KKT residual and the proof).

    Parameters
    ----------
    pos : (N, 3) chain with unit bonds (to 10⁻⁸) that satisfies its exclusion rule (to
        10⁻¹⁰).
    closed : closed ring (N bonds, N joints) or open chain (N − 1 bonds, N − 2 joints) with
        clamped ends (the fixed-extension ensemble of §VIII: beads 0, 1 and N−2, N−1 on the z
        axis, end segments along −z and +z, every other bead strictly between z_0 and
        z_{N−1}; the excess length L_e does not change).
    exclusion : ``"bead"`` (beads at index distance ≥ 2 at least ``d`` apart, §VII),
        ``"tube"`` (segments sharing no bead at least ``w`` apart, §II) or ``"none"``.
    d, w : exclusion distances (bond lengths).
    clamp_ends : open chains: beads held fixed at each end (default 2, the end segments).
    max_iter : largest number of accepted steps.
    tol : converged when the KKT residual is ≤ tol·‖∇E‖₂ (or, once no decrease of E is
        resolvable in floating point, ≤ 10⁻⁶·‖∇E‖₂; see the module docstring).
    max_step : largest displacement of any bead in one step (bond lengths).
    guard : strand-passage guard (default: on for ``bead`` and ``tube``, off for ``none``).
    min_gap : with the guard on and a rule that does not keep strands apart by itself
        (``bead``, ``none``), segments that share no bead are also kept ≥ ``min_gap`` apart.
        The bead rule with d = 1/√2 lets two segments touch (crossing at right angles at their
        midpoints, all four beads exactly d apart) and tight bead-model knots press into that
        singular configuration; the gap keeps the chain embedded and the problem well posed
        (nearly flat four-bead contacts make it degenerate as the gap goes to zero). The
        energy then lies above that of the touching limit by ≈ ``gap_force``·min_gap (first
        order; ≈ 3e-6 relative on the worst fixture at the default). If the input's strands
        are closer, half their distance is used instead.
    guard_depth : bisection levels the guard may use to certify a close pair (the guard
        rejects what it cannot certify).

    Returns
    -------
    PolishResult
        ``energy ≤ energy_before`` always: if no step lowers the energy the input comes back.

    Raises
    ------
    ValueError
        For a malformed chain (shape, non-unit bonds, exclusion violated by more than 10⁻¹⁰,
        bad open-chain clamping) or bad parameters.
    """
    t0 = time.perf_counter()
    x, nfix = _validate(pos, closed, exclusion, d, w, clamp_ends, max_iter, tol, max_step)
    if not 0 <= min_gap < 0.1:
        raise ValueError(f"min_gap must be in [0, 0.1), got {min_gap}")
    if int(guard_depth) != guard_depth or not 0 <= guard_depth <= 40:
        raise ValueError(f"guard_depth must be an integer in [0, 40], got {guard_depth}")
    n = x.shape[0]
    mode = EXCLUSIONS.index(exclusion)
    limit = d if mode == 0 else (w if mode == 1 else 0.0)
    guard = mode != 2 if guard is None else bool(guard)
    zrot = (not closed) and bool(np.max(np.abs(x[:nfix, :2])) <= 1e-12
                                 and np.max(np.abs(x[n - nfix:, :2])) <= 1e-12)
    zlo, zhi = (float(x[0, 2]), float(x[-1, 2])) if not closed else (0.0, 0.0)
    gap = 0.0
    if guard and mode != 1 and min_gap > 0:
        gap0 = float(_min_clearance(x, 1, 0.0, not closed))
        gap = min(float(min_gap), 0.5 * gap0)
    prob = _Problem(n, bool(closed), mode, limit, nfix, zrot, gap)
    pol = _Polisher(prob, float(max_step), guard, zlo, zhi, int(guard_depth))
    clear0 = pol.clearance(x)
    if clear0 < -1e-10:
        raise ValueError(f"the chain violates the {exclusion} exclusion rule by {-clear0:.3g}")
    e0 = pol.energy(x)
    # one BLAS thread: the dense matrices are small (the Cholesky of ≤ DENSE_GRAM_ROWS rows,
    # the working set's Schur complement), and replicas run on every core (the pool, Dask
    # workers), where OpenBLAS's threads oversubscribed them: two concurrent tube polishes
    # took 48 CPU s each with its default threads, 12.6 s with one (bench/RESULTS.md)
    with threadpool_limits(limits=1, user_api="blas"):
        # exact admissibility first: bonds to 1e-13, violated pieces pushed to limit + τ
        cons = prob.candidates(x, 1e-3)
        x1 = pol.project(x, cons, np.zeros(len(cons), dtype=bool))
        if x1 is None or (guard and not pol.passage_ok(x, x1)):
            x1 = x
        xf, ef, it, converged, reason = pol.run(x1, int(max_iter), float(tol))
        res, gn, _, akeys, amu = pol.kkt(xf)
    if ef > e0:  # nothing gained (only possible from the initial projection): keep the input
        xf, ef = x, e0
        reason += "; no energy decrease found, input returned"
        with threadpool_limits(limits=1, user_api="blas"):
            res, gn, _, akeys, amu = pol.kkt(xf)
    gap_force = float(np.sum(amu[akeys >= 3 * n * n])) if len(akeys) else 0.0
    cons = prob.candidates(xf, 1e-3)
    dist = cons.evaluate(xf)[0]
    n_active = int(np.sum(dist - cons.lim <= ACTIVE_TOL))
    bonds = np.linalg.norm((np.roll(xf, -1, axis=0) - xf) if closed else np.diff(xf, axis=0),
                           axis=1)
    if res <= tol * gn:
        converged = True
    return PolishResult(pos=xf.copy(), energy_before=e0, energy=ef, kkt_residual=res,
                        grad_norm=gn, iterations=it, converged=bool(converged), reason=reason,
                        n_active=n_active, max_bond_error=float(np.max(np.abs(bonds - 1.0))),
                        exclusion_margin=pol.clearance(xf), strand_gap=pol.strand_gap(xf),
                        gap_force=gap_force, seconds=time.perf_counter() - t0)


def passage_guard(old, new, *, closed: bool = True, clamp_ends: int | None = None,
                  guard_depth: int = 20) -> bool:
    """The strand-passage guard of :func:`polish` for the straight-line motion old → new.

    True when it certifies that no two segments that share no bead meet along the motion
    (D_before + D_after > L for every such pair, L ≤ δ_a + δ_b the largest relative
    displacement of their beads, on [0, 1] or on up to 2^guard_depth sub-intervals), that no
    two bonded segments fold onto each other and, for an open chain, that every free bead
    ends strictly inside the slab z_0 < z < z_{N−1}. See the module docstring.
    """
    a = np.ascontiguousarray(old, dtype=np.float64)
    b = np.ascontiguousarray(new, dtype=np.float64)
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"old and new must have the same shape (N, 3), got {a.shape}, "
                         f"{b.shape}")
    nfix = 0 if closed else (2 if clamp_ends is None else int(clamp_ends))
    zlo, zhi = (float(a[0, 2]), float(a[-1, 2])) if not closed else (0.0, 0.0)
    return bool(_passage_ok(a, b, not closed, nfix, zlo, zhi, int(guard_depth)))
