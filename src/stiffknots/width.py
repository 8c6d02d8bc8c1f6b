"""The width a number was computed at: one exclusion model, its thickness, the bead count N and
w/L — one object from the command line to the kernel, the store and the pages.

The paper's subject is the thin limit w/L → 0 (§V A); every Monte Carlo number is computed at a
finite width and must say which. Two exclusion models give a chain a width:

* ``bead`` — the paper's rule (§VII): no two beads at index distance ≥ 2 closer than d
  (d = 1/√2 at N = 150). Its tube is about d wide, so w/L ≈ d/L.
* ``tube`` — a hard tube of diameter w: no two segments that share no bead closer than w.

With bond length 1 the contour length is L = N for a closed chain (a knot) and L = N − 1 for an
open one, so w/L = w/N or w/(N − 1). A :class:`Width` is built from either the thickness in bond
lengths (:meth:`Width.tube`, :meth:`Width.bead`) or w/L (``Width.tube(N, w_over_L=…)``); it
holds both, exactly as given, and checks that they agree.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from stiffknots.errors import InvalidParameter

__all__ = ["BEAD_D", "EXCLUSIONS", "MAX_W_OVER_L", "Width"]

#: the paper's bead distance d = 1/√2 (§VII), also the default tube diameter
BEAD_D = float(1 / math.sqrt(2))
#: the exclusion models
EXCLUSIONS = ("bead", "tube")
#: the widest tube given by w/L (the paper's thin limit is w/L → 0, §V A)
MAX_W_OVER_L = 1 / 8


def _length(beads: int, closed: bool) -> int:
    return beads if closed else beads - 1


@dataclass(frozen=True)
class Width:
    """One exclusion model at one thickness and bead count.

    Attributes
    ----------
    exclusion : str
        ``"bead"`` (the paper's bead rule) or ``"tube"``.
    thickness : float
        d (bead rule) or w (tube diameter), in bond lengths; 0 < thickness < 1 (a tube as wide
        as a bond would forbid the chain's own bends).
    beads : int
        N.
    w_over_L : float
        thickness / L, L = N (closed) or N − 1 (open).
    closed : bool
        A knot (True) or an open chain.

    Notes
    -----
    Build it with :meth:`tube`, :meth:`bead` or :meth:`from_dict`; the constructor checks that
    the four numbers agree.
    """

    exclusion: str
    thickness: float
    beads: int
    w_over_L: float  # noqa: N815 (the paper's symbol)
    closed: bool = True

    def __post_init__(self):
        if self.exclusion not in EXCLUSIONS:
            raise InvalidParameter("exclusion", self.exclusion, "one of bead, tube")
        if isinstance(self.beads, bool) or not float(self.beads).is_integer() or self.beads < 3:
            raise InvalidParameter("beads", self.beads, "an integer ≥ 3")
        name = "d" if self.exclusion == "bead" else "w"
        t = self.thickness
        if not (isinstance(t, int | float) and math.isfinite(t) and 0 < t < 1):
            raise InvalidParameter(name, t, "a finite number in (0, 1)", "bond lengths")
        length = _length(int(self.beads), self.closed)
        if not math.isclose(self.w_over_L * length, t, rel_tol=1e-9):
            raise InvalidParameter("w_over_L", self.w_over_L,
                                   f"{name}/L = {t / length:.6g} ({name} = {t:g}, L = {length})")

    # -- constructors -------------------------------------------------------------------------

    @classmethod
    def tube(cls, beads: int, *, w: float | None = None, w_over_L: float | None = None,  # noqa: N803
             closed: bool = True) -> Width:
        """The tube model at N = ``beads``, its diameter given as ``w`` (bond lengths) or as
        ``w_over_L`` (one of the two; neither: w = 1/√2, the paper's d).

        Raises
        ------
        InvalidParameter
            Both given; w outside (0, 1); w/L outside (0, 1/8] or so wide that w = (w/L)·L
            is a bond or more at this N.
        """
        if w is not None and w_over_L is not None:
            raise InvalidParameter("w_over_L", w_over_L, "given without w (both set the "
                                   "tube's diameter; give one)")
        length = _length(int(beads), closed)
        if w_over_L is None:
            t = BEAD_D if w is None else w
            _check_thickness("w", t)
            return cls("tube", float(t), int(beads), float(t) / length, closed)
        wl = w_over_L
        if not (isinstance(wl, int | float) and not isinstance(wl, bool) and math.isfinite(wl)
                and 0 < wl <= MAX_W_OVER_L):
            raise InvalidParameter("w_over_L", wl, f"a finite number in (0, {MAX_W_OVER_L:g}]")
        if wl * length >= 1:
            ell = "N" if closed else "(N − 1)"
            raise InvalidParameter("w_over_L", wl, f"below 1/{ell} = {1 / length:.3g}",
                                   f"the tube w = (w/L)·{ell} must be thinner than a bond at "
                                   f"N = {int(beads)}")
        return cls("tube", float(wl) * length, int(beads), float(wl), closed)

    @classmethod
    def bead(cls, beads: int, *, d: float = BEAD_D, closed: bool = True) -> Width:
        """The paper's bead rule at N = ``beads`` with bead distance ``d`` (bond lengths)."""
        _check_thickness("d", d)
        return cls("bead", float(d), int(beads), float(d) / _length(int(beads), closed), closed)

    @classmethod
    def of(cls, exclusion: str, thickness: float, beads: int, *, closed: bool = True) -> Width:
        """``exclusion`` at ``thickness`` bond lengths (:meth:`bead` or :meth:`tube`)."""
        if exclusion == "tube":
            return cls.tube(beads, w=thickness, closed=closed)
        if exclusion == "bead":
            return cls.bead(beads, d=thickness, closed=closed)
        raise InvalidParameter("exclusion", exclusion, "one of bead, tube")

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Width:
        """The width of :meth:`as_dict` (``exclusion``, ``w`` or ``d``, ``beads``,
        ``w_over_L``, ``closed``)."""
        ex = d["exclusion"]
        t = d["w"] if ex == "tube" else d["d"]
        return cls(ex, float(t), int(d["beads"]), float(d["w_over_L"]),
                   bool(d.get("closed", True)))

    # -- derived ------------------------------------------------------------------------------

    @property
    def length(self) -> int:
        """L in bond lengths: N for a closed chain, N − 1 for an open one."""
        return _length(self.beads, self.closed)

    def at_beads(self, beads: int) -> Width:
        """The same thickness in bond lengths at another N (a thicker knot at fewer beads:
        w/L changes)."""
        return Width.of(self.exclusion, self.thickness, beads, closed=self.closed)

    def at(self, w_over_L: float) -> Width:  # noqa: N803
        """The tube at another w/L, the same N."""
        return Width.tube(self.beads, w_over_L=w_over_L, closed=self.closed)

    @property
    def _thickness_text(self) -> str:
        t = self.thickness
        return "1/√2" if math.isclose(t, BEAD_D, rel_tol=1e-12) else f"{t:.4g}"

    @property
    def short(self) -> str:
        """``tube w = 0.6, N = 150`` / ``bead d = 1/√2, N = 150``."""
        sym = "w" if self.exclusion == "tube" else "d"
        return f"{self.exclusion} {sym} = {self._thickness_text}, N = {self.beads}"

    @property
    def text(self) -> str:
        """One line saying what the width is:
        ``tube w = 0.6, N = 150 (w/L = 0.004)`` / ``bead rule d = 1/√2, N = 150 (w/L ≈ 0.0047)``
        (the bead rule's tube is about d wide, hence ≈)."""
        if self.exclusion == "tube":
            return (f"tube w = {self._thickness_text}, N = {self.beads} "
                    f"(w/L = {self.w_over_L:.2g})")
        return (f"bead rule d = {self._thickness_text}, N = {self.beads} "
                f"(w/L ≈ {self.w_over_L:.2g})")

    def __str__(self) -> str:
        return self.text

    def as_dict(self) -> dict[str, Any]:
        """``exclusion``, ``w`` (tube) or ``d`` (bead), ``beads``, ``w_over_L``, ``closed``,
        ``text`` and ``short`` — what every result, store row and page records."""
        sym = "w" if self.exclusion == "tube" else "d"
        return {"exclusion": self.exclusion, sym: self.thickness, "beads": self.beads,
                "w_over_L": self.w_over_L, "closed": self.closed, "text": self.text,
                "short": self.short}


def _check_thickness(name: str, t: Any) -> None:
    if isinstance(t, bool) or not (isinstance(t, int | float) and math.isfinite(t)
                                   and 0 < t < 1):
        raise InvalidParameter(name, t, "a finite number in (0, 1)", "bond lengths")
