"""The audit of an atlas's verdicts: how often a converged ground state is beaten by a second,
independent search — and whether verdicts reached from one start family fail more often.

Runs ``stiffknots audit --db DB`` with the given options (its searches are stored in DB: run
again, it only recomputes), then reads, for every audited entry, the starts of the searches that
reached its ground (its ``eps_by_start`` within the verdict's 0.1 %): a verdict whose agreeing
searches all started from one embedding (two replicas of one funnel?) against one where
different embeddings agreed. Writes bench/verdict_audit.json.

    python bench/verdict_audit.py DB [--sample 80] [--depth 2] [--replicas 3] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

from benchmeta import run_meta, stable_path


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("db")
    ap.add_argument("--sample", default="80")
    ap.add_argument("--depth", default="2")
    ap.add_argument("--replicas", default="3")
    ap.add_argument("--seed", default="0")
    ap.add_argument("--models", default="tube")
    ap.add_argument("--max-crossings", default=None)
    ap.add_argument("--note", default=None, help="How DB was made (stored in the meta).")
    a = ap.parse_args(argv)
    cmd = [sys.executable, "-m", "stiffknots.cli", "audit", "--db", a.db, "--sample", a.sample,
           "--depth", a.depth, "--replicas", a.replicas, "--seed", a.seed, "--models",
           a.models, "--json"]
    if a.max_crossings:
        cmd += ["--max-crossings", a.max_crossings]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"audit failed ({p.returncode}): {p.stderr.strip()[-500:]}")
    d = json.loads(p.stdout)

    from stiffknots.store import Store
    from stiffknots.sweeps.audit import summarise
    from stiffknots.sweeps.convergence import REL_TOL

    with Store(a.db, readonly=True) as st:
        grounds = {(g["knot"], g["exclusion"], g["settings_hash"]): g
                   for g in st.ground_states(problem="anneal", structure=False)}
    for e in d["entries"]:
        g = grounds[(e["knot"], e["exclusion"], e["settings_hash"])]
        lo = g["epsilon"]
        starts = sorted(s for s, eps in (g.get("eps_by_start") or {}).items()
                        if any(x - lo <= REL_TOL * lo for x in eps))
        e["agreeing_starts"] = starts
        e["start_families"] = len(starts)
    one = [e for e in d["entries"] if e["start_families"] == 1]
    several = [e for e in d["entries"] if e["start_families"] >= 2]
    out = {"meta": run_meta(argv, note=a.note), "db": a.db, "audit": d["audit"],
           "params": d["params"],
           "converged": d["converged"], "summary": d["summary"],
           "by_start_families": {"one": summarise(one), "several": summarise(several)},
           "false": [{k: e[k] for k in ("knot", "exclusion", "epsilon", "state",
                                        "audit_epsilon", "audit_state", "gap",
                                        "agreeing_starts")}
                     for e in d["entries"] if e["false_verdict"]],
           "entries": [{k: e[k] for k in ("knot", "exclusion", "crossings", "epsilon", "state",
                                          "audit_epsilon", "audit_state", "false_verdict",
                                          "searches", "agreeing_starts")}
                       for e in d["entries"]],
           "search_cpu_seconds": d["search_cpu_seconds"]}
    s = d["summary"]["all"]
    print(f"{s['false']} of {s['n']} verdicts false ({100 * (s['rate'] or 0):.1f} %, 95 % "
          f"interval {100 * s['low']:.1f}–{100 * s['high']:.1f} %), "
          f"{d['search_cpu_seconds']:.0f} "
          "CPU s of audit searches")
    for key, sub in out["by_start_families"].items():
        r = sub["all"]
        print(f"  agreeing searches from {key} start famil{'y' if key == 'one' else 'ies'}: "
              f"{r['false']} of {r['n']} false")
    for e in out["false"]:
        print(f"  false: {e['knot']} {e['epsilon']:.2f} ({e['state']}) → "
              f"{e['audit_epsilon']:.2f} ({e['audit_state']}), {100 * e['gap']:.2f} % lower; "
              f"agreeing starts {', '.join(e['agreeing_starts'])}")
    path = stable_path("verdict_audit")
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
