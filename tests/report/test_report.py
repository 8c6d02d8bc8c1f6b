"""Tests of stiffknots.report: tube rendering, report figures and the report document."""

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from stiffknots.chain import Chain  # noqa: E402
from stiffknots.knots.embedding import embed_braid, regular_polygon  # noqa: E402
from stiffknots.report.document import Document, format_cell  # noqa: E402
from stiffknots.report.figures import (  # noqa: E402
    plot_annealing_curves,
    plot_eps_vs_n2,
    plot_tension,
    save_figure,
)
from stiffknots.report.render import (  # noqa: E402
    DEFAULT_RADIUS,
    best_view,
    contact_pairs,
    plot_chain,
    plot_tube,
    save_chain_png,
    tube_mesh,
)


def torus_knot(n=90, p=2, q=3, R=6.0, r=2.0):
    """A smooth (p, q) torus knot sampled at n points (non-planar: the frame has holonomy)."""
    t = 2 * np.pi * np.arange(n) / n
    rr = R + r * np.cos(q * t)
    return np.column_stack([rr * np.cos(p * t), rr * np.sin(p * t), r * np.sin(q * t)])


def point_segment_distance(p, a, b):
    """Distances from points p (M, 3) to segments [a_k, b_k] (K, 3): array (M, K)."""
    ab = b - a
    t = np.einsum("mkj,kj->mk", p[:, None, :] - a[None], ab) / np.einsum("kj,kj->k", ab, ab)
    t = np.clip(t, 0.0, 1.0)
    foot = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(p[:, None, :] - foot, axis=2)


def bond_ends(x, closed):
    return (x, np.roll(x, -1, axis=0)) if closed else (x[:-1], x[1:])


# ---------------------------------------------------------------------------- the tube mesh


@pytest.mark.parametrize("closed", [True, False])
def test_tube_mesh_counts(closed):
    x = torus_knot(50)
    m = tube_mesh(x, 0.3, closed=closed, n_sides=9)
    assert m.vertices.shape == (50, 9, 3)
    assert m.points.shape == (450, 3)
    n_faces = 50 * 9 if closed else 49 * 9
    assert m.quads.shape == (n_faces, 4)
    assert m.caps.shape == ((0, 9) if closed else (2, 9))
    assert m.quads.min() == 0 and m.quads.max() == 449
    # every vertex is used by exactly 4 quads (closed) / 2 or 4 (open: end rings)
    counts = np.bincount(m.quads.ravel(), minlength=450)
    if closed:
        assert np.all(counts == 4)
    else:
        assert np.all(counts[9:-9] == 4) and np.all(counts[:9] == 2) and np.all(counts[-9:] == 2)


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("coords", [torus_knot(80), regular_polygon(40)], ids=["torus", "ring"])
def test_tube_vertices_at_radius_from_centre_line(coords, closed):
    r = DEFAULT_RADIUS
    s = 12
    m = tube_mesh(coords, r, closed=closed, n_sides=s)
    a, b = bond_ends(coords, closed)
    u = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    # each face between rings k and k+1 lies on the cylinder of radius r around bond k: all
    # its corners are at distance r from the line of the bond (mitred joints)
    corners = m.points[m.quads]  # (F, 4, 3)
    bond = m.quads[:, 0] // s
    rel = corners - a[bond][:, None, :]
    perp = rel - np.einsum("fcj,fj->fc", rel, u[bond])[..., None] * u[bond][:, None, :]
    np.testing.assert_allclose(np.linalg.norm(perp, axis=2), r, rtol=1e-9)
    # and from the centre line as a point set: r, up to the mitre stretch 1/cos(bend/2) at
    # the outer side of the (small) bends
    d = point_segment_distance(m.points, a, b).min(axis=1)
    cos_bend = np.einsum("ij,ij->i", u[1:], u[:-1]).min()
    cos_half = np.sqrt((1 + cos_bend) / 2)
    assert np.all(d >= r * (1 - 1e-9))
    assert np.all(d <= r / cos_half * (1 + 1e-9))
    assert d.max() < 1.01 * r
    # the rings are centred on the beads
    np.testing.assert_allclose(m.vertices.mean(axis=1), coords, atol=1e-9)


