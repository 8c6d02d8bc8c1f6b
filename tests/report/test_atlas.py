"""Tests of the atlas pages (stiffknots.report.atlas) on six synthetic knots: the HTML itself.

The browser tests (the pages load, sort, filter and draw in chromium) are in
``test_atlas_browser.py``.
"""

import html
import json
import math
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from atlas_support import BEAD_WIDTH, TUBE_RADIUS, synthetic_families, synthetic_knots
from stiffknots.report.atlas import family_statistics, format_width, state_mesh, write_atlas
from stiffknots.report.render import DEFAULT_RADIUS
from stiffknots.theory import closed_bounds


class _Rows(HTMLParser):
    """The rows of the knot table: their attributes and the text and attributes of each cell."""

    def __init__(self):
        super().__init__()
        self.rows, self._in_body, self._cell = [], False, None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table" and a.get("id") == "knots":
            self._in_table = True
        if tag == "tbody" and getattr(self, "_in_table", False):
            self._in_body = True
        elif tag == "tr" and self._in_body:
            self.rows.append({"attrs": a, "cells": []})
        elif tag == "td" and self._in_body:
            self._cell = {"attrs": a, "text": "", "spans": {}, "links": [], "imgs": []}
            self.rows[-1]["cells"].append(self._cell)
            self._span = None
        elif self._cell is not None:
            if tag == "span" and "m" in (a.get("class") or "").split():
                self._span = a["class"].split()[1][2:]  # "m m-bead" -> "bead"
                self._cell["spans"][self._span] = ""
            elif tag == "a":
                self._cell["links"].append(a.get("href"))
            elif tag == "img":
                self._cell["imgs"].append(a.get("src"))

    def handle_endtag(self, tag):
        if tag == "tbody":
            self._in_body = False
            self._in_table = False
        elif tag == "td":
            self._cell = None
        elif tag == "span":
            self._span = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell["text"] += data
            if self._span is not None:
                self._cell["spans"][self._span] += data


COLS = ["thumb", "knot", "n_c", "n", "i", "bounds", "shape", "eps", "width", "converged",
        "metastable", "dmin", "families"]


@pytest.fixture(scope="module")
def knots():
    return synthetic_knots()


@pytest.fixture(scope="module")
def atlas(tmp_path_factory, knots):
    out = tmp_path_factory.mktemp("atlas")
    index = write_atlas(out, knots, families=synthetic_families(), title="Test atlas",
                        meta={"budget": "synthetic"})
    return index


@pytest.fixture(scope="module")
def rows(atlas):
    p = _Rows()
    p.feed(atlas.read_text(encoding="utf-8"))
    return {r["attrs"]["data-name"]: dict(zip(COLS, r["cells"], strict=True)) for r in p.rows}


def _script_json(text, element_id):
    m = re.search(rf'<script type="application/json" id="{element_id}">(.*?)</script>', text,
                  re.S)
    assert m, f"no {element_id} in the page"
    return json.loads(m.group(1))


def test_writes_index_pages_and_one_copy_of_plotly(atlas, knots):
    out = atlas.parent
    assert atlas == out / "index.html" and atlas.is_file()
    js = out / "plotly.min.js"
    assert js.stat().st_size > 1_000_000
    assert sorted(p.name for p in out.rglob("plotly*.js")) == ["plotly.min.js"]
    assert '<script src="plotly.min.js"></script>' in atlas.read_text(encoding="utf-8")
    for k in knots:
        page = out / "knots" / f"{k['name']}.html"
        text = page.read_text(encoding="utf-8")
        assert '<script src="../plotly.min.js"></script>' in text
        assert len(text) < 1_000_000  # plotly.js is referenced, not inlined
    assert len(atlas.read_text(encoding="utf-8")) < 500_000
    # the verdict's column says what a verdict is not (a proof of the ground state)
    assert "not proof that no lower state exists" in atlas.read_text(encoding="utf-8")
    # writing again keeps the identical plotly.js (not rewritten) and the pages
    mtime = js.stat().st_mtime_ns
    write_atlas(out, knots, families=synthetic_families(), title="Test atlas",
                meta={"budget": "synthetic"})
    assert js.stat().st_mtime_ns == mtime


