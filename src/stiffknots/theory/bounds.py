"""Bounds on the equilibrium energy of stiff knots (§IV, §VI, §VIII, §IX).

* Closed knots (eq. (13)), (eq. (31)):
  ``2 pi^2 n^2 <= eps* <= 2 pi^2 min(alpha^2 n^2, i^2)``, ``alpha = (2 eps_loop)^(1/2) / pi``.
* Open knots (§VIII, eq. (45)) with ``n1 = n - 1``, ``i1 = i - 1``:
  ``2 pi^2 n1^2 <= mu* L_e^2 / C <= 2 pi^2 min(alpha^2 n1^2, i1^2)``. The paper prints
  ``alpha n1^2``; the correct form is ``alpha^2 n1^2`` as in the closed case.
* Restricted curvature (§IX D): ``2 pi n R <= L^dagger <= 2 pi min(7n/3, i) R``, with the PBL
  arc ansatz ``L = 2n [R1 (pi + 2 theta) + 2 R2 theta]``, ``R1 cos theta = R2 (1 - cos theta)``.
* Thick knots (§IX B): ``eps <= 2 (L/w)^2`` (the paper's "eps = E C / L" means ``E L / C``),
  and the self-consistency condition (eq. (16)) ``w / L << 1 / (2 pi n)``.
* Tension of open knots (eq. (41)), (eq. (42)): ``mu = E / L_e = eps_e C / L_e^2``
  with ``eps_e = E L_e / C`` (the paper's "eps_e = E / L_e" is a misprint).

Unknown knot data (``n`` or ``i`` = ``None``) give ``None`` for the quantities that need them;
nothing is guessed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stiffknots.theory.elastica import EPS_0, elastica_constants

__all__ = [
    "ClosedBounds",
    "OpenBounds",
    "RestrictedCurvatureBounds",
    "ArcAnsatz",
    "closed_bounds",
    "open_bounds",
    "restricted_curvature_bounds",
    "pbl_arc_length",
    "minimize_pbl_arc_ansatz",
    "thick_knot_bound",
    "self_consistency_limit",
    "tension_from_energy",
    "eps_e",
    "tension_from_eps_e",
]


def _check_int(name: str, value: int | None, minimum: int) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ValueError(f"{name} must be an integer or None, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")


def _check_knot_data(n: int | None, i: int | None) -> None:
    _check_int("the bridge number n", n, 1)
    _check_int("the braid index i", i, 1)
    if n is not None and i is not None and i < n:
        raise ValueError(
            f"the braid index i = {i} is smaller than the bridge number n = {n}; "
            "every knot has i >= n (e.g. the trefoil: n = 2, i = 2)"
        )


def _cb_or_pbl(cb: float | None, pbl: float | None) -> tuple[float | None, str | None]:
    """Upper bound = the lower of the known constructions; the winner only if both are known."""
    if cb is not None and pbl is not None:
        return (cb, "CB") if cb <= pbl else (pbl, "PBL")
    if cb is not None:
        return cb, None
    if pbl is not None:
        return pbl, None
    return None, None


@dataclass(frozen=True)
class ClosedBounds:
    """Bounds on ``eps* = E* L / C`` of a closed knot, (eq. (13)) and (eq. (31)).

    Attributes
    ----------
    n, i : int or None
        Bridge number and braid index.
    lower : float or None
        ``2 pi^2 n^2`` (None if ``n`` is unknown).
    upper : float or None
        ``min(eps_cb, eps_pbl) = 2 pi^2 min(alpha^2 n^2, i^2)``. If only one of ``n``, ``i`` is
        known, the one construction available (still a rigorous upper bound); None if neither.
    attained_by : str or None
        Which configuration gives ``upper`` (``"CB"`` or ``"PBL"``): ``"CB"`` when ``i <= alpha n``
        (ties to CB), None unless both ``n`` and ``i`` are known.
    eps_cb : float or None
        Circular braid, ``2 pi^2 i^2`` (eq. (30)).
    eps_pbl : float or None
        Point braid and loops, ``4 n^2 eps_loop = 2 pi^2 alpha^2 n^2`` (eq. (29)).
    exact : bool
        ``n == i``: the bounds coincide, the ground state is the ``i``-covered circle and
        ``eps* = 2 pi^2 i^2`` (§VI C).
    """

    n: int | None
    i: int | None
    lower: float | None
    upper: float | None
    attained_by: str | None
    eps_cb: float | None
    eps_pbl: float | None
    exact: bool

    def energy_bounds(self, length: float, C: float = 1.0) -> tuple[float | None, float | None]:
        """Bounds on the energy ``E* = eps* C / L`` (eq. (32)) for a knot of length ``L``."""
        f = C / length
        return (None if self.lower is None else self.lower * f,
                None if self.upper is None else self.upper * f)


def closed_bounds(n: int | None, i: int | None) -> ClosedBounds:
    """Bounds on the normalized ground-state energy of a closed stiff knot.

    Implements (eq. (13)) and (eq. (31)) of §IV and §VI:
    ``2 pi^2 n^2 <= eps* <= 2 pi^2 min(alpha^2 n^2, i^2)``.

    Parameters
    ----------
    n : int or None
        Bridge number (``>= 1``; ``None`` if unknown).
    i : int or None
        Braid index (``>= n``; ``None`` if unknown).

    Returns
    -------
    ClosedBounds

    Raises
    ------
    ValueError
        If ``n < 1``, ``i < 1``, ``i < n`` or a value is not an integer.

    Examples
    --------
    >>> b = closed_bounds(2, 2)  # trefoil 3_1
    >>> b.exact, round(b.lower / math.pi**2, 9), round(b.upper / math.pi**2, 9)
    (True, 8.0, 8.0)
    """
    _check_knot_data(n, i)
    c = elastica_constants()
    lower = None if n is None else EPS_0 * n * n
    e_cb = None if i is None else EPS_0 * i * i
    e_pbl = None if n is None else EPS_0 * c.alpha**2 * n * n
    upper, who = _cb_or_pbl(e_cb, e_pbl)
    exact = n is not None and i is not None and n == i
    return ClosedBounds(n=n, i=i, lower=lower, upper=upper, attained_by=who,
                        eps_cb=e_cb, eps_pbl=e_pbl, exact=exact)


@dataclass(frozen=True)
class OpenBounds:
    """Bounds on ``eps_e* = mu* L_e^2 / C`` of an open knot (§VIII, eq. (45)).

    Attributes
    ----------
    n1, i1 : int or None
        Bridge number and braid index of the open knot, ``n - 1`` and ``i - 1``.
    lower : float or None
        ``2 pi^2 n1^2``.
    upper : float or None
        ``2 pi^2 min(alpha^2 n1^2, i1^2)`` (the paper's "alpha n1^2" is a misprint).
    attained_by : str or None
        ``"CB"`` or ``"PBL"``, as for :class:`ClosedBounds`, with ``n1``, ``i1``.
    exact : bool
        ``n1 == i1``: a circle (``i1``-covered) tangent to the straight ends,
        ``mu* = 2 pi^2 i1^2 C / L_e^2`` (the open trefoil: ``2 pi^2 C / L_e^2``).
    """

    n1: int | None
    i1: int | None
    lower: float | None
    upper: float | None
    attained_by: str | None
    exact: bool

    def tension_bounds(self, L_e: float, C: float = 1.0) -> tuple[float | None, float | None]:
        """Bounds on the tension ``mu* = eps_e C / L_e^2`` (eq. (45)) at excess length ``L_e``."""
        if L_e <= 0:
            raise ValueError(f"the excess length L_e must be > 0, got {L_e}")
        f = C / (L_e * L_e)
        return (None if self.lower is None else self.lower * f,
                None if self.upper is None else self.upper * f)


def open_bounds(n: int | None, i: int | None) -> OpenBounds:
    """Bounds on the tension of an open knot, (eq. (45)) of §VIII.

    Parameters
    ----------
    n, i : int or None
        Bridge number and braid index of the *closed* knot; the open knot has
        ``n1 = n - 1``, ``i1 = i - 1``.

    Returns
    -------
    OpenBounds
        Bounds on ``mu* L_e^2 / C``:
        ``2 pi^2 n1^2 <= mu* L_e^2 / C <= 2 pi^2 min(alpha^2 n1^2, i1^2)``.
        (Misprint in the paper: "alpha n1^2" for ``alpha^2 n1^2``.) For the unknot
        (``n = i = 1``) both bounds are 0: a straight string.
    """
    _check_knot_data(n, i)
    c = elastica_constants()
    n1 = None if n is None else n - 1
    i1 = None if i is None else i - 1
    lower = None if n1 is None else EPS_0 * n1 * n1
    e_cb = None if i1 is None else EPS_0 * i1 * i1
    e_pbl = None if n1 is None else EPS_0 * c.alpha**2 * n1 * n1
    upper, who = _cb_or_pbl(e_cb, e_pbl)
    exact = n1 is not None and i1 is not None and n1 == i1
    return OpenBounds(n1=n1, i1=i1, lower=lower, upper=upper, attained_by=who, exact=exact)


@dataclass(frozen=True)
class RestrictedCurvatureBounds:
    """Bounds on the minimal length ``L^dagger`` of a knot with curvature ``<= 1/R`` (§IX D).

    Attributes
    ----------
    n, i : int or None
    R : float
        Minimal radius of curvature ``R_+``.
    lower : float or None
        ``2 pi n R``.
    upper : float or None
        ``2 pi min(7n/3, i) R`` (PBL arc ansatz ``14 pi n R / 3`` or circular braid
        ``2 pi i R``).
    attained_by : str or None
        ``"CB"`` or ``"PBL"``, as for :class:`ClosedBounds`.
    l_cb, l_pbl : float or None
        Lengths of the two constructions.
    exact : bool
        ``n == i``: ``L^dagger = 2 pi i R``, the circular braid.
    """

    n: int | None
    i: int | None
    R: float
    lower: float | None
    upper: float | None
    attained_by: str | None
    l_cb: float | None
    l_pbl: float | None
    exact: bool


def restricted_curvature_bounds(n: int | None, i: int | None, R: float = 1.0
                                ) -> RestrictedCurvatureBounds:
    """Bounds on the minimal length of a knot of curvature ``kappa <= 1/R`` (§IX D).

    ``2 pi n R <= L^dagger <= 2 pi min(7n/3, i) R``.

    Parameters
    ----------
    n, i : int or None
        Bridge number and braid index.
    R : float
        Minimal radius of curvature ``R_+ > 0``.

    Returns
    -------
    RestrictedCurvatureBounds
    """
    _check_knot_data(n, i)
    if not R > 0:
        raise ValueError(f"the minimal radius of curvature R must be > 0, got {R}")
    lower = None if n is None else 2.0 * math.pi * n * R
    l_cb = None if i is None else 2.0 * math.pi * i * R
    l_pbl = None if n is None else 2.0 * math.pi * (7.0 * n / 3.0) * R
    upper, who = _cb_or_pbl(l_cb, l_pbl)
    exact = n is not None and i is not None and n == i
    return RestrictedCurvatureBounds(n=n, i=i, R=R, lower=lower, upper=upper, attained_by=who,
                                     l_cb=l_cb, l_pbl=l_pbl, exact=exact)


def pbl_arc_length(R1: float, R2: float, n: int = 1) -> tuple[float, float]:
    """Length of the PBL arc ansatz of §IX D (Fig. restricted_curvarure_model).

    ``L = 2n [R1 (pi + 2 theta) + 2 R2 theta]`` with ``R1 cos theta = R2 (1 - cos theta)``,
    i.e. ``cos theta = R2 / (R1 + R2)``, ``0 < theta < pi/2``.

    Returns
    -------
    L, theta : float
    """
    if R1 <= 0 or R2 <= 0:
        raise ValueError(f"the radii must be > 0, got R1={R1}, R2={R2}")
    theta = math.acos(R2 / (R1 + R2))
    return 2.0 * n * (R1 * (math.pi + 2.0 * theta) + 2.0 * R2 * theta), theta


@dataclass(frozen=True)
class ArcAnsatz:
    """Minimum of the PBL arc ansatz: radii, angle and length."""

    R1: float
    R2: float
    theta: float
    length: float


def minimize_pbl_arc_ansatz(n: int = 1, R: float = 1.0) -> ArcAnsatz:
    """Minimize the PBL arc ansatz of §IX D numerically under ``R1, R2 >= R``.

    The paper finds ``R1 = R2 = R``, ``theta = pi/3`` and ``L_PBL = 2 n R (7 pi / 3)``.

    Parameters
    ----------
    n : int
        Bridge number (number of loop pairs).
    R : float
        Minimal radius of curvature.

    Returns
    -------
    ArcAnsatz
    """
    _check_int("the bridge number n", n, 1)
    if not R > 0:
        raise ValueError(f"the minimal radius of curvature R must be > 0, got {R}")
    from scipy.optimize import minimize

    best = None
    for start in ((2.0, 3.0), (5.0, 1.5), (1.2, 8.0)):
        res = minimize(lambda z: pbl_arc_length(z[0], z[1], n)[0] / R,
                       np.array(start) * R, method="L-BFGS-B",
                       bounds=[(R, None), (R, None)], options={"ftol": 1e-15, "gtol": 1e-12})
        if best is None or res.fun < best.fun:
            best = res
    r1, r2 = (float(v) for v in best.x)
    length, theta = pbl_arc_length(r1, r2, n)
    return ArcAnsatz(R1=r1, R2=r2, theta=theta, length=length)


def thick_knot_bound(L_over_w: float) -> float:
    """Upper bound ``eps = E L / C <= 2 (L/w)^2`` from ``kappa <= 2/w`` (§IX B).

    (The paper writes "eps = E C / L", a misprint for ``E L / C``.)
    """
    if not L_over_w > 0:
        raise ValueError(f"L/w must be > 0, got {L_over_w}")
    return 2.0 * L_over_w**2


def self_consistency_limit(n: int) -> float:
    """The bound in (eq. (16)): the theory needs ``w / L << 1 / (2 pi n)``.

    Returns ``1 / (2 pi n)``.
    """
    _check_int("the bridge number n", n, 1)
    return 1.0 / (2.0 * math.pi * n)


def tension_from_energy(E: float, L_e: float) -> float:
    """Equilibrium tension ``mu = E / L_e`` (eq. (41); ``L`` for closed knots)."""
    if L_e <= 0:
        raise ValueError(f"the (excess) length must be > 0, got {L_e}")
    return E / L_e


def eps_e(E: float, L_e: float, C: float = 1.0) -> float:
    """Normalized energy of an open knot ``eps_e = E L_e / C`` (eq. (42), misprint fixed).

    The paper prints "eps_e = E / L_e"; with ``E L_e / C``, (eq. (41)) reads
    ``mu = E / L_e = eps_e C / L_e^2``.
    """
    if L_e <= 0:
        raise ValueError(f"the excess length must be > 0, got {L_e}")
    return E * L_e / C


def tension_from_eps_e(eps: float, L_e: float, C: float = 1.0) -> float:
    """Tension ``mu = eps_e C / L_e^2`` (eq. (41))."""
    if L_e <= 0:
        raise ValueError(f"the excess length must be > 0, got {L_e}")
    return eps * C / (L_e * L_e)
