"""Every state followed to w = 0: the branches of a knot's census and their thin limits (§V A).

Gallotti & Pierre-Louis, "Stiff knots", PRE 2007, §V A: the thin limit of a knot is
``eps* = lim_{w -> 0} eps*_w``. The ground state can change with the width, so the limit is
the lowest of its *states'* limits: each state of the knot's census
(:mod:`stiffknots.analysis.census`) is followed down a ladder of ``w/L`` by continuation and
extrapolated on its own.

At each width of the ladder the previous point's chain is resampled to the N of the ladder
(the N rule at its widest width, :func:`~stiffknots.problems.closed_plan.beads_for_knot`;
the same N throughout, so one discretisation correction serves every point) and relaxed in the
thinner tube (:class:`~stiffknots.problems.relax.Relax`: a short low-temperature Monte Carlo
then the final minimiser, knot type verified; a chain admissible for a tube is admissible for
any thinner one). Each point records ε, N, the shape class, the structure (§V B) and its shape
distance from the previous point (:func:`~stiffknots.analysis.identity.shape_distance`).

A branch is the run of points reached continuously: no step longer than :data:`JUMP` (a
continuous deformation moves a chain by ≲ 0.01 L between neighbouring widths of the ladder;
distinct states lie ≥ 0.05 L apart). What happens on the way is recorded as **events**
(``events``), never hidden:

* ``changed class`` — the shape class read at a point differs from the one before (6_1's
  `other` becomes a 4-fold cage below w/L ≈ 0.001). The step is small: the state deformed
  continuously into another class, and the branch — the same state, followed — is still fitted
  through it; its thin limit is the limit of what it became;
* ``jumped`` — a step longer than :data:`JUMP`: the relaxation left the state; the fit stops
  before it;
* ``merged`` — two branches whose points at one width are one state
  (:func:`~stiffknots.analysis.identity.shape_distance` within
  :data:`~stiffknots.analysis.identity.SAME_STATE_DISTANCE`, ε within 0.1 %): the
  higher-ranked one's points from there are not fitted (they are the other's).

``event`` is the event that ended the fit (a jump or a merger), or None. A branch with such an
event has no limit of its own at w = 0 (``epsilon_thin`` None: the state folded into another
or became another's); what its points before the event extrapolate to is kept as
``partial``, for information. Only a branch that reaches the thinnest width can be the
thin-limit ground state.

Each branch's points are corrected for the discretisation (``eps = eps_N (1 + k/N^2)``, ``k``
measured on the branch's thinnest fitted point relaxed again at 2 N, or the polygon rule
``k = eps/6`` with the uncertainty of :data:`~stiffknots.studies.thin_limit.K_UNCERTAINTY`)
and extrapolated (:func:`~stiffknots.studies.thin_limit.correct_and_fit`): the state's
``eps*_s`` with its error. Nothing here but ``epsilon_thin`` is a thin-limit number: every
point states its ``w/L`` and N.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from stiffknots._version import __version__
from stiffknots.errors import InvalidParameter, UserInputError
from stiffknots.problems import validate as V
from stiffknots.problems.base import default_moves, solve
from stiffknots.studies.thin_limit import (
    CLASSIFY_D_MIN,
    K_UNCERTAINTY,
    correct_and_fit,
    doubled,
    k_from,
    structure_value,
)
from stiffknots.width import Width

__all__ = ["LADDER", "JUMP", "follow_state", "follow_states"]

#: The default ladder of w/L: from just below the atlas's width (0.0047) to the thinnest of
#: ``thin-limit --budget default``.
LADDER = (0.004, 0.003, 0.002, 0.0014, 0.001, 0.0007, 0.0005, 0.00035, 0.00025)
#: Largest shape distance (/ L) between neighbouring points of one branch.
JUMP = 0.03
#: ε tolerance of two branches met at one width (relative).
MERGE_REL = 1e-3


def _read(x: np.ndarray, w: float) -> tuple[str, str | None, int | None, str]:
    """Shape class and structure of a chain in a tube of diameter ``w``, read at
    ``max(w, CLASSIFY_D_MIN)`` (a tube much thinner than a bond parts a point-braid's strands
    within a few beads: see :data:`~stiffknots.studies.thin_limit.CLASSIFY_D_MIN`)."""
    import warnings

    from stiffknots.analysis import analyse_structure, classify
    from stiffknots.analysis.states import state_name

    d = max(float(w), CLASSIFY_D_MIN)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the bead-rule warning: a tube chain, on purpose
        c = classify(x, True, d=d)
        structure = analyse_structure(x, True, d=d).name
    name = state_name(c.label, c.multiplicity)
    return name, c.label, c.multiplicity, structure


def follow_state(knot: Any, coords: np.ndarray, *, widths: Sequence[float] = LADDER,
                 beads: int | None = None, rel_error: float = 1e-3,
                 relax_factor: float = 0.2, replicas: int = 2, seed: int = 0,
                 measure_k: bool = True, runner: Callable[[Any, str], Any] | None = None,
                 say: Callable[[str], None] | None = None,
                 tag: str = "state") -> dict[str, Any]:
    """Follow one state of a knot down a ladder of ``w/L`` (module docstring).

    Parameters
    ----------
    knot
        A catalogue entry or name.
    coords : array_like, shape (N0, 3)
        The state's chain at a wider tube (e.g. its census representative at the atlas width).
    widths : sequence of float
        The ladder of ``w/L``, taken widest first.
    beads : int or None
        N of every point (default: the N rule at the widest width with ``rel_error``).
    rel_error : float, default 1e-3
        Discretisation error of the N rule.
    relax_factor : float, default 0.2
        Moves of each relaxation, as a fraction of the annealing's default at N.
    replicas : int, default 2
        Independent relaxations per width (their spread is the point's error).
    seed : int
    measure_k : bool, default True
        Measure the discretisation coefficient ``k`` on the branch's thinnest fitted point
        (every bond cut in two, relaxed at 2 N) instead of the polygon rule ``k = eps/6``.
    runner, say
        As :func:`stiffknots.studies.thin_limit.thin_limit`.
    tag : str
        How the progress lines name the state.

    Returns
    -------
    dict
        ``knot``, ``start`` (the class, structure and ε of the given chain, read at its own
        width), ``shape`` (the class the branch keeps), ``points`` (each ``w_over_L``,
        ``beads``, ``w``, ``width``, ``epsilon_raw``, ``epsilon`` (corrected), ``sigma``,
        ``shape``, ``structure``, ``step`` (shape distance from the previous point),
        ``spread``, ``in_fit``), ``events`` (each ``{"kind", "w_over_L", "detail"}``),
        ``event`` (the one that ended the fit, or None),
        ``epsilon_thin``, ``error``, ``fit``, ``discretisation``, ``structure_route`` (the
        named w = 0 value of the class at the thinnest fitted point, or None), ``chains`` (one
        per point), ``parameters``, ``version``, ``seed``, ``wall_time``.
    """
    from stiffknots.analysis.identity import shape_distance
    from stiffknots.chain import Chain
    from stiffknots.knots.catalogue import Knot, get_knot
    from stiffknots.knots.resample import ResampleError, minimal_resample_beads
    from stiffknots.measures import min_segment_distance
    from stiffknots.problems.closed_plan import beads_for_knot
    from stiffknots.problems.relax import Relax

    k = knot if isinstance(knot, Knot) else get_knot(knot)
    name = k.name
    ws = sorted((float(x) for x in widths), reverse=True)
    if len(set(ws)) < 2:
        raise InvalidParameter("widths", list(widths), "at least two different w/L")
    seed = V.seed(seed)
    x0 = np.asarray(coords, dtype=float)
    n = V.beads(beads) if beads is not None else beads_for_knot(k, ws[0], rel_error)
    moves = V.moves(max(200_000, round(relax_factor * default_moves(n))))
    run = runner or (lambda p, _label: solve(p))
    say = say or (lambda _s: None)
    t0 = time.time()
    # read the start at its own tube: its smallest distance between non-adjacent segments
    s_name, s_label, s_mult, s_struct = _read(
        x0, min_segment_distance(np.ascontiguousarray(x0), True))
    s_key = (s_label, s_mult if s_label == "CB" else None)
    points: list[dict] = []
    chains: list[np.ndarray] = []
    event = None
    events: list[dict] = []
    key = s_key
    prev = x0
    beads_note = None
    for wl in ws:
        try:
            p = Relax(Chain(prev, closed=True), n, moves, replicas, seed, exclusion="tube",
                      w_over_L=wl, knot=name)
        except ResampleError:
            if points or beads is not None:
                raise
            # a start whose strands touch (a circular braid of 3) cannot be resampled to
            # fewer beads than length / (its distance between non-neighbouring parts): the
            # ladder takes the fewest beads that keep the knot type certified
            need = minimal_resample_beads(x0, start=n, limit=V.MAX_BEADS)
            beads_note = (f"N = {need}, not the rule's {n}: the fewest beads the start can be "
                          "resampled to with its knot type certified")
            say(f"{name} {tag}: {beads_note}")
            n = need
            moves = V.moves(max(200_000, round(relax_factor * default_moves(n))))
            p = Relax(Chain(prev, closed=True), n, moves, replicas, seed, exclusion="tube",
                      w_over_L=wl, knot=name)
        width = Width.tube(n, w_over_L=wl)
        r = run(p, f"{name} {tag}, w/L = {wl:g}")
        if r.interrupted:
            raise KeyboardInterrupt
        x = np.asarray(r.best.coords, dtype=float)
        shape, label, mult, structure = _read(x, width.thickness)
        same = [q.epsilon for q in r.replicas
                if abs(q.epsilon - r.best.epsilon) <= 1e-3 * r.best.epsilon]
        step = shape_distance(prev, x)
        pt = {"w_over_L": wl, "beads": n, "w": width.thickness, "width": width.as_dict(),
              "epsilon_raw": float(r.best.epsilon), "shape": shape, "label": label,
              "multiplicity": mult, "structure": structure, "step": step,
              "spread": (max(same) - min(same)) if len(same) > 1 else 0.0,
              "in_fit": event is None}
        now = ""
        if event is None and step > JUMP:
            event = {"kind": "jumped", "w_over_L": wl,
                     "detail": f"{step:.3f} L from the point before (more than {JUMP:g} L)"}
            events.append(event)
            now = "; jumped"
        elif event is None and (label, mult if label == "CB" else None) != key:
            was = points[-1]["shape"] if points else s_name
            events.append({"kind": "changed class", "w_over_L": wl,
                           "detail": f"{was} → {shape} (step {step:.4f} L: continuous)"})
            now = "; changed class"
        key = (label, mult if label == "CB" else None)
        pt["in_fit"] = event is None
        points.append(pt)
        chains.append(x)
        say(f"{name} {tag}: w/L = {wl:g}, N = {n}: ε_N = {r.best.epsilon:.5f} ({shape}; "
            f"step {step:.4f} L{now})")
        prev = x
    kind = "CB" if s_label == "CB" else "other"
    last = max((i for i, p in enumerate(points) if p["in_fit"]), default=len(points) - 1)
    k_rule = points[last]["epsilon_raw"] / 6.0
    disc = {"rule": "eps = eps_N (1 + k/N^2), k = eps/6 (regular polygon)", "beads": n,
            "k_rule": k_rule, "k": k_rule, "k_error": K_UNCERTAINTY[kind] * k_rule}
    n2 = 2 * n
    wl_k = points[last]["w_over_L"]
    if measure_k and wl_k * n2 < 1 and n2 <= V.MAX_BEADS:
        # the thinnest point of the branch again at 2 N (the same curve, so the same tube;
        # 1e-9 thinner against rounding), relaxed: k measured on the state itself
        try:
            r2 = run(Relax(Chain(doubled(chains[last]), closed=True), n2, moves, replicas,
                           seed, exclusion="tube", w_over_L=wl_k * (1 - 1e-9), knot=name),
                     f"{name} {tag}, w/L = {wl_k:g} at N = {n2} (discretisation)")
        except UserInputError as exc:
            disc["k_measurement_failed"] = str(exc)
            r2 = None
        if r2 is not None:
            if r2.interrupted:
                raise KeyboardInterrupt
            e1, e2 = points[last]["epsilon_raw"], float(r2.best.epsilon)
            k_meas = k_from(e1, e2, n, n2)
            shape2 = _read(np.asarray(r2.best.coords), wl_k * n2)[0]
            disc.update(k_measured=k_meas, check_beads=n2, check_epsilon=e2,
                        check_shape=shape2, check_w_over_L=wl_k)
            if shape2 == points[last]["shape"] and k_meas > 0:
                disc.update(k=k_meas, k_error=max(abs(k_meas - k_rule), 0.02 * k_rule))
            say(f"{name} {tag}: discretisation at w/L = {wl_k:g}: ε_{n} = {e1:.5f}, "
                f"ε_{n2} = {e2:.5f}: k = {k_meas:.3f} (polygon rule ε/6 = {k_rule:.3f})")
    fit, eps_thin, err = correct_and_fit(points, n, disc)
    partial = None
    if event is not None:   # the state ended on the ladder: no limit of its own at w = 0
        partial = {"epsilon_thin": eps_thin, "error": err, "fit": fit}
        fit = eps_thin = err = None
    struct = structure_value(points[last]["label"], points[last]["multiplicity"])
    if struct is not None and eps_thin is not None:
        struct["difference"] = eps_thin - struct["epsilon"]
        struct["in_error_bars"] = abs(struct["difference"]) / err if err else None
    return {"partial": partial, "knot": name, "tag": tag,
            "start": {"shape": s_name, "label": s_label, "multiplicity": s_mult,
                      "structure": s_struct},
            "shape": s_name, "points": points, "event": event, "events": events,
            "epsilon_thin": eps_thin,
            "error": err, "fit": fit, "discretisation": disc, "structure_route": struct,
            "chains": chains, "version": __version__, "seed": seed,
            "parameters": {"widths": ws, "beads": n, "beads_note": beads_note,
                           "rel_error": rel_error,
                           "relax_moves": moves, "replicas": replicas, "exclusion": "tube"},
            "wall_time": time.time() - t0}


def follow_states(knot: Any, states: Sequence[dict], **kw: Any) -> dict[str, Any]:
    """Follow several states of one knot (each a dict with ``coords`` and optionally ``tag``)
    down the same ladder, then mark where two branches **merged** (module docstring).

    Returns ``{"knot", "branches": [follow_state results, in the given order], "ground"}``;
    ``ground`` is the index of the branch with the lowest ``epsilon_thin`` (None when no
    branch has one). A branch that merged into an earlier one (lower index, still in its own
    state there) at some width gets that event (if it had none before), stops being fitted
    from there and has no limit of its own.
    """
    from stiffknots.analysis.identity import SAME_STATE_DISTANCE, shape_distance

    branches = [follow_state(knot, s["coords"], tag=s.get("tag", f"state {i}"), **kw)
                for i, s in enumerate(states)]
    for j, b in enumerate(branches):
        for i in range(j):
            a = branches[i]
            for pa, pb, xa, xb in zip(a["points"], b["points"], a["chains"], b["chains"],
                                      strict=False):
                if b["event"] is not None and pb["w_over_L"] < b["event"]["w_over_L"]:
                    break
                if not pa["in_fit"]:      # a has left its state there (a jump): not a merger
                    break
                if abs(pa["epsilon_raw"] - pb["epsilon_raw"]) <= MERGE_REL * pa["epsilon_raw"] \
                        and shape_distance(xa, xb) <= SAME_STATE_DISTANCE:
                    if b["event"] is None:
                        b["event"] = {"kind": "merged", "w_over_L": pb["w_over_L"],
                                      "detail": f"with {a['tag']}"}
                        b["events"].append(b["event"])
                        _refit(b)
                    break
    fitted = [(b["epsilon_thin"], i) for i, b in enumerate(branches)
              if b["epsilon_thin"] is not None]
    return {"knot": branches[0]["knot"] if branches else None, "branches": branches,
            "ground": min(fitted)[1] if fitted else None}


def _refit(b: dict) -> None:
    """A branch that merged: its points from the merger on are the other branch's; what its
    points before extrapolate to is kept as ``partial``, and it has no limit of its own."""
    w_event = b["event"]["w_over_L"]
    for p in b["points"]:
        p["in_fit"] = p["w_over_L"] > w_event
    fit, eps, err = correct_and_fit(b["points"], b["parameters"]["beads"], b["discretisation"])
    b.update(partial={"epsilon_thin": eps, "error": err, "fit": fit}, fit=None,
             epsilon_thin=None, error=None)
    if b["structure_route"] is not None:   # no limit of its own: nothing to compare
        b["structure_route"].update(difference=None, in_error_bars=None)
