"""Embedding of closed braids as closed chains of beads with unit bonds.

A braid word on ``n`` strands is turned into a smooth closed space curve (its *closure*), which
is then resampled into a closed chain of exactly ``n_beads`` beads joined by bonds of length
exactly 1 (paper §VII: bond length 1, non-bonded beads no closer than d = 1/√2).

Geometry of the smooth curve
----------------------------
The braid axis is the z axis.  The ``n`` strands wind once around it on a cylinder of radius
``R``; strand *slots* ``0 .. n-1`` are stacked along z (slot 0 lowest) with spacing ``gap``.
The word is read along the azimuth θ: the circle is cut into ``len(word)`` equal sectors, one
per generator.  In the sector of generator ``g = ±k`` (``1 <= k <= n-1``) the strands in slots
``k-1`` and ``k`` (zero-based; "strands k and k+1" in the one-based braid notation) exchange
heights along a C²-smooth step; meanwhile they bulge radially apart, one outwards to ``R + gap/2``
and one inwards to ``R - gap/2``, so that they pass each other at distance ``gap``.

Convention (seen from outside the cylinder, i.e. projecting radially onto the cylinder, the
outer strand is *over*):

* ``+k``: the strand descending from slot k to slot k-1 passes **outside (over)** the strand
  climbing from slot k-1 to k;
* ``-k``: the descending strand passes **inside (under)**.

Rotating each meridian half-plane by 90° (an isotopy of the solid torus) turns this picture into
the textbook closed braid (strand positions = radius, over/under = height), so the curve is the
closure of the braid.  Negating the word gives the mirror image.  With this convention a positive
generator is a positive (right-handed) crossing: the closure of ``[1, 1, 1]`` has writhe close to
+3 (Gauss writhe integral, checked in the tests), the right-handed trefoil.

Resampling
----------
The smooth curve is sampled as a dense closed polyline.  Starting from its first point, beads are
placed by walking along the polyline, each next bead being the first point of the polyline at
Euclidean distance exactly 1 from the current one (a sphere–polyline intersection, solved as a
quadratic on one polyline segment).  The cylinder radius ``R`` is tuned (Brent's method) so that
the ``n_beads``-th step lands exactly on the start: every bond, the closing one included, has
length 1 to ~1e-13.

The result is then checked: all bonds of unit length (within 1e-10) and all beads that are not
bonded neighbours (cyclic index distance >= 2) at distance >= ``d_min``.  If the check fails
for the requested ``n_beads``, :class:`EmbeddingError` is raised with the smallest ``n_beads``
that works (see :func:`minimal_beads`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.optimize import brentq

from stiffknots.errors import EmbeddingError
from stiffknots.geometry import seg_dist2
from stiffknots.measures import min_bead_distance, min_segment_distance

__all__ = [
    "EmbeddingError",
    "EmbeddingReport",
    "embed_braid",
    "embedding_report",
    "minimal_beads",
    "regular_polygon",
    "braid_permutation",
    "braid_curve",
    "parse_braid",
]

D_MIN = 1.0 / np.sqrt(2.0)
DEFAULT_GAP = 1.1
_MAX_BEADS = 20000


# --------------------------------------------------------------------------------------------
# braid words
# --------------------------------------------------------------------------------------------


def parse_braid(word) -> list[int]:
    """Braid word as a list of nonzero ints; accepts a sequence or a KnotInfo string '[1,-2,1]'
    (of a KnotInfo list of several words '[[1,...],[...]]', the first is taken)."""
    if isinstance(word, str):
        s = word.strip()
        if s.startswith("[[") or s.startswith("{{"):
            # KnotInfo lists several words for a few knots: '[[...],[...]]'; take the first
            s = s[1:].split("]")[0].split("}")[0]
        s = s.strip().strip("[]{}()").strip()
        if not s:
            return []
        try:
            out = [int(t) for t in s.replace(";", ",").split(",") if t.strip()]
        except ValueError as exc:
            raise EmbeddingError(
                f"cannot read braid word {word!r}: expected e.g. '[1,-2,1,-2]'") from exc
    else:
        out = [int(g) for g in word]
    if any(g == 0 for g in out):
        raise EmbeddingError(f"braid word {list(out)} contains 0; generators are ±1, ±2, ...")
    return out


def _strands(word: Sequence[int], n_strands: int | None) -> int:
    need = max((abs(g) for g in word), default=0) + 1
    if n_strands is None:
        return need
    if n_strands < need:
        raise EmbeddingError(
            f"braid word uses generator σ_{need - 1}, which needs at least {need} strands, "
            f"not n_strands={n_strands}"
        )
    return int(n_strands)


def braid_permutation(word: Sequence[int], n_strands: int) -> np.ndarray:
    """Slot permutation of the braid: ``perm[j]`` = slot reached after one turn from slot ``j``."""
    perm = np.arange(n_strands)
    pos = list(range(n_strands))  # pos[slot] = starting slot of the strand now in that slot
    for g in word:
        k = abs(g)
        pos[k - 1], pos[k] = pos[k], pos[k - 1]
    for slot, start in enumerate(pos):
        perm[start] = slot
    return perm


def _n_components(perm: np.ndarray) -> int:
    seen = np.zeros(len(perm), bool)
    c = 0
    for j in range(len(perm)):
        if not seen[j]:
            c += 1
            while not seen[j]:
                seen[j] = True
                j = perm[j]
    return c


def _require_knot(word, n: int) -> None:
    """EmbeddingError unless the closure of the braid ``word`` on ``n`` strands is a knot."""
    comps = _n_components(braid_permutation(word, n))
    if comps != 1:
        raise EmbeddingError(
            f"the closure of braid {word} on {n} strands is a link with {comps} components, "
            "not a knot"
        )


# --------------------------------------------------------------------------------------------
# smooth curve
# --------------------------------------------------------------------------------------------


def _step(t):
    """C²-smooth step from 0 to 1 on [0, 1] (zero first and second derivatives at the ends)."""
    return t - np.sin(2.0 * np.pi * t) / (2.0 * np.pi)


def _strand_profile(word, n_strands, start_slot, theta, gap):
    """Height (in slot units) and radial offset (in units of gap/2) of one pass along ``theta``."""
    ell = len(word)
    sector = np.minimum((theta / (2 * np.pi) * ell).astype(int), ell - 1)
    t = theta / (2 * np.pi) * ell - sector
    height = np.empty_like(theta)
    bulge = np.zeros_like(theta)
    slot = start_slot
    for m, g in enumerate(word):
        k = abs(g)
        sel = sector == m
        if slot == k - 1 or slot == k:
            up = slot == k - 1
            target = k if up else k - 1
            height[sel] = slot + (target - slot) * _step(t[sel])
            outward = (not up) if g > 0 else up
            bulge[sel] = (1.0 if outward else -1.0) * np.sin(np.pi * t[sel]) ** 2
            slot = target
        else:
            height[sel] = slot
    return height, bulge, slot


def braid_curve(
    word: Sequence[int],
    n_strands: int | None = None,
    radius: float = 10.0,
    gap: float = DEFAULT_GAP,
    samples_per_pass: int | None = None,
) -> np.ndarray:
    """Dense closed polyline (M, 3) of the braid closure (last point not repeated).

    Parameters
    ----------
    word : sequence of int
        Braid word, generators ±1 .. ±(n_strands-1).
    n_strands : int, optional
        Number of strands (default max|g| + 1).
    radius : float
        Radius R of the cylinder on which the strands wind around the z axis.
    gap : float
        Spacing of the strand slots along z, and distance at which crossing strands pass.
    samples_per_pass : int, optional
        Polyline points per turn around the axis (default: about 8 per unit length).
    """
    word = parse_braid(word)
    n = _strands(word, n_strands)
    if not word:
        raise EmbeddingError("the empty braid closes to unlinked circles; use regular_polygon")
    _require_knot(word, n)
    if samples_per_pass is None:
        samples_per_pass = max(400, 40 * len(word), int(8 * 2 * np.pi * radius))
    theta = np.arange(samples_per_pass) * (2 * np.pi / samples_per_pass)
    c, s = np.cos(theta), np.sin(theta)
    parts = []
    slot = 0
    for _ in range(n):
        h, b, nxt = _strand_profile(word, n, slot, theta, gap)
        r = radius + 0.5 * gap * b
        z = (h - 0.5 * (n - 1)) * gap
        parts.append(np.column_stack([r * c, r * s, z]))
        slot = nxt
    assert slot == 0
    return np.ascontiguousarray(np.concatenate(parts))


# --------------------------------------------------------------------------------------------
# unit-chord resampling
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _walk(poly, cum, n_beads, out, out_seg):
    """Place beads at unit chords along the closed polyline ``poly``.

    ``cum[i]`` is the arc length at vertex ``i`` (``cum[M]`` = total length, vertex M = vertex 0).
    Writes ``n_beads + 1`` points into ``out`` and returns the (unwrapped) arc-length parameter of
    the last one, or -1 if the walk could not proceed.
    """
    m = poly.shape[0]
    total = cum[m]
    seg = 0  # current segment index (unwrapped, may exceed m)
    frac = 0.0  # fraction along that segment
    px, py, pz = poly[0, 0], poly[0, 1], poly[0, 2]
    out[0, 0], out[0, 1], out[0, 2] = px, py, pz
    out_seg[0] = 0
    for b in range(1, n_beads + 1):
        found = False
        j = seg
        # first segment, starting at the current position, whose far end lies at distance >= 1
        while j < seg + 4 * m:
            i0 = j % m
            i1 = (j + 1) % m
            bx, by, bz = poly[i1, 0], poly[i1, 1], poly[i1, 2]
            dx, dy, dz = bx - px, by - py, bz - pz
            if dx * dx + dy * dy + dz * dz >= 1.0:
                if j == seg:
                    ax = poly[i0, 0] + frac * (bx - poly[i0, 0])
                    ay = poly[i0, 1] + frac * (by - poly[i0, 1])
                    az = poly[i0, 2] + frac * (bz - poly[i0, 2])
                    f0 = frac
                else:
                    ax, ay, az = poly[i0, 0], poly[i0, 1], poly[i0, 2]
                    f0 = 0.0
                # point a + u (b - a), u in [0, 1], at distance 1 from p: |a - p + u e|^2 = 1
                ex, ey, ez = bx - ax, by - ay, bz - az
                wx, wy, wz = ax - px, ay - py, az - pz
                qa = ex * ex + ey * ey + ez * ez
                qb = 2.0 * (ex * wx + ey * wy + ez * wz)
                qc = wx * wx + wy * wy + wz * wz - 1.0
                if qa <= 0.0:
                    return -1.0
                disc = qb * qb - 4.0 * qa * qc
                if disc < 0.0:
                    disc = 0.0
                u = (-qb + np.sqrt(disc)) / (2.0 * qa)
                if u < 0.0:
                    u = 0.0
                if u > 1.0:
                    u = 1.0
                px, py, pz = ax + u * ex, ay + u * ey, az + u * ez
                frac = f0 + u * (1.0 - f0)
                seg = j
                found = True
                break
            j += 1
        if not found:
            return -1.0
        out[b, 0], out[b, 1], out[b, 2] = px, py, pz
        out_seg[b] = seg
    i0 = seg % m
    lap = seg // m
    seglen = cum[i0 + 1] - cum[i0]
    return lap * total + cum[i0] + frac * seglen


def _resample(poly: np.ndarray, n_beads: int, with_segments: bool = False):
    """Walk unit chords; return (points (n_beads+1, 3), arc-length mismatch with one full turn).

    With ``with_segments``, also the (unwrapped) polyline segment index of each point.
    """
    seglen = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seglen)])
    out = np.empty((n_beads + 1, 3))
    out_seg = np.zeros(n_beads + 1, np.int64)
    u = _walk(poly, cum, n_beads, out, out_seg)
    d = np.nan if u < 0 else u - cum[-1]
    if with_segments:
        return out, d, out_seg
    return out, d


def _chord_deviation(poly: np.ndarray, pts: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Largest distance of the polyline arc between consecutive beads from their chord."""
    m = len(poly)
    dev = np.zeros(len(pts) - 1)
    for b in range(len(pts) - 1):
        idx = np.arange(segs[b] + 1, segs[b + 1] + 1) % m
        if len(idx) == 0:
            continue
        a, e = pts[b], pts[b + 1] - pts[b]
        w = poly[idx] - a
        t = np.clip(w @ e / (e @ e), 0.0, 1.0)
        dev[b] = np.sqrt(np.max(np.sum((w - t[:, None] * e) ** 2, axis=1)))
    return dev


