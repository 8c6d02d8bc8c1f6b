"""Planar elastica constants of Appendix D and the structure energies built from them.

The closed and looped planar solutions of the elastica enter the upper bounds of the paper
(Gallotti & Pierre-Louis, "Stiff knots", PRE 2007):

* the *loop* of the Point-Braid-and-Loops (PBL) configuration: a planar curve that starts and
  ends at the same point with opposite tangents, ``alpha_loop = A/mu`` from (eq. (D5)) and
  its normalized energy ``eps_loop`` from (eq. (D8));
* the *8*, the closed periodic figure-eight elastica, with ``alpha_8`` and ``eps_8``
  (Appendix D, "Energy of the 8");
* the circle, ``eps_0 = 2 pi^2``, and the structures composed of these parts,
  (eq. (27)), (eq. (28)), (eq. (30)), (eq. (29)) and the "80".

Conventions
-----------
Planar solutions obey (eq. (D1)), ``(1/2) phi'^2 = (mu + A cos phi) / C`` where ``phi`` is
the angle between the tangent and the constant force ``A`` (the paper's ``v = -alpha cos theta``
is ``v = alpha cos phi`` here, a mere sign convention for the angle). With
``alpha = A/mu > 1`` the curve has inflection points (``v = -1``) and is the inflectional
elastica of elliptic modulus ``m = k^2 = (1 + 1/alpha) / 2``:
``sin(phi/2) = k sn(u | m)``, ``u = s (A/C)^(1/2)``, ``x = 2 E(am u | m) - u``,
``y = -2 k cn(u | m)`` (``x`` along ``A``, lengths in units of ``(C/A)^(1/2)``).

The constants are computed three independent ways:

``"integrals"``
    Method 1: the integrals of Appendix D exactly as printed, evaluated with mpmath after the
    substitution ``v = -1 + (alpha + 1) sin^2 psi`` which removes the integrable endpoint
    singularities at ``v = -1`` and ``v = alpha``; roots by :func:`mpmath.findroot`.
``"integrals-raw"``
    The same integrals with no substitution, left to mpmath's tanh-sinh quadrature (which
    handles the endpoint singularities itself); slower, a check of the substitution.
``"elliptic"``
    Method 2: complete and incomplete elliptic integrals (mpmath) of the closed-form solution
    above; independent of the Appendix D integrals.
``"shooting"``
    Method 3: direct shooting integration of ``phi'' = -sin phi`` with
    :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-13) and geometric boundary conditions
    (loop: back on the symmetry axis with the tangent along it; 8: zero drift per period);
    double precision, agrees with the others to about 13 significant digits.

Misprint: in (eq. (D8)) the integration variable "dw" means ``dv``.

The paper prints ``alpha_loop ~ 2.158``, ``eps_loop ~ 18.19``, ``alpha_8 ~ 1.53``,
``eps_8 ~ 55.93``, ``eps_80 ~ 142.1`` and ``alpha ~ 1.92``. The verified values are
``alpha_loop = 2.16278854556``, ``eps_loop = 18.3331074530``, ``alpha_8 = 1.53320257821``,
``eps_8 = 56.2198048707``, ``eps_80 = 142.584...`` and ``alpha = 1.92749...``: only
``alpha_8`` agrees with the printed digits. The paper's own formula evaluated at its printed
``alpha = 2.158`` gives ``eps = 18.367`` and at ``alpha_8 = 1.53`` gives ``56.32``, so the
printed values are not a rounding of the equations; they are reproduced (except ``eps_8``,
55.7) by cutting the integrals off about ``5e-5`` before the singular endpoints, i.e. they are
consistent with an under-resolved quadrature of the ``1/sqrt`` endpoint singularities. The
figure-eight value also agrees with the classical condition ``2 E(m) = K(m)``
(``m = 0.826114765...``), so ``eps_8 = 32 K^2 (m - 1/2) = 56.2198...``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import mpmath as mp
import numpy as np

__all__ = [
    "EPS_0",
    "PAPER_VALUES",
    "METHODS",
    "ElasticaConstants",
    "StructureEnergy",
    "Hierarchy",
    "solve_loop",
    "solve_eight",
    "elastica_constants",
    "eps_cb",
    "eps_pbl",
    "eps_80",
    "eps_structure",
    "hierarchy",
    "discrete_epsilon",
    "loop_curve",
    "eight_curve",
    "eighty_curve",
]

#: Normalized energy of the circle, the ground state of a closed unknotted line (§III, §VI).
EPS_0: float = 2.0 * math.pi**2

#: Values printed in the paper (Appendix D, §VI, §VII). See the module docstring for why all
#: but ``alpha_8`` differ from the verified values beyond rounding.
PAPER_VALUES: dict[str, float] = {
    "alpha_loop": 2.158,
    "eps_loop": 18.19,
    "alpha_8": 1.53,
    "eps_8": 55.93,
    "eps_80": 142.1,
    "alpha": 1.92,
}

#: Methods accepted by :func:`solve_loop`, :func:`solve_eight` and :func:`elastica_constants`.
METHODS: tuple[str, ...] = ("integrals", "integrals-raw", "elliptic", "shooting")

# Starting points for the root searches (the paper's values are close enough).
_ALPHA_LOOP_GUESS = 2.16
_ALPHA_8_GUESS = 1.53


# --------------------------------------------------------------------------------------------
# Method 1: the integrals of Appendix D
# --------------------------------------------------------------------------------------------
def _appendix_integrals(alpha: Any, a: Any, b: Any, raw: bool) -> tuple[Any, Any, Any]:
    r"""Return ``(Ix, I0, I1)``, the three integrals of Appendix D over ``v`` in ``[a, b]``.

    ``Ix = \int v dv / ((alpha^2 - v^2)^(1/2) (v + 1)^(1/2))``,
    ``I0 = \int dv / ((alpha^2 - v^2)^(1/2) (v + 1)^(1/2))``,
    ``I1 = \int (v + 1)^(1/2) dv / (alpha^2 - v^2)^(1/2)``, with ``-1 <= a < b <= alpha``.

    With ``raw=False`` the substitution ``v = -1 + (alpha + 1) sin^2 psi`` gives
    ``dv / ((alpha - v)(v + 1))^(1/2) = 2 dpsi``, so that all three integrands become
    ``2 g(v) / (alpha + v)^(1/2)`` with ``g = v, 1, v + 1``: analytic on the closed interval
    (``alpha + v >= alpha - 1 > 0``), integrated to full precision by Gauss-Legendre.
    """
    if raw:
        def den(v):
            return mp.sqrt(alpha * alpha - v * v) * mp.sqrt(v + 1)

        ix = mp.quad(lambda v: v / den(v), [a, b])
        i0 = mp.quad(lambda v: 1 / den(v), [a, b])
        i1 = mp.quad(lambda v: (v + 1) / den(v), [a, b])
        return ix, i0, i1

    ap1 = alpha + 1

    def psi_of(v):
        return mp.asin(mp.sqrt((v + 1) / ap1))

    pa, pb = psi_of(a), psi_of(b)

    def vv(p):
        return -1 + ap1 * mp.sin(p) ** 2

    def fx(p):
        v = vv(p)
        return 2 * v / mp.sqrt(alpha + v)

    def f0(p):
        return 2 / mp.sqrt(alpha + vv(p))

    def f1(p):
        v = vv(p)
        return 2 * (v + 1) / mp.sqrt(alpha + v)

    quad = functools.partial(mp.quad, method="gauss-legendre")
    return quad(fx, [pa, pb]), quad(f0, [pa, pb]), quad(f1, [pa, pb])


def _loop_integrals(alpha: Any, raw: bool) -> tuple[Any, Any, Any]:
    """Weighted integrals ``2 int_{-1}^0 + int_0^alpha`` of (eq. (D5)), (eq. (D8)).
    """
    lo = _appendix_integrals(alpha, mp.mpf(-1), mp.mpf(0), raw)
    hi = _appendix_integrals(alpha, mp.mpf(0), alpha, raw)
    return tuple(2 * x + y for x, y in zip(lo, hi, strict=True))  # type: ignore[return-value]


def _loop_by_integrals(dps: int, raw: bool) -> tuple[Any, Any]:
    with mp.workdps(dps + 5):
        alpha = mp.findroot(lambda a: _loop_integrals(a, raw)[0], mp.mpf(_ALPHA_LOOP_GUESS))
        _, i0, i1 = _loop_integrals(alpha, raw)
        eps = 2 * i1 * i0
    return +alpha, +eps


def _eight_by_integrals(dps: int, raw: bool) -> tuple[Any, Any]:
    with mp.workdps(dps + 5):
        alpha = mp.findroot(
            lambda a: _appendix_integrals(a, mp.mpf(-1), a, raw)[0], mp.mpf(_ALPHA_8_GUESS)
        )
        _, i0, i1 = _appendix_integrals(alpha, mp.mpf(-1), alpha, raw)
        eps = 8 * i1 * i0
    return +alpha, +eps


# --------------------------------------------------------------------------------------------
# Method 2: elliptic integrals
# --------------------------------------------------------------------------------------------
def _alpha_from_m(m: Any) -> Any:
    """``alpha = A/mu`` from the elliptic parameter ``m = k^2 = (1 + 1/alpha)/2``."""
    return 1 / (2 * m - 1)


def _real_root(f: Any, alpha_guess: float) -> Any:
    """Root in ``m`` of ``f`` near ``m(alpha_guess)``, kept on the real axis."""
    m0 = (1 + 1 / mp.mpf(alpha_guess)) / 2
    root = mp.findroot(f, (m0 - mp.mpf("0.01"), m0 + mp.mpf("0.01")), solver="anderson")
    if abs(mp.im(root)) > mp.mpf(10) ** (-mp.mp.dps // 2):  # pragma: no cover
        raise ArithmeticError(f"elliptic root search left the real axis: {root}")
    return mp.re(root)


def _loop_elliptic_parts(m: Any) -> tuple[Any, Any, Any, Any, Any]:
    """Return ``(K, E, u1, E(u1), residual)`` for the loop at parameter ``m``.

    ``u1`` is where the tangent is perpendicular to ``A`` (``phi = pi/2``,
    ``sn u1 = 1/(2m)^(1/2)``); the loop runs over ``u in [-U, U]`` with ``U = 2K - u1``, and it
    closes (returns to its starting point) when ``x(U) = 2 E(am U) - U = 0``, i.e.
    ``2(2E - K) = 2 E(u1) - u1``.
    """
    k_ = mp.ellipk(m)
    e_ = mp.ellipe(m)
    psi1 = mp.asin(1 / mp.sqrt(2 * m))
    u1 = mp.ellipf(psi1, m)
    eu1 = mp.ellipe(psi1, m)
    return k_, e_, u1, eu1, 2 * (2 * e_ - k_) - (2 * eu1 - u1)


def _loop_by_elliptic(dps: int) -> tuple[Any, Any]:
    with mp.workdps(dps + 5):
        m = _real_root(lambda t: _loop_elliptic_parts(t)[4], _ALPHA_LOOP_GUESS)
        k_, e_, u1, eu1, _ = _loop_elliptic_parts(m)
        big_u = 2 * k_ - u1
        # L = 2U, int kappa^2 ds = 8 [E(U) - (1-m) U] with E(U) = 2E - E(u1); eps = L int/2
        eps = 8 * big_u * (2 * e_ - eu1 - (1 - m) * big_u)
        alpha = _alpha_from_m(m)
    return +alpha, +eps


def _eight_by_elliptic(dps: int) -> tuple[Any, Any]:
    with mp.workdps(dps + 5):
        m = _real_root(lambda t: 2 * mp.ellipe(t) - mp.ellipk(t), _ALPHA_8_GUESS)
        k_ = mp.ellipk(m)
        # L = 4K, int kappa^2 ds = 16 (E - (1-m) K) = 16 K (m - 1/2) when 2E = K
        eps = 32 * k_**2 * (m - mp.mpf(1) / 2)
        alpha = _alpha_from_m(m)
    return +alpha, +eps


# --------------------------------------------------------------------------------------------
# Method 3: shooting with the ODE
# --------------------------------------------------------------------------------------------
_ODE_TOL = {"rtol": 1e-13, "atol": 1e-14}


def _shoot(m: float, which: str) -> tuple[float, float, float]:
    """Integrate ``phi'' = -sin phi`` from the apex (``phi = 0``, ``phi' = 2 m^(1/2)``).

    Units ``A = C = 1``. State ``(x, y, phi, phi', int phi'^2 ds)``. Stops at the end of the
    half loop (``which="loop"``: second passage at ``phi = pi/2``, downwards) or at the first
    inflection point (``which="eight"``: ``phi' = 0``). Returns ``(x, s, int kappa^2 ds)`` there.
    """
    from scipy.integrate import solve_ivp

    def rhs(_s, z):
        return [math.cos(z[2]), math.sin(z[2]), z[3], -math.sin(z[2]), z[3] * z[3]]

    if which == "loop":
        def event(_s, z):
            return z[2] - math.pi / 2

        event.direction = -1.0
    else:
        def event(_s, z):
            return z[3]

        event.direction = -1.0
    event.terminal = True
    sol = solve_ivp(rhs, (0.0, 50.0), [0.0, 0.0, 0.0, 2.0 * math.sqrt(m), 0.0],
                    method="DOP853", events=event, **_ODE_TOL)
    if not sol.t_events[0].size:  # pragma: no cover - bracket chosen so this cannot happen
        raise RuntimeError(f"shooting for the {which} found no end point at m={m}")
    s_end = float(sol.t_events[0][0])
    z = sol.y_events[0][0]
    return float(z[0]), s_end, float(z[4])


def _loop_by_shooting() -> tuple[float, float]:
    from scipy.optimize import brentq

    m = brentq(lambda t: _shoot(t, "loop")[0], 0.65, 0.80, xtol=1e-16, rtol=1e-15)
    _, s_half, k2_half = _shoot(m, "loop")
    # whole loop: L = 2 s_half, int kappa^2 = 2 k2_half; eps = (1/2) int kappa^2 * L
    return 1.0 / (2.0 * m - 1.0), 2.0 * s_half * k2_half


def _eight_by_shooting() -> tuple[float, float]:
    from scipy.optimize import brentq

    m = brentq(lambda t: _shoot(t, "eight")[0], 0.75, 0.90, xtol=1e-16, rtol=1e-15)
    _, s_q, k2_q = _shoot(m, "eight")
    # four quarter periods: eps = (1/2) (4 k2_q) (4 s_q)
    return 1.0 / (2.0 * m - 1.0), 8.0 * s_q * k2_q


# --------------------------------------------------------------------------------------------
# Public solvers
# --------------------------------------------------------------------------------------------
def _check_method(method: str) -> None:
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")


@functools.cache
def solve_loop(method: str = "integrals", dps: int = 30) -> tuple[Any, Any]:
    """Return ``(alpha_loop, eps_loop)`` of the planar loop of the PBL configuration.

    Implements (eq. (D5)) and (eq. (D8)), Appendix D ("dw" read as ``dv``).
    The loop starts and ends at the same point with opposite tangents (§VI A).

    Parameters
    ----------
    method : {"integrals", "integrals-raw", "elliptic", "shooting"}
        See the module docstring. ``"shooting"`` works in double precision.
    dps : int
        Decimal digits of the mpmath computation (ignored by ``"shooting"``).

    Returns
    -------
    alpha_loop, eps_loop : mpmath.mpf (float for ``"shooting"``)
        ``alpha_loop = A/mu`` (paper: 2.158; verified 2.16278854556) and
        ``eps_loop = E L / C`` (paper: 18.19; verified 18.3331074530).
    """
    _check_method(method)
    if method == "integrals":
        return _loop_by_integrals(dps, raw=False)
    if method == "integrals-raw":
        return _loop_by_integrals(dps, raw=True)
    if method == "elliptic":
        return _loop_by_elliptic(dps)
    return _loop_by_shooting()


@functools.cache
def solve_eight(method: str = "integrals", dps: int = 30) -> tuple[Any, Any]:
    """Return ``(alpha_8, eps_8)`` of the closed figure-eight elastica.

    Implements the periodicity condition ``int_{-1}^{alpha} v dv / (...) = 0`` and
    ``eps_8 = 8 [int (v+1)^(1/2) dv/(...)] [int dv/(...)]`` of Appendix D ("Energy of the 8").

    Parameters
    ----------
    method : {"integrals", "integrals-raw", "elliptic", "shooting"}
        See the module docstring.
    dps : int
        Decimal digits of the mpmath computation (ignored by ``"shooting"``).

    Returns
    -------
    alpha_8, eps_8 : mpmath.mpf (float for ``"shooting"``)
        Paper: 1.53 and 55.93; verified 1.53320257821 and 56.2198048707.
    """
    _check_method(method)
    return {"integrals": lambda: _eight_by_integrals(dps, raw=False),
            "integrals-raw": lambda: _eight_by_integrals(dps, raw=True),
            "elliptic": lambda: _eight_by_elliptic(dps)}.get(method, _eight_by_shooting)()


@dataclass(frozen=True)
class ElasticaConstants:
    """The planar elastica constants (Appendix D, §VI, §VII), as floats.

    Attributes
    ----------
    alpha_loop : float
        ``A/mu`` of the PBL loop, root of (eq. (D5)).
    eps_loop : float
        Normalized energy of the loop, (eq. (D8)).
    alpha_8 : float
        ``A/mu`` of the figure eight (periodicity condition of Appendix D).
    eps_8 : float
        Normalized energy of the figure eight.
    eps_80 : float
        ``(eps_8^(1/2) + (2 pi^2)^(1/2))^2``, the "80" structure (§VII, from (eq. (27))).
    alpha : float
        ``(2 eps_loop)^(1/2) / pi``, the CB/PBL crossover of (eq. (31)) (§VI A);
        not the same quantity as ``alpha_loop``.
    """

    alpha_loop: float
    eps_loop: float
    alpha_8: float
    eps_8: float
    eps_80: float
    alpha: float

    @property
    def eps_0(self) -> float:
        """Normalized energy of the circle, ``2 pi^2``."""
        return EPS_0

    def as_dict(self) -> dict[str, float]:
        """The six constants as a plain dict, keys as in :data:`PAPER_VALUES`."""
        return {k: getattr(self, k) for k in PAPER_VALUES}


@functools.cache
def elastica_constants(method: str = "integrals") -> ElasticaConstants:
    """Return the planar elastica constants as floats (cached).

    The mpmath methods run at 20 significant digits here (use :func:`solve_loop` and
    :func:`solve_eight` for more). First call: about 0.5 s for ``"integrals"``, 0.05 s for
    ``"elliptic"``, 1 s for ``"shooting"``, 9 s for ``"integrals-raw"``.

    Parameters
    ----------
    method : {"integrals", "integrals-raw", "elliptic", "shooting"}
        Method 1 (the Appendix D integrals, default), or an independent check
        (see the module docstring).

    Returns
    -------
    ElasticaConstants
    """
    from stiffknots._diskcache import cached, source_key

    # computed once per installation (every command needs them for its bounds)
    return cached("elastica", source_key(method, files=(__file__,)),
                  lambda: _compute_constants(method))


def _compute_constants(method: str) -> ElasticaConstants:
    a_loop, e_loop = solve_loop(method, dps=20)
    a_8, e_8 = solve_eight(method, dps=20)
    e_loop, e_8 = float(e_loop), float(e_8)
    return ElasticaConstants(
        alpha_loop=float(a_loop),
        eps_loop=e_loop,
        alpha_8=float(a_8),
        eps_8=e_8,
        eps_80=(math.sqrt(e_8) + math.sqrt(EPS_0)) ** 2,
        alpha=math.sqrt(2.0 * e_loop) / math.pi,
    )


# --------------------------------------------------------------------------------------------
# Structures
# --------------------------------------------------------------------------------------------
def eps_cb(i: int) -> float:
    """Normalized energy of the circular braid of ``i`` strands, ``2 pi^2 i^2`` (eq. (30))."""
    if i < 1:
        raise ValueError(f"the braid index i must be >= 1, got {i}")
    return EPS_0 * i * i


def eps_pbl(n: int) -> float:
    """Normalized energy of the PBL configuration, ``4 n^2 eps_loop`` (eq. (29))."""
    if n < 1:
        raise ValueError(f"the bridge number n must be >= 1, got {n}")
    return 4.0 * n * n * elastica_constants().eps_loop


def eps_80() -> float:
    """Normalized energy of the "80" structure, ``(eps_8^(1/2) + eps_0^(1/2))^2`` (§VII)."""
    return elastica_constants().eps_80


@dataclass(frozen=True)
class StructureEnergy:
    """Result of :func:`eps_structure`.

    Attributes
    ----------
    eps : float
        ``[sum_p m_p eps_p^(1/2)]^2`` (eq. (27)).
    length_fractions : tuple of float
        ``L_p / L = (eps_p / eps)^(1/2)`` (eq. (28)), one per line-braid (length of the
        line-braid, not multiplied by its multiplicity; ``sum_p m_p L_p = L``).
    """

    eps: float
    length_fractions: tuple[float, ...]


def eps_structure(parts: Iterable[tuple[int, float]] | Mapping[Any, tuple[int, float]]
                  ) -> StructureEnergy:
    """Normalized energy and lengths of a structure of line-braids.

    Implements (eq. (27)) and (eq. (28)) (§V B, Appendix C), valid when all
    line-braids are arcs of circles, all are closed loops, or all have the same energy and
    length.

    Parameters
    ----------
    parts : iterable of (m_p, eps_p), or mapping name -> (m_p, eps_p)
        Multiplicity ``m_p >= 1`` and normalized energy ``eps_p >= 0`` of each line-braid.

    Returns
    -------
    StructureEnergy

    Examples
    --------
    >>> round(eps_structure([(3, 2 * math.pi**2)]).eps / math.pi**2, 12)  # CB with i = 3
    18.0
    """
    items = list(parts.values()) if isinstance(parts, Mapping) else list(parts)
    if not items:
        raise ValueError("a structure needs at least one line-braid (m_p, eps_p)")
    for m_p, e_p in items:
        if m_p < 1 or e_p < 0:
            raise ValueError(f"each part needs m_p >= 1 and eps_p >= 0, got ({m_p}, {e_p})")
    root = sum(m_p * math.sqrt(e_p) for m_p, e_p in items)
    eps = root * root
    if eps == 0.0:
        return StructureEnergy(0.0, tuple(float("nan") for _ in items))
    return StructureEnergy(eps, tuple(math.sqrt(e_p / eps) for _, e_p in items))


@dataclass(frozen=True)
class Hierarchy:
    """Result of :func:`hierarchy`: the energies in the paper's order and whether they increase."""

    entries: tuple[tuple[str, float], ...]
    holds: bool


def hierarchy(eps_4c: float = 129.6) -> Hierarchy:
    """The hierarchy (eq. (39)): CB(i=2) < 4C < 80 < CB(i=3) < PBL(n=2).

    Parameters
    ----------
    eps_4c : float
        Energy of the 4-fold cage, known only from Monte Carlo (an upper bound of the
        ``w -> 0`` value); default the paper's 129.6 (N = 150 beads).

    Returns
    -------
    Hierarchy
        ``entries`` = ``(label, value)`` in the paper's order, ``holds`` = strictly increasing.
    """
    entries = (
        ("CB(i=2)", eps_cb(2)),
        ("4C", float(eps_4c)),
        ("80", eps_80()),
        ("CB(i=3)", eps_cb(3)),
        ("PBL(n=2)", eps_pbl(2)),
    )
    vals = [v for _, v in entries]
    return Hierarchy(entries, all(a < b for a, b in zip(vals, vals[1:], strict=False)))


# --------------------------------------------------------------------------------------------
# Curves
# --------------------------------------------------------------------------------------------
def discrete_epsilon(points: np.ndarray, closed: bool = True) -> float:
    """Normalized energy ``eps = E L / C`` of a polyline, from ``E_d = C sum (1 - u_n.u_{n+1})``.

    For a chain of ``N`` bonds of equal length ``b`` this is ``eps = N sum_n (1 - u_n.u_{n+1})``
    (§VII, unit bonds: ``eps = E_d N / C``); for unequal bonds each vertex is divided by the
    mean length of its two bonds and multiplied by the total length. Converges to
    ``(L/2) int kappa^2 ds`` as ``2 pi^2 + O(1/N^2)`` for a circle.

    Parameters
    ----------
    points : (N, d) array
        Positions. If ``closed`` and the last point repeats the first, it is dropped.
    closed : bool
        Closed chain (N bonds and N vertices) or open chain (N-1 bonds, N-2 vertices; the
        curvature at the two ends is then not counted, an ``O(1/N)`` error).
    """
    p = np.asarray(points, dtype=float)
    if closed:
        if len(p) > 1 and np.allclose(p[0], p[-1], rtol=0.0, atol=1e-12):
            p = p[:-1]
        bonds = np.roll(p, -1, axis=0) - p
    else:
        bonds = np.diff(p, axis=0)
    blen = np.linalg.norm(bonds, axis=1)
    u = bonds / blen[:, None]
    if closed:
        cos = np.einsum("ij,ij->i", u, np.roll(u, -1, axis=0))
        bmean = 0.5 * (blen + np.roll(blen, -1))
    else:
        cos = np.einsum("ij,ij->i", u[:-1], u[1:])
        bmean = 0.5 * (blen[:-1] + blen[1:])
    return float(blen.sum() * np.sum((1.0 - cos) / bmean))


def _elliptic_point(u: np.ndarray, m: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions and unit tangents of the inflectional elastica at ``u`` (units ``A = C = 1``)."""
    from scipy.special import ellipeinc, ellipj

    sn, cn, dn, ph = ellipj(u, m)
    x = 2.0 * ellipeinc(ph, m) - u
    y = -2.0 * math.sqrt(m) * cn
    # cos phi = 1 - 2 m sn^2, sin phi = 2 k sn dn
    tx = 1.0 - 2.0 * m * sn * sn
    ty = 2.0 * math.sqrt(m) * sn * dn
    return np.column_stack([x, y]), np.column_stack([tx, ty])


def _m_of(alpha: float) -> float:
    return 0.5 * (1.0 + 1.0 / alpha)


def loop_curve(n_points: int = 400, *, with_tangents: bool = False
               ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The planar loop of the PBL configuration (Appendix D, Fig. energy_calc a).

    Exact elliptic solution ``x = 2E(am u) - u``, ``y = -2k cn u``, ``u in [-U, U]``, at the
    modulus fixed by (eq. (D5)). Points are equally spaced in arc length and the curve is
    normalized to total length 1. It starts and ends at the contact point ``P`` (placed at the
    origin; first and last points coincide) with tangents ``+y`` and ``-y``; its symmetry
    axis is the ``y`` axis.

    Parameters
    ----------
    n_points : int
        Number of points (``n_points - 1`` equal arcs).
    with_tangents : bool
        Also return the exact unit tangents at the points.

    Returns
    -------
    ndarray or tuple
        (n_points, 2) array, or (points, tangents) if ``with_tangents``.
    """
    if n_points < 3:
        raise ValueError(f"n_points must be >= 3, got {n_points}")
    from scipy.special import ellipkinc

    m = _m_of(elastica_constants().alpha_loop)
    u1 = ellipkinc(math.asin(1.0 / math.sqrt(2.0 * m)), m)
    from scipy.special import ellipk

    big_u = 2.0 * ellipk(m) - u1
    # start at P: u = U where phi = pi/2 going downwards; run backwards so the start tangent
    # is the reverse, then flip so the loop stands above P with tangent +y at the start.
    u = np.linspace(big_u, -big_u, n_points)
    pts, tan = _elliptic_point(u, m)
    tan = -tan  # traversal direction is decreasing u
    p0 = pts[0].copy()
    pts = pts - p0
    # reflect y so that the loop lies above P
    pts[:, 1] *= -1.0
    tan[:, 1] *= -1.0
    # make the start tangent +y (it is +-y by construction)
    if tan[0, 1] < 0:
        pts[:, 0] *= -1.0
        tan[:, 0] *= -1.0
        pts[:, 1] *= -1.0
        tan[:, 1] *= -1.0
    scale = 1.0 / (2.0 * big_u)
    pts *= scale
    pts[-1] = pts[0]
    return (pts, tan) if with_tangents else pts


def _eight_data() -> tuple[float, float]:
    from scipy.special import ellipk

    m = _m_of(elastica_constants().alpha_8)
    return m, float(ellipk(m))


def eight_curve(n_points: int = 400, *, with_tangents: bool = False, u_start: float = 0.0
                ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The closed figure-eight elastica (Appendix D, Fig. energy_calc b).

    Exact elliptic solution over one period ``4K``, normalized to total length 1, points
    equally spaced in arc length, first point repeated at the end. The crossing point is at
    the origin and the lobes are stacked along ``y``.

    Parameters
    ----------
    n_points : int
        Number of points including the repeated end point.
    with_tangents : bool
        Also return the exact unit tangents.
    u_start : float
        Starting point, as a fraction of the period (0: bottom apex).

    Returns
    -------
    ndarray or tuple
        The 8's (n_points, 2) points, or (points, tangents) if ``with_tangents``.
    """
    if n_points < 4:
        raise ValueError(f"n_points must be >= 4, got {n_points}")
    m, k_ = _eight_data()
    u = u_start * 4.0 * k_ + np.linspace(0.0, 4.0 * k_, n_points)
    pts, tan = _elliptic_point(u, m)
    pts /= 4.0 * k_
    pts[-1] = pts[0]
    return (pts, tan) if with_tangents else pts


def eighty_curve(n_points: int = 600, *, split: bool = False
                 ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The "80" structure (§VII): a figure-eight and a circle touching tangentially.

    The 8 is the exact elastica (:func:`eight_curve`); the circle 0 touches the rightmost point
    of its upper lobe from outside with the same tangent. Lengths follow (eq. (28)),
    ``L_p / L = (eps_p / eps_80)^(1/2)``, with total length 1. The returned path goes once
    around the 8 from the contact point and then once around the circle, so that it is one
    closed curve with a continuous tangent (the planar shadow of the structure; the paper does
    not give the 3D placement of the contact) whose energy is ``eps_80``. Points are equally
    spaced in arc length; the first point is repeated at the end.

    Parameters
    ----------
    n_points : int
        Number of points of the path.
    split : bool
        Return ``(eight, circle)``, two closed arrays, instead of the single path.

    Returns
    -------
    ndarray or tuple
        (n_points, 2) array, or the tuple ``(eight, circle)`` if ``split``.
    """
    if n_points < 8:
        raise ValueError(f"n_points must be >= 8, got {n_points}")
    from scipy.special import ellipkinc

    c = elastica_constants()
    m, k_ = _eight_data()
    f8 = math.sqrt(c.eps_8 / c.eps_80)
    f0 = 1.0 - f8  # = (eps_0 / eps_80)^(1/2)
    u1 = float(ellipkinc(math.asin(1.0 / math.sqrt(2.0 * m)), m))
    cand = np.array([2.0 * k_ - u1, 2.0 * k_ + u1])
    cpts, ctan = _elliptic_point(cand, m)
    j = int(np.argmax(cpts[:, 0]))
    u_c = float(cand[j])
    p_c = cpts[j] / (4.0 * k_) * f8
    t_c = ctan[j] / np.linalg.norm(ctan[j])
    normal = np.array([1.0, 0.0])  # outward at the rightmost point
    radius = f0 / (2.0 * math.pi)
    centre = p_c + radius * normal

    s = np.linspace(0.0, 1.0, n_points)
    out = np.empty((n_points, 2))
    on8 = s <= f8
    u = u_c + s[on8] / f8 * 4.0 * k_
    p8, _ = _elliptic_point(u, m)
    out[on8] = p8 / (4.0 * k_) * f8
    th = (s[~on8] - f8) / radius
    out[~on8] = (centre - radius * np.cos(th)[:, None] * normal
                 + radius * np.sin(th)[:, None] * t_c)
    out -= p_c  # contact point at the origin
    out[-1] = out[0]
    if not split:
        return out
    eight = np.vstack([out[on8], out[:1]])
    circle = np.vstack([out[:1], out[~on8]])
    return eight, circle
