"""Every prime knot through 8 crossings with `stiffknots anneal K` and its defaults.

What a new user gets: for each knot the command is run exactly as typed (N = 150, bead rule,
2 replicas per round on the two cores, up to 8 rounds — two of new searches, then legs of
basin hops continuing the lowest searches that still improve — until two independent
searches agree on the lowest state to 0.1 %), and its --json is read: ε of the best replica,
its shape, the verdict (`converged` and its reason), the rounds used and the wall time.
Prints one line per knot and a summary; writes bench/defaults_survey.json (or ``--out FILE``)
after every knot, with every replica's search (lineage, leg), start, ε and shape, and skips the
knots already in it (delete it to start over).

    python bench/defaults_survey.py [--out FILE] [--with "ANNEAL OPTIONS"] [KNOT ...]

``--with`` adds options to every command (e.g. ``--with "--exclusion tube"``: the tube model
with the same defaults otherwise); they are recorded in each row as ``options``.
"""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
import time
from pathlib import Path

from stiffknots.knots.catalogue import catalogue


def _replica(r: dict) -> dict:
    obs = r.get("observables") or {}
    return {"replica": r.get("replica"), "lineage": r.get("lineage"), "leg": r.get("leg"),
            "start": r.get("start"), "epsilon": r.get("epsilon"), "shape": obs.get("label"),
            "search": obs.get("search"),
            "wall_s": r.get("wall_time"), "cpu_s": r.get("cpu_time")}


def main(argv: list[str]) -> None:
    path = Path(__file__).with_name("defaults_survey.json")
    if argv[:1] == ["--out"]:
        path, argv = Path(argv[1]), argv[2:]
    options: list[str] = []
    if argv[:1] == ["--with"]:
        options, argv = shlex.split(argv[1]), argv[2:]
    knots = argv or [k.name for k in catalogue() if 3 <= k.crossing_number <= 8]
    # resumable: the knots already in the file are kept and not run again
    rows = json.loads(path.read_text()) if path.exists() else []
    done = {r["knot"] for r in rows}
    for name in knots:
        if name in done:
            continue
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "anneal", name, "--json",
                            *options], capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            rows.append({"knot": name, "rc": p.returncode, "options": options,
                         "error": p.stderr.strip()[-300:],
                         "wall_s": wall})
            print(f"{name:6s} rc={p.returncode} {p.stderr.strip()[-200:]}", flush=True)
            continue
        d = json.loads(p.stdout)
        row = {"knot": name, "rc": 0, "options": options, "epsilon": d["epsilon"],
               "shape": d.get("shape"), "converged": d.get("converged"),
               "reason": d.get("convergence"), "rounds": d.get("rounds"),
               "replicas": len(d.get("replicas", [])), "wall_s": round(wall, 1),
               "width": d.get("width"),
               "searches": [_replica(r) for r in d.get("replicas", [])]}
        rows.append(row)
        path.write_text(json.dumps(rows, indent=2))
        print(f"{name:6s} ε = {row['epsilon']:9.3f}  {str(row['shape']):7s} "
              f"converged={row['converged']!s:5s} rounds={row['rounds']} "
              f"{row['wall_s']:6.1f} s  {row['reason']}", flush=True)
    ok = [r for r in rows if r.get("converged")]
    print(f"\nconverged: {len(ok)} of {len(rows)} "
          f"({100 * len(ok) / max(1, len(rows)):.0f} %); not: "
          f"{', '.join(r['knot'] for r in rows if not r.get('converged'))}")
    print(f"total wall: {sum(r['wall_s'] for r in rows) / 60:.1f} min")
    path.write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main(sys.argv[1:])
