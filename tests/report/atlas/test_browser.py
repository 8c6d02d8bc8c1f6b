"""The atlas pages in a real headless browser: Debian's chromium driven by Playwright.

Chromium is installed with apt-get when it is missing (we are root on the project's machines);
the tests skip, saying why, only if that fails. Playwright's own browser download is never
used: the browser is ``/usr/bin/chromium`` with the flags of ``atlas_support.CHROMIUM_ARGS``
(WebGL on SwiftShader, so that plotly's 3D views render without a GPU).

Every page is opened from disk (``file://``), and any request that is not for a local file
fails the test: the pages must work with no network.
"""

import io
import re

import numpy as np
import pytest

from atlas_support import (
    chromium_context,
    find_chromium,
    synthetic_catalogue_rows,
    synthetic_families,
    synthetic_knots,
)
from stiffknots.report.atlas import write_atlas

pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install "
                    "-e '.[dev]')")

_LOCAL = ("file:", "data:", "blob:", "about:")


@pytest.fixture(scope="module")
def chromium():
    exe = find_chromium(install=True)
    if exe is None:
        pytest.skip("Debian's chromium is missing and `apt-get install -y chromium` failed")
    return exe


@pytest.fixture(scope="module")
def atlas(tmp_path_factory):
    out = tmp_path_factory.mktemp("atlas-browser")
    return write_atlas(out, synthetic_knots(), families=synthetic_families(),
                       title="Browser test atlas")


class Watched:
    """A page whose console errors, page errors and non-local requests are recorded."""

    def __init__(self, page):
        self.page, self.errors, self.remote = page, [], []
        page.on("console", lambda m: self.errors.append(f"console: {m.text}")
                if m.type == "error" else None)
        page.on("pageerror", lambda e: self.errors.append(f"pageerror: {e}"))
        page.on("request", lambda r: None if r.url.startswith(_LOCAL)
                else self.remote.append(r.url))

    def check(self):
        assert self.errors == [], self.errors
        assert self.remote == [], f"requests to the network: {self.remote}"


@pytest.fixture(scope="module")
def context(chromium):
    with chromium_context(chromium) as ctx:
        yield ctx


@pytest.fixture
def page(context):
    p = context.new_page()
    w = Watched(p)
    yield w
    p.close()


def _column(page, header: str) -> int:
    heads = page.locator("#knots thead th").all_inner_texts()
    return next(k for k, h in enumerate(heads) if h.strip().startswith(header))


def _visible(page):
    return page.eval_on_selector_all(
        "#knots tbody tr", "rs => rs.filter(r => !r.hidden).map(r => r.dataset.name)")


def _column_values(page, col: int) -> list[str]:
    return page.eval_on_selector_all(
        "#knots tbody tr",
        f"rs => rs.filter(r => !r.hidden).map(r => r.cells[{col}].innerText.trim())")


