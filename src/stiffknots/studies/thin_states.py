"""The thin-limit ground state of a knot: its census at the atlas width, every state followed to
w = 0, the lowest limit (§V A, §VI).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007: the paper's question is the ground state in
the thin limit w/L → 0. The ground state can change with the width, so one annealed series
answers it only if the series happens to sit in the right state. This study

1. anneals the knot in the tube model at the atlas's width (w = 1/√2, N = 150, w/L = 0.0047;
   :func:`~stiffknots.problems.closed_plan.plan_anneal`, the tube's verdict rule of three
   independent searches) and takes the **census** of its final chains
   (:func:`stiffknots.analysis.census`: states within 15 % of the lowest);
2. follows **every state** (or the ``states`` lowest) down a ladder of w/L by continuation and
   extrapolates each to its own ``ε*_s`` (:func:`stiffknots.studies.branches.follow_states`);
3. names the **thin-limit ground state** — the lowest ``ε*_s`` — with its margin over the next
   state in their combined errors, and says where it is not the finite-width ground (the
   branches cross) and near which w/L;
4. sets beside each ``ε*_s`` the structure route's value at w = 0 (:func:`structure_route`:
   the structure graph of the state's thinnest chain solved at w = 0, or the named structure
   of its class where the graph has a line-braid) — the two routes agree when they differ by
   less than twice the branch's error or 0.5 %.

Nothing here but ``epsilon_thin`` values are thin-limit numbers: every other states its w/L
and N.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from typing import Any

from stiffknots._version import __version__
from stiffknots.problems import validate as V
from stiffknots.problems.base import solve
from stiffknots.studies.branches import LADDER, follow_states

__all__ = ["BUDGETS", "AGREE_REL", "MAX_COMPARED_ERROR", "route_difference", "routes_agree",
           "structure_route", "thin_limit_states"]

#: What one run spends: the ladder of w/L and how each width is reached.
BUDGETS: dict[str, dict[str, Any]] = {
    "small": {"widths": (0.004, 0.002, 0.001, 0.0005), "rel_error": 2e-3,
              "relax_factor": 0.1, "replicas": 2, "measure_k": False},
    "default": {"widths": LADDER, "rel_error": 1e-3, "relax_factor": 0.2, "replicas": 2,
                "measure_k": True},
}

#: Two routes agree within twice the branch's error or this fraction of ε.
AGREE_REL = 5e-3
#: A branch whose extrapolation's error exceeds this fraction of its ε* is not compared: an
#: agreement within twice such an error decides nothing (8_3's branch, still falling by 3 a
#: width at w/L = 0.00025, extrapolated to 114.5 ± 15.2 and "agreed" with the cage's 126.47).
MAX_COMPARED_ERROR = 0.02


def routes_agree(epsilon_thin: float | None, error: float | None, route: dict) -> bool | None:
    """Whether a state's two routes agree: the branch's ε* and the structure route's ε within
    twice the branch's error or :data:`AGREE_REL` of ε. None (not compared) when either
    number is missing, the structure route's solution is not a converged minimum or lets
    strands meet, or the branch's error exceeds :data:`MAX_COMPARED_ERROR` of its ε*."""
    se = route.get("epsilon")
    if se is None or epsilon_thin is None or not route.get("keeps_knot") \
            or not route.get("minimum", True):
        return None
    err = error or 0.0
    if err > MAX_COMPARED_ERROR * abs(epsilon_thin):
        return None
    return abs(epsilon_thin - se) <= max(2 * err, AGREE_REL * se)


def too_wide(epsilon_thin: float | None, error: float | None) -> str | None:
    """The reason a branch is not compared for its error (None when it is narrow enough)."""
    if epsilon_thin is None or error is None or error <= MAX_COMPARED_ERROR * abs(epsilon_thin):
        return None
    return (f"not compared: the branch's extrapolation {epsilon_thin:.2f} ± {error:.2g} is "
            f"{100 * error / abs(epsilon_thin):.0f} % uncertain (over "
            f"{100 * MAX_COMPARED_ERROR:.0f} %): the branch is far from its limit on this "
            "ladder, and an agreement within such an error decides nothing")


