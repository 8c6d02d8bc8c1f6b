"""Write a demo atlas of synthetic knots and screenshot it with headless chromium.

Usage::

    .venv/bin/python scripts/atlas_demo.py [OUT_DIR]     # default /tmp/atlas-demo
    .venv/bin/python scripts/atlas_demo.py --existing results/atlas [KNOT]   # a real atlas

Writes ``OUT_DIR/index.html`` (with ``knots/``, ``thumbs/``, ``plotly.min.js``) and the
screenshots ``OUT_DIR/screenshot-index.png`` (the top of the index page),
``OUT_DIR/screenshot-index-full.png`` (all of it), ``OUT_DIR/screenshot-structures.png`` (the
table of the knots in no family by structure, where the atlas has one) and
``OUT_DIR/screenshot-knot.png`` (the page of 4_1 with its 3D view), and, where a state of
that page has its contact structure, ``OUT_DIR/screenshot-knot-structure.png`` (its 3D view
coloured by contact structure). The chains are synthetic (``tests/atlas_support.py``), not
annealed results.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from atlas_support import (  # noqa: E402
    chromium_context,
    find_chromium,
    synthetic_families,
    synthetic_knots,
)
from stiffknots.report.atlas import write_atlas  # noqa: E402


def main(argv: list[str]) -> int:
    knot = "4_1"
    if len(argv) > 2 and argv[1] == "--existing":
        out = Path(argv[2])
        index = out / "index.html"
        knot = argv[3] if len(argv) > 3 else knot
    else:
        out = Path(argv[1] if len(argv) > 1 else "/tmp/atlas-demo")
        index = write_atlas(out, synthetic_knots(), families=synthetic_families(),
                            title="Atlas of stiff knots (demo: synthetic chains)",
                            meta={"data": "synthetic chains of known shape, not annealed "
                                          "results"})
        print(f"wrote {index}")
    exe = find_chromium()
    if exe is None:
        print("no chromium (apt-get install -y chromium): no screenshots", file=sys.stderr)
        return 1
    with chromium_context(exe, width=1360, height=900) as ctx:
        page = ctx.new_page()
        page.goto(index.as_uri())
        page.wait_for_selector("#eps-plot .main-svg")
        page.screenshot(path=str(out / "screenshot-index.png"))
        page.screenshot(path=str(out / "screenshot-index-full.png"), full_page=True)
        shots = ["screenshot-index.png", "screenshot-index-full.png"]
        if page.locator("#structures").count():  # the knots in no family, by structure
            page.locator("#structures-title").scroll_into_view_if_needed()
            page.screenshot(path=str(out / "screenshot-structures.png"))
            shots.append("screenshot-structures.png")
        page.goto((out / "knots" / f"{knot}.html").as_uri())
        page.wait_for_selector("#view3d .gl-container canvas")
        time.sleep(0.5)
        page.screenshot(path=str(out / "screenshot-knot.png"), full_page=True)
        shots.append("screenshot-knot.png")
        if page.locator("#colour-select").count():  # coloured by contact structure (§V B)
            page.select_option("#colour-select", "zones")
            time.sleep(0.5)
            page.locator(".viewer").screenshot(path=str(out / "screenshot-knot-structure.png"))
            shots.append("screenshot-knot-structure.png")
    for name in shots:
        print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
