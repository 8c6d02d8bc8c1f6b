"""Numbers as the tables of the command line and of the pages print them."""

from __future__ import annotations

__all__ = ["segment_distance_text", "TOUCHING_BELOW", "touching_note"]

#: A closest approach of two segments below this (bond lengths) is a *touching crossing*:
#: under the bead rule d = 1/√2 two segments can meet (crossing at right angles, all four
#: beads exactly d apart), and the polish keeps them at its strand gap, 10⁻⁴
#: (:func:`stiffknots.engine.polish.polish`, ``min_gap``); the tube rule keeps them ≥ w.
TOUCHING_BELOW = 1e-3


def segment_distance_text(x: float | None) -> str:
    """A segment distance: 3 decimals, or two significant figures below 10⁻³ (a touching
    crossing of the bead rule sits at the polish's strand gap of 10⁻⁴, which "0.000" would
    hide); "—" for None."""
    if x is None:
        return "—"
    return f"{x:.3f}" if x >= TOUCHING_BELOW else f"{x:.1e}"


def touching_note() -> str:
    """The caption line that explains a distance printed as ``1.0e-04``."""
    return ("min seg dist ~1e-04: two strands touch where they cross (the bead rule allows it; "
            "the final minimiser holds them at its strand gap of 1e-4)")
