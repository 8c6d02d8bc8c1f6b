"""Tests of the KnotInfo knot catalogue (stiffknots.knots.catalogue)."""

from collections import Counter

import pytest

from stiffknots.knots.catalogue import (
    Knot,
    UnknownKnotError,
    catalogue,
    get_knot,
    knot_names,
    n_equals_i_knots,
    n_equals_i_statistics,
)

# Prime knots by crossing number (up to mirror image), OEIS A002863.
PRIME_KNOT_COUNTS = dict(
    zip(range(3, 14), (1, 1, 2, 3, 7, 21, 49, 165, 552, 2176, 9988), strict=True)
)


@pytest.fixture(scope="module")
def knots():
    return catalogue()


def test_catalogue_counts(knots):
    assert knots[0].name == "0_1" and knots[0].is_unknot
    counts = Counter(k.crossing_number for k in knots)
    assert counts.pop(0) == 1
    assert dict(counts) == PRIME_KNOT_COUNTS
    assert len(knots) == 1 + sum(PRIME_KNOT_COUNTS.values())
    assert len({k.name for k in knots}) == len(knots)


def test_catalogue_order_and_truncation(knots):
    names = knot_names()
    assert names[:4] == ("0_1", "3_1", "4_1", "5_1")
    assert names.index("10_165") + 1 == names.index("11a_1")
    cn = [k.crossing_number for k in knots]
    assert cn == sorted(cn)
    small = catalogue(10)
    assert small == knots[: len(small)]
    assert len(small) == 250 and small[-1].name == "10_165"
    assert catalogue(2) == (knots[0],)
    assert catalogue() is catalogue()  # cached
    with pytest.raises(ValueError, match="13"):
        catalogue(14)


def test_bridge_at_most_braid(knots):
    for k in knots:
        if k.bridge_number is not None and k.braid_index is not None:
            assert k.bridge_number <= k.braid_index, k.name
        if not k.is_unknot:
            assert k.bridge_number_range is not None
            assert k.bridge_number_range[0] >= 2, k.name
            if k.bridge_number is not None:
                assert k.bridge_number >= 2, k.name
        if k.braid_index_range is not None:
            lo, hi = k.braid_index_range
            assert lo <= hi, k.name
            assert k.bridge_number_range[0] <= hi, k.name


def test_unknowns_are_none_with_ranges(knots):
    # up to 12 crossings KnotInfo knows n and i for every knot
    for k in knots:
        if k.crossing_number <= 12:
            assert k.bridge_number is not None and k.braid_index is not None, k.name
            assert k.n_equals_i is not None
    thirteen = [k for k in knots if k.crossing_number == 13]
    assert all(k.braid_index is None and k.n_equals_i is None for k in thirteen)
    intervals = [k for k in thirteen if k.bridge_number is None]
    assert len(intervals) == 536
    assert all(k.bridge_number_range == (3, 4) for k in intervals)
    assert all(k.raw["bridge_index"].replace(" ", "") == "[3,4]" for k in intervals)


def test_braid_words(knots):
    for k in knots:
        if k.is_unknot:
            continue
        assert k.braid_word, k.name
        assert all(g != 0 for g in k.braid_word)
        if k.braid_index is not None:
            assert all(1 <= abs(g) <= k.braid_index - 1 for g in k.braid_word), k.name
            assert k.braid_strands == k.braid_index
        if k.braid_index_range is not None:
            assert k.braid_strands >= k.braid_index_range[1]


def test_pd_codes(knots):
    for k in knots:
        if k.pd_code is not None:
            assert len(k.pd_code) == k.crossing_number, k.name
            labels = Counter(x for quad in k.pd_code for x in quad)
            assert set(labels.values()) == {2}
            assert set(labels) == set(range(1, 2 * k.crossing_number + 1))
    assert all(k.pd_code is not None for k in knots if 3 <= k.crossing_number <= 12)


