"""Extrapolation of a finite-width series ``eps*_w`` to the thin limit ``w -> 0`` (§V A).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V A: the paper's subject is
``eps* = lim_{w -> 0} eps*_w``; ``eps*_w`` rises with the width ``w`` (a thicker tube has
fewer configurations). A Monte Carlo run gives ``eps*_w`` at a few finite widths only; this
module fits the model

    eps(w) = eps* + a w^p

to such a series and states the limit with an error bar. Pure numerics on arrays: no knots,
no engine.

Method
------
For a fixed exponent ``p`` the model is linear in ``(eps*, a)``: weighted least squares with
the points' own standard errors ``sigma_k``. The exponent is not assumed: ``chi^2(p)`` is
profiled over a grid of ``p`` in ``[P_MIN, P_MAX]`` (the best ``p`` when the series has at
least four points, so that one degree of freedom is left; with three points or fewer ``p`` is
held at :data:`DEFAULT_P` and the other exponents are shown as alternatives only). When the
fit is worse than the stated ``sigma_k`` allow (``chi^2/dof > 1``) every ``sigma_k`` is
scaled up by ``sqrt(chi^2/dof)`` (the points' own errors were too small or the model is not
exact): the residuals then set the error, and since a variance estimated from ``dof``
residuals is itself uncertain, the scale is multiplied by ``t_dof(0.975) / 2`` (Student's
``t``; 6.4 for one degree of freedom, 2.2 for two), so that ``2 error`` is still a 95 %
interval.

The error of ``eps*`` (one standard error) combines in quadrature

* the statistical error of the linear fit at the best ``p`` (covariance of the weighted
  least squares, after the scaling above);
* the exponent's uncertainty: the largest shift of ``eps*(p)`` over the exponents whose
  profile ``chi^2(p) <= chi^2_min + 1`` (scaled ``chi^2``), i.e. the ``1 sigma`` profile
  interval of ``p``;
* the fit range (six points or more): the largest shift of ``eps*`` when the widest points
  are left out one by one, down to :data:`MIN_RANGE_POINTS` points. A series that is not yet
  one power law (its local exponent drifts) moves its limit as the range shrinks; this term
  says so where the statistical error would not.

Tests (``tests/analysis/test_extrapolate.py``) check on synthetic series of known limit and
Gaussian noise that the ``2 sigma`` bar covers the truth in at least 90 % of 200 series.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

__all__ = ["DEFAULT_P", "P_MIN", "P_MAX", "PowerFit", "ThinLimitFit", "fit_power",
           "extrapolate"]

#: exponent held when the series has fewer than four points
DEFAULT_P = 1.0
#: range of the exponent scanned
P_MIN, P_MAX = 0.3, 3.0
#: the fewest points of a sub-series in the fit-range term
MIN_RANGE_POINTS = 5
#: alternatives always reported (fixed exponents)
ALTERNATIVE_P = (2.0 / 3.0, 1.0, 4.0 / 3.0, 2.0)


@dataclass
class PowerFit:
    """Weighted least squares of ``eps = eps* + a w^p`` at one fixed ``p``.

    Attributes
    ----------
    p : float
        Exponent.
    epsilon, error : float
        The intercept ``eps*`` and its standard error (with the points' ``sigma``
        as given, not scaled).
    a, a_error : float
        The amplitude and its standard error.
    chi2 : float
        ``sum ((eps_k - model_k) / sigma_k)^2``.
    dof : int
        Points minus 2.
    """

    p: float
    epsilon: float
    error: float
    a: float
    a_error: float
    chi2: float
    dof: int

    def as_dict(self) -> dict:
        return {"p": self.p, "epsilon": self.epsilon, "error": self.error, "a": self.a,
                "a_error": self.a_error, "chi2": self.chi2, "dof": self.dof}


@dataclass
class ThinLimitFit:
    """The thin limit of a series: ``epsilon`` +- ``error`` (one standard error).

    Attributes
    ----------
    epsilon, error : float
        ``eps*`` and its standard error (statistical and exponent parts in
        quadrature; see the module docstring).
    p, p_range
        The exponent used and its ``1 sigma`` profile interval (``None`` when held).
    p_free : bool
        Whether ``p`` was fitted (at least four points) or held at :data:`DEFAULT_P`.
    a : float
        The amplitude at ``p``.
    stat_error, exponent_error, range_error : float
        The parts of ``error``.
    range_fits : list of tuple
        ``(points, eps*)`` of the sub-series without the widest points.
    scale : float
        The factor applied to the points' ``sigma`` (``>= 1``).
    chi2, dof
        Of the best fit, with the ``sigma`` as given.
    alternatives : list of PowerFit
        Fits at the fixed exponents :data:`ALTERNATIVE_P`.
    """

    epsilon: float
    error: float
    p: float
    p_range: tuple[float, float] | None
    p_free: bool
    a: float
    stat_error: float
    exponent_error: float
    scale: float
    chi2: float
    dof: int
    alternatives: list[PowerFit] = field(default_factory=list)
    range_error: float = 0.0
    range_fits: list[tuple[int, float]] = field(default_factory=list)

    def model(self, w) -> np.ndarray:
        """``eps* + a w^p`` at the widths ``w``."""
        return self.epsilon + self.a * np.asarray(w, dtype=float) ** self.p

    def as_dict(self) -> dict:
        return {
            "model": "eps(w) = eps* + a w^p (weighted least squares; p profiled)",
            "epsilon": self.epsilon, "error": self.error, "p": self.p,
            "p_range": list(self.p_range) if self.p_range is not None else None,
            "p_free": self.p_free, "a": self.a, "stat_error": self.stat_error,
            "exponent_error": self.exponent_error, "range_error": self.range_error,
            "range_fits": [list(r) for r in self.range_fits], "sigma_scale": self.scale,
            "chi2": self.chi2, "dof": self.dof,
            "alternatives": [f.as_dict() for f in self.alternatives],
        }


def _scale(chi2: float, dof: int) -> float:
    """Factor on the stated ``sigma`` (module docstring): 1 when the fit is as good as the
    ``sigma`` allow, else ``sqrt(chi^2/dof) t_dof(0.975) / 2``."""
    if dof <= 0 or chi2 <= dof:
        return 1.0
    from scipy.stats import t

    return max(1.0, math.sqrt(chi2 / dof) * float(t.ppf(0.975, dof)) / 2.0)


def _arrays(w, eps, sigma):
    w = np.asarray(w, dtype=float)
    eps = np.asarray(eps, dtype=float)
    if w.ndim != 1 or w.shape != eps.shape:
        raise ValueError("w and eps must be 1-d arrays of one length")
    if sigma is None:
        sigma = np.ones_like(w)
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), w.shape).copy()
    if len(w) < 2:
        raise ValueError("a thin-limit fit needs at least two widths")
    if not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise ValueError("the widths must be finite and > 0")
    if len(np.unique(w)) < 2:
        raise ValueError("a thin-limit fit needs at least two different widths")
    if not (np.all(np.isfinite(eps)) and np.all(np.isfinite(sigma)) and np.all(sigma > 0)):
        raise ValueError("eps must be finite and sigma finite and > 0")
    return w, eps, sigma


def fit_power(w: Sequence[float], eps: Sequence[float], sigma=None, p: float = DEFAULT_P
              ) -> PowerFit:
    """Fit ``eps = eps* + a w^p`` at fixed ``p`` by weighted least squares.

    Parameters
    ----------
    w : sequence of float
        Widths (``w/L``), all ``> 0``.
    eps : sequence of float
        ``eps*_w`` at those widths.
    sigma
        Standard errors of ``eps`` (default 1 each).
    p : float
        Exponent ``> 0``.

    Returns
    -------
    PowerFit
    """
    w, eps, sigma = _arrays(w, eps, sigma)
    if not (math.isfinite(p) and p > 0):
        raise ValueError(f"p must be > 0, got {p}")
    x = w ** p
    X = np.column_stack([np.ones_like(x), x]) / sigma[:, None]
    y = eps / sigma
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    cov = np.linalg.inv(X.T @ X)
    r = y - X @ coef
    return PowerFit(p=float(p), epsilon=float(coef[0]), error=float(math.sqrt(cov[0, 0])),
                    a=float(coef[1]), a_error=float(math.sqrt(cov[1, 1])),
                    chi2=float(r @ r), dof=len(w) - 2)


def extrapolate(w: Sequence[float], eps: Sequence[float], sigma=None, *,
                p: float | None = None, p_grid: Sequence[float] | None = None
                ) -> ThinLimitFit:
    """The thin limit ``eps* = lim_{w -> 0} eps(w)`` of a series, with its error (§V A).

    Parameters
    ----------
    w : sequence of float
        Widths (``w/L``, any positive unit), at least two different ones.
    eps : sequence of float
        ``eps*_w`` at those widths.
    sigma
        Standard errors of ``eps`` (default: equal, then set by the residuals).
    p : float or None
        Hold the exponent at this value; default: profiled over ``p_grid`` when there are at
        least four points, else held at :data:`DEFAULT_P`.
    p_grid : sequence of float or None
        The exponents scanned (default 271 values in ``[P_MIN, P_MAX]``).

    Returns
    -------
    ThinLimitFit
        ``epsilon`` +- ``error`` (one standard error), the exponent and the alternatives.
    """
    w, eps, sigma = _arrays(w, eps, sigma)
    alternatives = [fit_power(w, eps, sigma, q) for q in ALTERNATIVE_P]
    n = len(w)
    free = p is None and n >= 4
    if not free:
        q = DEFAULT_P if p is None else float(p)
        f = fit_power(w, eps, sigma, q)
        s = _scale(f.chi2, f.dof)
        return ThinLimitFit(epsilon=f.epsilon, error=f.error * s, p=q, p_range=None,
                            p_free=False, a=f.a, stat_error=f.error * s, exponent_error=0.0,
                            scale=s, chi2=f.chi2, dof=f.dof, alternatives=alternatives)
    grid = np.linspace(P_MIN, P_MAX, 271) if p_grid is None else np.asarray(p_grid, float)
    fits = [fit_power(w, eps, sigma, q) for q in grid]
    chi = np.array([f.chi2 for f in fits])
    k = int(np.argmin(chi))
    best = fits[k]
    dof = n - 3  # the exponent is fitted too
    s = _scale(best.chi2, dof)
    ok = chi / s**2 <= chi[k] / s**2 + 1.0
    idx = np.flatnonzero(ok)
    shift = max(abs(fits[i].epsilon - best.epsilon) for i in idx)
    stat = best.error * s
    # the fit range: leave out the widest points, down to MIN_RANGE_POINTS
    order = np.argsort(w)[::-1]
    range_fits: list[tuple[int, float]] = []
    for m in range(n - 1, MIN_RANGE_POINTS - 1, -1):
        keep = np.sort(order[n - m:])
        sub = extrapolate(w[keep], eps[keep], sigma[keep], p=p, p_grid=grid)
        range_fits.append((m, sub.epsilon))
    rng = max((abs(e - best.epsilon) for _, e in range_fits), default=0.0)
    return ThinLimitFit(epsilon=best.epsilon, error=math.sqrt(stat**2 + shift**2 + rng**2),
                        p=best.p, p_range=(float(grid[idx.min()]), float(grid[idx.max()])),
                        p_free=True, a=best.a, stat_error=stat, exponent_error=shift,
                        scale=s, chi2=best.chi2, dof=dof, alternatives=alternatives,
                        range_error=rng, range_fits=range_fits)
