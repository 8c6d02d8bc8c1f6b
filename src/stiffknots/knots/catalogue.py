"""The knot catalogue: prime knots up to 13 crossings, from KnotInfo.

Every knot of the standard tables with the invariants the mechanics of stiff knots needs
(Gallotti & Pierre-Louis, "Stiff knots", PRE 2007):

* the crossing number :math:`n_c`;
* the bridge number :math:`n`, which sets the lower bound on the bending energy through
  Milnor's inequality :math:`2\\pi n \\le \\bar\\kappa` (§IV, eq. ``eq. (9)``), hence
  :math:`\\epsilon^* \\ge 2\\pi^2 n^2`;
* the braid index :math:`i`, which sets the circular-braid upper bound
  :math:`\\epsilon^*_{CB} = 2\\pi^2 i^2` (§VI A, eq. ``eq. (30)``), with :math:`i \\ge n`;
* a braid word (from which a 3D embedding is built) and a PD code;
* the torus-knot parameters, where the knot is a torus knot.

Knots with :math:`n = i` form the family of §VI C, whose ground state is the circular
line-braid of multiplicity :math:`i` (:math:`\\epsilon^* = 2\\pi^2 i^2`).

The data come from the ``database_knotinfo`` package (KnotInfo, Livingston & Moore), parsed
once per process and cached. KnotInfo stores some values as intervals (the bridge number of
536 knots with 13 crossings is ``[3,4]``) or not at all (the braid index of every knot with 13
crossings). Such values are represented as ``None`` in :attr:`Knot.bridge_number` /
:attr:`Knot.braid_index`, never guessed; the interval, or the rigorous bounds, are in
:attr:`Knot.bridge_number_range` / :attr:`Knot.braid_index_range`, and the KnotInfo text is kept
in :attr:`Knot.raw`.

Knots are identified up to mirror image (KnotInfo lists one chirality per knot type; the
bending energy does not depend on chirality).
"""

from __future__ import annotations

import difflib
import functools
import math
import re
from dataclasses import dataclass, field, replace
from typing import Any

from stiffknots.errors import UnknownKnotError

__all__ = [
    "Knot",
    "UnknownKnotError",
    "catalogue",
    "get_knot",
    "knot_names",
    "n_equals_i_knots",
    "n_equals_i_statistics",
    "MAX_CROSSINGS",
]

#: Largest crossing number tabulated by KnotInfo.
MAX_CROSSINGS = 13

#: KnotInfo fields parsed into :class:`Knot` (their raw text is kept in ``Knot.raw``).
_FIELDS = (
    "name",
    "dt_name",
    "crossing_number",
    "bridge_index",
    "braid_index",
    "braid_notation",
    "pd_notation",
    "alternating",
    "alexander_polynomial",
    "jones_polynomial",
    "conway_notation",
    # read by stiffknots.knots.exterior (naming, chirality): kept as KnotInfo text in Knot.raw
    "volume",
    "ozsvath_szabo_tau_invariant",
    "symmetry_type",
)

#: Friendly names (keys: lower case, without spaces, '-' or '_').
_ALIASES = {
    "unknot": "0_1",
    "trivial": "0_1",
    "trivialknot": "0_1",
    "circle": "0_1",
    "trefoil": "3_1",
    "trefoilknot": "3_1",
    "figureeight": "4_1",
    "figure8": "4_1",
    "figureeightknot": "4_1",
    "figure8knot": "4_1",
    "listingsknot": "4_1",
    "cinquefoil": "5_1",
    "solomonsseal": "5_1",
    "pentafoil": "5_1",
    "threetwist": "5_2",
    "threetwistknot": "5_2",
    "stevedore": "6_1",
    "stevedoreknot": "6_1",
}


