"""Compiled guarded Langevin dynamics of a closed bead-spring ring: the collective search.

The Monte Carlo kernels (:mod:`stiffknots.engine.kernel`) move a few beads at a time. The
dynamics here moves every bead at every step, the way the peer (LAMMPS, ``fix langevin``)
searches; it is a *search* stage, not a sampler of the constrained model: the bonds are stiff
springs and the bead rule a soft wall, and the chain it ends on is taken back onto the exact
model (unit bonds, the bead rule) by :mod:`stiffknots.engine.langevin` and the final minimiser.

Model (units: bond length 1, C = 1, k_B = 1, bead mass 1; the peer's, bench/peer_lammps.py) ::

    U = K_b Σ_bonds (|b_n| − 1)²  +  Σ_joints (1 − û_n·û_{n+1})  +  Σ_{|i−j| ≥ 2} φ(r_ij),

φ the WCA repulsion 4[(σ/r)¹² − (σ/r)⁶] + 1 for r < r_c = 2^{1/6}σ (0 beyond), r_c the contact
distance (0.72 by default, just above the bead rule's 1/√2, as in the peer benchmark), the
middle term the discrete bending energy E_d of §VII written with unit bond vectors û.

Integrator: BAOAB Langevin splitting (Leimkuhler & Matthews, Appl. Math. Res. Express 2013):
half kick, half drift, Ornstein–Uhlenbeck step v ← c₁v + √((1 − c₁²)T) ξ (c₁ = e^{−γ dt},
γ = 1/damp; ξ uniform with unit variance, as the peer's ``fix langevin`` draws it: the
kernel's xoshiro256+ generator, ten times cheaper than normal deviates), half drift, force,
half kick. T falls exponentially from ``t_start`` to
``t_end`` over the run (the peer's schedule).

No strand passage (proof)
-------------------------
A step moves every bead along the straight line from r_i to r'_i (the drift of the step;
kicks change only velocities). A point p = (1−s)r_a + s r_{a+1} of a segment then moves by at
most ``max(|Δr_a|, |Δr_{a+1}|)`` in that step, along a straight line; over several steps it
travels at most max(c_a, c_{a+1}), c_i the summed step lengths of bead i. So the distance D_ab
between two segments a = (a, a+1) and b = (b, b+1) that share no bead, measured at some moment,
has since fallen by at most e_a + e_b, e = the larger c of a segment's beads since then; and
within one step it is L-Lipschitz in the step's parameter with ``L = max|Δr|`` over a's beads plus
the same over b's, so D(t) ≥ (D(0) + D(1) − L)/2 on the step. The guard keeps, for every such
pair, one of these certificates > η (η = 10⁻⁹, the floor of the straight-line guard
:data:`stiffknots.engine.guard.GUARD_FLOOR`):

* pairs farther apart than ``cap`` at the last full listing (:func:`close_pairs`) are safe
  while 2·max_i c_i < cap − η (c counted since that listing); when a step would break this,
  the pairs are listed afresh from the chain before the step (and a bead whose single step
  would break it stays where it was);
* a listed pair is safe while D_ab − e_a − e_b > η, D_ab its distance at its reference moment;
  when the step would break this, the pair is certified by its own distances before and after
  the step, D(0) + D(1) − L > 2η, and its reference moves to the end of the step; failing that,
  its beads that move stay where they were, their velocities reversed (a reflection: the
  dynamics is a search, not a sampler). A bead that stays changes the step of its other pairs,
  so the listed pairs are checked again until no bead stops; the last pass certifies the step
  as taken. A pair whose four beads all stay keeps its distance, which was > η.

Then no two segments that share no bead meet at any time. Two segments that share a bead
could overlap only by folding back, which puts the far end of one on the other, and so
brings the next segment (which shares no bead with it, N ≥ 4) to distance 0: excluded too.
The polygon stays embedded along the whole motion — an isotopy — and its knot type cannot
change. The test suite shows a step that the guard refuses passing a strand when the guard is
off, and a hot chain that loses its knot without the guard and keeps it with it.

Kernels see arrays and numbers only; the public wrapper validates
(:func:`stiffknots.engine.langevin.run_langevin`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from stiffknots.engine.guard import GUARD_FLOOR
from stiffknots.engine.prims import _next
from stiffknots.geometry import seg_dist2


@njit(cache=True)
def close_pairs(pos, cap, pa, pb, pd):
    """The pairs of segments (a, a+1), (b, b+1) that share no bead closer than ``cap``
    (closed ring): their first beads in ``pa``, ``pb``, distances in ``pd``; returns how many
    (more than ``pa``'s length: the list overflowed and holds the first ones)."""
    n = pos.shape[0]
    k = 0
    for a in range(n):
        a1 = a + 1 if a < n - 1 else 0
        hx = pos[a1, 0] - pos[a, 0]
        hy = pos[a1, 1] - pos[a, 1]
        hz = pos[a1, 2] - pos[a, 2]
        ha = 0.5 * math.sqrt(hx * hx + hy * hy + hz * hz)
        for b in range(a + 2, n):
            if a == 0 and b == n - 1:
                continue
            b1 = b + 1 if b < n - 1 else 0
            gx = pos[b1, 0] - pos[b, 0]
            gy = pos[b1, 1] - pos[b, 1]
            gz = pos[b1, 2] - pos[b, 2]
            hb = 0.5 * math.sqrt(gx * gx + gy * gy + gz * gz)
            mx = 0.5 * (pos[a, 0] + pos[a1, 0] - pos[b, 0] - pos[b1, 0])
            my = 0.5 * (pos[a, 1] + pos[a1, 1] - pos[b, 1] - pos[b1, 1])
            mz = 0.5 * (pos[a, 2] + pos[a1, 2] - pos[b, 2] - pos[b1, 2])
            if math.sqrt(mx * mx + my * my + mz * mz) - ha - hb >= cap:
                continue  # the distance is ≥ that bound ≥ cap
            v = _seg_dist(pos, a, a1, b, b1)
            if v < cap:
                if k < pa.shape[0]:
                    pa[k] = a
                    pb[k] = b
                    pd[k] = v
                k += 1
    return k


@njit(cache=True, inline="always")
def _seg_dist(pos, a, a1, b, b1):
    return math.sqrt(seg_dist2(pos[a, 0], pos[a, 1], pos[a, 2], pos[a1, 0], pos[a1, 1],
                               pos[a1, 2], pos[b, 0], pos[b, 1], pos[b, 2], pos[b1, 0],
                               pos[b1, 1], pos[b1, 2]))


@njit(cache=True)
def guard_distance(pos, cap):
    """The smallest distance between two segments that share no bead (closed ring), exact
    below ``cap``, else ``cap``."""
    n = pos.shape[0]
    pa = np.empty(64 * n, np.int64)
    pb = np.empty(64 * n, np.int64)
    pd = np.empty(64 * n)
    k = min(close_pairs(pos, cap, pa, pb, pd), pa.shape[0])
    best = cap
    for i in range(k):
        if pd[i] < best:
            best = pd[i]
    return best


@njit(cache=True)
def _build_pairs(pos, reach2, pi, pj):
    """Verlet list: bead pairs at cyclic index distance ≥ 2 closer than √reach2."""
    n = pos.shape[0]
    k = 0
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            dx = pos[i, 0] - pos[j, 0]
            dy = pos[i, 1] - pos[j, 1]
            dz = pos[i, 2] - pos[j, 2]
            if dx * dx + dy * dy + dz * dz < reach2:
                if k < pi.shape[0]:
                    pi[k] = i
                    pj[k] = j
                k += 1
    return k  # > pi.shape[0]: the list overflowed (the caller stops)


@njit(cache=True)
def forces(pos, k_bond, sigma, rc2, pi, pj, npairs, f, gb, ub, il):
    """Forces ``f`` = −∇U at ``pos`` (closed ring) over the listed pairs; returns U.

    Scratch (N, 3) ``gb`` (∂U/∂b_n, b_n = r_{n+1} − r_n), ``ub`` (unit bonds û_n) and (N,)
    ``il`` (``1/|b_n|``): one square root and one division per bond.
    """
    n = pos.shape[0]
    u = 0.0
    # bonds: stretching K_b(|b| − 1)², ∂/∂b = 2K_b(|b| − 1) û
    for i in range(n):
        i1 = i + 1 if i < n - 1 else 0
        bx = pos[i1, 0] - pos[i, 0]
        by = pos[i1, 1] - pos[i, 1]
        bz = pos[i1, 2] - pos[i, 2]
        ln = math.sqrt(bx * bx + by * by + bz * bz)
        inv = 1.0 / ln
        il[i] = inv
        ub[i, 0] = bx * inv
        ub[i, 1] = by * inv
        ub[i, 2] = bz * inv
        u += k_bond * (ln - 1.0) ** 2
        g = 2.0 * k_bond * (ln - 1.0)
        gb[i, 0] = g * ub[i, 0]
        gb[i, 1] = g * ub[i, 1]
        gb[i, 2] = g * ub[i, 2]
    # bending: joint at bead i between bonds a = i − 1 and i: 1 − ûa·ûi (§VII, E_d);
    # ∂(−ûa·ûi)/∂b_a = −(ûi − c ûa)/|b_a|, and likewise for b_i
    for i in range(n):
        a = i - 1 if i > 0 else n - 1
        c = ub[a, 0] * ub[i, 0] + ub[a, 1] * ub[i, 1] + ub[a, 2] * ub[i, 2]
        u += 1.0 - c
        for q in range(3):
            gb[a, q] -= (ub[i, q] - c * ub[a, q]) * il[a]
            gb[i, q] -= (ub[a, q] - c * ub[i, q]) * il[i]
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        # r_i enters b_{i−1} = r_i − r_{i−1} (+) and b_i = r_{i+1} − r_i (−)
        f[i, 0] = gb[i, 0] - gb[im, 0]
        f[i, 1] = gb[i, 1] - gb[im, 1]
        f[i, 2] = gb[i, 2] - gb[im, 2]
    s2 = sigma * sigma
    for k in range(npairs):
        i = pi[k]
        j = pj[k]
        dx = pos[i, 0] - pos[j, 0]
        dy = pos[i, 1] - pos[j, 1]
        dz = pos[i, 2] - pos[j, 2]
        r2 = dx * dx + dy * dy + dz * dz
        if r2 >= rc2:
            continue
        q = s2 / r2
        q3 = q * q * q
        u += 4.0 * (q3 * q3 - q3) + 1.0
        # −dφ/dr / r = 24(2q⁶ − q³)/r²
        w = 24.0 * (2.0 * q3 * q3 - q3) / r2
        f[i, 0] += w * dx
        f[i, 1] += w * dy
        f[i, 2] += w * dz
        f[j, 0] -= w * dx
        f[j, 1] -= w * dy
        f[j, 2] -= w * dz
    return u


@njit(cache=True, inline="always")
def _pair_slack(k, n, pa, pb, pd, poff, cum, m):
    """Listed pair k's running bound after this step, D_ab − e_a − e_b (module docstring),
    and its beads a, a+1, b, b+1."""
    a = pa[k]
    a1 = a + 1 if a < n - 1 else 0
    b = pb[k]
    b1 = b + 1 if b < n - 1 else 0
    ea = max(cum[a] + m[a] - poff[k, 0], cum[a1] + m[a1] - poff[k, 1])
    eb = max(cum[b] + m[b] - poff[k, 2], cum[b1] + m[b1] - poff[k, 3])
    return pd[k] - ea - eb, a, a1, b, b1


@njit(cache=True, inline="always")
def _freeze(i, pos, old, vel, m):
    """Bead i stays where it was this step, its velocity reversed."""
    for q in range(3):
        pos[i, q] = old[i, q]
        vel[i, q] = -vel[i, q]
    m[i] = 0.0


@njit(cache=True)
def run_dynamics(pos, vel, steps, dt, gamma, t_start, t_end, k_bond, contact, skin, cap,
                 rng, out_stats, guard=True):
    """BAOAB Langevin dynamics with the passage guard (module docstring), in place.

    ``pos``, ``vel`` (N, 3) are updated; T(k) = t_start·(t_end/t_start)^(k/steps).
    ``out_stats`` receives [U, frozen bead-steps, full guard checks, list rebuilds, lowest
    certified strand distance]; a list that would overflow (64·N bead pairs, 32·N segment
    pairs) stops the run with out_stats[3] = −1. ``guard=False`` switches the passage guard
    off: for the tests that show it is needed.
    """
    n = pos.shape[0]
    s0, s1, s2, s3 = rng[0], rng[1], rng[2], rng[3]
    sigma = contact / 2.0 ** (1.0 / 6.0)
    rc2 = contact * contact
    reach = contact + skin
    cap_pairs = 64 * n
    pi = np.empty(cap_pairs, np.int64)
    pj = np.empty(cap_pairs, np.int64)
    cap_close = 32 * n
    pa = np.empty(cap_close, np.int64)
    pb = np.empty(cap_close, np.int64)
    pd = np.empty(cap_close)
    poff = np.zeros((cap_close, 4))
    cum = np.zeros(n)
    m = np.empty(n)
    f = np.empty((n, 3))
    gb = np.empty((n, 3))
    ub = np.empty((n, 3))
    il = np.empty(n)
    old = np.empty((n, 3))
    ref = pos.copy()  # positions at the last list build
    npairs = _build_pairs(pos, reach * reach, pi, pj)
    builds = 1
    nclose = close_pairs(pos, cap, pa, pb, pd)
    checks = 1
    if npairs > cap_pairs or nclose > cap_close:
        out_stats[3] = -1.0
        return
    lowest = cap
    for k in range(nclose):
        if pd[k] < lowest:
            lowest = pd[k]
    u = forces(pos, k_bond, sigma, rc2, pi, pj, npairs, f, gb, ub, il)
    frozen = 0
    c1 = math.exp(-gamma * dt)
    c2 = math.sqrt(1.0 - c1 * c1)
    h = 0.5 * dt
    decay = math.log(t_end / t_start) / max(steps, 1)
    eta = GUARD_FLOOR
    for step in range(steps):
        temp = t_start * math.exp(decay * step)
        noise = c2 * math.sqrt(12.0 * temp)  # uniform ξ − ½ has variance 1/12
        reach_max = 0.0
        for i in range(n):
            for q in range(3):
                old[i, q] = pos[i, q]
                v = vel[i, q] + h * f[i, q]
                x = pos[i, q] + h * v
                xi, s0, s1, s2, s3 = _next(s0, s1, s2, s3)
                v = c1 * v + noise * (xi - 0.5)
                x += h * v
                vel[i, q] = v
                pos[i, q] = x
            dx = pos[i, 0] - old[i, 0]
            dy = pos[i, 1] - old[i, 1]
            dz = pos[i, 2] - old[i, 2]
            m[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
            if cum[i] + m[i] > reach_max:
                reach_max = cum[i] + m[i]
        if guard:
            if 2.0 * reach_max >= cap - eta:
                # the far pairs' certificate would lapse: list the close pairs afresh, from
                # the chain before this step
                nclose = close_pairs(old, cap, pa, pb, pd)
                checks += 1
                if nclose > cap_close:
                    out_stats[3] = -1.0
                    return
                for i in range(n):
                    cum[i] = 0.0
                    if 2.0 * m[i] >= cap - eta:
                        _freeze(i, pos, old, vel, m)
                        frozen += 1
                for k in range(nclose):
                    poff[k, 0] = 0.0
                    poff[k, 1] = 0.0
                    poff[k, 2] = 0.0
                    poff[k, 3] = 0.0
                    if pd[k] < lowest:
                        lowest = pd[k]
            # the close pairs: a pair whose running bound lapses is certified for this step
            # by its distances before and after it, (D₀ + D₁ − L)/2 > η, or its moving beads
            # stay; a pass that stops beads is followed by another (they change D₁ and L of
            # their other pairs), and the last pass sees the step as it will be taken
            changed = True
            while changed:
                changed = False
                for k in range(nclose):
                    slack, a, a1, b, b1 = _pair_slack(k, n, pa, pb, pd, poff, cum, m)
                    if slack > eta:
                        continue
                    lip = max(m[a], m[a1]) + max(m[b], m[b1])
                    if (_seg_dist(old, a, a1, b, b1) + _seg_dist(pos, a, a1, b, b1) - lip
                            > 2.0 * eta):
                        continue
                    for i in (a, a1, b, b1):
                        if m[i] > 0.0:
                            _freeze(i, pos, old, vel, m)
                            frozen += 1
                            changed = True
            # the pairs certified by their own distances start a new bound after the step
            for k in range(nclose):
                slack, a, a1, b, b1 = _pair_slack(k, n, pa, pb, pd, poff, cum, m)
                if slack > eta:
                    continue
                d0 = _seg_dist(old, a, a1, b, b1)
                pd[k] = _seg_dist(pos, a, a1, b, b1)
                poff[k, 0] = cum[a] + m[a]
                poff[k, 1] = cum[a1] + m[a1]
                poff[k, 2] = cum[b] + m[b]
                poff[k, 3] = cum[b1] + m[b1]
                low = 0.5 * (d0 + pd[k] - max(m[a], m[a1]) - max(m[b], m[b1]))
                if low < lowest:
                    lowest = low
        for i in range(n):
            cum[i] += m[i]
        # Verlet list: rebuild when a bead may have entered the reach
        dmax2 = 0.0
        for i in range(n):
            dx = pos[i, 0] - ref[i, 0]
            dy = pos[i, 1] - ref[i, 1]
            dz = pos[i, 2] - ref[i, 2]
            m2 = dx * dx + dy * dy + dz * dz
            if m2 > dmax2:
                dmax2 = m2
        if 2.0 * math.sqrt(dmax2) >= skin:
            npairs = _build_pairs(pos, reach * reach, pi, pj)
            builds += 1
            if npairs > cap_pairs:
                out_stats[3] = -1.0
                return
            for i in range(n):
                for q in range(3):
                    ref[i, q] = pos[i, q]
        u = forces(pos, k_bond, sigma, rc2, pi, pj, npairs, f, gb, ub, il)
        for i in range(n):
            for q in range(3):
                vel[i, q] += h * f[i, q]
    rng[0], rng[1], rng[2], rng[3] = s0, s1, s2, s3
    out_stats[0] = u
    out_stats[1] = frozen
    out_stats[2] = checks
    out_stats[3] = builds
    out_stats[4] = lowest
