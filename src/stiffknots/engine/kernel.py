"""Compiled Monte Carlo kernel for closed bead chains (paper §VII).

The chain is a closed polygon of N beads with unit bonds. The energy is the paper's discrete
bending energy E_d = C Σ_n (1 − u_n·u_{n+1}) (§VII), with C = 1.

Moves
-----
One move type covers both the paper's move and its generalisation, the *crankshaft*: pick a
pivot bead j and a length m ≥ 1, and rotate the m beads j+1 … j+m (indices mod N) by an angle
φ about the axis through the pivots j and k = j+m+1. For m = 1 this is exactly the paper's
move (one bead rotated about the axis through its two neighbours by ±δ, δ = π/100). Bond
lengths are preserved exactly (every bond either moves rigidly or joins a pivot, which lies on
the axis), and only the bending angles at the two pivots change, so ΔE costs O(1).

The paper's move (m = 1) has its own code in the loop, written for one bead: it makes the same
draws in the same order and evaluates the same floating-point expressions as the general code
with m = 1 (which it replaces), so the chains are those of the general code, bit for bit.

Exclusion (two models)
----------------------
* ``bead``  — beads at cyclic index distance ≥ 2 are never closer than ``d`` (the paper's rule,
  d = 1/√2). Distances between a pivot and the moved beads are invariant (the pivots lie on
  the rotation axis), so only moved–fixed pairs are checked.
* ``tube``  — segments sharing no bead are never closer than ``w`` (the tube of §II).

Strand passage is impossible by construction
--------------------------------------------
The rotation is continuous in the angle, t ↦ t·φ for t ∈ [0, 1]. Every point of a moved
segment lies at distance ρ ≤ ρ_max from the axis (distance to a line is convex, so the maximum
over a segment is reached at an end point), so along the path it moves with speed
``|φ|·ρ ≤ L := |φ|·ρ_max``. The distance d(t) between a moved segment and a fixed segment is
therefore L-Lipschitz in t, and d(t) ≥ max(d(0) − L t, d(1) − L (1 − t)) ≥ (d(0) + d(1) − L)/2.
A move is accepted only if d(0) + d(1) > L for every pair (moved segment, fixed segment) that
share no bead, so d(t) > 0 along the whole path: no segment of the chain crosses a segment it
is not bonded to, and the knot type cannot change. Pairs of moved segments move rigidly
(their distance is constant), and two bonded segments share a bead: they could only meet by
folding back onto each other, which both exclusion models forbid (bead model: beads i, i+2 are
≥ d apart; tube model: segments i, i+2 are ≥ w apart), and the turning angle at a pivot changes
by at most L per move. Only pairs with d(1) ≤ L can fail the test; they are found with the
cell list below, so the guard costs O(1) per moved bead.

Cell list
---------
Segment midpoints are kept in a spatial hash of cubic cells of side ``cell`` (linked lists,
doubly linked for O(1) updates; the hash is linear in the z index, so a z column of cells is
contiguous in memory). A fixed segment within distance D of a moved segment has its midpoint
within 1 + D of the moved segment's midpoint, hence within 1.5 + D of its moved end bead, so
scanning the cells around each moved bead finds every candidate; the bead rule is checked from
the same scan (a bead within d of a point has the midpoint of the segment it starts within
d + 1/2). A crankshaft scans, for each moved bead b at its new place p, the cells that
overlap the bounding box of Ball(p, d + 1/2) (bead rule), Ball(A', 1 + D) (its segment
A = (b − 1, b), new midpoint A') and, for the last moved bead, Ball(B', 1 + D) (B = (b, k)):
every fixed segment that one of its tests could refuse on has its midpoint in one of these
balls (radii enlarged by 1e-9), and the box is about 0.6 of the cube's cells. The cost per
move is independent of N.

A single-bead move (bead i from o to p, pivots j = i − 1 and k = i + 1) tests a fixed segment
v ∉ {j, i} only through three tests, and each can refuse the move only if v's midpoint lies in
a ball: the bead rule (bead v, or an open chain's last bead, within d of p) in the ball of
radius d + 1/2 about p; segment A = (j, i) in the ball of radius 1 + D about A's new midpoint
(the midpoint bound of ``_segment_blocked()``, D = max(w, L));
segment B = (i, k) likewise about B's. The cells scanned are those that overlap the bounding
box of the three balls (radii enlarged by 1e-9 against rounding), a subset of the cube of
side 2(1.5 + D) about p that the general loop scans. Every segment a test could refuse is
therefore met, and the tests themselves are the general loop's, so the decision is the same.

Neighbour lists (the paper's move alone)
----------------------------------------
When every move is the paper's single-bead move (:func:`run_single_moves`), bead i keeps a
list of the segments v ∉ {i − 1, i} whose midpoint lay within R_list = R + δ + s of bead i
when the lists were built (positions ``ref``); R = max(1.5 + max(w, δ), d + 1/2) + 1e-9
contains the three balls above for any single-bead move (``|p − midpoint of A or B| = 1/2`` and
L = δ·ρ ≤ δ, as ``ρ ≤ |i − j| = 1``), and s = ``NBR_SKIN``. The lists are valid while every bead
lies within s/2 of its place at the build: then for a move of bead i to p and a segment v
whose midpoint m_v is within R of p now,
``|m_v(build) − ref_i| ≤ |m_v(build) − m_v| + |m_v − p| + |p − x_i| + |x_i − ref_i|
≤ s/2 + R + δ + s/2 = R_list`` (a midpoint moves no farther than the farther of its beads),
so v is in bead i's list and the list meets every segment the cell scan would refuse on.
The kernel rebuilds all lists as soon as an accepted move takes its bead farther than s/2
from ``ref``, and on entry when any bead (moved by any kernel, or replaced) is farther than
s/2, or when the radius needed grew (other δ, d, w). A bead whose list does not fit in the
reserved space is marked and scans the cell list. Lists and cell scan give the same
decisions, hence the same chains, draw for draw.

Open chains
-----------
With ``I_OPEN = 1`` the chain is open: beads 0, 1 and N−2, N−1 are clamped on the z axis (the
two end segments point along −z and +z; they never move), and pivots are chosen so that the
moved beads lie in 2 … N−3. Bond lengths and the end-to-end distance Δz are therefore fixed,
and so is the excess length L_e = (N−1) − Δz (paper §VIII): this is the fixed-extension
ensemble; the force term −F·Δz is a constant and drops out of every ΔE. The knot type of an
open chain is that of the closure along the two rays that continue the end segments to ±∞.
Those rays must not be crossed either: every free bead lives in the open slab
z_0 < z < z_{N−1}, and a move is accepted only if, for every moved bead,
(z_old − z_0) + (z_new − z_0) > L and (z_{N−1} − z_old) + (z_{N−1} − z_new) > L, with L the
largest displacement of the move. By the Lipschitz argument above each moved point stays at
height > z_0 and < z_{N−1} along the whole path, and z is linear along a segment, so no
segment touches a ray.

Energy modes and the curvature limit
------------------------------------
The energy per joint is f(c), c = u_n·u_{n+1} = cos θ_n: f = 1 − c (mode 0, the paper's
E_d), or f = ((1 − c)/s)^p (mode 1, whose sum is dominated by the largest turning angles as p
grows: used by the restricted-curvature search of §IX D; the scale s keeps the energies of
order one so that temperatures stay meaningful). Independently, a joint may be forbidden to turn
by more than θ_max (``F_CMIN`` = cos θ_max): a move is rejected if it leaves a pivot's c
below ``F_CMIN`` *and* lower than before (so a chain that starts above the limit can only
approach it). A bend of θ between unit bonds is a circle of radius 1/(2 sin(θ/2)) through
the three beads, so θ_max ↔ R_min = 1/(2 sin(θ_max/2)).

The shared primitives (generator, cell list, joint energy, Metropolis rule, rotation, guard of one
segment pair, brute-force checks) live in :mod:`stiffknots.engine.prims`; this module keeps the
crankshaft move. All functions see arrays and numbers only (no Python objects) and allocate
nothing in the loop. Inside the loop only helpers that take numbers are inlined: numba takes a
reference (two atomic operations) on every array passed to an inlined helper, which costs
more than a whole single-bead move; array work there is written out, or is a call that is
rarely made (``_cell_relink()``, ``_nbr_build()``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.engine.prims import (  # noqa: F401 (re-exported: the kernel's public names)
    C_ACCEPTED,
    C_ENERGY_OK,
    C_NCNT,
    C_TRIED,
    F_CELL,
    F_CMIN,
    F_D,
    F_DELTA,
    F_EINV,
    F_LCAP,
    F_LMIN,
    F_NFPAR,
    F_PHIMAX,
    F_PSINGLE,
    F_W,
    F_ZHI,
    F_ZLO,
    HASH_X,
    HASH_Y,
    I_EMODE,
    I_MLAW,
    I_MMAX,
    I_MODE,
    I_NIPAR,
    I_OPEN,
    I_POWER,
    _axis_dist2,
    _cell_of,
    _cell_range,
    _cell_update,
    _de2,
    _draw_angle,
    _draw_length,
    _hash,
    _metropolis,
    _move_scale,
    _next,
    _rehash,
    _rodrigues,
    _segment_blocked,
    _turn_blocked,
    cell_build,
    check_state,
    energy_chain,
    energy_closed,
    min_nonadjacent_segment_distance,
    new_rng_state,
    turning_cosines,
    uniforms,
)

# ---- the paper's single-bead move (m = 1) ------------------------------------------------
#
# Its code sits in the loop body of :func:`_moves_loop` and calls only helpers that take
# numbers: an inlined helper that takes an array makes numba take a reference to the array
# (an atomic increment and decrement) on every call, which costs more than the whole move.

#: neighbour lists (:func:`run_single_moves`): skin
NBR_SKIN = 0.3
#: neighbour lists: segments reserved per bead
NBR_PER_BEAD = 16
# slots of the neighbour lists' bookkeeping array ``nbr_meta``
NB_RADIUS = 0  # list radius of the last build (0: never built)
NB_BUILDS = 1  # number of builds (diagnostics)
NB_NMETA = 2


@njit(cache=True, inline="always")
def _pivot(u, n, span, is_open):
    """The first pivot j of a move from the uniform draw u ∈ [0, 1): 1 ≤ j ≤ span on an open
    chain (its clamped end segments never move), 0 ≤ j < n on a ring; −1 when an open chain
    has no room for the move (span < 1)."""
    if is_open:
        if span < 1:
            return -1
        j = 1 + int(u * span)
        if j > span:
            j = span
        return j
    j = int(u * n)
    if j >= n:
        j = n - 1
    return j


@njit(cache=True, inline="always")
def _single_limits(lmove, w, d, mode):
    """(dseg = max(w, L), radius R around the moved bead's new place that holds the midpoint
    of every fixed segment a single-bead move must test (module docstring, Cell list), with
    a margin of 1e-9 for rounding)."""
    dseg = w if w > lmove else lmove
    r = 1.5 + dseg
    if mode == 0 and d + 0.5 > r:
        r = d + 0.5
    return dseg, r + 1e-9


@njit(cache=True, inline="always")
def _single_bead_blocked(mode, is_open, n, v, v1, i, k, vx, vy, vz, px, py, pz, lx, ly, lz,
                         d2):
    """Bead rule of a single-bead move against fixed segment v = (v, v1): bead v (unless it
    is k, bonded to i; every other bead but j, i is ≥ 2 away in index) and, for the last
    segment of an open chain, its last bead (lx, ly, lz), which starts no segment."""
    if mode != 0:
        return False
    if v != k:
        ddx, ddy, ddz = vx - px, vy - py, vz - pz
        if ddx * ddx + ddy * ddy + ddz * ddz < d2:
            return True
    if is_open and v1 == n - 1 and n - 1 - i >= 2:
        ddx, ddy, ddz = lx - px, ly - py, lz - pz
        if ddx * ddx + ddy * ddy + ddz * ddz < d2:
            return True
    return False


@njit(cache=True, inline="always")
def _single_segments_blocked(v, jm, k, vx, vy, vz, wx, wy, wz, px, py, pz, ox, oy, oz,
                             jx, jy, jz, kx, ky, kz, lmove, w2, dseg):
    """The moved segments A = (j, i) and B = (i, k) (new ends p, old o) against the fixed
    segment v = (v, v + 1) = (vx.., wx..), unless bonded (A: v = j − 1 = jm; B: v = k):
    :func:`stiffknots.engine.prims._segment_blocked` (tube and strand-passage guard)."""
    mvx = 0.5 * (vx + wx)
    mvy = 0.5 * (vy + wy)
    mvz = 0.5 * (vz + wz)
    if v != jm and _segment_blocked(jx, jy, jz, px, py, pz, jx, jy, jz, ox, oy, oz,
                                    0.5 * (jx + px), 0.5 * (jy + py), 0.5 * (jz + pz),
                                    vx, vy, vz, wx, wy, wz, mvx, mvy, mvz, dseg, w2,
                                    lmove):
        return True
    return v != k and _segment_blocked(px, py, pz, kx, ky, kz, ox, oy, oz, kx, ky, kz,
                                       0.5 * (px + kx), 0.5 * (py + ky), 0.5 * (pz + kz),
                                       vx, vy, vz, wx, wy, wz, mvx, mvy, mvz, dseg, w2,
                                       lmove)


@njit(cache=True, inline="always")
def _single_box(jx, jy, jz, px, py, pz, kx, ky, kz, dseg, d, mode, inv):
    """First and last cell index along x, y, z of the cells that overlap the bounding box of
    Ball(A', 1 + dseg) ∪ Ball(B', 1 + dseg) ∪ Ball(p, d + 1/2) (the last for the bead rule
    only): A', B' the new midpoints of the moved segments (module docstring, Cell list)."""
    rs = 1.0 + dseg + 1e-9
    rb = d + 0.5 + 1e-9 if mode == 0 else 0.0
    amx, amy, amz = 0.5 * (jx + px), 0.5 * (jy + py), 0.5 * (jz + pz)
    bmx, bmy, bmz = 0.5 * (px + kx), 0.5 * (py + ky), 0.5 * (pz + kz)
    lx = min(min(amx, bmx) - rs, px - rb)
    hx = max(max(amx, bmx) + rs, px + rb)
    ly = min(min(amy, bmy) - rs, py - rb)
    hy = max(max(amy, bmy) + rs, py + rb)
    lz = min(min(amz, bmz) - rs, pz - rb)
    hz = max(max(amz, bmz) + rs, pz + rb)
    return (np.int64(math.floor(lx * inv)), np.int64(math.floor(hx * inv)),
            np.int64(math.floor(ly * inv)), np.int64(math.floor(hy * inv)),
            np.int64(math.floor(lz * inv)), np.int64(math.floor(hz * inv)))


@njit(cache=True)
def _nbr_build(pos, is_open, radius, inv, mask, head, nxt, nbr, row, ref):
    """Neighbour lists of every bead i: the segments v ≠ i − 1, i whose midpoint lies within
    ``radius`` of bead i (found with the cell list); ``ref`` = the positions now. Bead i's
    list is nbr[row[2i] : row[2i] + row[2i + 1]]; a bead whose list does not fit gets
    row[2i + 1] = −1 (its moves scan the cell list)."""
    n = pos.shape[0]
    cap = nbr.shape[0]
    r2 = radius * radius
    top = 0
    for i in range(n):
        px, py, pz = pos[i, 0], pos[i, 1], pos[i, 2]
        ref[i, 0] = px
        ref[i, 1] = py
        ref[i, 2] = pz
        im = i - 1 if i > 0 else n - 1
        c = 0
        x0, x1, y0, y1, z0, z1 = _cell_range(px, py, pz, radius, inv)
        for cx in range(x0, x1 + 1):
            for cy in range(y0, y1 + 1):
                for cz in range(z0, z1 + 1):
                    v = head[_hash(cx, cy, cz, mask)]
                    while v >= 0:
                        if v != i and v != im and c >= 0:
                            v1 = v + 1 if v < n - 1 else 0
                            mx = 0.5 * (pos[v, 0] + pos[v1, 0]) - px
                            my = 0.5 * (pos[v, 1] + pos[v1, 1]) - py
                            mz = 0.5 * (pos[v, 2] + pos[v1, 2]) - pz
                            if mx * mx + my * my + mz * mz <= r2:
                                if top + c < cap:
                                    nbr[top + c] = v
                                    c += 1
                                else:
                                    c = -1
                        v = nxt[v]
        row[2 * i] = top
        row[2 * i + 1] = c
        if c > 0:
            top += c


@njit(cache=True)
def _nbr_valid(pos, ref, radius, nbr_meta, half_skin):
    """Are the lists still valid: built with a radius ≥ ``radius``, and no bead farther than
    half the skin from where it was at the build (whatever moved it since)?"""
    if nbr_meta[NB_RADIUS] < radius or ref.shape[0] != pos.shape[0]:
        return False
    h2 = half_skin * half_skin
    for b in range(pos.shape[0]):
        dx = pos[b, 0] - ref[b, 0]
        dy = pos[b, 1] - ref[b, 1]
        dz = pos[b, 2] - ref[b, 2]
        if dx * dx + dy * dy + dz * dz > h2:
            return False
    return True


@njit(cache=True)
def _cell_relink(v, h, head, nxt, prv, bucket):
    """Move segment v to cell h (a call, not inlined: it is rarely needed)."""
    _cell_update(v, h, head, nxt, prv, bucket)


@njit(cache=True)
def run_single_moves(pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, cnt, rng,
                     nbr, row, ref, nbr_meta):
    """Attempt ``n_moves`` of the paper's single-bead move at ``temperature``; return ΔE.

    The same chain, counters and generator state as :func:`run_moves` with only single-bead
    moves (same draws, same tests), faster: the guard reads neighbour lists instead of
    scanning cells (module docstring, Neighbour lists).

    Parameters
    ----------
    pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, cnt, rng
        As :func:`run_moves` (``ipar[I_MMAX]`` and ``fpar[F_PSINGLE]`` are not read).
    nbr
        (≥ 1,) int32, the lists one after another (:data:`NBR_PER_BEAD` per bead is a good
        size; a bead whose list does not fit falls back to the cell list).
    row
        (2 N,) int64, start and length of bead i's list at 2i and 2i + 1.
    ref
        (N, 3) float64, the positions at the last build.
    nbr_meta
        (NB_NMETA,) float64: radius of the last build (0: never) and build count.
        These four are (re)built here when needed, whatever happened to the chain since.
    """
    return _moves_loop(pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, pos,
                       cnt, rng, nbr, row, ref, nbr_meta, True)


@njit(cache=True)
def run_moves(pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, newpos, cnt,
              rng):
    """Attempt ``n_moves`` crankshaft moves at ``temperature`` (Metropolis); return ΔE.

    Parameters
    ----------
    pos
        (N, 3) float64, modified in place. Closed chain with unit bonds.
    n_moves
        Number of attempted moves.
    temperature
        k_B T in units of C (0 means a quench: only ΔE ≤ 0 is accepted).
    ipar, fpar
        Integer and float parameters, see the ``I_*`` and ``F_*`` slots.
    head, nxt, prv, bucket
        The cell list of segment midpoints (``cell_build``).
    newpos
        (≥ m_max, 3) float64 scratch space.
    cnt
        (C_NCNT,) int64 counters, incremented.
    rng
        (4,) uint64 xoshiro256+ state (``new_rng_state``), advanced in place.

    Returns
    -------
    float
        The total energy change of the accepted moves.
    """
    return _moves_loop(pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, newpos,
                       cnt, rng, nxt, nxt, newpos, fpar, False)


@njit(cache=True)
def _moves_loop(pos, n_moves, temperature, ipar, fpar, head, nxt, prv, bucket, newpos, cnt,
                rng, nbr, row, ref, nbr_meta, single_lists):
    """The Monte Carlo loop of :func:`run_moves` (``single_lists`` False: crankshafts of
    every length, cell list) and of :func:`run_single_moves` (``single_lists`` True: the
    paper's move only, neighbour lists ``nbr``, ``row``, ``ref``, ``nbr_meta``; a literal, so
    numba compiles each case on its own and drops the other's code)."""
    n = pos.shape[0]
    mode = ipar[I_MODE]
    m_max = ipar[I_MMAX]
    is_open = ipar[I_OPEN] != 0
    emode = ipar[I_EMODE]
    power = ipar[I_POWER]
    cmin = fpar[F_CMIN]
    zlo = fpar[F_ZLO]
    zhi = fpar[F_ZHI]
    escale = fpar[F_EINV]
    mcap = n - 4 if is_open else n - 3
    if m_max > mcap:
        m_max = mcap
    m_law = ipar[I_MLAW]
    m_log_span = math.log(0.5 * (m_max + 1)) if m_max >= 2 else 0.0
    delta = fpar[F_DELTA]
    p_single = fpar[F_PSINGLE]
    phi_max = fpar[F_PHIMAX]
    l_cap = fpar[F_LCAP]
    l_min = fpar[F_LMIN]
    log_span = math.log(l_cap / l_min) if l_cap > l_min else 0.0
    d = fpar[F_D]
    d2 = d * d
    w = fpar[F_W]
    w2 = w * w
    cell = fpar[F_CELL]
    inv = 1.0 / cell
    mask = head.shape[0] - 1
    cd = math.cos(delta)
    sd = math.sin(delta)
    beta = 1.0 / temperature if temperature > 0.0 else 0.0
    # an open chain's last bead (clamped: crankshafts never move it)
    lbx, lby, lbz = pos[n - 1, 0], pos[n - 1, 1], pos[n - 1, 2]
    # neighbour lists: radius R of _single_limits at L = δ (ρ ≤ 1), plus δ and the skin
    half_skin2 = 0.25 * NBR_SKIN * NBR_SKIN
    nb_radius = _single_limits(delta, w, d, mode)[1] + delta + NBR_SKIN
    if single_lists:
        m_max = 1
        if not _nbr_valid(pos, ref, nb_radius, nbr_meta, 0.5 * NBR_SKIN):
            _nbr_build(pos, is_open, nb_radius, inv, mask, head, nxt, nbr, row, ref)
            nbr_meta[NB_RADIUS] = nb_radius
            nbr_meta[NB_BUILDS] += 1
    de_total = 0.0
    n_single = 0  # single-bead moves: tried, energy accepted, accepted
    e_single = 0
    a_single = 0
    s0, s1, s2, s3 = rng[0], rng[1], rng[2], rng[3]

    for _it in range(n_moves):
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        if m_max < 2 or u < p_single:
            # ---- the paper's move: bead i = j + 1 by ±δ about the axis through j, k ---------
            # (the same draws and the same floating-point expressions as the general code
            # below with m = 1, so both give the same chains)
            n_single += 1
            u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            # pivots 1 ≤ j and k ≤ N − 2 on an open chain: the clamped ends never move
            j = _pivot(u, n, n - 4, is_open)
            if j < 0:
                continue
            i = j + 1 if j < n - 1 else 0
            k = i + 1 if i < n - 1 else 0
            # unsigned indices: no test for negative (wrap-around) indices in the loads
            ju, iu, ku = np.uint64(j), np.uint64(i), np.uint64(k)
            jx, jy, jz = pos[ju, 0], pos[ju, 1], pos[ju, 2]
            ox, oy, oz = pos[iu, 0], pos[iu, 1], pos[iu, 2]
            kx, ky, kz = pos[ku, 0], pos[ku, 1], pos[ku, 2]
            ex, ey, ez = kx - jx, ky - jy, kz - jz
            el = math.sqrt(ex * ex + ey * ey + ez * ez)
            if el < 1e-9:
                continue
            ex, ey, ez = ex / el, ey / el, ez / el
            rho2 = _axis_dist2(ox, oy, oz, jx, jy, jz, ex, ey, ez)
            rho = math.sqrt(rho2) if rho2 > 0.0 else 0.0
            u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
            s = sd if u < 0.5 else -sd
            px, py, pz = _rodrigues(ox, oy, oz, jx, jy, jz, ex, ey, ez, cd, s, 1.0 - cd)
            # energy: only the bending angles at j and k change
            jm = j - 1 if j > 0 else n - 1
            kp = k + 1 if k < n - 1 else 0
            jmu, kpu = np.uint64(jm), np.uint64(kp)
            ax, ay, az = jx - pos[jmu, 0], jy - pos[jmu, 1], jz - pos[jmu, 2]
            old1 = ax * (ox - jx) + ay * (oy - jy) + az * (oz - jz)
            new1 = ax * (px - jx) + ay * (py - jy) + az * (pz - jz)
            bx, by, bz = pos[kpu, 0] - kx, pos[kpu, 1] - ky, pos[kpu, 2] - kz
            old2 = (kx - ox) * bx + (ky - oy) * by + (kz - oz) * bz
            new2 = (kx - px) * bx + (ky - py) * by + (kz - pz) * bz
            if cmin > -1.0 and (_turn_blocked(cmin, old1, new1)
                                or _turn_blocked(cmin, old2, new2)):
                continue
            de = _de2(old1, new1, old2, new2, emode, power, escale)
            ok, s0, s1, s2, s3 = _metropolis(de, beta, s0, s1, s2, s3)
            if not ok:
                continue
            e_single += 1
            # ---- exclusion and strand-passage guard
            lmove = delta * rho  # largest displacement of any moved point
            if is_open and ((oz - zlo) + (pz - zlo) <= lmove or (zhi - oz) + (zhi - pz) <= lmove):
                continue
            dseg = _single_limits(lmove, w, d, mode)[0]
            blocked = False
            iu2 = np.uint64(2) * iu
            if single_lists and row[iu2 + np.uint64(1)] >= 0:
                e0 = np.uint64(row[iu2])
                for e in range(row[iu2 + np.uint64(1)]):
                    v = np.int64(nbr[e0 + np.uint64(e)])
                    v1 = v + 1 if v < n - 1 else 0
                    vu, v1u = np.uint64(v), np.uint64(v1)
                    vx, vy, vz = pos[vu, 0], pos[vu, 1], pos[vu, 2]
                    wx, wy, wz = pos[v1u, 0], pos[v1u, 1], pos[v1u, 2]
                    if _single_bead_blocked(mode, is_open, n, v, v1, i, k, vx, vy, vz,
                                            px, py, pz, lbx, lby, lbz, d2) or \
                            _single_segments_blocked(v, jm, k, vx, vy, vz, wx, wy, wz,
                                                     px, py, pz, ox, oy, oz, jx, jy, jz,
                                                     kx, ky, kz, lmove, w2, dseg):
                        blocked = True
                        break
            else:
                x0, x1, y0, y1, z0, z1 = _single_box(jx, jy, jz, px, py, pz, kx, ky, kz,
                                                     dseg, d, mode, inv)
                for cx in range(x0, x1 + 1):
                    for cy in range(y0, y1 + 1):
                        hxy = cx * HASH_X + cy * HASH_Y
                        for cz in range(z0, z1 + 1):
                            v = head[np.uint64((hxy + cz) & mask)]
                            while v >= 0:
                                if v != j and v != i:  # not a moved segment
                                    v1 = v + 1 if v < n - 1 else 0
                                    vu, v1u = np.uint64(v), np.uint64(v1)
                                    vx, vy, vz = pos[vu, 0], pos[vu, 1], pos[vu, 2]
                                    wx, wy, wz = pos[v1u, 0], pos[v1u, 1], pos[v1u, 2]
                                    if _single_bead_blocked(
                                            mode, is_open, n, v, v1, i, k, vx, vy, vz,
                                            px, py, pz, lbx, lby, lbz, d2) or \
                                            _single_segments_blocked(
                                                v, jm, k, vx, vy, vz, wx, wy, wz,
                                                px, py, pz, ox, oy, oz, jx, jy, jz,
                                                kx, ky, kz, lmove, w2, dseg):
                                        blocked = True
                                        break
                                v = nxt[np.uint64(v)]
                            if blocked:
                                break
                        if blocked:
                            break
                    if blocked:
                        break
            if blocked:
                continue
            # ---- accept: bead i, and the cells of segments j = (j, i) and i = (i, k)
            a_single += 1
            de_total += de
            pos[iu, 0] = px
            pos[iu, 1] = py
            pos[iu, 2] = pz
            h = _cell_of(0.5 * (jx + px), 0.5 * (jy + py), 0.5 * (jz + pz), inv, mask)
            if h != bucket[ju]:
                _cell_relink(j, h, head, nxt, prv, bucket)
            h = _cell_of(0.5 * (px + kx), 0.5 * (py + ky), 0.5 * (pz + kz), inv, mask)
            if h != bucket[iu]:
                _cell_relink(i, h, head, nxt, prv, bucket)
            if single_lists:
                # every bead stays within half the skin of its place at the last build
                dx, dy, dz = px - ref[iu, 0], py - ref[iu, 1], pz - ref[iu, 2]
                if dx * dx + dy * dy + dz * dz > half_skin2:
                    _nbr_build(pos, is_open, nb_radius, inv, mask, head, nxt, nbr, row, ref)
                    nbr_meta[NB_BUILDS] += 1
            continue
        # ---- a crankshaft of m ≥ 2 beads ---------------------------------------------------
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        m = _draw_length(u, m_max, m_law, m_log_span)
        cls = 1
        cnt[C_TRIED + cls] += 1
        u, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
        # pivots 1 ≤ j and k ≤ N−2 on an open chain: the clamped end segments never move
        j = _pivot(u, n, n - 3 - m, is_open)
        if j < 0:
            continue
        k = j + m + 1
        if k >= n:
            k -= n
        jx, jy, jz = pos[j, 0], pos[j, 1], pos[j, 2]
        ex, ey, ez = pos[k, 0] - jx, pos[k, 1] - jy, pos[k, 2] - jz
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        if el < 1e-9:
            continue
        ex, ey, ez = ex / el, ey / el, ez / el
        # largest distance of a moved bead from the axis (invariant under the move)
        rho2 = 0.0
        for q in range(m):
            b = j + 1 + q
            if b >= n:
                b -= n
            r2 = _axis_dist2(pos[b, 0], pos[b, 1], pos[b, 2], jx, jy, jz, ex, ey, ez)
            if r2 > rho2:
                rho2 = r2
        rho = math.sqrt(rho2) if rho2 > 0.0 else 0.0
        phi, s0, s1, s2, s3 = _draw_angle(rho, phi_max, l_cap, log_span, s0, s1, s2, s3)
        c = math.cos(phi)
        s = math.sin(phi)
        phi = abs(phi)
        oc = 1.0 - c
        # ---- energy: only the bending angles at the pivots j and k change --------------
        # (only the first and last moved beads are rotated before the Metropolis test; the
        # others after it, with the same expressions, so a rejected move costs one pass)
        jm = j - 1 if j > 0 else n - 1
        kp = k + 1 if k < n - 1 else 0
        b1 = j + 1 if j < n - 1 else 0  # first moved bead
        bm = k - 1 if k > 0 else n - 1  # last moved bead
        f1x, f1y, f1z = _rodrigues(pos[b1, 0], pos[b1, 1], pos[b1, 2], jx, jy, jz,
                                   ex, ey, ez, c, s, oc)
        fmx, fmy, fmz = _rodrigues(pos[bm, 0], pos[bm, 1], pos[bm, 2], jx, jy, jz,
                                   ex, ey, ez, c, s, oc)
        ax, ay, az = jx - pos[jm, 0], jy - pos[jm, 1], jz - pos[jm, 2]
        old1 = ax * (pos[b1, 0] - jx) + ay * (pos[b1, 1] - jy) + az * (pos[b1, 2] - jz)
        new1 = ax * (f1x - jx) + ay * (f1y - jy) + az * (f1z - jz)
        kx, ky, kz = pos[k, 0], pos[k, 1], pos[k, 2]
        bx, by, bz = pos[kp, 0] - kx, pos[kp, 1] - ky, pos[kp, 2] - kz
        old2 = (kx - pos[bm, 0]) * bx + (ky - pos[bm, 1]) * by + (kz - pos[bm, 2]) * bz
        new2 = (kx - fmx) * bx + (ky - fmy) * by + (kz - fmz) * bz
        # curvature limit: no pivot may end beyond θ_max unless it bends less than before
        if cmin > -1.0 and (_turn_blocked(cmin, old1, new1) or _turn_blocked(cmin, old2, new2)):
            continue
        de = _de2(old1, new1, old2, new2, emode, power, escale)
        ok, s0, s1, s2, s3 = _metropolis(de, beta, s0, s1, s2, s3)
        if not ok:
            continue
        cnt[C_ENERGY_OK + cls] += 1
        # Rodrigues rotation of the moved beads about the axis through pivot j
        for q in range(m):
            b = j + 1 + q
            if b >= n:
                b -= n
            newpos[q, 0], newpos[q, 1], newpos[q, 2] = _rodrigues(
                pos[b, 0], pos[b, 1], pos[b, 2], jx, jy, jz, ex, ey, ez, c, s, oc)
        # ---- exclusion and strand-passage guard ----------------------------------------
        lmove = phi * rho  # largest displacement of any moved point
        dseg = w if w > lmove else lmove
        ok = True
        if is_open:
            # the closure rays beyond the clamped ends: moved beads stay inside the slab
            for q in range(m):
                b = j + 1 + q
                zo = pos[b, 2]
                zn = newpos[q, 2]
                if (zo - zlo) + (zn - zlo) <= lmove or (zhi - zo) + (zhi - zn) <= lmove:
                    ok = False
                    break
        for q in range(m):
            if not ok:
                break
            b = j + 1 + q
            if b >= n:
                b -= n
            px, py, pz = newpos[q, 0], newpos[q, 1], newpos[q, 2]
            # previous bead (moved or pivot j), new position
            if q == 0:
                ppx, ppy, ppz = jx, jy, jz
                opx, opy, opz = jx, jy, jz
            else:
                ppx, ppy, ppz = newpos[q - 1, 0], newpos[q - 1, 1], newpos[q - 1, 2]
                bb = b - 1 if b > 0 else n - 1
                opx, opy, opz = pos[bb, 0], pos[bb, 1], pos[bb, 2]
            last = q == m - 1
            # moved segment A = (b-1, b), and for the last moved bead also B = (b, k)
            amx = 0.5 * (ppx + px)
            amy = 0.5 * (ppy + py)
            amz = 0.5 * (ppz + pz)
            bmx = 0.5 * (px + kx)
            bmy = 0.5 * (py + ky)
            bmz = 0.5 * (pz + kz)
            sa = b - 1 if b > 0 else n - 1  # index of segment A
            # cells overlapping the bounding box of the balls that hold every fixed
            # segment a test below could refuse on (module docstring, Cell list): about
            # 0.6 of the cells of the cube of half-side max(1.5 + dseg, d + 1/2) about p
            # that the loop used to scan; for a bead that is not the last, B's ball is
            # A's (k ↦ the previous bead)
            if last:
                x0, x1, y0, y1, z0, z1 = _single_box(ppx, ppy, ppz, px, py, pz, kx, ky, kz,
                                                     dseg, d, mode, inv)
            else:
                x0, x1, y0, y1, z0, z1 = _single_box(ppx, ppy, ppz, px, py, pz,
                                                     ppx, ppy, ppz, dseg, d, mode, inv)
            for cx in range(x0, x1 + 1):
                if not ok:
                    break
                for cy in range(y0, y1 + 1):
                    if not ok:
                        break
                    for cz in range(z0, z1 + 1):
                        if not ok:
                            break
                        v = head[_hash(cx, cy, cz, mask)]
                        while v >= 0:
                            off = v - j
                            if off < 0:
                                off += n
                            if off <= m:  # moved segment: rigid with respect to A and B
                                v = nxt[v]
                                continue
                            vx, vy, vz = pos[v, 0], pos[v, 1], pos[v, 2]
                            v1 = v + 1 if v < n - 1 else 0
                            wx, wy, wz = pos[v1, 0], pos[v1, 1], pos[v1, 2]
                            # bead rule: fixed bead v against moved bead b
                            if mode == 0:
                                sep = v - b
                                if sep < 0:
                                    sep = -sep
                                if not is_open and n - sep < sep:
                                    sep = n - sep
                                if sep >= 2:
                                    ddx, ddy, ddz = vx - px, vy - py, vz - pz
                                    if ddx * ddx + ddy * ddy + ddz * ddz < d2:
                                        ok = False
                                        break
                                # an open chain's last bead starts no segment: check it
                                # with the last segment (its midpoint is within d + 1/2)
                                if is_open and v1 == n - 1 and n - 1 - b >= 2:
                                    ddx = pos[n - 1, 0] - px
                                    ddy = pos[n - 1, 1] - py
                                    ddz = pos[n - 1, 2] - pz
                                    if ddx * ddx + ddy * ddy + ddz * ddz < d2:
                                        ok = False
                                        break
                            mvx = 0.5 * (vx + wx)
                            mvy = 0.5 * (vy + wy)
                            mvz = 0.5 * (vz + wz)
                            # segment A = (b-1, b) against fixed segment v (skip if bonded)
                            if v1 != sa and v != b and _segment_blocked(
                                    ppx, ppy, ppz, px, py, pz,
                                    opx, opy, opz, pos[b, 0], pos[b, 1], pos[b, 2],
                                    amx, amy, amz, vx, vy, vz, wx, wy, wz,
                                    mvx, mvy, mvz, dseg, w2, lmove):
                                ok = False
                                break
                            # segment B = (b, k) for the last moved bead
                            if last and v != k and v1 != b and _segment_blocked(
                                    px, py, pz, kx, ky, kz,
                                    pos[b, 0], pos[b, 1], pos[b, 2], kx, ky, kz,
                                    bmx, bmy, bmz, vx, vy, vz, wx, wy, wz,
                                    mvx, mvy, mvz, dseg, w2, lmove):
                                ok = False
                                break
                            v = nxt[v]
        if not ok:
            continue
        # ---- accept ----------------------------------------------------------------------
        cnt[C_ACCEPTED + cls] += 1
        de_total += de
        for q in range(m):
            b = j + 1 + q
            if b >= n:
                b -= n
            pos[b, 0] = newpos[q, 0]
            pos[b, 1] = newpos[q, 1]
            pos[b, 2] = newpos[q, 2]
        for q in range(m + 1):
            v = j + q
            if v >= n:
                v -= n
            v1 = v + 1 if v < n - 1 else 0
            h = _cell_of(0.5 * (pos[v, 0] + pos[v1, 0]), 0.5 * (pos[v, 1] + pos[v1, 1]),
                         0.5 * (pos[v, 2] + pos[v1, 2]), inv, mask)
            if h != bucket[v]:
                _cell_relink(v, h, head, nxt, prv, bucket)
    cnt[C_TRIED] += n_single
    cnt[C_ENERGY_OK] += e_single
    cnt[C_ACCEPTED] += a_single
    rng[0], rng[1], rng[2], rng[3] = s0, s1, s2, s3
    return de_total