@dataclass(frozen=True)
class Knot:
    """A prime knot type (or the unknot) with its KnotInfo invariants.

    Attributes
    ----------
    name : str
        Canonical KnotInfo name: Rolfsen names up to 10 crossings (``'3_1'``, ``'10_124'``),
        Dowker-Thistlethwaite names from 11 crossings (``'11a_1'``, ``'13n_5110'``); ``'0_1'``
        is the unknot.
    crossing_number : int
        Minimal number of crossings of a planar projection, :math:`n_c` (§VI C).
    bridge_number : int or None
        Bridge number :math:`n`: the minimal number of maxima of a height function over all
        configurations of the knot (§IV). Milnor's bound :math:`2\\pi n \\le \\bar\\kappa`
        (eq. ``eq. (9)``) gives :math:`\\epsilon^* \\ge 2\\pi^2 n^2`. ``None`` when KnotInfo
        only gives an interval (see :attr:`bridge_number_range`).
    braid_index : int or None
        Braid index :math:`i`: the minimal number of strings of a closed braid representing the
        knot (§VI A), :math:`i \\ge n`; the circular braid gives
        :math:`\\epsilon^* \\le 2\\pi^2 i^2`. ``None`` where KnotInfo does not give it (every knot
        with 13 crossings); see :attr:`braid_index_range` for rigorous bounds.
    braid_word : tuple of int or None
        A braid word from KnotInfo: generator :math:`\\sigma_k^{\\pm 1}` is written ``±k``, the
        sign being the crossing sign as in KnotInfo. When KnotInfo gives several words, the one
        on :attr:`braid_index` strings (else the one on fewest strings) is kept. The closure of
        the word is the knot; its number of strings is :attr:`braid_strands`.
    pd_code : tuple of tuple of int or None
        Planar-diagram code (4-tuples of int) of a minimal diagram (KnotInfo has none for 13
        crossings).
    torus : tuple of int or None
        ``(p, q)`` for a torus knot :math:`T(p, q)`, with :math:`2 \\le p < q`; ``None`` otherwise.
        Torus knots belong to the :math:`n = i` family (§VI C), with :math:`n = i = p`.
    alternating : bool or None
        Whether the knot is alternating.
    dt_name : str or None
        Dowker-Thistlethwaite name in the ``'K11a1'`` style (``'K3a1'`` for 3_1); ``None`` for
        the unknot.
    alexander_polynomial, jones_polynomial : str or None
        The polynomials as KnotInfo writes them (in the variable ``t``).
    bridge_number_range : tuple of int or None
        ``(lo, hi)``, bounds on the bridge number: ``(n, n)`` when known, the KnotInfo interval
        otherwise.
    braid_index_range : tuple of int or None
        ``(lo, hi)``, bounds on the braid index: ``(i, i)`` when KnotInfo gives it; otherwise the
        rigorous bounds ``lo`` = lower bound of the bridge number (since :math:`i \\ge n`) and
        ``hi`` = number of strings of the KnotInfo braid word. When ``lo == hi`` the braid index is
        in fact determined, but :attr:`braid_index` stays ``None`` (it reports KnotInfo's value).
    conway_notation : str or None
        KnotInfo's Conway notation (e.g. ``'[32]'`` for 5_2); two-box rational knots ``[ab]``
        are the paper's conjectured 4-fold-cage family (see :mod:`stiffknots.knots.cage_embedding`).
    raw : dict
        KnotInfo text of the parsed fields (not compared, not shown in ``repr``).
    """

    name: str
    crossing_number: int
    bridge_number: int | None
    braid_index: int | None
    braid_word: tuple[int, ...] | None = None
    pd_code: tuple[tuple[int, int, int, int], ...] | None = None
    torus: tuple[int, int] | None = None
    alternating: bool | None = None
    dt_name: str | None = None
    alexander_polynomial: str | None = None
    jones_polynomial: str | None = None
    bridge_number_range: tuple[int, int] | None = None
    braid_index_range: tuple[int, int] | None = None
    conway_notation: str | None = None
    raw: dict[str, str] = field(default_factory=dict, compare=False, repr=False)

    @property
    def torus_notation(self) -> str | None:
        """``'T(p,q)'`` for a torus knot, else ``None``."""
        if self.torus is None:
            return None
        return f"T({self.torus[0]},{self.torus[1]})"

    @property
    def is_unknot(self) -> bool:
        """Whether this is the unknot ``0_1``."""
        return self.crossing_number == 0

    @property
    def n_equals_i(self) -> bool | None:
        """Whether the bridge number equals the braid index (the family of §VI C).

        For these knots the bounds of eq. ``eq. (32)`` coincide and the ground state is
        the circular line-braid of multiplicity :math:`i`, :math:`\\epsilon^* = 2\\pi^2 i^2`.
        ``None`` when either invariant is unknown.
        """
        if self.bridge_number is None or self.braid_index is None:
            return None
        return self.bridge_number == self.braid_index

    @property
    def braid_strands(self) -> int | None:
        """Number of strings of :attr:`braid_word` (``None`` without a braid word)."""
        if self.braid_word is None:
            return None
        return _strands(self.braid_word)

    def __str__(self) -> str:
        return self.name


