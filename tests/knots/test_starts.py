"""Starting chains are built once per process and handed out as copies."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.starts import _built, start_chain


def test_a_start_is_built_once_and_handed_out_as_copies():
    k = get_knot("5_2")
    _built.cache_clear()
    a = start_chain(k, "cage")
    assert _built.cache_info().misses == 1
    b = start_chain(k, "cage")
    assert _built.cache_info().hits == 1  # the second ask is not built again
    assert a is not b and np.array_equal(a, b) and a.flags.writeable
    a[:] = 0.0  # a caller's copy: the cached chain is untouched
    assert np.array_equal(start_chain(k, "cage"), b)
    bonds = np.linalg.norm(np.roll(b, -1, axis=0) - b, axis=1)
    assert np.allclose(bonds, 1.0) and len(b) == 150


def test_unknown_start_and_a_stand_in_knot():
    with pytest.raises(ValueError, match="unknown start 'spiral'"):
        start_chain(get_knot("3_1"), "spiral")
    k = get_knot("3_1")
    stand_in = SimpleNamespace(braid_word=list(k.braid_word), braid_strands=k.braid_strands)
    with pytest.raises(TypeError):
        hash(stand_in.braid_word)
    x = start_chain(stand_in, "braid")  # not hashable by its fields' lists: built, not cached
    assert np.array_equal(x, start_chain(k, "braid"))


def test_default_starts_are_the_shapes_conjectured_for_the_knot():
    from stiffknots.knots.starts import default_starts

    assert default_starts(get_knot("3_1")) == ["braid"]  # n = i: its circular braid
    assert default_starts(get_knot("7_4")) == ["braid"]  # in no family
    assert default_starts(get_knot("5_2")) == ["braid", "cage", "eighty"]  # [32]: cage, 80
    assert default_starts(get_knot("6_3")) == ["braid", "eighty"]  # 80 family, no cage


def test_later_rounds_take_the_starts_the_first_did_not():
    """Two replicas a round, three starts: round 2 starts from the 80 the first round lacked."""
    from stiffknots.problems.closed import ClosedAnneal

    p = ClosedAnneal("5_2", moves=20_000, replicas=2, rounds=3)
    starts = [j.start for rnd in range(3) for j in p.jobs(first=2 * rnd)]
    assert starts == ["braid", "cage", "eighty", "braid", "cage", "eighty"]
    q = ClosedAnneal("5_2", moves=20_000, replicas=2, rounds=2, start="cage")
    assert [j.start for j in q.jobs(first=2)] == ["cage", "cage"]


def test_too_few_beads_fail_before_the_eighty_search(monkeypatch):
    # 4_1 at 20 beads: the braid closure needs 23, so no start fits and the error says so at
    # once (the 80's search of every spec took 36 s before it)
    import stiffknots.knots.eighty_embedding as E
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import EmbeddingError
    from stiffknots.knots.starts import default_starts

    def no_search(*a):
        raise AssertionError("the 80 was searched")

    monkeypatch.setattr(E, "_search_spec", no_search)
    E._spec_for.cache_clear()
    with pytest.raises(EmbeddingError, match="least number of beads that works is 23"):
        default_starts(get_knot("4_1"), 20)


def test_the_eighty_search_is_kept_on_disk(monkeypatch, tmp_path):
    import stiffknots.knots.eighty_embedding as E

    monkeypatch.setenv("STIFFKNOTS_CACHE", str(tmp_path))
    E._spec_for.cache_clear()
    spec = E._spec_for("5_2", 150, E._MAX_DIAGRAM)
    assert spec is not None and list(tmp_path.glob("eighty-spec-*.pkl"))
    E._spec_for.cache_clear()
    monkeypatch.setattr(E, "_search_spec", lambda *a: None)  # a second process: no search
    assert E._spec_for("5_2", 150, E._MAX_DIAGRAM) == spec
    E._spec_for.cache_clear()
