"""Embedding of knots as an "80": a figure eight with a circle along one lobe (paper §VII).

The paper's *80* (§VII, Fig. 6 and Fig. 7 c, eq. for ε°_80) is the shape annealed
for 5_2, 6_2 and 6_3: "composed of an 8 and a circle (0)", with "one point-braid and 3 double
points", of thin-limit energy ε°_80 = (ε°_8^{1/2} + ε°_0^{1/2})² ≈ 142.1. In the Monte Carlo
80s (e.g. ``results/paper_full/6_2/bead``) the circle lies along one lobe of a planar figure
eight: it leaves the lobe at a point-braid (the two strands twist around each other), runs
round that lobe, passes just beyond the centre crossing of the 8 — across the two strands of
the *other* lobe, over one and under the other (a clasp) — and comes back to the point-braid.
The double points are the centre crossing and the two crossings of the clasp.

A braid closure (:mod:`stiffknots.knots.embedding`) starts the annealing near a circular
braid; this module builds a start that already is an 80, so that the search can explore the
80's basin. The start only chooses the basin: the final shape and energy are the annealing's.

Geometry of the smooth curve (design units: lobes about 2 long and 1.5 high; z is "up")
---------------------------------------------------------------------------------------
* Centre of the 8 at the origin: a twist box of ``c`` half-turns (``c`` odd, handedness
  ``sc``) — two strands along the x axis on a double helix of radius r, at y = ±r, z = 0 at
  its ends; ``c = 1`` is the plain crossing of the 8 (its strands tangent there rather than
  at an angle). On route B the circle's clasp may sit after ``j`` of the ``c`` half-turns
  (default all): for ``j < c`` the box is split by a short gap where the strands part.
* Lobe B (x > 0) joins the right ends of the centre part, lobe A (x < 0) its left ends; both
  are planar (z = 0) teardrops, lobe A drawn along a centreline parametrised by arc length.
* The point-braid: ``k`` half-turns (handedness ``sk``) of a double helix of radius r around
  an arc of lobe A's centreline (the braid follows the lobe, so long braids fit).
* Route ``"B"`` (the Monte Carlo 80 of 5_2 and 6_2): the braid is centred on lobe A's far
  point; the circle (the 0) joins its two outer ends, runs round lobe A on the outside, 0.3
  away from it, and on its right passes just beyond the centre half-turns before the clasp,
  crossing the two strands there (those of lobe B, or of the gap for ``j < c``).
* Route ``"X"`` (the 80 of 6_3): the braid sits on lobe A's upper strand near the centre;
  the circle leaves it on the inner side, crosses lobe A's lower strand, passes below the
  centre, crosses lobe B's lower strand into lobe B, leaves it across its upper strand, and
  comes back over the top, outside everything, to the braid's far end on the outer side.
* At each crossing with the 8 the circle hops above (``over = +1``) or below (``−1``) the
  strand by a smooth bump. Handedness ``+1`` is a right-handed double helix about the
  direction of travel, for both twists (strand frame: travel, in-plane left normal, z).

The helix radius (0.6), the length per half-turn (2.6) and the hops (1.15) are sized in bonds
of the final chain, so every chain built is a valid start for both exclusion models
(non-adjacent beads and non-adjacent bonds ≥ 1/√2 apart). The strand ends of a box are joined
straight through for an even number of half-turns and swapped for an odd one, so the pieces
form one closed curve only for ``k`` odd on route B and even on route X (otherwise the circle
is a component of its own: a two-component link); ``c`` odd keeps the 8 an 8 (even would make
it a twisted 0).

Which knot a spec gives is not assumed: the curve is resampled into unit bonds
(``stiffknots.knots.cage_embedding._scaled_chain()``, which also checks that the chords do
not change the knot type), checked (bonds, exclusion) and identified (HOMFLY-PT, mirror images
not told apart). :func:`eighty_table` lists the family; up to 10 crossings it holds 3_1, 4_1,
5_1, 5_2, 6_1, 6_2, 6_3, 7_1, 7_2, 7_3, 7_5, 7_6, 8_1, 8_2, 8_6, 8_7, 8_8, 9_1, 9_3, 9_6,
9_7, 9_8, 9_11, 10_2, 10_6, 10_20 — two-bridge knots only, not 7_4 or 7_7.

On route B the ``c − j`` half-turns beyond the clasp can be undone by turning lobe B over, and
the knot is the two-bridge knot of continued fraction ``[±k, ±j, ±2]`` (a free circle, both
``over`` equal, gives the torus knot T(2, k)). The paper's 80 — a plain centre crossing
(``j = 1``), one point-braid and three double points — then gives 5_2 and 6_2 (``k = 3``),
7_3 and 8_2 (``k = 5``), but never 6_3 (13/5): ``[k, ±1, ±2]`` has fraction ``k ± 2`` or
``(3k ± 2)/3``; route B needs ``j = 2`` for it, ``[3, −2, −2]``, a twisted centre. Route X
gives 6_3 with a plain centre, a point-braid of two half-turns and four double points
(``c = 1, k = 2``, a minimal diagram). That is the start :func:`find_eighty` returns for 6_3,
and the shape annealing keeps from it: with the default schedule (20 M moves, N = 150) every
seed ended as an 80 (:func:`stiffknots.analysis.shapes.classify`), ε ≈ 170–176 under the
bead rule, below the circular braid CB(i = 3) (ε ≈ 180) that the braid start gives; the
route-B 6_3 starts (``j = 2`` or 3) mostly end near ε ≈ 195–205 instead.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from stiffknots.knots.cage_embedding import _cycles, _scaled_chain
from stiffknots.knots.embedding import D_MIN, EmbeddingError, embedding_report

__all__ = [
    "EightySpec",
    "eighty_curve",
    "eighty_chain",
    "eighty_specs",
    "eighty_table",
    "find_eighty",
    "has_eighty",
    "embed_eighty",
]

# sizes of the twist boxes and crossings, in bonds of the final chain (converted to design
# units by :func:`eighty_curve` for the requested number of beads)
_R_BONDS = 0.6  # helix radius of both boxes: strands 1.2 bonds apart
_PITCH_BONDS = 2.6  # box length per half-turn
_HOP_BONDS = 1.15  # height of the circle above/below a strand where it crosses it
_GAP = 0.9  # length of the gap of a centre box split by the clasp (j < c)
_X_FAR = 2.1  # distance of the far points of the lobes from the centre
_DENSITY = 150  # polyline samples per unit length
_MAX_DIAGRAM = 10  # largest diagram (essential crossings) searched by find_eighty


@dataclass(frozen=True)
class EightySpec:
    """Parameters of an 80: the twists of the 8's centre and of the point-braid, the clasp.

    The default is the 80 of 6_2 (a plain centre crossing, a point-braid of three half-turns).

    Attributes
    ----------
    c : int
        Half-turns of the centre box of the 8 (odd, ≥ 1; 1 = the plain crossing of the 8).
    k : int
        Half-turns of the point-braid joining the circle to lobe A (odd for a knot on route
        ``"B"``, even on route ``"X"``; the other parity gives a two-component link, which
        raises :class:`EmbeddingError` when built).
    sc, sk : int
        Handedness of the two twists, +1 or −1.
    over : tuple of int
        Whether the circle passes over (+1) or under (−1) each strand of the 8 it crosses, in
        its order along the circle. Route ``"B"``: two values, the upper (y > 0) and the lower
        (y < 0) strand near the centre; ``(+1, −1)`` and ``(−1, +1)`` hook the circle (a
        clasp), ``(+1, +1)`` and ``(−1, −1)`` leave it free. Route ``"X"``: three values,
        lobe A's lower strand, then lobe B's lower and upper strands.
    j : int or None
        Number of the centre box's half-turns on lobe A's side of the clasp, 1 ≤ j ≤ c
        (default ``c``: the circle passes beyond the whole box, through lobe B). For ``j < c``
        the circle passes through the box, between its half-turns ``j`` and ``j + 1``. The
        ``c − j`` half-turns beyond the clasp can be undone by turning lobe B over, so the
        knot type depends on ``j``, not on ``c``; they only keep the 8 an 8 when ``j`` is
        even (``c`` odd). Route ``"X"`` has no clasp inside the box (``j`` must be ``c``).
    route : str
        ``"B"`` (default): the braid sits at the far point of lobe A and the circle runs
        round lobe A outside it and through lobe B just beyond the centre (the Monte Carlo
        80 of 5_2 and 6_2). ``"X"``: the braid sits on lobe A's upper strand near the
        centre; the circle leaves it inside lobe A, crosses lobe A's lower strand, passes
        below the centre, crosses lobe B's lower strand into lobe B, leaves it across its
        upper strand and comes back over the top, outside everything, to the braid's far
        end (the 80 annealed for 6_3 from a route-B start: a point-braid of two half-turns
        and four double points, a minimal diagram of 6_3).
    """

    c: int = 1
    k: int = 3
    sc: int = 1
    sk: int = -1
    over: tuple[int, ...] = (-1, 1)
    j: int | None = None
    route: str = "B"

    def __post_init__(self):
        object.__setattr__(self, "over", tuple(self.over))
        if int(self.c) != self.c or self.c < 1 or self.c % 2 == 0:
            raise EmbeddingError(
                f"the centre box of an 80 needs an odd number of half-turns c ≥ 1, not "
                f"c={self.c} (an even c turns the 8 into a twisted circle)")
        if int(self.k) != self.k or self.k < 0:
            raise EmbeddingError(f"the point-braid needs k ≥ 0 half-turns, not k={self.k}")
        if self.sc not in (1, -1) or self.sk not in (1, -1):
            raise EmbeddingError(f"twist signs must be ±1, got sc={self.sc}, sk={self.sk}")
        if self.route not in ("B", "X"):
            raise EmbeddingError(f"route must be 'B' or 'X', got {self.route!r}")
        n_over = 2 if self.route == "B" else 3
        if len(self.over) != n_over or any(o not in (1, -1) for o in self.over):
            raise EmbeddingError(f"over must be {n_over} values ±1 on route {self.route}, "
                                 f"got {self.over}")
        if self.j is not None and not (int(self.j) == self.j and 1 <= self.j <= self.c):
            raise EmbeddingError(f"the clasp must follow j = 1 … c={self.c} centre half-turns, "
                                 f"not j={self.j}")
        if self.route == "X" and self.clasp_after != self.c:
            raise EmbeddingError("route X passes below the whole centre box: j must be c")

    @property
    def clasp_after(self) -> int:
        """``j``: the centre half-turns before the clasp (``c`` when not given)."""
        return self.c if self.j is None else int(self.j)

    @property
    def crossings(self) -> int:
        """Number of crossings of the spec's diagram, ``c + k + len(over)``."""
        return self.c + self.k + len(self.over)

    @property
    def essential_crossings(self) -> int:
        """Crossings left once the half-turns beyond the clasp are undone,
        ``j + k + len(over)``."""
        return self.clasp_after + self.k + len(self.over)

    def mirror(self) -> EightySpec:
        """The mirror image (z → −z): every sign flipped."""
        return EightySpec(self.c, self.k, -self.sc, -self.sk, tuple(-o for o in self.over),
                          self.j, self.route)

    def __str__(self) -> str:
        o = "".join("o" if v > 0 else "u" for v in self.over)
        jj = "" if self.clasp_after == self.c else f" j={self.clasp_after}"
        return (f"{'X-route ' if self.route == 'X' else ''}c={self.c}"
                f"{'+' if self.sc > 0 else '-'}{jj} k={self.k}{'+' if self.sk > 0 else '-'} "
                f"{'clasp' if self.route == 'B' else 'over'}={o}")


