"""Starting chains for the annealing: which embedding the Monte Carlo search starts from.

``braid`` is the closure of KnotInfo's braid word
(:func:`stiffknots.knots.embedding.embed_braid`); ``cage`` is the 4-fold cage of a two-box
rational knot (:func:`stiffknots.knots.cage_embedding.embed_cage`); ``eighty`` is an "80", a
figure eight with a circle along one lobe (:func:`stiffknots.knots.eighty_embedding.embed_eighty`,
found by a search over a parametrised family, slower to build). ``all`` means the starts
that exist for the knot among braid and cage, and the 80 for the knots of the 80 family
(:func:`default_starts`; the same rule for ``anneal``, ``tightest`` and the atlas's sweeps),
taken by the replicas in turn over the rounds. The annealing decides the final shape and
energy; the start only chooses the basin it is searched from.
"""

from __future__ import annotations

import functools

import numpy as np

from stiffknots.errors import InvalidParameter

__all__ = ["ALL_STARTS", "STARTS", "available_starts", "default_starts", "resolve_starts",
           "split_replicas", "start_chain"]

#: Names of the starting embeddings.
STARTS = ("braid", "cage", "eighty")
#: The starts that ``start='all'`` draws from where they exist; ``eighty`` only for the knots
#: of the 80 family with n ≠ i (:func:`default_starts`).
ALL_STARTS = ("braid", "cage")


def start_chain(knot, start: str = "braid", n_beads: int = 150) -> np.ndarray:
    """Closed unit-bond chain of ``knot`` (a catalogue entry) built by the ``start`` method.

    Raises
    ------
    ValueError
        For an unknown ``start`` (the message lists :data:`STARTS`).
    EmbeddingError
        If that start does not exist for this knot or does not fit in ``n_beads`` beads.
    """
    if start not in STARTS:
        raise ValueError(f"unknown start {start!r}; choose one of {', '.join(STARTS)}")
    try:
        hash(knot)
    except TypeError:  # not a catalogue entry (a stand-in): built every time
        return _build(knot, start, int(n_beads))
    return _built(knot, start, int(n_beads)).copy()


@functools.lru_cache(maxsize=32)
def _built(knot, start: str, n_beads: int) -> np.ndarray:
    """:func:`start_chain`, built once per process (the embeddings are deterministic; the 80
    is a search of seconds, asked for by :func:`available_starts` and again by the problem,
    and by every problem of the same knot in a sweep's worker). Read-only; callers get copies."""
    x = _build(knot, start, n_beads)
    x.setflags(write=False)
    return x


def _build(knot, start: str, n_beads: int) -> np.ndarray:
    if start == "braid":
        from stiffknots.knots.embedding import embed_braid

        word = knot.braid_word or ()
        return embed_braid(word, n_strands=knot.braid_strands if word else None, n_beads=n_beads)
    if start == "cage":
        from stiffknots.knots.cage_embedding import embed_cage

        return embed_cage(knot, n_beads)
    if start == "eighty":
        from stiffknots.knots.eighty_embedding import embed_eighty

        return embed_eighty(knot, n_beads)
    raise ValueError(f"unknown start {start!r}; choose one of {', '.join(STARTS)}")


def available_starts(knot, n_beads: int = 150, starts=ALL_STARTS) -> list[str]:
    """The ``starts`` (default :data:`ALL_STARTS`) that exist for ``knot`` at ``n_beads`` beads.

    A start is available when :func:`start_chain` builds it (an :class:`.EmbeddingError` means
    the knot is outside that start's family or does not fit).
    """
    from stiffknots.knots.embedding import EmbeddingError

    out = []
    for st in starts:
        try:
            start_chain(knot, st, n_beads)
        except EmbeddingError:
            continue
        out.append(st)
    return out


def default_starts(knot, n_beads: int = 150) -> list[str]:
    """The starts of ``start='all'``, in the order the replicas take them (replica r the
    (r mod k)-th): the braid closure, the 4-fold cage where the knot is a two-box rational
    knot, and the 80 where the knot is of the 80 family (n ≠ i: an n = i knot's ground state
    is its circular braid) — the embeddings of the shapes §VII conjectures for it. Measured:
    the knots of the 80 family reached lower states from the 80 (8_8: 226.9 against 231.7
    from braid and cage alone in the atlas sweep, 216.98 against 233.42 in ``anneal``'s
    defaults survey; docs/history.md).

    Raises
    ------
    EmbeddingError
        No start fits in ``n_beads`` beads (the braid closure's message says how many).
    """
    found = available_starts(knot, n_beads, ALL_STARTS)
    if not found:
        # too few beads for the braid closure and the cage: an 80 (a figure eight and a
        # circle) needs more still, and its search of every spec took 36 s before the user
        # read the one-line error
        start_chain(knot, "braid", n_beads)  # raises, saying why
    if _eighty_is_a_default(knot):
        found += available_starts(knot, n_beads, ("eighty",))
    return found


def _eighty_is_a_default(knot) -> bool:
    """Is the 80 among the knot's default starts (when it fits): a knot of the 80 family
    with n ≠ i (an n = i knot's ground state is its circular braid)."""
    from stiffknots.knots.families import EIGHTY_FAMILY

    return knot.name in EIGHTY_FAMILY and not knot.n_equals_i


@functools.lru_cache(maxsize=4096)
def default_start_names(name: str, n_beads: int = 150) -> tuple[str, ...]:
    """The names of :func:`default_starts` of the knot ``name`` at ``n_beads`` beads, for the
    verdicts on stored results (which need the names only): braid and cage are built (a few
    milliseconds), the 80 is decided by its spec search, kept in the disk cache, whose spec
    is found only when its chain was built and verified — building every knot's 80 again
    took 21 s for the 249 knots. () when no start fits."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.eighty_embedding import has_eighty

    knot = get_knot(name)
    found = available_starts(knot, n_beads, ALL_STARTS)
    if not found:
        return ()
    if _eighty_is_a_default(knot) and has_eighty(knot, n_beads):
        found.append("eighty")
    return tuple(found)


def split_replicas(starts: list[str], replicas: int) -> list[str]:
    """Assign ``replicas`` replicas to ``starts`` round-robin (replica r gets start r mod k)."""
    if not starts:
        raise ValueError("no start to assign replicas to")
    return [starts[r % len(starts)] for r in range(replicas)]


def resolve_starts(knot, start, replicas: int, n_beads: int = 150) -> list[str]:
    """One start name per replica.

    Parameters
    ----------
    knot
        Catalogue entry.
    start
        ``'all'`` (every available start, shared round-robin), one name of :data:`STARTS`
        (every replica), or a sequence of ``replicas`` names.
    replicas : int
        Number of replicas.
    n_beads : int
        Number of beads (a start must fit in it to be available).

    Raises
    ------
    InvalidParameter
        For an unknown name (a ``ValueError``).
    ValueError
        For a sequence of the wrong length.
    """
    if isinstance(start, str):
        if start == "all":
            return split_replicas(default_starts(knot, n_beads), replicas)
        if start not in STARTS:
            raise InvalidParameter("start", start, "one of " + ", ".join(("all", *STARTS)))
        return [start] * replicas
    out = [str(s) for s in start]
    if len(out) != replicas:
        raise ValueError(f"start: {len(out)} starts given for {replicas} replicas")
    bad = [s for s in out if s not in STARTS]
    if bad:
        raise ValueError(f"unknown start(s) {bad}; choose from {', '.join(STARTS)}")
    return out