def test_one_row_and_one_page_per_knot(atlas, rows, knots):
    assert list(rows) == [k["name"] for k in knots]
    for k in knots:
        r = rows[k["name"]]
        href = f"knots/{k['name']}.html"
        assert r["knot"]["links"] == [href] and r["knot"]["text"] == k["name"]
        assert (atlas.parent / href).is_file()
        assert r["n_c"]["text"] == str(k["crossing_number"])
        assert r["n"]["text"] == str(k["n"]) and r["i"]["text"] == str(k["i"])


def test_no_external_urls_in_the_pages(atlas):
    pages = [atlas, *sorted((atlas.parent / "knots").glob("*.html"))]
    assert len(pages) == 7
    for page in pages:
        text = page.read_text(encoding="utf-8")
        assert "://" not in text, f"{page.name} has an absolute URL"
        for ref in re.findall(r'(?:src|href)="([^"]*)"', text):
            assert not ref.startswith("//"), ref
            assert ref.startswith(("data:", "#")) or not re.match(r"^[a-z]+:", ref), ref


def test_every_epsilon_is_shown_with_its_width(rows, knots):
    for k in knots:
        r = rows[k["name"]]
        for model, m in k["models"].items():
            g = m["ground"]
            width = format_width(g.get("width", m.get("width")))
            assert r["eps"]["spans"][model] == f"{g['epsilon']:.2f}"
            assert float(r["eps"]["attrs"][f"data-v-{model}"]) == pytest.approx(g["epsilon"],
                                                                              abs=1e-6)
            assert r["width"]["spans"][model] == width
            assert r["dmin"]["spans"][model] == f"{g['min_segment_distance']:.3f}"
            label = g["shape"] + (f"({g['multiplicity']})" if g.get("multiplicity") else "")
            assert r["shape"]["spans"][model] == label
            assert r["converged"]["spans"][model] == ("yes" if g["converged"] else "no")
            for s in m["metastable"]:
                assert f"×{s['count']} ({s['epsilon']:.2f})" in r["metastable"]["spans"][model]
            assert r["metastable"]["attrs"][f"data-v-{model}"] == str(len(m["metastable"]))
    # 6_2 has no tube results: a dash and no sort value
    r = rows["6_2"]
    assert r["eps"]["spans"]["tube"] == "—" and "data-v-tube" not in r["eps"]["attrs"]
    assert "tube" not in "".join(r["thumb"]["imgs"])
    assert "w/L = 0.01, N = 150" == rows["3_1"]["width"]["spans"]["tube"]
    assert rows["3_1"]["width"]["spans"]["bead"] == BEAD_WIDTH


def test_bounds_are_the_thin_limit_bounds(rows, knots, atlas):
    for k in knots:
        b = closed_bounds(k["n"], k["i"])
        text = rows[k["name"]]["bounds"]["text"]
        assert text.startswith(f"{b.lower:.2f} – {b.upper:.2f}")
        assert ("exact" in text) == (k["n"] == k["i"])
    assert "thin limit" in atlas.read_text(encoding="utf-8")


def test_thumbnails_are_png_files_next_to_the_page(rows, atlas, knots):
    n = 0
    for k in knots:
        imgs = rows[k["name"]]["thumb"]["imgs"]
        assert len(imgs) == len(k["models"])
        for src in imgs:
            data = (atlas.parent / src).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n"
            n += 1
    assert n == 9


def test_knot_pages_show_every_state(atlas, knots):
    for k in knots:
        text = (atlas.parent / "knots" / f"{k['name']}.html").read_text(encoding="utf-8")
        plain = html.unescape(re.sub(r"<[^>]+>", " ", text))
        states = _script_json(text, "states-data")
        n_states = 0
        for _model, m in k["models"].items():
            width = format_width(m.get("width") or m["ground"].get("width"))
            for s in [m["ground"], *m["metastable"]]:
                n_states += 1
                assert f"{s['epsilon']:.2f}" in plain
                assert f"{s['min_segment_distance']:.3f}" in plain
                assert f"{s['count']} / {m['replicas']}" in plain
                assert width in plain
        assert len(states) == n_states
        for st in states:
            assert len(st["v"]) == st["rings"] * st["sides"] * 3
            assert len(st["t"]) == st["rings"] == 150
            assert " at " in st["caption"] and "ε = " in st["caption"]
        b = closed_bounds(k["n"], k["i"])
        assert f"{b.lower:.2f} ≤ ε* ≤ {b.upper:.2f}" in plain


