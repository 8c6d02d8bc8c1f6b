"""Primitives shared by the compiled Monte Carlo kernels (paper §VII): parameter slots, the
random generator, the cell list, the joint energy, the Metropolis rule, rotations and the
strand-passage guard of one pair of segments.

Every kernel (:mod:`stiffknots.engine.kernel` for the crankshafts,
:mod:`stiffknots.engine.force_kernel` for the end moves at fixed force) is built from these
``inline="always"`` helpers and keeps only what differs, with its own proof. All functions see
arrays and numbers only and allocate nothing.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.geometry import seg_dist2

# integer parameter slots (``ipar``)
I_MODE = 0  # 0 = bead, 1 = tube
I_MMAX = 1  # largest number of beads moved by one crankshaft move (≥ 1)
I_OPEN = 2  # 0 = closed chain, 1 = open chain with both end segments clamped on the z axis
I_EMODE = 3  # energy per joint: 0 = bending 1 − cos θ (the paper), 1 = (1 − cos θ)^p
I_POWER = 4  # the exponent p of energy mode 1
I_MLAW = 5  # law of a crankshaft's length m in [2, m_max]: 0 = uniform, 1 = log-uniform
I_NIPAR = 6

# float parameter slots (``fpar``)
F_DELTA = 0  # angle of the single-bead move (paper: π/100)
F_PSINGLE = 1  # probability of a single-bead move
F_PHIMAX = 2  # largest angle of a multi-bead move
F_LCAP = 3  # largest displacement of any point in a multi-bead move
F_D = 4  # bead exclusion distance
F_W = 5  # tube diameter
F_CELL = 6  # cell side
F_LMIN = 7  # smallest displacement scale of a multi-bead move
F_CMIN = 8  # cos of the largest turning angle allowed at a joint (≤ −1: no limit)
F_ZLO = 9  # open chains: z of the first bead (bottom of the slab the free beads live in)
F_ZHI = 10  # open chains: z of the last bead (top of the slab)
F_EINV = 11  # energy mode 1: (1 − cos θ) is divided by this scale before the power
F_NFPAR = 12

# counters (``cnt``), per move class: 0 = single bead, 1 = multi-bead
C_TRIED = 0
C_ENERGY_OK = 2
C_ACCEPTED = 4
C_NCNT = 6


# multipliers of the cell hash (large odd numbers; wrapping int64 arithmetic)
HASH_X = 73856093
HASH_Y = 19349663


@njit(cache=True, inline="always")
def _hash(ix, iy, iz, mask):
    """Slot of cell (ix, iy, iz) in a table of mask + 1 (a power of two) slots.

    Linear in iz, so that the cells of one z column sit in consecutive slots: a scan that runs
    z innermost reads a few cache lines instead of one per cell. Two cells may share a slot;
    every scan tests each segment it meets by distance, so a collision costs time, never
    correctness."""
    return (ix * HASH_X + iy * HASH_Y + iz) & mask


@njit(cache=True)
def cell_build(pos, cell, head, nxt, prv, bucket, is_open=False):
    """(Re)build the spatial hash of segment midpoints. ``head`` has a power-of-two size.

    Segment v joins beads v and v+1; an open chain has no segment N−1 (its ``bucket`` is −1).
    """
    n = pos.shape[0]
    mask = head.shape[0] - 1
    inv = 1.0 / cell
    for h in range(head.shape[0]):
        head[h] = -1
    nseg = n
    if is_open:
        nseg = n - 1
        bucket[n - 1] = -1
        nxt[n - 1] = -1
        prv[n - 1] = -1
    for v in range(nseg):
        w = v + 1
        if w == n:
            w = 0
        mx = 0.5 * (pos[v, 0] + pos[w, 0])
        my = 0.5 * (pos[v, 1] + pos[w, 1])
        mz = 0.5 * (pos[v, 2] + pos[w, 2])
        h = _hash(
            np.int64(math.floor(mx * inv)),
            np.int64(math.floor(my * inv)),
            np.int64(math.floor(mz * inv)),
            mask,
        )
        _cell_push(v, h, head, nxt, prv, bucket)


@njit(cache=True, inline="always")
def _cell_push(v, h, head, nxt, prv, bucket):
    """Put segment v at the front of cell h's list."""
    bucket[v] = h
    prv[v] = -1
    nxt[v] = head[h]
    if head[h] >= 0:
        prv[head[h]] = v
    head[h] = v


