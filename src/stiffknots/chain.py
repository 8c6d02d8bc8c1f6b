"""The chain: a closed (knot) or open polygon in space, its energies and its file formats.

A :class:`Chain` holds the bead coordinates of a discretised string (float64, shape ``(N, 3)``)
and whether it is closed (bead ``N-1`` joined to bead ``0``, so ``N`` bonds) or open (``N-1``
bonds). Its methods compute the quantities of Gallotti & Pierre-Louis, "Stiff knots" (PRE 2007):

* the discrete bending energy of §VII, ``E_d = C Σ_n (1 - u_n·u_{n+1})`` (unit bonds), which
  tends to the continuum energy ``E = (C/2) ∫ κ² ds`` (eq. e:E) for smooth curves;
* the normalised energy ``ε = E L / C`` (eq. e:epsilon), ``ε = E_d N / C`` for unit bonds;
* the total curvature ``κ̄ = ∫ κ ds`` (eq. e:total_curv), bounded below by ``2πn`` (Milnor,
  eq. e:bridge_k);
* the excess length ``L_e = ∫ ds - ∫ dz`` of an open knot (eq. e:excess_length);
* geometric diagnostics: radius of gyration, writhe (exact, Klenin & Langowski 2000), minimum
  distances between beads and between non-adjacent segments (the tube/bead exclusion of §II and
  §VII).

File formats (:func:`save` / :func:`load` dispatch on the suffix):

``.xyz``
    Plain text, one bead per line. Two dialects are written (and both, plus plain ``x y z``
    lines, are read):

    * ``dialect="topoly"`` (default): topoly's *nxyz* format, ``"i x y z"`` with a 1-based
      integer index, exactly what ``topoly`` writes itself. A closed chain repeats its first line
      (same index, same coordinates) at the end, which is how topoly recognises a closed chain
      (its ``check_close`` finds the arc returning to its first vertex). No header and no comment
      lines: topoly's format sniffing would misread them.
    * ``dialect="kymoknot"``: KymoKnot's input format, a first line with the number of lines that
      follow, then ``"x y z"`` lines separated by single spaces (KymoKnot tokenises on ``' '``
      only and refuses a fourth column). A ring repeats its first bead at the end (KymoKnot's
      ``KymoKnot_ring.x`` requires first and last lines to coincide; ``KymoKnot_linear.x``
      requires them to differ).

    No single file satisfies both readers (topoly would read KymoKnot's count line as a bead,
    KymoKnot rejects the index column), hence the two dialects. Floats are written with
    ``repr`` (shortest round-trip representation), so coordinates survive a round trip exactly.
    The xyz formats store no metadata; use ``.json`` or ``.npz`` for that.
``.json``
    ``{"format": "stiffknots-chain", "version": 1, "closed": ..., "coords": [[x, y, z], ...],
    "meta": {...}, "stiffknots_version": ...}``; exact float round trip.
``.npz``
    NumPy archive with ``coords``, ``closed`` and ``meta`` (a JSON string); no pickles.
``.obj``
    Wavefront OBJ polylines as written by ElasticKnots: ``v x y z`` vertex lines and ``l i j ...``
    line elements (1-based, negative indices relative). Reading orders the vertices along the
    line elements and detects closure; writing emits one ``l i i+1`` element per bond.

Unreadable or corrupt files raise :class:`ChainFormatError` (a ``ValueError``) naming the file
and what was wrong.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from stiffknots._version import __version__
from stiffknots.geometry import seg_dist2

__all__ = [
    "Chain",
    "ChainFormatError",
    "regular_polygon",
    "save",
    "load",
    "to_xyz",
    "from_xyz",
    "to_json",
    "from_json",
    "to_npz",
    "from_npz",
    "to_obj",
    "from_obj",
]

FORMAT_NAME = "stiffknots-chain"
FORMAT_VERSION = 1

PathLike = str | os.PathLike


class ChainFormatError(ValueError):
    """A chain file that cannot be read: missing, corrupt, or not in the expected format."""


# --------------------------------------------------------------------------------------------
# compiled kernels (arrays and numbers only)
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _vertex_terms(coords, closed):
    """Turning angle, ``1 - cos`` of it and mean adjacent bond length at every bending vertex.

    Closed chains: vertex ``i`` (all ``N``) sits between bonds ``i-1 -> i`` and ``i -> i+1``
    (cyclic). Open chains: interior vertices ``1 .. N-2`` only.
    Returns three arrays (theta, one_minus_cos, mean_bond).
    """
    n = coords.shape[0]
    if closed:
        nv = n
        first = 0
    else:
        nv = n - 2
        first = 1
    theta = np.empty(nv)
    omc = np.empty(nv)
    lbar = np.empty(nv)
    for k in range(nv):
        i = k + first
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        ax = coords[i, 0] - coords[im, 0]
        ay = coords[i, 1] - coords[im, 1]
        az = coords[i, 2] - coords[im, 2]
        bx = coords[ip, 0] - coords[i, 0]
        by = coords[ip, 1] - coords[i, 1]
        bz = coords[ip, 2] - coords[i, 2]
        la = math.sqrt(ax * ax + ay * ay + az * az)
        lb = math.sqrt(bx * bx + by * by + bz * bz)
        cx = ay * bz - az * by
        cy = az * bx - ax * bz
        cz = ax * by - ay * bx
        theta[k] = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)
        # 1 - u_a.u_b computed as |u_a - u_b|^2 / 2 (same value, no cancellation when straight)
        dx = ax / la - bx / lb
        dy = ay / la - by / lb
        dz = az / la - bz / lb
        omc[k] = 0.5 * (dx * dx + dy * dy + dz * dz)
        lbar[k] = 0.5 * (la + lb)
    return theta, omc, lbar


@njit(cache=True)
def _bending_energy(coords, closed):
    """Σ_vertices (1 - u_a·u_b) / b̄ (times C outside); = E_d/C of §VII for unit bonds."""
    theta, omc, lbar = _vertex_terms(coords, closed)
    e = 0.0
    for k in range(omc.shape[0]):
        e += omc[k] / lbar[k]
    return e


@njit(cache=True)
def _writhe(coords, closed):
    """Writhe of a polygon by the exact Gauss integral (Klenin & Langowski, Biopolymers 2000).

    Each pair of non-adjacent segments (p1 p2), (p3 p4) contributes the signed solid angle
    Ω = ±Σ asin(n_k · n_{k+1}) of the quadrilateral of unit normals
    n1 ∝ r13×r14, n2 ∝ r14×r24, n3 ∝ r24×r23, n4 ∝ r23×r13, with sign of (r34×r12)·r13;
    Wr = Σ_{i≠j} Ω_ij / 4π = Σ_{i<j} Ω_ij / 2π. Adjacent segments are coplanar and give 0.
    ``asin(n_a·n_b)`` is evaluated as ``π/2 - atan2(|n_a×n_b|, n_a·n_b)`` for accuracy.
    """
    n = coords.shape[0]
    nseg = n if closed else n - 1
    half_pi = 0.5 * math.pi
    nv = np.empty((4, 3))
    total = 0.0
    for i in range(nseg):
        i2 = i + 1 if i + 1 < n else 0
        p1x, p1y, p1z = coords[i, 0], coords[i, 1], coords[i, 2]
        p2x, p2y, p2z = coords[i2, 0], coords[i2, 1], coords[i2, 2]
        for j in range(i + 2, nseg):
            if closed and i == 0 and j == nseg - 1:
                continue
            j2 = j + 1 if j + 1 < n else 0
            p3x, p3y, p3z = coords[j, 0], coords[j, 1], coords[j, 2]
            p4x, p4y, p4z = coords[j2, 0], coords[j2, 1], coords[j2, 2]
            r13x, r13y, r13z = p3x - p1x, p3y - p1y, p3z - p1z
            r14x, r14y, r14z = p4x - p1x, p4y - p1y, p4z - p1z
            r23x, r23y, r23z = p3x - p2x, p3y - p2y, p3z - p2z
            r24x, r24y, r24z = p4x - p2x, p4y - p2y, p4z - p2z
            # n1 = r13 x r14
            nv[0, 0] = r13y * r14z - r13z * r14y
            nv[0, 1] = r13z * r14x - r13x * r14z
            nv[0, 2] = r13x * r14y - r13y * r14x
            # n2 = r14 x r24
            nv[1, 0] = r14y * r24z - r14z * r24y
            nv[1, 1] = r14z * r24x - r14x * r24z
            nv[1, 2] = r14x * r24y - r14y * r24x
            # n3 = r24 x r23
            nv[2, 0] = r24y * r23z - r24z * r23y
            nv[2, 1] = r24z * r23x - r24x * r23z
            nv[2, 2] = r24x * r23y - r24y * r23x
            # n4 = r23 x r13
            nv[3, 0] = r23y * r13z - r23z * r13y
            nv[3, 1] = r23z * r13x - r23x * r13z
            nv[3, 2] = r23x * r13y - r23y * r13x
            degenerate = False
            for k in range(4):
                nn = math.sqrt(nv[k, 0] ** 2 + nv[k, 1] ** 2 + nv[k, 2] ** 2)
                if nn <= 1e-300:
                    degenerate = True
                    break
                nv[k, 0] /= nn
                nv[k, 1] /= nn
                nv[k, 2] /= nn
            if degenerate:
                continue
            # sign: (r34 x r12) . r13
            r12x, r12y, r12z = p2x - p1x, p2y - p1y, p2z - p1z
            r34x, r34y, r34z = p4x - p3x, p4y - p3y, p4z - p3z
            sx = r34y * r12z - r34z * r12y
            sy = r34z * r12x - r34x * r12z
            sz = r34x * r12y - r34y * r12x
            s = sx * r13x + sy * r13y + sz * r13z
            if s == 0.0:
                continue
            omega = 0.0
            for k in range(4):
                a = k
                b = (k + 1) % 4
                d = nv[a, 0] * nv[b, 0] + nv[a, 1] * nv[b, 1] + nv[a, 2] * nv[b, 2]
                cx = nv[a, 1] * nv[b, 2] - nv[a, 2] * nv[b, 1]
                cy = nv[a, 2] * nv[b, 0] - nv[a, 0] * nv[b, 2]
                cz = nv[a, 0] * nv[b, 1] - nv[a, 1] * nv[b, 0]
                omega += half_pi - math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), d)
            if s > 0.0:
                total += omega
            else:
                total -= omega
    return total / (2.0 * math.pi)


@njit(cache=True)
def _min_bead_distance(coords, closed, min_sep):
    """Minimum distance between beads i, j with index separation >= min_sep (cyclic if closed).

    Returns +inf when no pair qualifies.
    """
    n = coords.shape[0]
    best = np.inf
    for i in range(n):
        for j in range(i + min_sep, n):
            if closed and n - (j - i) < min_sep:
                continue
            dx = coords[i, 0] - coords[j, 0]
            dy = coords[i, 1] - coords[j, 1]
            dz = coords[i, 2] - coords[j, 2]
            d2 = dx * dx + dy * dy + dz * dz
            if d2 < best:
                best = d2
    return math.sqrt(best)


@njit(cache=True)
def _min_segment_distance(coords, closed):
    """Minimum distance between segments sharing no bead; +inf when there is no such pair."""
    n = coords.shape[0]
    nseg = n if closed else n - 1
    best = np.inf
    for i in range(nseg):
        i2 = i + 1 if i + 1 < n else 0
        for j in range(i + 2, nseg):
            if closed and i == 0 and j == nseg - 1:
                continue
            j2 = j + 1 if j + 1 < n else 0
            d2 = seg_dist2(
                coords[i, 0], coords[i, 1], coords[i, 2],
                coords[i2, 0], coords[i2, 1], coords[i2, 2],
                coords[j, 0], coords[j, 1], coords[j, 2],
                coords[j2, 0], coords[j2, 1], coords[j2, 2],
            )  # fmt: skip
            if d2 < best:
                best = d2
    return math.sqrt(best)


# --------------------------------------------------------------------------------------------
# the Chain
# --------------------------------------------------------------------------------------------


def _as_coords(coords: Any) -> np.ndarray:
    try:
        arr = np.array(coords, dtype=np.float64, order="C", copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"chain coordinates must be numbers, shape (N, 3): {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"chain coordinates must have shape (N, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise ValueError(f"chain coordinates must be finite; bead {bad} is {arr[bad].tolist()}")
    return arr


@dataclass(eq=False)
class Chain:
    """A closed or open polygonal chain of beads.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead positions; stored as a C-contiguous float64 copy.
    closed : bool, default True
        Closed chain (a knot: ``N`` bonds, bead ``N-1`` bonded to bead ``0``) or open chain
        (``N-1`` bonds).
    meta : dict
        Free metadata (knot name, seed, parameters, package version, ...); stored with the
        chain by the JSON and NPZ formats.

    Raises
    ------
    ValueError
        Wrong shape, non-finite values, too few beads (3 closed, 2 open) or a zero-length bond.
    """

    coords: np.ndarray
    closed: bool = True
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.coords = _as_coords(self.coords)
        self.closed = bool(self.closed)
        if self.meta is None:
            self.meta = {}
        if not isinstance(self.meta, dict):
            raise ValueError(f"chain meta must be a dict, got {type(self.meta).__name__}")
        self.meta = dict(self.meta)
        n = self.coords.shape[0]
        nmin = 3 if self.closed else 2
        if n < nmin:
            kind = "closed" if self.closed else "open"
            raise ValueError(f"a {kind} chain needs at least {nmin} beads, got {n}")
        lengths = self.bond_lengths()
        if np.any(lengths == 0.0):
            k = int(np.argmin(lengths))
            hint = ""
            if self.closed and k == n - 1:
                hint = " (a closed chain must not repeat its first bead at the end)"
            raise ValueError(f"bond {k} (beads {k} and {(k + 1) % n}) has zero length{hint}")

    # -- basic geometry -----------------------------------------------------------------------

    def __len__(self) -> int:
        return self.coords.shape[0]

    @property
    def n_beads(self) -> int:
        """Number of beads ``N``."""
        return self.coords.shape[0]

    @property
    def n_bonds(self) -> int:
        """Number of bonds: ``N`` closed, ``N-1`` open."""
        return self.n_beads if self.closed else self.n_beads - 1

    def copy(self) -> Chain:
        """An independent copy (coordinates and metadata)."""
        meta = json.loads(json.dumps(self.meta, default=_json_default))
        return Chain(self.coords.copy(), self.closed, meta)

    def bond_vectors(self) -> np.ndarray:
        """Bond vectors ``r_{n+1} - r_n``, shape ``(N, 3)`` closed (last: ``r_0 - r_{N-1}``) or
        ``(N-1, 3)`` open."""
        x = self.coords
        if self.closed:
            return np.roll(x, -1, axis=0) - x
        return x[1:] - x[:-1]

    def bond_lengths(self) -> np.ndarray:
        """Bond lengths (``N`` values closed, ``N-1`` open)."""
        return np.linalg.norm(self.bond_vectors(), axis=1)

    @property
    def length(self) -> float:
        """Contour length ``L = ∫ ds`` (eq. e:length): sum of bond lengths (``= N`` for a closed
        unit-bond chain)."""
        return float(np.sum(self.bond_lengths()))

    # -- energies -----------------------------------------------------------------------------

    def energy(self, C: float = 1.0) -> float:
        """Discrete bending energy.

        For unit bonds this is exactly the paper's §VII energy

        .. math:: E_d = C \\sum_n (1 - u_n \\cdot u_{n+1}),

        summed cyclically over all ``N`` vertices of a closed chain, and over the ``N-2``
        interior vertices of an open chain. For bonds of arbitrary length ``b`` each vertex
        term is divided by the mean length ``b̄`` of its two bonds,
        ``E = C Σ (1 - u_a·u_b) / b̄``; since ``1 - cos θ ≈ θ²/2`` and ``θ ≈ κ b̄``, this tends to
        the continuum energy ``(C/2) ∫ κ² ds`` (eq. e:E) for smooth curves, and equals ``E_d``
        when all bonds are 1 (the weight is then ``1``).
        """
        _check_C(C)
        return float(C * _bending_energy(self.coords, self.closed))

    def epsilon(self, C: float = 1.0) -> float:
        """Normalised energy ``ε = E L / C`` (eq. e:epsilon); ``ε = E_d N / C`` for a closed
        unit-bond chain (§VII). Independent of ``C`` and of the chain's scale."""
        _check_C(C)
        return self.energy(C) * self.length / C

    def turning_angles(self) -> np.ndarray:
        """Angle ``θ_i ∈ [0, π]`` between the two bonds meeting at each bending vertex.

        ``N`` values for a closed chain (vertex ``i`` between bonds ``i-1`` and ``i``, cyclic),
        ``N-2`` for an open chain (interior beads ``1 .. N-2``).
        """
        return _vertex_terms(self.coords, self.closed)[0]

    def curvature(self) -> np.ndarray:
        """Discrete curvature at each bending vertex: ``κ_i = θ_i / b̄_i``, turning angle over the
        mean length of the two adjacent bonds (same vertices as :meth:`turning_angles`).

        With this choice ``Σ κ_i b̄_i`` is exactly the total curvature (eq. e:total_curv); for a
        regular polygon inscribed in a circle of radius ``R`` it tends to ``1/R``.
        """
        theta, _, lbar = _vertex_terms(self.coords, self.closed)
        return theta / lbar

    def total_curvature(self) -> float:
        """Total curvature ``κ̄ = ∫ κ ds`` (eq. e:total_curv) = ``Σ θ_i`` for a polygon.

        Milnor (eq. e:bridge_k): ``κ̄ ≥ 2πn`` for a knot of bridge number ``n`` (Fáry–Milnor for
        polygons too); ``= 2π`` for a convex planar polygon.
        """
        return float(np.sum(self.turning_angles()))

    # -- shape diagnostics --------------------------------------------------------------------

    def radius_of_gyration(self) -> float:
        """Radius of gyration of the beads, ``sqrt(mean_i |r_i - r_cm|²)`` (equal bead masses)."""
        x = self.coords
        d = x - x.mean(axis=0)
        return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))

    def writhe(self) -> float:
        """Writhe ``Wr = (1/4π) ∮∮ (dr₁ × dr₂)·(r₁ - r₂)/|r₁ - r₂|³``, exact for the polygon.

        Sum of signed solid angles over non-adjacent segment pairs (Klenin & Langowski,
        Biopolymers 54, 307 (2000)); O(N²). For an open chain this is the same double integral
        over the open polygon (not a topological quantity). Changes sign under reflection.
        """
        return float(_writhe(self.coords, self.closed))

    def min_bead_distance(self, min_separation: int = 2) -> float:
        """Minimum distance between beads ``i, j`` whose index distance is ``>= min_separation``.

        Index distance is cyclic for a closed chain (``min(|i-j|, N-|i-j|)``), plain ``|i-j|``
        for an open one. With the default ``2`` bonded neighbours are excluded; this is the
        quantity constrained by the bead exclusion of §VII (beads no closer than ``1/√2``).
        Returns ``inf`` if no pair qualifies.
        """
        ms = int(min_separation)
        if ms != min_separation or ms < 1:
            raise ValueError(f"min_separation must be an integer >= 1, got {min_separation!r}")
        return float(_min_bead_distance(self.coords, self.closed, ms))

    def min_segment_distance(self) -> float:
        """Minimum distance between non-adjacent segments (segments sharing no bead).

        The tube of diameter ``w`` around the polygon (§II) does not self-intersect only if this
        is ``>= w`` (a necessary condition). Returns ``inf`` if there is no such pair (``N = 3``).
        """
        return float(_min_segment_distance(self.coords, self.closed))

    def excess_length(self, axis: Any = (0.0, 0.0, 1.0)) -> float:
        """Excess length ``L_e = ∫ ds - ∫ dz`` (eq. e:excess_length) along ``axis``.

        Contour length minus the signed projection of the end-to-end vector
        ``r_{N-1} - r_0`` on the unit vector ``axis`` (the direction of the straight ends of an
        open knot, the chain running towards ``+axis``). For a closed chain ``∫ dz = 0`` and
        ``L_e = L``.
        """
        a = np.asarray(axis, dtype=np.float64).reshape(-1)
        if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.any(a):
            raise ValueError(f"axis must be a finite non-zero 3-vector, got {axis!r}")
        a = a / np.linalg.norm(a)
        if self.closed:
            return self.length
        return float(self.length - np.dot(self.coords[-1] - self.coords[0], a))

    # -- dict form ----------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """JSON-ready dict of the ``stiffknots-chain`` format (see :func:`to_json`)."""
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "stiffknots_version": __version__,
            "closed": self.closed,
            "coords": self.coords.tolist(),
            "meta": self.meta,
        }

    @classmethod
    def from_dict(cls, d: Any, *, source: str = "<dict>") -> Chain:
        """Chain from a dict of the ``stiffknots-chain`` format; ChainFormatError if invalid."""
        if not isinstance(d, dict):
            raise ChainFormatError(f"{source}: expected a JSON object, got {type(d).__name__}")
        fmt = d.get("format")
        if fmt != FORMAT_NAME:
            raise ChainFormatError(f"{source}: 'format' is {fmt!r}, expected {FORMAT_NAME!r}")
        ver = d.get("version")
        if not isinstance(ver, int) or isinstance(ver, bool) or not 1 <= ver <= FORMAT_VERSION:
            raise ChainFormatError(
                f"{source}: unsupported format version {ver!r} "
                f"(this stiffknots reads 1..{FORMAT_VERSION})"
            )
        if "coords" not in d:
            raise ChainFormatError(f"{source}: missing 'coords'")
        closed = d.get("closed", True)
        if not isinstance(closed, bool):
            raise ChainFormatError(f"{source}: 'closed' must be true or false, got {closed!r}")
        meta = d.get("meta", {})
        if meta is None:
            meta = {}
        if not isinstance(meta, dict):
            raise ChainFormatError(f"{source}: 'meta' must be an object, got {type(meta).__name__}")
        coords = d["coords"]
        if not isinstance(coords, list) or not all(
            isinstance(row, list)
            and len(row) == 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
            for row in coords
        ):
            raise ChainFormatError(f"{source}: 'coords' must be a list of [x, y, z] number triples")
        try:
            return cls(np.array(coords, dtype=np.float64).reshape(-1, 3), closed, meta)
        except ValueError as exc:
            raise ChainFormatError(f"{source}: invalid chain: {exc}") from None


