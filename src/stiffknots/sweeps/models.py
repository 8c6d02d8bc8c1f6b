"""Models of a sweep: each a :class:`~stiffknots.width.Width` — the exclusion rule and its
thickness at a bead count.

``bead`` is the paper's rule (§VII): no two beads at index distance ≥ 2 closer than
d = 1/√2 (an excluded-volume tube of width between 1 and √2 bonds). ``tube`` is the hard
tube of diameter w (no two segments that share no bead closer than w), w = 1/√2 unless set.
Both at N = 150 beads (bond length 1, L = N), so w/L = d/N ≈ 0.0047 — a finite width: every
ε of a sweep is a finite-width value, above the thin-limit ε* (§V A, App. A).
"""

from __future__ import annotations

from stiffknots.engine.params import MoveParams
from stiffknots.errors import InvalidParameter
from stiffknots.width import BEAD_D, EXCLUSIONS, Width

__all__ = ["MODELS", "DEFAULT_BEADS", "BEAD_D", "parse_models", "for_beads", "params_of"]

#: The paper's bead count (§VII).
DEFAULT_BEADS = 150
#: The model names.
MODELS = EXCLUSIONS


def for_beads(obj, beads: int):
    """``obj.for_beads(beads)`` where the engine's parameters have it (sizes that scale with
    N, as :class:`~stiffknots.problems.closed.ClosedAnneal` applies them), else ``obj``: the
    sweep's key settings must be exactly the problem's."""
    f = getattr(obj, "for_beads", None)
    return f(beads) if callable(f) else obj


def params_of(model: Width) -> MoveParams:
    """The move parameters of a sweep's model (every other field at its default, sized for N
    as the problems size them: :func:`for_beads`)."""
    return for_beads(MoveParams().at_width(model), model.beads)


def parse_models(text: str | list[str] | tuple[str, ...], *, w: float | None = None,
                 beads: int = DEFAULT_BEADS) -> list[Width]:
    """The models of ``"bead,tube"`` (or a list of names), the tube at diameter ``w``
    (default 1/√2), each at ``beads`` beads; duplicates dropped, order kept.

    Raises
    ------
    InvalidParameter
        An unknown or missing name, a width the engine refuses (0 < w < 1).
    """
    names = [s.strip() for s in (text.split(",") if isinstance(text, str) else text)]
    names = [s for s in names if s]
    if not names:
        raise InvalidParameter("models", text, "bead and/or tube, separated by commas")
    out = []
    for name in dict.fromkeys(names):
        if name not in MODELS:
            raise InvalidParameter("models", name, "bead and/or tube, separated by commas")
        t = w if (name == "tube" and w is not None) else BEAD_D
        m = Width.of(name, float(t), int(beads))
        params_of(m).validate(m.beads)
        out.append(m)
    return out