# ----------------------------------------------------------------------------------------
# parsing KnotInfo text
# ----------------------------------------------------------------------------------------


def _text(row: dict[str, Any], key: str) -> str:
    value = row.get(key)
    if value is None:
        return ""
    return str(value).strip()


def _parse_int_or_range(text: str) -> tuple[int | None, tuple[int, int] | None]:
    """Parse ``'3'`` -> (3, (3, 3)), ``'[3,4]'`` -> (None, (3, 4)), other -> (None, None)."""
    t = text.replace(" ", "")
    if re.fullmatch(r"-?\d+", t):
        v = int(t)
        return v, (v, v)
    m = re.fullmatch(r"[\[\(\{](-?\d+)[,;](-?\d+)[\]\)\}]", t)
    if m:
        lo, hi = sorted((int(m.group(1)), int(m.group(2))))
        if lo == hi:
            return lo, (lo, lo)
        return None, (lo, hi)
    return None, None


def _strands(word: tuple[int, ...]) -> int:
    return max((abs(g) for g in word), default=0) + 1


def _parse_braid_words(text: str) -> list[tuple[int, ...]]:
    """All braid words in a KnotInfo braid notation (``'[1,-2]'`` or ``'[[..],[..]]'``)."""
    t = text.replace(" ", "")
    words = []
    for inner in re.findall(r"\[([-\d,]*)\]", t):
        items = [s for s in inner.split(",") if s]
        if items and all(re.fullmatch(r"-?\d+", s) for s in items):
            word = tuple(int(s) for s in items)
            if all(g != 0 for g in word):
                words.append(word)
    return words


def _choose_braid_word(words: list[tuple[int, ...]], braid_index: int | None):
    if not words:
        return None
    if braid_index is not None:
        for w in words:
            if _strands(w) == braid_index:
                return w
    return min(words, key=_strands)


def _parse_pd(text: str) -> tuple[tuple[int, int, int, int], ...] | None:
    quads = re.findall(r"\[\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*\]", text)
    if not quads:
        return None
    return tuple(tuple(int(x) for x in q) for q in quads)  # type: ignore[misc]


def _parse_bool(text: str) -> bool | None:
    t = text.strip().lower()
    if t in ("y", "yes", "true", "1"):
        return True
    if t in ("n", "no", "false", "0"):
        return False
    return None


def _dt_style(dt: str) -> str | None:
    """KnotInfo DT name ``'11a_1'`` -> ``'K11a1'``; ``None`` if not of that form."""
    m = re.fullmatch(r"(\d+)([an])_?(\d+)", dt.replace(" ", ""))
    if not m:
        return None
    return f"K{int(m.group(1))}{m.group(2)}{int(m.group(3))}"


_TERM = re.compile(r"([+-]?)(\d*)(\*?t|/t)?(?:\^\(?(-?\d+)\)?)?")


def _parse_laurent(text: str) -> dict[int, int] | None:
    """Parse a KnotInfo Laurent polynomial in ``t`` into ``{exponent: coefficient}``.

    Handles the formats found in KnotInfo: ``'t^(-2)-t^(-1)+ 1-t+ t^2'``, ``'2*t^3'``,
    ``'3/t^2'``, ``'-3 + t^(-1) + 7*t'``. Returns ``None`` if the text is not understood.
    """
    t = text.replace(" ", "")
    if not t:
        return None
    poly: dict[int, int] = {}
    for term in re.split(r"(?<![(^])(?=[+-])", t):
        if not term:
            continue
        m = _TERM.fullmatch(term)
        if m is None:
            return None
        sign, coef, var, exp = m.groups()
        if not coef and not var:
            return None
        if var is None and exp is not None:
            return None
        c = int(coef) if coef else 1
        if sign == "-":
            c = -c
        if var is None:
            e = 0
        else:
            e = int(exp) if exp is not None else 1
            if var == "/t":
                e = -e
        poly[e] = poly.get(e, 0) + c
    return {e: c for e, c in poly.items() if c != 0}


