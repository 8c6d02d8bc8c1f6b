"""Single searches of the hardest tube knots under other annealing schedules.

The audit campaign (bench/audit_campaign.json) found tube verdicts through 10 crossings whose
three agreeing searches all missed a deeper state that a search of twice the moves reached
(9_38, 10_30, 10_58, …). This benchmark asks, knot by knot, how often *one* search reaches that
state (within 0.1 %) under each schedule, and at what CPU cost: each run is
``stiffknots anneal K --exclusion tube --replicas 1 --rounds 1 --start braid --seed S --json``
plus the variant's options, as a user would type it (N = 150, w/L = 0.0047). The reference
state of a knot is the lowest ε the campaign's sweeps and audits stored for it, or a lower one
found here.

The default schedule spends 40 % of its moves relaxing the braid closure at T ≤ 5·10⁻⁵, then
anneals geometrically from T = 0.1 to 10⁻⁶ and quenches: an ε trace of 10_58 drops from 630 to
376 between T = 10⁻² and 3·10⁻⁴ and by under 1 % below 10⁻⁴ (docs/methods/verdicts.md). The
"window" variants put the moves where the funnel is chosen.

Writes bench/search_schedules.json after every run (resumable: runs already stored are
skipped).

    python bench/search_schedules.py [--seeds 11,12] [--variants base,window] [--knots K,...]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from threading import Lock

from benchmeta import run_meta, stable_path

#: name → options of `stiffknots anneal` added to the single search
VARIANTS = {
    "base": [],
    "long": ["--moves", "3e7"],
    "hot": ["--t-start", "0.3"],
    "norelax": ["--relax-fraction", "0"],
    "window": ["--relax-fraction", "0", "--t-start", "0.03", "--t-end", "1e-4"],
    "window-relax": ["--relax-fraction", "0.1", "--t-start", "0.03", "--t-end", "1e-4"],
    "narrow": ["--relax-fraction", "0", "--t-start", "0.01", "--t-end", "1e-4"],
    "coarse75": ["--coarse", "75"],
    "coarse100": ["--coarse", "100"],
    "coarse80": ["--coarse", "80"],
    "coarse100-3M": ["--coarse", "100", "--moves", "3e6"],
    "window-10M": ["--relax-fraction", "0", "--t-start", "0.03", "--t-end", "1e-4",
                   "--moves", "1e7"],
}
TOL = 1e-3  # a search "reaches" the reference within 0.1 % (the verdict's tolerance)
NAME = "search_schedules"


def references(path: Path) -> dict[str, float]:
    """Knot → the lowest ε stored for it by the campaign, for every knot where a verdict was
    beaten (its sweep's searches all missed that state)."""
    d = json.loads(path.read_text())
    false = {k for run in d["searches"].values() for k, v in run["knots"].items()
             if v.get("false_verdict")}
    ref: dict[str, float] = {}
    for run in d["searches"].values():
        for k, v in run["knots"].items():
            if k in false:
                lows = [e for e in (v.get("epsilon"), v.get("audit_epsilon")) if e is not None]
                ref[k] = min([ref.get(k, float("inf")), *lows])
    return ref


def search(knot: str, variant: str, seed: int) -> dict:
    """One search as typed: its ε, shape, wall and CPU seconds."""
    cmd = [sys.executable, "-m", "stiffknots.cli", "anneal", knot, "--exclusion", "tube",
           "--replicas", "1", "--rounds", "1", "--start", "braid", "--seed", str(seed),
           "--json", *VARIANTS[variant]]
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as so, tempfile.TemporaryFile("w+") as se:
        p = subprocess.Popen(cmd, stdout=so, stderr=se, text=True)
        # wait4: the CPU time of this search and the processes it waited for (a coarse
        # stage's workers), not of the other searches this script runs at the same time
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        so.seek(0)
        se.seek(0)
        stdout, stderr = so.read(), se.read()
    if p.returncode != 0:  # e.g. a coarse N too small for the knot's braid: kept, not summed
        return {"knot": knot, "variant": variant, "options": VARIANTS[variant], "seed": seed,
                "epsilon": None, "error": stderr.strip()[-300:], "exit": p.returncode}
    out = json.loads(stdout)
    cpu = usage.ru_utime + usage.ru_stime
    return {"knot": knot, "variant": variant, "options": VARIANTS[variant], "seed": seed,
            "epsilon": out["epsilon"], "shape": out.get("shape"), "wall_s": round(wall, 2),
            "cpu_s": round(cpu, 2),
            "search_cpu_s": round(sum(r.get("cpu_time") or 0.0 for r in out["replicas"]), 2),
            "knot_verified": out.get("knot_verified"), "width": (out.get("width") or {}).get(
                "text")}


def summarise(all_rows: list[dict], ref: dict[str, float]) -> dict:
    """Per variant: runs, searches within 0.1 % of the reference, the median gap, the mean
    CPU seconds and the CPU hours per hit."""
    low = dict(ref)
    rows = [r for r in all_rows if r["epsilon"] is not None]
    for r in rows:
        low[r["knot"]] = min(low.get(r["knot"], float("inf")), r["epsilon"])
    out = {}
    for v in VARIANTS:
        rs = [r for r in rows if r["variant"] == v]
        failed = sum(r["epsilon"] is None for r in all_rows if r["variant"] == v)
        if not rs:
            if failed:
                out[v] = {"runs": 0, "failed": failed, "hits": 0, "median_gap": None,
                          "mean_gap": None, "cpu_s_per_search": None, "cpu_s_per_hit": None,
                          "by_knot": {}}
            continue
        gaps = [r["epsilon"] / low[r["knot"]] - 1.0 for r in rs]
        hits = sum(g <= TOL for g in gaps)
        cpu = sum(r["cpu_s"] for r in rs)
        out[v] = {"runs": len(rs), "failed": failed, "hits": hits,
                  "median_gap": statistics.median(gaps),
                  "mean_gap": statistics.fmean(gaps), "cpu_s_per_search": cpu / len(rs),
                  "cpu_s_per_hit": cpu / hits if hits else None,
                  "by_knot": {k: sorted(round(r["epsilon"], 2) for r in rs if r["knot"] == k)
                              for k in sorted({r["knot"] for r in rs})}}
    return {"reference": low, "variants": out}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="11,12")
    ap.add_argument("--variants", default="base,window")
    ap.add_argument("--knots", default=None, help="Default: every knot with a beaten verdict "
                    "in bench/audit_campaign.json.")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    ref = references(stable_path("audit_campaign"))
    knots = a.knots.split(",") if a.knots else sorted(ref)
    unknown = [v for v in a.variants.split(",") if v not in VARIANTS]
    if unknown:
        raise SystemExit(f"unknown variant(s) {unknown}; known: {', '.join(VARIANTS)}")
    path = stable_path(NAME)
    old = json.loads(path.read_text()) if path.exists() else {"rows": []}
    rows = old["rows"]
    done = {(r["knot"], r["variant"], r["seed"]) for r in rows}
    jobs = [(k, v, int(s)) for s in a.seeds.split(",") for v in a.variants.split(",")
            for k in knots if (k, v, int(s)) not in done]
    lock = Lock()

    def one(job):
        r = search(*job)
        with lock:
            rows.append(r)
            d = {"meta": run_meta(argv, note="one search per row; tube w = 1/√2, N = 150 "
                                             "(w/L = 0.0047); braid start"),
                 "rows": rows, "summary": summarise(rows, ref)}
            path.write_text(json.dumps(d, indent=1) + "\n")
            if r["epsilon"] is None:
                print(f"{r['knot']} {r['variant']} seed {r['seed']}: failed: {r['error']}",
                      flush=True)
                return
            gap = r["epsilon"] / d["summary"]["reference"][r["knot"]] - 1.0
            print(f"{r['knot']} {r['variant']} seed {r['seed']}: ε = {r['epsilon']:.2f} "
                  f"({100 * gap:+.2f} %), {r['cpu_s']:.1f} CPU s", flush=True)

    with ThreadPoolExecutor(a.workers) as ex:
        list(ex.map(one, jobs))
    if path.exists():
        s = json.loads(path.read_text())["summary"]["variants"]
        for v, x in s.items():
            print(f"{v}: {x['hits']} of {x['runs']} within 0.1 %, median gap "
                  f"{100 * x['median_gap']:.2f} %, {x['cpu_s_per_search']:.1f} CPU s a search")


if __name__ == "__main__":
    main()
