"""Invariants beyond the HOMFLY-PT polynomial, from a diagram of the polygon: the hyperbolic
volume and the isometry class of the knot complement (SnapPy), and knot Floer homology
(``knot_floer_homology``, shipped with SnapPy). Used by
:func:`stiffknots.knots.identify.identify_name` to break HOMFLY-PT ties and to give the chirality.

Why these invariants
--------------------
* The **hyperbolic volume** of the complement S³ \\ K (SnapPy, compared with KnotInfo's
  ``volume`` column, ten digits) separates every HOMFLY-PT tie through 10 crossings: torus knots
  and composite knots have no hyperbolic structure (5_1 | 10_132, 9_12 | 4_1#5_2), and the other
  pairs have different volumes (8_8: 7.8013 | 10_129: 8.9015, ...). Mutant knots share both
  the polynomial and the volume (from 11 crossings on: the Conway and Kinoshita–Terasaka knots
  11n_34 | 11n_42, many 12-crossing pairs).
* **Knot Floer homology** (its ranks, hence the Seifert genus) separates some mutants: the
  Conway knot has genus 3, Kinoshita–Terasaka genus 2.
* The **isometry class** of the complement: knots are determined by their complements
  (Gordon–Luecke), and for hyperbolic knots Mostow rigidity makes SnapPy's isometry test
  exact in practice; what it cannot settle is reported as a remaining tie. An isometry from
  the polygon's complement to the complement of KnotInfo's diagram either preserves the
  orientation of S³ (the polygon is KnotInfo's knot) or reverses it (the mirror image); both
  exist exactly for amphichiral knots. This is the **chirality** for hyperbolic knots.
* For the non-hyperbolic prime knots (torus knots) the chirality is the sign of the
  Ozsváth–Szabó τ invariant compared with KnotInfo's ``ozsvath_szabo_tau_invariant`` (τ of a
  torus knot is ± its genus, never 0; ``knot_floer_homology`` computes τ with KnotInfo's sign
  convention, checked in the tests).

The diagram comes from :func:`stiffknots.knots.diagram.pd_code` on the KMT-reduced polygon and
is simplified by spherogram (``simplify('global')``) before SnapPy triangulates its complement.
"""

from __future__ import annotations

import contextlib
import functools
import io
import math
import re

from stiffknots.knots.diagram import pd_code, reduce_polygon

__all__ = [
    "Diagram",
    "diagram_of",
    "knotinfo_volume",
    "volumes_match",
    "hfk_matches",
    "isometry_orientations",
    "chirality_of",
]

#: SnapPy's answer is accepted as hyperbolic only with all tetrahedra positively oriented.
_GEOMETRIC = "all tetrahedra positively oriented"
#: KnotInfo prints volumes to 10 decimals.
VOLUME_TOL = 1e-6


@contextlib.contextmanager
def _quiet():
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        yield


@functools.cache
def _snappy():
    with _quiet():
        import snappy  # noqa: F401  (slow import: ~1 s)
        import spherogram
    return snappy, spherogram


class Diagram:
    """A knot diagram (spherogram ``Link``) and, lazily, its complement's invariants.

    Parameters
    ----------
    pd : list of 4-tuples
        PD code (KnotTheory convention).
    """

    def __init__(self, pd):
        _, spherogram = _snappy()
        self.pd = [tuple(int(v) for v in c) for c in pd]
        self.link = spherogram.Link(self.pd) if self.pd else None
        if self.link is not None:
            with _quiet():
                self.link.simplify("global")
            if not self.link.crossings:
                self.link = None
        self._volume = "unset"
        self._manifold = None
        self._hfk = None

    @property
    def crossings(self) -> int:
        """Crossings of the simplified diagram (an upper bound on the crossing number)."""
        return 0 if self.link is None else len(self.link.crossings)

    def simplified_pd(self) -> list[tuple[int, int, int, int]]:
        if self.link is None:
            return []
        return [tuple(c) for c in self.link.PD_code()]

    def manifold(self):
        """The complement (a SnapPy ``Manifold``), or None for the unknot."""
        if self._manifold is None and self.link is not None:
            with _quiet():
                self._manifold = self.link.exterior()
        return self._manifold

    def volume(self, tries: int = 16) -> float | None:
        """Hyperbolic volume of the complement, or None when SnapPy finds no hyperbolic
        structure after ``tries`` re-triangulations (torus knots, composite knots, unknot)."""
        if self._volume != "unset":
            return self._volume
        vol = None
        M = self.manifold()
        if M is not None:
            M = M.copy()
            with _quiet():
                for _ in range(tries):
                    if M.solution_type() == _GEOMETRIC:
                        vol = float(M.volume())
                        break
                    M.randomize()
        self._volume = vol
        return vol

    def hfk(self) -> dict | None:
        """Knot Floer homology of the diagram (``knot_floer_homology.pd_to_hfk``)."""
        if self._hfk is None and self.link is not None:
            from knot_floer_homology import pd_to_hfk

            self._hfk = pd_to_hfk(self.simplified_pd())
        return self._hfk

    def deconnects(self) -> int:
        """Number of non-trivial pieces the simplified diagram splits into along visible
        connected-sum circles (1 for a prime-looking diagram)."""
        if self.link is None:
            return 0
        with _quiet():
            parts = self.link.deconnect_sum()
        return sum(1 for p in parts if len(p.crossings) > 0)