@pytest.mark.parametrize(
    "name, n, i, torus, alternating, braid_len",
    [
        ("3_1", 2, 2, "T(2,3)", True, 3),
        ("4_1", 2, 3, None, True, 4),
        ("5_1", 2, 2, "T(2,5)", True, 5),
        ("8_19", 3, 3, "T(3,4)", False, 8),
        ("10_124", 3, 3, "T(3,5)", False, 10),
    ],
)
def test_known_values(name, n, i, torus, alternating, braid_len):
    k = get_knot(name)
    assert k.name == name
    assert k.bridge_number == n
    assert k.braid_index == i
    assert k.torus_notation == torus
    assert k.alternating is alternating
    assert len(k.braid_word) == braid_len
    assert k.n_equals_i is (n == i)
    assert k.bridge_number_range == (n, n) and k.braid_index_range == (i, i)


def test_misc_fields():
    k = get_knot("3_1")
    assert k.crossing_number == 3
    assert k.dt_name == "K3a1"
    assert k.torus == (2, 3)
    assert k.alexander_polynomial is not None and k.jones_polynomial is not None
    assert k.raw["braid_notation"] == "[1,1,1]"
    assert "raw" not in repr(k)
    assert get_knot("8_19").dt_name == "K8n3"
    assert get_knot("11a_1").dt_name == "K11a1"
    unknot = get_knot("unknot")
    assert unknot.is_unknot and unknot.crossing_number == 0 and unknot.n_equals_i
    assert unknot.braid_word is None and unknot.dt_name is None
    assert hash(k) == hash(get_knot("trefoil"))
    assert isinstance(k, Knot)


def test_torus_knots(knots):
    torus = {k.torus_notation: k.name for k in knots if k.torus is not None}
    assert torus == {
        "T(2,3)": "3_1",
        "T(2,5)": "5_1",
        "T(2,7)": "7_1",
        "T(2,9)": "9_1",
        "T(2,11)": "11a_367",
        "T(2,13)": "13a_4878",
        "T(3,4)": "8_19",
        "T(3,5)": "10_124",
    }
    for k in knots:
        if k.torus is not None:
            p, q = k.torus
            assert k.crossing_number == q * (p - 1)
            assert k.bridge_number == p
            assert k.braid_index in (p, None)
            assert k.braid_index_range == (p, p)


@pytest.mark.parametrize(
    "spellings, name",
    [
        (
            [
                "4_1",
                "4.1",
                "4-1",
                " 4_1 ",
                "41",
                "K4a1",
                "4a_1",
                "figure-eight",
                "Figure8",
                "figure eight",
                "FIGURE-8",
            ],
            "4_1",
        ),
        (
            [
                "3_1",
                "3.1",
                "trefoil",
                "Trefoil",
                "T(2,3)",
                "T(3,2)",
                "T2,3",
                "t(2, 3)",
                "T(2,-3)",
                "K3a1",
            ],
            "3_1",
        ),
        (["0_1", "unknot", "Unknot", "T(1,5)"], "0_1"),
        (["5_1", "T(2,5)", "T(5,2)"], "5_1"),
        (["8_19", "T(3,4)", "T(4,3)", "K8n3"], "8_19"),
        (["10_124", "10.124", "T(3,5)", "T3,5"], "10_124"),
        (["11a_1", "11a1", "K11a1", "k11a1", "11A_1", "11a-1"], "11a_1"),
        (["13n_5110", "K13n5110"], "13n_5110"),
        (["11a_367", "T(2,11)"], "11a_367"),
    ],
)
def test_spellings(spellings, name):
    for s in spellings:
        assert get_knot(s).name == name, s
    assert len({get_knot(s) for s in spellings}) == 1