def _torus_jones(p: int, q: int) -> dict[int, int]:
    """Jones polynomial of the torus knot T(p, q), as ``{exponent: coefficient}``.

    V(t) = t^((p-1)(q-1)/2) (1 - t^(p+1) - t^(q+1) + t^(p+q)) / (1 - t^2)  (Jones 1987).
    """
    num = [0] * (p + q + 1)
    num[0] += 1
    num[p + 1] -= 1
    num[q + 1] -= 1
    num[p + q] += 1
    quo = [0] * (p + q + 1)
    for k in range(p + q + 1):  # divide by (1 - t^2): b_k = a_k + b_{k-2}
        quo[k] = num[k] + (quo[k - 2] if k >= 2 else 0)
    assert all(c == 0 for c in quo[p + q - 1 :]), "remainder must vanish"
    shift = (p - 1) * (q - 1) // 2
    return {k + shift: c for k, c in enumerate(quo) if c != 0}


def _torus_pairs(max_crossings: int = MAX_CROSSINGS) -> list[tuple[int, int]]:
    """All (p, q), 2 <= p < q, gcd 1, with crossing number q (p - 1) <= max_crossings."""
    out = []
    for p in range(2, max_crossings + 2):
        for q in range(p + 1, max_crossings + 2):
            if math.gcd(p, q) == 1 and q * (p - 1) <= max_crossings:
                out.append((p, q))
    return out


def _torus_crossing_number(p: int, q: int) -> int:
    p, q = sorted((abs(p), abs(q)))
    return q * (p - 1)


# ----------------------------------------------------------------------------------------
# the cached database
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Tables:
    knots: tuple[Knot, ...]
    by_name: dict[str, Knot]  # canonical name (lower case) -> knot
    by_dt: dict[str, Knot]  # KnotInfo DT name '4a_1' / '11a_1' (lower case) -> knot
    by_torus: dict[tuple[int, int], Knot]  # (p, q), p < q -> knot


def _knot_from_row(row: dict[str, Any]) -> Knot | None:
    raw = {k: _text(row, k) for k in _FIELDS}
    name = raw["name"]
    cn = raw["crossing_number"]
    if not name or not re.fullmatch(r"\d+", cn):
        return None
    bridge, bridge_range = _parse_int_or_range(raw["bridge_index"])
    braid, braid_range = _parse_int_or_range(raw["braid_index"])
    word = _choose_braid_word(_parse_braid_words(raw["braid_notation"]), braid)
    if braid_range is None and word is not None and bridge_range is not None:
        # rigorous bounds: i >= n (>= lower bridge bound); i <= strings of any braid word
        braid_range = (bridge_range[0], _strands(word))
    dt = _dt_style(raw["dt_name"]) if raw["dt_name"] else None
    return Knot(
        name=name,
        crossing_number=int(cn),
        bridge_number=bridge,
        braid_index=braid,
        braid_word=word,
        pd_code=_parse_pd(raw["pd_notation"]),
        torus=None,
        alternating=_parse_bool(raw["alternating"]),
        dt_name=dt,
        alexander_polynomial=raw["alexander_polynomial"] or None,
        jones_polynomial=raw["jones_polynomial"] or None,
        bridge_number_range=bridge_range,
        braid_index_range=braid_range,
        conway_notation=raw["conway_notation"] or None,
        raw=raw,
    )


@functools.lru_cache(maxsize=1)
def _tables() -> _Tables:
    """Load and parse KnotInfo once per process, and once per installation on disk
    (:mod:`stiffknots._diskcache`, keyed by this module's source and the KnotInfo version)."""
    import database_knotinfo

    from stiffknots._diskcache import cached, source_key

    key = source_key(database_knotinfo.version(), str(MAX_CROSSINGS), files=(__file__,))
    return cached("knotinfo", key, _parse_tables)


