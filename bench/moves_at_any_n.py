"""Moves at any N: the default settings at N = 150, 300, 600 and 1,200 (closed, bead and tube).

The move parameters hold in N-free units (`MoveParams.for_beads`: sub-chains up to N/2;
`Schedule.for_beads`: temperatures × (150/N)²; `default_moves`: 15 M × N/150). This runs
`stiffknots anneal 3_1 --beads N --rounds 1` (2 replicas, one per core, polish on) for each N
and model and prints ε, its distance to the discrete reference — the doubly covered circle of
N beads, ε_N = N²(1 − cos 4π/N), the minimum without exclusion — and to the thin limit 8π²,
the wall time and the verdict. Writes bench/moves_at_any_n.json.

    python bench/moves_at_any_n.py [--beads 150,300,600,1200] [--models bead,tube] [--knot 3_1]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time

from benchmeta import run_meta, stable_path


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--beads", default="150,300,600,1200")
    ap.add_argument("--models", default="bead,tube")
    ap.add_argument("--knot", default="3_1")
    ap.add_argument("--rounds", default="1")
    a = ap.parse_args(argv)
    rows = []
    for model in a.models.split(","):
        for n in (int(v) for v in a.beads.split(",")):
            cmd = [sys.executable, "-m", "stiffknots.cli", "anneal", a.knot, "--beads", str(n),
                   "--rounds", a.rounds, "--exclusion", model, "--json"]
            load0 = os.getloadavg()[0]
            t0 = time.perf_counter()
            p = subprocess.run(cmd, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if p.returncode != 0:
                print(f"{model} N={n}: rc {p.returncode}: {p.stderr.strip()[-300:]}", flush=True)
                rows.append({"model": model, "beads": n, "rc": p.returncode})
                continue
            d = json.loads(p.stdout)
            eps = d["epsilon"]
            ref = n * n * (1 - math.cos(4 * math.pi / n))
            row = {"model": model, "beads": n, "moves": d["settings"]["moves"],
                   "epsilon": eps, "replicas": [r["epsilon"] for r in d["replicas"]],
                   "discrete_double_circle": ref, "thin_limit": 8 * math.pi**2,
                   "shape": d.get("shape"), "converged": d["converged"],
                   "wall_s": round(wall, 1), "load_before": load0,
                   "width": d["width"]["text"]}
            rows.append(row)
            print(f"{model:4s} N={n:5d} moves/replica {row['moves'] / 1e6:7.0f} M  "
                  f"ε = {eps:.4f} (replicas {', '.join(f'{e:.4f}' for e in row['replicas'])})"
                  f"  ε − ε_N(2-circle) = {eps - ref:+.4f}, ε/8π² − 1 = "
                  f"{100 * (eps / (8 * math.pi**2) - 1):+.3f} %  {row['shape']} "
                  f"converged={row['converged']}  {wall:.0f} s (load {load0:.1f})", flush=True)
    stable_path("moves_at_any_n").write_text(
        json.dumps({"meta": run_meta(argv), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