def test_unknown_names():
    with pytest.raises(UnknownKnotError) as e:
        get_knot("4_9")
    msg = str(e.value)
    assert "'4_9'" in msg and "4_1" in msg and "closest names" in msg
    assert isinstance(e.value, ValueError)
    with pytest.raises(UnknownKnotError, match="8_21"):
        get_knot("8_22")
    with pytest.raises(UnknownKnotError, match="trefoil"):
        get_knot("trefoyl")
    with pytest.raises(UnknownKnotError, match="Dowker-Thistlethwaite"):
        get_knot("11_5")
    with pytest.raises(UnknownKnotError, match="13 crossings"):
        get_knot("14_1")
    with pytest.raises(UnknownKnotError, match="1 or 2 crossings"):
        get_knot("2_1")
    with pytest.raises(UnknownKnotError):
        get_knot("")
    with pytest.raises(UnknownKnotError):
        get_knot("K4a2")


def test_mirror_spellings_are_the_same_knot():
    """#40 row 13: the mirror spellings of KnotInfo, SnapPy and knot tables name the knot (ε
    does not depend on the mirror) and say so; no name of the catalogue reads as one."""
    from stiffknots.knots.catalogue import _ALIASES, mirror_note, mirror_of

    for s in ("m3_1", "3_1*", "3_1m", "3_1!", "mirror(3_1)", "M3_1", "m 3_1", "trefoil*",
              "T(2,3)*"):
        assert get_knot(s).name == "3_1", s
        assert mirror_of(s) == "3_1", s
        assert "do not depend on the mirror" in mirror_note(s)
    assert get_knot("mK11n34").name == get_knot("K11n34m").name == "11n_34"
    assert mirror_of("3_1") is None and mirror_note("3_1") is None
    assert not [n for n in (*knot_names(), *_ALIASES) if mirror_of(n)]
    with pytest.raises(UnknownKnotError, match=r"'4_9'.*mirror image of '4_9'"):
        get_knot("m4_9")


def test_torus_errors():
    with pytest.raises(UnknownKnotError, match="link of 2 components"):
        get_knot("T(2,4)")
    with pytest.raises(UnknownKnotError, match="gcd"):
        get_knot("T(3,6)")
    with pytest.raises(UnknownKnotError, match="crossing number 15"):
        get_knot("T(4,5)")
    with pytest.raises(UnknownKnotError, match="crossing number 14"):
        get_knot("T(3,7)")


def test_n_equals_i_statistics_up_to_10():
    s = n_equals_i_statistics()
    assert s["min_crossings"] == 3 and s["max_crossings"] == 10
    assert not s["includes_unknot"]
    by_c = {
        c: (row["knots"], row["n_equals_i"], row["unknown"]) for c, row in s["by_crossing"].items()
    }
    assert by_c == {
        3: (1, 1, 0),
        4: (1, 0, 0),
        5: (2, 1, 0),
        6: (3, 0, 0),
        7: (7, 1, 0),
        8: (21, 8, 0),
        9: (49, 2, 0),
        10: (165, 33, 0),
    }
    total = s["total"]
    assert (total["knots"], total["n_equals_i"], total["unknown"]) == (249, 46, 0)
    assert total["fraction"] == pytest.approx(46 / 249)
    assert 0.15 < total["fraction"] < 0.25  # the paper's "~ 20 %" (section VI C)
    family = n_equals_i_knots(10)
    assert len(family) == 46
    assert {"3_1", "5_1", "8_19", "10_124"} <= {k.name for k in family}
    assert all(k.n_equals_i for k in family)


def test_n_equals_i_statistics_options():
    with_unknot = n_equals_i_statistics(10, min_crossings=0)
    assert with_unknot["includes_unknot"]
    assert with_unknot["total"]["knots"] == 250 and with_unknot["total"]["n_equals_i"] == 47
    s13 = n_equals_i_statistics(13)
    row = s13["by_crossing"][13]
    assert row["knots"] == 9988 and row["unknown"] == 9988 and row["fraction"] is None
    assert s13["total"]["unknown"] == 9988