def test_tube_does_not_twist():
    # consecutive rings are joined vertex to vertex: edges along the tube are as long as the
    # bonds (a twist would make them longer), also across the seam of a closed chain
    x = torus_knot(120)
    m = tube_mesh(x, 0.3, closed=True, n_sides=10)
    along = np.linalg.norm(m.vertices - np.roll(m.vertices, -1, axis=0), axis=2)
    bonds = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    assert np.all(along <= bonds[:, None] + 2 * 0.3 * 0.12)
    # a planar ring: the parallel-transport frame needs no correction, all rings alike
    p = regular_polygon(30)
    m = tube_mesh(p, 0.2, closed=True, n_sides=6)
    rel = m.vertices - p[:, None, :]
    z = rel[:, :, 2]
    np.testing.assert_allclose(z, np.tile(z[:1], (30, 1)), atol=1e-12)


def test_tube_mesh_errors():
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        tube_mesh(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="at least 3 beads"):
        tube_mesh(np.eye(3)[:2])
    with pytest.raises(ValueError, match="NaN"):
        tube_mesh(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]))
    with pytest.raises(ValueError, match="radius"):
        tube_mesh(regular_polygon(10), radius=0.0)
    with pytest.raises(ValueError, match="n_sides"):
        tube_mesh(regular_polygon(10), n_sides=2)
    with pytest.raises(ValueError, match="coincide"):
        tube_mesh(np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0]]), closed=False)


def test_best_view_is_a_proper_rotation():
    # A torus knot stretched to three distinct principal variances, then turned at random:
    # the round torus knot has two equal variances, whose order is a matter of rounding.
    q, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
    x = (torus_knot(60) * np.array([1.0, 1.6, 0.5])) @ q.T
    rot, (elev, azim) = best_view(x)
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)  # never a mirror image of the knot
    y = (x - x.mean(axis=0)) @ rot
    var = y.var(axis=0)
    assert var[0] > var[1] > var[2]
    # the principal variances, largest first, and no correlation left between the axes
    np.testing.assert_allclose(var, np.sort(np.linalg.eigvalsh(np.cov(x.T, bias=True)))[::-1])
    np.testing.assert_allclose(np.cov(y.T, bias=True), np.diag(var), atol=1e-9)
    assert 0 < elev <= 90
    # a planar ring is seen nearly from above
    assert best_view(regular_polygon(20))[1][0] > 70


def test_contact_pairs():
    x = regular_polygon(12)
    assert contact_pairs(x, 1.01) == []  # only neighbours are that close
    folded = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0.8, 0], [1, 0.8, 0], [0, 0.8, 0]],
                      dtype=float)
    assert contact_pairs(folded, 0.9, closed=False) == [(0, 5), (1, 4)]


# ---------------------------------------------------------------------------- pictures


def test_save_chain_png_writes_an_image(tmp_path):
    x = embed_braid([1, 1, 1], n_beads=150)
    out = save_chain_png(x, tmp_path / "sub" / "trefoil.png", title="3_1", contacts=0.8)
    assert out.exists() and out.stat().st_size > 1000
    img = mpimg.imread(out)
    assert img.shape[:2] == (600, 600) and img.shape[2] in (3, 4)
    assert img[..., :3].std() > 0.02  # not blank
    # tight framing: the tube reaches close to the edges of the picture
    ink = np.argwhere(img[..., :3].min(axis=2) < 0.9)
    assert ink[:, 1].min() < 60 and ink[:, 1].max() > 540
    assert not plt.get_fignums()  # the figure was closed


def test_plot_tube_variants():
    x = embed_braid([1, 1, 1], n_beads=150)
    ax = plot_tube(x, title="trefoil")
    assert ax.name == "3d" and len(ax.collections) == 1
    assert ax.get_title() == "trefoil"
    plt.close(ax.figure)
    # open chain, single colour, explicit contacts and view
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    plot_tube(x[:60], ax, closed=False, color="tab:orange", contacts=[(0, 10), (5, 40)],
              view=(20, 30), radius=0.5)
    assert ax.elev == 20 and ax.azim == 30
    assert len(ax.collections) == 3  # tube, contact segments, contact dots
    plt.close(fig)
    # a Chain object, open: closure taken from it; the old plot_chain entry point
    ax = plot_chain(Chain(x[:50], closed=False), contacts=1.2)
    plt.close(ax.figure)


