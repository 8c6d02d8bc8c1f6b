"""Models of a sweep: the exclusion rule and its width, at a bead count.

``bead`` is the paper's rule (§VII): no two beads at index distance ≥ 2 closer than
d = 1/√2 (an excluded-volume tube of width between 1 and √2 bonds). ``tube`` is the hard
tube of diameter w (no two segments that share no bead closer than w), w = 1/√2 unless set.
Both at N = 150 beads (bond length 1, L = N), so w/L = d/N ≈ 0.0047 — a finite width: every
ε of a sweep is a finite-width value, above the thin-limit ε* (§V A, App. A).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from stiffknots.engine.params import MoveParams
from stiffknots.errors import InvalidParameter

__all__ = ["Model", "MODELS", "DEFAULT_BEADS", "BEAD_D", "parse_models", "for_beads"]

#: The paper's bead count (§VII).
DEFAULT_BEADS = 150
#: The paper's bead distance d = 1/√2 (§VII), also the default tube diameter.
BEAD_D = MoveParams().d
#: The model names.
MODELS = ("bead", "tube")


def for_beads(obj, beads: int):
    """``obj.for_beads(beads)`` where the engine's parameters have it (sizes that scale with
    N, as :class:`~stiffknots.problems.closed.ClosedAnneal` applies them), else ``obj``: the
    sweep's key settings must be exactly the problem's."""
    f = getattr(obj, "for_beads", None)
    return f(beads) if callable(f) else obj


@dataclass(frozen=True)
class Model:
    """One exclusion model at one width and bead count.

    Attributes
    ----------
    name : str
        ``bead`` or ``tube`` (also the exclusion of the store key).
    thickness : float
        d (bead rule) or w (tube diameter), in bonds.
    beads : int
        N.
    """

    name: str
    thickness: float = BEAD_D
    beads: int = DEFAULT_BEADS

    @property
    def exclusion(self) -> str:
        return self.name

    @property
    def w_over_L(self) -> float:  # noqa: N802 (the paper's symbol)
        return self.thickness / self.beads

    def params(self) -> MoveParams:
        """The move parameters of the model (every other field at its default, sized for N
        as the problems size them: :func:`for_beads`)."""
        if self.name == "tube":
            p = replace(MoveParams(), exclusion="tube", w=self.thickness)
        else:
            p = replace(MoveParams(), exclusion="bead", d=self.thickness)
        return for_beads(p, self.beads)

    def width(self) -> dict:
        """The width every number of this model was computed at (for reports): the model's
        ``d`` or ``w``, ``beads``, ``w_over_L``, ``text`` (one line) and ``short``."""
        t, n = self.thickness, self.beads
        tt = "1/√2" if math.isclose(t, BEAD_D, rel_tol=1e-12) else f"{t:.4g}"
        if self.name == "tube":
            text = f"tube w = {tt}, N = {n} (w/L = {t / n:.2g})"
            return {"exclusion": "tube", "w": t, "beads": n, "w_over_L": t / n, "text": text,
                    "short": f"tube w = {tt}, N = {n}"}
        text = f"bead rule d = {tt}, N = {n} (w/L ≈ {t / n:.2g})"
        return {"exclusion": "bead", "d": t, "beads": n, "w_over_L": t / n, "text": text,
                "short": f"bead d = {tt}, N = {n}"}

    def validate(self) -> Model:
        if self.name not in MODELS:
            raise InvalidParameter("models", self.name, "bead and/or tube, separated by commas")
        self.params().validate(self.beads)
        return self


def parse_models(text: str | list[str] | tuple[str, ...], *, w: float | None = None,
                 beads: int = DEFAULT_BEADS) -> list[Model]:
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
        out.append(Model(name, float(t), int(beads)).validate())
    return out
