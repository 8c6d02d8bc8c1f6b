"""Tests of stiffknots.formats: exact round trips, dialects, topoly, OBJ import, corrupt files."""

import json

import numpy as np
import pytest

from helpers import trefoil
from stiffknots.chain import Chain, regular_polygon
from stiffknots.errors import ChainFormatError
from stiffknots.formats import (
    from_json,
    from_npz,
    from_obj,
    from_xyz,
    load,
    save,
    to_json,
    to_npz,
    to_obj,
    to_xyz,
)

# ---------------------------------------------------------------------------- I/O


def _sample_chains():
    rng = np.random.default_rng(9)
    x = rng.normal(size=(13, 3)) * np.array([1e-7, 3.0, 1e5])
    x[0, 0] = 0.1 + 0.2  # a float with a long repr
    return [
        Chain(
            trefoil(50),
            meta={"knot": "3_1", "seed": np.int64(7), "T": np.float64(0.25), "ok": True},
        ),
        Chain(x, closed=False, meta={"note": "random", "arr": np.arange(3)}),
        Chain(x, closed=True),
    ]


@pytest.mark.parametrize("suffix", [".xyz", ".json", ".npz", ".obj", ".vect"])
def test_round_trips_exact(tmp_path, suffix):
    for k, c in enumerate(_sample_chains()):
        p = tmp_path / f"c{k}{suffix}"
        save(c, p)
        # xyz records closure only by repeating the first vertex: an open chain needs closed=False
        d = load(p, closed=False) if suffix == ".xyz" and not c.closed else load(p)
        assert d.closed == c.closed
        assert d.coords.shape == c.coords.shape
        assert np.array_equal(d.coords, c.coords)
        if suffix in (".json", ".npz"):
            expected = json.loads(json.dumps(c.meta, default=lambda o: o.tolist()))
            assert d.meta == expected


def test_xyz_dialects(tmp_path):
    c = Chain(trefoil(20), meta={"knot": "3_1"})
    to_xyz(c, tmp_path / "t.xyz")
    lines = (tmp_path / "t.xyz").read_text().splitlines()
    assert len(lines) == 21 and lines[0].split()[0] == "1" and lines[-1] == lines[0]
    assert all(len(ln.split()) == 4 for ln in lines)
    to_xyz(c, tmp_path / "k.xyz", dialect="kymoknot")
    lines = (tmp_path / "k.xyz").read_text().splitlines()
    assert lines[0] == "21" and len(lines) == 22 and lines[1] == lines[-1]
    assert all(len(ln.split(" ")) == 3 for ln in lines[1:])  # single spaces, 3 columns
    for name in ("t.xyz", "k.xyz"):
        d = from_xyz(tmp_path / name)
        assert d.closed and np.array_equal(d.coords, c.coords)
    # open chain, plain "x y z" lines and a KymoKnot LAMMPS-style title line
    o = Chain(trefoil(20)[:9], closed=False)
    to_xyz(o, tmp_path / "o.xyz", dialect="kymoknot")
    assert not from_xyz(tmp_path / "o.xyz", closed=False).closed
    # the file does not say: assumed closed (a ring never silently becomes an open chain)
    d = from_xyz(tmp_path / "o.xyz")
    assert d.closed and d.meta["closure"].startswith("assumed closed")
    body = "\n".join(" ".join(repr(float(v)) for v in p) for p in o.coords)
    (tmp_path / "plain.xyz").write_text(body + "\n")
    assert np.array_equal(from_xyz(tmp_path / "plain.xyz").coords, o.coords)
    (tmp_path / "lammps.xyz").write_text("9\nTimestep 0 some words\n" + body + "\n")
    assert np.array_equal(from_xyz(tmp_path / "lammps.xyz").coords, o.coords)
    assert from_xyz(tmp_path / "plain.xyz", closed=True).closed
    assert not from_xyz(tmp_path / "plain.xyz", closed=False).closed
    with pytest.raises(ValueError, match="dialect"):
        to_xyz(o, tmp_path / "x.xyz", dialect="pdb")


def test_xyz_readable_by_topoly(tmp_path):
    topoly = pytest.importorskip("topoly")
    c = Chain(trefoil(40))
    to_xyz(c, tmp_path / "t.xyz")
    g = topoly.Graph(str(tmp_path / "t.xyz"))
    assert g.closed and len(g.coordinates) == 40
    o = Chain(trefoil(40)[:20], closed=False)
    to_xyz(o, tmp_path / "o.xyz")
    g = topoly.Graph(str(tmp_path / "o.xyz"))
    assert not g.closed and len(g.coordinates) == 20


def test_obj_import_closed_and_open(tmp_path):
    closed_obj = """# ElasticKnots-like curve
o knot
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0.5
l 1 2
l 2 3
l 3 4
l 4 1
"""
    (tmp_path / "c.obj").write_text(closed_obj)
    c = from_obj(tmp_path / "c.obj")
    assert c.closed and c.n_beads == 4
    assert np.array_equal(c.coords, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5]])
    # edges listed out of order and reversed; one polyline element; duplicated closing vertex
    (tmp_path / "c2.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.5\nv 0 0 0\nl 3 2\nl 1 2\nl 3 4 5\n"
    )
    c2 = from_obj(tmp_path / "c2.obj")
    assert c2.closed and np.array_equal(c2.coords, c.coords)
    (tmp_path / "c3.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.5\nl 1 2 3 4 1\n")
    assert np.array_equal(from_obj(tmp_path / "c3.obj").coords, c.coords)
    # open polyline, vertices defined in another order than the path
    (tmp_path / "o.obj").write_text("v 2 0 0\nv 0 0 0\nv 1 0 0\nv 3 1 0\nl 2 3\nl 3 1\nl 1 4\n")
    o = from_obj(tmp_path / "o.obj")
    assert not o.closed
    assert np.array_equal(o.coords, [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 1, 0]])
    # writer round trip keeps the ElasticKnots style
    to_obj(c, tmp_path / "w.obj")
    assert (tmp_path / "w.obj").read_text().splitlines()[-1] == "l 4 1"