def test_index_loads_sorts_and_filters(page, atlas):
    p = page.page
    p.goto(atlas.as_uri())
    p.wait_for_selector("#eps-plot.js-plotly-plot .main-svg")
    names = ["3_1", "4_1", "5_1", "5_2", "6_2", "8_19"]
    assert _visible(p) == names
    assert p.locator("#count").inner_text() == "6 of 6 knots shown"

    # sort by ε: numerically (as text, "135.11" < "78.93"), then the other way
    col = _column(p, "ε (ground)")
    p.locator("#knots thead th").nth(col).locator("button").click()
    eps = [float(v) for v in _column_values(p, col)]
    assert eps == sorted(eps) and len(eps) == 6
    assert eps[0] < 80 < eps[-1]
    assert p.locator("#knots thead th").nth(col).get_attribute("aria-sort") == "ascending"
    p.locator("#knots thead th").nth(col).locator("button").click()
    assert [float(v) for v in _column_values(p, col)] == sorted(eps, reverse=True)

    # the tube model: 3 knots have values, the other 3 (a dash) stay last in both directions
    p.select_option("#model", "tube")
    vals = _column_values(p, col)
    assert vals[3:] == ["—"] * 3
    tube = [float(v) for v in vals[:3]]
    assert tube == sorted(tube, reverse=True)
    p.locator("#knots thead th").nth(col).locator("button").click()
    vals = _column_values(p, col)
    assert [float(v) for v in vals[:3]] == sorted(tube) and vals[3:] == ["—"] * 3
    p.select_option("#model", "bead")

    # names sort naturally
    p.locator("#knots thead th").nth(_column(p, "knot")).locator("button").click()
    assert _visible(p) == names

    # filters: text (name, shapes, families) and ground shape
    p.fill("#filter", "4c")
    assert _visible(p) == ["4_1", "5_2"]
    p.fill("#filter", "8_19")
    assert _visible(p) == ["8_19"]
    assert p.locator("#count").inner_text() == "1 of 6 knots shown"
    p.fill("#filter", "")
    p.select_option("#shape-filter", "CB(2)")
    assert _visible(p) == ["3_1", "5_1"]
    p.select_option("#shape-filter", "")
    assert len(_visible(p)) == 6

    # the ε–n² plot: one point per knot of the model shown
    n_points = p.evaluate("""() => document.getElementById('eps-plot').data
        .filter(t => t.meta && t.meta.model && t.visible !== false)
        .reduce((s, t) => s + t.x.length, 0)""")
    assert n_points == 6
    assert p.locator("#eps-plot .scatterlayer .trace .points path").count() >= 6
    assert p.locator("#families tbody tr").count() == 5  # 4 shapes and the totals
    page.check()


def _nonblank_fraction(png: bytes) -> tuple[float, int]:
    import matplotlib.image as mpimg

    img = mpimg.imread(io.BytesIO(png))[..., :3]
    ink = np.any(img < 0.9, axis=-1)
    colours = len({tuple(c) for c in np.round(img[ink] * 8).astype(int)})
    return float(ink.mean()), colours


def _grey_fraction(png: bytes) -> float:
    """The fraction of the drawn (non-white) pixels that are grey (no hue)."""
    import matplotlib.image as mpimg

    img = mpimg.imread(io.BytesIO(png))[..., :3]
    ink = np.any(img < 0.9, axis=-1)
    spread = img.max(axis=-1) - img.min(axis=-1)
    return float((spread[ink] < 0.08).mean())


def test_knot_page_renders_each_state_in_3d(page, atlas):
    p = page.page
    p.goto((atlas.parent / "knots" / "4_1.html").as_uri())
    p.wait_for_selector("#view3d.js-plotly-plot .gl-container canvas")
    p.wait_for_timeout(300)
    assert "WebGL is not supported" not in p.inner_text("body")
    assert p.locator("#view3d").evaluate("d => d.data[0].type") == "mesh3d"
    shot = p.locator("#view3d").screenshot()
    ink, colours = _nonblank_fraction(shot)
    assert 0.01 < ink < 0.6, ink  # a tube is drawn, not a blank or a filled box
    assert colours > 10  # shaded and coloured along the arclength
    assert "ground: 4C" in p.inner_text("#view-caption")

    # the metastable state, by a click on its row of the table
    p.locator("tr.state-row", has_text="metastable 1").click()
    p.wait_for_timeout(300)
    assert "metastable 1: 80" in p.inner_text("#view-caption")
    assert p.locator("#state-select").input_value() == "1"
    shot2 = p.locator("#view3d").screenshot()
    assert shot2 != shot and _nonblank_fraction(shot2)[0] > 0.01
    page.check()


