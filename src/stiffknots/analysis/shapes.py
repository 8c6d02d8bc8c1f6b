"""Shape classification of closed stiff knots: circular braid, 4-fold cage, "80" (paper §VII).

The Monte Carlo study of §VII (Fig. 6, Fig. 7) finds three shapes for the
``n = 2`` knots: the circular braid (CB) of the trefoil, the 4-fold cage (4C) of ``4_1`` and
``5_2``, and the "80" (an 8 plus a circle) of ``5_2``, ``6_2`` and ``6_3``. :func:`classify`
decides between them from the geometry and the contact structure of the chain alone — never
from the knot's name or its energy — and returns the features it used, so a report can show
why. Anything that does not clearly match a class is ``"other"``.

Classes and their criteria (thresholds in :class:`Thresholds`)
----------------------------------------------------------------
``"CB"`` — circular braid of index ``i`` (§VI C, Fig. 7 a)
    An ``i``-times covered circle (the ``n = i`` family, ``ε° = 2π²i²``). Seen along the normal
    of its best-fit plane the chain winds ``i`` times around its centroid, *monotonically*
    (every bond advances the azimuth the same way: fraction ``≥ 0.97``), on a thin annulus
    (radial coefficient of variation ``≤ 0.15``, thickness out of the plane ``≤ 0.15`` of the
    radius) whose mean radius is that of an ``i``-covered circle, ``ρ̄ = L/(2πi)`` (within
    10 %), with total curvature ``κ̄ = 2πi`` (within 10 %). ``Shape.multiplicity = i``.

    The annealed covers of a trefoil do *not* stay in contact along the whole circle: at
    ``N = 150`` they wander a few bonds apart (two slightly shifted circles touching along
    30–75 % of the length), so the criterion is geometric — all covers lie on one thin circle
    — and the contact line-braids are only reported. A plain circle satisfies the criterion
    with ``i = 1``: it is the ``i = 1`` member of the family (the unknot, ``ε = 2π²``) and is
    reported as ``CB`` with multiplicity 1.
``"4C"`` — 4-fold cage (Fig. 6, Fig. 7 b)
    Structure: exactly two contact zones, each a point-braid of two strand passages (or a
    two-strand line-braid no longer than 15 % of L: at a finite width the twist box of a cage
    with three or more half-turns, as 5_2 = [32], is a short twisted stretch that becomes a
    point-braid as w → 0; strands within 45° of tangent), joined by exactly four free arcs, each
    running from one point-braid to the other and carrying 10–40 % of the length. Geometry: the
    cage is wrapped around a sphere (paper: "approximately wrapped around a sphere") — distances
    to the centroid vary by ``≤ 15 %``, the chain is three-dimensional (inertia ratio ``λ3/λ1 ≥
    0.2``), the two point-braids sit at opposite poles (their distance ``≥ 0.8`` of the sphere's
    diameter) and their axes (the common tangent of their strands) are crossed, at least 60°
    apart — the four-fold symmetry of the cage. Annealed 4_1 cages at ``N = 150`` give radial
    variation 0.06, ``λ3/λ1 ≈ 0.4``, pole distance ≈ 1.02 diameters and pole axes 87–90° apart.
``"80"`` — an 8 plus a circle (Fig. 7 c, eq. (27))
    The chain can be cut at one of its contacts into two closed sub-loops: a *circle* (the
    0: planar turning number ``±1``, radial variation about its centre ``≤ 0.2``, total
    curvature ``2π`` within −15 %/+35 %, 20–55 % of the length; the theory gives
    ``(2π²/ε_80)^{1/2} = 37 %``) and a *figure eight* (planar turning number 0, two
    inflection points, total curvature between 1.1 and 2 turns — the elastica 8 has 1.45 —,
    the rest of the length). Both sub-loops must close smoothly at the cut (their end
    tangents within 45°): the 8 and the 0 are joined by a point-braid, whose strands are
    tangent (§V B), not by a crossing. Both must be roughly planar (``(λ3/λ1)^{1/2} ≤ 0.35``).
    Where the circle lies is not imposed: the Monte Carlo 80s run the circle along one lobe
    of the 8 (one point-braid and three double points), the theoretical shadow of
    :func:`stiffknots.theory.elastica.eighty_curve` puts it outside; both are 80s.

    Cut candidates are contacts of the contact zones (for every two runs of a zone: their
    closest, first, middle and last contact, both ways round); the 24 most promising (right
    circle fraction, smoothest cut) are measured in full. A chain with more than 8 contact
    zones (the 80 has 4) is not searched.

The checks run in the order CB, 4C, 80; the first class whose criteria all hold is the label.
The nearly flat three-lobed state that ``4_1`` sometimes reaches under the bead rule
(``ε ≈ 127.9``, strands passing within ~0.2 bond of each other) comes out ``"other"``: it is
an 8 and a 0 of the right lengths, but they meet at a crossing (cut angle ≈ 78°) rather than
at a point-braid, and it is flat, not a cage.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from stiffknots._json import to_plain
from stiffknots.analysis.contacts import (
    DEFAULT_CONTACT_FACTOR,
    DEFAULT_D,
    DEFAULT_MIN_SEP,
    as_coords,
)
from stiffknots.analysis.geometry import (
    arc_lengths,
    axis_winding,
    count_inflections,
    principal_axes,
    total_curvature,
    turning_angles,
)
from stiffknots.analysis.structure import Structure, analyse_structure, tangents

__all__ = ["LABELS", "Thresholds", "Shape", "classify", "shape_features"]

#: The possible labels of :func:`classify`.
LABELS = ("CB", "4C", "80", "other")

TWO_PI = 2.0 * math.pi
#: Length fraction of the circle in the 80: ``(ε_0/ε_80)^{1/2}`` with the Appendix D values.
CIRCLE_FRACTION_80 = 0.3721
#: Total curvature of the elastica figure eight in turns (``4 θ_0 / 2π``, Appendix D).
EIGHT_TURNS = 1.452


@dataclass(frozen=True)
class Thresholds:
    """Every threshold of :func:`classify` (defaults documented in the module docstring)."""

    # CB
    cb_monotonic_min: float = 0.97
    cb_radius_cv_max: float = 0.15
    cb_thickness_max: float = 0.15
    cb_radius_tol: float = 0.10
    cb_curvature_tol: float = 0.10
    # 4C
    c4_alignment_min: float = math.cos(math.radians(45.0))
    c4_arc_fraction: tuple[float, float] = (0.10, 0.40)
    #: a pole may be a short two-strand line-braid: at a finite width the twist box of a
    #: cage with a ≥ 3 half-turns (5_2 = [32]) is a twisted stretch ~10 % of L long, which
    #: shrinks to a point-braid as w → 0 (§V B); longer line-braids are not poles
    c4_pole_length_max: float = 0.15
    c4_radius_cv_max: float = 0.15
    c4_inertia_min: float = 0.20
    c4_pole_separation_min: float = 0.80
    c4_pole_axes_min: float = 60.0
    # 80
    e80_closure_angle_max: float = 45.0
    e80_circle_fraction: tuple[float, float] = (0.20, 0.55)
    e80_circle_cv_max: float = 0.20
    e80_circle_turns: tuple[float, float] = (0.85, 1.35)
    e80_eight_turns: tuple[float, float] = (1.10, 2.00)
    e80_flatness_max: float = 0.35
    e80_max_zones: int = 8
    e80_max_candidates: int = 24

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class Shape:
    """Result of :func:`classify`.

    Attributes
    ----------
    label : str
        ``"CB"``, ``"4C"``, ``"80"`` or ``"other"``.
    multiplicity : int or None
        For ``"CB"`` the index ``i`` (number of covers of the circle); ``None`` otherwise.
    features : dict
        The measured features (plain numbers), grouped ``"global"``, ``"CB"``, ``"4C"``,
        ``"80"``.
    checks : dict
        For every class, each criterion and whether it held (``{"CB": {"monotonic": True,
        ...}, ...}``).
    reason : str
        One line: why this label (or why no class matched).
    structure : dict
        Summary of the contact structure (zones by kind, graph summary, line-braids).
    """

    label: str
    multiplicity: int | None
    features: dict
    checks: dict
    reason: str
    structure: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"label": self.label, "multiplicity": self.multiplicity,
                "features": self.features, "checks": self.checks, "reason": self.reason,
                "structure": self.structure}

    def __str__(self) -> str:
        if self.label == "CB":
            return f"CB(i={self.multiplicity})"
        return self.label


# --------------------------------------------------------------------------------------------
# features
# --------------------------------------------------------------------------------------------


def _global_features(x: np.ndarray, st: Structure) -> dict:
    pa = principal_axes(x)
    r2, r3 = pa.ratios()
    radial = np.linalg.norm(x - pa.centroid, axis=1)
    kbar = total_curvature(x, True)
    return {
        "n_beads": int(x.shape[0]),
        "length": float(arc_lengths(x, True).sum()),
        "total_curvature": kbar,
        "curvature_turns": kbar / TWO_PI,
        "inertia_ratios": [r2, r3],
        "radius_mean": float(radial.mean()),
        "radius_cv": float(radial.std() / radial.mean()),
        "contact_fraction": float(np.mean(st.multiplicity >= 2)),
        "max_multiplicity": int(st.multiplicity.max()),
        "zones": st.zone_counts(),
        "graph": st.graph.summary(),
    }


def _cb_features(x: np.ndarray, length: float, kbar: float, th: Thresholds) -> tuple[dict, dict]:
    pa = principal_axes(x)
    p, h = pa.project(x)
    w, dphi = axis_winding(p)
    i = int(round(abs(w)))
    rho = np.hypot(p[:, 0], p[:, 1])
    rho_mean = float(rho.mean())
    sign = 1.0 if w >= 0 else -1.0
    feats = {
        "winding": w,
        "i": i,
        "monotonic_fraction": float(np.mean(dphi * sign > 0.0)),
        "radius_cv": float(rho.std() / rho_mean) if rho_mean > 0 else math.inf,
        "thickness": float(h.std() / rho_mean) if rho_mean > 0 else math.inf,
        "radius_ratio": rho_mean * TWO_PI * max(i, 1) / length,
        "curvature_ratio": kbar / (TWO_PI * max(i, 1)),
    }
    checks = {
        "winds": i >= 1,
        "monotonic": feats["monotonic_fraction"] >= th.cb_monotonic_min,
        "thin_annulus": feats["radius_cv"] <= th.cb_radius_cv_max,
        "flat": feats["thickness"] <= th.cb_thickness_max,
        "radius_L_over_2pi_i": abs(feats["radius_ratio"] - 1.0) <= th.cb_radius_tol,
        "curvature_2pi_i": abs(feats["curvature_ratio"] - 1.0) <= th.cb_curvature_tol,
    }
    return feats, checks


def _c4_features(x: np.ndarray, st: Structure, gfeat: dict, th: Thresholds
                 ) -> tuple[dict, dict]:
    zones = st.zones
    arcs = [e for e in st.graph.edges if e.kind == "arc"]
    nodes = {nd.index: nd for nd in st.graph.nodes}
    length = gfeat["length"]
    feats: dict[str, Any] = {
        "n_zones": len(zones),
        "zone_kinds": [z.kind for z in zones],
        "zone_strands": [z.strands for z in zones],
        "zone_alignment": [z.alignment for z in zones],
        "n_arcs": len(arcs),
        "arc_fractions": [e.length / length for e in arcs],
        "radius_cv": gfeat["radius_cv"],
        "inertia_min_ratio": gfeat["inertia_ratios"][1],
        "pole_separation": None,
        "pole_axes_angle": None,
    }
    two = len(zones) == 2
    if two:
        sep = float(np.linalg.norm(zones[0].centre - zones[1].centre))
        feats["pole_separation"] = sep / (2.0 * gfeat["radius_mean"])
        t = tangents(x, True)
        axes = []
        for z in zones:
            beads = np.concatenate([(s + np.arange(ln)) % len(x) for s, ln in z.runs])
            tz = t[beads]
            tz = tz * np.sign(tz @ tz[0])[:, None]
            axes.append(tz.mean(axis=0) / np.linalg.norm(tz.mean(axis=0)))
        cos_axes = min(1.0, abs(float(axes[0] @ axes[1])))
        feats["pole_axes_angle"] = math.degrees(math.acos(cos_axes))
    lo, hi = th.c4_arc_fraction
    joins = two and all(
        e.nodes[0] is not None and e.nodes[1] is not None
        and nodes[e.nodes[0]].zone != nodes[e.nodes[1]].zone for e in arcs)
    checks = {
        "two_zones": two,
        "point_braids": two and all(
            (z.kind != "line-braid" or z.length <= th.c4_pole_length_max * length)
            and z.strands == 2 and z.alignment >= th.c4_alignment_min for z in zones),
        "four_arcs": len(arcs) == 4,
        "arcs_join_poles": bool(joins) and len(arcs) == 4,
        "arc_lengths": len(arcs) == 4 and all(lo <= f <= hi for f in feats["arc_fractions"]),
        "spherical": gfeat["radius_cv"] <= th.c4_radius_cv_max,
        "three_dimensional": gfeat["inertia_ratios"][1] >= th.c4_inertia_min,
        "opposite_poles": two and feats["pole_separation"] >= th.c4_pole_separation_min,
        "crossed_poles": two and feats["pole_axes_angle"] >= th.c4_pole_axes_min,
    }
    return feats, checks


def _signed_angle_2d(a: np.ndarray, b: np.ndarray) -> float:
    return math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


def _loop_measures(x: np.ndarray) -> dict:
    """Measures of the sub-loop ``x[0] .. x[-1]`` (an open polyline) closed by the cut.

    The cut joins ``x[-1]`` back to ``x[0]`` through a contact: the two strands there are
    side by side, so the closing chord is not part of the curve. The sub-loop is closed at the
    level of tangents instead: its turning is the sum of its inner turning angles plus the
    angle from its last bond to its first. Planar quantities use the sub-loop's own best-fit
    plane.
    """
    pa = principal_axes(x)
    p, _ = pa.project(x)
    e2 = np.diff(p, axis=0)
    a, b = e2[:-1], e2[1:]
    inner = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], np.einsum("ij,ij->i", a, b))
    turns2d = np.concatenate([inner, [_signed_angle_2d(e2[-1], e2[0])]])
    e3 = np.diff(x, axis=0)
    u, v = e3[-1], e3[0]
    close3d = math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v))
    kbar = float(turning_angles(x, False).sum()) + close3d
    rho = np.hypot(*(p - p.mean(axis=0)).T)
    return {
        "turning_number": int(round(float(turns2d.sum()) / TWO_PI)),
        "turns": kbar / TWO_PI,
        "cut_angle": math.degrees(close3d),
        "radius_cv": float(rho.std() / rho.mean()) if rho.mean() > 0 else math.inf,
        "flatness": math.sqrt(pa.ratios()[1]),
        "inflections": count_inflections(turns2d),
    }


def _candidate_cuts(st: Structure, n: int) -> list[tuple[int, int]]:
    """A few contact pairs per pair of runs of every zone: closest, first, middle, last."""
    cm = st.contact_map
    if cm.n_contacts == 0:
        return []
    run_id = np.full(n, -1, dtype=np.int64)
    k = 0
    for z in st.zones:
        for s, ln in z.runs:
            run_id[(s + np.arange(ln)) % n] = k
            k += 1
    ra, rb = run_id[cm.i], run_id[cm.j]
    key = np.minimum(ra, rb) * (k + 1) + np.maximum(ra, rb)
    out = set()
    for kk in np.unique(key):
        idx = np.flatnonzero(key == kk)
        picks = {idx[np.argmin(cm.dist[idx])], idx[0], idx[len(idx) // 2], idx[-1]}
        out.update((int(cm.i[q]), int(cm.j[q])) for q in picks)
    return sorted(out)


def _e80_features(x: np.ndarray, st: Structure, length: float, th: Thresholds
                  ) -> tuple[dict, dict]:
    n = len(x)
    bonds = arc_lengths(x, True)
    cum = np.concatenate([[0.0], np.cumsum(bonds)])
    n_zones = len(st.zones)
    if n_zones > th.e80_max_zones:
        return {"cut": None, "n_zones": n_zones}, {"few_zones": False}
    lo, hi = th.e80_circle_fraction
    clo, chi = th.e80_circle_turns
    elo, ehi = th.e80_eight_turns
    # cheap pre-selection: circle fraction and smoothness of the cut, then full measures on
    # the most promising candidates only
    cands = []
    for i, j in _candidate_cuts(st, n):
        for a, b in ((i, j), (j, i)):
            na, nb = (b - a) % n + 1, (a - b) % n + 1
            if na < 8 or nb < 8:
                continue
            frac = ((cum[b] - cum[a]) if b > a else (length - cum[a] + cum[b])) / length
            u, v = x[b] - x[(b - 1) % n], x[(a + 1) % n] - x[a]
            cut = math.degrees(math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v)))
            ok = lo <= frac <= hi and cut <= th.e80_closure_angle_max
            cands.append((not ok, cut, a, b, frac))
    cands.sort()
    best: tuple[float, dict, dict] | None = None
    for _, _, a, b, frac in cands[:th.e80_max_candidates]:
        circ = _loop_measures(x[(a + np.arange((b - a) % n + 1)) % n])    # circle: a .. b
        eight = _loop_measures(x[(b + np.arange((a - b) % n + 1)) % n])   # eight: b .. a
        closure = max(circ["cut_angle"], eight["cut_angle"])
        checks = {
            "few_zones": True,
            "smooth_cut": closure <= th.e80_closure_angle_max,
            "circle_fraction": lo <= frac <= hi,
            "circle_turning_1": abs(circ["turning_number"]) == 1,
            "circle_round": circ["radius_cv"] <= th.e80_circle_cv_max,
            "circle_curvature": clo <= circ["turns"] <= chi,
            "eight_turning_0": eight["turning_number"] == 0,
            "eight_two_inflections": eight["inflections"] == 2,
            "eight_curvature": elo <= eight["turns"] <= ehi,
            "planar_parts": max(circ["flatness"], eight["flatness"]) <= th.e80_flatness_max,
        }
        score = (sum(not v for v in checks.values()) * 10.0
                 + abs(frac - CIRCLE_FRACTION_80) / CIRCLE_FRACTION_80
                 + circ["radius_cv"] + abs(eight["turns"] / EIGHT_TURNS - 1.0)
                 + closure / 90.0)
        feats = {"cut": [int(a), int(b)], "cut_angle": closure, "circle_fraction": frac,
                 "n_zones": n_zones, "circle": circ, "eight": eight}
        if best is None or score < best[0]:
            best = (score, feats, checks)
    if best is None:
        return {"cut": None, "n_zones": n_zones}, {"few_zones": True, "has_cut": False}
    return best[1], best[2]




def shape_features(coords: Any, closed: bool = True, *, d: float = DEFAULT_D,
                   factor: float = DEFAULT_CONTACT_FACTOR, cutoff: float | None = None,
                   min_sep: int = DEFAULT_MIN_SEP, thresholds: Thresholds | None = None,
                   structure: Structure | None = None) -> tuple[dict, dict, Structure]:
    """All features and checks of :func:`classify` (see there), without the decision.

    Returns
    -------
    features : dict
    checks : dict
    structure : Structure
    """
    x = as_coords(coords, closed)
    th = thresholds or Thresholds()
    if not closed:
        raise ValueError("shape features are defined for closed chains (the CB, 4C and 80 of "
                         "§VII are closed knots); got closed=False")
    st = structure or analyse_structure(x, True, d=d, factor=factor, cutoff=cutoff,
                                        min_sep=min_sep)
    g = _global_features(x, st)
    cb_f, cb_c = _cb_features(x, g["length"], g["total_curvature"], th)
    c4_f, c4_c = _c4_features(x, st, g, th)
    e_f, e_c = _e80_features(x, st, g["length"], th)
    features = to_plain({"global": g, "CB": cb_f, "4C": c4_f, "80": e_f})
    checks = {lab: {k: bool(v) for k, v in c.items()}
              for lab, c in (("CB", cb_c), ("4C", c4_c), ("80", e_c))}
    return features, checks, st


def classify(coords: Any, closed: bool = True, *, d: float = DEFAULT_D,
             factor: float = DEFAULT_CONTACT_FACTOR, cutoff: float | None = None,
             min_sep: int = DEFAULT_MIN_SEP, thresholds: Thresholds | None = None) -> Shape:
    """Classify a closed chain as circular braid, 4-fold cage, 80 or other (§VII, Figs 6, 7).

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead positions, in the units of ``d`` (bond length ≈ 1 for the §VII chains). The
        result is invariant under rotations and translations, and under scaling when ``d``
        (or ``cutoff``) is scaled alike.
    closed : bool, default True
        Must be True for a class to be found; an open chain is ``"other"``.
    d : float, default ``1/√2``
        Exclusion distance of the chain (sets the contact distance ``factor × d``).
    factor, cutoff, min_sep
        Contact rule, see :func:`~stiffknots.analysis.contacts.contact_map`.
    thresholds : Thresholds, optional
        Override the criteria (defaults in the module docstring).

    Returns
    -------
    Shape
        ``label`` in ``{"CB", "4C", "80", "other"}``, ``multiplicity`` (``i`` for CB), the
        features and the pass/fail of every criterion.

    Raises
    ------
    ValueError
        Bad coordinates or parameters.
    """
    x = as_coords(coords, closed)
    if not closed:
        return Shape("other", None, {}, {}, "open chain: CB, 4C and 80 are closed-knot "
                     "shapes (§VII)", {})
    features, checks, st = shape_features(x, True, d=d, factor=factor, cutoff=cutoff,
                                          min_sep=min_sep, thresholds=thresholds)
    summary = to_plain({"name": st.name, "zones": st.zone_counts(),
                        "graph": st.graph.summary(),
                        "line_braids": [[b.multiplicity, round(b.length, 2)]
                                        for b in st.line_braids],
                        "params": st.params})
    if all(checks["CB"].values()):
        i = features["CB"]["i"]
        why = (f"winds {i}x monotonically around one axis on a thin annulus, radius "
               f"{features['CB']['radius_ratio']:.2f} L/(2πi), curvature "
               f"{features['CB']['curvature_ratio']:.2f}·2πi")
        return Shape("CB", i, features, checks, why, summary)
    if all(checks["4C"].values()):
        why = ("two point-braids at opposite poles joined by four arcs on a sphere (radial "
               f"variation {features['4C']['radius_cv']:.2f})")
        return Shape("4C", None, features, checks, why, summary)
    if all(checks["80"].values()):
        f = features["80"]
        why = (f"cut at beads {f['cut']} into a circle ({f['circle_fraction']:.2f} L) and a "
               f"figure eight ({f['eight']['turns']:.2f} turns, 2 inflections)")
        return Shape("80", None, features, checks, why, summary)
    fails = []
    for lab in ("CB", "4C", "80"):
        bad = [k for k, v in checks[lab].items() if not v]
        fails.append(f"{lab}: fails {', '.join(bad)}")
    return Shape("other", None, features, checks, "; ".join(fails), summary)
