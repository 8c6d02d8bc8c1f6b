"""Resampling a closed polygon into a chain of N equal bonds that keeps its knot type.

A curve brought by the user (KnotPlot, ridgerunner, ElasticKnots, an experiment) has bonds of
any length; the Monte Carlo of the paper (§VII) needs ``N`` beads joined by bonds of length 1.
:func:`resample` places ``N`` points *on the polygon* at equal chords (each point the first
one along the polygon at distance ℓ from the previous, ℓ tuned by Brent's method so that the
``N``-th step lands back on the start), joins them (the chord polygon), and scales by 1/ℓ.

Why the knot type is kept
-------------------------
The chord polygon Q is reached from the input polygon P by collapsing each arc A_k of P (the
part between two consecutive points of Q, of arclength a_k) onto its chord, one vertex at a
time: each step replaces two edges by the third side of their triangle. Such a step is an
isotopy (a Reidemeister Δ-move) whenever the triangle meets no other edge of the current
polygon. A triangle of arc k lies in the convex hull of A_k, inside the ball of radius a_k/2
about the arclength midpoint c_k of A_k (every point of A_k is within arclength a_k/2 of c_k).
Two arcs that are not neighbours have midpoints at least 2ℓ apart along the curve (each arc
is at least as long as its chord ℓ), so they are at least D(2ℓ) apart in space, where D(λ) is
the smallest distance between two points of P that are at least λ apart along P (the
distance between "non-adjacent parts" of P at scale λ). Hence, if

    a_max < D(2ℓ),

the balls of non-neighbouring arcs are disjoint and no triangle of one arc can meet another
arc or its chord: only neighbouring arcs could interfere, which requires P to fold back within
two chords. :func:`resample` computes D(2ℓ) (conservatively, from segment distances of a
refinement of P); when the condition fails it still accepts an ``N`` whose Δ-moves are all
certified one by one (below: a proof of the isotopy by itself), and otherwise refuses it,
naming the smallest ``N`` that satisfies the condition. It *certifies* the isotopy: every
Δ-move is tested exactly (no triangle pierced by any other edge), and finally the HOMFLY-PT
polynomial (chiral) of the result is compared with that of the input (``check=True``): it
must be identical.

Thickness: ``w_over_L`` gives the tube diameter of the stiff-knot model in bond units,
``w = (w/L) · N`` (L = N for unit bonds); the result records it with the chain's own
thickness (its minimal distance between non-adjacent bonds) in ``meta``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.optimize import brentq

from stiffknots.chain import Chain, as_coords
from stiffknots.errors import InvalidParameter, TopologyChangedError
from stiffknots.geometry import seg_dist2
from stiffknots.knots.singular import refuse_singular, rescaled
from stiffknots.width import Width

__all__ = ["resample", "minimal_resample_beads", "separation_distance", "ResampleError",
           "CurveError"]


#: the most beads :func:`minimal_resample_beads` tries for a curve in :func:`resample`'s errors
RESAMPLE_LIMIT = 20_000


class ResampleError(InvalidParameter):
    """``n_beads`` too small for the curve (the message names the smallest that works)."""


class CurveError(ResampleError):
    """No number of beads keeps the curve's knot type: its strands touch. The message names
    the curve, not ``n_beads`` (a command line would otherwise blame its ``--beads``); still
    a :class:`ResampleError` for the callers that skip a curve that does not resample."""

    def __init__(self, text: str):
        self.text = text
        super().__init__("n_beads", None, "a number of beads that keeps the knot type", text)

    def message(self, name: str) -> str:
        return self.text


# --------------------------------------------------------------------------------------------
# geometry of the input polygon
# --------------------------------------------------------------------------------------------


def _closed_coords(chain) -> np.ndarray:
    if isinstance(chain, Chain):
        if not chain.closed:
            raise ValueError("resample() needs a closed chain (a knot); this one is open")
        x = chain.coords
    else:
        x = as_coords(chain)
    if len(x) > 3 and np.array_equal(x[0], x[-1]):
        x = x[:-1]
    if len(x) < 3:
        raise ValueError(f"a closed polygon needs at least 3 vertices, got {len(x)}")
    zero = ~np.any(np.roll(x, -1, axis=0) - x, axis=1)  # no norm: 1e300 overflowed
    if np.any(zero):
        k = int(np.argmax(zero))
        raise ValueError(f"edge {k} of the polygon has zero length")
    return np.ascontiguousarray(x)


def _point_at(x, cum, s):
    """Points of the closed polygon at arclengths ``s`` (array), cum = cumulative lengths."""
    L = cum[-1]
    s = np.mod(s, L)
    k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(x) - 1)
    t = (s - cum[k]) / (cum[k + 1] - cum[k])
    a = x[k]
    b = x[(k + 1) % len(x)]
    return a + t[:, None] * (b - a)


@njit(cache=True)
def _march(x, cum, ell, n):
    """Arclengths of n+1 points: s_0 = 0, each next the first point along the polygon at
    distance ell from the previous. Returns s (n+1); s[n] = inf if a step runs > 2 turns."""
    m = x.shape[0]
    L = cum[m]
    s = np.empty(n + 1)
    s[0] = 0.0
    k = 0  # current edge (unrolled index: edge k % m)
    t0 = 0.0
    cx, cy, cz = x[0, 0], x[0, 1], x[0, 2]
    for step in range(n):
        found = False
        while k < 3 * m:
            e = k % m
            ax, ay, az = x[e, 0], x[e, 1], x[e, 2]
            f = (e + 1) % m
            dx, dy, dz = x[f, 0] - ax, x[f, 1] - ay, x[f, 2] - az
            rx, ry, rz = ax - cx, ay - cy, az - cz
            A = dx * dx + dy * dy + dz * dz
            B = 2.0 * (dx * rx + dy * ry + dz * rz)
            C = rx * rx + ry * ry + rz * rz - ell * ell
            disc = B * B - 4.0 * A * C
            if disc >= 0.0:
                t = (-B + math.sqrt(disc)) / (2.0 * A)  # the larger root: leaving the sphere
                if t > t0 and t <= 1.0:
                    t0 = t
                    cx, cy, cz = ax + t * dx, ay + t * dy, az + t * dz
                    s[step + 1] = (k // m) * L + cum[e] + t * (cum[e + 1] - cum[e])
                    found = True
                    break
            k += 1
            t0 = 0.0
        if not found:
            s[n] = np.inf
            return s
    return s


def _equal_chords(x: np.ndarray, n: int):
    """(points (n, 3), chord ell, arclengths s (n+1)) of the equal-chord polygon on x."""
    seg = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    L = cum[-1]

    def g(ell):
        return _march(x, cum, ell, n)[n] - L

    hi = L / n
    if g(hi) < 0:  # pragma: no cover - chords are never longer than their arcs
        hi *= 1.5
    lo = hi
    for _ in range(200):
        lo *= 0.95
        if g(lo) < 0:
            break
    else:
        raise ValueError("could not bracket the equal chord (degenerate polygon?)")
    ell = brentq(g, lo, hi, xtol=1e-15 * L, rtol=1e-15, maxiter=400)
    s = _march(x, cum, ell, n)
    pts = _point_at(x, cum, s[:n])
    return pts, ell, s, cum


# --------------------------------------------------------------------------------------------
# the metric condition
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _min_distance_at_separation(y, cum, lam):
    """min distance between segments of the closed polygon y whose arclength gap >= lam."""
    m = y.shape[0]
    L = cum[m]
    best = np.inf
    for i in range(m):
        i1 = (i + 1) % m
        for j in range(i + 1, m):
            # arclength gap between segment i [cum[i], cum[i+1]] and j [cum[j], cum[j+1]]
            g1 = cum[j] - cum[i + 1]
            g2 = L - cum[j + 1] + cum[i]
            gap = min(g1, g2)
            if gap < lam:
                continue
            j1 = (j + 1) % m
            d2 = seg_dist2(y[i, 0], y[i, 1], y[i, 2], y[i1, 0], y[i1, 1], y[i1, 2],
                           y[j, 0], y[j, 1], y[j, 2], y[j1, 0], y[j1, 1], y[j1, 2])
            if d2 < best:
                best = d2
    return math.sqrt(best)


def _refine(x: np.ndarray, h: float) -> np.ndarray:
    out = []
    nxt = np.roll(x, -1, axis=0)
    for a, b in zip(x, nxt, strict=True):
        k = max(1, math.ceil(np.linalg.norm(b - a) / h))
        t = np.arange(k)[:, None] / k
        out.append(a + t * (b - a))
    return np.vstack(out)


def separation_distance(coords, lam: float) -> float:
    """D(λ): a lower bound on the smallest distance between two points of the closed polygon
    that are at least ``lam`` apart along it (segments of a refinement into pieces of length
    <= λ/8 whose arclength gap is at least λ - λ/4 are compared: slightly more pairs than the
    definition, so the value never exceeds the true one)."""
    x = _closed_coords(coords)
    h = lam / 8.0
    y = _refine(x, h)
    seg = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    return float(_min_distance_at_separation(y, cum, lam - 2 * h))


def _condition(x: np.ndarray, n: int):
    pts, ell, s, cum = _equal_chords(x, n)
    a_max = float(np.max(np.diff(s)))
    D = separation_distance(x, 2 * ell)
    return a_max < D, a_max, D, (pts, ell, s, cum)


def minimal_resample_beads(coords, start: int = 6, limit: int = 20000) -> int:
    """The smallest number of beads for which the condition a_max < D(2ℓ) holds (found by
    doubling then bisection; the condition is monotone in practice, not in theory)."""
    x = _closed_coords(coords)
    n = max(3, int(start))
    while not _condition(x, n)[0]:
        if n >= limit:
            raise ValueError(f"no number of beads up to {limit} satisfies the condition")
        n = min(limit, 2 * n)
    lo = max(3, n // 2)
    if lo == n or _condition(x, lo)[0]:
        return lo if lo < n and _condition(x, lo)[0] else n
    while n - lo > 1:
        mid = (lo + n) // 2
        if _condition(x, mid)[0]:
            n = mid
        else:
            lo = mid
    return n


# --------------------------------------------------------------------------------------------
# the certificate: Δ-moves
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _pierced(t0, t1, t2, poly, skip_a, skip_b, tol):
    """Does the triangle (t0, t1, t2) meet an edge of the closed polygon ``poly`` other than
    edges skip_a, skip_b (its two sides)? Edges sharing a vertex with the triangle are tested
    without that vertex's end."""
    m = poly.shape[0]
    e1 = t1 - t0
    e2 = t2 - t0
    nrm = np.cross(e1, e2)
    area2 = math.sqrt(nrm[0] ** 2 + nrm[1] ** 2 + nrm[2] ** 2)
    if area2 == 0.0:
        return False  # a degenerate (flat) triangle: the move changes nothing
    for k in range(m):
        if k == skip_a or k == skip_b:
            continue
        p = poly[k].copy()
        q = poly[(k + 1) % m].copy()
        # pull an end that coincides with a triangle vertex slightly inwards
        for v in (t0, t1, t2):
            if np.all(p == v):
                p = p + 1e-9 * (q - p)
            if np.all(q == v):
                q = q + 1e-9 * (p - q)
        d = q - p
        h = np.cross(d, e2)
        a = np.dot(e1, h)
        if abs(a) <= tol * area2 * math.sqrt(np.dot(d, d)):
            # segment parallel to the plane (or of zero length, a = 0: a repeated point of
            # the polygon, once a ZeroDivisionError): conservative when it lies in it
            dist = abs(np.dot(p - t0, nrm)) / area2
            if dist < tol:
                lo = np.minimum(np.minimum(t0, t1), t2)
                hi = np.maximum(np.maximum(t0, t1), t2)
                if np.all(np.minimum(p, q) <= hi) and np.all(np.maximum(p, q) >= lo):
                    return True
            continue
        f = 1.0 / a
        sv = p - t0
        u = f * np.dot(sv, h)
        if u < -tol or u > 1.0 + tol:
            continue
        qv = np.cross(sv, e1)
        v = f * np.dot(d, qv)
        if v < -tol or u + v > 1.0 + tol:
            continue
        t = f * np.dot(e2, qv)
        if -tol <= t <= 1.0 + tol:
            return True
    return False