def test_knot_page_colours_a_state_by_its_contact_structure(page, atlas):
    """The colour select: by contact structure the cage's two point-braids show in their
    colour on grey free strands, with a legend; a state without zones keeps the arclength
    colours and says so."""
    p = page.page
    p.goto((atlas.parent / "knots" / "4_1.html").as_uri())
    p.wait_for_selector("#view3d.js-plotly-plot .gl-container canvas")
    p.wait_for_timeout(300)
    assert p.locator("#zone-legend").is_hidden()
    arc = p.locator("#view3d").screenshot()
    p.select_option("#colour-select", "zones")
    p.wait_for_timeout(300)
    assert p.locator("#zone-legend").is_visible()
    assert p.locator("#zone-missing").is_hidden()
    assert "point-braid" in p.inner_text("#zone-legend")
    faces = p.locator("#view3d").evaluate(
        "d => ({n: d.data[0].i.length, intensity: d.data[0].intensity || null, "
        "colours: Array.from(new Set(d.data[0].facecolor)).sort()})")
    assert faces["intensity"] is None
    # one flat colour a face: free strands (grey) and the two point-braids (orange)
    assert faces["colours"] == ["#c9c9c9", "#ff7f0e"]
    zones = p.locator("#view3d").screenshot()
    assert zones != arc and _nonblank_fraction(zones)[0] > 0.01
    # drawn as given: the free strands grey (the arclength colours are hues)
    assert _grey_fraction(arc) < 0.2 < 0.5 < _grey_fraction(zones), (
        _grey_fraction(arc), _grey_fraction(zones))
    # the metastable 80 has no zones given: coloured along the chain, with a word
    p.locator("tr.state-row", has_text="metastable 1").click()
    p.wait_for_timeout(300)
    assert p.locator("#zone-missing").is_visible()
    assert p.locator("#view3d").evaluate("d => [d.data[0].cmax, d.data[0].facecolor]") == [
        1, None]
    page.check()


@pytest.mark.slow  # about 1-2 s a page
def test_every_knot_page_loads_from_disk_without_errors(page, atlas):
    p = page.page
    for path in sorted((atlas.parent / "knots").glob("*.html")):
        p.goto(path.as_uri())
        p.wait_for_selector("#view3d.js-plotly-plot .gl-container canvas")
        n_options = p.locator("#state-select option").count()
        n_rows = p.locator("tr.state-row").count()
        assert n_options == n_rows >= 1, path.name
        assert re.search(r"\d+\.\d\d", p.inner_text("table.states"))
    # the links of the index lead to the pages, and back
    p.goto(atlas.as_uri())
    p.locator("#knots tbody tr[data-name='5_2'] td:nth-child(2) a").click()
    p.wait_for_selector("#view3d .gl-container canvas")
    assert p.locator("h1").inner_text() == "5_2"
    p.locator("nav.top a", has_text="all knots").click()
    p.wait_for_selector("#knots")
    page.check()


def test_the_thin_limit_column_and_the_branch_diagram(page, atlas):
    """#37: the index's ε* column (the thin-limit ground, ≠ where the finite-width ground
    differs) sorts by number; a knot page draws the branch diagram (one curve per state, the
    w = 0 values on the axis) and shows the thin-limit ground's chain in the 3D view."""
    p = page.page
    p.goto(atlas.as_uri())
    col = _column(p, "ε* (w → 0)")
    cell = p.locator("#knots tbody tr[data-name='4_1'] td").nth(col)
    assert "126.03 ± 0.18" in cell.inner_text() and "≠ finite" in cell.inner_text()
    p.locator("#knots thead th").nth(col).locator("button").click()
    assert _visible(p)[0] == "4_1"              # the only knot with an ε*: first ascending
    p.goto((atlas.parent / "knots" / "4_1.html").as_uri())
    p.wait_for_selector("#branch-plot .main-svg")
    names = p.locator("#branch-plot").evaluate("d => d.data.map(t => t.name)")
    assert "1: other (thin-limit ground)" in names and "0: 4C" in names
    xs0 = p.locator("#branch-plot").evaluate(
        "d => d.data.filter(t => t.name.endsWith('structure route')).map(t => t.x[0])")
    assert xs0 == [0, 0]                        # both routes' values at w = 0
    assert p.locator("#branch-plot .scatterlayer .trace").count() >= 5
    assert "crossing" not in p.inner_text("#thin-title")
    assert "branches cross near w/L = 0.002" in p.inner_text("main")
    sel = p.locator("#state-select")
    thin = next(o for o in sel.locator("option").all_inner_texts() if o.startswith("thin"))
    sel.select_option(label=thin)
    p.wait_for_timeout(300)
    assert "thin-limit ground other" in p.inner_text("#view-caption")
    page.check()


