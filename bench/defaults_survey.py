"""Every prime knot through 8 crossings with `stiffknots anneal K` and its defaults.

What a new user gets: for each knot the command is run exactly as typed (N = 150, bead rule,
every option at its default: 2 replicas a round on the two cores, rounds until two independent
searches agree on the lowest state to 0.1 % or the schedule's most rounds; docs/methods/search.md)
and its --json is read: ε of the best replica, its shape, the verdict (`converged` and its
reason), the rounds used and the wall time. Prints one line per knot and a summary; writes
bench/defaults_survey.json after every knot — the survey of the defaults, the current result
of this benchmark — with every replica's search (lineage, leg), start, ε and shape, and skips
the knots already in it (delete it to start over). A variant (``--with``) writes to
``--out FILE``, not over the survey of the defaults.

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

from benchmeta import run_meta, stable_path
from stiffknots.knots.catalogue import catalogue


def _replica(r: dict) -> dict:
    obs = r.get("observables") or {}
    return {"replica": r.get("replica"), "lineage": r.get("lineage"), "leg": r.get("leg"),
            "start": r.get("start"), "epsilon": r.get("epsilon"), "shape": obs.get("label"),
            "search": obs.get("search"),
            "wall_s": r.get("wall_time"), "cpu_s": r.get("cpu_time")}


def _rows(path: Path) -> list[dict]:
    """The rows already in the file ({"meta", "rows"}; a bare list in older files)."""
    if not path.exists():
        return []
    d = json.loads(path.read_text())
    return d["rows"] if isinstance(d, dict) else d


def _write(path: Path, meta: dict, rows: list[dict]) -> None:
    path.write_text(json.dumps({"meta": meta, "rows": rows}, indent=2))


def main(argv: list[str]) -> None:
    path = stable_path("defaults_survey")
    meta = run_meta(argv)
    if argv[:1] == ["--out"]:
        path, argv = Path(argv[1]), argv[2:]
    options: list[str] = []
    if argv[:1] == ["--with"]:
        options, argv = shlex.split(argv[1]), argv[2:]
    knots = argv or [k.name for k in catalogue() if 3 <= k.crossing_number <= 8]
    # resumable: the knots already in the file are kept and not run again
    rows = _rows(path)
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
        _write(path, meta, rows)
        print(f"{name:6s} ε = {row['epsilon']:9.3f}  {str(row['shape']):7s} "
              f"converged={row['converged']!s:5s} rounds={row['rounds']} "
              f"{row['wall_s']:6.1f} s  {row['reason']}", flush=True)
    ok = [r for r in rows if r.get("converged")]
    print(f"\nconverged: {len(ok)} of {len(rows)} "
          f"({100 * len(ok) / max(1, len(rows)):.0f} %); not: "
          f"{', '.join(r['knot'] for r in rows if not r.get('converged'))}")
    print(f"total wall: {sum(r['wall_s'] for r in rows) / 60:.1f} min")
    _write(path, meta, rows)


if __name__ == "__main__":
    main(sys.argv[1:])