def test_eps_figure_has_every_knot_and_the_bounds(atlas, knots):
    fig = _script_json(atlas.read_text(encoding="utf-8"), "eps-data")
    by_model = {}
    for t in fig["data"]:
        model = (t.get("meta") or {}).get("model")
        if model:
            by_model.setdefault(model, []).extend(
                zip(t["customdata"], t["x"], t["y"], strict=True))
            assert t["visible"] == (model == "bead")
    assert {m: len(v) for m, v in by_model.items()} == {"bead": 6, "tube": 3}
    eps = {k["name"]: k for k in knots}
    for cd, x, y in by_model["bead"]:
        k = eps[cd[0]]
        assert abs(x - k["n"] ** 2) <= 0.8 + 1e-12
        assert y == pytest.approx(k["models"]["bead"]["ground"]["epsilon"])
        assert cd[4] == BEAD_WIDTH  # the width goes with every point
    lower = next(t for t in fig["data"] if t["name"].startswith("lower bound"))
    assert lower["y"][1] / lower["x"][1] == pytest.approx(2 * math.pi**2)
    cb = next(t for t in fig["data"] if t["name"].startswith("circular braid"))
    assert sorted(set(np.round(cb["y"], 6))) == pytest.approx(
        [2 * math.pi**2 * 4, 2 * math.pi**2 * 9])


def test_family_table(atlas):
    text = atlas.read_text(encoding="utf-8")
    m = re.search(r'<table id="families">(.*?)</table>', text, re.S)
    assert m
    plain = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", m.group(1)))
    assert "n_c &lt; 7" in m.group(1) and "n_c &lt; 9" in m.group(1)
    assert "CB(2) 2 (40 %) 2 (33 %)" in plain
    assert "CB(3) 0 (0 %) 1 (17 %)" in plain
    assert "knots 5 6" in plain


def test_family_statistics_from_the_knots(knots):
    f = family_statistics(knots)
    assert f["model"] == "bead"
    # every knot has n_c < 9: that column equals "all knots" and is left out
    assert [g["label"] for g in f["groups"]] == ["n_c < 7", "all knots"]
    assert f["groups"][0] == {"label": "n_c < 7", "total": 5,
                              "counts": {"CB(2)": 2, "4C": 2, "other": 1}}
    assert f["groups"][1]["total"] == 6 and f["groups"][1]["counts"]["CB(3)"] == 1
    t = family_statistics(knots, model="tube", max_crossings=[5])
    assert t["groups"] == [{"label": "n_c < 5", "total": 2, "counts": {"CB(2)": 1, "4C": 1}},
                           {"label": "all knots", "total": 3,
                            "counts": {"CB(2)": 2, "4C": 1}}]


def test_atlas_json_summary(atlas, knots):
    data = json.loads((atlas.parent / "atlas.json").read_text(encoding="utf-8"))
    assert [k["name"] for k in data["knots"]] == [k["name"] for k in knots]
    s = data["knots"][1]["models"]["bead"]["states"]
    assert [x["shape"] for x in s] == ["4C", "80"]
    assert s[0]["width"] == BEAD_WIDTH and "coords" not in s[0]
    assert data["meta"]["budget"] == "synthetic" and "stiffknots" in data["meta"]


def test_state_mesh_is_a_proper_rotation_of_the_chain(knots):
    x = np.asarray(knots[1]["models"]["bead"]["ground"]["coords"])
    m = state_mesh(x, n_sides=8)
    v = np.asarray(m["v"]).reshape(m["rings"], m["sides"], 3)
    centres = v.mean(axis=1)  # the mitre ellipse is symmetric about its bead
    a = x - x.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ centres)
    rot = u @ vt
    assert np.linalg.det(rot) == pytest.approx(1.0)  # never a mirror image
    assert np.abs(a @ rot - centres).max() < 5e-3
    assert m["t"][0] == 0.0 and 0.99 < m["t"][-1] < 1.0
    assert max(m["aspect"].values()) == pytest.approx(1.8)
    # the tube radius: every vertex at least that far from its bead, the nearest exactly
    for radius, mesh in [(DEFAULT_RADIUS, m), (0.75, state_mesh(x, radius=0.75, n_sides=8))]:
        v = np.asarray(mesh["v"]).reshape(mesh["rings"], mesh["sides"], 3)
        d = np.linalg.norm(v - v.mean(axis=1, keepdims=True), axis=2)
        assert d.min() == pytest.approx(radius, abs=2e-3)