# --------------------------------------------------------------------------------------------
# pieces
# --------------------------------------------------------------------------------------------


def _twist_profile(u, ramp: float = 0.2):
    """Step 0 → 1 on [0, 1] whose slope rises from 0 as cos² over the first and last
    ``ramp`` of the box and is constant in between (twists start and end gently, the peak
    twist rate is only 1/(1 − ramp) times the mean)."""
    v = np.linspace(0.0, 1.0, 2001)
    w = np.ones_like(v)
    a = v < ramp
    w[a] = np.sin(0.5 * np.pi * v[a] / ramp) ** 2
    b = v > 1 - ramp
    w[b] = np.sin(0.5 * np.pi * (1 - v[b]) / ramp) ** 2
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(v))])
    return np.interp(u, v, cum / cum[-1])


def _box(turns: int, sign: int, t: float, r: float, offset: float = 0.0):
    """The two strands of a twist box along the x axis, as (n, 3) arrays oriented along +x.

    The box spans x ∈ offset ± t; strand s starts at phase s·π (phase 0: y = +r, z = 0) and
    turns by ``sign · turns · π`` about +x.
    """
    n = max(40, int(_DENSITY * 2 * t) + 1)
    u = np.linspace(-t, t, n)
    phi = sign * turns * np.pi * _twist_profile((u + t) / (2 * t))
    return [np.column_stack([u + offset, r * np.cos(phi + s * np.pi), r * np.sin(phi + s * np.pi)])
            for s in (0, 1)]


