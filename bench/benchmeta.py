"""Where and when a benchmark ran, stored with its result (the ``meta`` of every bench JSON).

Each benchmark writes one current JSON under a stable name (``bench/<name>.json``); the
history of its results lives in git, and ``bench/make_page.py`` writes docs/benchmarks.md
from the files, quoting the date, machine and command stored here.
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def stable_path(name: str) -> Path:
    """``bench/<name>.json``: where a benchmark's current result lives."""
    return HERE / f"{name}.json"


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, text=True,
                             capture_output=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def run_meta(argv: list[str] | None = None, note: str | None = None) -> dict:
    """The date (UTC), the machine (CPU model and cores, load before the run), the package
    version and commit, and the command line of this run."""
    from stiffknots import __version__

    args = sys.argv[1:] if argv is None else argv
    meta = {
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": f"{_cpu()}, {os.cpu_count()} cores",
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "python": platform.python_version(),
        "stiffknots": __version__,
        "commit": _commit(),
        "command": " ".join(["python", f"bench/{Path(sys.argv[0]).name}", *args]),
    }
    if note:
        meta["note"] = note
    return meta