@njit(cache=True)
def _isotopy_safe(x, dev):
    """True if every pair of non-adjacent bonds is farther apart than the sum of their arcs'
    deviations from them: then moving each arc straight onto its chord crosses no other arc
    or chord, and the polygon has the knot type of the smooth curve."""
    n = x.shape[0]
    for i in range(n):
        i1 = (i + 1) % n
        for j in range(i + 2, n):
            j1 = (j + 1) % n
            if j1 == i:
                continue
            lim = dev[i] + dev[j]
            d2 = seg_dist2(
                x[i, 0], x[i, 1], x[i, 2], x[i1, 0], x[i1, 1], x[i1, 2],
                x[j, 0], x[j, 1], x[j, 2], x[j1, 0], x[j1, 1], x[j1, 2],
            )
            if d2 <= lim * lim:
                return False
    return True


# --------------------------------------------------------------------------------------------
# checks
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EmbeddingReport:
    """Quality of a closed chain: bonds, exclusion distances."""

    n_beads: int
    max_bond_error: float
    min_bead_distance: float
    min_segment_distance: float

    def ok(self, d_min: float = D_MIN, bond_tol: float = 1e-10) -> bool:
        return self.max_bond_error <= bond_tol and self.min_bead_distance >= d_min


def embedding_report(coords: np.ndarray) -> EmbeddingReport:
    """Bond-length error and minimal non-adjacent bead and segment distances of a closed chain."""
    x = np.ascontiguousarray(coords, dtype=np.float64)
    bonds = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    if len(x) < 4:
        dmin = smin = np.inf
    else:
        dmin, smin = min_bead_distance(x, True, 2), min_segment_distance(x, True)
    return EmbeddingReport(len(x), float(np.max(np.abs(bonds - 1.0))), float(dmin), float(smin))


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------


