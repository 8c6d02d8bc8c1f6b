"""Tests of writing the atlas (stiffknots.report.atlas.pages): the files of the folder,
plotly.js once, ``atlas.json``, pages that need no network.

The browser tests (the pages load, sort, filter and draw in chromium) are in
``test_browser.py``.
"""

import json
import re
import subprocess
import sys
from pathlib import Path

from atlas_support import BEAD_WIDTH, synthetic_families
from stiffknots.report.atlas import write_atlas
from stiffknots.theory import closed_bounds


def test_writes_index_pages_and_one_copy_of_plotly(atlas, knots):
    out = atlas.parent
    assert atlas == out / "index.html" and atlas.is_file()
    js = out / "plotly.min.js"
    assert js.stat().st_size > 1_000_000
    assert sorted(p.name for p in out.rglob("plotly*.js")) == ["plotly.min.js"]
    # the index loads plotly.js itself once its table is shown (js.src = "plotly.min.js")
    assert 'js.src = "plotly.min.js"' in atlas.read_text(encoding="utf-8")
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


def test_no_external_urls_in_the_pages(atlas):
    pages = [atlas, *sorted((atlas.parent / "knots").glob("*.html"))]
    assert len(pages) == 7
    for page in pages:
        text = page.read_text(encoding="utf-8")
        assert "://" not in text, f"{page.name} has an absolute URL"
        for ref in re.findall(r'(?:src|href)="([^"]*)"', text):
            assert not ref.startswith("//"), ref
            assert ref.startswith(("data:", "#")) or not re.match(r"^[a-z]+:", ref), ref


def test_atlas_json_summary(atlas, knots):
    data = json.loads((atlas.parent / "atlas.json").read_text(encoding="utf-8"))
    assert [k["name"] for k in data["knots"]] == [k["name"] for k in knots]
    s = data["knots"][1]["models"]["bead"]["states"]
    assert [x["shape"] for x in s] == ["4C", "80"]
    assert s[0]["width"] == BEAD_WIDTH and "coords" not in s[0]
    assert data["meta"]["budget"] == "synthetic" and "stiffknots" in data["meta"]


def test_import_sets_no_matplotlib_backend():
    code = ("import matplotlib; matplotlib.use('svg'); import stiffknots.report.atlas; "
            "print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).parent)
    assert out.stdout.strip() == "svg"


def test_knots_without_results_still_get_a_row_and_a_page(tmp_path, read_rows):
    idx = write_atlas(tmp_path, [{"name": "0_1"}, {"name": "K11n34", "crossing_number": 11,
                                                   "n": 3, "i": 4}])
    text = idx.read_text(encoding="utf-8")
    rows = read_rows(text)
    assert [a["data-name"] for a, _ in rows] == ["0_1", "K11n34"]
    cells = rows[0][1]
    assert cells["bounds"]["text"] == "—" and cells["n"]["text"] == "—"
    b = closed_bounds(3, 4)
    assert rows[1][1]["bounds"]["text"].startswith(f"{b.lower:.2f} – {b.upper:.2f}")
    assert 'id="model"' not in text and 'id="families"' not in text
    page = (tmp_path / "knots" / "K11n34.html").read_text(encoding="utf-8")
    assert "No computed states" in page and "states-data" not in page
    assert not (tmp_path / "thumbs").exists()
