"""Verdict rules and search budgets side by side: several tube atlases of the same knots (other
budgets, other rules), each verdict judged against the lowest state that *any* of them — or a
further run — found for its knot.

A verdict is counted false when its ground lies more than 0.1 % (the verdict's own tolerance)
above that lowest state. This is not an audit (``stiffknots audit`` searches every verdict
again); it pools what the runs found, so a run is judged by the others' searches too. The rule
of each database is the tube's rule of k searches (``problems.base.AGREE["tube"]`` set to k
while it is judged); its CPU seconds are those of its stored replicas.

    python bench/verdict_rules.py LABEL=DB:K [LABEL=DB:K ...] [--also DIR_OR_JSON ...]

``--also`` adds lowest states from ``stiffknots anneal --json`` outputs (a folder of them) or a
``bench/verdict_audit.json`` (its entries' ``audit_epsilon``). A database's own audit searches
(problem ``audit``) count towards the lowest state too; its verdicts are read from its sweep
ensemble (problem ``anneal``). ``--knots`` limits the comparison to those knots (the runs' other
knots are left out); ``--name`` writes bench/NAME.json instead of bench/verdict_rules.json.

``LABEL=DB:K@2,4,6`` replays a sweep that stops early: a sweep's replica r depends only on the
replicas before it, so a sweep under the rule of K that adds replicas 2 at a time from 2 would
have run exactly the stored replicas numbered below the first of those caps at which the
prefix converged (all of them where none did). Only for databases without continuation legs
(a sweep with ``--moves``, which runs none).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from benchmeta import run_meta, stable_path

TOL = 1e-3


def _lowest_from(path: Path, low: dict[str, float]) -> None:
    files = sorted(path.glob("*.json")) if path.is_dir() else [path]
    for f in files:
        try:
            d = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if "entries" in d:  # an audit
            pairs = [(e["knot"], e.get("audit_epsilon")) for e in d["entries"]]
        elif "replicas" in d:  # anneal --json
            pairs = [(d["knot"], r["epsilon"]) for r in d["replicas"]]
        else:
            continue
        for k, e in pairs:
            if e is not None:
                low[k] = min(low.get(k, float("inf")), float(e))


def _stopped_early(db: str, mine: dict, caps: list[int]) -> dict:
    """``mine`` (knot → (states, replicas, CPU s)) as a sweep that stops at the first of
    ``caps`` where the knot's verdict holds (the rule as set now) would have left it."""
    import sqlite3
    import tempfile

    from stiffknots.store.sqlite import Store
    from stiffknots.sweeps.convergence import ensemble_converged
    from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA
    from stiffknots.sweeps.legs import LEG_REPLICA

    own_below = min(OLDER_SEEDED_REPLICA, LEG_REPLICA)  # a model's own searches' numbers
    with sqlite3.connect(db) as con:
        if con.execute("SELECT COUNT(*) FROM replicas WHERE problem = 'anneal' AND "
                       "replica >= ?", (own_below,)).fetchone()[0]:
            raise SystemExit(f"{db}: continuation legs or seeded replicas: no early-stop replay")
    out, left = {}, set(mine)
    with tempfile.TemporaryDirectory() as tmp:
        for cap in caps:
            copy = f"{tmp}/cap{cap}.db"
            with sqlite3.connect(db) as src, sqlite3.connect(copy) as dst:
                src.backup(dst)  # safe beside a running writer
            with sqlite3.connect(copy) as con:
                con.execute("DELETE FROM replicas WHERE problem = 'anneal' AND replica >= ?",
                            (cap,))
            with Store(copy, readonly=True) as st:
                for knot in sorted(left):
                    h = mine[knot][0]["settings_hash"]
                    s = st.states(knot, exclusion="tube", settings_hash=h, structure=False)
                    if ensemble_converged(s):
                        rows = st.replicas(knot=knot, exclusion="tube", problem="anneal")
                        out[knot] = (s, len(rows), sum(r["cpu_seconds"] or 0 for r in rows))
                        left.discard(knot)
    out.update({k: mine[k] for k in left})
    return out


def main(argv: list[str] | None = None) -> None:
    import stiffknots.problems.base as base
    from stiffknots.store.sqlite import Store
    from stiffknots.sweeps.convergence import ensemble_converged

    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+", help="LABEL=DB:K (K: searches the tube verdict needs)")
    ap.add_argument("--also", nargs="*", default=[])
    ap.add_argument("--note", default=None, help="How the databases were made (in the meta).")
    ap.add_argument("--knots", default=None, help="Only these knots, separated by commas.")
    ap.add_argument("--name", default="verdict_rules")
    a = ap.parse_args(argv)
    only = set(a.knots.split(",")) if a.knots else None
    runs = []
    for spec in a.runs:
        label, rest = spec.split("=", 1)
        db, k = rest.rsplit(":", 1)
        k, _, caps = k.partition("@")
        runs.append((label, db, int(k), [int(c) for c in caps.split(",")] if caps else None))
    low: dict[str, float] = {}
    for p in a.also:
        _lowest_from(Path(p), low)
    states = {}
    for label, db, _, _ in runs:
        with Store(db, readonly=True) as st:
            for knot in st.knots():
                if only is not None and knot not in only:
                    continue
                ens = st.ensembles(knot=knot, exclusion="tube", problem="anneal")
                if len(ens) != 1:
                    raise SystemExit(f"{db}: {knot} has {len(ens)} tube sweep ensembles, not 1")
                s = st.states(knot, exclusion="tube", settings_hash=ens[0]["settings_hash"],
                              structure=False)
                rows = st.replicas(knot=knot, exclusion="tube", problem="anneal")
                states[(label, knot)] = (s, len(rows), sum(r["cpu_seconds"] or 0 for r in rows))
                every = [r["epsilon"] for r in st.replicas(knot=knot, exclusion="tube")]
                low[knot] = min(low.get(knot, float("inf")), *every)  # the ground among them
    out, saved = [], base.AGREE["tube"]
    try:
        for label, db, k, caps in runs:
            base.AGREE["tube"] = k
            mine = {kn: v for (lb, kn), v in states.items() if lb == label}
            if caps:
                mine = _stopped_early(db, mine, caps)
            conv, false = [], []
            for knot, (s, _, _) in mine.items():
                if ensemble_converged(s):
                    conv.append(knot)
                    g = s["ground"]["epsilon"]
                    if g > low[knot] * (1 + TOL):
                        false.append({"knot": knot, "epsilon": g, "lowest": low[knot],
                                      "above": g / low[knot] - 1})
            out.append({"label": label, "db": db, "rule": k, "caps": caps, "knots": len(mine),
                        "converged": len(conv), "false": sorted(false, key=lambda e: -e["above"]),
                        "replicas": sum(v[1] for v in mine.values()),
                        "cpu_seconds": sum(v[2] for v in mine.values())})
    finally:
        base.AGREE["tube"] = saved
    for r in out:
        print(f"{r['label']}: rule of {r['rule']}, converged {r['converged']} of {r['knots']}, "
              f"false {len(r['false'])} ("
              + ", ".join(f"{e['knot']} +{100 * e['above']:.1f} %" for e in r["false"])
              + f"), {r['replicas']} replicas, {r['cpu_seconds']:.0f} CPU s")
    doc = {"meta": run_meta(argv, note=a.note),
           "tolerance": TOL, "runs": out, "lowest": low}
    stable_path(a.name).write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
