"""One knot at a glance: its catalogue data and its bounds (closed §VI, open §VIII,
restricted curvature §IX D), as plain data for tables, JSON and reports."""

from __future__ import annotations

from stiffknots.knots.catalogue import get_knot
from stiffknots.theory.bounds import closed_bounds, open_bounds, restricted_curvature_bounds

__all__ = ["knot_summary"]


def knot_summary(name: str) -> dict:
    """Catalogue data and bounds of one knot (closed, open, restricted curvature).

    The closed bounds are 2π²n² ≤ ε* ≤ 2π² min(α²n², i²) (eqs. (13), (31)); when n = i the
    ground state is the i-times covered circle, ε* = 2π²i² (§VI C).
    """
    k = get_knot(name)
    cb = closed_bounds(k.bridge_number, k.braid_index)
    d = {
        "name": k.name,
        "crossing_number": k.crossing_number,
        "bridge_number": k.bridge_number,
        "braid_index": k.braid_index,
        "braid_word": list(k.braid_word) if k.braid_word else None,
        "torus": k.torus_notation,
        "alternating": k.alternating,
        "n_equals_i": k.n_equals_i,
        "lower_bound": cb.lower,
        "upper_bound": cb.upper,
        "upper_bound_attained_by": cb.attained_by,
        "eps_cb": cb.eps_cb,
        "eps_pbl": cb.eps_pbl,
        "predicted_ground_state": (
            {"shape": "CB", "multiplicity": k.braid_index, "epsilon": cb.eps_cb}
            if cb.exact else None
        ),
    }
    rc = restricted_curvature_bounds(k.bridge_number, k.braid_index)
    d["restricted_curvature_bounds"] = {"lower": rc.lower, "upper": rc.upper,
                                        "unit": "L_dagger / R"}
    d["bridge_number_range"] = list(k.bridge_number_range) if k.bridge_number_range else None
    d["braid_index_range"] = list(k.braid_index_range) if k.braid_index_range else None
    if cb.lower is None and k.bridge_number_range:
        # n unknown but n ≥ n_lo: 2π²n² ≥ 2π²n_lo² still bounds ε* from below (eq. (13)); and
        # with n ≤ n_hi, i ≤ i_hi the upper bound holds at (n_hi, i_hi) (eq. (31))
        lo, hi = k.bridge_number_range
        d["lower_bound"] = closed_bounds(lo, None).lower
        d["bounds_from_ranges"] = True
        if k.braid_index_range:
            ihi = k.braid_index_range[1]
            up = closed_bounds(min(hi, ihi), ihi)
            d["upper_bound"], d["upper_bound_attained_by"] = up.upper, None
            r_lo = restricted_curvature_bounds(lo, None).lower
            r_hi = restricted_curvature_bounds(min(hi, ihi), ihi).upper
            d["restricted_curvature_bounds"] = {"lower": r_lo, "upper": r_hi,
                                                "unit": "L_dagger / R"}
    if k.bridge_number is not None and k.bridge_number >= 2:
        ob = open_bounds(k.bridge_number, k.braid_index)
        d["open_tension_bounds"] = {"lower": ob.lower, "upper": ob.upper,
                                    "unit": "mu* L_e^2 / C"}
    return d
