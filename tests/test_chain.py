"""Tests of stiffknots.chain: energies of §VII, curvature, writhe, distances, excess length, I/O."""

import json
import math

import numpy as np
import pytest

from stiffknots.chain import (
    Chain,
    ChainFormatError,
    from_json,
    from_npz,
    from_obj,
    from_xyz,
    load,
    regular_polygon,
    save,
    to_json,
    to_npz,
    to_obj,
    to_xyz,
)
from stiffknots.geometry import segment_distance

TWO_PI2 = 2.0 * math.pi**2


def trefoil(n=120, R=2.0):
    """Smooth T(2,3) torus knot."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack(
        [(R + np.cos(3 * t)) * np.cos(2 * t), (R + np.cos(3 * t)) * np.sin(2 * t), np.sin(3 * t)]
    )


def gauss_writhe(x, closed=True, q=128):
    """Brute-force Gauss double integral with Gauss-Legendre quadrature on segment pairs."""
    n = len(x)
    nseg = n if closed else n - 1
    g, w = np.polynomial.legendre.leggauss(q)
    s, w = (g + 1) / 2, w / 2
    tot = 0.0
    for i in range(nseg):
        a0, a1 = x[i], x[(i + 1) % n]
        for j in range(nseg):
            if abs(i - j) <= 1 or (closed and abs(i - j) == nseg - 1):
                continue
            b0, b1 = x[j], x[(j + 1) % n]
            P = a0 + s[:, None] * (a1 - a0)
            Q = b0 + s[:, None] * (b1 - b0)
            r = P[:, None, :] - Q[None, :, :]
            val = (r @ np.cross(a1 - a0, b1 - b0)) / np.linalg.norm(r, axis=2) ** 3
            tot += w @ val @ w
    return tot / (4 * np.pi)


# ---------------------------------------------------------------------------- construction


def test_validation_messages():
    with pytest.raises(ValueError, match="shape"):
        Chain(np.zeros((5, 2)))
    with pytest.raises(ValueError, match="finite"):
        Chain([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]])
    with pytest.raises(ValueError, match="at least 3"):
        Chain([[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="at least 2"):
        Chain([[0, 0, 0]], closed=False)
    with pytest.raises(ValueError, match="zero length.*repeat"):
        Chain([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0]])
    c = Chain([[0, 0, 0], [1, 0, 0]], closed=False)
    assert c.n_beads == 2 and c.n_bonds == 1 and c.length == 1.0


def test_coords_are_a_contiguous_copy():
    x = np.asfortranarray(regular_polygon(10).coords)
    c = Chain(x)
    assert c.coords.flags.c_contiguous and c.coords.dtype == np.float64
    x[0, 0] = 99.0
    assert c.coords[0, 0] != 99.0


# ---------------------------------------------------------------------------- energy, ε


@pytest.mark.parametrize("n", [3, 4, 7, 30, 150])
def test_regular_polygon_unit_bonds_and_epsilon(n):
    c = regular_polygon(n)
    np.testing.assert_allclose(c.bond_lengths(), 1.0, rtol=0, atol=1e-13)
    assert c.length == pytest.approx(n, abs=1e-12)
    eps_exact = n * n * (1.0 - math.cos(2 * math.pi / n))  # E_d = N(1 - cos 2π/N), ε = E_d N
    assert c.epsilon() == pytest.approx(eps_exact, rel=1e-12)
    assert c.energy() == pytest.approx(n * (1.0 - math.cos(2 * math.pi / n)), rel=1e-12)


def test_circle_epsilon_limit():
    eps = regular_polygon(150).epsilon()
    assert abs(eps / TWO_PI2 - 1.0) < 1e-3
    assert eps < TWO_PI2  # discretisation error is one-sided
    # ε is independent of C and of the scale (non-unit bonds: generalised energy)
    c = regular_polygon(150)
    assert c.epsilon(C=3.7) == pytest.approx(eps, rel=1e-12)
    assert Chain(2.5 * c.coords).epsilon() == pytest.approx(eps, rel=1e-12)
    assert Chain(2.5 * c.coords).energy() == pytest.approx(c.energy() / 2.5, rel=1e-12)


def test_energy_matches_paper_formula_for_unit_bonds():
    # random closed unit-bond chain: compare with C Σ (1 - u_n.u_{n+1}) literally
    rng = np.random.default_rng(0)
    u = rng.normal(size=(40, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    x = np.cumsum(u, axis=0)  # open unit chain of 40 beads
    c = Chain(x, closed=False)
    uu = c.bond_vectors()
    uu /= np.linalg.norm(uu, axis=1)[:, None]
    ed = 2.0 * np.sum(1.0 - np.sum(uu[:-1] * uu[1:], axis=1))
    assert c.energy(C=2.0) == pytest.approx(ed, rel=1e-12)
    assert c.epsilon() == pytest.approx(ed / 2 * c.length, rel=1e-12)


@pytest.mark.parametrize("m", [2, 3])
def test_covered_circle(m):
    n = 150 * m
    c = regular_polygon(n, m)
    np.testing.assert_allclose(c.bond_lengths(), 1.0, rtol=0, atol=1e-12)
    assert c.epsilon() == pytest.approx(TWO_PI2 * m * m, rel=2e-3)
    assert c.total_curvature() == pytest.approx(2 * math.pi * m, rel=1e-3)
    # the covers do not touch: beads of different covers are separated
    assert c.min_bead_distance() > 0.7
    assert c.min_segment_distance() > 0.5


def test_open_chain_energy_interior_vertices_only():
    # an L-shaped open chain: one right angle -> E = C (1 - cos 90°) = C
    c = Chain([[0, 0, 0], [1, 0, 0], [1, 1, 0]], closed=False)
    assert c.energy() == pytest.approx(1.0)
    assert c.turning_angles() == pytest.approx([math.pi / 2])
    straight = Chain(np.column_stack([np.zeros(5), np.zeros(5), np.arange(5.0)]), closed=False)
    assert straight.energy() == 0.0
    assert straight.total_curvature() == 0.0


# ---------------------------------------------------------------------------- curvature


def test_total_curvature_convex_planar_polygon():
    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0, 2 * np.pi, 17))
    x = np.column_stack([3 * np.cos(t), 1.5 * np.sin(t), np.zeros_like(t)])
    c = Chain(x)
    assert c.total_curvature() == pytest.approx(2 * math.pi, abs=1e-12)
    assert len(c.turning_angles()) == 17
    # Σ κ_i b̄_i = total curvature
    lb = 0.5 * (c.bond_lengths() + np.roll(c.bond_lengths(), 1))
    assert np.sum(c.curvature() * lb) == pytest.approx(c.total_curvature(), rel=1e-12)


def test_curvature_of_polygon_tends_to_inverse_radius():
    c = regular_polygon(400)
    R = 0.5 / math.sin(math.pi / 400)
    np.testing.assert_allclose(c.curvature(), 2 * math.pi / 400, rtol=1e-10)  # θ / b̄, b̄ = 1
    np.testing.assert_allclose(c.curvature(), 1.0 / R, rtol=2e-5)  # O(1/N²) discretisation


def test_trefoil_total_curvature_above_milnor_bound():
    assert Chain(trefoil()).total_curvature() > 4 * math.pi  # bridge number 2


# ---------------------------------------------------------------------------- writhe


def test_writhe_planar_is_zero():
    c = regular_polygon(50)
    assert c.writhe() == 0.0
    rng = np.random.default_rng(2)
    t = np.sort(rng.uniform(0, 2 * np.pi, 25))
    x = np.column_stack(
        [np.cos(t) * (2 + np.sin(3 * t)), np.sin(t) * (2 + np.sin(3 * t)), np.zeros(25)]
    )
    # tilt the plane: rounding only
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    assert abs(Chain(x @ q.T).writhe()) < 1e-9


def test_writhe_trefoil_mirror():
    x = trefoil(200)
    w = Chain(x).writhe()
    wm = Chain(x * np.array([1.0, 1.0, -1.0])).writhe()
    assert abs(w) > 2.0
    assert wm == pytest.approx(-w, abs=1e-10)
    # invariant under rotation, translation and re-indexing
    q, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    assert Chain(x @ q.T + 5.0).writhe() == pytest.approx(w, abs=1e-10)
    assert Chain(np.roll(x, 17, axis=0)).writhe() == pytest.approx(w, abs=1e-10)
    assert Chain(x[::-1]).writhe() == pytest.approx(w, abs=1e-10)


def test_writhe_matches_gauss_integral():
    rng = np.random.default_rng(3)
    done = 0
    while done < 2:
        x = rng.normal(size=(7, 3))
        c = Chain(x)
        if c.min_segment_distance() < 0.1:
            continue
        assert c.writhe() == pytest.approx(gauss_writhe(x), abs=1e-3)
        o = Chain(x, closed=False)
        assert o.writhe() == pytest.approx(gauss_writhe(x, closed=False), abs=1e-3)
        done += 1


# ---------------------------------------------------------------------------- distances


def _brute_min_segment_distance(x, closed):
    n = len(x)
    nseg = n if closed else n - 1
    best = np.inf
    for i in range(nseg):
        for j in range(i + 1, nseg):
            share = {i, (i + 1) % n} & {j, (j + 1) % n}
            if share:
                continue
            best = min(best, segment_distance(x[i], x[(i + 1) % n], x[j], x[(j + 1) % n]))
    return best


@pytest.mark.parametrize("closed", [True, False])
def test_min_segment_distance_brute_force(closed):
    rng = np.random.default_rng(11)
    for n in (4, 5, 9, 25):
        x = rng.normal(size=(n, 3))
        c = Chain(x, closed=closed)
        assert c.min_segment_distance() == pytest.approx(
            _brute_min_segment_distance(x, closed), abs=1e-14
        )
    assert Chain(rng.normal(size=(3, 3))).min_segment_distance() == math.inf


def test_min_bead_distance():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(12, 3))
    for closed in (True, False):
        c = Chain(x, closed=closed)
        for s in (1, 2, 3, 5):
            best = np.inf
            for i in range(12):
                for j in range(i + 1, 12):
                    d = j - i
                    if closed:
                        d = min(d, 12 - d)
                    if d >= s:
                        best = min(best, np.linalg.norm(x[i] - x[j]))
            assert c.min_bead_distance(s) == pytest.approx(best, abs=1e-14)
    R = 0.5 / math.sin(math.pi / 100)
    assert regular_polygon(100).min_bead_distance(2) == pytest.approx(
        2 * R * math.sin(2 * math.pi / 100)
    )
    with pytest.raises(ValueError):
        Chain(x).min_bead_distance(0)


def test_radius_of_gyration_circle():
    c = regular_polygon(60)
    assert c.radius_of_gyration() == pytest.approx(0.5 / math.sin(math.pi / 60), rel=1e-12)


# ---------------------------------------------------------------------------- excess length


def test_excess_length_straight_and_loop():
    z = np.arange(-10.0, 11.0)
    straight = Chain(np.column_stack([np.zeros_like(z), np.zeros_like(z), z]), closed=False)
    assert straight.excess_length() == pytest.approx(0.0, abs=1e-12)
    # a unit-radius circular loop tangent to the z axis at the origin, then the line goes on
    M = 4000
    th = 2 * np.pi * np.arange(1, M) / M
    loop = np.column_stack([1 - np.cos(th), np.zeros_like(th), np.sin(th)])
    lower = np.column_stack([np.zeros(11), np.zeros(11), np.arange(-10.0, 1.0)])  # ends at origin
    upper = np.column_stack([np.zeros(11), np.zeros(11), np.arange(0.0, 11.0)])  # starts at origin
    x = np.vstack([lower, loop, upper])
    c = Chain(x, closed=False)
    assert c.excess_length() == pytest.approx(2 * np.pi, abs=1e-4)
    # along another axis: rotate everything
    q, _ = np.linalg.qr(np.random.default_rng(7).normal(size=(3, 3)))
    assert Chain(x @ q.T, closed=False).excess_length(axis=q @ [0, 0, 1]) == pytest.approx(
        2 * np.pi, abs=1e-4
    )
    # closed chain: ∮dz = 0
    assert regular_polygon(10).excess_length() == pytest.approx(10.0)


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


@pytest.mark.parametrize("suffix", [".xyz", ".json", ".npz", ".obj"])
def test_round_trips_exact(tmp_path, suffix):
    for k, c in enumerate(_sample_chains()):
        p = tmp_path / f"c{k}{suffix}"
        save(c, p)
        d = load(p)
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
    assert not from_xyz(tmp_path / "o.xyz").closed
    body = "\n".join(" ".join(repr(float(v)) for v in p) for p in o.coords)
    (tmp_path / "plain.xyz").write_text(body + "\n")
    assert np.array_equal(from_xyz(tmp_path / "plain.xyz").coords, o.coords)
    (tmp_path / "lammps.xyz").write_text("9\nTimestep 0 some words\n" + body + "\n")
    assert np.array_equal(from_xyz(tmp_path / "lammps.xyz").coords, o.coords)
    assert from_xyz(tmp_path / "plain.xyz", closed=True).closed
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