def _check_C(C: float) -> None:
    if not (isinstance(C, (int, float, np.floating, np.integer)) and math.isfinite(C) and C > 0):
        raise ValueError(f"bending rigidity C must be a positive finite number, got {C!r}")


# --------------------------------------------------------------------------------------------
# convenience constructors
# --------------------------------------------------------------------------------------------


def regular_polygon(n: int, m: int = 1, amplitude: float | None = None) -> Chain:
    """An ``m``-times covered circle with ``n`` beads and unit bonds (closed).

    ``m = 1``: the planar regular ``n``-gon of circumradius ``R = 1/(2 sin(π/n))``; its
    normalised energy is ``ε = n²(1 - cos(2π/n)) → 2π²`` (the circle, §III).

    ``m ≥ 2``: the circular braid of index ``m`` (§V, eq. e:epsilon*_CB, ``ε → 2π²m²``). The
    centre line winds ``m`` times around the ``z`` axis while going once around a thin torus
    tube of radius ``amplitude`` (a ``(m, 1)`` torus curve, an unknot), so the covers never
    touch: two covers at the same azimuth are ``2·amplitude·sin(π/m)`` apart. The beads are
    placed at equal chords along this curve (shooting on the chord length) and the curve is
    rescaled so every bond is 1 to ~1e-14.

    Parameters
    ----------
    n : int
        Number of beads (``>= 3``, and ``> 2m`` for ``m ≥ 2``; a few nearly degenerate star
        polygons with ``n`` close to ``2m`` are refused with a ``ValueError``).
    m : int, default 1
        Number of covers (winding number about the ``z`` axis).
    amplitude : float, optional
        Tube radius in bond units for ``m ≥ 2``; default ``min(0.5, R/10)`` with
        ``R = n/(2πm)`` the radius of the covered circle.
    """
    if int(n) != n or n < 3:
        raise ValueError(f"n must be an integer >= 3, got {n!r}")
    if int(m) != m or m < 1:
        raise ValueError(f"m must be an integer >= 1, got {m!r}")
    n, m = int(n), int(m)
    meta = {"shape": "regular_polygon", "n": n, "m": m}
    if m == 1:
        R = 0.5 / math.sin(math.pi / n)
        t = 2.0 * np.pi * np.arange(n) / n
        x = np.column_stack([R * np.cos(t), R * np.sin(t), np.zeros(n)])
        return Chain(x, True, meta)
    if n <= 2 * m:
        raise ValueError(f"an {m}-times covered circle needs n > 2m beads, got n={n}")
    Rc = n / (2.0 * math.pi * m)
    a = min(0.5, Rc / 10.0) if amplitude is None else float(amplitude)
    if not (math.isfinite(a) and 0.0 < a < Rc):
        raise ValueError(f"amplitude must be in (0, {Rc:.6g}), got {amplitude!r}")
    meta["amplitude"] = a
    x = _equal_chord_torus_curve(n, m, Rc, a)
    return Chain(x, True, meta)


