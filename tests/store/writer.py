"""Writer process for the store's concurrency and kill -9 tests (run as a script).

    writer.py DB loop SEED COUNT BEADS [--shared N] [--barrier FILE] [--skip-stored]
        Write COUNT rows (seed SEED, replicas 0..COUNT-1) and N rows shared by all writers
        (seed 999, replicas 0..N-1), each chain of BEADS beads. Prints ``ready`` once the store
        is open, ``begin K`` before and ``done K 1|0`` after each put (1: written), and
        ``inserted M`` at the end. ``--barrier``: wait for FILE to exist before writing;
        ``--skip-stored``: skip keys already stored (as a resumed sweep does).
    writer.py DB hang BEADS
        Start a put and stop inside its transaction, after the INSERT, before the COMMIT;
        prints ``in-transaction`` and sleeps (the test kills it there).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from stiffknots.store import ReplicaKey, Store, settings_hash

SETTINGS = {"problem": "anneal", "moves": 1000, "start": "all"}
HASH = settings_hash(SETTINGS)


def row(seed: int, replica: int, beads: int) -> dict:
    return {"knot": "5_2", "exclusion": "bead", "beads": beads, "thickness": 2 ** -0.5,
            "seed": seed, "replica": replica, "settings": SETTINGS,
            "epsilon": 128.0 + replica * 1e-3, "min_segment_distance": 0.7,
            "wall_seconds": 1.0, "shape": "4C", "start": "cage"}


def say(*words: object) -> None:
    """Print one line in one write: a kill -9 then leaves a whole line or none of it (print
    writes its arguments one by one, and an unbuffered stdout, as under PYTHONUNBUFFERED, passes
    each on at once)."""
    sys.stdout.write(" ".join(map(str, words)) + "\n")
    sys.stdout.flush()


def chain(seed: int, replica: int, beads: int, base: np.ndarray) -> np.ndarray:
    return base + (seed * 100_000 + replica)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("db")
    sub = p.add_subparsers(dest="mode", required=True)
    loop = sub.add_parser("loop")
    loop.add_argument("seed", type=int)
    loop.add_argument("count", type=int)
    loop.add_argument("beads", type=int)
    loop.add_argument("--shared", type=int, default=0)
    loop.add_argument("--barrier")
    loop.add_argument("--skip-stored", action="store_true")
    hang = sub.add_parser("hang")
    hang.add_argument("beads", type=int)
    a = p.parse_args()

    store = Store(a.db)
    if a.mode == "hang":
        def stop_before_commit(sql: str) -> None:
            if sql.startswith("COMMIT"):
                say("in-transaction")
                time.sleep(600)

        store._conn().set_trace_callback(stop_before_commit)  # test-only hook
        base = np.random.default_rng(0).normal(size=(a.beads, 3))
        store.put(row(7, 0, a.beads), base)
        sys.exit("not killed")  # pragma: no cover

    base = np.random.default_rng(a.seed).normal(size=(a.beads, 3))
    jobs = [(a.seed, r) for r in range(a.count)] + [(999, r) for r in range(a.shared)]
    say("ready")
    if a.barrier:
        while not Path(a.barrier).exists():
            time.sleep(0.005)
    inserted = 0
    for seed, r in jobs:
        if a.skip_stored and store.has(ReplicaKey("5_2", "bead", a.beads, 2 ** -0.5, seed, r,
                                                  HASH)):
            continue
        say("begin", r)
        ok = store.put(row(seed, r, a.beads), chain(seed, r, a.beads, base))
        inserted += ok
        say("done", r, int(ok))
    say("inserted", inserted)


if __name__ == "__main__":
    main()