def _spline(points, d0, d1) -> np.ndarray:
    """Planar C² curve through ``points`` (z = 0) with end directions ``d0``, ``d1``."""
    p = np.asarray(points, float)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    cs = CubicSpline(s, p, bc_type=((1, np.asarray(d0, float)), (1, np.asarray(d1, float))))
    n = max(40, int(_DENSITY * s[-1]) + 1)
    q = cs(np.linspace(0.0, s[-1], n))
    return np.column_stack([q, np.zeros(n)])


class _Centreline:
    """A planar spline curve parametrised by arc length: points, unit tangents, normals."""

    def __init__(self, points, d0, d1, n: int = 4000):
        p = np.asarray(points, float)
        u = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        cs = CubicSpline(u, p, bc_type=((1, np.asarray(d0, float)), (1, np.asarray(d1, float))))
        uu = np.linspace(0.0, u[-1], n)
        self._p = cs(uu)
        d = cs(uu, 1)
        self._t = d / np.linalg.norm(d, axis=1)[:, None]
        self._s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self._p, axis=0),
                                                                  axis=1))])
        self.length = float(self._s[-1])

    def at(self, s):
        """(points, tangents, left normals) at arc lengths ``s``, each (len(s), 2)."""
        s = np.atleast_1d(np.asarray(s, float))
        p = np.column_stack([np.interp(s, self._s, self._p[:, i]) for i in (0, 1)])
        t = np.column_stack([np.interp(s, self._s, self._t[:, i]) for i in (0, 1)])
        t /= np.linalg.norm(t, axis=1)[:, None]
        return p, t, np.column_stack([-t[:, 1], t[:, 0]])

    def arc(self, s0: float, s1: float) -> np.ndarray:
        """Arc lengths from s0 to s1 at the polyline density."""
        return np.linspace(s0, s1, max(2, int(_DENSITY * abs(s1 - s0)) + 1))


