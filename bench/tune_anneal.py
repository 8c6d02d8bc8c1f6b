"""Measure annealing/tempering settings by time to target (the tuning behind the defaults).

Usage::

    .venv/bin/python bench/tune_anneal.py KNOT SEEDS 'CONFIGS' [LOG.jsonl]

``CONFIGS`` is a JSON list of overrides of the defaults, e.g.
``'[{}, {"moves": 1.2e7, "schedule": {"relax_fraction": 0.9999}},
{"params": {"m_max": 70}}]'``: keys ``moves``, ``quench_fraction``, ``n_chunks``,
``schedule`` (fields of Schedule) and ``params`` (fields of MoveParams). Every run is one
:func:`~stiffknots.engine.driver.run_replica` on the braid embedding at N = 150 (seeds
1 … SEEDS, two processes at a time); printed per config: runs reaching the target
(3_1: ε ≤ 79.1, 4_1: ε ≤ 129.6, other knots: none), median and worst CPU and wall seconds to
it, final ε, CPU seconds per run, the quenched ε of each stage, the swap rates of tempering,
and the load average. CPU seconds are the fair measure on a shared machine.
"""

from __future__ import annotations

import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np

from stiffknots.engine.driver import AnnealSettings, run_replica
from stiffknots.engine.params import MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.tempering import run_tempering
from stiffknots.studies.benchmark import TARGETS, _chain


def settings_of(cfg: dict, knot: str) -> AnnealSettings:
    st = AnnealSettings(target_epsilon=TARGETS.get(knot, -1.0))
    st.moves = int(float(cfg.get("moves", st.moves)))
    st.quench_fraction = cfg.get("quench_fraction", st.quench_fraction)
    st.n_chunks = cfg.get("n_chunks", st.n_chunks)
    st.schedule = replace(Schedule(), **cfg.get("schedule", {}))
    st.params = replace(MoveParams(), **cfg.get("params", {}))
    return st


def job(args) -> dict:
    knot, seed, cfg = args
    settings = settings_of(cfg, knot)
    runner = run_tempering if settings.schedule.kind == "tempering" else run_replica
    r = runner(_chain(knot, 150), settings, seed)

    def inf(x):
        return math.inf if x is None else x

    return {"seed": seed, "cpu_to_target": inf(r.cpu_seconds_to_target),
            "wall_to_target": inf(r.seconds_to_target), "epsilon": r.epsilon,
            "cpu_time": r.cpu_time, "wall_time": r.wall_time, "stage_epsilon": r.stage_epsilon,
            "swap_rate": (r.tempering or {}).get("swap_rate")}


def run(knot: str, seeds: list[int], cfgs: list[dict], workers: int = 2) -> list[dict]:
    jobs = [(knot, s, c) for c in cfgs for s in seeds]
    load0 = os.getloadavg()[0]
    with ProcessPoolExecutor(workers) as ex:
        got = list(ex.map(job, jobs))
    out = []
    for i, c in enumerate(cfgs):
        g = got[i * len(seeds):(i + 1) * len(seeds)]
        cpu = [x["cpu_to_target"] for x in g]
        eps = [x["epsilon"] for x in g]
        rec = {"knot": knot, "config": c, "seeds": seeds, "runs": g,
               "reached": int(np.isfinite(cpu).sum()),
               "median_cpu_to_target": float(np.median(cpu)), "worst_cpu_to_target": max(cpu),
               "median_wall_to_target": float(np.median([x["wall_to_target"] for x in g])),
               "epsilon_median": float(np.median(eps)), "epsilon_min": min(eps),
               "epsilon_max": max(eps),
               "cpu_per_run": float(np.mean([x["cpu_time"] for x in g])),
               "load_average": [load0, os.getloadavg()[0]]}
        line = (f"{knot} {json.dumps(c)} | reached {rec['reached']}/{len(g)} | CPU to target "
                f"median {rec['median_cpu_to_target']:.2f} worst {rec['worst_cpu_to_target']:.2f}"
                f" (wall median {rec['median_wall_to_target']:.2f}) | ε median "
                f"{rec['epsilon_median']:.3f} [{rec['epsilon_min']:.3f}, {rec['epsilon_max']:.3f}]"
                f" | CPU/run {rec['cpu_per_run']:.1f} | load {load0:.1f}")
        if len(g[0]["stage_epsilon"]) > 1:
            line += " | stages " + " ".join(
                f"{k}:{np.median([x['stage_epsilon'][k] for x in g]):.2f}"
                for k in g[0]["stage_epsilon"])
        if g[0]["swap_rate"]:
            line += " | swap " + " ".join(
                f"{np.mean([x['swap_rate'][k] for x in g]):.2f}"
                for k in range(len(g[0]["swap_rate"])))
        print(line, flush=True)
        out.append(rec)
    return out


if __name__ == "__main__":
    knot, nseeds, cfgs = sys.argv[1], int(sys.argv[2]), json.loads(sys.argv[3])
    recs = run(knot, list(range(1, nseeds + 1)), cfgs)
    if len(sys.argv) > 4:
        with open(sys.argv[4], "a") as f:
            for r in recs:
                f.write(json.dumps(r) + "\n")