CORRUPT = {
    "bad.xyz": "1 0 0 0\n2 1 0 zz\n3 0 1 0\n",
    "cols.xyz": "0 0\n1 0\n",
    "count.xyz": "5\n0 0 0\n1 0 0\n0 1 0\n",
    "empty.xyz": "\n\n",
    "multi.xyz": "1 0 0 0\n2 1 0 0\nX\n3 0 1 0\n4 0 0 1\n",
    "bad.json": '{"format": "stiffknots-chain", "version": 1, "coords": [[0, 0]]}',
    "trunc.json": '{"format": "stiffknots-chain", "version": 1, "coo',
    "fmt.json": '{"format": "other", "version": 1, "coords": []}',
    "ver.json": '{"format": "stiffknots-chain", "version": 99, "coords": [[0,0,0],[1,0,0]]}',
    "nocoords.json": '{"format": "stiffknots-chain", "version": 1}',
    "short.json": '{"format": "stiffknots-chain", "version": 1, "coords": [[0,0,0],[1,0,0]]}',
    "bad.npz": "this is not a zip archive",
    "range.obj": "v 0 0 0\nv 1 0 0\nl 1 2 3\n",
    "branch.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nl 1 2\nl 1 3\nl 1 4\n",
    "pieces.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nl 1 2\nl 3 4\n",
    "face.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "novert.obj": "# nothing\n",
    "nan.obj": "v 0 0 nan\nv 1 0 0\nl 1 2\n",
    "text.obj": "v a b c\n",
}


@pytest.mark.parametrize("name", sorted(CORRUPT))
def test_corrupt_files_raise_chain_format_error(tmp_path, name):
    p = tmp_path / name
    p.write_text(CORRUPT[name])
    with pytest.raises(ChainFormatError, match=name.replace(".", r"\.")):
        load(p)


def test_missing_and_unknown_files(tmp_path):
    with pytest.raises(ChainFormatError, match="no such file"):
        load(tmp_path / "nope.json")
    for reader in (from_xyz, from_json, from_npz, from_obj):
        with pytest.raises(ChainFormatError, match="no such file"):
            reader(tmp_path / "nope.x")
    with pytest.raises(ChainFormatError, match="suffix"):
        load(tmp_path / "a.pdb")
    with pytest.raises(ChainFormatError, match="suffix"):
        save(regular_polygon(5), tmp_path / "a.pdb")
    # npz without the required arrays
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(ChainFormatError, match="lacks"):
        from_npz(tmp_path / "x.npz")
    assert issubclass(ChainFormatError, ValueError)


def test_json_layout(tmp_path):
    c = Chain(regular_polygon(5).coords, meta={"knot": "0_1"})
    to_json(c, tmp_path / "c.json")
    d = json.loads((tmp_path / "c.json").read_text())
    assert d["format"] == "stiffknots-chain" and d["version"] == 1 and d["closed"] is True
    assert d["meta"] == {"knot": "0_1"} and len(d["coords"]) == 5
    to_npz(c, tmp_path / "c.bin")  # no suffix appended
    assert from_npz(tmp_path / "c.bin").meta == {"knot": "0_1"}
    assert from_json(tmp_path / "c.json").meta == {"knot": "0_1"}


def test_nxyz_index_catches_a_lost_or_moved_line(tmp_path):
    """A line lost or moved inside an nxyz file is an error naming the line, not another
    chain read silently (the index column must count up by one)."""
    c = Chain(trefoil(30))
    to_xyz(c, tmp_path / "t.xyz")
    full = (tmp_path / "t.xyz").read_text().splitlines(keepends=True)
    assert np.array_equal(from_xyz(tmp_path / "t.xyz").coords, c.coords)
    (tmp_path / "hole.xyz").write_text("".join(full[:10] + full[11:]))
    with pytest.raises(ChainFormatError, match=r"line 11: index 12, expected 11 .*missing"):
        from_xyz(tmp_path / "hole.xyz")
    (tmp_path / "swap.xyz").write_text("".join(full[:5] + [full[6], full[5]] + full[7:]))
    with pytest.raises(ChainFormatError, match="out of order"):
        from_xyz(tmp_path / "swap.xyz")
    # a file that starts at index 0 (another writer) is fine, and so is a cut tail: the
    # closure rule then assumes a closed chain and says so
    (tmp_path / "zero.xyz").write_text("".join(f"{k} {ln.split(' ', 1)[1]}"
                                               for k, ln in enumerate(full[:-1])))
    assert from_xyz(tmp_path / "zero.xyz").n_beads == 30
    (tmp_path / "cut.xyz").write_text("".join(full[:20]))
    assert from_xyz(tmp_path / "cut.xyz").meta["closure"].startswith("assumed closed")