def _bump(s, s0, width):
    """Smooth bump of height 1 at arc length ``s0``, zero beyond ±``width``."""
    v = np.clip(np.abs(s - s0) / width, 0.0, 1.0)
    return np.cos(0.5 * np.pi * v) ** 2


def _planar_hits(a: np.ndarray, b: np.ndarray) -> list[tuple[float, float]]:
    """Crossings of the xy projections of the polylines ``a`` and ``b``: (arc length along
    ``a``, y) of each, sorted along ``a``."""
    p, r = a[:-1, None, :2], (a[1:] - a[:-1])[:, None, :2]
    q, d = b[None, :-1, :2], (b[1:] - b[:-1])[None, :, :2]
    den = r[..., 0] * d[..., 1] - r[..., 1] * d[..., 0]
    w = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * d[..., 1] - w[..., 1] * d[..., 0]) / den
        v = (w[..., 0] * r[..., 1] - w[..., 1] * r[..., 0]) / den
    ii, jj = np.nonzero((np.abs(den) > 1e-15) & (t >= 0) & (t < 1) & (v >= 0) & (v < 1))
    sa = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(a[:, :2], axis=0), axis=1))])
    hits = [(sa[i] + t[i, j] * (sa[i + 1] - sa[i]), a[i, 1] + t[i, j] * (a[i + 1, 1] - a[i, 1]))
            for i, j in zip(ii, jj, strict=True)]
    return sorted(hits)


