"""Whether two chains are the same state: a shape distance blind to pose, direction and labels.

A *state* of a knot is a distinct polished minimum at one width (#37). Two annealed chains of
one knot are the same state when they have the same shape class, the same structure (§V B)
and ``ε`` within a tolerance — and, because several states can share all three (the class
``other`` holds many; two 80s can differ by which lobe carries the twist), when their shapes
are close. :func:`shape_distance` measures that closeness without caring how the chain was
placed, written or numbered:

* **translation** — both curves are centred on their centroid;
* **rotation and mirror** — the optimal orthogonal superposition (Kabsch; with ``mirror=True``
  a reflection is allowed too, so a state and its mirror image are at distance 0);
* **reversal and shift of the bead index** — every cyclic shift of the sample points and both
  directions of travel are tried, and the smallest distance is kept;
* **bead count** — both curves are resampled to the same number of points, equally spaced in
  arc length, and scaled to unit length ``L = 1``, so chains with other ``N`` compare too.

The distance is the root-mean-square distance between corresponding sample points after the
best superposition, in units of the contour length ``L``:

.. math::  d(a, b) = \\min_{s,\\ \\pm,\\ R}\\ \\Big[\\frac1M \\sum_k
           \\big|a_k - R\\, b_{\\pm k + s}\\big|^2\\Big]^{1/2} \\Big/ L .

For one shift the minimum over orthogonal ``R`` is
``(|a|² + |b|² − 2 (σ₁ + σ₂ ± σ₃)) / M`` with ``σ`` the singular values of the 3 × 3
cross-covariance ``H(s) = Σ_k a_kᵀ b_{k+s}`` (the sign is that of ``det H`` for a proper
rotation, + when a reflection is allowed). All ``M`` covariances at once are nine circular
cross-correlations, computed by FFT: ``O(M log M)``, well under a millisecond for ``M = 256``.

A shift of the bead index is in general a fraction of a sample spacing too (``N`` beads, ``M``
samples). The shifts are therefore tried in two steps: every whole sample spacing (the FFT)
in both directions, then, for the better direction, the fraction of a spacing by which the
second curve's samples start (a bounded Brent search, :func:`scipy.optimize.minimize_scalar`).
A renumbered copy of a chain is then at distance ≲ 1e-6 instead of up to half a spacing,
``1/(2M)`` of ``L``. One distance takes ≈ 10–20 ms.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DEFAULT_POINTS", "SAME_STATE_DISTANCE", "resample_unit", "shape_distance"]

#: Sample points of :func:`shape_distance`.
DEFAULT_POINTS = 256

#: Largest :func:`shape_distance` (in units of ``L``) of two chains of one state. Measured on
#: annealed chains at ``N = 150`` (tests/data/analysis; docs/methods/states.md): replicas of one
#: state lie at 0.004–0.009, distinct states of one knot at ≥ 0.05 (4_1's cage and its flat
#: ``other`` 0.052; 6_3's 80 and CB(3) 0.064).
SAME_STATE_DISTANCE = 0.02


def resample_unit(coords: np.ndarray, points: int = DEFAULT_POINTS,
                  offset: float = 0.0) -> np.ndarray:
    """A closed chain resampled at ``points`` points equally spaced in arc length, scaled to
    unit contour length and centred on its centroid.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        The vertices of a closed polygon (the bond from the last vertex to the first closes
        it), ``N ≥ 3``, no zero-length bond.
    points : int, default :data:`DEFAULT_POINTS`
        Number of sample points (≥ 8).
    offset : float, default 0
        Arc length (in units of the contour length) from vertex 0 to the first point.

    Returns
    -------
    ndarray, shape (points, 3)
        The first point lies ``offset · L`` after vertex 0; the points follow the chain's
        direction.

    Raises
    ------
    ValueError
        Bad shape, non-finite coordinates, a zero-length bond or too few points.
    """
    x = np.asarray(coords, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 3:
        raise ValueError(f"coords must be an (N, 3) array with N >= 3 (a closed chain), "
                         f"got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("coords must be finite")
    m = int(points)
    if m < 8:
        raise ValueError(f"points must be >= 8, got {points!r}")
    closed = np.vstack([x, x[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    if np.any(seg <= 0.0):
        raise ValueError("the chain has a zero-length bond (two equal consecutive vertices)")
    s = np.concatenate([[0.0], np.cumsum(seg)])
    length = s[-1]
    t = np.mod((np.arange(m) / m + float(offset)) * length, length)
    y = np.column_stack([np.interp(t, s, closed[:, j]) for j in range(3)]) / length
    return y - y.mean(axis=0)


def _best(a: np.ndarray, b: np.ndarray, mirror: bool) -> float:
    """Smallest mean squared distance over cyclic shifts of ``b`` and orthogonal maps."""
    m = a.shape[0]
    fa = np.conj(np.fft.rfft(a, axis=0))                    # (m//2+1, 3)
    fb = np.fft.rfft(b, axis=0)
    # H[s, i, j] = Σ_k a[k, i] b[k + s, j]: circular cross-correlation, one per (i, j)
    h = np.fft.irfft(fa[:, :, None] * fb[:, None, :], n=m, axis=0)   # (m, 3, 3)
    sv = np.linalg.svd(h, compute_uv=False)                 # (m, 3), decreasing
    if mirror:
        trace = sv.sum(axis=1)
    else:
        sign = np.sign(np.linalg.det(h))
        sign[sign == 0.0] = 1.0
        trace = sv[:, 0] + sv[:, 1] + sign * sv[:, 2]
    msd = (np.sum(a * a) + np.sum(b * b) - 2.0 * trace) / m
    return float(max(msd.min(), 0.0))


def shape_distance(a: np.ndarray, b: np.ndarray, *, points: int = DEFAULT_POINTS,
                   mirror: bool = True) -> float:
    """Root-mean-square distance of two closed chains after the best superposition, in units
    of the contour length (module docstring).

    Invariant under translation, rotation, reflection (``mirror=True``), reversal of the
    direction of travel, cyclic shift of the bead index and, up to the resampling, the bead
    count. Symmetric up to the search's tolerance; ≲ 1e-6 for a chain and any such copy of
    itself.

    Parameters
    ----------
    a, b : array_like, shape (N, 3) and (N', 3)
        Closed chains (see :func:`resample_unit`).
    points : int, default :data:`DEFAULT_POINTS`
        Sample points of the comparison.
    mirror : bool, default True
        Allow a reflection: a chain and its mirror image are at distance 0. False compares
        under proper rotations only (a chiral state and its mirror then differ).

    Returns
    -------
    float
        The distance / L (dimensionless, ≥ 0). Two chains of one state lie within
        :data:`SAME_STATE_DISTANCE`.
    """
    from scipy.optimize import minimize_scalar

    pa = resample_unit(a, points)
    rb = np.asarray(b, dtype=float)
    forward = _best(pa, resample_unit(rb, points), mirror)
    backward = _best(pa, resample_unit(rb[::-1], points), mirror)
    if backward < forward:
        rb = rb[::-1]
    spacing = 1.0 / points

    def msd(offset: float) -> float:
        return _best(pa, resample_unit(rb, points, offset), mirror)

    best = min(forward, backward)
    if best > 0.0:
        fit = minimize_scalar(msd, bounds=(-spacing, spacing), method="bounded",
                              options={"xatol": spacing * 1e-4})
        best = min(best, float(fit.fun))
    return float(np.sqrt(best))
