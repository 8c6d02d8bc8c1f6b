"""Tests of the atlas index page (stiffknots.report.atlas.index_page) on six synthetic
knots: the table, the bounds, the family and structure tables."""

import re

import pytest

from atlas_support import BEAD_WIDTH, synthetic_families
from stiffknots.report.atlas import format_width, write_atlas
from stiffknots.theory import closed_bounds


def test_one_row_and_one_page_per_knot(atlas, rows, knots):
    assert list(rows) == [k["name"] for k in knots]
    for k in knots:
        r = rows[k["name"]]
        href = f"knots/{k['name']}.html"
        assert r["knot"]["links"] == [href] and r["knot"]["text"] == k["name"]
        assert (atlas.parent / href).is_file()
        assert r["n_c"]["text"] == str(k["crossing_number"])
        assert r["n"]["text"] == str(k["n"]) and r["i"]["text"] == str(k["i"])


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


def test_family_table(atlas):
    text = atlas.read_text(encoding="utf-8")
    m = re.search(r'<table id="families">(.*?)</table>', text, re.S)
    assert m
    plain = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", m.group(1)))
    assert "n_c &lt; 7" in m.group(1) and "n_c &lt; 9" in m.group(1)
    assert "CB(2) 2 (40 %) 2 (33 %)" in plain
    assert "CB(3) 0 (0 %) 1 (17 %)" in plain
    assert "knots 5 6" in plain


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


def test_an_audit_is_shown_under_its_verdict(tmp_path, knots, read_rows):
    import copy

    audited = copy.deepcopy([k for k in knots if k["name"] in ("3_1", "4_1")])
    audited[0]["models"]["bead"]["ground"]["audit"] = "false: 70.00 (CB(i=2))"
    audited[1]["models"]["bead"]["ground"]["audit"] = "held (3 searches)"
    index = write_atlas(tmp_path, audited, title="audited", thumbnails=False)
    rows = {a["data-name"]: c for a, c in read_rows(index.read_text(encoding="utf-8"))}
    assert rows["3_1"]["converged"]["spans"]["bead"].endswith("audit: false: 70.00 (CB(i=2))")
    assert rows["4_1"]["converged"]["spans"]["bead"].endswith("audit: held (3 searches)")
    assert "audit" not in rows["3_1"]["converged"]["spans"].get("tube", "")
    page = (tmp_path / "knots" / "3_1.html").read_text(encoding="utf-8")
    assert 'class="audit">audit: false: 70.00 (CB(i=2))</small>' in page
    with pytest.raises(ValueError, match="audit must be a text"):
        bad = copy.deepcopy(audited[:1])
        bad[0]["models"]["bead"]["ground"]["audit"] = 1
        write_atlas(tmp_path / "bad", bad, thumbnails=False)
