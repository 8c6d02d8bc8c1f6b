"""The atlas's bead-rule ensembles searched two ways on one sample of knots: the paper's
annealing against the Langevin dynamics (``Budget.bead_search``).

    python bench/atlas_bead_search.py --db DB [--knots 9_1,9_7,...] [--cap 16]
                                      [--replay 4,6,8,10,12] [--compare-only] [--json [FILE]]

Step 1 sweeps the knots under both models with the default budget's bead ensembles annealing
(2 × 15 M moves, up to 6, tube legs as usual); step 2 sweeps them again on the same database
with the Langevin bead ensembles (10⁶ steps a replica, up to ``--cap``): the tube ensembles
are the same (their settings do not change), so step 2 runs only the bead-rule replicas and
seeds its bead ensemble from the stored tube replicas. It prints, per knot, each bead
ensemble's ground ε, verdict (:func:`stiffknots.sweeps.convergence.ensemble_converged`) and
own replicas; the CPU seconds of their own searches; the verdicts above the other ensemble's
lowest state; and, with ``--replay``, the verdicts a lower cap would have given (the
replicas numbered below it kept: a capped sweep runs exactly those, since every replica's
seed and start depend only on the replicas before it). ``--compare-only`` reads a database
made before. Every ε at N = 150, d = 1/√2 (w/L ≈ 0.0047), seed 0.

The default sample (2026-12-05, tenth session): every sixth 9-crossing knot and every
twentieth 10-crossing one.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from atlas_replay import capped_copy  # bench/, beside this script
from benchmeta import run_meta, stable_path
from stiffknots.store import settings_hash
from stiffknots.store.keys import knot_sort_key
from stiffknots.store.sqlite import Store
from stiffknots.sweeps import budget_of, parse_models, run_sweep
from stiffknots.sweeps.convergence import ensemble_converged
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA
from stiffknots.sweeps.plan import sweep_settings

SAMPLE = ("9_1,9_7,9_13,9_19,9_25,9_31,9_37,9_43,9_49,"
          "10_1,10_21,10_41,10_61,10_81,10_101,10_121,10_141,10_161")


def budgets(cap: int) -> dict:
    """search name → the budget of that bead search."""
    return {"annealing": budget_of("default", bead_search="annealing"),
            "langevin": replace(budget_of("default", bead_search="langevin"),
                                bead_max_replicas=cap)}


def own(r: dict) -> bool:
    """A replica of the ensemble's own search (not seeded from a tube replica)."""
    return r["replica"] < OLDER_SEEDED_REPLICA


def compare(db: str, hashes: dict[str, str], replay: list[int]) -> dict:
    st = Store(db, create=False)
    out: dict = {"db": db, "searches": {}, "knots": {}}
    grounds = {}
    for name, h in hashes.items():
        rows = st.replicas(exclusion="bead", settings_hash=h)
        g = {x["knot"]: x for x in st.ground_states(settings_hash=h, structure=False)}
        grounds[name] = g
        by = collections.Counter(r["knot"] for r in rows if own(r))
        out["searches"][name] = {
            "settings_hash": h, "knots": len(g),
            "own_replicas": sum(by.values()),
            "own_cpu_seconds": round(sum(r["cpu_seconds"] or 0 for r in rows if own(r)), 1),
            "seeded_cpu_seconds": round(sum(r["cpu_seconds"] or 0 for r in rows
                                            if not own(r)), 1),
            "converged": sum(ensemble_converged(x) for x in g.values())}
        for k, x in g.items():
            out["knots"].setdefault(k, {})[name] = {
                "epsilon": x["epsilon"], "converged": ensemble_converged(x),
                "own_replicas": by[k], "state": x["state"]}
    for name in hashes:
        bad = []
        for k, e in out["knots"].items():
            lo = min(v["epsilon"] for v in e.values())
            if e.get(name, {}).get("converged") and e[name]["epsilon"] > lo * (1 + 1e-3):
                bad.append(k)
        out["searches"][name]["verdicts_above_other"] = sorted(bad, key=knot_sort_key)
        lower = sum(1 for e in out["knots"].values() if name in e and len(e) > 1
                    and e[name]["epsilon"] < min(v["epsilon"] for n, v in e.items()
                                                 if n != name) * (1 - 1e-3))
        out["searches"][name]["grounds_lower_than_other"] = lower
    out["replay"] = []
    for cap in replay:
        with tempfile.TemporaryDirectory() as tmp:
            s2 = Store(capped_copy(db, tmp, cap), create=False)
            for name, h in hashes.items():
                g = s2.ground_states(settings_hash=h, structure=False)
                cpu = sum(r["cpu_seconds"] or 0 for r in s2.replicas(settings_hash=h)
                          if own(r))
                out["replay"].append({"cap": cap, "search": name,
                                      "converged": sum(ensemble_converged(x) for x in g),
                                      "own_cpu_seconds": round(cpu, 1)})
            s2.close()
    st.close()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--db", required=True)
    ap.add_argument("--knots", default=SAMPLE)
    ap.add_argument("--cap", type=int, default=16, help="most Langevin bead replicas")
    ap.add_argument("--replay", default="", help="caps to replay, e.g. 4,6,8")
    ap.add_argument("--compare-only", action="store_true")
    ap.add_argument("--json", nargs="?", const=str(stable_path("atlas_bead_search")),
                    help="also write the comparison to FILE "
                         "(default: bench/atlas_bead_search.json)")
    a = ap.parse_args(argv)
    knots = [k.strip() for k in a.knots.split(",") if k.strip()]
    models = parse_models("bead,tube")
    buds = budgets(a.cap)
    bead = models[0]
    hashes = {n: settings_hash(sweep_settings(bead, b)) for n, b in buds.items()}
    walls = {}
    if not a.compare_only:
        for name, b in buds.items():
            with Store(a.db) as st:
                t0 = time.perf_counter()
                res = run_sweep(knots, models, b, st, seed=0)
                walls[name] = time.perf_counter() - t0
            print(f"{name}: {res.ran} jobs in {walls[name]:.1f} s wall, {res.cpu_seconds:.0f} "
                  "CPU s (the first sweep runs the tube ensembles too)", flush=True)
    d = compare(a.db, hashes, [int(c) for c in a.replay.split(",") if c.strip()])
    d["wall_seconds"] = walls
    d["cap"] = a.cap
    for name, s in d["searches"].items():
        print(f"{name:9s} converged {s['converged']}/{s['knots']}, own replicas "
              f"{s['own_replicas']}, own CPU {s['own_cpu_seconds']:.0f} s, lower grounds "
              f"{s['grounds_lower_than_other']}, verdicts above the other's lowest: "
              f"{', '.join(s['verdicts_above_other']) or 'none'}")
    names = list(hashes)
    print("knot     " + " | ".join(f"{n:>24s}" for n in names))
    for k in sorted(d["knots"], key=knot_sort_key):
        e = d["knots"][k]
        cells = [(f"{e[n]['epsilon']:10.3f} {'✓' if e[n]['converged'] else '·'} "
                  f"{e[n]['own_replicas']:2d} own" if n in e else "—").rjust(24)
                 for n in names]
        print(f"{k:8s} " + " | ".join(cells))
    for r in d["replay"]:
        print(f"cap {r['cap']:2d}: {r['search']:9s} converged {r['converged']}, own CPU "
              f"{r['own_cpu_seconds']:.0f} s")
    if a.json:
        Path(a.json).write_text(json.dumps({"meta": run_meta(argv), **d}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