def regular_polygon(n_beads: int) -> np.ndarray:
    """Unknot: regular ``n_beads``-gon with unit sides in the xy plane, centred at the origin."""
    if n_beads < 3:
        raise EmbeddingError(f"a closed chain needs at least 3 beads, not n_beads={n_beads}")
    r = 0.5 / np.sin(np.pi / n_beads)
    t = 2 * np.pi * np.arange(n_beads) / n_beads
    return np.column_stack([r * np.cos(t), r * np.sin(t), np.zeros(n_beads)])


def _try_embed(word, n, n_beads, gap):
    """Closed unit-chord chain of the braid closure, or None when the closure cannot be tuned."""
    length_per_turn = 2 * np.pi  # per unit radius
    # fixed sampling for all radii, so that the mismatch is a continuous function of R
    spp = max(400, 40 * len(word), int(10 * n_beads / n))

    def mismatch(radius):
        poly = braid_curve(word, n, radius=radius, gap=gap, samples_per_pass=spp)
        _, d = _resample(poly, n_beads)
        return d

    r0 = n_beads / (n * length_per_turn)
    r_lo = max(0.5 * gap + 0.05, 0.6 * r0)
    r_hi = 1.2 * r0
    f_lo = mismatch(r_lo)
    if not np.isfinite(f_lo) or f_lo < 0:
        return None
    f_hi = mismatch(r_hi)
    tries = 0
    while (not np.isfinite(f_hi) or f_hi > 0) and tries < 8:
        r_hi *= 1.3
        f_hi = mismatch(r_hi)
        tries += 1
    if not np.isfinite(f_hi) or f_hi > 0:
        return None
    # mismatch decreases with R (longer curve for the same number of unit chords)
    try:
        r = brentq(mismatch, r_lo, r_hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    except (ValueError, RuntimeError):
        return None
    poly = braid_curve(word, n, radius=r, gap=gap, samples_per_pass=spp)
    pts, d, segs = _resample(poly, n_beads, with_segments=True)
    if not np.isfinite(d):
        return None
    x = pts[:-1].copy()
    if not _isotopy_safe(x, _chord_deviation(poly, pts, segs)):
        return None
    return x


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _embed_checked(word, n, n_beads, d_min, gap):
    if not word:
        return regular_polygon(n_beads)
    x = _try_embed(word, n, n_beads, gap)
    if x is None:
        return None
    rep = embedding_report(x)
    if not rep.ok(d_min):
        return None
    return x


def minimal_beads(
    word,
    n_strands: int | None = None,
    d_min: float = D_MIN,
    *,
    gap: float = DEFAULT_GAP,
    start: int | None = None,
    max_beads: int = _MAX_BEADS,
) -> int:
    """Smallest number of beads for which :func:`embed_braid` succeeds (linear search upwards).

    The search starts from a lower estimate (about 1.5 bond lengths of polyline per crossing and
    strand) and increases ``n_beads`` one by one; the answer is the first value that passes all
    checks.  Raises :class:`EmbeddingError` if nothing up to ``max_beads`` works.
    """
    word = parse_braid(word)
    n = _strands(word, n_strands)
    if not word:
        return 3
    if start is None:
        start = max(8, int(1.0 * n * len(word)))
    for nb in range(start, max_beads + 1):
        if _embed_checked(word, n, nb, d_min, gap) is not None:
            return nb
    raise EmbeddingError(f"braid {word} could not be embedded with up to {max_beads} beads")


def embed_braid(
    word,
    n_strands: int | None = None,
    n_beads: int = 150,
    d_min: float = D_MIN,
    seed: int | None = None,
    *,
    gap: float = DEFAULT_GAP,
) -> np.ndarray:
    """Closed chain of ``n_beads`` beads with unit bonds whose shape is the closure of a braid.

    Parameters
    ----------
    word : sequence of int or str
        Braid word: ``+k`` is σ_k (strand k passes over strand k+1, see the module docstring for
        the exact geometric convention), ``-k`` its inverse; KnotInfo strings '[1,-2,1,-2]' are
        accepted.  The empty word gives the unknot (a regular polygon).
    n_strands : int, optional
        Number of strands (default max|g| + 1).
    n_beads : int
        Number of beads N (= number of bonds, = length of the chain).
    d_min : float
        Minimal distance allowed between beads that are not bonded neighbours (default 1/√2).
    seed : int, optional
        If given, the chain is rotated by a random rotation and its bead numbering shifted
        cyclically (reproducibly from the seed); the shape is otherwise the same.
    gap : float
        Strand spacing of the braid and distance at which crossing strands pass (keyword only).

    Returns
    -------
    numpy.ndarray, shape (n_beads, 3)
        Bead coordinates; bond i joins beads i and i+1, bond N-1 joins bead N-1 to bead 0.
        All bonds have length 1 within 1e-10 and all non-adjacent beads are >= d_min apart;
        segments sharing no bead too (a tube of diameter d_min fits) wherever a strand
        spacing up to 1.2 ``gap`` gives that.

    Raises
    ------
    EmbeddingError
        If the word is not a knot (closure with several components), or ``n_beads`` is too
        small for the word and for each of its cyclic rotations (conjugate braids, the same
        closure, tried in turn when the word as given does not fit); the message gives the
        smallest ``n_beads`` that works for the word as given.
    """
    word = parse_braid(word)
    n = _strands(word, n_strands)
    n_beads = int(n_beads)
    if n_beads < 3:
        raise EmbeddingError(f"a closed chain needs at least 3 beads, not n_beads={n_beads}")
    if word:
        _require_knot(word, n)
    elif n > 1 and n_strands is not None:
        raise EmbeddingError(f"the empty braid on {n} strands is an unlink of {n} circles")
    x = _embed_checked(word, n, n_beads, d_min, gap)
    if x is not None and embedding_report(x).min_segment_distance < d_min:
        # beads d_min apart, but segments closer where strands cross (12a_32 at N = 150:
        # 0.695): not admissible for a tube of diameter d_min. A wider strand spacing first;
        # the bead layout stays where none is (every knot through 10 crossings passes as is)
        for wider in (1.05 * gap, 1.1 * gap, 1.2 * gap):
            y = _embed_checked(word, n, n_beads, d_min, wider)
            if y is not None and embedding_report(y).min_segment_distance >= d_min:
                x = y
                break
    # a word too long for n_beads: its cyclic rotations are conjugate braids with the same
    # closure, laid out otherwise (12a_1202's word needs 152 beads, its 16th rotation 146)
    for r in range(1, len(word) if x is None else 0):
        x = _embed_checked(word[r:] + word[:r], n, n_beads, d_min, gap)
        if x is not None:
            break
    if x is None:
        nmin = minimal_beads(word, n, d_min, gap=gap)
        if nmin <= n_beads:  # pragma: no cover - non-monotone corner case
            nmin = minimal_beads(word, n, d_min, gap=gap, start=n_beads + 1)
        raise EmbeddingError(
            f"{n_beads} beads are too few to embed braid {word} on {n} strands with "
            f"non-adjacent beads ≥ {d_min:.4g} apart, nor any of its cyclic rotations (the "
            f"same closure); the least number of beads that works is {nmin} (for the word as "
            "given)"
        )
    if seed is not None:
        rng = np.random.default_rng(seed)
        x = x @ _random_rotation(rng).T
        x = np.roll(x, int(rng.integers(n_beads)), axis=0)
        x -= x.mean(axis=0)
    return np.ascontiguousarray(x)
