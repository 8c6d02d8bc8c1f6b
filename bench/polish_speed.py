"""Seconds of the final minimiser (the polish) on the end states of default replicas.

    python bench/polish_speed.py [--pair] [--sparse]

The chains (``bench/polish_chains.npz``) are the Monte Carlo end states, before their polish,
of ten default replicas at N = 150 (15 M moves, ``stiffknots.anneal(K, seed=S, replicas=1,
rounds=1, polish=False, params=MoveParams(exclusion=X))``): 7_4, 8_2, 10_1, 10_4, 10_7,
bead rule (d = 1/√2) or tube (w = 1/√2); the name says knot_seed_model. For each: the polish's
wall seconds, accepted steps, ε before and after (N·E_d at N = 150) and its verdict; then the
total.

``--pair`` runs the set in two processes at once, as the atlas's two workers do, and prints each
process's wall and CPU seconds: the figure that exposed BLAS threads oversubscribing the cores
(docs/history.md, 2026-12-03, second session). ``--sparse`` factorises the projection's Gram
matrix by sparse LU at every size (``DENSE_GRAM_ROWS = 0``), the path of long chains, for
comparison with the dense Cholesky used at N = 150.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

CHAINS = Path(__file__).with_name("polish_chains.npz")


def run(sparse: bool, tag: str = "") -> float:
    import stiffknots.engine.polish as P
    import stiffknots.engine.polish.kkt as KKT

    if sparse:
        KKT.DENSE_GRAM_ROWS = 0
    chains = np.load(CHAINS)
    names = sorted(chains.files)
    for model in ("bead", "tube"):  # compile the kernels outside the timings
        name = next(n for n in names if n.endswith(model))
        P.polish(chains[name], exclusion=model, max_iter=2)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for name in names:
        x = chains[name]
        model = name.rsplit("_", 1)[1]
        t = time.perf_counter()
        r = P.polish(x, exclusion=model)
        n = len(x)
        print(f"{tag}{name:14s} {time.perf_counter() - t:6.2f} s  {r.iterations:4d} steps  "
              f"ε {n * r.energy_before:9.4f} → {n * r.energy:9.4f}  "
              f"{'converged' if r.converged else r.reason}", flush=True)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    print(f"{tag}total: {wall:.2f} s wall, {cpu:.2f} s CPU "
          f"({'sparse LU' if sparse else 'dense Cholesky'} of the Gram matrix at N = 150)",
          flush=True)
    return wall


def main(argv: list[str]) -> None:
    sparse = "--sparse" in argv
    if "--pair" in argv:
        cmd = [sys.executable, __file__] + (["--sparse"] if sparse else [])
        procs = [subprocess.Popen(cmd + ["--tag", f"[{i}] "]) for i in (1, 2)]
        for p in procs:
            p.wait()
        return
    tag = argv[argv.index("--tag") + 1] if "--tag" in argv else ""
    run(sparse, tag)


if __name__ == "__main__":
    main(sys.argv[1:])