@njit(cache=True, inline="always")
def _cell_update(v, h, head, nxt, prv, bucket):
    old = bucket[v]
    if old == h:
        return
    # unlink
    p = prv[v]
    q = nxt[v]
    if p >= 0:
        nxt[p] = q
    else:
        head[old] = q
    if q >= 0:
        prv[q] = p
    _cell_push(v, h, head, nxt, prv, bucket)


@njit(cache=True, inline="always")
def _joint_energy(c, emode, power, escale):
    """Energy of one joint with c = u_n·u_{n+1}: 1 − c (paper §VII) or ((1 − c)/s)^p."""
    if emode == 0:
        return 1.0 - c
    x = (1.0 - c) / escale
    if x < 0.0:
        x = 0.0
    return x ** power


@njit(cache=True, inline="always")
def _joint_cos(pos, v, n):
    """c = u·w at joint v: u the bond into bead v, w the bond out of it (cyclic indices)."""
    a = v - 1 if v > 0 else n - 1
    b = v + 1 if v < n - 1 else 0
    return ((pos[v, 0] - pos[a, 0]) * (pos[b, 0] - pos[v, 0])
            + (pos[v, 1] - pos[a, 1]) * (pos[b, 1] - pos[v, 1])
            + (pos[v, 2] - pos[a, 2]) * (pos[b, 2] - pos[v, 2]))


@njit(cache=True)
def energy_chain(pos, is_open=False, emode=0, power=1, escale=1.0):
    """Σ_joints f(u_n·u_{n+1}) for a unit-bond chain (f: see the module docstring), C = 1.

    Closed chains have N joints, open chains the N − 2 interior ones (beads 1 … N−2).
    """
    n = pos.shape[0]
    e = 0.0
    lo = 1 if is_open else 0
    hi = n - 1 if is_open else n
    for v in range(lo, hi):
        e += _joint_energy(_joint_cos(pos, v, n), emode, power, escale)
    return e


@njit(cache=True)
def energy_closed(pos):
    """E_d = Σ_n (1 − u_n·u_{n+1}) for a closed unit-bond chain (paper §VII), C = 1."""
    return energy_chain(pos, False, 0, 1)


@njit(cache=True)
def turning_cosines(pos, is_open=False):
    """c_n = u_n·u_{n+1} at every joint (N for closed chains, N − 2 for open ones)."""
    n = pos.shape[0]
    lo = 1 if is_open else 0
    hi = n - 1 if is_open else n
    out = np.empty(hi - lo)
    for v in range(lo, hi):
        out[v - lo] = _joint_cos(pos, v, n)
    return out


_M64 = 0xFFFFFFFFFFFFFFFF


def new_rng_state(seed: int) -> np.ndarray:
    """xoshiro256+ state (4 × uint64) from an integer seed, expanded with splitmix64."""
    x = int(seed) & _M64
    out = np.empty(4, dtype=np.uint64)
    for q in range(4):
        x = (x + 0x9E3779B97F4A7C15) & _M64
        z = x
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _M64
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _M64
        out[q] = z ^ (z >> 31)
    if not out.any():
        out[0] = 1
    return out


@njit(cache=True, inline="always")
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@njit(cache=True, inline="always")
def _next(s0, s1, s2, s3):
    """One step of xoshiro256+ (Blackman & Vigna); returns (uniform in [0, 1), new state)."""
    r = s0 + s3
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    return (r >> np.uint64(11)) * (1.0 / 9007199254740992.0), s0, s1, s2, s3


@njit(cache=True)
def uniforms(rng, n):
    """``n`` uniforms from the kernel's generator (for tests of the generator)."""
    out = np.empty(n)
    s0, s1, s2, s3 = rng[0], rng[1], rng[2], rng[3]
    for q in range(n):
        out[q], s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    rng[0], rng[1], rng[2], rng[3] = s0, s1, s2, s3
    return out