def _parse_tables() -> _Tables:
    from database_knotinfo import link_list

    rows = link_list()
    knots: list[Knot] = []
    for row in rows:
        if _text(row, "name") == "Name" or not re.fullmatch(r"\d+", _text(row, "crossing_number")):
            continue  # the header row of human-readable column names
        k = _knot_from_row(row)
        if k is not None and k.crossing_number <= MAX_CROSSINGS:
            knots.append(k)

    # Torus knots: KnotInfo has no torus-notation field, so T(p, q) is identified as the knot
    # with crossing number q(p-1), bridge number p, and the Jones polynomial of T(p, q) (or of
    # its mirror image).
    by_torus: dict[tuple[int, int], Knot] = {}
    for p, q in _torus_pairs(MAX_CROSSINGS):
        cn = q * (p - 1)
        target = _torus_jones(p, q)
        mirror = {-e: c for e, c in target.items()}
        hits = []
        for idx, k in enumerate(knots):
            if k.crossing_number != cn or k.bridge_number_range is None:
                continue
            if k.bridge_number_range[0] > p or k.bridge_number_range[1] < p:
                continue
            poly = _parse_laurent(k.jones_polynomial or "")
            if poly is not None and (poly == target or poly == mirror):
                hits.append(idx)
        if len(hits) == 1:
            idx = hits[0]
            k = knots[idx]
            knots[idx] = replace(k, torus=(p, q))
            by_torus[(p, q)] = knots[idx]

    by_name = {k.name.lower(): k for k in knots}
    by_dt = {
        k.raw["dt_name"].lower(): k for k in knots if k.raw.get("dt_name") and k.crossing_number
    }
    return _Tables(tuple(knots), by_name, by_dt, by_torus)


# ----------------------------------------------------------------------------------------
# public API
# ----------------------------------------------------------------------------------------


def _check_max(max_crossings: int, name: str = "max_crossings") -> int:
    if isinstance(max_crossings, bool) or not isinstance(max_crossings, int):
        raise TypeError(f"{name} must be an integer, got {max_crossings!r}")
    if max_crossings < 0:
        raise ValueError(f"{name} must be >= 0, got {max_crossings}")
    if max_crossings > MAX_CROSSINGS:
        raise ValueError(
            f"{name}={max_crossings}: KnotInfo tabulates prime knots up to "
            f"{MAX_CROSSINGS} crossings only; use max_crossings <= {MAX_CROSSINGS}"
        )
    return max_crossings


@functools.lru_cache(maxsize=MAX_CROSSINGS + 2)
def catalogue(max_crossings: int = MAX_CROSSINGS) -> tuple[Knot, ...]:
    """The unknot and every prime knot with crossing number <= ``max_crossings``.

    Parameters
    ----------
    max_crossings : int, default 13
        Largest crossing number (KnotInfo goes to 13; larger values raise ``ValueError``).

    Returns
    -------
    tuple of Knot
        In KnotInfo order: ``0_1, 3_1, 4_1, ..., 10_165, 11a_1, ..., 11n_185, 12a_1, ...``.
        Up to 13 crossings: 1 + 12,965 knots. Knots are counted up to mirror image.

    Notes
    -----
    The KnotInfo database is parsed once per process (about a second) and cached.
    """
    _check_max(max_crossings)
    return tuple(k for k in _tables().knots if k.crossing_number <= max_crossings)


def knot_names(max_crossings: int = MAX_CROSSINGS) -> tuple[str, ...]:
    """Canonical names of :func:`catalogue` (``max_crossings``), in the same order."""
    return tuple(k.name for k in catalogue(max_crossings))


def _describe_crossings(c: int) -> str:
    """A phrase naming the knots with ``c`` crossings."""
    if c == 0:
        return "the only knot with 0 crossings is the unknot 0_1"
    if c in (1, 2):
        return "no knot has 1 or 2 crossings (every non-trivial knot has at least 3)"
    if c > MAX_CROSSINGS:
        return f"KnotInfo tabulates prime knots up to {MAX_CROSSINGS} crossings only"
    names = [k.name for k in _tables().knots if k.crossing_number == c]
    if len(names) <= 3:
        return f"knots with {c} crossings are {', '.join(names)}"
    if c <= 10:
        return f"there are {len(names)} knots with {c} crossings: {names[0]} ... {names[-1]}"
    parts = []
    for kind in ("a", "n"):
        sub = [n for n in names if n.startswith(f"{c}{kind}_")]
        if sub:
            parts.append(f"{sub[0]} ... {sub[-1]}")
    return (
        f"there are {len(names)} knots with {c} crossings, named {c}a_N (alternating) or "
        f"{c}n_N (non-alternating): {', '.join(parts)}"
    )


