"""The chain: a closed (knot) or open polygon in space and its geometric quantities.

A :class:`Chain` holds the bead coordinates of a discretised string (float64, shape ``(N, 3)``)
and whether it is closed (bead ``N-1`` joined to bead ``0``, so ``N`` bonds) or open (``N-1``
bonds). Its methods compute the quantities of Gallotti & Pierre-Louis, "Stiff knots" (PRE 2007):

* the discrete bending energy of §VII, ``E_d = C Σ_n (1 - u_n·u_{n+1})`` (unit bonds), which
  tends to the continuum energy ``E = (C/2) ∫ κ² ds`` (eq. (2)) for smooth curves;
* the normalised energy ``ε = E L / C`` (eq. (11)), ``ε = E_d N / C`` for unit bonds;
* the total curvature ``κ̄ = ∫ κ ds`` (eq. (10)), bounded below by ``2πn`` (Milnor, eq. (9));
* the excess length ``L_e = ∫ ds - ∫ dz`` of an open knot (eq. (40), §VIII);
* geometric diagnostics: radius of gyration, writhe (exact, Klenin & Langowski 2000), minimum
  distances between beads and between non-adjacent segments (the tube/bead exclusion of §II and
  §VII).

The file formats are in :mod:`stiffknots.formats` (``load``/``save``); the compiled measures in
:mod:`stiffknots.measures`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots import measures as M
from stiffknots._json import json_default
from stiffknots._version import __version__
from stiffknots.errors import ChainFormatError
from stiffknots.geometry import rescaled

__all__ = ["Chain", "as_coords", "regular_polygon"]

FORMAT_NAME = "stiffknots-chain"
FORMAT_VERSION = 1


def as_coords(coords: Any, name: str = "chain coordinates", *, item: str = "bead",
              first: int = 0) -> np.ndarray:
    """``coords`` (an array-like or a :class:`Chain`) as a C-contiguous float64 copy of shape
    (N, 3) with finite values; ValueError naming ``name`` otherwise (and the first point that is
    not finite, as ``item`` numbered from ``first``)."""
    if hasattr(coords, "coords") and hasattr(coords, "closed"):
        coords = coords.coords
    try:
        arr = np.array(coords, dtype=np.float64, order="C", copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numbers of shape (N, 3): {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise ValueError(f"{name} must be finite; {item} {bad + first} is {arr[bad].tolist()}")
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
        self.coords = as_coords(self.coords)
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
        # a repeated bead, tested without a norm (1e-300 underflowed to 0, 1e300 overflowed)
        zero = ~np.any(self.bond_vectors(), axis=1)
        if np.any(zero):
            k = int(np.argmax(zero))
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
        meta = json.loads(json.dumps(self.meta, default=json_default))
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
        """Contour length ``L = ∫ ds`` (eq. (1)): sum of bond lengths (``= N`` for a closed
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
        the continuum energy ``(C/2) ∫ κ² ds`` (eq. (2)) for smooth curves, and equals ``E_d``
        when all bonds are 1 (the weight is then ``1``).
        """
        _check_C(C)
        return float(C * M.bending_energy(self.coords, self.closed))

    def epsilon(self, C: float = 1.0) -> float:
        """Normalised energy ``ε = E L / C`` (eq. (11)); ``ε = E_d N / C`` for a closed
        unit-bond chain (§VII). Independent of ``C`` and of the chain's scale."""
        _check_C(C)
        x = rescaled(self.coords)  # a power of two: 1e300 coordinates overflowed to nan
        chain = self if x is self.coords else Chain(x, self.closed)
        return chain.energy(C) * chain.length / C

    def turning_angles(self) -> np.ndarray:
        """Angle ``θ_i ∈ [0, π]`` between the two bonds meeting at each bending vertex.

        ``N`` values for a closed chain (vertex ``i`` between bonds ``i-1`` and ``i``, cyclic),
        ``N-2`` for an open chain (interior beads ``1 .. N-2``).
        """
        return M.vertex_terms(self.coords, self.closed)[0]

    def curvature(self) -> np.ndarray:
        """Discrete curvature at each bending vertex: ``κ_i = θ_i / b̄_i``, turning angle over the
        mean length of the two adjacent bonds (same vertices as :meth:`turning_angles`).

        With this choice ``Σ κ_i b̄_i`` is exactly the total curvature (eq. (10)); for a
        regular polygon inscribed in a circle of radius ``R`` it tends to ``1/R``.
        """
        theta, _, lbar = M.vertex_terms(self.coords, self.closed)
        return theta / lbar

    def total_curvature(self) -> float:
        """Total curvature ``κ̄ = ∫ κ ds`` (eq. (10)) = ``Σ θ_i`` for a polygon.

        Milnor (eq. (9)): ``κ̄ ≥ 2πn`` for a knot of bridge number ``n`` (Fáry–Milnor for
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
        return float(M.writhe(self.coords, self.closed))

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
        return float(M.min_bead_distance(self.coords, self.closed, ms))

    def min_segment_distance(self) -> float:
        """Minimum distance between non-adjacent segments (segments sharing no bead).

        The tube of diameter ``w`` around the polygon (§II) does not self-intersect only if this
        is ``>= w`` (a necessary condition). Returns ``inf`` if there is no such pair (``N = 3``).
        """
        return float(M.min_segment_distance(self.coords, self.closed))

    def excess_length(self, axis: Any = (0.0, 0.0, 1.0)) -> float:
        """Excess length ``L_e = ∫ ds - ∫ dz`` (eq. (40)) along ``axis``.

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
        """JSON-ready dict of the ``stiffknots-chain`` format (see :func:`.to_json`)."""
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

    ``m ≥ 2``: the circular braid of index ``m`` (§V, eq. (30), ``ε → 2π²m²``). The
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


