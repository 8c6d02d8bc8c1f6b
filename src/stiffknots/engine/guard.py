"""The strand-passage guard of a straight-line motion: no two strands meet along a step (§II).

The problem is posed for a given knot K (paper §II), so no step may pass one strand through
another. A step of the final minimiser (:mod:`stiffknots.engine.polish`), and the projection
that takes the Langevin search's chain onto unit bonds (:mod:`stiffknots.engine.langevin`),
move every bead along the straight line r_i(t) = r_i + t(r'_i − r_i), t ∈ [0, 1];
:func:`passage_guard` accepts such a motion only when it certifies the proof below.

No strand passage (proof)
-------------------------
For segments a = (a, a+1) and b = (b, b+1) and points at parameters s and u on them,
p_a − p_b moves with velocity (1−s)Δr_a + sΔr_{a+1} − (1−u)Δr_b − uΔr_{b+1}, a convex
combination of the four differences Δr_i − Δr_j (i ∈ a, j ∈ b); so every ``|p_a − p_b|`` is
L-Lipschitz in t with ``L = max |Δr_i − Δr_j| ≤ δ_a + δ_b`` (δ = the larger displacement of a
segment's two beads: a point of a segment moves at most as fast as the faster of its ends),
and so is their minimum, the segment distance D(t). On any interval [t₀, t₁],
D(t) ≥ (D(t₀) + D(t₁) − L(t₁ − t₀))/2. A motion is accepted only if, for every pair of
segments that share no bead,

    D(0) + D(1) − L > 2η,                                     η = 10⁻⁹ (``GUARD_FLOOR``),

or, failing that, the same inequality holds on every sub-interval of a bisection of [0, 1]
(at most 2^guard_depth pieces; D computed at the new nodes). Then D(t) > η > 0 for all t:
no two such segments meet at any time. (The floor η makes the certificate immune to
rounding: at a true crossing the computed D can be 10⁻¹⁷ rather than 0.) Two segments that
share bead k could only meet elsewhere by folding back (collinear and overlapping), i.e. with
the far end of one on the other: the same certificate is required for r_{k+1} against
[r_{k−1}, r_k] and for r_{k−1} against [r_k, r_{k+1}] (both exclusion rules keep these
distances positive at every admissible state). So the polygon stays embedded along the whole
motion — an isotopy — and its knot type cannot change; this is the Lipschitz argument of
:mod:`stiffknots.engine.kernel` applied to straight-line motions (with the relative
displacement, and on sub-intervals). For an open chain the knot type is that of the closure
along the z-axis rays beyond the clamped end segments: each free bead must end strictly inside
the slab z_0 < z < z_{N−1}, and z is linear in t, so the whole path stays in the slab and no
segment touches a ray. Pairs with D(1) > δ_a + δ_b + η are skipped by a screen on segment
midpoints, so the guard is one O(N²) pass of cheap tests plus a few bisections.

The Langevin dynamics certifies its own steps by running bounds against the same floor
(:mod:`stiffknots.engine.langevin_kernel`). The ``@njit`` kernels see arrays and numbers
only; :func:`passage_guard` checks its arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.geometry import seg_dist2

#: the guard certifies that strands stay this far apart (≫ rounding)
GUARD_FLOOR = 1e-9


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


def passage_guard(old, new, *, closed: bool = True, clamp_ends: int | None = None,
                  guard_depth: int = 20) -> bool:
    """The strand-passage guard of the final minimiser for the straight-line motion old → new.

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
