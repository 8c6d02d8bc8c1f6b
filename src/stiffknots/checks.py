"""Is a chain what the package assumes? Bonds, exclusion and, if asked, the knot type.

Every quantity of stiffknots is defined for a chain of unit bonds obeying an exclusion rule
(the paper's bead rule, §VII: beads at index distance ≥ 2 no closer than d = 1/√2). A chain
from elsewhere — a file, another program, a hand-made polygon — may not be one: ε, the knot
type and the shape class are computed all the same, and mean little. :func:`check` says what
the chain is::

    from stiffknots.checks import check
    c = check(chain, knot="3_1")
    c.ok, c.problems          # False, ['bond 17 has length 1.3 (unit bonds: ...)', ...]
    c.min_bead_distance, c.min_segment_distance, c.max_bond_error, c.knot_found

The shape analysis (:func:`stiffknots.analysis.classify`,
:func:`~stiffknots.analysis.analyse_structure`) warns (:class:`~stiffknots.errors.ChainWarning`)
on a chain that is not a unit-bond chain obeying the bead rule; both use
:func:`stiffknots.measures.chain_report`.

The module sits above the catalogue and the analysis in the layers (the knot type needs the
invariants of :mod:`stiffknots.knots.identify`); the geometric checks live below them, in
:mod:`stiffknots.measures`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from stiffknots.chain import as_coords
from stiffknots.measures import BEAD_D, chain_report

__all__ = ["ChainCheck", "check"]


@dataclass(frozen=True)
class ChainCheck:
    """What :func:`check` found.

    Attributes
    ----------
    n_beads, closed
        The chain.
    bond_min, bond_max, max_bond_error
        Bond lengths and the largest ``|bond − 1|``.
    min_bead_distance : float
        The smallest distance between beads at index distance ≥ 2 (the bead
        rule's quantity; cyclic for a closed chain).
    min_segment_distance : float or None
        The smallest distance between segments sharing no bead (the tube's
        quantity: a tube of diameter w fits only if it is ≥ w).
    d, bond_tol : float
        The bead rule's distance and the bond tolerance checked against.
    unit_bonds, bead_rule : bool
        The two checks.
    knot : str or None
        The knot type asked for (None if not asked).
    knot_found : str or None
        What the HOMFLY-PT polynomial identifies (None unless asked; candidates joined by
        ``'|'``).
    knot_ok : bool or None
        Whether ``knot`` is among them.
    problems : tuple of str
        One sentence per failed check.
    """

    n_beads: int
    closed: bool
    bond_min: float | None
    bond_max: float | None
    max_bond_error: float
    min_bead_distance: float
    min_segment_distance: float | None
    d: float
    bond_tol: float
    unit_bonds: bool
    bead_rule: bool
    knot: str | None = None
    knot_found: str | None = None
    knot_ok: bool | None = None
    problems: tuple[str, ...] = field(default_factory=tuple)

    @property
    def ok(self) -> bool:
        """True when every check asked for passed."""
        return not self.problems

    def to_dict(self) -> dict:
        return asdict(self) | {"problems": list(self.problems), "ok": self.ok}

    def __str__(self) -> str:
        head = (f"{'closed' if self.closed else 'open'} chain of {self.n_beads} beads: bonds "
                f"{self.bond_min:.6g}–{self.bond_max:.6g}, closest beads "
                f"{self.min_bead_distance:.4g}"
                + (f", closest segments {self.min_segment_distance:.4g}"
                   if self.min_segment_distance is not None else "")
                + (f", knot {self.knot_found}" if self.knot_found is not None else ""))
        return head + ("; ok" if self.ok else "; " + "; ".join(self.problems))


def check(chain: Any, closed: bool | None = None, *, d: float = BEAD_D,
          bond_tol: float = 1e-6, knot: str | None = None, identify: bool = False
          ) -> ChainCheck:
    """Check a chain against the model of the package.

    Parameters
    ----------
    chain
        A :class:`~stiffknots.chain.Chain` or bead coordinates, shape (N, 3).
    closed : bool or None
        Default: the Chain's own, True for coordinates.
    d : float
        The bead rule's distance (default 1/√2, the paper's); for the tube model pass the tube
        diameter w (a tube of diameter w keeps beads at index distance ≥ 2 at least w apart).
    bond_tol : float
        Largest allowed ``|bond − 1|`` (default 1e-6; annealed chains keep 1e-10).
    knot : str or None
        A knot name: also check that the chain has this knot type (HOMFLY-PT polynomial,
        mirror-insensitive; an open chain is closed along z first, §VIII).
    identify : bool
        Also identify the knot type without expecting one.

    Returns
    -------
    ChainCheck
        ``ok`` and ``problems`` summarise it.
    """
    if closed is None:
        closed = bool(getattr(chain, "closed", True))
    x = as_coords(chain)
    rep = chain_report(x, closed, d=d, bond_tol=bond_tol)
    problems = list(rep.pop("problems"))
    rep.pop("worst_bond")
    found = ok = None
    if knot is not None:
        from stiffknots.knots.identify import normalize_name, verify_knot

        ok, found = verify_knot(x, knot, closed=closed)
        if not ok:
            problems.append(f"its knot type is {found}, not {normalize_name(knot)}")
    elif identify:
        from stiffknots.knots.identify import identify as identify_knot

        found = identify_knot(x, closed=closed)
    return ChainCheck(**rep, knot=knot, knot_found=found, knot_ok=ok,
                      problems=tuple(problems))