def _suggest(query: str) -> list[str]:
    """Up to five valid names close to ``query``: knots with the same crossing number first,
    then the swapped name (``'4_9'`` -> ``'9_4'``), then the closest names by
    :func:`difflib.get_close_matches` over the canonical names and aliases."""
    t = _tables()
    out: list[str] = []
    m = re.match(r"(\d+)([an]?)_(\d+)$", query)
    if m:
        c = int(m.group(1))
        same = [k.name for k in t.knots if k.crossing_number == c]
        out += difflib.get_close_matches(query, same, n=2, cutoff=0.0)
        swapped = f"{int(m.group(3))}_{c}"
        if swapped in t.by_name:
            out.append(swapped)
    pool = [k.name for k in t.knots] + sorted(set(_ALIASES))
    out += difflib.get_close_matches(query, pool, n=5, cutoff=0.5)
    return list(dict.fromkeys(out))[:5]


def _unknown(original: str, query: str, reason: str) -> UnknownKnotError:
    msg = f"unknown knot {original!r}: {reason}"
    close = _suggest(query)
    if close:
        msg += f"; closest names: {', '.join(close)}"
    return UnknownKnotError(msg)


def _torus_lookup(original: str, p: int, q: int) -> Knot:
    t = _tables()
    if p == 0 or q == 0:
        raise UnknownKnotError(
            f"unknown knot {original!r}: T(p,q) needs non-zero p and q "
            "(T(p,q) winds p times around one axis of the torus and q times around the other)"
        )
    g = math.gcd(p, q)
    if g != 1:
        raise UnknownKnotError(
            f"{original!r} is not a knot: T({p},{q}) has gcd(p,q) = {g}, so it is a link of "
            f"{g} components; a torus knot needs coprime p and q, e.g. T(2,3), T(2,5), T(3,4)"
        )
    a, b = sorted((abs(p), abs(q)))
    if a == 1:
        return t.by_name["0_1"]  # T(1, q) is the unknot
    cn = _torus_crossing_number(a, b)
    if cn > MAX_CROSSINGS:
        raise UnknownKnotError(
            f"{original!r} is the torus knot T({a},{b}) with crossing number "
            f"{cn} = min(p(q-1), q(p-1)) > {MAX_CROSSINGS}: beyond the KnotInfo tables; "
            f"torus knots in the tables: " + ", ".join(f"T({x},{y})" for x, y in sorted(t.by_torus))
        )
    knot = t.by_torus.get((a, b))
    if knot is None:  # pragma: no cover - every T(p,q) up to 13 crossings is identified
        raise UnknownKnotError(f"{original!r}: torus knot T({a},{b}) not found in KnotInfo")
    return knot


#: the mirror-image spellings of other tools: KnotInfo's and SnapPy's ``m`` prefix (``m3_1``),
#: the star and the bang of knot tables and KnotPlot (``3_1*``, ``3_1!``), an ``m`` suffix
#: (``3_1m``), ``mirror(3_1)``
_MIRROR = (re.compile(r"mirror[(\[]?(.+?)[)\]]?"), re.compile(r"m[_\-]?([\dkt].*)"),
           re.compile(r"(.+?)(?:\*|!)"), re.compile(r"(.+?\d)[_\-]?m"))


def _mirror_base(key: str) -> str | None:
    """The name inside a mirror spelling (:data:`_MIRROR`) of ``key`` (lower case, no
    white space); None if ``key`` is not one."""
    for pattern in _MIRROR:
        m = pattern.fullmatch(key)
        if m and m.group(1):
            return m.group(1)
    return None


