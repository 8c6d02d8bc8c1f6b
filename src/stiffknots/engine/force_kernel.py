"""Compiled end moves for open chains at fixed force (paper §VIII): the ends slide along z.

The crankshaft kernel (:func:`stiffknots.engine.kernel.run_moves`) keeps the two clamped end
segments of an open chain fixed: Δz = z_{N−1} − z_0, hence the excess length
L_e = (N − 1) − Δz, is constant (fixed-extension ensemble). The two moves here let one end
move along the z axis, so that together with the crankshafts the chain samples the fixed-force
ensemble with energy

    E = E_d − F·Δz,   E_d = C Σ_{joints 1..N−2} (1 − u_n·u_{n+1}),   C = 1, b = 1,

F the pulling force in C/b². Two move classes, both exact in bond length and clamping:

* the *pivot* move (:func:`run_end_moves`): a rigid rotation of the m free beads next to an
  end about a pivot, then the end segment re-attached on the axis;
* the *slide* move (:func:`run_slide_moves`): the end segment and the m free beads next to it
  translated along z, and the next bead re-placed on the circle that keeps its two bonds.

A stretched chain has straight tails on the axis; the pivot move can only tilt them (it changes
Δz at second order in the angle), while the slide move lets a tail slide along its own line and
the knot take up or give back that length at the junction — it is the move that relaxes L_e.

Notation
--------
A move acts on one end; index the beads from that end: k = 0 is the end bead (N−1 for the
top end, 0 for the bottom end), k = 1 the other bead of the clamped end segment, k = 2 the
first free bead, and so on (chain index N−1−k at the top, k at the bottom). ``sg`` = +1 at the
top, −1 at the bottom: the end segment points along sg·ẑ, from bead k = 1 to bead k = 0.
Segment q joins beads k = q and k = q + 1 (segment 0 is the clamped end segment).

The pivot move
--------------
Pick the end (probability ½ each) and m ∈ {1 … m_max} (uniform, m ≤ N − 4). The pivot is bead
P = k(m + 2); the beads k = 2 … m + 1 are rotated rigidly by an angle φ about an axis of
uniformly random direction n through the pivot (Rodrigues). The end segment is then
re-attached deterministically: with ρ the distance of the new bead k = 2 from the z axis,

    z_{k1} = z_{k2} + sg·√(1 − ρ²),   z_{k0} = z_{k1} + sg,   x = y = 0 for both,

i.e. bead k = 1 is the point of the z axis at distance exactly 1 from bead k = 2 on the side of
the end. The move is rejected if ρ ≥ 1, or if the current chain does not have this root
already (h := sg·(z_{k1} − z_{k2}) ≤ 0; a crankshaft may put bead k = 2 beyond bead k = 1).
Every bond keeps its length exactly (rotated bonds move rigidly, the pivot lies on the axis,
the re-attached bond has length √(ρ² + 1 − ρ²) = 1), and the end beads stay exactly on the z
axis with the end segment along sg·ẑ. The angle is drawn like the crankshaft's multi-bead
move: a displacement scale ℓ log-uniform in [l_min, l_cap], then φ uniform in ±min(φ_max,
ℓ/ρ_max), ρ_max the largest distance of a rotated bead from the rotation axis (invariant
under the rotation).

Energy. Only three joints change: at bead k = 1 (its cosine is h), at bead k = 2 and at the
pivot; the rigid part keeps its angles. Δz changes by sg·Δ, Δ := z'_{k0} − z_{k0}, so
ΔE = ΔE_d − F·sg·Δ. The kernel returns the sum of ΔE over the accepted moves.

Detailed balance (pivot move)
-----------------------------
The stationary measure of the crankshafts (open chain, ends fixed) is the bond-constrained
measure ``Π_{free b} d³r_b Π_{bonds} δ(|r_{b+1} − r_b| − 1)`` times e^{−E/T}. The fixed-force
ensemble adds the end heights as variables with Lebesgue measure, dz_{first} dz_{last} (the
Laplace transform of the fixed-extension ensemble, Z(F) = ∫dΔz e^{FΔz/T} Z(Δz)). In the
coordinates of a move — the rotated beads, with the pivot fixed — the rotation is an isometry
of their positions that preserves every bond delta, so it preserves their measure; the last
variable, z_{k1}, is fixed by the bond delta ``δ(|r_{k1} − r_{k2}| − 1)``, whose integral over
z_{k1} leaves the Jacobian ``1/|∂|r_{k1} − r_{k2}|/∂z_{k1}| = 1/h``. The target density of the
move's coordinates is therefore ∝ e^{−E/T}/h. The proposal is symmetric: the move (end, m, n,
φ) from X to X' is undone by (end, m, n, −φ) from X' — same pivot (it does not move), same
ρ_max, hence the same angle range and the same density, and the re-attachment maps the
rotated bead k = 2 back to the old end heights because X has the same root (h > 0); states
with h ≤ 0 are left alone by this move in both directions. Metropolis therefore accepts with

    min(1, (h/h')·e^{−ΔE/T})

(T = 0: ΔE ≤ 0, a quench). Every geometric test below is a symmetric function of the pair
(X, X') and the path between them, so rejecting on it keeps detailed balance. The crankshafts
preserve the same measure, so their alternation with the end moves samples the fixed-force
ensemble (checked against an exact average on a 7-bead chain in tests/test_open_force.py).

Strand passage is impossible by construction (pivot move)
---------------------------------------------------------
The knot type is that of the closed curve K = (bottom ray) ∪ segments ∪ (top ray), the rays
continuing the end segments along ∓z to infinity (as for :func:`~.kernel.run_moves`). Take the path
t ∈ [0, 1]: the rotated beads turn by t·φ, the end beads slide linearly, z_{k0}(t) =
z_{k0} + tΔ (bead k = 1 follows one bond behind), and every segment is the linear
interpolation of its two end beads; the moving ray slides with its end bead. Speeds: a rotated
bead moves at ``|φ|·ρ ≤ L_rot := |φ|·ρ_max``, the end beads and the moving ray at ``|Δ|``, and a
point of a segment at most as fast as the faster of its two end beads, so every moved segment moves
at speed ``≤ L := max(L_rot, |Δ|)``. The distance between two pieces is then Lipschitz in t with
the sum of their speeds, and it stays > 0 on [0, 1] if d(0) + d(1) exceeds that sum (same
argument as in :mod:`stiffknots.engine.kernel`). The move is accepted only if:

(A) slab: every free bead stays strictly between the two end beads along the path. For a
    rotated bead, with a = sg·(z − z_far) (the height above the fixed far end) and
    b = sg·(z_{k0} − z) (the depth below the moving end): a(0) + a(1) > L_rot and
    ``b(0) + b(1) > L_rot + |Δ|``. For a fixed bead b(t) is linear, so b(1) > 0 suffices — checked
    (O(N)) only when the end moves inward; for bead k = 1, a(t) is linear: a(1) > 0.
    Then every segment but the two end segments has both end beads strictly inside the slab,
    hence lies strictly inside it, and cannot meet a ray; an end segment lies beyond every
    free bead of its side and meets only its own ray. So no ray is ever crossed.
(B) every moved segment (0 … m + 1) against every fixed segment it shares no bead with:
    d(0) + d(1) > L (found with the cell list: d(1) ≤ L needs the midpoints within 1 + L);
(C) the moved segments that move differently: the end segment (0) against every rotated
    segment (2 … m + 1), and segment 1 against rotated segments 3 … m + 1:
    d(0) + d(1) > L_rot + L (pairs of rotated segments move rigidly: constant distance);
(D) the exclusion rule at X' (bead: beads at index distance ≥ 2 at least d apart — moved
    against fixed, end beads against rotated beads; tube: segments sharing no bead at least w
    apart — (B) and (C) check d(1) ≥ w on every pair whose distance changes).

Bonded pairs cannot fold onto each other either. At the pivot, both segments have unit
length, so a fold means bead k = m + 1 reaches bead k = m + 3, i.e. segment m meets segment
m + 2 — excluded by (B). At bead k = 2, a fold of segments 1 (length ℓ(t) > 0) and 2 puts
bead k = 1 on segment 2 if ℓ ≤ 1 (then segment 0 meets segment 2: (C)), or bead k = 3 on
segment 1 if ℓ > 1 (segment 3 meets segment 1: (C) if m ≥ 2, (B) if m = 1). At bead k = 1,
segment 1 folds onto the end segment only if bead k = 2 lies on the axis beyond bead k = 1 and,
by (A), short of bead k = 0, i.e. on segment 0: then segment 2 meets segment 0, excluded by
(C). Hence K(t) stays a simple closed curve for all t and the knot type of the closure along
±z cannot change.

Cell list
---------
The cell list of :func:`~stiffknots.engine.kernel.cell_build` (segment midpoints) is scanned
around the new midpoint of each moved segment with reach 1 + max(L, w, d): it finds every fixed
segment within max(L, w) of the moved one and every fixed bead within d of the moved segment's
first bead. After an accepted move the moved segments are re-hashed, and the kernel's
slab bounds ``fpar[F_ZLO]``/``fpar[F_ZHI]`` (read by :func:`~.kernel.run_moves`) follow the ends.

All functions here see arrays and numbers only and allocate nothing in the loop.
"""

