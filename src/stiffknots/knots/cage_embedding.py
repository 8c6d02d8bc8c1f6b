"""Embedding of two-twist rational knots as a 4-fold cage (paper §VII, Figs. 7–8).

The paper's *4-fold cage* (4C) is the equilibrium shape of 4_1 and 5_2: a curve wrapped around
a sphere with two *point-braids* (contact zones) at opposite poles, joined by four arcs. Each
point-braid is a twist box of the knot diagram: the two strands that pass through it twist
around each other. The conjectured 4C family of the paper (its Fig. 8, "the boxes account for
twists with an arbitrary number of turns") is the family of rational knots with a two-box
Conway notation ``[a b]``: 4_1 = [22], 5_2 = [32], 6_1 = [42], 7_2 = [52], 7_3 = [43], …

A braid closure (:mod:`stiffknots.knots.embedding`) starts the annealing near a circular braid,
from which the Monte Carlo search reaches the 80 or a circular braid far more often than the
cage. This module builds a start that already has the cage's structure, so that the search
can also explore the cage's basin: the resulting shape and energy are the annealing's, the
start only chooses the basin.

Geometry of the smooth curve (sphere of radius 1 before scaling)
----------------------------------------------------------------
* Box A at the north pole (0, 0, 1): two strands run along y ∈ [−t_a, t_a] on a helix of
  radius r around the y axis, making ``a`` half-turns (sign ``sa``); at each end of the box the
  two strands sit at x = ±r.
* Box B at the south pole (0, 0, −1): two strands along x ∈ [−t_b, t_b], helix around the x
  axis, ``b`` half-turns (sign ``sb``); at each end the strands sit at y = ±r.
* Four arcs, one per quadrant (sign x, sign y): the arc of quadrant (sx, sy) leaves the end of
  box A at (sx·r, sy·t_a, 1) along +sy·y and enters the end of box B at (sx·t_b, sy·r, −1)
  along −sx·x (a cubic Hermite curve bulging out to the equator).

The eight box ends each meet one box strand and one arc, so the curve is a union of cycles;
the twist parities decide how many. Which (a, b, signs) gives which knot is not assumed: the
chain is built, resampled with unit bonds, checked (bonds, exclusion, chords safe) and its knot
type is identified (HOMFLY-PT) by :func:`embed_cage` against the requested knot.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from stiffknots.knots.embedding import (
    D_MIN,
    EmbeddingError,
    _chord_deviation,
    _isotopy_safe,
    _resample,
    embedding_report,
)

__all__ = ["CageSpec", "cage_curve", "cage_spec_for", "embed_cage", "two_box_conway"]

_SAMPLES_BOX = 120  # polyline samples per box strand
_SAMPLES_ARC = 200  # polyline samples per arc


@dataclass(frozen=True)
class CageSpec:
    """Twist counts and handedness of the two boxes of a 4-fold cage.

    Attributes
    ----------
    a, b : int
        Number of half-turns (crossings) of box A (north pole) and box B (south pole), ≥ 1.
    sa, sb : int
        Handedness of each box's twist, +1 or −1.
    """

    a: int
    b: int
    sa: int = 1
    sb: int = 1


def two_box_conway(conway: str | None, crossings: int | None = None) -> tuple[int, int] | None:
    """The two twist counts of a KnotInfo Conway notation of two boxes (e.g. '[32]' → (3, 2),
    '[10 2]' → (10, 2)).

    KnotInfo writes ``[ab]`` without a separator when both counts are single digits and
    separates them by a space otherwise ('[10 2]', '[8 4]', '[6 6]' at 12 crossings). The
    digits of an unseparated body are ambiguous for a one-box knot of ten or more crossings:
    '[11]' is the (2, 11) torus knot, not [1 1]; with ``crossings`` (the knot's crossing
    number) the counts must add up to it, which tells these apart.

    Returns ``None`` for any other notation (one box, three or more boxes, non-rational).
    """
    if not conway:
        return None
    s = conway.strip()
    if not (s.startswith("[") and s.endswith("]")):
        return None
    parts = s[1:-1].split()
    if len(parts) == 1 and len(parts[0]) == 2 and parts[0].isdigit():
        a, b = int(parts[0][0]), int(parts[0][1])
    elif len(parts) == 2 and all(p.isdigit() for p in parts):
        a, b = int(parts[0]), int(parts[1])
    else:
        return None
    if a < 1 or b < 1 or (crossings is not None and a + b != crossings):
        return None
    return a, b


def _box(spec_turns: int, sign: int, t: float, r: float, along: str, z: float, n: int):
    """The two strands of a twist box: list of two (n, 3) arrays, oriented along + axis."""
    u = np.linspace(-t, t, n)
    phi = sign * spec_turns * np.pi * (u + t) / (2 * t)
    strands = []
    for s in (0, 1):
        c = r * np.cos(phi + s * np.pi)
        h = z + r * np.sin(phi + s * np.pi)
        if along == "y":
            strands.append(np.column_stack([c, u, h]))
        else:
            strands.append(np.column_stack([u, c, h]))
    return strands


def _hermite(p0, t0, p1, t1, n):
    s = np.linspace(0.0, 1.0, n)[:, None]
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    return h00 * p0 + h10 * t0 + h01 * p1 + h11 * t1


def _cycles(pieces: list[np.ndarray]) -> list[np.ndarray]:
    """Chain open polyline pieces into closed polylines through their shared end points
    (every end point must be shared by exactly two piece ends)."""

    def key(p):
        return tuple(np.round(p, 9))

    ends: dict = {}
    for i, pc in enumerate(pieces):
        for e, p in ((0, pc[0]), (1, pc[-1])):
            ends.setdefault(key(p), []).append((i, e))
    if any(len(v) != 2 for v in ends.values()):
        raise EmbeddingError("internal: curve pieces do not meet in pairs")
    used = [False] * len(pieces)
    cycles = []
    for start in range(len(pieces)):
        if used[start]:
            continue
        cyc = []
        i, forward = start, True
        while not used[i]:
            used[i] = True
            pc = pieces[i] if forward else pieces[i][::-1]
            cyc.append(pc[:-1])
            (j, e), = [(j, e) for (j, e) in ends[key(pc[-1])] if j != i]
            i, forward = j, (e == 0)
        cycles.append(np.concatenate(cyc))
    return cycles


def cage_curve(spec: CageSpec, *, r: float = 0.09, pitch: float = 0.16,
               bulge: float = 5.0) -> list[np.ndarray]:
    """Smooth 4-fold cage as a list of closed polylines (one per component).

    Parameters
    ----------
    spec : CageSpec
        Twist counts and signs of the two boxes.
    r : float
        Helix radius of the boxes (half the strand separation), sphere radius 1.
    pitch : float
        Box length per half-turn.
    bulge : float
        Magnitude of the arcs' end tangents (larger: rounder arcs).
    """
    ta = 0.5 * pitch * spec.a
    tb = 0.5 * pitch * spec.b
    box_a = _box(spec.a, spec.sa, ta, r, "y", 1.0, _SAMPLES_BOX)
    box_b = _box(spec.b, spec.sb, tb, r, "x", -1.0, _SAMPLES_BOX)
    pieces = []
    for strand in box_a + box_b:
        pieces.append(strand)
    for sx, sy in itertools.product((1, -1), (1, -1)):
        p0 = np.array([sx * r, sy * ta, 1.0])
        p1 = np.array([sx * tb, sy * r, -1.0])
        t0 = bulge * np.array([0.0, sy, 0.0])
        t1 = bulge * np.array([-sx, 0.0, 0.0])
        pieces.append(_hermite(p0, t0, p1, t1, _SAMPLES_ARC))
    return _cycles(pieces)


def _scaled_chain(poly: np.ndarray, n_beads: int) -> np.ndarray | None:
    """Unit-bond closed chain of ``n_beads`` beads along ``poly`` scaled to fit exactly."""
    length = np.sum(np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1))

    def mismatch(s):
        _, d = _resample(poly * s, n_beads)
        return d

    s0 = n_beads / length
    lo, hi = 0.8 * s0, 1.25 * s0
    f_lo, f_hi = mismatch(lo), mismatch(hi)
    if not (np.isfinite(f_lo) and np.isfinite(f_hi)) or f_lo < 0 or f_hi > 0:
        return None
    s = brentq(mismatch, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    pts, d, segs = _resample(poly * s, n_beads, with_segments=True)
    if not np.isfinite(d):
        return None
    x = pts[:-1].copy()
    if not _isotopy_safe(x, _chord_deviation(poly * s, pts, segs)):
        return None
    return x


def cage_chain(spec: CageSpec, n_beads: int = 150, d_min: float = D_MIN) -> np.ndarray:
    """Closed unit-bond chain of a 4-fold cage (no knot identification; see :func:`embed_cage`).

    Raises
    ------
    EmbeddingError
        If the twist parities give a link (several components) or the chain cannot be made
        with ``n_beads`` beads at non-adjacent bead distance ≥ ``d_min``.
    """
    cycles = cage_curve(spec)
    if len(cycles) != 1:
        raise EmbeddingError(f"cage {spec} is a {len(cycles)}-component link, not a knot")
    x = _scaled_chain(cycles[0], int(n_beads))
    if x is None or not embedding_report(x).ok(d_min):
        raise EmbeddingError(f"cage {spec} cannot be embedded with n_beads={n_beads}")
    return x


def cage_spec_for(knot) -> CageSpec:
    """The cage of a knot whose KnotInfo Conway notation has two boxes ``[ab]``.

    The twist counts are (a, b) and both boxes twist the same way, which gives the rational
    knot [ab] (checked by :func:`embed_cage`: 4_1 = [22], 5_2 = [32], 6_1 = [42], …).

    Raises
    ------
    EmbeddingError
        If the knot is not in the two-box family (the message gives its Conway notation).
    """
    ab = two_box_conway(knot.conway_notation, knot.crossing_number)
    if ab is None:
        raise EmbeddingError(
            f"{knot.name} has Conway notation {knot.conway_notation or 'unknown'}; a 4-fold cage "
            "start exists only for two-box rational knots [ab] (4_1, 5_2, 6_1, 7_2, 7_3, …)")
    return CageSpec(*ab)


def embed_cage(knot, n_beads: int = 150, d_min: float = D_MIN) -> np.ndarray:
    """Closed unit-bond chain of ``knot`` shaped as a 4-fold cage, knot type verified.

    Parameters
    ----------
    knot : Knot
        A catalogue entry (:func:`stiffknots.knots.catalogue.get_knot`) of the two-box family.
    n_beads : int
        Number of beads N (bond length 1).
    d_min : float
        Smallest distance allowed between non-bonded beads (paper: 1/√2).

    Raises
    ------
    EmbeddingError
        If the knot has no two-box Conway notation, the chain does not fit in ``n_beads``, or
        the chain built is not the requested knot (never expected).
    """
    from stiffknots.knots.identify import verify_knot

    spec = cage_spec_for(knot)
    x = cage_chain(spec, n_beads, d_min)
    ok, found = verify_knot(x, knot.name)
    if not ok:
        raise EmbeddingError(f"the cage {spec} built for {knot.name} is {found}")
    return x
