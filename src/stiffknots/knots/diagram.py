"""A knot diagram of a 3D polygon: its planar-diagram (PD) code, as SnapPy/spherogram and
KnotInfo write them.

The closed polygon is turned by a fixed generic rotation and projected along z. Every crossing
of two non-adjacent edges in the projection is found exactly (segment intersection in the
plane, heights from the same edge parameters), the crossings are ordered along the curve, and
the 2M arcs between successive passages through crossings are labelled 1 .. 2M in the
direction of the polygon. A crossing is written ``(a, b, c, d)`` in the KnotTheory convention
used by KnotInfo's ``pd_notation`` and by :class:`spherogram.Link`: ``a`` is the incoming
under-arc, then the other three arcs counterclockwise (seen from +z, the viewer above the
over-strand). Hence a right-handed (positive) crossing has the over-strand's incoming arc at
``d``.

A projection in which a vertex falls on another edge, two edges overlap, or two crossings
coincide is not generic; the next of a fixed sequence of rotations is then tried, so the
answer is deterministic. A polygon that meets itself in space has no knot type (ValueError).
"""

from __future__ import annotations

import numpy as np

__all__ = ["pd_code", "generic_rotation", "reduce_polygon"]

_TOL = 1e-9


def generic_rotation(k: int = 0) -> np.ndarray:
    """The ``k``-th rotation of a fixed pseudo-random sequence (k = 0 is the one topoly's
    projections use in :mod:`stiffknots.knots.identify`)."""
    rng = np.random.default_rng(20070101 + k)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def reduce_polygon(coords) -> np.ndarray:
    """The closed polygon after topoly's KMT reduction (Koniaris–Muthukumar / Taylor triangle
    elimination: a vertex is removed when the triangle it spans with its neighbours is pierced
    by no other edge, an isotopy), in the original frame. Fewer vertices, same knot type."""
    import contextlib
    import io

    from stiffknots.knots.topoly_core import kmt_reduce

    x = np.asarray(coords, dtype=np.float64)
    if len(x) > 3 and np.array_equal(x[0], x[-1]):
        x = x[:-1]
    if len(x) <= 6:
        return x
    rot = generic_rotation(0)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        y = kmt_reduce(x @ rot.T)   # topoly's compiled KMT (topoly_core)
    if y.ndim != 2 or y.shape[1] != 3 or len(y) < 3:
        return x
    return y @ rot  # back to the original frame (rot is orthogonal)


def pd_code(coords, *, tries: int = 12) -> list[tuple[int, int, int, int]]:
    """PD code of the closed polygon ``coords`` (N, 3) (last vertex joined to the first).

    Returns a list of 4-tuples (empty for a diagram without crossings). Mirror images give
    mirrored codes: the code carries the chirality of the polygon.

    Raises
    ------
    ValueError
        If the coordinates are not an (N >= 3, 3) finite array, or if the polygon meets itself
        (no generic projection found in ``tries`` rotations).
    """
    x = np.asarray(coords, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or len(x) < 3 or not np.all(np.isfinite(x)):
        raise ValueError(f"expected finite coordinates of shape (N >= 3, 3), got {x.shape}")
    if np.array_equal(x[0], x[-1]):
        x = x[:-1]
    x = x - x.mean(axis=0)
    scale = float(np.max(np.abs(x))) or 1.0
    x = x / scale
    for k in range(tries):
        code = _pd_once(x @ generic_rotation(k).T)
        if code is not None:
            return code
    raise ValueError(
        f"no generic projection of the polygon found in {tries} directions: "
        "it meets itself (two edges touch), so it has no knot type")


def _pd_once(x: np.ndarray):
    n = len(x)
    p = x[:, :2]
    e = np.roll(p, -1, axis=0) - p  # 2D edge vectors
    z0 = x[:, 2]
    ez = np.roll(z0, -1) - z0
    passes = []  # (curve parameter, crossing id, is_over)
    dirs = []  # per crossing: (under edge, over edge)
    ncross = 0
    for i in range(n - 2):
        j = np.arange(i + 2, n if i > 0 else n - 1)
        if len(j) == 0:
            continue
        r = e[i]
        u = e[j]
        qp = p[j] - p[i]
        den = r[0] * u[:, 1] - r[1] * u[:, 0]
        s_num = qp[:, 0] * u[:, 1] - qp[:, 1] * u[:, 0]
        t_num = qp[:, 0] * r[1] - qp[:, 1] * r[0]
        small = np.abs(den) < 1e-14
        if np.any(small):
            # parallel edges: degenerate only when they are collinear and overlap
            cj = j[small]
            coll = np.abs(qp[small, 0] * r[1] - qp[small, 1] * r[0]) < 1e-12
            if np.any(coll):
                rr = float(r @ r)
                if rr == 0.0:
                    return None
                for jj in cj[coll]:
                    a0 = float((p[jj] - p[i]) @ r) / rr
                    a1 = float((p[jj] + e[jj] - p[i]) @ r) / rr
                    if max(a0, a1) >= -_TOL and min(a0, a1) <= 1 + _TOL:
                        return None
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(small, -1.0, s_num / np.where(small, 1.0, den))
            t = np.where(small, -1.0, t_num / np.where(small, 1.0, den))
        near = ((np.abs(s) < _TOL) | (np.abs(s - 1) < _TOL) | (np.abs(t) < _TOL)
                | (np.abs(t - 1) < _TOL))
        inside_loose = (s > -_TOL) & (s < 1 + _TOL) & (t > -_TOL) & (t < 1 + _TOL)
        if np.any(near & inside_loose & ~small):
            return None  # a vertex projects onto another edge
        hit = (s > 0) & (s < 1) & (t > 0) & (t < 1) & ~small
        for jj, ss, tt in zip(j[hit], s[hit], t[hit], strict=True):
            zi = z0[i] + ss * ez[i]
            zj = z0[jj] + tt * ez[jj]
            if abs(zi - zj) < 1e-12:
                return None  # the strands touch (or nearly) in space
            over_i = zi > zj
            passes.append((i + ss, ncross, over_i))
            passes.append((jj + tt, ncross, not over_i))
            dirs.append((int(jj), i) if over_i else (i, int(jj)))
            ncross += 1
    if ncross == 0:
        return []
    passes.sort(key=lambda q: q[0])
    params = np.array([q[0] for q in passes])
    if np.any(np.diff(params) < _TOL):
        return None  # two crossings on top of each other along the curve
    m2 = len(passes)
    inc = {}
    out = {}
    for k, (_, cid, over) in enumerate(passes):
        inc[(cid, over)] = k if k > 0 else m2
        out[(cid, over)] = k + 1
    code = []
    for cid, (eu, eo) in enumerate(dirs):
        a, c = inc[(cid, False)], out[(cid, False)]
        b_in, b_out = inc[(cid, True)], out[(cid, True)]
        cross = e[eu][0] * e[eo][1] - e[eu][1] * e[eo][0]
        # counterclockwise from the incoming under-arc: the over-strand's incoming arc comes
        # next when the over-strand goes to the left of the under-strand (cross > 0)
        b, d = (b_in, b_out) if cross > 0 else (b_out, b_in)
        code.append((a, b, c, d))
    return code