def test_plot_tube_errors():
    x = regular_polygon(20)
    with pytest.raises(ValueError, match="out of range"):
        plot_tube(x, contacts=[(0, 20)])
    fig, ax2d = plt.subplots()
    with pytest.raises(ValueError, match="3D axis"):
        plot_tube(x, ax2d)
    plt.close("all")
    with pytest.raises(ValueError):
        plot_tube([[0, 0], [1, 1], [2, 2]])


# ---------------------------------------------------------------------------- figures


class _Trace:
    """Looks like a ReplicaResult: trace_* arrays and a replica number."""

    def __init__(self, replica, moves, temperature, epsilon):
        self.replica = replica
        self.trace_moves = moves
        self.trace_temperature = temperature
        self.trace_epsilon = epsilon


def _traces():
    m = np.arange(1, 101) * 1000
    t = np.where(m <= 90_000, 1e-2 * (1 + m / 1e3) ** -1.5, 0.0)
    return [
        {"moves": m, "temperature": t, "epsilon": 80 + 300 * np.exp(-m / 2e4)},
        _Trace(1, m, t, 130 + 250 * np.exp(-m / 1e4)),
    ]


def test_plot_annealing_curves(tmp_path):
    ax = plot_annealing_curves(_traces(), references={"4-fold cage": 129.6})
    assert len(ax.get_lines()) >= 2
    assert ax.temperature_axis.get_yscale() == "log"
    assert ax.get_xscale() == "log"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["replica 0", "replica 1"]
    path = save_figure(ax, tmp_path / "anneal.png")
    assert mpimg.imread(path).shape[0] > 100
    with pytest.raises(ValueError, match="no traces"):
        plot_annealing_curves([])
    with pytest.raises(ValueError, match="missing field"):
        plot_annealing_curves([{"moves": [1, 2], "epsilon": [3, 4]}])
    with pytest.raises(ValueError, match="one length"):
        plot_annealing_curves([{"moves": [1, 2], "temperature": [1.0], "epsilon": [3, 4]}])
    plt.close("all")


def test_plot_eps_vs_n2(tmp_path):
    pts = [
        {"knot": "3_1", "n": 2, "i": 2, "epsilon": 79.3, "shape": "circular braid"},
        {"knot": "4_1", "n": 2, "i": 3, "epsilon": 129.6, "shape": "4-fold cage"},
        {"knot": "6_2", "n": 2, "i": 3, "epsilon": 143.0, "shape": "80"},
        {"knot": "8_19", "n": 3, "i": 3, "epsilon": 178.0},
        {"knot": "x", "n": 2, "i": None, "epsilon": 150.0, "shape": "new shape"},
    ]
    ax = plot_eps_vs_n2(pts, title="closed")
    ydata = [line.get_ydata() for line in ax.get_lines()]
    # the general lower bound 2 pi^2 n^2 is drawn as a line through the origin
    slope = 2 * math.pi**2
    assert any(len(y) == 2 and y[0] == 0 and np.isclose(y[1] / ax.get_lines()[0].get_xdata()[1],
                                                       slope) for y in ydata)
    names = {t.get_text() for t in ax.texts}
    assert {"3_1", "4_1", "6_2", "8_19", "x"} <= names
    save_figure(ax.figure, tmp_path / "eps.png")
    ax = plot_eps_vs_n2(pts[:2], bounds=False, labels=False)
    assert not ax.texts
    plt.close("all")
    with pytest.raises(ValueError, match="lacks"):
        plot_eps_vs_n2([{"knot": "3_1", "n": 2}])
    with pytest.raises(ValueError, match="braid index"):
        plot_eps_vs_n2([{"knot": "bad", "n": 3, "i": 2, "epsilon": 1.0}])
    plt.close("all")


