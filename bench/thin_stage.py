"""The atlas's thin stage on a stored database: every knot's states followed to w = 0, both
routes, the thin-limit grounds, and what the stage cost.

    stiffknots atlas --max-crossings 8 --models tube --thin --db DB --json > RUN.json
    python bench/thin_stage.py DB [--run RUN.json] [--note TEXT] [--name thin_stage]

Reads the ``thin`` table (:func:`stiffknots.store.thin.thin_knots`: each knot's newest run)
and, with ``--run``, the atlas command's ``--json`` (the sweep's and the thin stage's wall and
CPU seconds). Per knot: its states, the thin-limit ground (ε* ± error, the structure route,
whether they agree), the ground at the census's width and whether it differs. In all: the
states compared and agreeing (within twice the branch's error or 0.5 %,
``stiffknots.studies.thin_states.AGREE_REL``), the n = i knots against 2π²i², the thin-limit
grounds by class (circular braid, 4-fold cage, 80, other). Writes bench/thin_stage.json (the
atlas's default, ``--thin-budget small``), or bench/NAME.json with ``--name`` (the default
ladder: ``--name thin_stage_default``).
"""

from __future__ import annotations

import argparse
import json
import math
from collections import Counter

from benchmeta import run_meta, stable_path


def _class(name: str | None) -> str:
    if name is None:
        return "none"
    return "CB" if name.startswith("CB") else name


def main(argv: list[str] | None = None) -> None:
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.store import Store
    from stiffknots.store.thin import thin_knots
    from stiffknots.studies.thin_states import MAX_COMPARED_ERROR

    ap = argparse.ArgumentParser()
    ap.add_argument("db")
    ap.add_argument("--run", default=None, help="The atlas command's --json output.")
    ap.add_argument("--note", default=None)
    ap.add_argument("--name", default="thin_stage", help="bench/NAME.json is written.")
    a = ap.parse_args(argv)
    with Store(a.db, readonly=True) as s:
        knots = thin_knots(s)
    rows = []
    for t in knots:
        k = get_knot(t["knot"])
        g = t["ground"]
        rows.append({
            "knot": t["knot"], "crossings": k.crossing_number, "n": k.bridge_number,
            "i": k.braid_index, "budget": t["budget"], "w_over_L": t["w_over_L"],
            "cpu_seconds": t["cpu_seconds"], "finite": t["finite"]["name"],
            "ground": None if g is None else g["name"],
            "epsilon_thin": t["epsilon_thin"], "error": t["thin_error"],
            "structure_epsilon": None if g is None else g["structure_epsilon"],
            "structure": t["thin_structure"], "agree": t["agree"],
            "differs": g is not None and g["state"] != 0, "crossing": t["crossing"],
            "states": [{k2: st[k2] for k2 in ("state", "name", "epsilon", "epsilon_thin",
                                               "error", "structure_epsilon",
                                               "structure_name", "agree", "event")}
                       for st in t["states"]]})
    states = [st for r in rows for st in r["states"]]
    compared = [st for st in states if st["agree"] is not None]
    # the stage's rule since the tenth session: a branch whose error is over
    # MAX_COMPARED_ERROR of its ε* is not compared (rows stored before kept their agree)
    narrow = [st for st in compared
              if (st["error"] or 0.0) <= MAX_COMPARED_ERROR * abs(st["epsilon_thin"])]
    n_eq_i = []
    for r in rows:
        if r["n"] == r["i"] and r["epsilon_thin"] is not None:
            target = 2 * math.pi**2 * r["i"] ** 2
            n_eq_i.append({"knot": r["knot"], "i": r["i"], "epsilon_thin": r["epsilon_thin"],
                           "target": target, "rel": r["epsilon_thin"] / target - 1,
                           "ground": r["ground"]})
    doc = {"meta": run_meta(argv, note=a.note), "knots": rows, "n_knots": len(rows),
           "states": len(states), "compared": len(compared),
           "agree": sum(bool(st["agree"]) for st in compared),
           "compared_narrow": len(narrow), "agree_narrow": sum(bool(st["agree"]) for st in narrow),
           "no_limit": sum(st["epsilon_thin"] is None for st in states),
           "differs": [r["knot"] for r in rows if r["differs"]],
           "classes": dict(Counter(_class(r["ground"]) for r in rows)),
           "n_eq_i": n_eq_i,
           "thin_cpu_seconds": sum(r["cpu_seconds"] or 0.0 for r in rows)}
    if a.run:
        with open(a.run, encoding="utf-8") as f:
            run = json.load(f)
        doc["run"] = {"sweep_wall_seconds": run["sweep"]["wall_seconds"],
                      "sweep_cpu_seconds": run["sweep"]["cpu_seconds"],
                      "thin_wall_seconds": (run.get("thin") or {}).get("wall_seconds"),
                      "thin_cpu_seconds": (run.get("thin") or {}).get("cpu_seconds"),
                      "workers": (run.get("thin") or {}).get("workers")}
    for r in rows:
        eps = None if r["epsilon_thin"] is None else round(r["epsilon_thin"], 4)
        print(f"{r['knot']}: {len(r['states'])} states, thin ground {r['ground']} ε* = {eps} "
              f"(structure {r['structure_epsilon']}, agree {r['agree']}); finite "
              f"{r['finite']}")
    print(f"{doc['n_knots']} knots, {doc['states']} states, {doc['agree']} of "
          f"{doc['compared']} compared agree ({doc['agree_narrow']} of "
          f"{doc['compared_narrow']} with an error ≤ {100 * MAX_COMPARED_ERROR:.0f} % of ε*); "
          f"thin ground differs from the finite-width "
          f"ground for {len(doc['differs'])}: {', '.join(doc['differs']) or 'none'}; "
          f"classes {doc['classes']}; thin stage {doc['thin_cpu_seconds']:.0f} CPU s")
    stable_path(a.name).write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