def _circle_b(lobe, sa, sb, r, t1, grow_a, right, pieces, lobe_b, m):
    """Route B: the circle clockwise around lobe A, from the outer end of the braid at sb to
    its outer end at sa: outside the lobe at distance up to 0.3 (an offset of the
    centreline), except near the centre, where it crosses the two strands just beyond the
    clasp's centre half-turns: those of lobe B (m = 0) or those of the gap."""
    gap = 0.3

    def outer(u):
        w = np.clip(np.where(u >= sb, u - sb, sa - u) / 0.8, 0.0, 1.0)
        return r + (gap - r) * np.sin(0.5 * np.pi * w) ** 2

    span = np.concatenate([np.arange(sb, lobe.length, 0.2), np.arange(0.0, sa, 0.2)])
    span = span[(span >= sb) | (span <= sa)]
    qc, _, nc = lobe.at(span)
    qc = qc + outer(span)[:, None] * nc
    keep = qc[:, 0] < -1.15 - grow_a  # away from the centre
    top = qc[keep & (span >= sb)][1:]
    bottom = qc[keep & (span <= sa)][:-1]
    if m == 0:
        c_right = right([(0.3, 0.78), (0.52, 0.38), (0.58, 0.0)])
        crossed = [lobe_b]
    else:
        xc = t1 + 0.5 * _GAP
        c_right = [(xc - 0.25, 0.8), (xc - 0.04, 0.45), (xc, 0.0)]
        crossed = pieces[2:4]
    ends = lobe.at([sb, sa])
    start = ends[0][0] + r * ends[2][0]
    stop = ends[0][1] + r * ends[2][1]
    circle = _spline([tuple(start)] + [tuple(v) for v in top] + [(-0.35 - grow_a, 0.98)]
                     + c_right + [(x, -y) for x, y in c_right[-2::-1]]
                     + [(-0.35 - grow_a, -0.98)] + [tuple(v) for v in bottom] + [tuple(stop)],
                     ends[1][0], ends[1][1])
    return circle, crossed


def _pieces(spec: EightySpec, unit: float) -> list[np.ndarray]:
    """All pieces of the curve (boxes, lobes, circle) as open polylines sharing end points;
    ``unit`` is the length of one bond in design units."""
    r, pitch, hop = _R_BONDS * unit, _PITCH_BONDS * unit, _HOP_BONDS * unit
    j = spec.clasp_after
    m = spec.c - j  # centre half-turns beyond the clasp
    t1 = 0.5 * pitch * j
    pieces = _box(j, spec.sc, t1, r)
    # the shapes below are drawn for a one-half-turn centre box (ends at ±pitch/2); longer
    # centre parts push the lobes outwards
    grow_a = t1 - 0.5 * pitch
    if m == 0:
        x2 = t1
    else:  # a gap where the strands part (the circle passes there), then the other box
        pieces += [_spline([(t1, y), (t1 + 0.5 * _GAP, np.sign(y) * 0.3), (t1 + _GAP, y)],
                           (1, 0), (1, 0)) for y in (r, -r)]
        pieces += _box(m, spec.sc, 0.5 * pitch * m, r, offset=t1 + _GAP + 0.5 * pitch * m)
        x2 = t1 + _GAP + pitch * m
    grow_b = x2 - 0.5 * pitch

    def right(pts):
        return [(x + grow_b, y) for x, y in pts]

    def left(pts):
        return [(-x - grow_a, y) for x, y in pts]

    # lobe B, counter-clockwise, from the lower right end of the centre part to the upper one
    half = [(0.3, 0.12), (0.6, 0.3), (1.05, 0.62), (1.65, 0.72), (2.03, 0.4)]
    lobe_b = _spline([(x2, -r)] + right([(x, -y) for x, y in half] + [(_X_FAR, 0.0)]
                                        + half[::-1]) + [(x2, r)], (1, 0), (-1, 0))
    # lobe A: centreline, clockwise from the lower left end of the centre box round the far
    # point to its upper left end; the point-braid is a double helix of radius r around its
    # arc [sa, sb] (route B: centred on the far point; X: on the upper strand near the
    # centre), its two strands starting at ∓r along the outer normal.
    lobe = _Centreline([(-t1, -r)] + left([(x, -y) for x, y in half] + [(_X_FAR, 0.0)]
                                          + half[::-1]) + [(-t1, r)], (-1, 0), (1, 0))
    tk = 0.5 * pitch * spec.k
    if tk > 0.35 * lobe.length:
        raise EmbeddingError(f"the point-braid of {spec} is too long for its lobe")
    if spec.route == "B":  # centred on the far point
        sa, sb = 0.5 * lobe.length - tk, 0.5 * lobe.length + tk
    else:  # on the upper strand, ending 0.75 from the centre
        sb = lobe.length - 0.75
        sa = sb - 2 * tk
        if sa < 0.65 * lobe.length:
            raise EmbeddingError(f"the point-braid of {spec} is too long for route X")
    ease = 0.4  # length over which the lobe's strand eases onto the braid's side

    def offset_arc(s0, s1, off):
        q, _, nrm = lobe.at(lobe.arc(s0, s1))
        q = q + off(lobe.arc(s0, s1))[:, None] * nrm
        return np.column_stack([q, np.zeros(len(q))])

    def side(u):
        return r * np.sin(0.5 * np.pi * np.clip(u, 0.0, 1.0)) ** 2

    # the lobe's strand reaches the braid on its inner side; on route X it leaves it on the
    # outer side (the circle leaves on the inner side)
    after = 1.0 if spec.route == "X" else -1.0
    a_before = offset_arc(0.0, sa, lambda u: -side((u - sa + ease) / ease))
    pieces.append(a_before)
    pieces.append(offset_arc(sb, lobe.length, lambda u: after * side((sb + ease - u) / ease)))
    u = lobe.arc(sa, sb)
    q, _, nrm = lobe.at(u)
    phi = spec.sk * spec.k * np.pi * _twist_profile((u - sa) / (sb - sa))
    for ph0 in (np.pi, 0.0):  # the lobe's own strand (inner at sa), then the circle's
        pieces.append(np.column_stack([q + r * np.cos(phi + ph0)[:, None] * nrm,
                                       r * np.sin(phi + ph0)]))
    ends = lobe.at([sb, sa])
    if spec.route == "B":
        circle, crossed = _circle_b(lobe, sa, sb, r, t1, grow_a, right, pieces, lobe_b, m)
    else:
        start = ends[0][0] - r * ends[2][0]  # inner side of the braid's end near the centre
        stop = ends[0][1] + r * ends[2][1]  # outer side of its far end
        # back over the top, round the upper left corner of lobe A, onto the braid's far end
        behind = ends[0][1] + 0.25 * ends[2][1] - 0.45 * ends[1][1]
        way = (left([(0.55, -0.02), (0.33, -0.45)]) + [(0.0, -0.58)]
               + right([(0.4, -0.6), (0.95, -0.28), (1.3, 0.25), (1.42, 1.0), (0.9, 1.3)])
               + [(0.0, 1.33)] + left([(0.9, 1.36)])
               + [(behind[0] - 0.3, behind[1] + 0.3), tuple(behind)])
        circle = _spline([tuple(start)] + way + [tuple(stop)], ends[1][0], ends[1][1])
        crossed = [a_before, lobe_b]
    found = [_planar_hits(circle, piece) for piece in crossed]
    hits = sorted(h for f in found for h in f)
    if spec.route == "B":
        ok = len(hits) == 2 and hits[0][1] > 0 > hits[1][1]
    else:
        ok = [len(f) for f in found] == [1, 2] and hits[0] == found[0][0]
    if not ok:
        raise EmbeddingError(f"internal: the circle of {spec} crosses the 8 "
                             f"{[len(f) for f in found]} times, not as designed")
    sc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(circle, axis=0), axis=1))])
    for (s0, _), o in zip(hits, spec.over, strict=True):
        circle[:, 2] += o * hop * _bump(sc, s0, 0.3)
    return pieces + [lobe_b, circle]


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------


