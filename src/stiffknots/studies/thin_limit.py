"""The thin limit ``eps* = lim_{w -> 0} eps*_w`` of one knot, measured (§V A), next to the
structure route at ``w = 0`` (§V B).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V A: the paper's subject is the limit of
the minimum energy ``eps*_w`` of a tube of width ``w`` as ``w/L -> 0``; ``eps*_w`` rises with
``w``. Every Monte Carlo number is at a finite width. This study

1. anneals the knot in the tube model at the widest ``w/L`` of the series (``w = (w/L)·N``
   bond units, :class:`~stiffknots.problems.closed.ClosedAnneal`, polished), N from the rule
   :func:`~stiffknots.problems.validate.beads_for_width` (the same N for every width);
2. walks down the series by continuation: the polished chain of one width is relaxed at the
   next, thinner one (:class:`~stiffknots.problems.relax.Relax`: a thinner tube always fits
   the thicker chain); with the ``default`` budget every width is also annealed afresh from
   the built-in starts, and the lower of the two is the point (so that a ground state that
   changes with ``w`` is found; the shape of each point is reported);
3. corrects each point for the discretisation, ``eps = eps_N (1 + k/N^2)`` with
   ``k = eps_N / 6`` (the regular polygon's leading term; with the ``default`` budget ``k``
   is measured on the knot itself by relaxing the thinnest point again at 2 N), the
   correction's uncertainty being a systematic error common to all points;
4. fits ``eps(w) = eps* + a w^p`` (:func:`stiffknots.analysis.extrapolate.extrapolate`) to the
   points of the thinnest point's shape and states ``eps*`` with an error bar: fit
   (statistical and exponent) and discretisation in quadrature;
5. compares with the structure route: ``CB(i) = 2 pi^2 i^2`` (eq. (30)), the 80 and the
   4-fold cage ``eps*_4C`` solved at ``w = 0``
   (:func:`stiffknots.theory.structures.structure_energy`).

Nothing here is a thin-limit number except ``epsilon_thin``: every point states its ``w/L``
and ``N``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from stiffknots._version import __version__
from stiffknots.analysis.extrapolate import extrapolate
from stiffknots.engine.params import MoveParams
from stiffknots.errors import InvalidParameter, UserInputError
from stiffknots.problems import validate as V
from stiffknots.problems.base import default_moves, solve
from stiffknots.width import Width

BUDGET_NAMES = ("small", "default")


@dataclass(frozen=True)
class Budget:
    """What one thin-limit run spends.

    Attributes
    ----------
    widths : tuple of float
        The series of ``w/L``, widest first.
    rel_error : float
        Relative discretisation error of the N rule (before the correction).
    moves_factor : float
        Annealing moves per replica, as a fraction of :func:`default_moves` (N).
    relax_factor : float
        Relaxation moves of a continuation step, same unit.
    rounds, replicas : int
        The convergence rule of each annealing (rounds of replicas).
    anneal_each : bool
        Anneal every width afresh too (else only the widest one).
    measure_k : bool
        Measure the discretisation coefficient ``k`` at the thinnest width (2 N).
    """

    widths: tuple[float, ...]
    rel_error: float
    moves_factor: float
    relax_factor: float
    rounds: int
    replicas: int
    anneal_each: bool
    measure_k: bool


#: the named budgets of the study, by name
BUDGETS = {
    # a few minutes per knot on two cores
    "small": Budget(widths=(0.004, 0.002, 0.001, 0.0005), rel_error=2e-3, moves_factor=0.25,
                    relax_factor=0.1, rounds=1, replicas=2, anneal_each=False, measure_k=False),
    # at most about 15 minutes per knot on two cores (3_1, 4_1)
    "default": Budget(widths=(0.004, 0.003, 0.002, 0.0014, 0.001, 0.0007, 0.0005, 0.00035,
                              0.00025), rel_error=1e-3, moves_factor=0.3, relax_factor=0.2,
                      rounds=2, replicas=2, anneal_each=True, measure_k=True),
}

#: per-point floor of the standard error, relative: the spread left after the polish between
#: chains of the same state and N (3_1, w/L = 0.002, N = 100…300: 3e-4 absolute)
POINT_FLOOR = 2e-6
#: relative uncertainty of the polygon coefficient k = eps/6 when not measured: for circular
#: braids it is the exact leading term (measured to 0.3 % of the correction for 3_1); other
#: shapes have non-uniform curvature and a larger k (Cauchy–Schwarz), not known beforehand
K_UNCERTAINTY = {"CB": 0.02, "other": 1.0}


def structure_value(label: str | None, multiplicity: int | None) -> dict | None:
    """The structure route's ``eps`` at ``w = 0`` for a shape class, or None.

    ``CB`` of index ``i`` -> ``CB(i)`` = 2 pi^2 i^2 (eq. (30)), ``80`` and ``4C`` solved by
    :func:`stiffknots.theory.structures.structure_energy` (§V B); other shapes have none.
    """
    from stiffknots.theory.structures import structure_energy

    if label == "CB" and multiplicity:
        name = f"CB({int(multiplicity)})"
    elif label in ("80", "4C"):
        name = label
    else:
        return None
    r = structure_energy(name)
    return {"name": name, "epsilon": r["epsilon"], "error": r["error"], "method": r["method"]}


#: contact distance (bonds) below which the shape is read at this distance instead of w: the
#: classifier's contact zones are ``factor × d`` wide, and in a tube much thinner than a bond
#: the strands of a point-braid part within a few beads (4_1's cage at w/L = 0.001, N = 122,
#: w = 0.12, reads "other" at d = w and "4C" at d = 0.5)
CLASSIFY_D_MIN = 0.5


def _shape(res) -> tuple[str, str | None, int | None]:
    """Shape of the best chain: the run's own verdict, or read again at
    :data:`CLASSIFY_D_MIN` when the tube is thinner than that."""
    import warnings

    from stiffknots.analysis import classify

    obs = res.best.observables
    w = res.settings.get("params", {}).get("w") if isinstance(res.settings, dict) else None
    if w is None or w >= CLASSIFY_D_MIN:
        return obs["shape"], obs.get("label"), obs.get("multiplicity")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the bead-rule warning: a tube chain, on purpose
        c = classify(res.best.coords, d=CLASSIFY_D_MIN)
    return (f"CB{c.multiplicity}" if c.label == "CB" else c.label), c.label, c.multiplicity


def _spread(res, rel_tol: float = 1e-3) -> float:
    """Spread of the replicas in the best one's state (shape and eps within ``rel_tol``)."""
    b = res.best
    same = [r.epsilon for r in res.replicas
            if r.observables.get("shape") == b.observables.get("shape")
            and abs(r.epsilon - b.epsilon) <= rel_tol * b.epsilon]
    return max(same) - min(same) if len(same) > 1 else 0.0


