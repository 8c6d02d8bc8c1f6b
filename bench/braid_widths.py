"""How a ground's braids change with the width: the contact zones of the lowest chain of each
knot at N = 150 (an atlas database) and at larger N (``stiffknots anneal`` output folders),
the tube model at w = 1/√2, so w/L = w/N halves as N doubles.

For every knot: N, w/L, ε of the lowest chain, its contact structure (§V B) and each
zone's kind, strands m and length as a fraction of L (the longest run of the zone;
``Structure.zones``). §V B: in the thin limit a line-braid keeps a finite fraction of L
(eq. (28)), a point-braid shrinks with w. A zone is named a line-braid when it reaches
max(3 × contact cutoff, 0.1 L), so a braid whose fraction falls below 0.1 changes its name.

    python bench/braid_widths.py --db /work/atlas10/atlas.db RUN_DIR [RUN_DIR ...]

A RUN_DIR is the ``--out`` folder of ``stiffknots anneal K --exclusion tube --beads N --json
--out RUN_DIR`` (its ``result.json`` and ``best.xyz``).
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import warnings
from pathlib import Path

import numpy as np

from stiffknots.analysis.structure import analyse_structure
from stiffknots.formats import from_xyz


def _zones_text(x: np.ndarray, d: float) -> tuple[str, str]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = analyse_structure(x, True, d=d)
    zs = sorted(s.zones, key=lambda z: -z.length)
    return s.name, ", ".join(f"{z.kind} m={z.multiplicity} {z.length / s.length:.3f}"
                             for z in zs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="*", help="anneal --out folders")
    ap.add_argument("--db", help="an atlas database (its N = 150 grounds of the same knots)")
    ap.add_argument("--exclusion", default="tube")
    ap.add_argument("--json", help="also write the rows to this file")
    a = ap.parse_args()
    rows = []
    for run in a.runs:
        if not (Path(run) / "result.json").exists():
            print(f"{run}: no result.json (still running?): left out")
            continue
        r = json.loads((Path(run) / "result.json").read_text())
        w = r["width"]
        x = from_xyz(Path(run) / "best.xyz", closed=True).coords
        name, zones = _zones_text(x, float(w.get("w") or w.get("d")))
        rows.append({"knot": r["knot"], "N": r["beads"], "w_over_L": w["w_over_L"],
                     "epsilon": r["epsilon"], "converged": r["converged"],
                     "structure": name, "zones": zones, "source": str(run)})
    if a.db:
        from stiffknots.store import Store

        store = Store(a.db)
        con = sqlite3.connect(f"file:{a.db}?mode=ro", uri=True)
        for knot in dict.fromkeys(r["knot"] for r in list(rows)):
            got = con.execute("SELECT id, beads, thickness, w_over_L, epsilon FROM replicas "
                              "WHERE knot = ? AND exclusion = ? ORDER BY epsilon LIMIT 1",
                              (knot, a.exclusion)).fetchone()
            if got is None:
                continue
            rid, n, t, wl, eps = got
            name, zones = _zones_text(store.coords(rid), t)
            rows.append({"knot": knot, "N": n, "w_over_L": wl, "epsilon": eps,
                         "converged": None, "structure": name, "zones": zones,
                         "source": a.db})
    rows.sort(key=lambda r: (r["knot"], r["N"]))
    print("knot | N | w/L | ε (lowest found) | structure | zones (kind, m, length / L)")
    for r in rows:
        print(f"{r['knot']} | {r['N']} | {r['w_over_L']:.5f} | {r['epsilon']:.3f} | "
              f"{r['structure']} | {r['zones']}")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