def eighty_curve(spec: EightySpec, n_beads: int = 150) -> np.ndarray:
    """Smooth 80 of ``spec`` as a dense closed polyline (M, 3), last point not repeated.

    The lobes and the circle have fixed design sizes (lobes about 2 long); the twist boxes
    and the hops of the circle are sized in bonds of a chain of ``n_beads`` beads along the
    curve (helix radius 0.6, 2.6 per half-turn, hop 1.15), so that long boxes keep their
    strands apart.

    Raises
    ------
    EmbeddingError
        If the spec gives a link (``k`` of the wrong parity for the route: the circle closes
        on itself), or its point-braid is too long for the lobe.
    """
    unit = 23.5 / n_beads  # design length of one bond, refined below
    for _ in range(4):
        cycles = _cycles(_pieces(spec, unit))
        if len(cycles) != 1:
            parity = "an odd" if spec.route == "B" else "an even"
            raise EmbeddingError(
                f"the 80 {spec} is a {len(cycles)}-component link, not a knot (on route "
                f"{spec.route} the point-braid needs {parity} number k of half-turns)")
        poly = cycles[0]
        length = float(np.sum(np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)))
        if abs(length / n_beads - unit) < 0.01 * unit:  # sizes within 1 %: enough
            break
        unit = length / n_beads
    return poly


