"""The table of a knot's stored thin stage (``stiffknots db thin``, ``atlas --thin``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.markup import escape
from rich.table import Table

from stiffknots.cli.app import out
from stiffknots.studies.thin_states import route_difference

__all__ = ["thin_table", "thin_verdict", "print_thin"]


def thin_table(t: Mapping[str, Any]) -> Table:
    """One row per state of a knot's thin run (:func:`stiffknots.store.thin.thin_knots`)."""
    tab = Table(title=f"{t['knot']}: every state of the tube census at w/L = "
                      f"{t['w_over_L']:.2g} followed to w = 0 (budget {t['budget']}, seed "
                      f"{t['seed']})",
                caption="ε: at the census's width; ε* branch: extrapolated along the "
                        "state's branch; ε* struct.: its structure solved at w = 0; (jumped), "
                        "(merged): the branch left its state (no limit of its own)")
    for col, right in (("state", False), ("ε", True), ("ε* branch", True),
                       ("ε* struct.", True), ("structure", False), ("routes", False)):
        tab.add_column(col, justify="right" if right else "left",
                       no_wrap=col in ("ε", "ε* struct.", "routes"),
                       overflow="fold", min_width=12 if col == "structure" else None)
    for s in t["states"]:
        branch = "—" if s["epsilon_thin"] is None else (
            f"{s['epsilon_thin']:.4f}" + (f" ± {s['error']:.2g}" if s["error"] is not None
                                          else ""))
        tab.add_row(escape(f"{s['state']}: {s['name']}" + (" ◀ ground" if s["ground"] else "")
                           + (f" ({s['event']})" if s["event"] else "")),
                    f"{s['epsilon']:.3f}", branch,
                    "—" if s["structure_epsilon"] is None else f"{s['structure_epsilon']:.4f}",
                    escape(s["structure_name"] or "—"),
                    {True: "agree", False: "differ", None: "—"}[s["agree"]])
    return tab


def thin_verdict(t: Mapping[str, Any]) -> str:
    """One sentence: the thin-limit ground, its margin, and whether it is the ground at the
    census's width."""
    g = t["ground"]
    if g is None:
        return (f"{t['knot']}: no state reached w = 0 in its own state (every branch jumped or "
                "merged)")
    text = (f"{t['knot']}: thin-limit ground {g['name']}, ε* = {g['epsilon_thin']:.4f}"
            + (f" ± {g['error']:.2g}" if g["error"] is not None else ""))
    if g["structure_epsilon"] is not None:
        why = route_difference(g["epsilon_thin"], g["structure_epsilon"], g["structure_name"],
                               g["agree"])
        text += (f" (structure route {g['structure_epsilon']:.4f}: "
                 + {True: "agree", False: "differ", None: "not compared"}[g["agree"]]
                 + (f": {why}" if why else "") + ")")
    m = t.get("margin")
    if m:
        sig = f", {m['sigmas']:.1f} σ" if m.get("sigmas") is not None else ""
        text += f"; the next state {m['gap']:+.3f} above{sig}"
        nxt = next((s for s in t["states"] if s["state"] == m["next"]), None)
        if nxt is not None and nxt["structure_epsilon"] is not None \
                and g["structure_epsilon"] is not None:
            text += (f" (by the structure route "
                     f"{nxt['structure_epsilon'] - g['structure_epsilon']:+.4f})")
    if g["state"] != 0:
        text += (f"; not the ground at w/L = {t['w_over_L']:.2g} ({t['finite']['name']})"
                 + (f", the branches cross near w/L = {t['crossing']:.2g}"
                    if t.get("crossing") is not None else ""))
    return text


def print_thin(t: Mapping[str, Any]) -> None:
    """Print a knot's thin run: :func:`thin_table`, :func:`thin_verdict` and when and by what
    it was computed."""
    out.print(thin_table(t))
    out.print(thin_verdict(t), highlight=False, markup=False)
    out.print(f"computed {t['created']} by stiffknots {t['version']}"
              + (f" in {t['cpu_seconds']:.0f} CPU s" if t.get("cpu_seconds") else ""),
              highlight=False, markup=False)
