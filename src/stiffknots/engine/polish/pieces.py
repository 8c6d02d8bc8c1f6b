"""Constraint pieces of the final minimiser: the exclusion rule as smooth inequalities.

Every exclusion constraint is a *piece*: the vector v = Σ_i w_i r_i between two closest points
(barycentric weights on at most four beads) with ``g = |v|² − T² ≥ 0``, T = limit + τ, τ = 10⁻¹³
(so the final margin is ≥ 0 in floating point). ``bead`` pieces are bead pairs (the rule of
§VII). In the ``tube`` model (§II) the segment distance is split into vertex–vertex,
vertex–segment and (both closest points interior) segment–segment pieces; their minimum is
the segment distance, so they are equivalent to the rule, and strands in parallel contact get
one smooth piece per touching vertex instead of one kinked one. The Hessians of the
vertex–vertex pieces are isotropic (⊗ I₃); the others get exact 12 × 12 blocks (central
differences of the analytic gradients of the point–line and line–line distances).

The bead rule with d = 1/√2 lets two segments *touch* (crossing at right angles at their
midpoints, all four beads exactly d apart; any other crossing brings a pair closer), and tight
bead-model knots press strands into that configuration: the infimum is a non-embedded chain,
and near it the four bead pairs and the crossing form a nearly flat, degenerate contact. With
the guard on and a rule that does not separate strands by itself (``bead``, ``none``), segments
that share no bead are therefore also kept ≥ ``min_gap`` apart (distance-form pieces g = D − T,
whose multipliers are the forces that press the strands through each other); the energy then
exceeds the touching limit by ≈ ``gap_force``·min_gap.

The candidates (every piece within a margin of its limit) come from an O(N²) compiled scan;
``_min_clearance()`` measures the rule on all pairs, independently of the candidates.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.engine.guard import _half_length
from stiffknots.geometry import _clamp01, seg_dist2
from stiffknots.geometry import seg_params as _seg_params

TAU = 1e-13  # active contacts are held at limit + TAU, so the final margin is ≥ 0 in floats


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