def mirror_of(name: str) -> str | None:
    """The knot's canonical name if ``name`` spells a mirror image (``'m3_1'``, ``'3_1*'``,
    ``'3_1m'``), else None. A knot and its mirror image are one entry of the catalogue:
    KnotInfo lists one chirality per knot type and the bending energy, its bounds and its
    ground states do not depend on chirality (a mirror maps a chain to one of the same ε).

    Raises
    ------
    UnknownKnotError
        If the name inside the mirror spelling is not a knot.
    """
    if not isinstance(name, str):
        return None
    base = _mirror_base(re.sub(r"\s+", "", name).lower())
    return None if base is None else get_knot(base).name


def mirror_note(name: str) -> str | None:
    """One line saying that ``name`` is read as its mirror image's knot (None if it is no
    mirror spelling)."""
    base = mirror_of(name)
    if base is None:
        return None
    return (f"{name.strip()} is the mirror image of {base}: the same knot here (ε, its bounds "
            "and ground states do not depend on the mirror)")


def get_knot(name: str) -> Knot:
    """Look up a knot by name.

    Parameters
    ----------
    name : str
        Accepted spellings (case and whitespace are ignored):

        * canonical KnotInfo names: ``'4_1'``, ``'10_124'``, ``'11a_1'``, ``'13n_5110'``;
        * other separators: ``'4.1'``, ``'4-1'``, ``'11a1'``; digits only when unambiguous
          (``'41'`` is 4_1);
        * Dowker-Thistlethwaite names: ``'K11a1'``, ``'K4a1'``, ``'4a_1'`` (DT name of 4_1);
        * torus notation: ``'T(2,3)'``, ``'T(3,2)'``, ``'T2,3'``, ``'T(2,-3)'`` (mirror image,
          the same knot type here) — the prime knot that is that torus knot, e.g. T(3,4) is
          8_19; T(1,q) is the unknot;
        * aliases: ``'unknot'``, ``'trefoil'``, ``'figure-eight'``, ``'figure8'``,
          ``'cinquefoil'``, ``'three-twist'``, ``'stevedore'``;
        * any of these as a mirror image (:func:`mirror_of`): ``'m3_1'``, ``'3_1*'``,
          ``'3_1m'``, ``'3_1!'``, ``'mirror(3_1)'`` — the same knot here.

    Returns
    -------
    Knot

    Raises
    ------
    UnknownKnotError
        If the name is not a knot of the catalogue; the message says why and lists up to five
        closest valid names. A torus notation with gcd(p, q) != 1 (a link) or crossing number
        above 13 gets a specific message.
    """
    if not isinstance(name, str):
        raise TypeError(f"knot name must be a string, got {type(name).__name__}")
    t = _tables()
    key = re.sub(r"\s+", "", name).lower()
    if not key:
        raise UnknownKnotError("empty knot name; examples: 3_1, 4_1, 11a_1, T(2,5), trefoil")

    base = _mirror_base(key)
    if base is not None:
        try:
            return get_knot(base)
        except UnknownKnotError as exc:
            raise UnknownKnotError(f"{exc} (read {name!r} as the mirror image of {base!r})"
                                   ) from None

    alias = re.sub(r"[\s_\-'’.]", "", key)
    if alias in _ALIASES:
        return t.by_name[_ALIASES[alias]]

    m = re.fullmatch(r"t_?[(\[{]?(-?\d+)[,;](-?\d+)[)\]}]?", key)
    if m:
        return _torus_lookup(name, int(m.group(1)), int(m.group(2)))

    m = re.fullmatch(r"k?(\d+)([an])[_.\-]?(\d+)", key)
    if m:
        c, kind, idx = int(m.group(1)), m.group(2), int(m.group(3))
        dt = f"{c}{kind}_{idx}"
        if dt in t.by_dt:
            return t.by_dt[dt]
        if 3 <= c <= 10:
            reason = f"no DT name {dt}; {_describe_crossings(c)}"
        else:
            reason = _describe_crossings(c)
        raise _unknown(name, dt, reason)

    m = re.fullmatch(r"(\d+)[_.\-](\d+)", key)
    if m:
        c, idx = int(m.group(1)), int(m.group(2))
        canon = f"{c}_{idx}"
        if canon in t.by_name:
            return t.by_name[canon]
        if 11 <= c <= MAX_CROSSINGS:
            reason = (
                f"knots with 11 or more crossings have Dowker-Thistlethwaite names; "
                f"{_describe_crossings(c)}"
            )
        else:
            reason = _describe_crossings(c)
        raise _unknown(name, canon, reason)

    m = re.fullmatch(r"\d+", key)
    if m:
        found = {
            t.by_name[f"{int(key[:s])}_{int(key[s:])}"].name
            for s in range(1, len(key))
            if f"{int(key[:s])}_{int(key[s:])}" in t.by_name
        }
        if len(found) == 1:
            return t.by_name[found.pop()]
        reason = (
            f"ambiguous, could be {' or '.join(sorted(found))}"
            if found
            else "not a knot name (write crossing number and index as in 5_2)"
        )
        raise _unknown(name, key, reason)

    raise _unknown(
        name,
        key.replace(".", "_").replace("-", "_"),
        "not a knot name (examples: 3_1, 4_1, 10_124, 11a_1, K11n34, T(2,5), trefoil)",
    )