def _certify(x: np.ndarray, cum: np.ndarray, s: np.ndarray, n: int) -> bool:
    """Collapse every arc of x onto its chord by Δ-moves, each tested exactly."""
    m = len(x)
    L = cum[-1]
    sq = np.mod(s[:n], L)
    pq = _point_at(x, cum, sq)
    items = [(float(cum[e]), 1, x[e]) for e in range(m)]  # original vertices
    items += [(float(sq[k]), 0, pq[k]) for k in range(n)]  # resampled points first on ties
    items.sort(key=lambda t: (t[0], t[1]))
    poly: list[np.ndarray] = []
    flag: list[bool] = []  # True: a resampled point
    last_s = None
    for sv, kind, p in items:
        if last_s is not None and sv == last_s and kind == 1 and flag and flag[-1]:
            continue  # an original vertex where a resampled point already sits
        poly.append(np.asarray(p, dtype=np.float64))
        flag.append(kind == 0)
        last_s = sv
    tol = 1e-12
    while True:
        mm = len(poly)
        idx = next((j for j in range(mm) if not flag[j] and flag[j - 1]), None)
        if idx is None:
            return True
        a = (idx - 1) % mm
        b = (idx + 1) % mm
        cur = np.array(poly)
        if _pierced(cur[a], cur[idx], cur[b], cur, a, idx, tol):
            return False
        del poly[idx]
        del flag[idx]


