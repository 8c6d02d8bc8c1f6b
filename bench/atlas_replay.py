"""What a smaller budget would have given: an atlas database replayed under lower caps.

    python bench/atlas_replay.py DB [--bead-caps 4,6,8,10,12,16] [--tube-caps 2,4,6]
                                    [--legs 0,1,2] [--bead-legs 0,4] [--wall-per-cpu F]
                                    [--json [FILE]]

A sweep's replicas are a prefix: replica r's seed and start depend only on the replicas
before it (``stiffknots.sweeps.plan``), and a (knot, model) gets two more replicas while it
has not converged, up to its cap. So the replicas a capped sweep would have run are those the
stored sweep ran numbered below the cap, *exactly*, where the cap only removes replicas. This
script copies the database, deletes the replicas a budget would not have run, and counts the
verdicts (:func:`stiffknots.sweeps.convergence.ensemble_converged`) and the CPU seconds of the
replicas left:

* ``bead cap c``: the bead rule's own replicas numbered ≥ c;
* ``tube cap m`` (m < the stored cap): the tube replicas numbered ≥ m, *all* continuation legs
  (a leg continues the second-lowest of the first m searches, not stored), and the bead
  replicas seeded from any of them (replica 2,000,000 + r);
* ``legs l``: the tube legs numbered ≥ l (replica 1,500,000 + k) and their seeds;
* ``bead legs b``: the Langevin bead legs numbered ≥ b (replica 1,500,000 + k of a bead
  ensemble); every bead leg where the bead cap is below the stored one (a leg continues one
  of the searches stored when it was planned).

Where a removed seeded replica was the second opinion of a bead verdict, the capped sweep
would have added bead replicas the database does not hold: that verdict counts as not
converged, so a row's bead count is a lower bound whenever tube replicas or legs are removed
(marked ``≥``); likewise where bead legs are removed below a lower bead cap (the capped
sweep would have run legs of its own). Wall time is estimated as CPU seconds ×
``--wall-per-cpu`` (default: the stored sweep's, the wall seconds of its stretches over its
CPU seconds, when given with ``--wall`` in minutes; otherwise 0.5 — two cores fully used).

Every ε at the stored width (N and d or w/L); seed 0 as stored.
"""

from __future__ import annotations

import argparse
import collections
import json
import sqlite3
import sys
import tempfile
from pathlib import Path

from benchmeta import run_meta, stable_path
from stiffknots.store.sqlite import Store
from stiffknots.sweeps import BUDGETS
from stiffknots.sweeps.convergence import ensemble_converged
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA, SEEDED_REPLICA
from stiffknots.sweeps.legs import LEG_REPLICA

FRESH_BELOW = OLDER_SEEDED_REPLICA  # below it: the replicas of a model's own searches
#: the budget the stored sweep ran (its tube cap and legs)
STORED = BUDGETS["default"]


def _ints(s: str) -> list[int]:
    return [int(x) for x in s.split(",") if x.strip()]


def verdicts(path: str) -> dict:
    """Per model: (knots, converged, CPU s, replicas, knots not converged) of a database."""
    st = Store(path, create=False)
    out: dict = {}
    grounds = st.ground_states(structure=False)
    cpu = collections.Counter()
    n = collections.Counter()
    for ex, c, k in st._query(  # noqa: SLF001 (numbers only)
            "SELECT exclusion, SUM(cpu_seconds), COUNT(*) FROM replicas GROUP BY exclusion"):
        cpu[ex] = float(c or 0.0)
        n[ex] = int(k)
    for ex in sorted({g["exclusion"] for g in grounds}):
        gs = [g for g in grounds if g["exclusion"] == ex]
        missed = sorted(g["knot"] for g in gs if not ensemble_converged(g))
        out[ex] = {"knots": len(gs), "converged": len(gs) - len(missed),
                   "cpu_seconds": round(cpu[ex], 1), "replicas": n[ex],
                   "not_converged": missed}
    st.close()
    return out


def capped_copy(db: str, folder: str, bead_cap: int) -> str:
    """A copy of ``db`` in ``folder`` (SQLite's backup: safe beside a running writer) without
    the bead rule's own replicas numbered ≥ ``bead_cap``; its path."""
    copy = str(Path(folder) / "replay.db")
    with sqlite3.connect(db) as src, sqlite3.connect(copy) as dst:
        src.backup(dst)
    with sqlite3.connect(copy) as con:
        con.execute("DELETE FROM replicas WHERE exclusion = 'bead' AND replica >= ? "
                    "AND replica < ?", (bead_cap, FRESH_BELOW))
    return copy


def _has_bead_legs(db: str, kept: int) -> bool:
    """Whether ``db`` holds bead legs numbered ≥ ``kept`` (a replay that removes them counts
    a lower bound: a capped sweep would have run legs of its own)."""
    with sqlite3.connect(db) as con:
        return con.execute("SELECT COUNT(*) FROM replicas WHERE exclusion = 'bead' AND "
                           "replica >= ? AND replica < ?",
                           (LEG_REPLICA + kept, SEEDED_REPLICA)).fetchone()[0] > 0


