"""Small geometric primitives shared by the kernels and the analysis (numba-compiled).

The segment-segment distance is the basis of the tube exclusion model (paper §II: a tube of
diameter w around the centre line) and of the strand-passage guard of the Monte Carlo moves.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def rescaled(coords) -> np.ndarray:
    """``coords`` (N, 3) scaled by a power of two to a largest coordinate in [1/2, 2) when
    it lies outside [2⁻¹⁶, 2¹⁶] (a scaling is an isotopy; a power of two is exact), else as
    given."""
    x = np.asarray(coords, dtype=np.float64)
    if not x.size:
        return x
    s = float(np.max(np.abs(x)))
    if s == 0.0 or not math.isfinite(s) or 2.0 ** -16 <= s <= 2.0 ** 16:
        return x
    return np.ldexp(x, -math.frexp(s)[1])


@njit(cache=True, inline="always")
def _clamp01(x):
    if x < 0.0:
        return 0.0
    if x > 1.0:
        return 1.0
    return x


@njit(cache=True, inline="always")
def seg_params(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """Parameters (s, t) ∈ [0, 1]² of the closest points a + s(b − a) and c + t(d − c) of
    segments [a, b] and [c, d] (scalar arguments, no allocation).

    Closest points of two segments (Ericson, *Real-Time Collision Detection*, §5.1.9), robust
    for parallel and degenerate segments (a point: its parameter is 0).
    """
    d1x = bx - ax
    d1y = by - ay
    d1z = bz - az
    d2x = dx - cx
    d2y = dy - cy
    d2z = dz - cz
    rx = ax - cx
    ry = ay - cy
    rz = az - cz
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-300
    if a <= eps and e <= eps:
        return 0.0, 0.0
    if a <= eps:
        return 0.0, _clamp01(f / e)
    c = d1x * rx + d1y * ry + d1z * rz
    if e <= eps:
        return _clamp01(-c / a), 0.0
    b = d1x * d2x + d1y * d2y + d1z * d2z
    denom = a * e - b * b
    if denom > 1e-14 * a * e:
        s = _clamp01((b * f - c * e) / denom)
    else:
        s = 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = _clamp01(-c / a)
    elif t > 1.0:
        t = 1.0
        s = _clamp01((b - c) / a)
    return s, t


@njit(cache=True)
def seg_dist2(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """Squared distance between segments [a, b] and [c, d] (scalar arguments, no allocation):
    the distance of the closest points of :func:`seg_params`."""
    s, t = seg_params(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz)
    px = ax + (bx - ax) * s - (cx + (dx - cx) * t)
    py = ay + (by - ay) * s - (cy + (dy - cy) * t)
    pz = az + (bz - az) * s - (cz + (dz - cz) * t)
    return px * px + py * py + pz * pz


@njit(cache=True)
def _segment_distance(p0, p1, q0, q1):
    return np.sqrt(
        seg_dist2(p0[0], p0[1], p0[2], p1[0], p1[1], p1[2],
                  q0[0], q0[1], q0[2], q1[0], q1[1], q1[2])
    )


def segment_distance(p0, p1, q0, q1) -> float:
    """Distance between the segments [p0, p1] and [q0, q1] (3-vectors)."""
    arrs = [np.ascontiguousarray(x, dtype=np.float64).reshape(3) for x in (p0, p1, q0, q1)]
    return float(_segment_distance(*arrs))
