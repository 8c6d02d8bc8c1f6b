"""Curves brought by the user: plain x y z / tsv / csv tables, VECT (KnotPlot, ridgerunner),
npy and bare JSON lists, and the closure rule shared by every reader."""

import json

import numpy as np
import pytest

from helpers import DATA, trefoil
from stiffknots.chain import Chain
from stiffknots.errors import ChainFormatError
from stiffknots.formats import (
    closure_note,
    from_text,
    from_vect,
    load,
    save,
    to_vect,
)

RIDGERUNNER = DATA / "curves" / "ridgerunner"


def _r(v):
    return repr(float(v))


def _rows(x, sep=" "):
    return "\n".join(sep.join(repr(float(v)) for v in p) for p in x) + "\n"


@pytest.fixture(scope="module")
def fig8_100():
    """A closed 4_1 polygon of 100 unit bonds (the 4-fold cage)."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.starts import start_chain

    return start_chain(get_knot("4_1"), "cage", 100)


def test_issue_closed_xyz_without_repeat_is_not_silently_open(tmp_path, fig8_100):
    """The issue: a closed 4_1 polygon of 100 vertices in xyz, first vertex not repeated, was
    read as an open chain and its ε came out too low (121.8 instead of 126.1 there)."""
    ring = Chain(fig8_100)
    p = tmp_path / "fig8.xyz"
    p.write_text(_rows(fig8_100))
    c = load(p)
    assert c.closed and c.n_beads == 100
    assert c.meta["closure"].startswith("assumed closed")
    assert c.epsilon() == pytest.approx(ring.epsilon(), rel=1e-12)
    opened = load(p, closed=False)
    assert not opened.closed and opened.epsilon() < ring.epsilon() - 1.0
    assert closure_note(opened).startswith("open: as requested")


@pytest.mark.parametrize("sep,suffix,header", [
    (" ", ".txt", ""), ("\t", ".tsv", "x\ty\tz\n"), (",", ".csv", "x,y,z\n"),
    (", ", ".csv", '"X", "Y", "Z"\n'), ("  ", ".dat", "# comment\n"),
])
def test_plain_tables(tmp_path, sep, suffix, header):
    x = trefoil(30)
    p = tmp_path / f"t{suffix}"
    p.write_text(header + _rows(x, sep))
    c = load(p)
    assert c.closed and np.array_equal(c.coords, x)
    assert c.meta["closure"].startswith("assumed closed")
    # the same file with the first vertex repeated at the end: closed, repeat dropped
    p.write_text(header + _rows(np.vstack([x, x[:1]]), sep))
    c = load(p)
    assert c.closed and c.n_beads == 30 and "repeats the first" in c.meta["closure"]
    assert not load(p, closed=False).closed


def test_header_picks_named_columns(tmp_path):
    x = trefoil(12)
    lines = ["id\tz\tcolour\tx\ty"] + [f"{i}\t{_r(p[2])}\tred\t{_r(p[0])}\t{_r(p[1])}"
                                         for i, p in enumerate(x)]
    (tmp_path / "t.tsv").write_text("\n".join(lines) + "\n")
    assert np.array_equal(from_text(tmp_path / "t.tsv").coords, x)


def test_molecular_xyz_and_index_columns(tmp_path):
    x = trefoil(10)
    body = "".join(f"C {_r(p[0])} {_r(p[1])} {_r(p[2])}\n" for p in x)
    (tmp_path / "m.xyz").write_text(f"10\nsome molecule\n{body}")
    assert np.array_equal(load(tmp_path / "m.xyz").coords, x)
    (tmp_path / "bad.xyz").write_text("1.5 0 0 0\n2 1 0 0\n3 0 1 0\n")
    with pytest.raises(ChainFormatError, match=r"bad\.xyz, line 1"):
        load(tmp_path / "bad.xyz")


def test_vect_closed_open_and_written(tmp_path):
    x = trefoil(20)
    c = Chain(x)
    to_vect(c, tmp_path / "c.vect")
    text = (tmp_path / "c.vect").read_text().splitlines()
    assert text[:4] == ["VECT", "1 20 1", "-20", "1"]
    d = from_vect(tmp_path / "c.vect")
    assert d.closed and np.array_equal(d.coords, x) and "negative" in d.meta["closure"]
    o = Chain(x[:8], closed=False)
    save(o, tmp_path / "o.vect")
    d = load(tmp_path / "o.vect")
    assert not d.closed and d.meta["closure"].startswith("open: the VECT vertex count")
    assert load(tmp_path / "o.vect", closed=True).closed
    # free layout, comments, and a positive count whose last vertex repeats the first
    body = " ".join(repr(float(v)) for v in np.vstack([x[:5], x[:1]]).ravel())
    (tmp_path / "r.vect").write_text(f"VECT # knot\n1 6 0\n6\n0\n{body}\n")
    d = load(tmp_path / "r.vect")
    assert d.closed and d.n_beads == 5


def test_ridgerunner_vect_files():
    c = load(RIDGERUNNER / "8.18.vect")
    assert c.closed and c.n_beads == 97
    b = c.bond_lengths()
    assert 1.1 < b.min() < b.max() < 1.5  # non-unit bonds
    with pytest.raises(ChainFormatError, match="2 polylines"):
        load(RIDGERUNNER / "6.2.1.vect")


BAD_VECT = {
    "notvect.vect": ("OFF\n1 2 3\n", "starts with 'VECT'"),
    "four.vect": ("4VECT\n1 3 0\n-3\n0\n", "4VECT"),
    "link.vect": ("VECT\n3 9 0\n-3 -3 -3\n0 0 0\n", "3 polylines"),
    "count.vect": ("VECT\n1 4 0\n-3\n0\n0 0 0 1 0 0 0 1 0\n", "announces 4"),
    "short.vect": ("VECT\n1 3 0\n-3\n0\n0 0 0 1 0 0\n", "ends after 2 of the 3"),
    "text.vect": ("VECT\n1 3 0\n-3\n0\n0 0 0\n1 x 0\n0 1 0\n", "line 6"),
    "colours.vect": ("VECT\n1 3 1\n-3\n1\n0 0 0 1 0 0 0 1 0\n1 1\n", "colour"),
    "hdr.vect": ("VECT\n1 three 0\n", "line 2"),
    "dup.vect": ("VECT\n1 4 0\n-4\n0\n0 0 0\n1 0 0\n1 0 0\n0 1 0\n", "lines 6 and 7"),
}


@pytest.mark.parametrize("name", sorted(BAD_VECT))
def test_bad_vect_files(tmp_path, name):
    text, what = BAD_VECT[name]
    p = tmp_path / name
    p.write_text(text)
    with pytest.raises(ChainFormatError, match=name.replace(".", r"\.")) as e:
        load(p)
    assert what in str(e.value) and "\n" not in str(e.value)


BAD_TEXT = {
    "cols.csv": ("x,y,z\n0,0,0\n1,0\n", "line 3"),
    "nan.txt": ("0 0 0\n1 nan 0\n0 1 0\n", "line 2"),
    "hdr.csv": ("a,b\n0,0\n", "does not name x, y and z"),
    "word.tsv": ("0\t0\t0\n1\tone\t0\n", "line 2"),
    "dup.txt": ("0 0 0\n1 0 0\n1 0 0\n0 1 0\n", "lines 2 and 3"),
    "kymo.xyz": ("4\n0 0 0\n1 0 0\n0 1 0\n", "announces 4"),
    "list.json": ("[[0, 0, 0], [1, 0]]", "triples"),
    "trunc.json": ('{"format": "stiffknots-chain",\n "version": 1, "coo', "line 2"),
}


@pytest.mark.parametrize("name", sorted(BAD_TEXT))
def test_bad_text_files(tmp_path, name):
    text, what = BAD_TEXT[name]
    p = tmp_path / name
    p.write_text(text)
    with pytest.raises(ChainFormatError, match=name.replace(".", r"\.")) as e:
        load(p)
    assert what in str(e.value) and "\n" not in str(e.value)


def test_npy_json_list_obj_without_lines(tmp_path):
    x = trefoil(16)
    np.save(tmp_path / "a.npy", x)
    c = load(tmp_path / "a.npy")
    assert c.closed and c.meta["closure"].startswith("assumed") and np.array_equal(c.coords, x)
    (tmp_path / "l.json").write_text(json.dumps(x.tolist()))
    assert load(tmp_path / "l.json").meta["closure"].startswith("assumed")
    assert not load(tmp_path / "l.json", closed=False).closed
    (tmp_path / "v.obj").write_text("".join(f"v {_r(p[0])} {_r(p[1])} {_r(p[2])}\n" for p in x))
    assert load(tmp_path / "v.obj").meta["closure"].startswith("assumed")
    np.savez(tmp_path / "c.npz", coords=x)  # no 'closed' array
    assert load(tmp_path / "c.npz").meta["closure"].startswith("assumed")


def test_recorded_flags_win_and_meta_round_trips(tmp_path):
    o = Chain(trefoil(9), closed=False, meta={"k": 1})
    for suffix in (".json", ".npz"):
        save(o, tmp_path / f"o{suffix}")
        d = load(tmp_path / f"o{suffix}")
        assert not d.closed and d.meta == {"k": 1}
        assert closure_note(d).startswith("open: recorded")
        assert load(tmp_path / f"o{suffix}", closed=True).closed


@pytest.mark.parametrize("suffix", [".txt", ".xyz", ".csv", ".json", ".vect"])
def test_a_byte_order_mark_drops_no_vertex(tmp_path, suffix):
    """#40 row 8: a file that starts with a UTF-8 byte-order mark (Notepad, Excel) reads the
    same as without it (it dropped the first vertex as a header line)."""
    x = trefoil(40)
    plain = tmp_path / f"plain{suffix}"
    if suffix in (".txt", ".csv"):
        plain.write_text(_rows(x, "," if suffix == ".csv" else " "))
    else:
        save(Chain(x, True), plain)
    bom = tmp_path / f"bom{suffix}"
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    a, b = load(plain), load(bom)
    assert b.n_beads == a.n_beads == 40
    np.testing.assert_array_equal(a.coords, b.coords)