def _stats_row(knots: list[Knot]) -> dict[str, Any]:
    unknown = sum(1 for k in knots if k.n_equals_i is None)
    equal = sum(1 for k in knots if k.n_equals_i)
    known = len(knots) - unknown
    return {
        "knots": len(knots),
        "n_equals_i": equal,
        "unknown": unknown,
        "known": known,
        "fraction": equal / known if known else None,
    }


def n_equals_i_statistics(max_crossings: int = 10, min_crossings: int = 3) -> dict[str, Any]:
    """Statistics of the :math:`n = i` knot family (§VI C) by crossing number.

    The paper analyses the prime knots with :math:`n_c < 11` and finds that
    :math:`\\approx 20\\%` of them have bridge number equal to braid index. With the KnotInfo
    values, for :math:`3 \\le n_c \\le 10` the family holds 46 of 249 knots (18.5 %).

    Parameters
    ----------
    max_crossings : int, default 10
        Largest crossing number included (at most 13; at 13 KnotInfo has no braid index, so
        every knot counts as unknown).
    min_crossings : int, default 3
        Smallest crossing number included. The default excludes the unknot (which is not
        prime and trivially has n = i = 1); ``min_crossings=0`` includes it.

    Returns
    -------
    dict
        ``{'min_crossings', 'max_crossings', 'includes_unknot', 'by_crossing', 'total'}``,
        where ``by_crossing`` maps each crossing number that has knots to a row and ``total``
        is the row for all of them. A row is ``{'knots': count, 'n_equals_i': count with
        n = i, 'unknown': count with n or i unknown, 'known': knots - unknown, 'fraction':
        n_equals_i / known}`` (``fraction`` is ``None`` when nothing is known).
    """
    _check_max(max_crossings)
    if isinstance(min_crossings, bool) or not isinstance(min_crossings, int) or min_crossings < 0:
        raise ValueError(f"min_crossings must be an integer >= 0, got {min_crossings!r}")
    knots = [k for k in catalogue(max_crossings) if k.crossing_number >= min_crossings]
    by_c: dict[int, list[Knot]] = {}
    for k in knots:
        by_c.setdefault(k.crossing_number, []).append(k)
    return {
        "min_crossings": min_crossings,
        "max_crossings": max_crossings,
        "includes_unknot": min_crossings == 0,
        "by_crossing": {c: _stats_row(ks) for c, ks in sorted(by_c.items())},
        "total": _stats_row(knots),
    }


def n_equals_i_knots(max_crossings: int = 10, min_crossings: int = 3) -> list[Knot]:
    """The knots of the :math:`n = i` family (§VI C) with crossing numbers in range.

    For these the ground state of the stiff knot is the circular line-braid of multiplicity
    :math:`i`, with :math:`\\epsilon^* = 2\\pi^2 i^2` (eq. ``eq. (32)`` becomes an
    equality). Knots with unknown n or i are left out. The unknot is included only with
    ``min_crossings=0``.
    """
    _check_max(max_crossings)
    return [
        k for k in catalogue(max_crossings) if k.crossing_number >= min_crossings and k.n_equals_i
    ]
