"""Polygons that meet themselves, and polygons of extreme scale.

A polygon two of whose edges meet (a knot diagram flattened into its plane, a bow-tie) is
*singular*: it has no knot type, and a knot invariant computed from it names whatever its
projection happens to resolve to (the trefoil flattened to z = 0 read as ``0_1``). Every
command that names or resamples a curve refuses one first (:func:`meeting_edges`).

The search is ``O(N log N)`` for a well-sampled polygon, so that a file of 10⁶ vertices is
checked in seconds: every edge is cut into pieces no longer than ``p`` (about twice the median
edge), and two edges within ``tol`` of each other own two pieces whose midpoints lie within
``h = p + tol`` of each other — in the same or neighbouring cells of a grid of cells of side
``h``, whose pairs are measured exactly.

A knot type is scale invariant, but arithmetic is not: coordinates of order 1e300 overflow
in a crossing test (the trefoil scaled by 1e300 read as ``0_1``).
:func:`~stiffknots.geometry.rescaled` brings a polygon of extreme scale to order 1 by a power
of two (exact: no vertex moves relative to the others).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from stiffknots.errors import UserInputError
from stiffknots.geometry import rescaled, seg_dist2

__all__ = ["meeting_edges", "refuse_singular", "rescaled", "RELATIVE_TOL",
           "SingularCurveError"]

#: two edges closer than this times the polygon's extent meet (double precision resolves the
#: crossing of two strands to about 1e-16 of the extent; a polygon whose strands come that
#: close has no knot type that arithmetic can decide)
RELATIVE_TOL = 1e-12

#: below this many edges every pair is measured
_BRUTE_FORCE_BELOW = 600


class SingularCurveError(UserInputError):
    """A curve that meets itself: it has no knot type (:func:`refuse_singular`)."""


def refuse_singular(coords, closed: bool = True, source=None) -> None:
    """Raise :class:`SingularCurveError` if the polygon meets itself (:func:`meeting_edges`);
    ``source``: the file it came from, named in the message."""
    hit = meeting_edges(coords, closed)
    if hit is not None:
        where = f"{source}: " if source else ""
        raise SingularCurveError(
            f"{where}the curve meets itself (its edges {hit[0]} and {hit[1]}, counted from 0, "
            "cross or touch): a singular curve has no knot type; move its strands apart")


@njit(cache=True)
def _before(c, k, x, y, z):
    """Is the sorted cell ``c[k]`` lexicographically before (x, y, z)?"""
    if c[k, 0] != x:
        return c[k, 0] < x
    if c[k, 1] != y:
        return c[k, 1] < y
    return c[k, 2] < z


@njit(cache=True)
def _first_not_before(c, x, y, z):
    lo, hi = 0, c.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if _before(c, mid, x, y, z):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _grid_search(a, b, own, cells, order, tol2, closed, m):
    """The first two pieces (indices into ``a``/``b``) of edges that share no vertex within
    ``√tol2`` of each other, found among the pieces of neighbouring grid cells (``cells``:
    each piece's cell, sorted by ``order``); (-1, -1) when none."""
    c = cells[order]
    for s in range(c.shape[0]):
        i = order[s]
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                # the cells (x+dx, y+dy, z-1 … z+1) are one run of the sorted list
                x, y, z = c[s, 0] + dx, c[s, 1] + dy, c[s, 2]
                k = _first_not_before(c, x, y, z - 1)
                while k < c.shape[0] and not (c[k, 0] != x or c[k, 1] != y
                                              or c[k, 2] > z + 1):
                    j = order[k]
                    k += 1
                    if j <= i:
                        continue  # each pair once
                    d = abs(own[i] - own[j])
                    if d <= 1 or (closed and d == m - 1):
                        continue  # the same edge, or neighbours (they share a vertex)
                    d2 = seg_dist2(a[i, 0], a[i, 1], a[i, 2], b[i, 0], b[i, 1], b[i, 2],
                                   a[j, 0], a[j, 1], a[j, 2], b[j, 0], b[j, 1], b[j, 2])
                    if d2 <= tol2:
                        return i, j
    return -1, -1


@njit(cache=True)
def _brute_force(x, closed, tol2):
    n = x.shape[0]
    m = n if closed else n - 1
    for i in range(m):
        i2 = (i + 1) % n
        for j in range(i + 2, m):
            if closed and i == 0 and j == m - 1:
                continue
            j2 = (j + 1) % n
            d2 = seg_dist2(x[i, 0], x[i, 1], x[i, 2], x[i2, 0], x[i2, 1], x[i2, 2],
                           x[j, 0], x[j, 1], x[j, 2], x[j2, 0], x[j2, 1], x[j2, 2])
            if d2 <= tol2:
                return i, j
    return -1, -1


def meeting_edges(coords, closed: bool = True, tol: float | None = None
                  ) -> tuple[int, int] | None:
    """Two edges of the polygon that share no vertex and meet (come within ``tol``), or None.

    Parameters
    ----------
    coords : array (N, 3)
        The vertices; edge k joins vertex k to k + 1 (and, closed, the last to the first).
    closed : bool
    tol : float, optional
        Default :data:`RELATIVE_TOL` times the polygon's extent (its largest coordinate
        range).

    Returns
    -------
    (i, j) or None
        The edges' indices (i < j).
    """
    x = np.ascontiguousarray(coords, dtype=np.float64)
    if tol is not None:
        tol = tol * float(np.max(np.abs(rescaled(x)))) / float(np.max(np.abs(x)) or 1.0)
    x = rescaled(x)
    n = len(x)
    m = n if closed else n - 1
    if m < 3:
        return None
    if tol is None:
        tol = RELATIVE_TOL * float(np.max(np.ptp(x, axis=0)))
    tol2 = float(tol) ** 2
    if m < _BRUTE_FORCE_BELOW:
        i, j = _brute_force(x, closed, tol2)
        return None if i < 0 else (int(i), int(j))
    a = x[:m]
    b = np.roll(x, -1, axis=0)[:m] if closed else x[1:]
    ell = np.linalg.norm(b - a, axis=1)
    total = float(ell.sum())
    # pieces of length ≤ p; p ≥ total/(4m) keeps them fewer than 5m (a few long edges among
    # many short ones)
    p = max(2.0 * float(np.median(ell)), total / (4 * m), 1e-300)
    cuts = np.maximum(np.ceil(ell / p).astype(np.int64), 1)
    own = np.repeat(np.arange(m), cuts)
    first = np.cumsum(cuts) - cuts
    t0 = (np.arange(len(own)) - first[own]) / cuts[own]
    t1 = t0 + 1.0 / cuts[own]
    step = (b - a)[own]
    pa = a[own] + t0[:, None] * step
    pb = a[own] + t1[:, None] * step
    h = float(np.max(np.linalg.norm(pb - pa, axis=1))) * (1 + 1e-9) + tol
    mid = (pa + pb) / 2
    cells = np.floor((mid - mid.min(axis=0)) / h).astype(np.int64)
    order = np.lexsort((cells[:, 2], cells[:, 1], cells[:, 0]))
    i, j = _grid_search(pa, pb, own, cells, order, tol2, closed, m)
    if i < 0:
        return None
    i, j = sorted((int(own[i]), int(own[j])))
    return i, j
