"""The start table: every catalogue knot's starting chains built and their knot type verified.

Per knot and start family (:data:`FAMILIES`): the braid closure of KnotInfo's braid word
(every knot), the 4-fold cage (two-box rational knots, KnotInfo Conway notation ``[a b]``)
and the 80 (the two-bridge knots of the 80 family's specs,
:func:`stiffknots.knots.eighty_embedding.eighty_specs`, searched up to the knot's own
crossing number). Each chain is built at ``n_beads`` beads of unit bond and named by
:func:`stiffknots.knots.identify.identify_details` — the HOMFLY-PT polynomial, then the
invariants that break its ties through 12 crossings — which must give the knot's own name
(mirror-insensitive). A row is

* ``verified``: built, and named as the knot;
* ``tie``: built, and the knot is among the names its invariants leave (never seen through 12
  crossings; kept apart from ``verified`` so that it is never counted as one);
* ``absent``: the family has no member of this knot (or none that fits in ``n_beads``); the
  reason says which;
* ``failed``: a chain was built and is another knot, or the build raised — a defect, listed
  with the reason.

Rows are computed in chunks of :data:`CHUNK` knots of one crossing number and kept in the
disk cache (``stiffknots._diskcache``) under the package version and the sources they
depend on: the table is built once per installation, a run stopped half-way keeps its
finished chunks, and an edited embedding or identification builds it anew.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path

__all__ = ["CHUNK", "FAMILIES", "StartCheck", "check_start", "start_table", "summarise"]

#: The start families checked, in this order.
FAMILIES = ("braid", "cage", "eighty")
#: Knots per cached chunk (of one crossing number, in catalogue order).
CHUNK = 50
#: The 80 specs are searched up to this diagram size at least (``find_eighty``'s default).
_EIGHTY_MIN_DIAGRAM = 10

_SOURCES = ("embedding.py", "cage_embedding.py", "eighty_embedding.py", "identify.py",
            "catalogue.py", "topoly_core.py", "exterior.py", "start_table.py")


@dataclass(frozen=True)
class StartCheck:
    """One knot's start of one family, built and named.

    Attributes
    ----------
    knot : str
        Catalogue name.
    crossings : int
        Its crossing number.
    family : str
        One of :data:`FAMILIES`.
    status : str
        ``'verified'``, ``'tie'``, ``'absent'`` or ``'failed'`` (module docstring).
    reason : str
        Why absent or failed; the deciding invariants when built.
    found : str or None
        The name the chain was given (or the '|'-joined candidates of a tie); None when no
        chain was built.
    seconds : float
        Wall seconds to build and name the chain.
    segment_distance : float or None
        Smallest distance between two segments sharing no bead (bond units): the chain is
        admissible for the tube model of diameter w when it is ≥ w (1/√2 by default). None
        when no chain was built.
    """

    knot: str
    crossings: int
    family: str
    status: str
    reason: str
    found: str | None
    seconds: float
    segment_distance: float | None = None

    def as_dict(self) -> dict:
        return asdict(self)


def _build(knot, family: str, n_beads: int):
    """The chain of ``family`` for ``knot``, not yet named; raises EmbeddingError when the
    family has no member of the knot or its chain does not fit in ``n_beads`` beads."""
    if family == "braid":
        from stiffknots.knots.embedding import embed_braid

        word = knot.braid_word or ()
        return embed_braid(word, n_strands=knot.braid_strands if word else None,
                           n_beads=n_beads)
    if family == "cage":  # the chain itself: embed_cage would verify it by HOMFLY-PT only
        from stiffknots.knots.cage_embedding import cage_chain, cage_spec_for

        return cage_chain(cage_spec_for(knot), n_beads)
    from stiffknots.knots.eighty_embedding import find_eighty

    # the spec search keeps the first spec whose chain is the knot (HOMFLY-PT); named below
    return find_eighty(knot, n_beads, max(_EIGHTY_MIN_DIAGRAM, knot.crossing_number))[1]


def check_start(knot, family: str, n_beads: int = 150) -> StartCheck:
    """Build ``knot``'s start of ``family`` at ``n_beads`` beads and name it.

    Parameters
    ----------
    knot : Knot or str
        A catalogue entry or name.
    family : str
        One of :data:`FAMILIES`.
    n_beads : int
        Number of beads N.

    Raises
    ------
    ValueError
        For an unknown family.
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import EmbeddingError, embedding_report
    from stiffknots.knots.identify import identify_details, normalize_name

    if family not in FAMILIES:
        raise ValueError(f"unknown start family {family!r}; choose from {', '.join(FAMILIES)}")
    if isinstance(knot, str):
        knot = get_knot(knot)
    t0 = time.perf_counter()

    seg = None

    def row(status: str, reason: str, found: str | None = None) -> StartCheck:
        return StartCheck(knot.name, knot.crossing_number, family, status, reason, found,
                          time.perf_counter() - t0, seg)

    try:
        x = _build(knot, family, int(n_beads))
    except EmbeddingError as e:
        # every knot has a braid word: a braid start that cannot be built is a failure
        return row("failed" if family == "braid" else "absent", str(e))
    except Exception as e:  # noqa: BLE001 — a defect of a builder: listed, not hidden
        return row("failed", f"{type(e).__name__}: {e}")
    seg = float(embedding_report(x).min_segment_distance)
    d = identify_details(x)
    want = normalize_name(knot.name)
    by = ", ".join(d.decided_by) or "HOMFLY-PT"
    if d.name is not None:
        if normalize_name(d.name) == want:
            return row("verified", f"named by {by}", d.name)
        return row("failed", f"the chain is {d.name}, not {knot.name}", d.name)
    cands = "|".join(d.candidates) or d.homfly
    if want in d.candidates:
        return row("tie", f"{knot.name} among {cands} (decided by {by})", cands)
    return row("failed", f"the chain is {cands}, not {knot.name}", cands)