def diagram_of(coords) -> Diagram:
    """The simplified diagram of the closed polygon ``coords`` (KMT-reduced first)."""
    return Diagram(pd_code(reduce_polygon(coords)))


# --------------------------------------------------------------------------------------------
# catalogue side
# --------------------------------------------------------------------------------------------


def knotinfo_volume(knot) -> float | None:
    """KnotInfo's hyperbolic volume of a catalogue knot; None where it is not hyperbolic (the
    unknot, torus knots: KnotInfo writes 0 or nothing)."""
    text = (knot.raw.get("volume") or "").strip()
    try:
        v = float(text)
    except ValueError:
        return None
    return v if v > 0 else None


def _knotinfo_tau(knot) -> int | None:
    text = (knot.raw.get("ozsvath_szabo_tau_invariant") or "").strip()
    return int(text) if re.fullmatch(r"-?\d+", text) else None


@functools.lru_cache(maxsize=4096)
def _catalogue_diagram(name: str) -> Diagram:
    from stiffknots.knots.catalogue import get_knot

    k = get_knot(name)
    if not k.pd_code:
        raise ValueError(f"KnotInfo has no PD code for {name}")
    return Diagram(k.pd_code)


def volumes_match(measured: float | None, expected: float | None) -> bool:
    """Same volume (to KnotInfo's precision), or both not hyperbolic."""
    if measured is None or expected is None:
        return measured is None and expected is None
    return abs(measured - expected) <= VOLUME_TOL * max(1.0, expected)


def _mirror_ranks(ranks: dict) -> dict:
    return {(-a, -m): r for (a, m), r in ranks.items()}


def hfk_matches(d: Diagram, name: str) -> bool | None:
    """Does the polygon's knot Floer homology equal that of the catalogue knot ``name`` or of
    its mirror? None if it cannot be computed (no PD code, a composite name)."""
    if "#" in name:
        return None
    try:
        ref = _catalogue_diagram(name).hfk()
    except ValueError:
        return None
    mine = d.hfk()
    if mine is None or ref is None:
        return (mine is None) == (ref is None)
    a, b = dict(mine["ranks"]), dict(ref["ranks"])
    return a == b or a == _mirror_ranks(b)


def isometry_orientations(d: Diagram, name: str) -> set[int] | None:
    """Orientation signs (+1 preserving, -1 reversing) of the isometries from the polygon's
    complement to the complement of KnotInfo's diagram of ``name``; an empty set when they are
    not isometric, None when SnapPy cannot decide."""
    M = d.manifold()
    try:
        N = _catalogue_diagram(name).manifold()
    except ValueError:
        return None
    if M is None or N is None:
        return None
    snappy, _ = _snappy()
    try:
        with _quiet():
            isos = M.is_isometric_to(N, return_isometries=True)
    except (RuntimeError, ValueError, snappy.SnapPeaFatalError):
        return None
    out = set()
    for iso in isos:
        det = iso.cusp_maps()[0].det()
        out.add(1 if det > 0 else -1)
    return out


def chirality_of(d: Diagram, name: str) -> tuple[str | None, str]:
    """Chirality of the polygon relative to KnotInfo's diagram of ``name``.

    Returns ``(chirality, how)``: ``'+'`` (KnotInfo's knot: the diagram of its
    ``pd_notation``), ``'-'`` (its mirror image) or None (amphichiral, or undecided), and a
    short phrase saying how it was decided.
    """
    from stiffknots.knots.catalogue import get_knot

    if "#" in name or name == "0_1":
        return None, "not defined here (unknot or composite knot)"
    k = get_knot(name)
    sym = (k.raw.get("symmetry_type") or "").lower()
    if "amphicheiral" in sym or "amphichiral" in sym:
        return None, f"amphichiral ({sym}): the mirror image is the same knot"
    if knotinfo_volume(k) is not None:
        ori = isometry_orientations(d, name)
        if ori == {1}:
            return "+", "isometry of the complements (SnapPy) preserves orientation"
        if ori == {-1}:
            return "-", "isometry of the complements (SnapPy) reverses orientation"
        if ori == {1, -1}:
            return None, "the complement has orientation-reversing symmetries (amphichiral)"
    tau_ref = _knotinfo_tau(k)
    h = d.hfk()
    if tau_ref and h is not None and h.get("tau"):
        return ("+" if math.copysign(1, h["tau"]) == math.copysign(1, tau_ref) else "-",
                "sign of the Ozsváth–Szabó τ invariant (knot Floer homology)")
    return None, "undecided (no invariant at hand tells the mirror images apart)"
