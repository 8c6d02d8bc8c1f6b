"""Replay a sweep's stored replicas to judge its time-left estimate (the jobs expected).

For cut points along the sweep (the n-th replica stored, in order of storing), the
(knot, model)s whose every own replica was stored by then count as settled, the others as
open with the replicas they had; the jobs expected from then on by
:func:`stiffknots.sweeps.run.expected_todo` — with and without crossing numbers (the mean
over all of a model's settled knots) — are printed beside the jobs that actually followed.
Also the mean own replicas per (knot, model) by crossing number.

    python bench/eta_replay.py /work/atlas10/atlas.db [--base 2] [--cuts 400,674,895,1201]
"""

from __future__ import annotations

import argparse
import sqlite3
from collections import defaultdict

from stiffknots.knots.catalogue import get_knot
from stiffknots.sweeps.cross import SEEDED_REPLICA
from stiffknots.sweeps.run import expected_todo


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("db")
    ap.add_argument("--base", type=int, default=2, help="the budget's replicas (default 2)")
    ap.add_argument("--cuts", default="400,674,895,1201",
                    help="replicas stored at each cut (comma-separated)")
    a = ap.parse_args()
    con = sqlite3.connect(f"file:{a.db}?mode=ro", uri=True)
    rows = con.execute("SELECT knot, exclusion, created FROM replicas WHERE replica < ? "
                       "ORDER BY created, id", (SEEDED_REPLICA,)).fetchall()
    stored: dict[tuple[str, str], list[str]] = defaultdict(list)
    for knot, model, created in rows:
        stored[(knot, model)].append(created)
    nc = {k: get_knot(k).crossing_number for k, _ in stored}
    per: dict[tuple[str, int], list[int]] = defaultdict(list)
    for (k, m), v in stored.items():
        per[(m, nc[k])].append(len(v))
    print("own replicas per (knot, model), mean by crossing number:")
    for m in sorted({m for m, _ in per}):
        print(f"  {m}: " + ", ".join(f"{c}: {sum(v) / len(v):.2f} ({len(v)})"
                                     for (mm, c), v in sorted(per.items()) if mm == m))
    print(f"{len(rows)} own replicas stored in all")
    print("cut | settled | open | jobs that followed | expected: by model and crossings | "
          "by model only")
    for cut_i in (int(c) for c in a.cuts.split(",")):
        if not 0 < cut_i < len(rows):
            continue
        cut = rows[cut_i - 1][2]
        groups = {}
        for key, v in stored.items():
            have = sum(1 for c in v if c <= cut)
            settled = max(v) <= cut
            groups[key] = {"replicas": have if settled else max(have, a.base),
                           "settled": settled, "crossings": nc[key[0]]}
        done = cut_i
        # jobs of the open ones not yet stored: the budget's replicas they lack
        todo = sum(max(0, a.base - sum(1 for c in v if c <= cut)) for key, v in stored.items()
                   if not groups[key]["settled"])
        flat = {k: {"replicas": g["replicas"], "settled": g["settled"]}
                for k, g in groups.items()}
        by_crossings = expected_todo(groups, todo, a.base)
        print(f"{cut_i} | {sum(g['settled'] for g in groups.values())} | "
              f"{sum(not g['settled'] for g in groups.values())} | {len(rows) - done} | "
              f"{by_crossings:.0f} | {expected_todo(flat, todo, a.base):.0f}")


if __name__ == "__main__":
    main()
