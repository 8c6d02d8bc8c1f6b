"""Synthetic chains with known shape, for testing and illustrating the classifier (§VII).

All return closed chains as ``(N, 3)`` float arrays with bonds of length 1 (to ~1e-3: beads are
equally spaced in arc length on a smooth curve which is then scaled to unit mean bond).

* :func:`torus_braid` — a circular braid of index ``i``: the torus knot ``T(i, i+1)`` on a thin
  torus, i.e. an ``i``-times covered circle whose covers twist around each other (a line-braid
  of multiplicity ``i``, §V B / §VI C).
* :func:`eight_plus_circle` — the "80": the elastica figure eight (Appendix D) followed by a
  circle of the theoretical length fraction ``(2π²/ε_80)^{1/2}`` (eq. (28)), running
  along one lobe (as in the Monte Carlo 80s) or touching it from outside (as in
  :func:`stiffknots.theory.elastica.eighty_curve`).
* :func:`four_cage` — a 4-fold cage built from the paper's description (Fig. 6): four arcs
  on a sphere, each running from one pole to the other while turning 90° in azimuth, the
  strands passing tangentially side by side through the two poles (two point-braids, the
  north one along ``x``, the south one along ``y``). Only the geometry is modelled; the knot
  type of this curve is not imposed.
* :func:`random_compact_chain` — a random closed polygon (no shape).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "resample_closed",
    "torus_braid",
    "eight_plus_circle",
    "four_cage",
    "random_compact_chain",
]


def _check_n(n: int, low: int = 8) -> int:
    if isinstance(n, bool) or int(n) != n or int(n) < low:
        raise ValueError(f"n must be an integer >= {low}, got {n!r}")
    return int(n)


def resample_closed(points: np.ndarray, n: int) -> np.ndarray:
    """Resample a densely sampled closed curve at ``n`` points equally spaced in arc length and
    scale it so that the mean bond is 1.

    Parameters
    ----------
    points : (M, 2) or (M, 3) array
        The curve, without repeating the first point at the end (a repeated end point is
        dropped).
    n : int
        Number of beads.
    """
    n = _check_n(n, 4)
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or p.shape[0] < 4:
        raise ValueError(f"points must have shape (M, 2) or (M, 3) with M >= 4, got {p.shape}")
    if p.shape[1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    if np.allclose(p[0], p[-1]):
        p = p[:-1]
    closed = np.vstack([p, p[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    target = np.linspace(0.0, s[-1], n, endpoint=False)
    out = np.column_stack([np.interp(target, s, closed[:, k]) for k in range(3)])
    bonds = np.linalg.norm(np.roll(out, -1, axis=0) - out, axis=1)
    return out / bonds.mean()


def torus_braid(i: int, n: int = 150, separation: float = 1.0, dense: int = 20) -> np.ndarray:
    """Circular braid of index ``i``: the torus knot ``T(i, i+1)`` on a thin torus.

    The core circle has radius ``≈ n/(2πi)`` (an ``i``-covered circle of length ``n``); the
    tube radius ``a`` puts neighbouring covers ``separation`` apart,
    ``2a sin(π/i) = separation`` (default 1: between the exclusion distance ``1/√2`` and the
    widest bead tube ``√2`` of §VII). ``i = 1`` gives a circle with a small wiggle.

    Parameters
    ----------
    i : int
        Braid index (number of covers), ``>= 1``.
    n : int
        Number of beads.
    separation : float
        Distance between neighbouring covers (bond units).
    dense : int
        Oversampling factor of the smooth curve before resampling.
    """
    if isinstance(i, bool) or int(i) != i or int(i) < 1:
        raise ValueError(f"i must be an integer >= 1, got {i!r}")
    i = int(i)
    n = _check_n(n, 4 * i + 4)
    a = separation / (2.0 * math.sin(math.pi / i)) if i >= 2 else 0.5 * separation
    big_r = n / (2.0 * math.pi * i)
    t = np.linspace(0.0, 2.0 * math.pi, dense * n, endpoint=False)
    phi, th = i * t, (i + 1) * t
    pts = np.column_stack([(big_r + a * np.cos(th)) * np.cos(phi),
                           (big_r + a * np.cos(th)) * np.sin(phi), a * np.sin(th)])
    return resample_closed(pts, n)


def eight_plus_circle(n: int = 150, *, inside: bool = True, lift: float = 1.5,
                      dense: int = 20) -> np.ndarray:
    """The "80": the elastica figure eight followed by a circle (§VII, Appendix D).

    The figure eight is the exact elastica of :func:`stiffknots.theory.elastica.eight_curve`;
    the lengths follow eq. (28), ``L_0/L = (2π²/ε_80)^{1/2} ≈ 0.372``. The path goes
    once around the 8 from the apex of its upper lobe, then once around the circle, which is
    tangent to the lobe at that apex with the same tangent (a point-braid of two strands):
    ``inside=True`` puts the circle inside the lobe, running along it (it is a little longer
    than the lobe, so it crosses it twice: the Monte Carlo 80 with one point-braid and three
    double points, Fig. 7 c); ``inside=False`` puts it outside, touching the apex
    (the planar shadow of :func:`~stiffknots.theory.elastica.eighty_curve`).

    The planar path is lifted out of its plane by ``z = (lift/2) cos(2πs/L)`` so that the two
    passes at the point-braid and at the crossings are about ``lift`` apart instead of
    intersecting.
    """
    from stiffknots.theory.elastica import eight_curve, elastica_constants

    n = _check_n(n, 16)
    c = elastica_constants()
    f8 = math.sqrt(c.eps_8 / c.eps_80)
    f0 = 1.0 - f8
    m8 = max(64, int(round(dense * n * f8)))
    m0 = max(32, int(round(dense * n * f0)))
    eight = eight_curve(m8 + 1, u_start=0.5)[:-1] * f8   # starts at the top apex, tangent +x
    apex = eight[0]
    radius = f0 / (2.0 * math.pi)
    th = np.linspace(0.0, 2.0 * math.pi, m0, endpoint=False)
    if inside:   # centre below the apex, clockwise like the upper lobe at its apex
        centre = apex - np.array([0.0, radius])
        circ = centre + radius * np.column_stack([np.sin(th), np.cos(th)])
    else:        # centre above the apex, counter-clockwise
        centre = apex + np.array([0.0, radius])
        circ = centre + radius * np.column_stack([np.sin(th), -np.cos(th)])
    pts = resample_closed(np.vstack([eight, circ]), n)
    # bead k sits at the arc length fraction k/n from the apex (equal-arc resampling)
    pts[:, 2] = 0.5 * lift * np.cos(2.0 * math.pi * np.arange(n) / n)
    return pts


def four_cage(n: int = 150, *, offset: float = 1.0, dense: int = 20) -> np.ndarray:
    """A 4-fold cage (Fig. 6): four pole-to-pole arcs on a sphere, two point-braids.

    Arc ``k`` (``k = 0..3``) runs between the poles while its azimuth turns by 90° linearly in
    the polar angle; consecutive arcs pass straight through a pole, so the chain goes through
    each pole twice, both times tangent to one axis (``x`` at the north pole, ``y`` at the
    south pole): a point-braid of two strands at each pole. The two passes through a pole are
    pushed ``offset`` apart sideways (Gaussian bump of width 0.25 rad) so they touch instead of
    intersecting. The sphere's radius makes the length ``n``.
    """
    n = _check_n(n, 16)
    m = max(64, dense * n // 4)
    theta = np.linspace(0.0, math.pi, m, endpoint=False)
    # (start azimuth, direction of the polar angle, azimuth sweep) of the four arcs
    arcs = [(0.0, +1, +0.5 * math.pi),            # N -> S, azimuth 0 -> 90
            (1.5 * math.pi, -1, +0.5 * math.pi),  # S -> N, azimuth 270 -> 360
            (math.pi, +1, +0.5 * math.pi),        # N -> S, azimuth 180 -> 270
            (0.5 * math.pi, -1, +0.5 * math.pi)]  # S -> N, azimuth 90 -> 180
    pieces = []
    for phi0, direction, sweep in arcs:
        th = theta if direction > 0 else math.pi - theta
        u = theta / math.pi
        phi = phi0 + sweep * u
        pieces.append(np.column_stack([np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi),
                                       np.cos(th)]))
    unit = np.vstack(pieces)
    # every point belongs to the pole pass nearest along the path: pass k is at the start of
    # arc k (k even: north pole, along x; k odd: south pole, along y)
    idx = np.arange(4 * m)
    k_pass = np.where(idx % m < m // 2, idx // m, (idx // m + 1) % 4)
    sign = np.where(k_pass < 2, 1.0, -1.0)   # the two passes of a pole go to opposite sides
    polar = np.arccos(np.clip(unit[:, 2], -1.0, 1.0))
    north = k_pass % 2 == 0
    bump = np.where(north, np.exp(-((polar / 0.25) ** 2)),
                    np.exp(-(((math.pi - polar) / 0.25) ** 2)))
    closed = np.vstack([unit, unit[:1]])
    radius = n / float(np.linalg.norm(np.diff(closed, axis=0), axis=1).sum())
    pts = unit * radius
    pts[:, 1] += np.where(north, 0.5 * offset * sign * bump, 0.0)   # north: push along y
    pts[:, 0] += np.where(north, 0.0, 0.5 * offset * sign * bump)   # south: push along x
    return resample_closed(pts, n)


def random_compact_chain(n: int = 150, seed: int = 0) -> np.ndarray:
    """A random closed polygon with unit bonds: ``n/2`` random unit vectors and their
    opposites, shuffled and summed (``n`` even; odd ``n`` is rounded up)."""
    n = _check_n(n, 4)
    n += n % 2
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n // 2, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    steps = np.vstack([v, -v])
    rng.shuffle(steps)
    return np.cumsum(steps, axis=0)
