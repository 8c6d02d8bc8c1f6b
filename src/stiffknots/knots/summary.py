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
    if k.bridge_number is not None and k.bridge_number >= 2:
        ob = open_bounds(k.bridge_number, k.braid_index)
        d["open_tension_bounds"] = {"lower": ob.lower, "upper": ob.upper,
                                    "unit": "mu* L_e^2 / C"}
    rc = restricted_curvature_bounds(k.bridge_number, k.braid_index)
    d["restricted_curvature_bounds"] = {"lower": rc.lower, "upper": rc.upper,
                                        "unit": "L_dagger / R"}
    return d