def _equal_chord_torus_curve(n: int, m: int, R: float, a: float) -> np.ndarray:
    """n points at equal chords on c(t) = ((R + a cos t) e(m t) + a sin t z), t ∈ [0, 2π),
    rescaled to unit chords."""
    from scipy.optimize import brentq

    def c(t: float) -> np.ndarray:
        r = R + a * math.cos(t)
        return np.array([r * math.cos(m * t), r * math.sin(m * t), a * math.sin(t)])

    two_pi = 2.0 * math.pi
    dt0 = two_pi / n

    # a step never turns the azimuth m·t by π or more (n > 2m): beyond, the chord shrinks again
    t_max_step = 0.999 * math.pi / m

    def march(ell: float) -> np.ndarray:
        """Parameters of n successive beads at chord ell from t = 0; ts[n] = +big if ell is
        longer than any admissible step."""
        ts = np.empty(n + 1)
        ts[0] = 0.0
        for k in range(n):
            p = c(ts[k])

            def f(t: float, p: np.ndarray = p) -> float:
                return float(np.linalg.norm(c(t) - p)) - ell

            lo = ts[k]
            hi = lo + min(dt0, t_max_step)
            # the chord grows monotonically with t on a step of azimuth < π; bracket the root
            at_max = hi >= lo + t_max_step
            while f(hi) < 0.0:
                if at_max:
                    ts[n] = 1e3
                    return ts
                hi = hi + 0.5 * dt0
                if hi >= lo + t_max_step:
                    hi, at_max = lo + t_max_step, True
            ts[k + 1] = brentq(f, lo, hi, xtol=1e-15, rtol=1e-15)
        return ts

    # the chord ell for which n steps return exactly to t = 2π; bracket around the chord of
    # the m-covered circle (the tube radius a <= R/10 changes it by a few per cent at most)
    ell0 = 2.0 * R * math.sin(math.pi * m / n)
    ell = brentq(lambda e: march(e)[n] - two_pi, 0.7 * ell0, 1.3 * ell0, xtol=1e-15, rtol=1e-15)
    ts = march(ell)[:n]
    pts = np.array([c(t) for t in ts])
    chords = np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)
    pts = pts / np.mean(chords)
    bonds = np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-10:
        raise ValueError(
            f"could not place n={n} beads at unit bonds on a {m}-times covered circle "
            f"(tube radius {a:.3g}); use more beads or a smaller amplitude"
        )
    return pts