from __future__ import annotations

import math

from numba import njit

from stiffknots.engine.prims import (
    C_ACCEPTED,
    C_ENERGY_OK,
    C_TRIED,
    F_CELL,
    F_CMIN,
    F_D,
    F_EINV,
    F_LCAP,
    F_LMIN,
    F_PHIMAX,
    F_W,
    F_ZHI,
    F_ZLO,
    I_EMODE,
    I_MODE,
    I_POWER,
    _axis_dist2,
    _cell_range,
    _de3,
    _draw_angle,
    _hash,
    _metropolis_jac,
    _move_scale,
    _next,
    _pair_blocked,
    _rehash,
    _rodrigues,
    _segment_blocked,
    _turn_blocked,
)

# counter classes (``cnt[C_* + cls]``)
CLS_TOP = 0
CLS_BOTTOM = 1


@njit(cache=True, inline="always")
def _commit_end(pos, newpos, count, base, step, top, fpar, head, nxt, prv, bucket, inv, mask,
                cnt, cls, de):
    """Write an accepted end move: ``count`` beads from ``newpos`` (bead base + k·step), the
    slab bound of the moved end, and the cell of every segment that starts at a moved bead
    counted from that end; count the acceptance. Returns the move's ΔE ``de``."""
    cnt[C_ACCEPTED + cls] += 1
    n = pos.shape[0]
    for k in range(count):
        b = base + k * step
        pos[b, 0] = newpos[k, 0]
        pos[b, 1] = newpos[k, 1]
        pos[b, 2] = newpos[k, 2]
    if top:
        fpar[F_ZHI] = pos[n - 1, 2]
    else:
        fpar[F_ZLO] = pos[0, 2]
    for q in range(count):
        v = (n - 2 - q) if top else q
        _rehash(pos, v, v + 1, inv, mask, head, nxt, prv, bucket)
    return de


