"""Deeper bead-rule searches for the knots an atlas left unconverged: alone, and pooled.

    stiffknots atlas --knots K1,K2,... --models bead --replicas 4 --bead-steps 3e6 --seed 1 \\
        --db DEEP.db --out DIR
    python bench/atlas_bead_deeper.py ATLAS.db DEEP.db [--json [FILE]]

``ATLAS.db`` holds a default-budget atlas (bead rule: Langevin replicas of 10⁶ steps, up to
16, plus the replicas seeded from the tube replicas); ``DEEP.db`` other bead-rule replicas of
the same N and d (any steps, another seed: independent searches). For every knot of
``DEEP.db`` the script prints the lowest ε of the atlas's own searches, of its seeded ones and
of the deeper ones, and the verdicts (:func:`stiffknots.sweeps.convergence.ensemble_converged`)
of the deeper ensemble alone and of both pooled — the deeper replicas copied into a copy of the
atlas's bead ensemble as further searches (replica numbers shifted, settings hash the atlas's),
with the atlas's own replicas capped at 0, 8 and 16 (0: the seeded ones only).

Every ε at the stored width (bead rule, N = 150, d = 1/√2: w/L = 0.004714 — a finite-width
number, not the thin limit).
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from atlas_replay import capped_copy, verdicts  # noqa: E402
from benchmeta import run_meta, stable_path  # noqa: E402
from stiffknots.sweeps.cross import OLDER_SEEDED_REPLICA  # noqa: E402

SHIFT = 100  # the deeper replicas' numbers in the pooled copy: r + SHIFT (above any cap)


def _bead_hash(con: sqlite3.Connection, knots: list[str]) -> str:
    q = ",".join("?" * len(knots))
    rows = con.execute(f"SELECT DISTINCT settings_hash FROM replicas WHERE exclusion = 'bead' "
                       f"AND knot IN ({q})", knots)
    hashes = sorted(r[0] for r in rows)
    if len(hashes) != 1:
        raise SystemExit(f"expected one bead ensemble per knot in the atlas, got {hashes}")
    return hashes[0]


def _knots_copy(atlas: str, folder: str, cap: int, knots: list[str]) -> str:
    """A copy of ``atlas`` with only ``knots`` and its own bead replicas numbered below
    ``cap`` (:func:`atlas_replay.capped_copy`); its path."""
    path = capped_copy(atlas, folder, cap)
    with sqlite3.connect(path) as con:
        q = ",".join("?" * len(knots))
        con.execute(f"DELETE FROM replicas WHERE knot NOT IN ({q})", knots)
    return path


def pooled_copy(atlas: str, deep: str, folder: str, cap: int, knots: list[str]) -> str:
    """:func:`_knots_copy` with every bead replica of ``deep`` added to the same ensemble
    (numbers + :data:`SHIFT`, the atlas's settings hash; their ``search`` is their own
    replica)."""
    path = _knots_copy(atlas, folder, cap, knots)
    con = sqlite3.connect(path)
    target = _bead_hash(con, knots)
    cols = [r[1] for r in con.execute("PRAGMA table_info(replicas)") if r[1] != "id"]
    src = sqlite3.connect(deep)
    for row in src.execute(f"SELECT {','.join(cols)} FROM replicas WHERE exclusion = 'bead'"):
        d = dict(zip(cols, row, strict=True))
        d.update(settings_hash=target, replica=d["replica"] + SHIFT)
        extra = json.loads(d["extra"])
        extra.pop("search", None)
        d["extra"] = json.dumps(extra)
        con.execute(f"INSERT INTO replicas ({','.join(cols)}) VALUES "
                    f"({','.join('?' * len(cols))})", [d[c] for c in cols])
    con.commit()
    con.close()
    src.close()
    return path


def lowest(con: sqlite3.Connection, knot: str, where: str) -> float | None:
    row = con.execute(f"SELECT MIN(epsilon) FROM replicas WHERE exclusion = 'bead' AND "
                      f"knot = ? AND {where}", (knot,)).fetchone()
    return None if row[0] is None else float(row[0])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("atlas")
    ap.add_argument("deep")
    ap.add_argument("--json", nargs="?", const=str(stable_path("atlas_bead_deeper")),
                    help="also write the result to FILE (default: bench/atlas_bead_deeper.json)")
    a = ap.parse_args(argv)
    deep = sqlite3.connect(a.deep)
    knots = sorted(r[0] for r in deep.execute(
        "SELECT DISTINCT knot FROM replicas WHERE exclusion = 'bead'"))
    steps = sorted({json.loads(r[0]).get("moves") for r in deep.execute(
        "SELECT DISTINCT settings FROM replicas WHERE exclusion = 'bead'")})
    cpu = float(deep.execute("SELECT SUM(cpu_seconds) FROM replicas").fetchone()[0] or 0.0)
    n_deep = int(deep.execute("SELECT COUNT(*) FROM replicas").fetchone()[0])
    atlas = sqlite3.connect(a.atlas)
    per_knot = []
    lower = higher = 0
    for k in knots:
        own = lowest(atlas, k, f"replica < {OLDER_SEEDED_REPLICA}")
        seeded = lowest(atlas, k, f"replica >= {OLDER_SEEDED_REPLICA}")
        d = lowest(deep, k, "1")
        stored = [e for e in (own, seeded) if e is not None]
        rel = d / min(stored) - 1.0 if stored else None
        lower += rel is not None and rel < -1e-3
        higher += rel is not None and rel > 1e-3
        per_knot.append({"knot": k, "atlas_own": own, "atlas_seeded": seeded, "deeper": d,
                         "deeper_vs_atlas": rel})
        nan = float("nan")
        print(f"{k:7s} atlas own {own or nan:9.3f}  seeded {seeded or nan:9.3f}  "
              f"deeper {d:9.3f}  " + (f"({100 * rel:+.2f} % against the atlas's lowest)"
                                      if rel is not None else "(not in the atlas)"))
    out = {"atlas": a.atlas, "deep": a.deep, "knots": knots, "deeper_steps": steps,
           "deeper_replicas": n_deep, "deeper_cpu_seconds": round(cpu, 1),
           "lower_by_more_than_0.1%": lower, "higher_by_more_than_0.1%": higher,
           "per_knot": per_knot, "verdicts": {}}
    out["verdicts"]["deeper alone"] = verdicts(a.deep).get("bead")
    with tempfile.TemporaryDirectory() as folder:
        for cap in (0, 8, 16):
            path = pooled_copy(a.atlas, a.deep, folder, cap, knots)
            out["verdicts"][f"atlas own < {cap} + seeded + deeper"] = verdicts(path)["bead"]
            Path(path).unlink()
        out["verdicts"]["atlas alone"] = verdicts(_knots_copy(a.atlas, folder, 16,
                                                              knots))["bead"]
    print(f"{len(knots)} knots; deeper replicas ({steps} steps): {n_deep}, {cpu:.0f} CPU s; "
          f"deeper lowest below the atlas's by > 0.1 %: {lower}, above: {higher}")
    for name, v in out["verdicts"].items():
        print(f"  {name}: converged {v['converged']} of {v['knots']}; not: "
              f"{', '.join(v['not_converged']) or 'none'}")
    if a.json:
        Path(a.json).write_text(json.dumps({"meta": run_meta(argv), **out}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
