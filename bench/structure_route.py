"""The structure route again on every state a thin stage stored: what the current solver gives
and what it costs, beside the stored answer.

    python bench/structure_route.py DB [--knots 4_1,7_6] [--old 4_1:0,7_6:0]

For each state of ``DB``'s ``thin`` table (the newest row of each knot and state; the atlas's
thin stage, ``stiffknots atlas --thin``), the structure route
(:func:`stiffknots.studies.thin_states.structure_route`) is solved again from the state's stored
thinnest chain and the stored points of its branch, with the code of this checkout (Newton from
the chain first, the coarse search within its time budget), timed in CPU seconds of this
process, and compared with the stored branch's extrapolation by the product's rule (twice the
error or 0.5 %). ``--old`` solves the listed states also with the SLSQP search first and no
budget (the route before Newton-first), for the time side by side. Writes
bench/structure_route.json.
"""

from __future__ import annotations

import argparse
import functools
import json
import sqlite3
import time
import warnings

import numpy as np

from benchmeta import run_meta, stable_path


def _rows(db: str, knots: list[str] | None) -> list[dict]:
    con = sqlite3.connect(db)
    con.row_factory = sqlite3.Row
    q = ("SELECT knot, state, name, epsilon, epsilon_thin, error, structure_epsilon, "
         "structure_name, agree, details, chain, beads_thin, cpu_seconds FROM thin "
         "WHERE id IN (SELECT MAX(id) FROM thin GROUP BY knot, state) ORDER BY id")
    out = []
    for r in con.execute(q):
        if knots and r["knot"] not in knots:
            continue
        d = dict(r)
        d["details"] = json.loads(d["details"])
        d["chain"] = np.frombuffer(d["chain"], dtype="<f8").reshape(-1, 3).copy()
        out.append(d)
    return out


def _branch(r: dict) -> dict:
    det = r["details"]
    pts = det["points"]
    last = max((i for i, p in enumerate(pts) if p["in_fit"]), default=len(pts) - 1)
    chains: list = [None] * len(pts)
    chains[last] = r["chain"]
    return {"knot": r["knot"], "points": pts, "chains": chains,
            "start": {"label": det.get("shape", r["name"]), "multiplicity": None}}


def _solve(r: dict, old: bool) -> tuple[dict, float]:
    from stiffknots.analysis import structure_route as sr
    from stiffknots.studies.thin_states import structure_route

    saved = sr.solve_chain
    if old:        # the route before Newton-first: SLSQP from the chain, no budget
        sr.solve_chain = functools.partial(saved, newton_first=False, coarse_budget_s=None)
    t = time.process_time()
    try:
        route = structure_route(_branch(r))
    finally:
        sr.solve_chain = saved
    return route, time.process_time() - t


def _agree(r: dict, route: dict) -> bool | None:
    from stiffknots.studies.thin_states import AGREE_REL

    eps_t, err = r["epsilon_thin"], r["error"]
    if route["epsilon"] is None or eps_t is None or not route["keeps_knot"] \
            or not route.get("minimum", True):
        return None
    return abs(eps_t - route["epsilon"]) <= max(2 * (err or 0.0), AGREE_REL * route["epsilon"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("db")
    ap.add_argument("--knots", default="")
    ap.add_argument("--old", default="", help="knot:state,... solved also SLSQP-first")
    a = ap.parse_args()
    knots = [k for k in a.knots.split(",") if k] or None
    old = {tuple(s.split(":")) for s in a.old.split(",") if s}
    rows = []
    warnings.simplefilter("ignore")
    for r in _rows(a.db, knots):
        route, cpu = _solve(r, old=False)
        row = {"knot": r["knot"], "state": r["state"], "shape": r["name"],
               "epsilon_thin": r["epsilon_thin"], "error": r["error"],
               "stored": {"structure_epsilon": r["structure_epsilon"],
                          "structure_name": r["structure_name"],
                          "agree": None if r["agree"] is None else bool(r["agree"]),
                          "method": r["details"]["route"].get("method"),
                          "note": r["details"]["route"].get("note")},
               "now": {"structure_epsilon": route["epsilon"], "error": route["error"],
                       "structure_name": route["name"], "method": route["method"],
                       "minimum": route["minimum"], "keeps_knot": route["keeps_knot"],
                       "note": route["note"], "agree": _agree(r, route),
                       "cpu_seconds": round(cpu, 2)},
               "knot_cpu_seconds": r["cpu_seconds"]}
        if (r["knot"], str(r["state"])) in old:
            route_o, cpu_o = _solve(r, old=True)
            row["old"] = {"structure_epsilon": route_o["epsilon"],
                          "minimum": route_o["minimum"], "cpu_seconds": round(cpu_o, 2)}
        rows.append(row)
        n = row["now"]
        print(f"{r['knot']:>6} {r['state']}: {n['cpu_seconds']:7.1f} CPU s  "
              f"ε = {n['structure_epsilon']}  agree {n['agree']} (stored "
              f"{row['stored']['agree']})"
              + (f"  old {row['old']['cpu_seconds']} s" if "old" in row else ""), flush=True)
    graph = [r for r in rows if (r["now"]["method"] or "").startswith("the graph")]
    summary = {
        "states": len(rows),
        "compared_now": sum(r["now"]["agree"] is not None for r in rows),
        "agree_now": sum(r["now"]["agree"] is True for r in rows),
        "compared_stored": sum(r["stored"]["agree"] is not None for r in rows),
        "agree_stored": sum(r["stored"]["agree"] is True for r in rows),
        "graph_solved": len(graph),
        "graph_minima": sum(bool(r["now"]["minimum"]) for r in graph),
        "cpu_seconds": round(sum(r["now"]["cpu_seconds"] for r in rows), 1),
        "cpu_seconds_max": max((r["now"]["cpu_seconds"] for r in rows), default=0.0),
        "stored_knot_cpu_seconds": round(sum({r["knot"]: r["knot_cpu_seconds"] or 0.0
                                              for r in rows}.values()), 1),
    }
    out = {"meta": run_meta(), "db": a.db, "summary": summary, "rows": rows}
    stable_path("structure_route").write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