@njit(cache=True, inline="always")
def _end_params(ipar, fpar, head, temperature, rng, m_max, cap1, cap2):
    """What both end-move kernels read: exclusion mode, energy mode, power and scale, curvature
    limit, displacement scales, exclusion distances, cell geometry, 1/T, the generator, and
    ``m_max`` capped at ``cap1`` and ``cap2``."""
    l_cap = fpar[F_LCAP]
    l_min = fpar[F_LMIN]
    log_span = math.log(l_cap / l_min) if l_cap > l_min else 0.0
    d = fpar[F_D]
    w = fpar[F_W]
    beta = 1.0 / temperature if temperature > 0.0 else 0.0
    return (ipar[I_MODE], ipar[I_EMODE], ipar[I_POWER], fpar[F_EINV], fpar[F_CMIN], l_cap,
            log_span, d, d * d, w, w * w, 1.0 / fpar[F_CELL], head.shape[0] - 1, beta,
            rng[0], rng[1], rng[2], rng[3], min(m_max, cap1, cap2))


@njit(cache=True, inline="always")
def _end_accept(o1, n1, o2, n2, o3, n3, cmin, emode, power, escale, work, beta, j_old, j_new,
                cnt, cls, s0, s1, s2, s3):
    """The energy test of an end move that changes three joints (old/new cosines o, n): the
    curvature limit, ΔE = ΔE_d − F·sg·Δ (``work`` = F·sg·Δ), Metropolis with the Jacobian
    ratio j_old/j_new; counts the moves that pass. Returns (accept, ΔE, generator state)."""
    if cmin > -1.0 and (_turn_blocked(cmin, o1, n1) or _turn_blocked(cmin, o2, n2)
                        or _turn_blocked(cmin, o3, n3)):
        return False, 0.0, s0, s1, s2, s3
    de = _de3(o1, n1, o2, n2, o3, n3, emode, power, escale)
    de -= work
    ok, s0, s1, s2, s3 = _metropolis_jac(de, beta, j_old, j_new, s0, s1, s2, s3)
    if ok:
        cnt[C_ENERGY_OK + cls] += 1
    return ok, de, s0, s1, s2, s3


@njit(cache=True, inline="always")
def _pick_end(n, cnt, s0, s1, s2, s3):
    """Draw the end a move acts on (½ each) and count the attempt. Returns (top, cls, sg,
    base, step, generator state): bead k from that end is chain bead base + step·k, and the
    end segment points along sg·ẑ."""
    u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    top = u < 0.5
    cls = CLS_TOP if top else CLS_BOTTOM
    cnt[C_TRIED + cls] += 1
    if top:
        return top, cls, 1.0, n - 1, -1, s0, s1, s2, s3
    return top, cls, -1.0, 0, 1, s0, s1, s2, s3


@njit(cache=True, inline="always")
def _below_end(pos, zen, sg, base, step, k0):
    """True if every fixed bead k = k0 … N − 2 (from the moving end) lies strictly inside the
    moving end's new height ``zen`` (the slab check of an inward end move)."""
    for k in range(k0, pos.shape[0] - 1):
        if sg * (zen - pos[base + k * step, 2]) <= 0.0:
            return False
    return True


