"""The audit of the tube atlas through 10 crossings, run in chunks that each finish: a fixed
random order of the 249 prime knots, and each call sweeps the next knots of it and audits
their converged verdicts at the audit's defaults.

    python bench/audit_campaign.py --count 30 [--db DB] [--note TEXT]
    python bench/audit_campaign.py --count 30 --search 30M \\
        --atlas-args "--moves 3e7 --max-replicas 6" [--db DB]

Why chunks: the sweep of all 249 knots under the rule of three and the audit of 80 of them
take about five hours on 2 cores, more than one sitting of a machine whose disk is not kept;
each chunk here is a complete sweep + audit of its knots, and the JSON keeps every chunk's
rows, so the sample grows call by call. The order is ``random.Random(0).sample`` of the 249
names (``--order-seed``): the union of the chunks done is a uniform random sample of the
knots, and the audited entries are its converged verdicts — the issue's "≥ 80 random
converged knots through 10 crossings" once enough chunks are in.

Per chunk: ``stiffknots atlas --knots CHUNK --models tube [ATLAS-ARGS] --db DB --json`` (seed
0: the replica seeds derive from the seed and the knot, so a knot's verdict is the one the
249-knot atlas with the same options gives it), then ``stiffknots audit --db DB --knots CHUNK
--sample 1000 --json`` (depth 2 of the search's own replicas, 3 searches, seed 0). ``--search``
names the search compared: each keeps its own rows, chunks and rate (``default``: the atlas's
own defaults). A knot's CPU seconds are its stored replicas' own. Writes
bench/audit_campaign.json: every knot's row per search, every chunk's wall and CPU time, and
each search's false-verdict rate with its 95 % Wilson interval over its chunks.
"""

from __future__ import annotations

import argparse
import json
import random
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmeta import run_meta, stable_path

MAX_CROSSINGS = 10
#: The label of the atlas's own search (no options beyond --models tube).
DEFAULT = "default"


def order(seed: int = 0) -> list[str]:
    """The campaign's fixed random order of the prime knots through 10 crossings."""
    from stiffknots.sweeps.plan import resolve_knots

    names = resolve_knots(max_crossings=MAX_CROSSINGS)
    return random.Random(seed).sample(names, len(names))


def _cli(args: list[str]) -> dict:
    """Run ``stiffknots ARGS --json`` (progress on this terminal), return its JSON."""
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args, "--json"],
                       stdout=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise SystemExit(f"stiffknots {' '.join(args[:3])} … failed ({p.returncode})")
    return json.loads(p.stdout)


def agreeing_starts(db: str, knots: list[str]) -> dict[str, list[str]]:
    """Per knot, the default starts (braid, cage, 80, …) whose sweep searches reached its tube
    ground within the verdict's 0.1 % (as bench/verdict_audit.py reads them): one start alone
    is two replicas of one start family agreeing."""
    from stiffknots.store import Store
    from stiffknots.sweeps.convergence import REL_TOL

    out = {}
    with Store(db, readonly=True) as st:
        for g in st.ground_states(knot=knots, exclusion="tube", problem="anneal",
                                  structure=False):
            lo = g["epsilon"]
            out[g["knot"]] = sorted(s for s, eps in (g.get("eps_by_start") or {}).items()
                                    if any(x - lo <= REL_TOL * lo for x in eps))
    return out


def summary(knots: dict) -> dict:
    from stiffknots.sweeps.audit import wilson_interval

    audited = [r for r in knots.values() if r.get("audited")]
    k = sum(int(r["false_verdict"]) for r in audited)
    lo, hi = wilson_interval(k, len(audited))
    by_c: dict[int, list] = {}
    for r in knots.values():
        by_c.setdefault(r["crossings"], []).append(r)
    cpu = [r["atlas_cpu_seconds"] for r in knots.values()]
    return {"knots": len(knots), "converged": sum(r["converged"] for r in knots.values()),
            "audited": len(audited), "false": k, "rate": k / len(audited) if audited else None,
            "low": lo, "high": hi,
            "false_entries": sorted(r["knot"] for r in audited if r["false_verdict"]),
            "by_start_families": {
                key: {"audited": len(v), "false": sum(bool(r["false_verdict"]) for r in v)}
                for key, v in (("one", [r for r in audited
                                        if len(r.get("agreeing_starts") or []) <= 1]),
                               ("several", [r for r in audited
                                            if len(r.get("agreeing_starts") or []) >= 2]))},
            "atlas_cpu_seconds_per_knot": sum(cpu) / len(cpu) if cpu else None,
            "by_crossings": {str(c): {"knots": len(v), "converged": sum(r["converged"] for r in v),
                                      "audited": sum(bool(r.get("audited")) for r in v),
                                      "false": sum(bool(r.get("false_verdict")) for r in v),
                                      "atlas_cpu_seconds": sum(r["atlas_cpu_seconds"] for r in v)}
                             for c, v in sorted(by_c.items())}}


def _load(path: Path, order_seed: int) -> dict:
    doc = json.loads(path.read_text()) if path.exists() else {"searches": {}, "chunks": []}
    if "knots" in doc:  # the first chunk's layout: one search, the atlas's defaults
        doc = {"order_seed": doc["order_seed"], "chunks": [
            {**c, "search": DEFAULT} for c in doc["chunks"]],
            "searches": {DEFAULT: {"atlas_args": [], "knots": doc["knots"]}}}
    if doc.get("order_seed", order_seed) != order_seed:
        raise SystemExit(f"{path} holds the order of seed {doc['order_seed']}")
    doc["order_seed"] = order_seed
    return doc


