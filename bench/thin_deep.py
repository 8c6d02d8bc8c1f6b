"""Stored thin-stage branches continued far below the ladder: does the Monte Carlo route reach
the structure route?

    python bench/thin_deep.py DB [--states 6_1:1,7_2:0,...] [--floor 6.25e-5] [--beads-x 2]
    python bench/thin_deep.py DB --reuse      # the fits again, from the JSON's continuations

For each ``knot:state`` of the atlas's thin stage (``DB``'s ``thin`` table, its newest run),
the state's thinnest stored chain (w/L = 0.0005 with the small ladder) is followed further by
the same continuation (:func:`stiffknots.studies.branches.follow_state`: a short
low-temperature Monte Carlo, the final minimiser and the knot check at each width, 2
replicas, seed 1), halving w/L down to ``--floor`` at the branch's own N (and, with
``--beads-x M``, for the first state also at M·N: does the discretisation move the limit?).
The stored points and the new ones, corrected alike (ε_N (1 + k/N²), the branch's k), are
then extrapolated (:func:`stiffknots.analysis.extrapolate.extrapolate`) with the fit ending
at each new width in turn, beside the structure route's w = 0 value; the local exponent of
each three consecutive points, ``log2((ε₁ − ε₂)/(ε₂ − ε₃))``, says whether the series is one
power law yet. Writes bench/thin_deep.json.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from benchmeta import run_meta, stable_path

DEFAULT_STATES = "6_1:1,7_2:0,7_3:0,8_2:0,4_1:1,7_1:0"


def _local_exponents(eps: list[float]) -> list[float | None]:
    out: list[float | None] = []
    for a, b, c in zip(eps, eps[1:], eps[2:], strict=False):
        d1, d2 = a - b, b - c
        out.append(math.log2(d1 / d2) if d1 > 0 and d2 > 0 else None)
    return out


def main(argv: list[str] | None = None) -> None:
    from stiffknots.analysis.extrapolate import extrapolate
    from stiffknots.store import Store
    from stiffknots.store.thin import thin_chain, thin_rows
    from stiffknots.studies.branches import follow_state
    from stiffknots.studies.thin_states import AGREE_REL

    ap = argparse.ArgumentParser()
    ap.add_argument("db")
    ap.add_argument("--states", default=DEFAULT_STATES)
    ap.add_argument("--floor", type=float, default=6.25e-5)
    ap.add_argument("--beads-x", type=int, default=0)
    ap.add_argument("--note", default=None)
    ap.add_argument("--reuse", action="store_true",
                    help="Take the continuations from the current bench/thin_deep.json (same "
                         "states) instead of running them: only the fits are computed again.")
    a = ap.parse_args(argv)
    path = stable_path("thin_deep")
    before = json.loads(path.read_text()) if a.reuse else None
    rows = []
    for i, item in enumerate(a.states.split(",")):
        knot, state = item.split(":")
        with Store(a.db, readonly=True) as s:
            rs = thin_rows(s, knot)
            st = next(r for r in rs if r["state"] == int(state) and r["run"] == rs[0]["run"])
            x = thin_chain(s, st["id"])
        d = st["details"]
        n = d["parameters"]["beads"]
        k = d["discretisation"]["k"]
        stored = [p for p in d["points"] if p["in_fit"]]
        w0 = stored[-1]["w_over_L"]
        widths = [w0]
        while widths[-1] / 2 >= a.floor * (1 - 1e-9):
            widths.append(widths[-1] / 2)
        runs = {}
        if before is not None:
            old_row = next(r for r in before["rows"]
                           if r["knot"] == knot and r["state"] == int(state))
            runs = {int(m): r for m, r in old_row["runs"].items()}
        for mult in ([1, a.beads_x] if (a.beads_x and i == 0) else [1]):
            if mult in runs:
                continue
            t0 = time.time()
            b = follow_state(knot, x, widths=widths, beads=mult * n, relax_factor=0.1,
                             replicas=2, seed=1, measure_k=False,
                             say=lambda line: print(line, flush=True))
            runs[mult] = {"beads": mult * n, "wall_s": time.time() - t0,
                          "points": [{"w_over_L": p["w_over_L"], "epsilon_raw": p["epsilon_raw"],
                                      "shape": p["shape"], "step": p["step"],
                                      "in_fit": p["in_fit"]} for p in b["points"]],
                          "events": b["events"]}
        se = st["structure_epsilon"]
        ws = [p["w_over_L"] for p in stored]
        es = [p["epsilon"] for p in stored]
        sg = [p["sigma"] for p in stored]
        for p in runs[1]["points"][1:]:
            if not p["in_fit"]:
                break
            e = p["epsilon_raw"] * (1 + k / n**2)
            ws.append(p["w_over_L"])
            es.append(e)
            sg.append(2e-6 * e)
        fits = []
        disc = d["discretisation"].get("error", 0.0)   # the correction's, as the stage's
        for m in range(len(stored), len(ws) + 1):
            f = extrapolate(ws[:m], es[:m], sg[:m])
            err = math.hypot(f.error, disc)
            agree = (None if se is None else
                     abs(f.epsilon - se) <= max(2 * err, AGREE_REL * se))
            fits.append({"to_w_over_L": ws[m - 1], "points": m, "epsilon_thin": f.epsilon,
                         "error": err, "p": f.p, "agree": agree,
                         "above_structure_pct": (None if se is None
                                                 else 100 * (f.epsilon - se) / se)})
            print(f"{knot} state {state}: fit to w/L = {ws[m - 1]:g} ({m} points): "
                  f"ε* = {f.epsilon:.3f} ± {err:.3f} (p = {f.p:.2f}); structure "
                  f"{se if se is None else round(se, 4)}; agree {agree}", flush=True)
        rows.append({"knot": knot, "state": int(state), "name": st["name"],
                     "shape_thin": st["shape_thin"], "beads": n, "k": k,
                     "structure_epsilon": se, "structure_name": st["structure_name"],
                     "stored_epsilon_thin": st["epsilon_thin"], "stored_error": st["error"],
                     "series": [{"w_over_L": w, "epsilon": e} for w, e in zip(ws, es,
                                                                              strict=True)],
                     "local_exponents": _local_exponents(es), "fits": fits,
                     "runs": {str(m): r for m, r in runs.items()}})
    meta = before["meta"] if before is not None else run_meta(argv, a.note)
    out = {"meta": meta, "db": a.db, "floor": a.floor, "rows": rows}
    path.write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