@njit(cache=True, inline="always")
def _moving_pair_blocked(pax, pay, paz, pbx, pby, pbz, qax, qay, qaz, qbx, qby, qbz,
                         oax, oay, oaz, obx, oby, obz, rax, ray, raz, rbx, rby, rbz,
                         lim_mid2, w2, lrel):
    """Two moved unit segments, new P = pa–pb and Q = qa–qb, old P = oa–ob and Q = ra–rb: True
    if the new distance is below the tube diameter or d_before + d_after ≤ ``lrel``."""
    mx = 0.5 * (pax + pbx - qax - qbx)
    my = 0.5 * (pay + pby - qay - qby)
    mz = 0.5 * (paz + pbz - qaz - qbz)
    if mx * mx + my * my + mz * mz > lim_mid2:
        return False
    return _pair_blocked(pax, pay, paz, pbx, pby, pbz, qax, qay, qaz, qbx, qby, qbz,
                         oax, oay, oaz, obx, oby, obz, rax, ray, raz, rbx, rby, rbz, w2, lrel)


@njit(cache=True, inline="always")
def _fixed_clash(pos, head, nxt, inv, mask, top, kfix, q, kinv, pax, pay, paz, pbx, pby, pbz,
                 oax, oay, oaz, obx, oby, obz, lmove, mode, d, w):
    """Does moved segment q (new ends pa–pb, old oa–ob; indices k from the moving end) clash
    with a fixed segment (k ≥ ``kfix``) or, in the bead model, its moved bead k = q with a
    fixed bead? Scans the cell list around the new midpoint (module docstring). ``kinv``:
    a fixed bead whose distance to bead q the move leaves invariant (−1: none)."""
    n = pos.shape[0]
    dseg = w if w > lmove else lmove
    reach = 1.0 + dseg
    if mode == 0 and 1.0 + d > reach:
        reach = 1.0 + d
    d2 = d * d
    w2 = w * w
    mx = 0.5 * (pax + pbx)
    my = 0.5 * (pay + pby)
    mz = 0.5 * (paz + pbz)
    x0, x1, y0, y1, z0, z1 = _cell_range(mx, my, mz, reach, inv)
    for cx in range(x0, x1 + 1):
        for cy in range(y0, y1 + 1):
            for cz in range(z0, z1 + 1):
                v = head[_hash(cx, cy, cz, mask)]
                while v >= 0:
                    # segment v joins chain beads v, v + 1; kv is its index from the end
                    kv = (n - 2 - v) if top else v
                    if kv < kfix:  # moved: handled by the caller
                        v = nxt[v]
                        continue
                    vx, vy, vz = pos[v, 0], pos[v, 1], pos[v, 2]
                    wx, wy, wz = pos[v + 1, 0], pos[v + 1, 1], pos[v + 1, 2]
                    if mode == 0:
                        for f in range(2):
                            kf = kv + f
                            if kf - q < 2 or kf == kinv:
                                continue  # bonded, or a distance the move keeps
                            fb = (n - 1 - kf) if top else kf
                            ddx, ddy, ddz = pos[fb, 0] - pax, pos[fb, 1] - pay, pos[fb, 2] - paz
                            if ddx * ddx + ddy * ddy + ddz * ddz < d2:
                                return True
                    if kv != q + 1 and _segment_blocked(
                            pax, pay, paz, pbx, pby, pbz, oax, oay, oaz, obx, oby, obz,
                            mx, my, mz, vx, vy, vz, wx, wy, wz,
                            0.5 * (vx + wx), 0.5 * (vy + wy), 0.5 * (vz + wz),
                            dseg, w2, lmove):
                        return True
                    v = nxt[v]
    return False