@njit(cache=True, inline="always")
def _segment_blocked(nax, nay, naz, nbx, nby, nbz, oax, oay, oaz, obx, oby, obz,
                     mx, my, mz, vx, vy, vz, wx, wy, wz, mvx, mvy, mvz, dseg, w2, lmove):
    """Does a moved segment (new ends na–nb, old ends oa–ob, new midpoint m) clash with the
    fixed segment v–w (midpoint mv)? True if the new distance is below the tube diameter, or
    if d_before + d_after ≤ L (the strand-passage guard of the module docstring);
    dseg = max(w, L).

    Both tests need the new distance D ≤ dseg, so two cheap lower bounds of D come first:
    D ≥ |Δ| − 1 (Δ = mv − m; both segments have unit length), and the separating axis
    along u = Δ/|Δ|: every point x of a segment with midpoint c and direction a has
    |u·(x − c)| ≤ |u·a|/2, so D ≥ g/|Δ| with g = |Δ|² − (|a·Δ| + |b·Δ|)/2. When
    g² > (dseg + 1e-9)²|Δ|² (g > 0) the full test could only say False; the margin covers
    rounding, so the answer is the same as without the shortcut."""
    ddx = mvx - mx
    ddy = mvy - my
    ddz = mvz - mz
    dm2 = ddx * ddx + ddy * ddy + ddz * ddz
    if dm2 > (1.0 + dseg) * (1.0 + dseg):
        return False  # too far apart for either test to fail
    g = dm2 - 0.5 * (abs((nbx - nax) * ddx + (nby - nay) * ddy + (nbz - naz) * ddz)
                     + abs((wx - vx) * ddx + (wy - vy) * ddy + (wz - vz) * ddz))
    t = dseg + 1e-9
    if g > 0.0 and g * g > t * t * dm2:
        return False
    return _pair_blocked(nax, nay, naz, nbx, nby, nbz, vx, vy, vz, wx, wy, wz,
                         oax, oay, oaz, obx, oby, obz, vx, vy, vz, wx, wy, wz, w2, lmove)


@njit(cache=True, inline="always")
def _pair_blocked(pax, pay, paz, pbx, pby, pbz, qax, qay, qaz, qbx, qby, qbz,
                  oax, oay, oaz, obx, oby, obz, rax, ray, raz, rbx, rby, rbz, w2, lmove):
    """Segments P = pa–pb and Q = qa–qb after a move, O = oa–ob and R = ra–rb before it:
    True if |PQ| < w (tube) or d_before + d_after ≤ L, the largest relative displacement of
    their points along the move (then the pair might have crossed: the guard of
    :mod:`stiffknots.engine.kernel`)."""
    dn2 = seg_dist2(pax, pay, paz, pbx, pby, pbz, qax, qay, qaz, qbx, qby, qbz)
    if dn2 < w2:
        return True
    if dn2 <= lmove * lmove:
        do2 = seg_dist2(oax, oay, oaz, obx, oby, obz, rax, ray, raz, rbx, rby, rbz)
        if math.sqrt(do2) + math.sqrt(dn2) <= lmove:
            return True
    return False



# ---- helpers that several kernels share (inline: no call overhead in the loops) -------------


@njit(cache=True, inline="always")
def _cell_of(x, y, z, inv, mask):
    """Hash of the cell holding the point (x, y, z) (cells of side 1/inv)."""
    return _hash(np.int64(math.floor(x * inv)), np.int64(math.floor(y * inv)),
                 np.int64(math.floor(z * inv)), mask)


@njit(cache=True, inline="always")
def _rehash(pos, v, v1, inv, mask, head, nxt, prv, bucket):
    """Move segment v (beads v, v1) to the cell of its current midpoint."""
    h = _hash(
        np.int64(math.floor(0.5 * (pos[v, 0] + pos[v1, 0]) * inv)),
        np.int64(math.floor(0.5 * (pos[v, 1] + pos[v1, 1]) * inv)),
        np.int64(math.floor(0.5 * (pos[v, 2] + pos[v1, 2]) * inv)),
        mask,
    )
    _cell_update(v, h, head, nxt, prv, bucket)


@njit(cache=True, inline="always")
def _cell_range(x, y, z, reach, inv):
    """First and last cell index along x, y, z of the cells that overlap the cube
    [p − reach, p + reach] around the point p (cells of side 1/inv)."""
    return (np.int64(math.floor((x - reach) * inv)), np.int64(math.floor((x + reach) * inv)),
            np.int64(math.floor((y - reach) * inv)), np.int64(math.floor((y + reach) * inv)),
            np.int64(math.floor((z - reach) * inv)), np.int64(math.floor((z + reach) * inv)))


