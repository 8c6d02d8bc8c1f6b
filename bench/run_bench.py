"""Full benchmark run (make bench): prints numbers and writes bench/last_run.json.

10 seeds per target, both cores (each run single-threaded on one core), with the default
annealing settings (AnnealSettings(): 30 M moves, relaxation stage then the paper's power-law
annealing, §VII). Seconds to target are recorded as wall-clock and CPU seconds, with the load
average before and after (other jobs on the machine inflate the wall clock); see
bench/RESULTS.md for the tuning and for the tempering comparison (bench/compare_tempering.py).
"""

import json
import sys
from pathlib import Path

from stiffknots.studies.benchmark import run_benchmarks

if __name__ == "__main__":
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    d = run_benchmarks(budget=600, seeds=seeds, log=print)
    print(json.dumps(d, indent=2))
    Path(__file__).with_name("last_run.json").write_text(json.dumps(d, indent=2))