def replay(db: str, bead_cap: int, tube_cap: int | None, legs: int,
           bead_legs: int | None = None) -> dict:
    """The verdicts and CPU of the database with the replicas the caps rule out removed
    (``tube_cap`` None: the stored tube replicas and the first ``legs`` legs kept; a
    ``tube_cap``: every leg removed; ``bead_legs``: the first that many bead legs kept, None
    all)."""
    top = FRESH_BELOW if tube_cap is None else tube_cap
    first_leg = LEG_REPLICA + (legs if tube_cap is None else 0)
    with tempfile.TemporaryDirectory() as tmp:
        copy = capped_copy(db, tmp, bead_cap)
        with sqlite3.connect(copy) as con:
            gone = [(r,) for (r,) in con.execute(  # tube replica numbers; their seeds go too
                "SELECT DISTINCT replica FROM replicas WHERE exclusion = 'tube' AND "
                "((replica >= ? AND replica < ?) OR replica >= ?)",
                (top, FRESH_BELOW, first_leg))]
            con.executemany("DELETE FROM replicas WHERE exclusion = 'tube' AND replica = ?",
                            gone)
            con.executemany("DELETE FROM replicas WHERE exclusion = 'bead' AND replica = ?",
                            [(SEEDED_REPLICA + r,) for (r,) in gone])
            if bead_legs is not None:
                con.execute("DELETE FROM replicas WHERE exclusion = 'bead' AND replica >= ? "
                            "AND replica < ?", (LEG_REPLICA + bead_legs, SEEDED_REPLICA))
        return verdicts(copy)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("db")
    ap.add_argument("--bead-caps", default="4,6,8,10,12,16")
    ap.add_argument("--tube-caps", default="2,4,6", help="the stored cap keeps its legs")
    ap.add_argument("--legs", default="0,1,2")
    ap.add_argument("--bead-legs", default="",
                    help="bead legs kept, e.g. 0,4 (default: as stored)")
    ap.add_argument("--stored-bead-cap", type=int, default=STORED.bead_max_replicas,
                    help="the stored sweep's bead cap (default: the default budget's)")
    ap.add_argument("--stored-tube-cap", type=int, default=STORED.max_replicas,
                    help="the stored sweep's tube cap (default: the default budget's)")
    ap.add_argument("--stored-legs", type=int, default=STORED.legs,
                    help="the stored sweep's tube legs (default: the default budget's)")
    ap.add_argument("--wall", type=float, help="the stored sweep's wall minutes")
    ap.add_argument("--wall-per-cpu", type=float)
    ap.add_argument("--json", nargs="?", const=str(stable_path("atlas_replay")),
                    help="also write the replays to FILE (default: bench/atlas_replay.json)")
    a = ap.parse_args(argv)
    base = verdicts(a.db)
    cpu_all = sum(m["cpu_seconds"] for m in base.values())
    f = a.wall_per_cpu or ((a.wall * 60 / cpu_all) if a.wall else 0.5)
    rows = []
    for tc in _ints(a.tube_caps):
        for lg in (_ints(a.legs) if tc >= a.stored_tube_cap else [0]):
            for bc in _ints(a.bead_caps):
                for bl in (_ints(a.bead_legs) or [None]):
                    kept = 0 if bc < a.stored_bead_cap else bl
                    v = replay(a.db, bc, tc if tc < a.stored_tube_cap else None, lg, kept)
                    cpu = sum(m["cpu_seconds"] for m in v.values())
                    lower = (tc < a.stored_tube_cap or lg < a.stored_legs
                             or (kept is not None and _has_bead_legs(a.db, kept)))
                    rows.append({"bead_cap": bc, "tube_cap": tc, "legs": lg, "bead_legs": kept,
                                 "bead": v["bead"]["converged"], "tube": v["tube"]["converged"],
                                 "knots": v["tube"]["knots"], "bead_lower_bound": lower,
                                 "cpu_seconds": round(cpu, 1),
                                 "bead_cpu": v["bead"]["cpu_seconds"],
                                 "tube_cpu": v["tube"]["cpu_seconds"],
                                 "wall_hours": round(cpu * f / 3600, 2)})
                    r = rows[-1]
                    print(f"tube cap {tc} legs {lg} bead cap {bc:2d}"
                          + ("" if kept is None else f" bead legs {kept}") + ": bead "
                          f"{'≥' if lower else ' '}{r['bead']}/{r['knots']}, tube {r['tube']}/"
                          f"{r['knots']}, CPU {cpu:8.0f} s (bead {r['bead_cpu']:.0f}, tube "
                          f"{r['tube_cpu']:.0f}), ≈ {r['wall_hours']:.2f} h wall", flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps({"meta": run_meta(argv), "db": a.db,
                                            "wall_per_cpu": f, "stored": base,
                                            "replays": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
