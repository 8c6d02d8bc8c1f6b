"""Small geometric measures of closed polygons used by the shape classifier (all vectorised).

Principal axes (best-fit plane), winding about an axis, planar turning number, total
curvature, inflection points. Conventions follow the paper: total curvature
``κ̄ = ∫ κ ds`` (eq. (10)), for a polygon the sum of its turning angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "PrincipalAxes",
    "principal_axes",
    "turning_angles",
    "total_curvature",
    "planar_signed_turns",
    "axis_winding",
    "count_inflections",
    "arc_lengths",
]


@dataclass(frozen=True)
class PrincipalAxes:
    """Centroid and principal axes of a set of points.

    ``axes[0]`` is the direction of largest spread, ``axes[2]`` the normal of the best-fit
    plane; ``eigenvalues`` are the variances along them (descending).
    """

    centroid: np.ndarray
    axes: np.ndarray
    eigenvalues: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        return self.axes[2]

    def project(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """In-plane coordinates ``(N, 2)`` and heights ``(N,)`` of points ``x``."""
        y = x - self.centroid
        return y @ self.axes[:2].T, y @ self.axes[2]

    def ratios(self) -> tuple[float, float]:
        """``(λ2/λ1, λ3/λ1)``: 1 for an isotropic cloud, ``λ3/λ1 → 0`` for a planar one."""
        top = self.eigenvalues[0] if self.eigenvalues[0] > 0 else 1.0
        return float(self.eigenvalues[1] / top), float(self.eigenvalues[2] / top)


def principal_axes(x: np.ndarray) -> PrincipalAxes:
    """Principal axes of the points ``x`` (N, 3) (eigenvectors of their covariance)."""
    c = x.mean(axis=0)
    y = x - c
    w, v = np.linalg.eigh(y.T @ y / max(len(x), 1))
    order = np.argsort(w)[::-1]
    return PrincipalAxes(c, v[:, order].T.copy(), np.clip(w[order], 0.0, None))


def _edges(x: np.ndarray, closed: bool) -> np.ndarray:
    return (np.roll(x, -1, axis=0) - x) if closed else (x[1:] - x[:-1])


def arc_lengths(x: np.ndarray, closed: bool = True) -> np.ndarray:
    """Bond lengths of the polygon (``N`` closed, ``N-1`` open)."""
    return np.linalg.norm(_edges(x, closed), axis=1)


def turning_angles(x: np.ndarray, closed: bool = True) -> np.ndarray:
    """Turning angle (radians, ``>= 0``) at every vertex (closed) or inner vertex (open)."""
    e = _edges(x, closed)
    if closed:
        a, b = np.roll(e, 1, axis=0), e
    else:
        a, b = e[:-1], e[1:]
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    return np.arctan2(cross, np.einsum("ij,ij->i", a, b))


def total_curvature(x: np.ndarray, closed: bool = True) -> float:
    """Total curvature ``κ̄`` (eq. (10)): the sum of the turning angles."""
    return float(turning_angles(x, closed).sum())


def planar_signed_turns(p: np.ndarray) -> np.ndarray:
    """Signed turning angle at every vertex of a closed planar polygon ``p`` (N, 2).

    Their sum is ``2π`` times the turning (rotation) number: ``±1`` for a circle, ``0`` for a
    figure eight.
    """
    e = np.roll(p, -1, axis=0) - p
    a = np.roll(e, 1, axis=0)
    cross = a[:, 0] * e[:, 1] - a[:, 1] * e[:, 0]
    dot = np.einsum("ij,ij->i", a, e)
    return np.arctan2(cross, dot)


def axis_winding(p: np.ndarray) -> tuple[float, np.ndarray]:
    """Winding of a closed planar polygon ``p`` (N, 2) about the origin.

    Returns ``(W, dphi)``: the winding number (a real number, an integer unless the curve
    passes through the origin) and the azimuth increment of every bond.
    """
    phi = np.arctan2(p[:, 1], p[:, 0])
    dphi = np.roll(phi, -1) - phi
    dphi = (dphi + math.pi) % (2.0 * math.pi) - math.pi
    return float(dphi.sum() / (2.0 * math.pi)), dphi


def count_inflections(signed_turns: np.ndarray, window: int | None = None,
                      rel_threshold: float = 0.25) -> int:
    """Number of sign changes of the (smoothed) signed curvature along a closed planar curve.

    The signed turning angles are smoothed by a cyclic moving average of ``window`` vertices
    (default ``max(3, N // 25)``); values smaller than ``rel_threshold`` times the mean absolute
    smoothed value are ignored, so bead-scale noise on straight-ish stretches does not count.
    A circle has 0 inflections, the elastica figure eight has 2.
    """
    k = np.asarray(signed_turns, dtype=float)
    n = k.shape[0]
    w = max(3, n // 25) if window is None else int(window)
    w = min(w, n)
    kern = np.ones(w) / w
    padded = np.concatenate([k[-w:], k, k[:w]])
    smooth = np.convolve(padded, kern, mode="same")[w:w + n]
    thr = rel_threshold * float(np.mean(np.abs(smooth)))
    signs = np.sign(smooth[np.abs(smooth) > thr])
    if signs.size < 2:
        return 0
    return int(np.count_nonzero(signs != np.roll(signs, 1)))