def eighty_chain(spec: EightySpec, n_beads: int = 150, d_min: float = D_MIN) -> np.ndarray:
    """Closed unit-bond chain of ``n_beads`` beads along the 80 of ``spec`` (type not checked).

    ``n_beads`` beads N of bond length 1, no two non-bonded beads closer than ``d_min``
    (paper: 1/√2). Raises EmbeddingError if the spec gives a link, or the chain cannot be made
    with ``n_beads`` beads, unit bonds, safe chords, non-adjacent bead distances ≥ ``d_min``
    and distances ≥ ``d_min`` between bonds that share no bead (so that the chain is a valid
    start under both the bead and the tube exclusion rules of
    :class:`~stiffknots.engine.params.MoveParams`).
    """
    poly = eighty_curve(spec, int(n_beads))
    x = _scaled_chain(poly, int(n_beads))
    rep = None if x is None else embedding_report(x)
    if rep is None or not rep.ok(d_min) or rep.min_segment_distance < d_min:
        raise EmbeddingError(f"the 80 {spec} cannot be embedded with n_beads={n_beads}")
    return x


def eighty_specs(max_crossings: int = _MAX_DIAGRAM, *, chiral: bool = False,
                 free: bool = False) -> list[EightySpec]:
    """The knot-giving specs, one per knot-type class, in the order :func:`find_eighty` tries.

    Route B: every ``j ≥ 1`` (centre half-turns before the clasp) with the smallest odd
    ``c ≥ j`` (``c = j`` or ``j + 1``: the extra half-turn beyond the clasp only keeps the 8
    an 8) and every odd ``k``, ``j + k + 2 ≤ max_crossings``. Route X: odd ``c``, even ``k``,
    ``c + k + 3 ≤ max_crossings``. Ordered by ``j`` (the paper's 80, a plain centre crossing,
    first), then route (B first), ``k``, ``sk`` (+1 first) and ``over``.

    Parameters
    ----------
    max_crossings : int
        Largest diagram size :attr:`EightySpec.essential_crossings` (crossings once the
        half-turns beyond the clasp are undone).
    chiral : bool
        Also list ``sc = −1`` (the mirror images, which
        :func:`~stiffknots.knots.identify.identify` does not tell apart from ``sc = +1``).
    free : bool
        Also list the free circles, all ``over`` equal (torus knots T(2, k) on route B).
    """
    overs_b = [(1, -1), (-1, 1)] + ([(1, 1), (-1, -1)] if free else [])
    overs_x = [o for o in itertools.product((-1, 1), repeat=3) if free or len(set(o)) > 1]
    signs = (1, -1) if chiral else (1,)
    out = []
    for j in range(1, max_crossings - 2):
        c = j if j % 2 else j + 1
        for k in range(1, max_crossings - j - 1, 2):
            for sc, sk, over in itertools.product(signs, (1, -1), overs_b):
                out.append(EightySpec(c, k, sc, sk, over, None if j == c else j))
        if j % 2:
            for k in range(2, max_crossings - j - 2, 2):
                for sc, sk, over in itertools.product(signs, (1, -1), overs_x):
                    out.append(EightySpec(c, k, sc, sk, over, route="X"))
    return out


def eighty_table(max_crossings: int = 8, n_beads: int = 150,
                 free: bool = True) -> list[tuple[EightySpec, str]]:
    """(spec, knot) for every spec of :func:`eighty_specs` (``sc = +1``), the knot identified
    (HOMFLY-PT, mirror-insensitive) on the ``n_beads`` chain; ``'no chain'`` where the chain
    cannot be built. Slow: about 0.3 s per spec."""
    from stiffknots.knots.identify import identify

    rows = []
    for spec in eighty_specs(max_crossings, free=free):
        try:
            rows.append((spec, identify(eighty_chain(spec, n_beads))))
        except EmbeddingError:
            rows.append((spec, "no chain"))
    return rows


@functools.cache
def _curve_knot(spec: EightySpec) -> str:
    """Knot type of the smooth curve of ``spec`` (300-gon inscribed in it; a quick filter,
    the chain itself is checked by :func:`find_eighty`)."""
    from stiffknots.knots.identify import identify

    poly = eighty_curve(spec)
    return identify(poly[np.linspace(0, len(poly), 300, endpoint=False).astype(int)])


