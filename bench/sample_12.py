"""A seeded sample of the knots of 11 and 12 crossings at the atlas's default budget (tube
model): how many converge, what a knot costs, whether the n = i knots reach their circular
braid, and what all 2,977 prime knots through 12 crossings would take.

    stiffknots atlas --crossings 11,12 --sample 100 --seed 0 --models tube --db DB --json
    stiffknots atlas --crossings 11,12 --sample 100 --seed 0 --models tube --db DB \\
        --out STORED_PAGES --stored --json > STORED.json
    python bench/sample_12.py DB STORED.json [--note TEXT]

A run stopped part-way (``kill PID``; the same command resumes) is read as it stands: a knot
is *settled* when its verdict converged or it has run every replica and continuation leg of
the budget (6 + 2 for the tube at the default budget); knots with fewer replicas are still in
flight and left out of the rates. CPU seconds are the stored replicas' own. The projection
takes each crossing number's mean CPU seconds a settled knot (9–10 crossings: the tube atlas of
249 knots, ``bench/atlas_summary.json``, when present) times KnotInfo's count of knots, on 2
cores and on 64 with perfect sharing (a Dask cluster, one job per replica). Writes
bench/sample_12.json.
"""

from __future__ import annotations

import argparse
import json
import math
import sqlite3
import statistics

from benchmeta import run_meta, stable_path