@njit(cache=True, inline="always")
def _axis_dist2(px, py, pz, jx, jy, jz, ex, ey, ez):
    """Squared distance of the point p from the line through j along the unit vector e."""
    rx = px - jx
    ry = py - jy
    rz = pz - jz
    t = rx * ex + ry * ey + rz * ez
    return rx * rx + ry * ry + rz * rz - t * t


@njit(cache=True, inline="always")
def _rodrigues(px, py, pz, jx, jy, jz, ex, ey, ez, c, s, oc):
    """The point p rotated by the angle φ (c = cos φ, s = sin φ, oc = 1 − c) about the line
    through j along the unit vector e (Rodrigues' formula)."""
    rx = px - jx
    ry = py - jy
    rz = pz - jz
    t = (rx * ex + ry * ey + rz * ez) * oc
    return (jx + rx * c + (ey * rz - ez * ry) * s + ex * t,
            jy + ry * c + (ez * rx - ex * rz) * s + ey * t,
            jz + rz * c + (ex * ry - ey * rx) * s + ez * t)


@njit(cache=True, inline="always")
def _turn_blocked(cmin, old, new):
    """Curvature limit: a joint may not end beyond θ_max (cos below ``cmin``) unless it bends
    less than before (so a chain above the limit can only approach it)."""
    return new < cmin and new < old


@njit(cache=True, inline="always")
def _de2(o1, n1, o2, n2, emode, power, escale):
    """Energy change of a move that changes two joints (old/new cosines o, n)."""
    if emode == 0:
        return (o1 - n1) + (o2 - n2)
    return (_joint_energy(n1, emode, power, escale)
            - _joint_energy(o1, emode, power, escale)
            + _joint_energy(n2, emode, power, escale)
            - _joint_energy(o2, emode, power, escale))


@njit(cache=True, inline="always")
def _de3(o1, n1, o2, n2, o3, n3, emode, power, escale):
    """Energy change of a move that changes three joints (old/new cosines o, n)."""
    if emode == 0:
        return (o1 - n1) + (o2 - n2) + (o3 - n3)
    return (_joint_energy(n1, emode, power, escale)
            - _joint_energy(o1, emode, power, escale)
            + _joint_energy(n2, emode, power, escale)
            - _joint_energy(o2, emode, power, escale)
            + _joint_energy(n3, emode, power, escale)
            - _joint_energy(o3, emode, power, escale))


@njit(cache=True, inline="always")
def _below_exp(u, x):
    """u < e^{−x} for x ≥ 0, decided exactly as ``u < math.exp(-x)`` but with the exponential
    evaluated only when u falls in a narrow band: 1 − x + x²/2 − x³/6 ≤ e^{−x} ≤
    1/(1 + x + x²/2 + x³/6) (Taylor with alternating remainder; the series of e^x has
    positive terms). Both shortcuts keep a margin of 1e-9, far above the rounding of the
    bounds (a few ulps where they can be near u ∈ [0, 1)) and of libm's exp (< 1 ulp), so
    they never decide differently from the plain test."""
    x2 = x * x
    h = 0.5 * x2
    t = x2 * x * (1.0 / 6.0)
    if u < (1.0 - x) + (h - t) - 1e-9:
        return True
    if u * ((1.0 + x) + (h + t)) > 1.0 + 1e-9:
        return False
    return u < math.exp(-x)


@njit(cache=True, inline="always")
def _boltzmann(x, s0, s1, s2, s3):
    """Accept with probability e^{−x} (x > 0; never when x > 50). Returns (accept, state)."""
    if x > 50.0:
        return False, s0, s1, s2, s3
    u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    return _below_exp(u, x), s0, s1, s2, s3


@njit(cache=True, inline="always")
def _metropolis(de, beta, s0, s1, s2, s3):
    """Metropolis rule of a symmetric proposal: accept with min(1, e^{−βΔE}); β = 0 is a
    quench (ΔE ≤ 0 only). Draws a uniform only when it needs one. Returns (accept, state)."""
    if de > 0.0:
        if beta == 0.0:
            return False, s0, s1, s2, s3
        return _boltzmann(de * beta, s0, s1, s2, s3)
    return True, s0, s1, s2, s3