def doubled(coords: Any) -> np.ndarray:
    """A closed chain with every bond cut at its midpoint and scaled by 2: the same curve at
    2 N unit bonds, so the same tube (a resampling to another N need not keep it: a polished
    chain touches its tube)."""
    x = np.asarray(coords, dtype=float)
    x2 = np.empty((2 * len(x), 3))
    x2[0::2] = 2 * x
    x2[1::2] = x + np.roll(x, -1, axis=0)
    return x2


def k_from(e1: float, e2: float, n1: int, n2: int) -> float:
    """The polygon coefficient ``k`` of ``eps_N = eps (1 - k/N^2)`` from the energies of one
    state at two bead counts: ``k = (e2 - e1) / (e2 (1/N1^2 - 1/N2^2))``."""
    return (e2 - e1) / (e2 * (1 / n1**2 - 1 / n2**2))


def correct_and_fit(points: list[dict], n: int, disc: dict) -> tuple[dict | None,
                                                                     float | None,
                                                                     float | None]:
    """Correct every point for the discretisation and extrapolate the points marked
    ``in_fit`` to ``w -> 0``.

    Each point (``epsilon_raw``, ``spread``, ``w_over_L``, ``in_fit``) gains ``epsilon`` =
    ``epsilon_raw (1 + k/N^2)`` and ``sigma`` = its spread ⊕ :data:`POINT_FLOOR`; ``disc``
    (``k``, ``k_error``) gains ``error``, the systematic error of the common correction at the
    thinnest fitted point. Returns ``(fit, eps_thin, error)`` — None each with fewer than two
    points in the fit; the error is the fit's ⊕ the correction's (one standard error).
    """
    k_used, k_err = disc["k"], disc["k_error"]
    for p in points:
        e = p["epsilon_raw"]
        p["epsilon"] = e * (1 + k_used / n**2)
        p["sigma"] = math.hypot(p["spread"], POINT_FLOOR * e)
    fit_pts = [p for p in points if p["in_fit"]]
    thin = fit_pts[-1] if fit_pts else points[-1]
    disc["error"] = thin["epsilon_raw"] * k_err / n**2
    if len(fit_pts) < 2:
        return None, None, None
    f = extrapolate([p["w_over_L"] for p in fit_pts], [p["epsilon"] for p in fit_pts],
                    [p["sigma"] for p in fit_pts])
    return f.as_dict(), f.epsilon, math.hypot(f.error, disc["error"])