def _chunk_rows(names: tuple[str, ...], families: tuple[str, ...], n_beads: int) -> list[dict]:
    return [check_start(n, f, n_beads).as_dict() for n in names for f in families]


def _cached_chunk(names: tuple[str, ...], families: tuple[str, ...], n_beads: int) -> list[dict]:
    from stiffknots._diskcache import cached, source_key

    here = Path(__file__).resolve().parent
    key = source_key("start-table", ",".join(names), ",".join(families), str(n_beads),
                     files=tuple(str(here / f) for f in _SOURCES))
    return cached("start-table", key, lambda: _chunk_rows(names, families, n_beads))


def _chunks(knots: Sequence, chunk: int) -> list[tuple[str, ...]]:
    by_c: dict[int, list[str]] = {}
    for k in knots:
        by_c.setdefault(k.crossing_number, []).append(k.name)
    return [tuple(names[i:i + chunk]) for c in sorted(by_c)
            for names in [by_c[c]] for i in range(0, len(names), chunk)]


def start_table(max_crossings: int = 12, *, crossings: Iterable[int] | None = None,
                knots: Iterable[str] | None = None, families: Sequence[str] = FAMILIES,
                n_beads: int = 150, workers: int = 1,
                progress: Callable[[int, int, str], None] | None = None) -> list[StartCheck]:
    """The start table of the prime knots through ``max_crossings`` crossings.

    Parameters
    ----------
    max_crossings : int
        Largest crossing number (3..13; KnotInfo's tables).
    crossings : iterable of int, optional
        Only these crossing numbers.
    knots : iterable of str, optional
        Only these knots (catalogue names), instead of the crossing numbers.
    families : sequence of str
        Start families, a subset of :data:`FAMILIES`.
    n_beads : int
        Number of beads N of every chain.
    workers : int
        Processes building chunks side by side (1: in this process).
    progress : callable, optional
        Called as ``progress(done_chunks, total_chunks, last_chunk_label)``.

    Returns
    -------
    list of StartCheck
        In catalogue order, each knot's families in the order given.
    """
    from stiffknots.knots.catalogue import catalogue, get_knot

    fams = tuple(families)
    bad = [f for f in fams if f not in FAMILIES]
    if bad or not fams:
        raise ValueError(f"start families {bad or fams!r}: choose from {', '.join(FAMILIES)}")
    if knots is not None:
        ks = [get_knot(n) for n in knots]
    else:
        want = None if crossings is None else {int(c) for c in crossings}
        ks = [k for k in catalogue(max_crossings)
              if k.crossing_number >= 3 and (want is None or k.crossing_number in want)]
    chunks = _chunks(ks, CHUNK)
    results: dict[tuple[str, ...], list[dict]] = {}

    def label(ch):
        return ch[0] if len(ch) == 1 else f"{ch[0]} … {ch[-1]}"

    if workers <= 1 or len(chunks) <= 1:
        for i, ch in enumerate(chunks):
            results[ch] = _cached_chunk(ch, fams, int(n_beads))
            if progress:
                progress(i + 1, len(chunks), label(ch))
    else:
        import multiprocessing as mp

        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as ex:
            futs = {ex.submit(_cached_chunk, ch, fams, int(n_beads)): ch for ch in chunks}
            for i, f in enumerate(as_completed(futs)):
                results[futs[f]] = f.result()
                if progress:
                    progress(i + 1, len(chunks), label(futs[f]))
    order = {n: i for i, n in enumerate(k.name for k in ks)}
    rows = [StartCheck(**r) for ch in chunks for r in results[ch]]
    rows.sort(key=lambda r: (order[r.knot], fams.index(r.family)))
    return rows


def summarise(rows: Iterable[StartCheck], w: float = 2 ** -0.5) -> dict:
    """Counts by crossing number and family: knots, verified, tie, absent, failed, and the
    verified chains admissible for a tube of diameter ``w`` (``tube_ok``); the knots with a
    verified start of a family other than the braid; and the failed rows."""
    rows = list(rows)
    by_c: dict[int, dict] = {}
    other: dict[str, bool] = {}
    for r in rows:
        c = by_c.setdefault(r.crossings, {"knots": set(), "families": {}})
        c["knots"].add(r.knot)
        f = c["families"].setdefault(r.family, {"verified": 0, "tie": 0, "absent": 0,
                                                 "failed": 0, "tube_ok": 0})
        f[r.status] += 1
        if r.status == "verified" and r.segment_distance is not None \
                and r.segment_distance >= w - 1e-9:
            f["tube_ok"] += 1
        if r.family != "braid":
            other[r.knot] = other.get(r.knot, False) or r.status == "verified"
    out = {}
    for c in sorted(by_c):
        d = by_c[c]
        out[c] = {"knots": len(d["knots"]), "families": d["families"],
                  "another_family": sum(1 for k in d["knots"] if other.get(k))}
    knots = {r.knot for r in rows}
    return {
        "knots": len(knots),
        "by_crossing": out,
        "another_family": sum(1 for k in knots if other.get(k)),
        "failed": [r.as_dict() for r in rows if r.status == "failed"],
        "not_tube": [r.as_dict() for r in rows if r.status == "verified"
                     and r.segment_distance is not None and r.segment_distance < w - 1e-9],
        "ties": [r.as_dict() for r in rows if r.status == "tie"],
        "seconds": sum(r.seconds for r in rows),
    }