def _wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def main(argv: list[str] | None = None) -> None:
    from stiffknots.knots.catalogue import catalogue, get_knot

    ap = argparse.ArgumentParser()
    ap.add_argument("db")
    ap.add_argument("stored", help="`stiffknots atlas ... --stored --json` of the same sample")
    ap.add_argument("--note", default=None)
    a = ap.parse_args(argv)
    d = json.load(open(a.stored))
    bud = d["sweep"]["budget"]
    full = bud["max_replicas"] + bud["legs"]
    with sqlite3.connect(f"file:{a.db}?mode=ro", uri=True) as con:
        cpu = dict(con.execute("SELECT knot, sum(cpu_seconds) FROM replicas "
                               "WHERE exclusion = 'tube' GROUP BY knot"))
        cb = con.execute("SELECT knot, multiplicity, min(epsilon) FROM replicas "
                         "WHERE exclusion = 'tube' AND shape = 'CB' "
                         "GROUP BY knot, multiplicity").fetchall()
    rows = []
    for k in d["knots"]:
        m = (k.get("models") or {}).get("tube")
        reps = m["replicas"] if m else 0
        kn = get_knot(k["name"])
        rows.append({"knot": k["name"], "crossings": kn.crossing_number, "n": kn.bridge_number,
                     "i": kn.braid_index, "replicas": reps, "converged": bool(k["converged"]),
                     "settled": bool(k["converged"]) or reps >= full,
                     "shape": k.get("shape"), "multiplicity": k.get("multiplicity"),
                     "epsilon": k.get("epsilon"), "cpu_seconds": cpu.get(k["name"], 0.0)})
    settled = [r for r in rows if r["settled"]]
    conv = [r for r in settled if r["converged"]]
    by_c = {}
    for c in sorted({r["crossings"] for r in rows}):
        s = [r for r in settled if r["crossings"] == c]
        by_c[c] = {"sampled": sum(1 for r in rows if r["crossings"] == c), "settled": len(s),
                   "converged": sum(r["converged"] for r in s),
                   "cpu_mean": statistics.mean(r["cpu_seconds"] for r in s) if s else None,
                   "cpu_median": statistics.median(r["cpu_seconds"] for r in s) if s else None,
                   "cpu_max": max((r["cpu_seconds"] for r in s), default=None)}
    # every circular braid any replica reached: its energy at this width grows with the
    # crossings its strands make, so an n = i knot's state is read against the CB(i) of knots
    # of its own crossing number
    crossings_of = {r["knot"]: r["crossings"] for r in rows}
    circular = [{"knot": k, "crossings": crossings_of.get(k), "i": m, "epsilon": e}
                for k, m, e in cb if m is not None]

    def cb_range(knot, c, i):
        es = [x["epsilon"] for x in circular
              if x["crossings"] == c and x["i"] == i and x["knot"] != knot]
        return [min(es), max(es)] if es else None

    def own_cb(knot, i):
        es = [x["epsilon"] for x in circular if x["knot"] == knot and x["i"] == i]
        return min(es) if es else None

    n_eq_i = [{"knot": r["knot"], "i": r["i"], "shape": r["shape"],
               "multiplicity": r["multiplicity"], "epsilon": r["epsilon"],
               "cb_i": r["shape"] == "CB" and r["multiplicity"] == r["i"],
               "cb_i_same_crossings": cb_range(r["knot"], r["crossings"], r["i"]),
               "own_cb_i": own_cb(r["knot"], r["i"]),
               "converged": r["converged"], "settled": r["settled"]}
              for r in rows if r["n"] is not None and r["n"] == r["i"] and r["replicas"]]
    # the projection: mean CPU a settled knot by crossing number, times the catalogue's count
    counts = {}
    for kn in catalogue(12):
        if kn.crossing_number >= 3:
            counts[kn.crossing_number] = counts.get(kn.crossing_number, 0) + 1
    per_knot = {c: v["cpu_mean"] for c, v in by_c.items() if v["cpu_mean"] is not None}
    atlas = None
    try:
        atlas = json.load(open(stable_path("atlas_summary")))
    except (OSError, ValueError):
        pass
    low_cpu = None
    if atlas:
        tube = (atlas.get("models") or {}).get("tube")
        if tube and tube.get("pairs"):
            low_cpu = tube["cpu_seconds"] / tube["pairs"]
    proj = None
    if per_knot:
        fill = low_cpu if low_cpu is not None else min(per_knot.values())
        total = sum(n * per_knot.get(c, fill if c <= 10 else max(per_knot.values()))
                    for c, n in counts.items())
        longest = max(r["cpu_seconds"] for r in settled)
        proj = {"knots": sum(counts.values()), "cpu_hours": total / 3600,
                "assumed": [c for c in counts if c > 10 and c not in per_knot],
                "per_knot_by_crossings": per_knot, "through_10_per_knot": fill,
                "wall_hours_2_cores": total / 2 / 3600,
                "wall_hours_64_cores": max(total / 64, longest) / 3600}
    lo, hi = _wilson(len(conv), len(settled))
    out = {"meta": run_meta(argv, a.note), "db": a.db, "budget": bud["name"],
           "width": d["sweep"]["widths"]["tube"]["text"], "seed": d["sweep"]["seed"],
           "sampled": len(rows), "with_results": sum(1 for r in rows if r["replicas"]),
           "settled": len(settled), "converged": len(conv),
           "converged_interval": [lo, hi], "by_crossings": by_c, "n_eq_i": n_eq_i,
           "circular_braids": circular,
           "projection": proj, "rows": rows}
    stable_path("sample_12").write_text(json.dumps(out, indent=1) + "\n")
    print(f"{len(rows)} knots sampled, {out['with_results']} with results, {len(settled)} "
          f"settled: {len(conv)} converged ({100 * len(conv) / max(1, len(settled)):.0f} %, "
          f"95 % interval {100 * lo:.0f}–{100 * hi:.0f} %) at {out['width']}")
    for c, v in by_c.items():
        if v["settled"]:
            print(f"  {c} crossings: {v['converged']} of {v['settled']} settled converged; CPU "
                  f"s a knot mean {v['cpu_mean']:.0f}, median {v['cpu_median']:.0f}, max "
                  f"{v['cpu_max']:.0f}")
    for r in n_eq_i:
        print(f"  n = i = {r['i']}: {r['knot']} {r['shape']}"
              f"{'' if r['multiplicity'] is None else '(' + str(r['multiplicity']) + ')'} "
              f"ε = {r['epsilon']:.2f}{' (CB(i))' if r['cb_i'] else ''}"
              f"{'' if r['settled'] else ' (in flight)'}"
              + ("" if r["cb_i"] or r["own_cb_i"] is None else
                 f" (its own CB({r['i']}) reached by a replica: {r['own_cb_i']:.2f})")
              + ("" if r["cb_i_same_crossings"] is None else
                 " — CB({}) of other knots of its crossing number: {:.2f}–{:.2f}".format(
                     r["i"], *r["cb_i_same_crossings"])))
    if proj:
        print(f"projection: {proj['knots']} knots, {proj['cpu_hours']:.0f} CPU h: "
              f"{proj['wall_hours_2_cores']:.0f} h on 2 cores, "
              f"{proj['wall_hours_64_cores']:.1f} h on 64"
              + (f" (crossing numbers {proj['assumed']} without a settled knot: the largest "
                 "mean measured)" if proj["assumed"] else ""))
    print(f"wrote {stable_path('sample_12')}")


if __name__ == "__main__":
    main()