def test_the_drawing_radius_reaches_the_3d_view(atlas):
    text = (atlas.parent / "knots" / "4_1.html").read_text(encoding="utf-8")
    states = _script_json(text, "states-data")
    assert [s["label"].split(" — ")[0] for s in states] == ["bead", "bead", "tube"]
    for s, radius in zip(states, [DEFAULT_RADIUS, DEFAULT_RADIUS, TUBE_RADIUS], strict=True):
        v = np.asarray(s["v"]).reshape(s["rings"], s["sides"], 3)
        d = np.linalg.norm(v - v.mean(axis=1, keepdims=True), axis=2)
        assert d.min() == pytest.approx(radius, abs=2e-3)


def test_zones_reach_the_3d_view_and_bad_ones_are_refused(tmp_path, atlas, knots):
    """A state's zones (each bead's contact-zone kind, §V B) travel with its mesh, one code a
    ring, and the page offers the colouring; zones that do not fit the chain are refused."""
    text = (atlas.parent / "knots" / "4_1.html").read_text(encoding="utf-8")
    states = _script_json(text, "states-data")
    ground = next(k for k in knots if k["name"] == "4_1")["models"]["bead"]["ground"]
    assert states[0]["zones"] == list(ground["zones"]) and len(states[0]["zones"]) == \
        states[0]["rings"]
    assert states[1]["zones"] is None  # the 80 was given none
    assert 'id="colour-select"' in text and "multiple point" in text
    plain = (atlas.parent / "knots" / "3_1.html").read_text(encoding="utf-8")
    assert 'id="colour-select"' not in plain  # no state of 3_1 has zones
    x = np.asarray(ground["coords"])
    n = len(x)
    # too few; a code out of range; not integers; a string
    for zones in ([0] * (n - 1), [0] * (n - 1) + [4], [0.5] * n, "0" * n):
        bad = {**knots[0], "models": {"bead": {"width": "w", "ground": {
            "epsilon": 1.0, "coords": x, "zones": zones}}}}
        with pytest.raises(ValueError, match=rf"zones must be {n} integers \(one per bead"):
            write_atlas(tmp_path, [bad])
    lone = {**knots[0], "models": {"bead": {"width": "w", "ground": {
        "epsilon": 1.0, "zones": [0] * n}}}}
    with pytest.raises(ValueError, match="need the state's coords"):
        write_atlas(tmp_path, [lone])


def test_input_errors_say_what_is_wrong(tmp_path, knots):
    k = knots[0]
    no_width = {**k, "models": {"bead": {"ground": {"shape": "CB", "epsilon": 79.0}}}}
    with pytest.raises(ValueError, match="no width"):
        write_atlas(tmp_path, [no_width])
    bare = {**k, "models": {"bead": {"width": 0.01, "ground": {"epsilon": 79.0}}}}
    with pytest.raises(ValueError, match="bare number"):
        write_atlas(tmp_path, [bare])
    with pytest.raises(ValueError, match="appears twice"):
        write_atlas(tmp_path, [k, k])
    bad = {**k, "models": {"bead": {"width": "w", "ground": {"epsilon": 1.0,
                                                            "coords": [[0, 0, 0]]}}}}
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        write_atlas(tmp_path, [bad])
    with pytest.raises(ValueError, match="default_model"):
        write_atlas(tmp_path, knots, default_model="nope")
    named = {**k, "models": {"bead": {"width": "w", "ground": {"epsilon": 1.0,
                                                              "structure": 3}}}}
    with pytest.raises(ValueError, match="structure must be a text"):
        write_atlas(tmp_path, [named])
    fam = {"groups": [], "structures": {"rows": [{"structure": "double point"}]}}
    with pytest.raises(ValueError, match="needs 'structure' .* and 'knots'"):
        write_atlas(tmp_path, knots, families=fam)
    fam["structures"]["rows"][0]["knots"] = "7_4"  # a name, not a list of names
    with pytest.raises(ValueError, match="needs 'structure' .* and 'knots'"):
        write_atlas(tmp_path, knots, families=fam)
    assert not (tmp_path / "index.html").exists()