# -- an atlas of every prime knot through 12 crossings (#39) -------------------------------------


@pytest.fixture(scope="module")
def big_atlas(tmp_path_factory):
    """The index of 2,977 knots (the knot pages stubbed: they are one per knot and tested
    above; writing 2,977 of them takes minutes)."""
    import stiffknots.report.atlas.pages as pages

    out = tmp_path_factory.mktemp("atlas-2977")
    keep = pages.knot_page
    pages.knot_page = lambda *a, **k: "<!DOCTYPE html><title>stub</title>"
    try:
        rows = synthetic_catalogue_rows()
        index = write_atlas(out, rows, families=synthetic_families(),
                            title="2,977 synthetic rows", thumbnails=False)
    finally:
        pages.knot_page = keep
    return index, rows


def test_index_of_every_knot_through_12_crossings_pages_sorts_and_filters(page, big_atlas):
    from stiffknots.report.atlas.index_page import PAGE_ROWS

    index, rows = big_atlas
    names = [r["name"] for r in rows]
    assert len(names) == 2977
    p = page.page
    p.goto(index.as_uri())
    assert len(_visible(p)) == PAGE_ROWS and _visible(p)[0] == "3_1"
    assert p.locator("#count").inner_text() == f"2977 of 2977 knots match; 1–{PAGE_ROWS} shown"
    assert p.locator("#page-info").inner_text() == "page 1 of 15"
    assert p.locator("#page-prev").is_disabled()
    p.click("#page-next")
    assert _visible(p) == names[PAGE_ROWS:2 * PAGE_ROWS]
    assert p.locator("#count").inner_text().endswith(f"{PAGE_ROWS + 1}–{2 * PAGE_ROWS} shown")

    # sort by crossing number, descending: the 12-crossing knots first, across every page
    col = _column(p, "nc")  # n<sub>c</sub>
    p.locator("#knots thead th").nth(col).locator("button").click()
    p.locator("#knots thead th").nth(col).locator("button").click()
    assert p.locator("#page-info").inner_text() == "page 1 of 15"  # a new order starts over
    assert set(_column_values(p, col)) == {"12"}
    p.select_option("#page-size", "0")                 # all on one page
    assert len(_visible(p)) == 2977
    assert [int(v) for v in _column_values(p, col)] == sorted(
        (r["crossing_number"] for r in rows), reverse=True)
    p.select_option("#page-size", str(PAGE_ROWS))

    # the filter searches every row, not the page shown
    p.fill("#filter", "11n_")
    n11 = sum(1 for n in names if n.startswith("11n_"))
    assert p.locator("#count").inner_text() == f"{n11} of 2977 knots shown"  # one page
    assert all(n.startswith("11n_") for n in _visible(p)) and len(_visible(p)) == n11
    p.fill("#filter", "12a_")
    n12 = sum(1 for n in names if n.startswith("12a_"))
    assert p.locator("#count").inner_text() == (f"{n12} of 2977 knots match; 1–{PAGE_ROWS} "
                                                 "shown")
    p.fill("#filter", "")

    # the plot follows the table, one point per knot of the model shown
    p.wait_for_selector("#eps-plot.js-plotly-plot .main-svg", timeout=60_000)
    n_points = p.evaluate("""() => document.getElementById('eps-plot').data
        .filter(t => t.meta && t.meta.model && t.visible !== false)
        .reduce((s, t) => s + t.x.length, 0)""")
    assert n_points == 2977
    page.check()