# --------------------------------------------------------------------------------------------
# public
# --------------------------------------------------------------------------------------------


def _unit_bonds(y: np.ndarray, max_it: int = 8) -> np.ndarray:
    """Nearly unit bonds of a closed chain made unit to rounding: Gauss–Newton steps of least
    norm on c_k = |r_{k+1} − r_k|² − 1 (J Jᵀ is cyclic tridiagonal, solved sparse)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    y = y.copy()
    n = len(y)
    k = np.arange(n)
    for _ in range(max_it):
        b = np.roll(y, -1, axis=0) - y
        c = np.einsum("ij,ij->i", b, b) - 1.0
        if np.max(np.abs(c)) < 1e-15:
            break
        # row k: ∂c_k/∂r_{k+1} = 2b_k, ∂c_k/∂r_k = −2b_k
        rows = np.repeat(k, 6)
        cols = np.concatenate([3 * ((k + 1) % n)[:, None] + np.arange(3),
                               3 * k[:, None] + np.arange(3)], axis=1).ravel()
        vals = np.concatenate([2 * b, -2 * b], axis=1).ravel()
        jac = sp.csr_matrix((vals, (rows, cols)), shape=(n, 3 * n))
        lam = spsolve((jac @ jac.T).tocsc(), -c)
        y = y + (jac.T @ lam).reshape(n, 3)
    return y


def resample(chain, n_beads: int, *, w_over_L: float | None = None, check: bool = True,
             certify: bool = True) -> Chain:
    """A closed chain of exactly ``n_beads`` unit bonds with the knot type of ``chain``.

    Parameters
    ----------
    chain : Chain (closed) or array (N, 3)
        The input polygon, any bond lengths (the closing edge joins the last vertex to the
        first; a repeated first vertex is dropped).
    n_beads : int
        Number of beads of the result (>= 3).
    w_over_L : float, optional
        Tube diameter over contour length, in (0, 1/8] and below 1/N; recorded as
        ``meta["w"] = w_over_L * n_beads`` (bond units) with ``meta["tube_fits"]`` (the
        chain's own thickness >= w).
    check : bool
        Compare the HOMFLY-PT polynomials (chiral) of input and output (must be identical).
    certify : bool
        Test every Δ-move of the isotopy from the input to the output (module docstring).

    Returns
    -------
    Chain
        Bonds all 1 to 1e-12. ``meta``: ``resampled_from`` (input vertices), ``chord`` (ℓ in
        input units), ``scale`` (1/ℓ), ``a_max``, ``D_2l`` (the condition's two sides, input
        units), ``thickness``, and the ``w`` entries.

    Raises
    ------
    ResampleError
        If ``n_beads`` violates a_max < D(2ℓ) (the message gives the smallest that works), or
        the isotopy cannot be certified at this ``n_beads``.
    TopologyChangedError
        If the polynomials differ (never expected: a bug).
    """
    if isinstance(n_beads, bool) or int(n_beads) != n_beads or n_beads < 3:
        raise InvalidParameter("n_beads", n_beads, "an integer >= 3")
    n = int(n_beads)
    # the tube's rule everywhere (:class:`~stiffknots.width.Width`): w/L in (0, 1/8], w < 1
    width = None if w_over_L is None else Width.tube(n, w_over_L=w_over_L)
    x = _closed_coords(chain)
    source = chain.meta.get("source") if isinstance(chain, Chain) else None
    where = f"{source}: " if source else ""
    refuse_singular(x, source=source)  # no --beads can keep a knot type it has not
    # at order 1 (exactly: a power of two); ``unit`` takes lengths back to the input's units
    big = float(np.max(np.abs(x)))
    x = rescaled(x)
    unit = big / float(np.max(np.abs(x)))
    b = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    if len(x) == n and np.ptp(b) <= 1e-10 * b.mean():
        # already N equal bonds (e.g. a chain of stiffknots in any unit): a uniform scaling
        # is an isotopy, nothing to resample
        out = Chain((x - x.mean(axis=0)) / b.mean(), True,
                    dict(chain.meta) if isinstance(chain, Chain) else {})
        out.meta.update({"resampled_from": n, "chord": float(b.mean()) * unit,
                         "scale": float(1 / b.mean()) / unit,
                         "thickness": out.min_segment_distance()})
        if width is not None:
            out.meta.update({"w_over_L": width.w_over_L, "w": width.thickness,
                             "tube_fits": bool(out.meta["thickness"] >= width.thickness)})
        return out
    ok, a_max, D, (pts, ell, s, cum) = _condition(x, n)
    if not ok and not (certify and _certify(x, cum, s, n)):
        # the sufficient condition fails and the Δ-moves cannot be certified one by one
        length = float(np.sum(np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)))
        try:
            # arcs of length/N must be shorter than D (≤ its value at this N): no N up to
            # the limit can do when length/D exceeds it — say so without the long search
            if length > RESAMPLE_LIMIT * D:
                raise ValueError("strands (nearly) touch")
            need = minimal_resample_beads(x, start=n, limit=RESAMPLE_LIMIT)
        except ValueError:  # none up to the limit: strands (nearly) touch
            raise CurveError(
                f"{where}two non-neighbouring parts of the curve come within {D * unit:.2g} of "
                "each other (touching strands): no number of beads up to "
                f"{RESAMPLE_LIMIT:,} keeps its knot type certified; move the strands apart"
            ) from None
        raise ResampleError(
            "n_beads", n, f"an integer >= {need} for this curve",
            note=f"the arcs between beads ({a_max * unit:.4g}) must be shorter than the "
                 f"distance between non-neighbouring parts of the curve ({D * unit:.4g}) for "
                 "the knot type to be kept")
    if certify and ok and not _certify(x, cum, s, n):
        raise ResampleError(
            "n_beads", n, f"an integer > {n} for this curve",
            note="the isotopy to the chord polygon could not be certified (a neighbouring arc "
                 "folds back): use more beads")
    y = pts / ell
    y = y - y.mean(axis=0)
    bonds = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-12:
        y = y / np.mean(bonds)
        bonds = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-12:
        # the chords are equal only as far as Brent's root of the closing step (≈ 10⁻¹² on
        # 150 near-unit bonds): a min-norm correction of ~10⁻¹² per bead, far below the
        # polygon's thickness, so the certified isotopy and the knot type are unchanged
        # (the HOMFLY-PT check below is made on the corrected chain)
        y = _unit_bonds(y)
        bonds = np.linalg.norm(np.roll(y, -1, axis=0) - y, axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-12:  # pragma: no cover
        raise ValueError(f"bonds not unit after resampling (max error "
                         f"{np.max(np.abs(bonds - 1.0)):.2e})")
    src_meta = dict(chain.meta) if isinstance(chain, Chain) else {}
    meta = {**src_meta, "resampled_from": len(x), "chord": float(ell) * unit,
            "scale": float(1 / ell) / unit, "a_max": a_max * unit, "D_2l": D * unit}
    out = Chain(y, True, meta)
    thick = out.min_segment_distance()
    out.meta["thickness"] = thick
    if width is not None:
        out.meta.update({"w_over_L": width.w_over_L, "w": width.thickness,
                         "tube_fits": bool(thick >= width.thickness)})
    if check:
        from stiffknots.knots.identify import homfly_code

        before, after = homfly_code(x), homfly_code(y)
        if before != after:
            raise TopologyChangedError(
                f"resampling to {n} beads changed the HOMFLY-PT polynomial ({before} -> "
                f"{after}); please report this bug")
        out.meta["homfly"] = after
    return out
