"""The per-user disk cache: computed once, read back equal, a damaged file recomputed."""

from stiffknots import _diskcache as D


def test_cached_value_is_computed_once_and_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv("STIFFKNOTS_CACHE", str(tmp_path))
    calls = []

    def compute():
        calls.append(1)
        return {"eps": [1.5, 2.5]}

    key = D.source_key("x", files=(__file__,))
    assert D.cached("t", key, compute) == {"eps": [1.5, 2.5]}
    assert D.cached("t", key, compute) == {"eps": [1.5, 2.5]}
    assert len(calls) == 1
    (f,) = tmp_path.glob("t-*.pkl")
    f.write_bytes(b"not a pickle")  # damaged (a killed writer cannot do this: rename)
    assert D.cached("t", key, compute) == {"eps": [1.5, 2.5]}
    assert len(calls) == 2
    assert D.source_key("y", files=(__file__,)) != key  # another input, another file


def test_unwritable_cache_still_returns_the_value(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("STIFFKNOTS_CACHE", str(blocker / "sub"))  # cannot be a folder
    assert D.cached("t", "k", lambda: 42) == 42


def test_catalogue_from_the_cache_equals_a_fresh_parse(tmp_path, monkeypatch):
    from stiffknots.knots import catalogue as C

    monkeypatch.setenv("STIFFKNOTS_CACHE", str(tmp_path))
    C._tables.cache_clear()
    try:
        first = C._tables()  # parsed and written
        C._tables.cache_clear()
        second = C._tables()  # read back
        assert second.knots == first.knots and second.by_torus == first.by_torus
        assert list(tmp_path.glob("knotinfo-*.pkl"))
    finally:
        C._tables.cache_clear()