@njit(cache=True)
def run_end_moves(pos, n_moves, temperature, force, m_max, ipar, fpar, head, nxt, prv, bucket,
                  newpos, cnt, rng):
    """Attempt ``n_moves`` end-slide moves (module docstring) at ``temperature`` and force F.

    Parameters
    ----------
    pos
        (N, 3) float64 open chain, clamped as :func:`.check_open_clamping` requires; modified
        in place.
    n_moves
        Number of attempted moves.
    temperature
        k_B T in units of C (0: quench, only ΔE ≤ 0 is accepted).
    force
        F in C/b² (E = E_d − F·Δz).
    m_max
        Largest number of rotated beads (capped at N − 4 and at ``len(newpos) − 2``).
    ipar, fpar
        The crankshaft kernel's parameter arrays (exclusion, energy mode, curvature
        limit, angle scales, cell side); ``fpar[F_ZLO]``/``fpar[F_ZHI]`` are updated.
    head, nxt, prv, bucket
        The cell list of segment midpoints (open chain), kept current.
    newpos
        (≥ m_max + 2, 3) float64 scratch space.
    cnt
        (C_NCNT,) int64 counters, class 0 = top end, 1 = bottom end.
    rng
        (4,) uint64 xoshiro256+ state, advanced in place.

    Returns
    -------
    float
        The total change of E_d − F·Δz over the accepted moves.
    """
    n = pos.shape[0]
    # the pivot needs rows k = 0 … m + 1 of newpos
    (mode, emode, power, escale, cmin, l_cap, log_span, d, d2, w, w2, inv, mask, beta, s0, s1,
     s2, s3, m_max) = _end_params(ipar, fpar, head, temperature, rng, m_max, n - 4,
                                  newpos.shape[0] - 2)
    if m_max < 1:
        return 0.0
    phi_max = fpar[F_PHIMAX]
    de_total = 0.0

    for _it in range(n_moves):
        # ---- propose -------------------------------------------------------------------
        top, cls, sg, base, step, s0, s1, s2, s3 = _pick_end(n, cnt, s0, s1, s2, s3)
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        m = 1 + int(u * m_max)
        if m > m_max:
            m = m_max
        e0 = base
        e1 = base + step
        b2 = base + 2 * step
        piv = base + (m + 2) * step
        h_old = sg * (pos[e1, 2] - pos[b2, 2])
        if h_old <= 0.0:
            continue  # bead k = 2 lies beyond bead k = 1: not this move's root
        # random axis through the pivot
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        ez = 2.0 * u - 1.0
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        az = 2.0 * math.pi * u
        sxy = math.sqrt(max(0.0, 1.0 - ez * ez))
        ex = sxy * math.cos(az)
        ey = sxy * math.sin(az)
        jx, jy, jz = pos[piv, 0], pos[piv, 1], pos[piv, 2]
        rho2 = 0.0
        for k in range(2, m + 2):
            b = base + k * step
            r2 = _axis_dist2(pos[b, 0], pos[b, 1], pos[b, 2], jx, jy, jz, ex, ey, ez)
            if r2 > rho2:
                rho2 = r2
        rho = math.sqrt(rho2)
        phi, s0, s1, s2, s3 = _draw_angle(rho, phi_max, l_cap, log_span, s0, s1, s2, s3)
        c = math.cos(phi)
        s = math.sin(phi)
        oc = 1.0 - c
        for k in range(2, m + 2):
            b = base + k * step
            newpos[k, 0], newpos[k, 1], newpos[k, 2] = _rodrigues(
                pos[b, 0], pos[b, 1], pos[b, 2], jx, jy, jz, ex, ey, ez, c, s, oc)
        # re-attach the end segment on the axis, one bond beyond bead k = 2
        rr = newpos[2, 0] * newpos[2, 0] + newpos[2, 1] * newpos[2, 1]
        if rr >= 1.0:
            continue
        h_new = math.sqrt(1.0 - rr)
        if h_new <= 0.0:
            continue
        z1 = newpos[2, 2] + sg * h_new
        newpos[1, 0] = 0.0
        newpos[1, 1] = 0.0
        newpos[1, 2] = z1
        newpos[0, 0] = 0.0
        newpos[0, 1] = 0.0
        newpos[0, 2] = z1 + sg
        dlt = newpos[0, 2] - pos[e0, 2]
        # ---- energy: joints at k = 1 (cosine h), k = 2 and the pivot --------------------
        k3 = base + 3 * step
        if m >= 2:
            n3x, n3y, n3z = newpos[3, 0], newpos[3, 1], newpos[3, 2]
        else:  # bead k = 3 is the pivot
            n3x, n3y, n3z = jx, jy, jz
        old2 = ((pos[b2, 0] - pos[e1, 0]) * (pos[k3, 0] - pos[b2, 0])
                + (pos[b2, 1] - pos[e1, 1]) * (pos[k3, 1] - pos[b2, 1])
                + (pos[b2, 2] - pos[e1, 2]) * (pos[k3, 2] - pos[b2, 2]))
        new2 = ((newpos[2, 0] - newpos[1, 0]) * (n3x - newpos[2, 0])
                + (newpos[2, 1] - newpos[1, 1]) * (n3y - newpos[2, 1])
                + (newpos[2, 2] - newpos[1, 2]) * (n3z - newpos[2, 2]))
        bl = base + (m + 1) * step  # last rotated bead
        pn = base + (m + 3) * step  # fixed bead beyond the pivot
        fx, fy, fz = pos[pn, 0] - jx, pos[pn, 1] - jy, pos[pn, 2] - jz
        oldp = (jx - pos[bl, 0]) * fx + (jy - pos[bl, 1]) * fy + (jz - pos[bl, 2]) * fz
        newp = ((jx - newpos[m + 1, 0]) * fx + (jy - newpos[m + 1, 1]) * fy
                + (jz - newpos[m + 1, 2]) * fz)
        # Metropolis with the Jacobian h/h' of the re-attachment (module docstring)
        ok, de, s0, s1, s2, s3 = _end_accept(h_old, h_new, old2, new2, oldp, newp, cmin, emode,
                                             power, escale, force * sg * dlt, beta, h_old,
                                             h_new, cnt, cls, s0, s1, s2, s3)
        if not ok:
            continue
        # ---- strand-passage guard and exclusion ----------------------------------------
        lrot = abs(phi) * rho
        adl = abs(dlt)
        lmv = lrot if lrot > adl else adl
        lrel = lrot + lmv
        ok = True
        # (A) slab between the far end (fixed) and the moving end
        zf = pos[base + (n - 1) * step, 2]
        zeo = pos[e0, 2]
        zen = newpos[0, 2]
        if sg * (z1 - zf) <= 0.0:
            ok = False
        for k in range(2, m + 2):
            if not ok:
                break
            zo = pos[base + k * step, 2]
            zn = newpos[k, 2]
            if sg * (zo - zf) + sg * (zn - zf) <= lrot:
                ok = False
            elif sg * (zeo - zo) + sg * (zen - zn) <= lrot + adl:
                ok = False
        if ok and sg * dlt < 0.0:
            ok = _below_end(pos, zen, sg, base, step, m + 2)
        if not ok:
            continue
        # (C) moved segments that move differently; (D) end beads against rotated beads
        dmv = w if w > lrel else lrel
        lim_mm2 = (1.0 + dmv) * (1.0 + dmv)
        for q in range(2, m + 2):
            if not ok:
                break
            # rotated segment q: beads k = q, q + 1 (q + 1 = pivot when q = m + 1)
            bq = base + q * step
            bq1 = bq + step
            pax, pay, paz = newpos[q, 0], newpos[q, 1], newpos[q, 2]
            if q + 1 <= m + 1:
                pbx, pby, pbz = newpos[q + 1, 0], newpos[q + 1, 1], newpos[q + 1, 2]
            else:
                pbx, pby, pbz = jx, jy, jz
            if mode == 0:
                for ke in range(2):
                    if q - ke >= 2:
                        ddx = newpos[ke, 0] - pax
                        ddy = newpos[ke, 1] - pay
                        ddz = newpos[ke, 2] - paz
                        if ddx * ddx + ddy * ddy + ddz * ddz < d2:
                            ok = False
            if not ok:
                break
            # against the end segment 0 (beads k = 0, 1), then segment 1 (beads k = 1, 2),
            # which shares bead 2 with segment 2 (so only for q ≥ 3)
            for g in range(2 if q >= 3 else 1):
                ga = base + g * step  # chain index of bead k = g
                if _moving_pair_blocked(pax, pay, paz, pbx, pby, pbz,
                                        newpos[g, 0], newpos[g, 1], newpos[g, 2],
                                        newpos[g + 1, 0], newpos[g + 1, 1], newpos[g + 1, 2],
                                        pos[bq, 0], pos[bq, 1], pos[bq, 2],
                                        pos[bq1, 0], pos[bq1, 1], pos[bq1, 2],
                                        pos[ga, 0], pos[ga, 1], pos[ga, 2],
                                        pos[ga + step, 0], pos[ga + step, 1], pos[ga + step, 2],
                                        lim_mm2, w2, lrel):
                    ok = False
                    break
            if not ok:
                break
        if not ok:
            continue
        # (B) + (D) moved segments against fixed segments and beads, from the cell list
        for q in range(m + 2):
            bq = base + q * step
            bq1 = bq + step
            if q + 1 <= m + 1:
                pbx, pby, pbz = newpos[q + 1, 0], newpos[q + 1, 1], newpos[q + 1, 2]
            else:
                pbx, pby, pbz = jx, jy, jz
            if _fixed_clash(pos, head, nxt, inv, mask, top, m + 2, q,
                            m + 2 if q >= 2 else -1,
                            newpos[q, 0], newpos[q, 1], newpos[q, 2], pbx, pby, pbz,
                            pos[bq, 0], pos[bq, 1], pos[bq, 2],
                            pos[bq1, 0], pos[bq1, 1], pos[bq1, 2],
                            lmv, mode, d, w):
                ok = False
                break
        if ok:  # accept
            de_total += _commit_end(pos, newpos, m + 2, base, step, top, fpar, head, nxt, prv,
                                    bucket, inv, mask, cnt, cls, de)
    rng[0], rng[1], rng[2], rng[3] = s0, s1, s2, s3
    return de_total


