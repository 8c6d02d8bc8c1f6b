"""What the store's tests share (tests/store): rows, chains, the writer process."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

WRITER = Path(__file__).parent / "store" / "writer.py"
SETTINGS = {"problem": "anneal", "moves": 30_000_000, "start": "all",
            "params": {"exclusion": "bead", "d": 2 ** -0.5, "delta": np.pi / 100}}
D = 2 ** -0.5


def make_row(**over):
    row = {"knot": "5_2", "exclusion": "bead", "beads": 150, "thickness": D, "seed": 0,
           "replica": 0, "settings": SETTINGS, "epsilon": 128.4, "min_segment_distance": 0.72,
           "wall_seconds": 12.5}
    row.update(over)
    return row


def chain(beads=150, seed=0):
    return np.random.default_rng(seed).normal(size=(beads, 3))


def writer(*args, **kw):
    return subprocess.Popen([sys.executable, str(WRITER), *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def wait_for(proc, word, timeout=30.0):
    """Read the writer's stdout until a line starting with ``word``; return the lines."""
    lines, end = [], time.monotonic() + timeout
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            raise AssertionError(f"writer ended before {word!r}: {proc.stderr.read()}")
        lines.append(line.split())
        if lines[-1][0] == word:
            return lines
    raise AssertionError(f"writer did not say {word!r} in {timeout} s")


def fill_5_2(store):
    """A 5_2 ensemble with a known grouping (1 % rule) and rows that must stay apart."""
    data = [  # (epsilon, shape, multiplicity, start)
        (128.9, "4C", None, "braid"), (128.4, "4C", None, "cage"), (129.5, "4C", None, "cage"),
        (147.3, "80", None, "80"), (148.1, "80", None, "braid"),
        (152.0, "80", None, "80"),  # > 1 % above 147.3: a state of its own
        (181.2, "CB", 3, "braid"), (150.0, "other", None, "braid"),
    ]
    ids = {}
    for r, (eps, shape, mult, start) in enumerate(data):
        store.put(make_row(replica=r, epsilon=eps, shape=shape, multiplicity=mult, start=start,
                           converged=r != 1), chain())
        ids[eps] = store.replicas(replica=r, beads=150, exclusion="bead")[0]["id"]
    # never mixed in: other N, other model, other width, other settings (all with lower ε)
    store.put(make_row(beads=100, epsilon=100.0, shape="4C"), chain(100))
    store.put(make_row(exclusion="tube", epsilon=101.0, shape="4C"), chain())
    store.put(make_row(thickness=0.5, epsilon=102.0, shape="4C"), chain())
    store.put(make_row(settings={**SETTINGS, "moves": 10}, epsilon=103.0, shape="80"),
              chain())
    return ids