def test_structures_are_escaped_and_linked(tmp_path, knots):
    """A state's structure (§V B) shows on its knot page and as the index badge's tooltip;
    the families' table of structures links the knots that have a page, escaped."""
    k = {**knots[0], "models": {"bead": {"width": "w", "ground": {
        "shape": "other", "epsilon": 171.2, "structure": "2 line-braids <m = 2>"}}}}
    fam = {"groups": [{"label": "all", "total": 1, "counts": {"other": 1}}],
           "structures": {"title": "by structure", "rows": [
               {"structure": "2 line-braids <m = 2>", "knots": [k["name"], "99_9"],
                "shapes": {"other": 2}, "epsilon": [171.2, 181.5]}]}}
    idx = write_atlas(tmp_path, [k], families=fam, thumbnails=False)
    html = idx.read_text(encoding="utf-8")
    assert 'title="2 line-braids &lt;m = 2&gt;"' in html
    # the filter box finds a knot by its structure's words
    assert re.search(r'data-search-bead="[^"]*2 line-braids &lt;m = 2&gt;', html)
    assert f'<a href="knots/{k["name"]}.html">{k["name"]}</a>, 99_9' in html
    assert '<td class="num">171.20 – 181.50</td>' in html
    page = (tmp_path / "knots" / f"{k['name']}.html").read_text(encoding="utf-8")
    assert "<td>2 line-braids &lt;m = 2&gt;</td>" in page


def test_hostile_names_are_escaped(tmp_path):
    name = '</script><img src=x onerror="alert(1)">'
    idx = write_atlas(tmp_path, [{"name": name, "n": 2, "i": 2, "note": "<b>bold?</b>",
                                  "models": {"bead": {"width": "w </script>",
                                                      "ground": {"shape": "CB<>",
                                                                 "epsilon": 80.0}}}}],
                      thumbnails=False)
    pages = [idx, *(tmp_path / "knots").glob("*.html")]
    assert len(pages) == 2 and all(re.fullmatch(r"[\w.-]+\.html", p.name) for p in pages)
    for p in pages:
        text = p.read_text(encoding="utf-8")
        assert "<img src=x" not in text and "<b>bold?</b>" not in text
        assert "</script><" not in text.replace("</script>\n", "")


def test_import_sets_no_matplotlib_backend():
    code = ("import matplotlib; matplotlib.use('svg'); import stiffknots.report.atlas; "
            "print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).parent)
    assert out.stdout.strip() == "svg"


def test_knots_without_results_still_get_a_row_and_a_page(tmp_path):
    idx = write_atlas(tmp_path, [{"name": "0_1"}, {"name": "K11n34", "crossing_number": 11,
                                                   "n": 3, "i": 4}])
    text = idx.read_text(encoding="utf-8")
    p = _Rows()
    p.feed(text)
    assert [r["attrs"]["data-name"] for r in p.rows] == ["0_1", "K11n34"]
    cells = dict(zip(COLS, p.rows[0]["cells"], strict=True))
    assert cells["bounds"]["text"] == "—" and cells["n"]["text"] == "—"
    b = closed_bounds(3, 4)
    assert dict(zip(COLS, p.rows[1]["cells"], strict=True))["bounds"]["text"].startswith(
        f"{b.lower:.2f} – {b.upper:.2f}")
    assert 'id="model"' not in text and 'id="families"' not in text
    page = (tmp_path / "knots" / "K11n34.html").read_text(encoding="utf-8")
    assert "No computed states" in page and "states-data" not in page
    assert not (tmp_path / "thumbs").exists()


def test_a_segment_distance_below_a_thousandth_is_not_shown_as_zero(tmp_path, knots):
    """Under the bead rule two segments may close to the no-passage guard's gap (10⁻⁴): the
    index and the knot page show 1.0e-04, not 0.000."""
    import copy

    ks = copy.deepcopy(knots)
    ks[0]["models"]["bead"]["ground"]["min_segment_distance"] = 1.0e-4
    idx = write_atlas(tmp_path, ks, families=synthetic_families(), thumbnails=False)
    index = idx.read_text(encoding="utf-8")
    page = (tmp_path / "knots" / f"{ks[0]['name']}.html").read_text(encoding="utf-8")
    for text in (index, page):
        assert ">1.0e-04<" in text
    assert ">0.000<" not in index
