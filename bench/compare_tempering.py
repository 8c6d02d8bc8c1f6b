"""Parallel tempering against annealing: runs reaching the target per CPU-second (§VII).

Every method gets the same move budget (30 M moves per run: the default; tempering shares it
between its copies), on the braid embedding of 3_1 (target ε ≤ 79.1) and 4_1 (ε ≤ 129.6) at
N = 150, seeds 1 … SEEDS, two runs at a time. Printed and written to
bench/tempering_comparison.json: runs reaching the target, CPU seconds per run, successes per
CPU-minute (whole runs counted), and CPU seconds per success if every run stopped at the
target (runs that miss count in full).

Usage: ``.venv/bin/python bench/compare_tempering.py [SEEDS]`` (default 4).
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

from benchmeta import run_meta, stable_path
from tune_anneal import run

METHODS = {
    "annealing (default)": {},
    "PT K=4, T 5e-6…5e-5": {"schedule": {"kind": "tempering", "t_end": 5e-6, "t_start": 5e-5,
                                         "n_temps": 4}},
    "PT K=4, T 1e-7…5e-5": {"schedule": {"kind": "tempering", "t_end": 1e-7, "t_start": 5e-5,
                                         "n_temps": 4}},
    "PT K=8, T 1e-7…3e-2": {"schedule": {"kind": "tempering", "t_end": 1e-7, "t_start": 3e-2,
                                         "n_temps": 8}},
}


def main(nseeds: int = 4) -> dict:
    out = {}
    for knot in ("3_1", "4_1"):
        recs = run(knot, list(range(1, nseeds + 1)), list(METHODS.values()))
        for name, rec in zip(METHODS, recs, strict=True):
            runs = rec["runs"]
            cpu = sum(r["cpu_time"] for r in runs)
            stop = sum(r["cpu_to_target"] if math.isfinite(r["cpu_to_target"]) else r["cpu_time"]
                       for r in runs)
            ok = rec["reached"]
            rec.update(method=name, successes_per_cpu_minute=60.0 * ok / cpu,
                       cpu_per_success_stopping_at_target=(stop / ok) if ok else math.inf)
            print(f"{knot} {name}: {ok}/{len(runs)} reached, CPU/run {rec['cpu_per_run']:.1f} s, "
                  f"{rec['successes_per_cpu_minute']:.2f} successes per CPU-minute, "
                  f"{rec['cpu_per_success_stopping_at_target']:.1f} CPU s per success if "
                  f"stopped at the target", flush=True)
            out[f"{knot} / {name}"] = rec
    return out


if __name__ == "__main__":
    d = main(int(sys.argv[1]) if len(sys.argv) > 1 else 4)
    stable_path("tempering_comparison").write_text(
        json.dumps({"meta": run_meta(), **d}, indent=1,
                   default=lambda x: x.item() if isinstance(x, np.generic) else x))
