"""Every state to w = 0, knot by knot: `stiffknots thin-limit K` as typed, its wall time, each
state's two routes and the thin-limit ground state.

    python bench/thin_states.py KNOT[:BUDGET] ... [--out DIR]   # runs them (DIR/K.json kept)
    python bench/thin_states.py --from DIR                       # reads DIR/*.json only

(with ``--from``, a ``DIR/K.time`` written by ``/usr/bin/time -f "%e s wall %U user"`` gives
the wall and user CPU seconds of the command; without one, the study's own wall time.)

Each knot runs in a fresh process with the command's defaults (``--budget default`` unless
``:small`` is given) and ``--json``; the wall and CPU seconds are the process's
(``resource.getrusage`` of the children). A state's two routes agree when the Monte Carlo
limit and the structure route differ by less than twice the branch's error or 0.5 %
(``stiffknots.studies.thin_states.AGREE_REL``). Writes bench/thin_states.json.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

from benchmeta import run_meta, stable_path


def _run(knot: str, budget: str, out: Path) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "thin-limit", knot,
                        "--budget", budget, "--json"], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"thin-limit {knot} failed ({p.returncode}): {p.stderr[-2000:]}")
    d = json.loads(p.stdout)
    d["bench"] = {"wall_seconds": wall,
                  "cpu_seconds": (after.ru_utime - before.ru_utime)
                  + (after.ru_stime - before.ru_stime)}
    (out / f"{knot}.json").write_text(json.dumps(d) + "\n")
    return d


def _row(d: dict) -> dict:
    states = []
    for s in d["states"]:
        r = s.get("structure_route") or {}
        states.append({"shape": s["shape"], "epsilon": s["epsilon"],
                       "epsilon_thin": s["epsilon_thin"], "error": s["error"],
                       "structure_epsilon": s["structure_epsilon"],
                       "route": r.get("method"), "agree": s["agree"],
                       "event": s["event"], "note": r.get("note")})
    m = d.get("margin") or {}
    b = d.get("bench") or {}
    return {"knot": d["knot"], "budget": d["budget"], "census_width": d["census"]["width"],
            "wall_seconds": b.get("wall_seconds", d.get("wall_time")),
            "cpu_seconds": b.get("cpu_seconds"), "ground": d["ground"], "shape": d["shape"],
            "epsilon_thin": d["epsilon_thin"], "error": d["error"],
            "margin_sigmas": m.get("sigmas"), "crossing": d.get("crossing"),
            "states": states}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("knots", nargs="*", help="KNOT or KNOT:small")
    ap.add_argument("--out", default="runs/bench-thin", help="Folder of the runs' JSON.")
    ap.add_argument("--from", dest="src", default=None, help="Read DIR/*.json, run nothing.")
    ap.add_argument("--note", default=None)
    a = ap.parse_args(argv)
    docs = []
    if a.src:
        for f in sorted(Path(a.src).glob("*.json")):
            try:
                d = json.loads(f.read_text())
            except ValueError:
                continue
            if not ("states" in d and "census" in d):
                continue
            t = f.with_suffix(".time")        # /usr/bin/time -f "%e s wall %U user" -o K.time
            if "bench" not in d and t.exists():
                w = t.read_text().split()
                d["bench"] = {"wall_seconds": float(w[0]), "cpu_seconds": float(w[3])}
            docs.append(d)
    else:
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        for spec in a.knots:
            knot, _, budget = spec.partition(":")
            docs.append(_run(knot, budget or "default", out))
    rows = [_row(d) for d in docs]
    compared = [s for r in rows for s in r["states"] if s["agree"] is not None]
    for r in rows:
        g = r["states"][r["ground"]] if r["ground"] is not None else None
        print(f"{r['knot']} ({r['budget']}): {len(r['states'])} states, ground "
              f"{r['shape']} ε* = {r['epsilon_thin']:.4f} ± {r['error']:.2g}"
              + (f", route {g['structure_epsilon']:.4f}" if g and g["structure_epsilon"]
                 else "") + f", {r['wall_seconds']:.0f} s wall")
    doc = {"meta": run_meta(argv, note=a.note), "knots": rows,
           "states": sum(len(r["states"]) for r in rows),
           "compared": len(compared), "agree": sum(bool(s["agree"]) for s in compared),
           "wall_seconds": sum(r["wall_seconds"] or 0 for r in rows)}
    print(f"{doc['agree']} of {doc['compared']} compared states agree; "
          f"{doc['states']} states; {doc['wall_seconds']:.0f} s wall in all")
    stable_path("thin_states").write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
