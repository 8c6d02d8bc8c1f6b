"""Thin-limit energies of the shape classes, for comparing a finite-width result with w = 0.

Every Monte Carlo result is computed at a finite width (the bead rule d = 1/√2 at N beads,
w/L = d/N; or a tube of diameter w, w/L = w/N). Its energy is an upper bound of the knot's
thin-limit energy: ε*_w rises with w (§V A, App. A), so ε ≥ ε*_w ≥ ε*. How far above the thin
limit it lies depends on the shape; this module gives the thin-limit value of the shape a
result reached, when the structure of that shape is solved (§V B):

``CB(i)``
    the circular braid, 2π²i² (eq. (30)), exact.
``80``
    (√ε_8 + √(2π²))² (§VII, from eq. (27)) with Appendix D's constants
    (:mod:`stiffknots.theory.elastica`).
``4C``
    the 4-fold cage, ε*_4C, which the paper could not compute (§VII: "< 129.6"): solved at
    w = 0 by :func:`stiffknots.theory.structures.structure_energy` ("4C": line-braids of
    multiplicity 2 joined at two point-braids, Richardson extrapolation and a shooting check);
    the value is tabulated here (:data:`EPS_4C`) because that solve takes about a minute, and
    a test recomputes it.

Other shapes ('other', open knots' loops are handled by their own bounds) have no value here.
"""

from __future__ import annotations

import math

__all__ = ["EPS_4C", "EPS_4C_ERROR", "thin_limit_note", "thin_limit_of_shape"]

#: ε*_4C at w = 0 from :func:`stiffknots.theory.structures.structure_energy` ("4C").
EPS_4C = 126.4724695555
#: its error (extrapolation and optimiser estimate).
EPS_4C_ERROR = 2e-10


def thin_limit_of_shape(shape: str | None, multiplicity: int | None = None) -> dict | None:
    """The thin-limit energy ε (w = 0) of a shape class, or None where none is known.

    Parameters
    ----------
    shape : str or None
        A label of :func:`stiffknots.analysis.classify` ('CB', '4C', '80', 'other') or the
        short form of a result ('CB2', 'CB3', …).
    multiplicity : int, optional
        The multiplicity i of a circular braid (needed for 'CB').

    Returns
    -------
    dict or None
        ``shape`` (e.g. 'CB(2)'), ``epsilon``, ``error`` and ``method``.
    """
    if not shape:
        return None
    label = str(shape)
    if label.startswith("CB"):
        i = multiplicity if label == "CB" else int(label[2:]) if label[2:].isdigit() else None
        if not i or i < 1:
            return None
        return {"shape": f"CB({i})", "epsilon": 2.0 * math.pi**2 * i * i, "error": 0.0,
                "method": "circular braid 2π²i², eq. (30)"}
    if label == "80":
        from stiffknots.theory.elastica import eps_80

        return {"shape": "80", "epsilon": eps_80(), "error": 1e-9,
                "method": "(√ε_8 + √(2π²))², §VII from eq. (27), Appendix D"}
    if label == "4C":
        return {"shape": "4C", "epsilon": EPS_4C, "error": EPS_4C_ERROR,
                "method": "structure solved at w = 0 (§V B), theory.structures"}
    return None


def thin_limit_note(epsilon: float | None, shape: str | None, multiplicity: int | None,
                    width_text: str) -> dict:
    """What a finite-width result says about the thin limit: the shape's w = 0 value and the
    relative excess of ``epsilon`` over it, with the width in words."""
    ref = thin_limit_of_shape(shape, multiplicity)
    if epsilon is None or ref is None:
        return {"shape": ref["shape"] if ref else shape, "epsilon": None, "excess": None,
                "note": (f"computed at {width_text}; ε at a finite width is an upper bound "
                         "of the thin-limit ε* (ε*_w rises with w, §V A); no w = 0 value is "
                         f"known for shape {shape!r} (see `stiffknots thin-limit`)")}
    excess = epsilon / ref["epsilon"] - 1.0
    pct = 100 * excess
    # two significant figures below 0.1 % (3_1 at N = 600 is +0.005 %, not "+0.00 %")
    text = f"{pct:+.2g}" if 0 < abs(pct) < 0.1 else f"{pct:+.2f}"
    note = (f"computed at {width_text}: {text} % from the thin limit of its shape "
            f"{ref['shape']}, ε = {ref['epsilon']:.4f} ({ref['method']})")
    if excess < 0:  # N beads of a thin chain: the discretisation wins over the width
        note += ("; below it because the discretisation of N beads lowers ε (a regular "
                 "N-gon: N²(1 − cos 2π/N) < 2π²) more than the width raises it")
    return {**ref, "excess": excess, "note": note}
