"""Two atlas databases of the same knots, their bead-rule ensembles compared cap by cap.

    python bench/atlas_compare.py A.db B.db [--bead-caps 2,4,6,8,16] [--json [FILE]]

A and B are two sweeps of the same knots that differ in the bead rule's search (for example
the default 10⁶ Langevin steps a replica against ``--bead-steps 3e6``), their tube replicas
the same. A sweep's replicas are a prefix (``bench/atlas_replay.py``), so each database
replayed at a bead cap c — its own bead replicas numbered ≥ c removed, the replicas seeded
from tube replicas kept — is exactly the sweep that cap would have run. For every cap this
prints, for A and for B: the knots converged, the bead CPU seconds, and how many of the
converged grounds lie more than 0.1 % above the lowest state *either* database holds for the
knot (a wrong verdict, found by the other search); and, over all stored replicas, for how
many knots B's lowest lies below A's by more than 0.1 % and above it.

Only the knots of both databases with a bead ensemble count. Every ε at the stored width (N
and d), as stored; the seed is each sweep's own.
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from atlas_replay import capped_copy  # noqa: E402
from benchmeta import run_meta, stable_path  # noqa: E402
from stiffknots.store.sqlite import Store  # noqa: E402
from stiffknots.sweeps.convergence import ensemble_converged  # noqa: E402

REL = 1e-3  # the verdict's tolerance: two states within 0.1 % are the same


def _bead_knots(path: str) -> set[str]:
    with sqlite3.connect(path) as con:
        return {r[0] for r in con.execute(
            "SELECT DISTINCT knot FROM replicas WHERE exclusion = 'bead'")}


def _lowest(path: str, knots: list[str]) -> dict[str, float]:
    q = ",".join("?" * len(knots))
    with sqlite3.connect(path) as con:
        return {k: float(e) for k, e in con.execute(
            f"SELECT knot, MIN(epsilon) FROM replicas WHERE exclusion = 'bead' AND knot IN "
            f"({q}) GROUP BY knot", knots)}


def at_cap(path: str, cap: int, knots: list[str]) -> dict:
    """The bead ensembles of ``path`` (only ``knots``) as the sweep capped at ``cap`` would
    have left them: per knot the ground's ε and the verdict, and the bead CPU seconds."""
    with tempfile.TemporaryDirectory() as tmp:
        copy = capped_copy(path, tmp, cap)
        q = ",".join("?" * len(knots))
        with sqlite3.connect(copy) as con:
            con.execute(f"DELETE FROM replicas WHERE knot NOT IN ({q})", knots)
            cpu = float(con.execute("SELECT SUM(cpu_seconds) FROM replicas WHERE "
                                    "exclusion = 'bead'").fetchone()[0] or 0.0)
        st = Store(copy, create=False)
        grounds = {g["knot"]: g for g in st.ground_states(exclusion="bead", structure=False)}
        st.close()
    return {"cpu_seconds": round(cpu, 1),
            "grounds": {k: {"epsilon": float(g["epsilon"]), "converged": ensemble_converged(g)}
                        for k, g in grounds.items()}}


def compare(a: str, b: str, caps: list[int]) -> dict:
    knots = sorted(_bead_knots(a) & _bead_knots(b))
    if not knots:
        raise SystemExit(f"no knot has a bead ensemble in both {a} and {b}")
    low_a, low_b = _lowest(a, knots), _lowest(b, knots)
    best = {k: min(low_a[k], low_b[k]) for k in knots}
    out = {"a": a, "b": b, "knots": knots,
           "b_lower": sorted(k for k in knots if low_b[k] < low_a[k] * (1 - REL)),
           "b_higher": sorted(k for k in knots if low_b[k] > low_a[k] * (1 + REL)),
           "caps": []}
    for cap in caps:
        row = {"cap": cap}
        for name, path in (("a", a), ("b", b)):
            r = at_cap(path, cap, knots)
            conv = sorted(k for k, g in r["grounds"].items() if g["converged"])
            wrong = sorted(k for k in conv if r["grounds"][k]["epsilon"] > best[k] * (1 + REL))
            row[name] = {"converged": len(conv), "wrong": wrong, "cpu_seconds": r["cpu_seconds"],
                         "not_converged": sorted(set(knots) - set(conv))}
        out["caps"].append(row)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--bead-caps", default="2,4,6,8,10,12,16")
    ap.add_argument("--json", nargs="?", const=str(stable_path("atlas_compare")),
                    help="also write the comparison to FILE (default: bench/atlas_compare.json)")
    args = ap.parse_args(argv)
    caps = [int(c) for c in args.bead_caps.split(",") if c.strip()]
    out = compare(args.a, args.b, caps)
    n = len(out["knots"])
    print(f"{n} knots with a bead ensemble in both; over all stored replicas B's lowest lies "
          f"below A's by > 0.1 % for {len(out['b_lower'])}, above for {len(out['b_higher'])}")
    for row in out["caps"]:
        print(f"bead cap {row['cap']:2d}: " + ";  ".join(
            f"{name.upper()} {row[name]['converged']}/{n} converged "
            f"({len(row[name]['wrong'])} above the other's lowest), bead CPU "
            f"{row[name]['cpu_seconds']:.0f} s" for name in ("a", "b")))
    if args.json:
        Path(args.json).write_text(json.dumps({"meta": run_meta(argv), **out}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