@njit(cache=True)
def run_slide_moves(pos, n_moves, temperature, force, m_max, ipar, fpar, head, nxt, prv,
                    bucket, newpos, cnt, rng):
    """Attempt ``n_moves`` slide moves (module docstring, "The slide move") at
    ``temperature`` and force F and return the total change of E_d − F·Δz; arguments as for
    :func:`run_end_moves` (``m_max``: largest number of translated free beads, capped at
    N − 5 and ``len(newpos) − 3``)."""
    n = pos.shape[0]
    # the slide needs rows k = 0 … m + 2 of newpos
    (mode, emode, power, escale, cmin, l_cap, log_span, d, d2, w, w2, inv, mask, beta, s0, s1,
     s2, s3, m_max) = _end_params(ipar, fpar, head, temperature, rng, m_max, n - 5,
                                  newpos.shape[0] - 3)
    if m_max < 0:
        return 0.0
    de_total = 0.0

    for _it in range(n_moves):
        # ---- propose -------------------------------------------------------------------
        top, cls, sg, base, step, s0, s1, s2, s3 = _pick_end(n, cnt, s0, s1, s2, s3)
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        m = int(u * (m_max + 1))
        if m > m_max:
            m = m_max
        ia = base + (m + 1) * step  # last translated bead A
        ip = ia + step  # the re-placed bead P
        iq = ip + step  # fixed bead Q
        ir = iq + step  # fixed bead beyond Q
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        scale = _move_scale(u, l_cap, log_span)
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        dlt = (2.0 * u - 1.0) * scale
        qx, qy, qz = pos[iq, 0], pos[iq, 1], pos[iq, 2]
        # old circle: axis a = (A − Q)/D, P = Q + (D/2) a + r_c e
        ax, ay, az = pos[ia, 0] - qx, pos[ia, 1] - qy, pos[ia, 2] - qz
        dd = math.sqrt(ax * ax + ay * ay + az * az)
        # new circle: A' = A + δ ẑ
        bx, by, bz = ax, ay, az + dlt
        dn = math.sqrt(bx * bx + by * by + bz * bz)
        if not (1e-9 < dd < 2.0 - 1e-9 and 1e-9 < dn < 2.0 - 1e-9):
            continue
        ax, ay, az = ax / dd, ay / dd, az / dd
        bx, by, bz = bx / dn, by / dn, bz / dn
        ex, ey, ez = pos[ip, 0] - qx, pos[ip, 1] - qy, pos[ip, 2] - qz
        t = ex * ax + ey * ay + ez * az
        ex, ey, ez = ex - t * ax, ey - t * ay, ez - t * az
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        if el < 1e-9:
            continue
        ex, ey, ez = ex / el, ey / el, ez / el
        # e' = R e, R the smallest rotation taking a to a': R = I + [c]× + [c]×²/(1 + a·a')
        cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        ca = ax * bx + ay * by + az * bz
        if ca <= -0.5:
            continue
        kx, ky, kz = cy * ez - cz * ey, cz * ex - cx * ez, cx * ey - cy * ex
        fx, fy, fz = cy * kz - cz * ky, cz * kx - cx * kz, cx * ky - cy * kx
        g = 1.0 / (1.0 + ca)
        fx, fy, fz = ex + kx + fx * g, ey + ky + fy * g, ez + kz + fz * g
        t = fx * bx + fy * by + fz * bz
        fx, fy, fz = fx - t * bx, fy - t * by, fz - t * bz
        el = math.sqrt(fx * fx + fy * fy + fz * fz)
        fx, fy, fz = fx / el, fy / el, fz / el
        rc = math.sqrt(1.0 - 0.25 * dn * dn)
        # new positions: k = 0 … m + 1 translated, k = m + 2 is P'
        for k in range(m + 2):
            b = base + k * step
            newpos[k, 0] = pos[b, 0]
            newpos[k, 1] = pos[b, 1]
            newpos[k, 2] = pos[b, 2] + dlt
        newpos[0, 0] = 0.0
        newpos[0, 1] = 0.0
        newpos[1, 0] = 0.0
        newpos[1, 1] = 0.0
        newpos[1, 2] = newpos[0, 2] - sg
        px = qx + 0.5 * dn * bx + rc * fx
        py = qy + 0.5 * dn * by + rc * fy
        pz = qz + 0.5 * dn * bz + rc * fz
        newpos[m + 2, 0] = px
        newpos[m + 2, 1] = py
        newpos[m + 2, 2] = pz
        # ---- energy: joints at A, P and Q -----------------------------------------------
        ib = ia - step  # the bead before A (translated with it)
        ux, uy, uz = pos[ia, 0] - pos[ib, 0], pos[ia, 1] - pos[ib, 1], pos[ia, 2] - pos[ib, 2]
        olda = (ux * (pos[ip, 0] - pos[ia, 0]) + uy * (pos[ip, 1] - pos[ia, 1])
                + uz * (pos[ip, 2] - pos[ia, 2]))
        nax, nay, naz = newpos[m + 1, 0], newpos[m + 1, 1], newpos[m + 1, 2]
        newa = ux * (px - nax) + uy * (py - nay) + uz * (pz - naz)
        oldp = ((pos[ip, 0] - pos[ia, 0]) * (qx - pos[ip, 0])
                + (pos[ip, 1] - pos[ia, 1]) * (qy - pos[ip, 1])
                + (pos[ip, 2] - pos[ia, 2]) * (qz - pos[ip, 2]))
        newp = (px - nax) * (qx - px) + (py - nay) * (qy - py) + (pz - naz) * (qz - pz)
        vx, vy, vz = pos[ir, 0] - qx, pos[ir, 1] - qy, pos[ir, 2] - qz
        oldq = (qx - pos[ip, 0]) * vx + (qy - pos[ip, 1]) * vy + (qz - pos[ip, 2]) * vz
        newq = (qx - px) * vx + (qy - py) * vy + (qz - pz) * vz
        # Metropolis with the Jacobian D/D' of the circle (module docstring)
        ok, de, s0, s1, s2, s3 = _end_accept(olda, newa, oldp, newp, oldq, newq, cmin, emode,
                                             power, escale, force * sg * dlt, beta, dd, dn, cnt,
                                             cls, s0, s1, s2, s3)
        if not ok:
            continue
        # ---- strand-passage guard and exclusion ----------------------------------------
        ltr = abs(dlt)
        ddx, ddy, ddz = px - pos[ip, 0], py - pos[ip, 1], pz - pos[ip, 2]
        lp = math.sqrt(ddx * ddx + ddy * ddy + ddz * ddz)
        lmv = ltr if ltr > lp else lp
        lrel = lmv + ltr
        ok = True
        # (A) slab: heights are linear along the path
        zf = pos[base + (n - 1) * step, 2]
        zen = newpos[0, 2]
        if sg * (pz - zf) <= 0.0 or sg * (zen - pz) <= 0.0:
            ok = False
        elif sg * dlt < 0.0:
            for k in range(1, m + 2):
                if sg * (newpos[k, 2] - zf) <= 0.0:
                    ok = False
                    break
            if ok:
                ok = _below_end(pos, zen, sg, base, step, m + 3)
        if not ok:
            continue
        # (C) segments m + 1 (A–P) and m + 2 (P–Q) against the translated segments;
        # (D) bead P against the translated beads
        lim_mm2 = (1.0 + (w if w > lrel else lrel)) ** 2
        for q in range(m + 1):
            b = base + q * step
            b1 = b + step
            if mode == 0 and m + 2 - q >= 2:
                hx, hy, hz = newpos[q, 0] - px, newpos[q, 1] - py, newpos[q, 2] - pz
                if hx * hx + hy * hy + hz * hz < d2:
                    ok = False
                    break
            if q <= m - 1 and _moving_pair_blocked(
                    nax, nay, naz, px, py, pz,
                    newpos[q, 0], newpos[q, 1], newpos[q, 2],
                    newpos[q + 1, 0], newpos[q + 1, 1], newpos[q + 1, 2],
                    pos[ia, 0], pos[ia, 1], pos[ia, 2], pos[ip, 0], pos[ip, 1], pos[ip, 2],
                    pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2],
                    lim_mm2, w2, lrel):
                ok = False
                break
            if _moving_pair_blocked(
                    px, py, pz, qx, qy, qz,
                    newpos[q, 0], newpos[q, 1], newpos[q, 2],
                    newpos[q + 1, 0], newpos[q + 1, 1], newpos[q + 1, 2],
                    pos[ip, 0], pos[ip, 1], pos[ip, 2], qx, qy, qz,
                    pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2],
                    lim_mm2, w2, lrel):
                ok = False
                break
        if not ok:
            continue
        # (B) + (D) moved segments against fixed segments and beads
        for q in range(m + 3):
            b = base + q * step
            b1 = b + step
            if q <= m + 1:
                qbx, qby, qbz = newpos[q + 1, 0], newpos[q + 1, 1], newpos[q + 1, 2]
            else:
                qbx, qby, qbz = qx, qy, qz
            if _fixed_clash(pos, head, nxt, inv, mask, top, m + 3, q, -1,
                            newpos[q, 0], newpos[q, 1], newpos[q, 2], qbx, qby, qbz,
                            pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2],
                            ltr if q <= m else lmv, mode, d, w):
                ok = False
                break
        if not ok:
            continue
        # ---- accept ----------------------------------------------------------------------
        de_total += _commit_end(pos, newpos, m + 3, base, step, top, fpar, head, nxt, prv,
                                bucket, inv, mask, cnt, cls, de)
    rng[0], rng[1], rng[2], rng[3] = s0, s1, s2, s3
    return de_total
