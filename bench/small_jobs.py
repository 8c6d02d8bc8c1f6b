"""Small jobs: the wall and CPU seconds of short commands as a user types them.

Each command runs ``--repeats`` times as a fresh process (the numba kernels compiled and cached
before, as `make` leaves them); the median wall time and the median CPU time of the process and
its children are printed. The default commands are those of the issue "answers in seconds":
a 1,000-step ``anneal 3_1 --replicas 1``, a default ``anneal 3_1 --replicas 1`` and
``identify`` of a 100-vertex trefoil. Writes bench/small_jobs.json.

    python bench/small_jobs.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmeta import run_meta, stable_path

#: (label, arguments of `stiffknots`) — FILE is replaced by the 100-vertex trefoil's path
COMMANDS = [
    ("version (start-up only)", ["version"]),
    ("anneal 3_1 --replicas 1 --moves 1000", ["anneal", "3_1", "--replicas", "1", "--moves",
                                              "1000", "--json"]),
    ("anneal 3_1 --replicas 1", ["anneal", "3_1", "--replicas", "1", "--json"]),
    ("identify (100-vertex trefoil)", ["identify", "FILE", "--json"]),
]


def trefoil(path: Path, n: int = 100) -> Path:
    """The (2,3) torus-like trefoil x = sin t + 2 sin 2t, y = cos t − 2 cos 2t, z = −sin 3t
    at n vertices."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    x = np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]
    np.savetxt(path, x)
    return path


def time_command(args: list[str]) -> tuple[float, float, dict | None]:
    """(wall s, CPU s of the process and its children, its JSON output or None)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args], capture_output=True,
                       text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if p.returncode != 0:
        raise SystemExit(f"stiffknots {' '.join(args)}: exit {p.returncode}: "
                         f"{p.stderr.strip()[-400:]}")
    try:
        out = json.loads(p.stdout) if "--json" in args else None
    except ValueError:
        out = None
    return wall, cpu, out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        curve = trefoil(Path(tmp) / "trefoil100.xyz")
        for label, args in COMMANDS:
            args = [str(curve) if v == "FILE" else v for v in args]
            walls, cpus, out = [], [], None
            for _ in range(a.repeats):
                w, c, out = time_command(args)
                walls.append(w)
                cpus.append(c)
            row = {"command": "stiffknots " + " ".join(args).replace(str(curve),
                                                                     "trefoil100.xyz"),
                   "label": label, "wall_s": statistics.median(walls),
                   "cpu_s": statistics.median(cpus), "walls": walls, "cpus": cpus}
            if out and "epsilon" in out:
                row.update(epsilon=out["epsilon"], rounds=out.get("rounds"),
                           width=(out.get("width") or {}).get("text"))
            if out and "name" in out:
                row["name"] = out["name"]
            rows.append(row)
            extra = (f", ε = {row['epsilon']:.4f} ({row['rounds']} rounds)"
                     if "epsilon" in row else "")
            print(f"{label}: {row['wall_s']:.2f} s wall, {row['cpu_s']:.2f} CPU s "
                  f"(median of {a.repeats}){extra}", flush=True)
    d = {"meta": run_meta(argv, note=f"{os.cpu_count()} cores; each command a fresh process, "
                                     "kernels cached"), "rows": rows}
    path = stable_path("small_jobs")
    path.write_text(json.dumps(d, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