# --------------------------------------------------------------------------------------------
# I/O
# --------------------------------------------------------------------------------------------


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    raise TypeError(
        f"chain meta value of type {type(obj).__name__} is not JSON-serialisable: {obj!r}"
    )


def _fmt(v: float) -> str:
    return repr(float(v))


def _read_text(path: PathLike) -> str:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.read()
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except UnicodeDecodeError:
        raise ChainFormatError(f"{path}: not a text file (cannot decode as UTF-8)") from None
    except OSError as exc:
        raise ChainFormatError(f"{path}: cannot read: {exc.strerror or exc}") from None


def _make_chain(coords: Any, closed: bool, meta: dict, path: PathLike) -> Chain:
    try:
        return Chain(coords, closed, meta)
    except ValueError as exc:
        raise ChainFormatError(f"{path}: invalid chain: {exc}") from None


def _ends_coincide(x: np.ndarray) -> bool:
    """First and last bead equal (exactly, or within KymoKnot's 1e-6 ring tolerance)."""
    return bool(np.array_equal(x[0], x[-1]) or np.linalg.norm(x[0] - x[-1]) < 1e-6)


def to_xyz(chain: Chain, path: PathLike, dialect: str = "topoly") -> None:
    """Write the bead coordinates as plain text.

    Parameters
    ----------
    chain : Chain
    path : str or path-like
    dialect : {"topoly", "kymoknot"}
        ``"topoly"``: lines ``"i x y z"`` (1-based index; topoly's nxyz format). ``"kymoknot"``:
        a count line then ``"x y z"`` lines (KymoKnot's input format). In both a closed chain
        repeats its first bead (and, for topoly, its index) as the last line. Floats are written
        with ``repr``: the round trip is exact. Metadata is not stored.
    """
    if dialect not in ("topoly", "kymoknot"):
        raise ValueError(f"unknown xyz dialect {dialect!r}; use 'topoly' or 'kymoknot'")
    x = chain.coords
    rows = [(i + 1, x[i]) for i in range(len(x))]
    if chain.closed:
        rows.append((1, x[0]))
    if dialect == "topoly":
        lines = [f"{i} {_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for i, p in rows]
    else:
        lines = [str(len(rows))] + [f"{_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for _, p in rows]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def from_xyz(path: PathLike, closed: bool | None = None, meta: dict | None = None) -> Chain:
    """Read a chain from an xyz text file (one configuration).

    Accepts topoly's nxyz lines ``"i x y z"``, plain ``"x y z"`` lines, and KymoKnot files (a
    first line with the count, optionally followed by a non-numeric title line as in its LAMMPS
    variant). Blank lines and ``#`` comments are skipped.

    Parameters
    ----------
    closed : bool, optional
        ``None`` (default): the chain is closed iff the last bead repeats the first (which is then
        dropped). ``True``/``False`` force it; with ``True`` a repeated closing bead is dropped.
    meta : dict, optional
        Metadata for the chain (the format stores none); ``{"source": path}`` by default.
    """
    text = _read_text(path)
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if not lines:
        raise ChainFormatError(f"{path}: empty xyz file (no bead lines)")
    count = None
    first = lines[0].split()
    if len(first) == 1:
        try:
            count = int(first[0])
        except ValueError:
            raise ChainFormatError(
                f"{path}, line 1: {lines[0]!r} is neither a bead line nor a bead count"
            ) from None
        lines = lines[1:]
        if lines and not _is_number(lines[0].split()[0]):
            lines = lines[1:]  # KymoKnot/LAMMPS title line
    rows = []
    ncol = None
    for k, ln in enumerate(lines):
        tok = ln.split()
        if tok in (["X"], ["END"]):
            raise ChainFormatError(
                f"{path}: contains several chains (separator {tok[0]!r}); only one is supported"
            )
        if len(tok) not in (3, 4):
            raise ChainFormatError(
                f"{path}: bead line {k + 1} {ln!r} has {len(tok)} columns, "
                "expected 'x y z' or 'i x y z'"
            )
        if ncol is None:
            ncol = len(tok)
        elif len(tok) != ncol:
            raise ChainFormatError(
                f"{path}: bead line {k + 1} {ln!r} has {len(tok)} columns, "
                f"earlier lines have {ncol}"
            )
        try:
            if ncol == 4:
                int(tok[0])
            rows.append([float(v) for v in tok[ncol - 3 :]])
        except ValueError:
            raise ChainFormatError(f"{path}: bead line {k + 1} {ln!r} is not numeric") from None
    if count is not None and count != len(rows):
        raise ChainFormatError(
            f"{path}: header announces {count} beads but {len(rows)} bead lines follow "
            "(several configurations in one file are not supported)"
        )
    if not rows:
        raise ChainFormatError(f"{path}: no bead lines")
    x = np.array(rows, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ChainFormatError(f"{path}: non-finite coordinates")
    repeated = len(x) >= 2 and _ends_coincide(x)
    is_closed = repeated if closed is None else bool(closed)
    if is_closed and repeated:
        x = x[:-1]
    return _make_chain(x, is_closed, {"source": os.fspath(path)} if meta is None else meta, path)


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def to_json(chain: Chain, path: PathLike, indent: int | None = None) -> None:
    """Write the ``stiffknots-chain`` JSON format (coordinates, closure, metadata; exact floats).

    ``{"format": "stiffknots-chain", "version": 1, "stiffknots_version": ..., "closed": ...,
    "coords": [[x, y, z], ...], "meta": {...}}``. NumPy scalars/arrays in ``meta`` are
    converted; other non-JSON values raise ``TypeError``.
    """
    text = json.dumps(chain.to_dict(), indent=indent, default=_json_default, allow_nan=False)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text + "\n")


def from_json(path: PathLike) -> Chain:
    """Read the ``stiffknots-chain`` JSON format written by :func:`to_json`."""
    text = _read_text(path)
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
    return Chain.from_dict(d, source=os.fspath(path))


def to_npz(chain: Chain, path: PathLike) -> None:
    """Write a NumPy ``.npz`` archive: ``coords`` (float64), ``closed`` (bool), ``meta`` (JSON
    string), ``format`` and ``version``. Written to ``path`` as given (no suffix added)."""
    meta = json.dumps(chain.meta, default=_json_default, allow_nan=False)
    with open(path, "wb") as fh:
        np.savez(
            fh,
            format=np.array(FORMAT_NAME),
            version=np.array(FORMAT_VERSION),
            stiffknots_version=np.array(__version__),
            coords=chain.coords,
            closed=np.array(chain.closed),
            meta=np.array(meta),
        )


def from_npz(path: PathLike) -> Chain:
    """Read an archive written by :func:`to_npz` (no pickles are loaded)."""
    try:
        with open(path, "rb") as fh:
            magic = fh.read(4)
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except OSError as exc:
        raise ChainFormatError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if magic[:2] != b"PK":
        raise ChainFormatError(f"{path}: not an npz archive (no zip signature)")
    try:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in ("coords", "closed") if k not in z.files]
            if missing:
                raise ChainFormatError(f"{path}: npz archive lacks {', '.join(missing)}")
            if "format" in z.files and str(z["format"]) != FORMAT_NAME:
                raise ChainFormatError(
                    f"{path}: npz 'format' is {str(z['format'])!r}, expected {FORMAT_NAME!r}"
                )
            coords = np.array(z["coords"])
            closed_arr = z["closed"]
            meta_s = str(z["meta"]) if "meta" in z.files else "{}"
    except ChainFormatError:
        raise
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError) as exc:
        raise ChainFormatError(f"{path}: not a readable npz archive ({exc})") from None
    if closed_arr.shape != () or closed_arr.dtype != np.bool_:
        raise ChainFormatError(f"{path}: 'closed' must be a boolean scalar")
    if coords.dtype.kind not in "fiu":
        raise ChainFormatError(f"{path}: 'coords' must be numeric, got dtype {coords.dtype}")
    try:
        meta = json.loads(meta_s)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(f"{path}: 'meta' is not valid JSON ({exc.msg})") from None
    if not isinstance(meta, dict):
        raise ChainFormatError(f"{path}: 'meta' must be a JSON object")
    return _make_chain(coords, bool(closed_arr), meta, path)


