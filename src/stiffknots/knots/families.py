"""The paper's conjectured knot families and the ground-state shape each one predicts (§VI C, §VII).

Gallotti & Pierre-Louis (PRE 2007) name three families whose stiff ground states they know or
conjecture:

``"n=i"`` — bridge number equals braid index (§VI C)
    The bounds of eq. (e:epsilon_ineq) coincide: the ground state *is* the circular braid
    CB(i), ε* = 2π²i² (proven, not conjectured). It holds the torus knots.
``"4C"`` — the 4-fold cage (§VII, Fig. 8)
    Two twist boxes joined by four arcs around a sphere: the rational knots with a two-box
    Conway notation ``[ab]`` (4_1 = [22], 5_2 = [32], 6_1 = [42], ...), read from KnotInfo by
    :func:`stiffknots.knots.cage_embedding.two_box_conway`.
``"80"`` — the 80, a figure eight plus a circle (§VII, Fig. 8)
    The knots an 80 with twist boxes of any number of half-turns can be: the family of
    :mod:`stiffknots.knots.eighty_embedding` (centre twist ``j``, point-braid ``k``, a clasp;
    two-bridge knots only). :data:`EIGHTY_FAMILY` lists its members through 10 crossings, as
    :func:`~stiffknots.knots.eighty_embedding.eighty_table` finds them (diagrams of
    ``j + k + 2 ≤ 10`` crossings, N = 150 chains identified by HOMFLY-PT, two-bridge knots
    kept; HOMFLY-PT twins such as 10_132 of 5_1 dropped). The list is data computed once
    (about 45 s); ``tests/knots/test_families.py`` recomputes it (slow).

A knot may belong to several families (3_1 is ``n=i`` and an 80; 4_1 is a cage and an 80).
The hierarchy of §VII, CB(i=2) < 4C < 80 < CB(i=3) < PBL(n=2) (eq. e:hierarchy), orders the
predictions: :func:`predicted_shape` gives CB for ``n=i`` (proven), else 4C for a cage knot,
else 80 for an 80 knot, else None.

The paper counts (§VII, from the knot tables): the three families hold all prime knots with
n_c < 7 and 75 % of those with n_c < 9 (:func:`coverage` recomputes both).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

__all__ = ["FAMILIES", "EIGHTY_FAMILY", "EIGHTY_FAMILY_MAX_CROSSINGS", "SHAPE_OF_FAMILY",
           "families_of", "predicted_shape", "coverage"]

#: The families, in the order of the hierarchy of their shapes (eq. e:hierarchy).
FAMILIES = ("n=i", "4C", "80")

#: The shape class (:func:`stiffknots.analysis.classify` label) each family predicts.
SHAPE_OF_FAMILY = {"n=i": "CB", "4C": "4C", "80": "80"}

#: Largest crossing number :data:`EIGHTY_FAMILY` is complete for.
EIGHTY_FAMILY_MAX_CROSSINGS = 10

#: Prime knots through 10 crossings that are 80s (module docstring; 26 knots).
EIGHTY_FAMILY = frozenset({
    "3_1", "4_1", "5_1", "5_2", "6_1", "6_2", "6_3", "7_1", "7_2", "7_3", "7_5", "7_6", "8_1",
    "8_2", "8_6", "8_7", "8_8", "9_1", "9_3", "9_6", "9_7", "9_8", "9_11", "10_2", "10_6",
    "10_20",
})


def families_of(knot: Any) -> list[str]:
    """The conjectured families a knot belongs to, in the order of :data:`FAMILIES`.

    Parameters
    ----------
    knot : Knot
        A catalogue entry (:func:`stiffknots.knots.catalogue.get_knot`).

    Returns
    -------
    list of str
        A subset of ``["n=i", "4C", "80"]``; ``"80"`` is decided only through
        :data:`EIGHTY_FAMILY_MAX_CROSSINGS` crossings (a larger knot is never listed as an 80).
    """
    from stiffknots.knots.cage_embedding import two_box_conway

    out = []
    if knot.n_equals_i:
        out.append("n=i")
    if two_box_conway(knot.conway_notation, knot.crossing_number) is not None:
        out.append("4C")
    if knot.name in EIGHTY_FAMILY:
        out.append("80")
    return out


def predicted_shape(knot: Any) -> tuple[str, int | None] | None:
    """The ground-state shape the families predict: ``("CB", i)``, ``("4C", None)``,
    ``("80", None)``, or None for a knot in no family (see the module docstring)."""
    fams = families_of(knot)
    if "n=i" in fams:
        return "CB", knot.braid_index
    for f in ("4C", "80"):
        if f in fams:
            return SHAPE_OF_FAMILY[f], None
    return None


def coverage(knots: Iterable[Any], limits: Iterable[int] = (7, 9)) -> list[dict[str, Any]]:
    """How many knots of the catalogue the families hold, for n_c below each limit (§VII).

    Parameters
    ----------
    knots : iterable of Knot
        Catalogue entries (e.g. ``catalogue(10)``); the unknot is ignored.
    limits : iterable of int
        One row per limit ``c``: the knots with ``n_c < c``; a last row counts them all.

    Returns
    -------
    list of dict
        ``label``, ``limit``, ``knots``, ``covered`` (in at least one family), ``fraction``,
        ``by_family`` (family → members), ``outside`` (names in no family).
    """
    ks = [k for k in knots if k.crossing_number >= 3]
    too_big = [k.name for k in ks if k.crossing_number > EIGHTY_FAMILY_MAX_CROSSINGS]
    if too_big:
        raise ValueError(f"the 80 family is tabulated through {EIGHTY_FAMILY_MAX_CROSSINGS} "
                         f"crossings; {too_big[0]} is larger")
    rows = []
    top = max((k.crossing_number for k in ks), default=0)
    for c in [*sorted(set(limits)), None]:
        sel = [k for k in ks if c is None or k.crossing_number < c]
        fam = {k.name: families_of(k) for k in sel}
        covered = sum(1 for f in fam.values() if f)
        rows.append({
            "label": f"n_c < {c}" if c is not None else f"n_c ≤ {top}",
            "limit": c, "knots": len(sel), "covered": covered,
            "fraction": covered / len(sel) if sel else None,
            "by_family": {f: sum(1 for v in fam.values() if f in v) for f in FAMILIES},
            "outside": [n for n, v in fam.items() if not v],
        })
    return rows