def test_plot_tension(tmp_path):
    pts = [{"knot": "3_1", "L_e": L, "mu": 2 * math.pi**2 / L**2, "n": 2, "i": 2}
           for L in (20.0, 30.0)]
    pts.append({"knot": "4_1", "L_e": 25.0, "mu": 0.05, "n": 2, "i": 3})
    ax = plot_tension(pts)
    # the open trefoil's exact line mu = 2 pi^2 / L_e^2 passes through its points
    x_max = ax.get_xlim()[1]
    exact = [ln for ln in ax.get_lines()
             if len(ln.get_xdata()) == 2 and np.isclose(ln.get_ydata()[1],
                                                        2 * math.pi**2 * x_max)]
    assert exact
    save_figure(ax, tmp_path / "tension.svg")
    assert (tmp_path / "tension.svg").read_text().lstrip().startswith("<?xml")
    with pytest.raises(ValueError, match="L_e must be > 0"):
        plot_tension([{"knot": "3_1", "L_e": 0.0, "mu": 1.0, "n": 2, "i": 2}])
    plt.close("all")


# ---------------------------------------------------------------------------- document


def test_document_markdown_and_html(tmp_path):
    img = tmp_path / "figs" / "best.png"
    doc = (Document("Report <3_1> & co")
           .heading("Results")
           .paragraph("We find **ε = 83.0** with `N < 150 & more` and $\\varepsilon < 2\\pi^2$.")
           .table(["knot", "ε", "note"], [["3_1", 83.0334, "a|b"], ["4_1", None, "<i>"]])
           .image(img, "Fig. 1: the <tube>", width=300)
           .code("x = 1 < 2")
           .bullets(["one & two", "**three**"]))
    md = doc.to_markdown()
    lines = md.splitlines()
    assert lines[0] == "# Report &lt;3_1&gt; &amp; co"
    assert "| knot | ε | note |" in lines
    k = lines.index("| knot | ε | note |")
    assert lines[k + 1] == "| --- | ---: | --- |"
    assert lines[k + 2] == "| 3_1 | 83.0334 | a\\|b |"
    assert lines[k + 3] == "| 4_1 | — | &lt;i&gt; |"
    assert "`N < 150 & more`" in md  # code spans are verbatim
    assert "- one &amp; two" in md

    html_text = doc.to_html()
    assert html_text.startswith("<!DOCTYPE html>") and "<style>" in html_text
    assert "<title>Report &lt;3_1&gt; &amp; co</title>" in html_text
    assert "<tube>" not in html_text and "&lt;tube&gt;" in html_text
    assert "<code>N &lt; 150 &amp; more</code>" in html_text
    assert "<strong>ε = 83.0</strong>" in html_text
    assert "$\\varepsilon &lt; 2\\pi^2$" in html_text
    assert "<td>&lt;i&gt;</td>" in html_text
    assert "<th" in html_text and "border" in html_text

    paths = doc.write(tmp_path)
    assert paths["markdown"].name == "report.md" and paths["html"].name == "report.html"
    written = paths["html"].read_text(encoding="utf-8")
    assert 'src="figs/best.png"' in written  # absolute path made relative to the folder
    assert "figs/best.png" in paths["markdown"].read_text(encoding="utf-8")


def test_document_markdown_escaping():
    doc = Document("t").paragraph("ε* and ε* stay stars; _x_ and [link](y)").paragraph(
        "1. not a list").paragraph("# not a heading").paragraph("- not an item")
    md = doc.to_markdown()
    assert "ε\\* and ε\\* stay stars; \\_x\\_ and \\[link\\](y)" in md
    assert "\n1\\. not a list\n" in md
    assert "\n\\# not a heading\n" in md
    assert "\n\\- not an item\n" in md
    assert "3_1" in Document("3_1").to_markdown()  # intraword underscores kept
    code = Document("t").code("```\ninner\n```").to_markdown()
    assert "````\n```\ninner\n```\n````" in code


def test_document_errors_and_cells():
    with pytest.raises(ValueError):
        Document("")
    doc = Document("t")
    with pytest.raises(ValueError, match="level"):
        doc.heading("h", 7)
    with pytest.raises(ValueError, match="row 0"):
        doc.table(["a", "b"], [[1]])
    with pytest.raises(ValueError, match="stem"):
        doc.write("/tmp", stem="a/b")
    assert format_cell(None) == "—"
    assert format_cell(1 / 3) == "0.333333"
    assert format_cell(np.float64(2.5)) == "2.5"
    assert format_cell(True) == "yes"