def _write(path: Path, doc: dict) -> None:
    for run in doc["searches"].values():
        run["summary"] = summary(run["knots"])
    doc["meta"] = doc["chunks"][-1]["meta"]  # the page quotes the latest chunk's
    path.write_text(json.dumps(doc, indent=1) + "\n")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=25, help="Knots in this chunk.")
    ap.add_argument("--db", default=None, help="Results database (default: a temporary one).")
    ap.add_argument("--search", default=DEFAULT,
                    help="Label of the search compared (each keeps its own rows and rate).")
    ap.add_argument("--atlas-args", default="",
                    help="Options of `stiffknots atlas` that make the search, e.g. "
                         "'--moves 3e7 --max-replicas 6' (none: the atlas's defaults).")
    ap.add_argument("--order-seed", type=int, default=0)
    ap.add_argument("--note", default=None)
    ap.add_argument("--refresh", action="store_true",
                    help="Run nothing: reread the agreeing starts of the search's knots "
                         "stored in --db and rewrite the summaries.")
    a = ap.parse_args(argv)
    path = stable_path("audit_campaign")
    doc = _load(path, a.order_seed)
    extra = a.atlas_args.split()
    run = doc["searches"].setdefault(a.search, {"atlas_args": extra, "knots": {}})
    if run["atlas_args"] != extra:
        raise SystemExit(f"search {a.search!r} was run with atlas options "
                         f"{' '.join(run['atlas_args']) or '(none)'}, not {a.atlas_args!r}")
    if a.refresh:
        if not a.db:
            raise SystemExit("--refresh reads --db")
        for k, v in agreeing_starts(a.db, list(run["knots"])).items():
            run["knots"][k]["agreeing_starts"] = v
        _write(path, doc)
        return
    todo = [k for k in order(a.order_seed) if k not in run["knots"]][:a.count]
    if not todo:
        print(f"every knot through 10 crossings is in the campaign of {a.search!r}")
        return
    db = a.db or str(Path(tempfile.mkdtemp(prefix="campaign")) / "a.db")
    chunk = ",".join(todo)
    print(f"{a.search}: chunk of {len(todo)} knots ({len(run['knots'])} done before) into "
          f"{db}: {chunk}", flush=True)
    t0 = time.perf_counter()
    at = _cli(["atlas", "--knots", chunk, "--models", "tube", *extra, "--db", db,
               "--out", str(Path(db).parent / "atlas")])
    t1 = time.perf_counter()
    au = _cli(["audit", "--db", db, "--knots", chunk, "--sample", "1000"])
    t2 = time.perf_counter()
    with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as con:
        cpu = {(k, p): c for k, p, c in con.execute(
            "SELECT knot, problem, sum(cpu_seconds) FROM replicas WHERE exclusion = 'tube' "
            "GROUP BY knot, problem")}
    audits = {e["knot"]: e for e in au["entries"]}
    starts = agreeing_starts(db, todo)
    for e in at["knots"]:
        m = e["models"]["tube"]
        g = m["ground"] or {}
        row = {"knot": e["name"], "crossings": e["crossing_number"],
               "converged": bool(m["converged"]), "epsilon": g.get("epsilon"),
               "state": g.get("name"), "replicas": m.get("replicas"),
               "agreeing_starts": starts.get(e["name"], []),
               "atlas_cpu_seconds": round(cpu.get((e["name"], "anneal"), 0.0), 1),
               "chunk": len(doc["chunks"])}
        x = audits.get(e["name"])
        if x is not None and x["searches"] > 0:
            row.update(audited=True, false_verdict=bool(x["false_verdict"]),
                       audit_epsilon=x["audit_epsilon"], audit_state=x["audit_state"],
                       gap=x["gap"],
                       audit_cpu_seconds=round(cpu.get((e["name"], "audit"), 0.0), 1))
        run["knots"][e["name"]] = row
    sw = at["sweep"]
    doc["chunks"].append({"meta": run_meta(argv, note=a.note), "search": a.search,
                          "knots": todo,
                          "atlas_wall_seconds": round(t1 - t0, 1),
                          "atlas_cpu_seconds": round(sw["cpu_seconds"], 1),
                          "atlas_jobs": sw["jobs"], "atlas_jobs_stored_before": sw["skipped"],
                          "audit_wall_seconds": round(t2 - t1, 1),
                          "audit_cpu_seconds": round(au["search_cpu_seconds"], 1),
                          "audit_id": au["audit"]})
    _write(path, doc)
    s = run["summary"]
    rate = f"{100 * s['rate']:.1f} %" if s["rate"] is not None else "—"
    print(f"{a.search}: {s['knots']} knots, {s['converged']} converged, {s['audited']} "
          f"audited: {s['false']} false ({rate}, 95 % interval {100 * s['low']:.1f}–"
          f"{100 * s['high']:.1f} %); false: {', '.join(s['false_entries']) or 'none'}; "
          f"this chunk {t1 - t0:.0f} s + {t2 - t1:.0f} s wall; wrote {path}")


if __name__ == "__main__":
    main()