def _crossing(lower: dict, finite: dict) -> float | None:
    """The widest ladder width at which branch ``lower`` (the thin-limit ground) lies below
    branch ``finite`` (the ground at the atlas width), both still in their states."""
    for a, b in zip(lower["points"], finite["points"], strict=False):
        if a["in_fit"] and b["in_fit"] and a["epsilon"] < b["epsilon"]:
            return a["w_over_L"]
    return None


def _thinned(points: Any, most: int = 200) -> Any:
    """At most ``most`` of an arc's points, its two ends kept (for storage and drawing)."""
    import numpy as np

    q = np.asarray(points, dtype=float)
    if len(q) <= most:
        return q
    return q[np.unique(np.linspace(0, len(q) - 1, most).round().astype(int))]


def structure_route(branch: dict, *, say: Callable[[str], None] | None = None,
                    tag: str = "") -> dict[str, Any]:
    """The structure route (w = 0) of a followed state: the structure graph of its thinnest
    chain before any event turned into the w = 0 problem and solved
    (:func:`stiffknots.analysis.structure_route.solve_chain`, read at ``max(w, 0.5)``); where
    the graph has a line-braid the route cannot translate yet, or its solution is no converged
    minimum or lets strands meet, the named structure of the state's class (CB(i), the 80, the
    4-fold cage) with a note saying why; else none, or the flagged solution, not compared.

    Returns ``{"epsilon", "error", "name", "method", "keeps_knot", "min_arc_distance",
    "minimum", "negative_modes", "curves", "w_over_L", "note"}`` (``epsilon`` None when there
    is no route; a route that is not a converged minimum or lets strands meet is not compared;
    ``curves``: the w = 0 solution's arcs, at most 200 points each, when the chain's graph was
    solved).
    """
    from stiffknots.analysis.structure_route import StructureRouteError, solve_chain
    from stiffknots.studies.thin_limit import CLASSIFY_D_MIN, structure_value

    say = say or (lambda _s: None)
    pts = branch["points"]
    last = max((i for i, p in enumerate(pts) if p["in_fit"]), default=len(pts) - 1)
    p = pts[last]
    out: dict[str, Any] = {"epsilon": None, "error": None, "name": None, "method": None,
                           "keeps_knot": None, "min_arc_distance": None, "minimum": None,
                           "negative_modes": None, "curves": None,
                           "w_over_L": p["w_over_L"], "note": None}
    named = structure_value(p.get("label", branch["start"]["label"]),
                            p.get("multiplicity", branch["start"]["multiplicity"]))

    def use_named(why: str) -> dict[str, Any]:
        out.update(epsilon=named["epsilon"], error=named["error"], name=named["name"],
                   method="named structure (theory.structures)", keeps_knot=True,
                   minimum=True, note=f"{why}; the named {named['name']} solved instead")
        return out

    try:
        with warnings.catch_warnings():   # read at d > w on purpose (CLASSIFY_D_MIN)
            warnings.simplefilter("ignore")
            r = solve_chain(branch["chains"][last], max(p["w"], CLASSIFY_D_MIN))
    except StructureRouteError as exc:
        if named is None:
            out["note"] = f"no structure route: {exc}"
            return out
        return use_named(f"the chain's graph is not translated ({exc})")
    say(f"{branch['knot']} {tag}: structure route ({r.name}, {r.arcs} arcs): ε = "
        f"{r.epsilon:.6f} ± {r.error:.1g}"
        + ("" if r.keeps_knot else " — FLAGGED: strands meet away from the junctions")
        + ("" if r.minimum else f" — not a converged minimum ({r.negative_modes} negative "
                                f"mode(s))"))
    problem = None
    stopped = not r.minimum and r.details.get("budget_hit", False)
    if not r.keeps_knot:
        problem = (f"its w = 0 solution brings two arcs within {r.min_arc_distance:.2g} L of "
                   "each other away from the junctions (strands may have passed)")
    elif stopped:
        problem = (f"the coarse search stopped at its {r.details['coarse_budget_s']:g} CPU s "
                   f"budget "
                   f"without a converged minimum ({r.negative_modes} negative mode(s))")
    elif not r.minimum:
        problem = (f"its w = 0 solution is not a converged minimum ({r.negative_modes} "
                   f"negative mode(s), error {r.error:.2g})")
    if problem is not None and named is not None:
        return use_named(f"the chain's graph ({r.name}, {r.arcs} arcs): {problem}")
    if stopped:
        # what Newton reached from a stopped search is no structure's energy: no number
        out.update(name=r.name, method=f"the graph of the chain at w/L = {p['w_over_L']:g} "
                   f"({r.arcs} arcs, {r.junctions} junctions)", minimum=False,
                   note=f"no structure route: {problem}")
        return out
    out.update(epsilon=r.epsilon, error=r.error, name=r.name,
               method=f"the graph of the chain at w/L = {p['w_over_L']:g} solved at w = 0 "
                      f"({r.arcs} arcs, {r.junctions} junctions)",
               keeps_knot=r.keeps_knot, min_arc_distance=r.min_arc_distance,
               minimum=r.minimum, negative_modes=r.negative_modes,
               curves=[{"points": _thinned(c["points"]).tolist(),
                        "multiplicity": c["multiplicity"]} for c in r.curves])
    if problem is not None:
        out["note"] = f"{problem}: not compared"
    return out