def to_obj(chain: Chain, path: PathLike) -> None:
    """Write a Wavefront OBJ polyline as ElasticKnots does: ``v x y z`` lines, then one
    ``l i i+1`` element per bond (1-based; a closed chain ends with ``l N 1``)."""
    x = chain.coords
    n = len(x)
    out = [f"v {_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for p in x]
    out += [f"l {i + 1} {i + 2}" for i in range(n - 1)]
    if chain.closed:
        out.append(f"l {n} 1")
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(out) + "\n")


def from_obj(path: PathLike, meta: dict | None = None) -> Chain:
    """Import a curve from a Wavefront OBJ file (ElasticKnots ``.obj`` centre lines).

    ``v x y z [w]`` lines give vertices; ``l i j k ...`` lines give polylines (1-based indices,
    negative ones relative to the vertices read so far, ``i/t`` forms allowed). The bonds of all
    line elements must form one simple path or one cycle; the vertices are ordered along it
    (from the lowest-index end of a path; a cycle starts at its lowest index and follows the
    direction in which its elements are written). A cycle gives a closed chain. A path whose end
    vertex repeats the coordinates of its start (a duplicated closing vertex) also gives a closed
    chain, the duplicate dropped. Without ``l`` lines the vertices are taken in file order
    (closed iff the last repeats the first). Vertices not on the line elements are ignored.
    Other OBJ statements (``vn``, ``vt``, ``o``, ``g``, ``s``, ``mtllib``, ...) are ignored;
    faces (``f``) are an error.
    """
    text = _read_text(path)
    verts: list[list[float]] = []
    succ: dict[int, list[int]] = {}
    edges: set[tuple[int, int]] = set()
    order_edges: list[tuple[int, int]] = []
    has_lines = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        ln = raw.split("#", 1)[0].strip()
        if not ln:
            continue
        tok = ln.split()
        kw = tok[0]
        if kw == "v":
            if len(tok) not in (4, 5):
                raise ChainFormatError(
                    f"{path}, line {lineno}: vertex line {raw.strip()!r} needs 'v x y z'"
                )
            try:
                p = [float(t) for t in tok[1:4]]
            except ValueError:
                raise ChainFormatError(
                    f"{path}, line {lineno}: non-numeric vertex {raw.strip()!r}"
                ) from None
            if not all(math.isfinite(v) for v in p):
                raise ChainFormatError(f"{path}, line {lineno}: non-finite vertex {raw.strip()!r}")
            verts.append(p)
        elif kw == "l":
            has_lines = True
            if len(tok) < 3:
                raise ChainFormatError(
                    f"{path}, line {lineno}: line element {raw.strip()!r} "
                    "needs two or more vertices"
                )
            idx = []
            for t in tok[1:]:
                try:
                    k = int(t.split("/", 1)[0])
                except ValueError:
                    raise ChainFormatError(
                        f"{path}, line {lineno}: bad vertex index {t!r}"
                    ) from None
                k = k - 1 if k > 0 else len(verts) + k
                if k < 0 or k >= len(verts) or t.split("/", 1)[0] in ("0", "-0"):
                    raise ChainFormatError(
                        f"{path}, line {lineno}: vertex index {t!r} out of range "
                        f"(1..{len(verts)} defined so far)"
                    )
                idx.append(k)
            for a, b in zip(idx[:-1], idx[1:], strict=True):
                if a == b:
                    raise ChainFormatError(
                        f"{path}, line {lineno}: line element joins vertex {a + 1} to itself"
                    )
                key = (min(a, b), max(a, b))
                if key in edges:
                    continue
                edges.add(key)
                order_edges.append((a, b))
        elif kw == "f":
            raise ChainFormatError(
                f"{path}, line {lineno}: faces ('f') found; expected a curve ('l' elements)"
            )
    if not verts:
        raise ChainFormatError(f"{path}: no vertices ('v x y z' lines)")
    X = np.array(verts, dtype=np.float64)
    src_meta = {"source": os.fspath(path)} if meta is None else meta
    if not has_lines:
        x = X
        closed = len(x) >= 4 and _ends_coincide(x)
        if closed:
            x = x[:-1]
        return _make_chain(x, closed, src_meta, path)
    if not edges:
        raise ChainFormatError(f"{path}: line elements contain no bonds")
    adj: dict[int, list[int]] = {}
    for a, b in order_edges:
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
        succ.setdefault(a, []).append(b)
    for v, nb in adj.items():
        if len(nb) > 2:
            raise ChainFormatError(
                f"{path}: vertex {v + 1} has {len(nb)} bonds; the line elements must form a single "
                "path or loop (no branching)"
            )
    ends = sorted(v for v, nb in adj.items() if len(nb) == 1)
    if ends:
        if len(ends) != 2:
            raise ChainFormatError(
                f"{path}: the line elements form {len(ends) // 2} separate pieces, "
                "expected one curve"
            )
        start = ends[0]
        nxt = adj[start][0]
        cycle = False
    else:
        start = min(adj)
        cand = succ.get(start, [])
        nxt = cand[0] if cand else adj[start][0]
        cycle = True
    order = [start]
    prev, cur = start, nxt
    while cur != start:
        order.append(cur)
        nb = adj[cur]
        if len(nb) == 1:
            break
        prev, cur = cur, (nb[0] if nb[1] == prev else nb[1])
    if len(order) != len(adj):
        raise ChainFormatError(
            f"{path}: the line elements form separate pieces ({len(order)} of {len(adj)} "
            "vertices connected); expected one curve"
        )
    x = X[order]
    closed = cycle
    if not cycle and len(x) >= 4 and _ends_coincide(x):
        x = x[:-1]
        closed = True
    elif cycle:
        # a loop through a duplicated vertex (e.g. the closing one repeated): drop the repeat
        same = np.all(x == np.roll(x, 1, axis=0), axis=1)
        if np.any(same) and len(x) - int(np.sum(same)) >= 3:
            x = x[~same]
    return _make_chain(x, closed, src_meta, path)


_READERS = {".xyz": from_xyz, ".json": from_json, ".npz": from_npz, ".obj": from_obj}
_WRITERS = {".xyz": to_xyz, ".json": to_json, ".npz": to_npz, ".obj": to_obj}


def save(chain: Chain, path: PathLike, **kwargs: Any) -> None:
    """Write ``chain`` in the format named by the suffix of ``path`` (``.xyz``, ``.json``,
    ``.npz``, ``.obj``); keyword arguments go to the writer (e.g. ``dialect="kymoknot"``)."""
    if not isinstance(chain, Chain):
        raise TypeError(f"save() expects a Chain, got {type(chain).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in _WRITERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_WRITERS)}"
        )
    _WRITERS[suffix](chain, path, **kwargs)


def load(path: PathLike, **kwargs: Any) -> Chain:
    """Read a chain, choosing the format by the suffix of ``path`` (``.xyz``, ``.json``,
    ``.npz``, ``.obj``); keyword arguments go to the reader."""
    suffix = Path(path).suffix.lower()
    if suffix not in _READERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_READERS)}"
        )
    if not Path(path).exists():
        raise ChainFormatError(f"{path}: no such file")
    return _READERS[suffix](path, **kwargs)
