"""The atlas's pages at the size of every prime knot through 12 crossings (2,977 knots), in
headless chromium: how long the index takes to open, filter, sort and page, how big it is, and
what the per-knot pages and thumbnails cost in time and bytes.

    python bench/atlas_page.py [--sample 100] [--repeats 3]

The rows are synthetic (tests/atlas_support.py: six knots' states in turn, renamed to every
catalogue knot through 12 crossings). The index is written with all 2,977 rows; the knot
pages and thumbnails are written for a seeded sample of ``--sample`` knots and their mean
size and time scaled to 2,977 (a knot page's size depends on its states, not on its name).
In chromium (Debian's, as the browser test drives it): the navigation timing of the index
(DOMContentLoaded, load), the time until the ε–n² plot is drawn, and the time of a filter
keystroke, a sort and a page turn (Playwright round trips included), medians of
``--repeats``. Writes bench/atlas_page.json.
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

from benchmeta import run_meta, stable_path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))


def _size(folder: Path, pattern: str) -> int:
    return sum(p.stat().st_size for p in folder.glob(pattern))


def main(argv: list[str] | None = None) -> None:
    import stiffknots.report.atlas.pages as pages
    from atlas_support import (
        chromium_context,
        find_chromium,
        synthetic_catalogue_rows,
        synthetic_families,
    )
    from stiffknots.report.atlas import write_atlas
    from stiffknots.report.atlas.index_page import PAGE_ROWS

    ap = argparse.ArgumentParser()
    ap.add_argument("--sample", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--note", default=None)
    a = ap.parse_args(argv)
    rows = synthetic_catalogue_rows(12)
    n = len(rows)
    tmp = Path(tempfile.mkdtemp(prefix="atlas-page-"))

    # the index of every row (the knot pages stubbed: timed on the sample below)
    keep = pages.knot_page
    pages.knot_page = lambda *x, **k: ""
    t0 = time.perf_counter()
    index = write_atlas(tmp / "index", rows, families=synthetic_families(),
                        title=f"{n} synthetic rows", thumbnails=False)
    index_s = time.perf_counter() - t0
    pages.knot_page = keep
    index_bytes = index.stat().st_size

    # knot pages and thumbnails of a sample
    sample = random.Random(0).sample(rows, a.sample)
    t0 = time.perf_counter()
    write_atlas(tmp / "sample", sample, families=synthetic_families(), title="sample")
    sample_s = time.perf_counter() - t0
    page_bytes = _size(tmp / "sample" / "knots", "*.html")
    thumb_bytes = _size(tmp / "sample" / "thumbs", "*.png")
    plotly_bytes = (tmp / "sample" / "plotly.min.js").stat().st_size
    n_thumbs = len(list((tmp / "sample" / "thumbs").glob("*.png")))

    exe = find_chromium(install=True)
    if exe is None:
        raise SystemExit("chromium is missing and apt-get install -y chromium failed")
    runs = []
    with chromium_context(exe) as ctx:
        for _ in range(a.repeats):
            p = ctx.new_page()
            t0 = time.perf_counter()
            p.goto(index.as_uri(), wait_until="load")
            goto = time.perf_counter() - t0
            nav = p.evaluate("""() => { const e = performance.getEntriesByType('navigation')[0];
                return {dcl: e.domContentLoadedEventEnd, load: e.loadEventEnd}; }""")
            t0 = time.perf_counter()
            p.wait_for_selector("#eps-plot.js-plotly-plot .main-svg", timeout=120_000)
            plot = time.perf_counter() - t0
            t0 = time.perf_counter()
            p.fill("#filter", "12n_")
            p.evaluate("1")
            filt = time.perf_counter() - t0
            p.fill("#filter", "")
            t0 = time.perf_counter()
            p.locator("#knots thead th").nth(2).locator("button").click()
            p.evaluate("1")
            sort = time.perf_counter() - t0
            t0 = time.perf_counter()
            p.click("#page-next")
            p.evaluate("1")
            turn = time.perf_counter() - t0
            runs.append({"goto_s": goto, "dom_content_loaded_s": nav["dcl"] / 1000,
                         "load_s": nav["load"] / 1000, "plot_after_load_s": plot,
                         "filter_s": filt, "sort_s": sort, "page_turn_s": turn})
            p.close()
    med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
    scale = n / a.sample
    d = {"meta": run_meta(argv, a.note), "knots": n, "page_rows": PAGE_ROWS,
         "index_bytes": index_bytes, "index_write_s": index_s,
         "sample": a.sample, "sample_write_s": sample_s, "sample_thumbnails": n_thumbs,
         "knot_page_bytes_mean": page_bytes / a.sample,
         "thumbnail_bytes_mean": thumb_bytes / max(n_thumbs, 1),
         "plotly_bytes": plotly_bytes,
         "projected": {"knot_pages_bytes": page_bytes * scale,
                       "thumbnails_bytes": thumb_bytes * scale,
                       "total_bytes": index_bytes + plotly_bytes + (page_bytes + thumb_bytes)
                       * scale,
                       "write_s": index_s + sample_s * scale},
         "browser": {"median": med, "runs": runs}}
    stable_path("atlas_page").write_text(json.dumps(d, indent=1) + "\n")
    print(f"{n} knots: index {index_bytes / 1e6:.2f} MB written in {index_s:.1f} s; opens in "
          f"{med['load_s']:.2f} s (DOMContentLoaded {med['dom_content_loaded_s']:.2f} s), the "
          f"plot {med['plot_after_load_s']:.2f} s later; filter {med['filter_s']:.2f} s, sort "
          f"{med['sort_s']:.2f} s, page turn {med['page_turn_s']:.2f} s (medians of "
          f"{a.repeats})")
    pr = d["projected"]
    print(f"knot pages {d['knot_page_bytes_mean'] / 1e3:.0f} kB and thumbnails "
          f"{d['thumbnail_bytes_mean'] / 1e3:.1f} kB each: all {n} "
          f"{pr['total_bytes'] / 1e6:.0f} MB with plotly.js, written in about "
          f"{pr['write_s'] / 60:.0f} min (from {a.sample} knots in {sample_s:.1f} s)")
    print(f"wrote {stable_path('atlas_page')}")


if __name__ == "__main__":
    main()
