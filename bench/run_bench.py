"""Full benchmark run (make bench): prints numbers and writes bench/last_run.json.

10 seeds per target, both cores (each run single-threaded on one core), with the default
annealing settings (AnnealSettings(): 30 M moves, relaxation stage then the paper's power-law
annealing, §VII). Seconds to target are recorded as wall-clock and CPU seconds, with the load
average before and after (other jobs on the machine inflate the wall clock); see
docs/benchmarks.md for the current numbers and docs/history.md for the tuning and the tempering
comparison (bench/compare_tempering.py).
"""

import json
import sys

from benchmeta import run_meta, stable_path
from stiffknots.studies.benchmark import run_benchmarks

if __name__ == "__main__":
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    d = {"meta": run_meta(), **run_benchmarks(budget=600, seeds=seeds, log=print)}
    print(json.dumps(d, indent=2))
    stable_path("last_run").write_text(json.dumps(d, indent=2))