def thin_limit_states(knot: Any, budget: str = "default", seed: int = 0, *,
                      states: int | None = None, window: float = 0.15,
                      runner: Callable[[Any, str], Any] | None = None,
                      say: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Census, branches and the thin-limit ground state of a knot (module docstring).

    Parameters
    ----------
    knot
        A catalogue entry or name.
    budget : str
        ``"small"`` (4 widths, 0.004 … 0.0005, k by the polygon rule) or ``"default"`` (9
        widths down to 0.00025, k measured per branch); :data:`BUDGETS`.
    seed : int
        Seed of the census's annealing and of every relaxation.
    states : int or None
        Follow only the lowest ``states`` states of the census (default: all).
    window : float
        The census's window above the lowest ε.
    runner, say
        As :func:`stiffknots.studies.thin_limit.thin_limit`.

    Returns
    -------
    dict
        ``knot``, ``budget``, ``seed``, ``version``, ``wall_time``; ``census`` (the anneal's
        ``epsilon``, ``converged``, ``width``, replicas and the census's states);
        ``states``: one per followed state, by the census's order — ``shape``,
        ``structure``, ``epsilon`` (at the atlas width), ``epsilon_thin``, ``error``,
        ``event``, ``structure_epsilon`` and ``structure_error`` (the structure route at
        w = 0, or None), ``structure_route`` (how, and its note), ``agree``, ``points``,
        ``chains``, ``fit``, ``discretisation``; ``ground`` (the index into ``states`` of the lowest
        ``epsilon_thin``), ``margin`` (the next state's ``epsilon_thin`` minus the ground's,
        and in combined errors), ``crossing`` (None, or the width at which the thin-limit
        ground first lies below the finite-width ground); and, the ground's, ``shape``,
        ``epsilon_thin``, ``error``.
    """
    from stiffknots.analysis.census import census
    from stiffknots.knots.catalogue import Knot, get_knot
    from stiffknots.problems.closed_plan import plan_anneal

    V.choice("budget", budget, tuple(BUDGETS))
    seed = V.seed(seed)
    if states is not None:
        states = V.integer("states", states, 1, 1000)
    k = knot if isinstance(knot, Knot) else get_knot(knot)
    run = runner or (lambda p, _label: solve(p))
    say = say or (lambda _s: None)
    t0 = time.time()
    plan = plan_anneal(k, exclusion="tube", seed=seed)
    res = run(plan.problem(), f"census of {k.name}: anneal at the atlas width")
    if res.interrupted:
        raise KeyboardInterrupt
    items = [{"coords": r.coords, "epsilon": r.epsilon, "label": r.observables["label"],
              "multiplicity": r.observables.get("multiplicity"),
              "search": r.lineage if r.lineage is not None else i,
              "structure": r.observables.get("structure")}
             for i, r in enumerate(res.replicas)]
    c = census(items, window=window)
    width = res.width.as_dict()
    say(f"{k.name}: census at {width['text']}: {len(c.states)} state(s) within "
        f"{100 * window:g} % of {c.ground.epsilon:.3f} from {len(items)} replicas: "
        + ", ".join(f"{s.name} {s.epsilon:.3f} ({s.searches} searches)" for s in c.states))
    chosen = c.states[:states] if states else c.states
    starts = [{"coords": items[s.representative]["coords"], "name": s.name, "label": s.label,
               "multiplicity": s.multiplicity, "structure": s.structure,
               "epsilon": s.epsilon, "searches": s.searches} for s in chosen]
    out = follow_census(k, starts, budget=budget, seed=seed, runner=run, say=say)
    out["parameters"]["states"] = states
    return {"knot": k.name, "budget": budget, "seed": seed, "version": __version__,
            "census": {"epsilon": res.best.epsilon, "converged": bool(res.converged),
                       "convergence": res.convergence, "width": width,
                       "replicas": len(items), "window": window,
                       "states": [s.to_dict() for s in c.states]},
            **out, "wall_time": time.time() - t0}


def follow_census(knot: Any, starts: list[dict], *, budget: str = "default", seed: int = 0,
                  runner: Callable[[Any, str], Any] | None = None,
                  say: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Follow the states of a census to w = 0, each by both routes, and name the thin-limit
    ground (steps 2–4 of the module docstring; the atlas's thin stage runs this per knot).

    Parameters
    ----------
    knot
        A catalogue entry or name.
    starts : list of dict
        The states in the census's order (by increasing ε), each with ``coords`` (its
        representative chain at the atlas width), ``name``, ``label``, ``multiplicity``,
        ``structure``, ``epsilon`` and ``searches``.
    budget, seed, runner, say
        As :func:`thin_limit_states`.

    Returns
    -------
    dict
        ``states`` (one row per start, as :func:`thin_limit_states` describes), ``ground``,
        ``margin``, ``crossing``, ``shape``, ``epsilon_thin``, ``error`` and ``parameters``.
    """
    from stiffknots.knots.catalogue import Knot, get_knot

    V.choice("budget", budget, tuple(BUDGETS))
    k = knot if isinstance(knot, Knot) else get_knot(knot)
    run = runner or (lambda p, _label: solve(p))
    say = say or (lambda _s: None)
    b = BUDGETS[budget]
    fs = follow_states(k, [{"coords": s["coords"], "tag": f"state {i} ({s['name']})"}
                           for i, s in enumerate(starts)],
                       seed=V.seed(seed), runner=run, say=say, **b)
    rows = []
    for i, (s, br) in enumerate(zip(starts, fs["branches"], strict=True)):
        route = structure_route(br, say=say, tag=f"state {i} ({s['name']})")
        eps_t, err = br["epsilon_thin"], br["error"]
        agree = routes_agree(eps_t, err, route)
        rows.append({
            "shape": s["name"], "label": s["label"], "multiplicity": s["multiplicity"],
            "structure": s["structure"], "epsilon": s["epsilon"], "searches": s["searches"],
            "epsilon_thin": eps_t, "error": err, "event": br["event"],
            "events": br["events"], "shape_thin": br["points"][-1]["shape"],
            "structure_epsilon": route["epsilon"], "structure_error": route["error"],
            "structure_name": route["name"], "structure_route": route,
            "agree": agree,
            "difference": (route_difference(eps_t, route["epsilon"], route["name"], agree)
                           or (too_wide(eps_t, err) if route["epsilon"] is not None
                               else None)),
            "points": br["points"], "chains": br["chains"],
            "fit": br["fit"], "discretisation": br["discretisation"],
            "parameters": br["parameters"]})
    return {**summarise_states(rows), "states": rows,
            "parameters": {**b, "widths": list(b["widths"])}}


def route_difference(epsilon_thin: float | None, structure_epsilon: float | None,
                     structure_name: str | None, agree: bool | None) -> str | None:
    """Why a state's two routes differ, in one sentence (None when they agree or were not
    compared).

    Measured on branches continued to w/L = 6.25·10⁻⁵ (``bench/thin_deep.py``, the docs'
    thin-limit page): circular braids approach w = 0 as w², a cage without twist linearly,
    but states with point-braids (the 80s, most cages) with a local exponent that keeps
    falling (towards ½: a twist of two strands inside a point-braid costs ∝ w^½), so one power
    law fitted to the ladder lands *above* their limit — an upper estimate, the structure
    route the number to read. A branch *below* its structure's w = 0 value has another limit
    than the structure read from its thinnest chain.
    """
    if agree is not False or epsilon_thin is None or structure_epsilon is None:
        return None
    pct = 100 * (epsilon_thin - structure_epsilon) / structure_epsilon
    braided = structure_name == "80" or "point-braid" in (structure_name or "")
    if pct > 0 and braided:
        return (f"the branch's extrapolation lies {pct:.2f} % above the w = 0 solution: "
                "states with point-braids approach w = 0 more slowly than one power law "
                "below the ladder, so the extrapolation is an upper estimate and the structure "
                "route the value to read")
    if pct > 0:
        return (f"the branch's extrapolation lies {pct:.2f} % above the w = 0 solution: the "
                "branch has not reached its asymptotic regime on this ladder (an upper "
                "estimate)")
    return (f"the branch's extrapolation lies {-pct:.2f} % below the w = 0 solution of the "
            "structure read from its thinnest chain: that structure is not this branch's limit")


def summarise_states(rows: list[dict]) -> dict[str, Any]:
    """The thin-limit ground of followed states (rows of :func:`follow_census`): ``ground``
    (the index of the lowest ``epsilon_thin``, None when none has one), ``margin`` (the next
    state's ``epsilon_thin`` minus the ground's, and in combined errors), ``crossing`` (None,
    or the widest width at which the thin-limit ground lies below state 0, the ground at the
    atlas width), and the ground's ``shape``, ``epsilon_thin`` and ``error``."""
    fitted = [(r["epsilon_thin"], i) for i, r in enumerate(rows)
              if r["epsilon_thin"] is not None]
    g = min(fitted)[1] if fitted else None
    margin = crossing = None
    if g is not None:
        others = [r for i, r in enumerate(rows) if i != g and r["epsilon_thin"] is not None]
        if others:
            nxt = min(others, key=lambda r: r["epsilon_thin"])
            gap = nxt["epsilon_thin"] - rows[g]["epsilon_thin"]
            sig = math.hypot(nxt["error"] or 0.0, rows[g]["error"] or 0.0)
            margin = {"next": rows.index(nxt), "gap": gap,
                      "sigmas": gap / sig if sig > 0 else None}
        if g != 0:
            crossing = _crossing(rows[g], rows[0])
    ground = rows[g] if g is not None else None
    return {"ground": g, "margin": margin, "crossing": crossing,
            "shape": None if ground is None else ground["shape"],
            "epsilon_thin": None if ground is None else ground["epsilon_thin"],
            "error": None if ground is None else ground["error"]}