@njit(cache=True, inline="always")
def _metropolis_jac(de, beta, j_old, j_new, s0, s1, s2, s3):
    """Metropolis rule with the Jacobian ratio j_old/j_new of a deterministic re-attachment:
    accept with min(1, (j_old/j_new)·e^{−βΔE}); β = 0 is a quench (ΔE ≤ 0 only)."""
    if beta == 0.0:
        if de > 0.0:
            return False, s0, s1, s2, s3
    elif de > 0.0 or j_new > j_old:
        x = de * beta - math.log(j_old / j_new)
        if x > 0.0:
            return _boltzmann(x, s0, s1, s2, s3)
    return True, s0, s1, s2, s3


@njit(cache=True, inline="always")
def _move_scale(u, l_cap, log_span):
    """Displacement scale ℓ = l_cap·e^{−u·log(l_cap/l_min)}: log-uniform in [l_min, l_cap]."""
    return l_cap * math.exp(-u * log_span)


@njit(cache=True, inline="always")
def _draw_angle(rho, phi_max, l_cap, log_span, s0, s1, s2, s3):
    """A rotation angle of a multi-bead move: a displacement scale ℓ log-uniform in
    [l_min, l_cap] (large moves early, fine ones late; a mixture of symmetric proposals is
    symmetric), then φ uniform in ±min(φ_max, ℓ/ρ_max), so that no point moves farther than ℓ.
    Returns (φ, generator state)."""
    u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    scale = _move_scale(u, l_cap, log_span)
    lim = phi_max
    if rho * lim > scale:
        lim = scale / rho
    u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
    return (2.0 * u - 1.0) * lim, s0, s1, s2, s3


@njit(cache=True, inline="always")
def _draw_length(u, m_max, law, log_span):
    """The length m ∈ [2, m_max] of a multi-bead crankshaft from one uniform u ∈ [0, 1):
    ``law`` 0 uniform; 1 log-uniform, m = ⌊2·((m_max + 1)/2)^u⌋ (``log_span`` =
    ln((m_max + 1)/2)): as many moves at every scale of m, whatever N; 2 mixed: u < 1/2 draws
    uniformly (from 2u), u ≥ 1/2 log-uniformly (from 2u − 1). The proposal is symmetric for
    any law (m does not depend on the chain), so detailed balance holds."""
    if law == 2:
        if u < 0.5:
            m = 2 + int(2.0 * u * (m_max - 1))
        else:
            m = int(2.0 * math.exp((2.0 * u - 1.0) * log_span))
    elif law == 0:
        m = 2 + int(u * (m_max - 1))
    else:
        m = int(2.0 * math.exp(u * log_span))
    if m > m_max:  # rounding at u → 1 (every law gives m ≥ 2: exp(·) ≥ 1)
        m = m_max
    return m


# ---- brute-force checks (O(N²); verification, not the hot loop) ------------------------------


@njit(cache=True)
def check_state(pos, mode, d, w, is_open=False):
    """Brute-force O(N²) check of the exclusion rule; returns the worst violation (≤ 0 is ok).

    bead mode: max over pairs at (cyclic, for closed chains) index distance ≥ 2 of
    (d − distance); tube mode: max over segment pairs sharing no bead of (w − distance).
    """
    n = pos.shape[0]
    worst = -np.inf
    if mode == 0:
        for a in range(n):
            for b in range(a + 2, n):
                if a == 0 and b == n - 1 and not is_open:
                    continue
                dx = pos[a, 0] - pos[b, 0]
                dy = pos[a, 1] - pos[b, 1]
                dz = pos[a, 2] - pos[b, 2]
                v = d - math.sqrt(dx * dx + dy * dy + dz * dz)
                if v > worst:
                    worst = v
    else:
        worst = w - min_nonadjacent_segment_distance(pos, is_open)
    return worst


@njit(cache=True)
def min_nonadjacent_segment_distance(pos, is_open=False):
    """Minimum distance between segments that share no bead (O(N²)); an open chain has no
    closing segment N−1 → 0."""
    n = pos.shape[0]
    best = np.inf
    nseg = n - 1 if is_open else n
    for a in range(nseg):
        a1 = a + 1 if a < n - 1 else 0
        for b in range(a + 2, nseg):
            if a == 0 and b == n - 1:
                continue
            b1 = b + 1 if b < n - 1 else 0
            dd = seg_dist2(pos[a, 0], pos[a, 1], pos[a, 2], pos[a1, 0], pos[a1, 1], pos[a1, 2],
                           pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0], pos[b1, 1], pos[b1, 2])
            if dd < best:
                best = dd
    return math.sqrt(best)