@functools.cache
def _spec_for(name: str, n_beads: int, max_crossings: int) -> EightySpec | None:
    """The search of :func:`find_eighty` (its answer, None included), kept in the disk cache
    (``stiffknots._diskcache``) under the knot, N, the diagram limit and the sources it
    depends on: it identifies up to ~140 curves (2–5 s a knot, 36 s for a chain too short
    for every spec), which every process of a sweep and every `anneal` of a knot of the 80
    family repeated."""
    from stiffknots._diskcache import cached, source_key

    here = Path(__file__).resolve().parent
    key = source_key("eighty-spec", name, str(n_beads), str(max_crossings),
                     files=tuple(str(here / f) for f in ("eighty_embedding.py", "identify.py",
                                                         "embedding.py", "catalogue.py")))
    return cached("eighty-spec", key, lambda: _search_spec(name, n_beads, max_crossings))


def _search_spec(name: str, n_beads: int, max_crossings: int) -> EightySpec | None:
    from stiffknots.knots.identify import crossing_number_of_name, normalize_name, verify_knot

    want = normalize_name(name)
    need = crossing_number_of_name(want)
    for spec in eighty_specs(max_crossings):
        if spec.essential_crossings < need:
            continue
        try:
            if want not in _curve_knot(spec).split("|"):
                continue
            x = eighty_chain(spec, n_beads)
        except EmbeddingError:  # a braid too long for its lobe, a chain that does not fit
            continue
        if verify_knot(x, want)[0]:
            return spec
    return None


def find_eighty(knot, n_beads: int = 150,
                max_crossings: int = _MAX_DIAGRAM) -> tuple[EightySpec, np.ndarray]:
    """The first spec of :func:`eighty_specs` whose chain is ``knot``, and that chain.

    Parameters
    ----------
    knot : Knot or str
        A catalogue entry (:func:`stiffknots.knots.catalogue.get_knot`) or a knot name.
    n_beads : int
        Number of beads N.
    max_crossings : int
        Search the specs of :func:`eighty_specs` up to this diagram size ``j + k + 2``.

    Returns
    -------
    spec : EightySpec
    coords : ndarray, shape (n_beads, 3)
        Unit bonds, non-adjacent beads and bonds ≥ 1/√2 apart, knot type verified
        (HOMFLY-PT, mirror-insensitive).

    Raises
    ------
    EmbeddingError
        If no spec of :func:`eighty_specs` (diagrams of ``j + k + 2 ≤ max_crossings``) gives
        the knot with ``n_beads`` beads (knots of bridge number > 2 are refused at once: the
        family holds two-bridge knots only). The spec found (or its absence) is cached per
        knot name and bead number.
    """
    if isinstance(knot, str):
        from stiffknots.knots.catalogue import get_knot

        knot = get_knot(knot)
    name = knot.name
    spec = _spec_of(knot, n_beads, max_crossings)
    if spec is None:
        raise EmbeddingError(
            f"{name} has no 80 start with n_beads={n_beads}: it is not in the searched 80 "
            "family (a figure eight with a circle along one lobe — centre twist j, "
            f"point-braid k, clasp — with j + k + 2 ≤ {max_crossings} crossings: the two-bridge "
            "knots [±k, ±j, ±2], e.g. 5_2, 6_2, 6_3, 7_5; not 7_4 or 7_7)")
    return spec, eighty_chain(spec, n_beads)


def _spec_of(knot, n_beads: int, max_crossings: int = _MAX_DIAGRAM) -> EightySpec | None:
    """The spec of :func:`find_eighty` for a catalogue entry, or None. Every member of the
    family is a two-bridge knot: others are refused without a search."""
    two_bridge = knot.bridge_number_range is None or knot.bridge_number_range[0] <= 2
    return _spec_for(knot.name, int(n_beads), int(max_crossings)) if two_bridge else None


def has_eighty(knot, n_beads: int = 150) -> bool:
    """Does :func:`find_eighty` find an 80 of the catalogue entry ``knot`` at ``n_beads``
    beads? Its spec search alone (kept in the disk cache), without building the chain: a spec
    is found only when its chain was built and its knot type verified."""
    return _spec_of(knot, n_beads) is not None


def embed_eighty(knot, n_beads: int = 150) -> np.ndarray:
    """Closed unit-bond chain of ``knot`` shaped as an 80 (paper §VII), knot type verified.

    Parameters
    ----------
    knot : Knot
        A catalogue entry (:func:`stiffknots.knots.catalogue.get_knot`); a name also works.
    n_beads : int
        Number of beads N (bond length 1).

    Raises
    ------
    EmbeddingError
        If the knot is not in the 80 family (see :func:`find_eighty`).
    """
    return find_eighty(knot, n_beads)[1]