def thin_limit(knot, budget: str = "small", seed: int = 0, *,
               widths: Sequence[float] | None = None, beads: int | None = None,
               runner: Callable[[Any, str], Any] | None = None,
               say: Callable[[str], None] | None = None) -> dict[str, Any]:
    """``eps*_w`` of ``knot`` over a series of ``w/L``, extrapolated to ``w -> 0`` (§V A).

    Parameters
    ----------
    knot
        A catalogue entry (:class:`~stiffknots.knots.catalogue.Knot`) or name.
    budget : str
        ``"small"`` (minutes) or ``"default"`` (up to about 15 min per knot on 2 cores);
        see :data:`BUDGETS`.
    seed : int
        The seed of every run (replica seeds derive from it).
    widths : sequence of float or None
        The series of ``w/L`` (default: the budget's), at least two.
    beads : int or None
        N of every point (default: :func:`~stiffknots.problems.validate.beads_for_width`
        with the knot's upper bound as the energy estimate).
    runner : callable or None
        ``runner(problem, label)`` solves one problem (the command line passes one with
        live progress); default :func:`~stiffknots.problems.base.solve`.
    say : callable or None
        Receives one line per finished step.

    Returns
    -------
    dict
        ``knot``, ``shape`` (of the thinnest point), ``epsilon_thin``, ``error``, ``points``
        (each ``w_over_L``, ``beads``, ``w``, ``epsilon`` (corrected), ``epsilon_raw``,
        ``sigma``, ``shape``, ``converged``, ``route``), ``fit``, ``discretisation``,
        ``structure`` (None when the shape has no structure value), ``version``, ``seed``,
        ``budget``, ``parameters``, ``wall_time``; and ``chains``: the best chain of each
        point (coordinates, for the caller to save).
    """
    from stiffknots.chain import Chain
    from stiffknots.knots.catalogue import Knot, get_knot
    from stiffknots.problems.closed import ClosedAnneal
    from stiffknots.problems.closed_plan import beads_for_knot
    from stiffknots.problems.relax import Relax
    from stiffknots.theory.bounds import closed_bounds

    V.choice("budget", budget, BUDGET_NAMES)
    b = BUDGETS[budget]
    seed = V.seed(seed)
    k = knot if isinstance(knot, Knot) else get_knot(knot)
    name = k.name
    ws = sorted((float(x) for x in (widths if widths is not None else b.widths)), reverse=True)
    if len(set(ws)) < 2:
        raise InvalidParameter("widths", list(widths or []), "at least two different w/L")
    bnd = closed_bounds(k.bridge_number, k.braid_index)
    n = V.beads(beads) if beads is not None else beads_for_knot(k, ws[0], b.rel_error)
    widths_ = {wl: Width.tube(n, w_over_L=wl) for wl in ws}
    run = runner or (lambda p, _label: solve(p))
    say = say or (lambda _s: None)
    anneal_moves = V.moves(max(1_000_000, round(b.moves_factor * default_moves(n))))
    relax_moves = V.moves(max(200_000, round(b.relax_factor * default_moves(n))))
    t0 = time.time()

    def anneal_at(wl: float):
        p = ClosedAnneal(k, beads=n, moves=anneal_moves, replicas=b.replicas, seed=seed,
                         params=MoveParams().at_width(widths_[wl]), rounds=b.rounds)
        return run(p, f"thin-limit {name} w/L = {wl:g}: anneal")

    def relax_at(coords, wl: float, nn: int, what: str = "relax"):
        p = Relax(Chain(coords, closed=True), nn, relax_moves, b.replicas, seed,
                  exclusion="tube", w_over_L=wl, knot=name)
        return run(p, f"thin-limit {name} w/L = {wl:g}: {what}")

    points: list[dict] = []
    chains: dict[str, Any] = {}
    prev = None
    for wl in ws:
        cands = []
        if prev is None or b.anneal_each:
            cands.append(("anneal", anneal_at(wl)))
        if prev is not None:
            cands.append(("continuation", relax_at(prev.best.coords, wl, n)))
        for _, r in cands:
            if r.interrupted:
                raise KeyboardInterrupt
        route, res = min(cands, key=lambda c: c[1].best.epsilon)
        shape, label, mult = _shape(res)
        convergence = res.convergence
        run_shape = res.best.observables.get("shape")
        if run_shape != shape:  # a tube thinner than CLASSIFY_D_MIN: the verdict's words
            convergence += (f" (the run names shapes at d = w = {widths_[wl].thickness:.3g}, "
                            f"where this "
                            f"chain reads {run_shape}; read at d = {CLASSIFY_D_MIN:g} it is "
                            f"{shape})")
        sig = [_spread(res)]
        other = [c[1] for c in cands if c[1] is not res and _shape(c[1])[0] == shape]
        sig += [abs(o.best.epsilon - res.best.epsilon) for o in other]
        points.append({
            "w_over_L": wl, "beads": n, "w": widths_[wl].thickness,
            "width": widths_[wl].as_dict(), "epsilon_raw": res.best.epsilon,
            "shape": shape, "label": label, "multiplicity": mult,
            "converged": bool(res.converged), "convergence": convergence, "route": route,
            "run_shape": run_shape,
            "routes": {c[0]: {"epsilon": c[1].best.epsilon, "shape": _shape(c[1])[0]}
                       for c in cands},
            "spread": max(sig),
        })
        chains[f"{wl:g}"] = res.best.coords
        say(f"{name}: w/L = {wl:g}, N = {n}: ε_N = {res.best.epsilon:.5f} ({shape}, {route}"
            f"{'' if res.converged else ', NOT converged'})")
        prev = res

    thin = points[-1]
    # the discretisation coefficient k of eps_N = eps (1 - k/N^2)
    k_rule = thin["epsilon_raw"] / 6.0
    kind = "CB" if thin["label"] == "CB" else "other"
    disc: dict[str, Any] = {"rule": "eps = eps_N (1 + k/N^2), k = eps/6 (regular polygon)",
                            "k_rule": k_rule, "beads": n}
    k_used, k_err = k_rule, K_UNCERTAINTY[kind] * k_rule
    # 2N: every bond cut at its midpoint (and the chain scaled by 2) is the same curve, so
    # it keeps the tube exactly (a resampling to another N need not: the polished chain
    # touches its tube); the width is taken 1e-9 thinner against rounding
    n2 = 2 * n
    r2 = None
    if b.measure_k and thin["w_over_L"] * n2 < 1 and n2 <= V.MAX_BEADS:
        x2 = doubled(chains[f"{thin['w_over_L']:g}"])
        try:
            r2 = relax_at(x2, thin["w_over_L"] * (1 - 1e-9), n2,
                          f"relax at N = {n2} (discretisation)")
        except UserInputError as exc:  # the resampled chain did not fit: k from the rule
            disc["k_measurement_failed"] = str(exc)
            say(f"{name}: discretisation not measured ({exc}); k = ε/6")
    if r2 is not None:
        if r2.interrupted:
            raise KeyboardInterrupt
        e1, e2 = thin["epsilon_raw"], r2.best.epsilon
        k_meas = k_from(e1, e2, n, n2)
        disc.update(k_measured=k_meas, check_beads=n2, check_epsilon=e2,
                    check_shape=_shape(r2)[0])
        if _shape(r2)[0] == thin["shape"] and k_meas > 0:
            k_used = k_meas
            k_err = max(abs(k_meas - k_rule), 0.02 * k_rule)
        say(f"{name}: discretisation at w/L = {thin['w_over_L']:g}: ε_{n} = {e1:.5f}, "
            f"ε_{n2} = {e2:.5f}: k = {k_meas:.3f} (polygon rule ε/6 = {k_rule:.3f})")
    disc.update(k=k_used, k_error=k_err)
    for p in points:
        p["in_fit"] = p["shape"] == thin["shape"]
    fit, eps_thin, err = correct_and_fit(points, n, disc)
    struct = structure_value(thin["label"], thin["multiplicity"])
    if struct is not None and eps_thin is not None:
        struct["difference"] = eps_thin - struct["epsilon"]
        struct["in_error_bars"] = abs(eps_thin - struct["epsilon"]) / err if err else None
    decreasing = all(a["epsilon"] > b_["epsilon"] for a, b_ in pairwise(points))
    return {
        "knot": name, "shape": thin["shape"], "epsilon_thin": eps_thin, "error": err,
        "error_note": "one standard error: fit (statistical, exponent) and discretisation "
                      "in quadrature",
        "points": points, "series_decreasing": decreasing, "fit": fit,
        "discretisation": disc, "structure": struct, "bounds": {
            "lower": bnd.lower, "upper": bnd.upper, "attained_by": bnd.attained_by},
        "version": __version__, "seed": seed, "budget": budget,
        "parameters": {**asdict(b), "widths": ws, "beads": n, "anneal_moves": anneal_moves,
                       "relax_moves": relax_moves, "exclusion": "tube"},
        "wall_time": time.time() - t0, "chains": chains,
    }


def plot(result: dict, path: str | Path) -> Path:
    """Figure: ``eps`` against ``w/L`` with the fit, the limit and the structure value."""
    from stiffknots.report.figures import plot_thin_limit, save_figure

    return save_figure(plot_thin_limit(result), path)
