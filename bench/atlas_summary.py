"""What a sweep's database holds: replicas, CPU, verdicts by crossing number, and how far apart
the two best replicas of each ground shape are.

    python bench/atlas_summary.py [results/stiffknots.db] [--json [FILE]] [--structures]

Reads the store only (any sweep: ``stiffknots atlas``). Per model (bead rule, tube): the (knot,
model) pairs, the replicas and their CPU/wall seconds, the converged verdicts of
:mod:`stiffknots.sweeps.convergence` (≥ 2 replicas of the ground shape within 0.1 % of its
lowest ε) by crossing number, the pairs not converged, and the distribution of the relative gap
between the lowest replica of the ground shape and the next one of that shape — the gap the
verdict's 0.1 % must bridge (docs/atlas.md, "Bead rule against tube"); per conjectured family
(and for the knots in none) the ground shapes and the contact structures of the grounds (§V B:
line-braids, point-braids, multiple points; ``--structures`` lists each structure's knots with
their Conway notation); and the replicas whose strands touch where they cross (min segment
distance below 10⁻³: the bead rule's touching crossings, held at the polish's strand gap),
searches of the model's own and seeded ones apart, with how far above their knot's lowest state
they end. Every number is at the stored width (N and d or w/L, printed).
"""

from __future__ import annotations

import argparse
import collections
import json
import re
import sys

from benchmeta import run_meta, stable_path
from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.families import families_of, predicted_shape
from stiffknots.report.text import TOUCHING_BELOW
from stiffknots.store.keys import knot_sort_key
from stiffknots.store.sqlite import Store
from stiffknots.sweeps.convergence import RULE, SEEDED_START, is_converged

GAP_EDGES = (1e-3, 3e-3, 1e-2, 3e-2)
GAP_LABELS = ("≤ 0.1 %", "0.1–0.3 %", "0.3–1 %", "1–3 %", "> 3 %")


def summarise(path: str) -> dict:
    store = Store(path, create=False)
    grounds = store.ground_states()
    rows = store._query(  # noqa: SLF001 (numbers only, no coordinates)
        "SELECT knot, exclusion, w_over_L, beads, epsilon, shape, multiplicity, cpu_seconds, "
        "wall_seconds, min_segment_distance, start FROM replicas")
    by_pair: dict[tuple[str, str], list[tuple]] = collections.defaultdict(list)
    widths: dict[str, set] = collections.defaultdict(set)
    touch: dict[tuple[str, str], list[tuple]] = collections.defaultdict(list)
    for knot, model, wl, beads, eps, shape, mult, cpu, wall, gap, start in rows:
        by_pair[(knot, model)].append((eps, f"{shape}{mult or ''}", cpu or 0.0, wall))
        widths[model].add((beads, round(wl, 6)))
        touch[(knot, model)].append((eps, gap < TOUCHING_BELOW, start == SEEDED_START))
    out: dict = {"db": str(path), "rule": RULE, "models": {}}
    for model in sorted({m for _, m in by_pair}):
        pairs = sorted((k for k, m in by_pair if m == model), key=knot_sort_key)
        verdict = {g["knot"]: is_converged(g) for g in grounds if g["exclusion"] == model}
        by_nc: dict[int, list[int]] = collections.defaultdict(lambda: [0, 0])
        gaps = [0] * len(GAP_LABELS)
        lone = 0
        for k in pairs:
            nc = get_knot(k).crossing_number
            by_nc[nc][0] += 1
            by_nc[nc][1] += bool(verdict.get(k))
            reps = sorted(by_pair[(k, model)])
            same = [e for e, s, _, _ in reps if s == reps[0][1]]
            if len(same) < 2:
                lone += 1
                continue
            gap = (same[1] - same[0]) / same[0]
            gaps[sum(gap > edge for edge in GAP_EDGES)] += 1
        reps = [r for k in pairs for r in by_pair[(k, model)]]
        shape_of = {g["knot"]: (g["shape"], g["multiplicity"]) for g in grounds
                    if g["exclusion"] == model}
        structure_of = {g["knot"]: g["structure"] or "unreadable chain" for g in grounds
                        if g["exclusion"] == model}
        fam_rows: dict[str, dict] = {}
        for k in pairs:
            knot = get_knot(k)
            pred = predicted_shape(knot)
            got = shape_of.get(k)
            hit = pred is not None and got is not None and (
                got[0] == pred[0] and (pred[1] is None or got[1] == pred[1]))
            for fam in families_of(knot) or ["none"]:
                row = fam_rows.setdefault(fam, {"knots": 0, "as_predicted": 0, "converged": 0,
                                                "shapes": collections.Counter(),
                                                "structures": collections.defaultdict(list)})
                row["knots"] += 1
                row["as_predicted"] += hit
                row["converged"] += bool(verdict.get(k))
                if got is not None:
                    row["shapes"][got[0] if got[0] != "CB" else f"CB({got[1]})"] += 1
                    row["structures"][structure_of[k]].append(k)
        touching = {}
        for kind, seeded in (("own", False), ("seeded", True)):
            groups = {True: [], False: []}  # touching? → excess over the knot's lowest
            for k in pairs:
                low = min(e for e, _, _ in touch[(k, model)])
                for e, t, sd in touch[(k, model)]:
                    if sd == seeded:
                        groups[t].append(e / low - 1.0)
            touching[kind] = {
                "replicas": len(groups[True]) + len(groups[False]),
                "touching": len(groups[True]),
                "mean_excess_touching": _mean(groups[True]),
                "mean_excess_not_touching": _mean(groups[False])}
        touching["grounds_touching"] = [k for k in pairs if any(
            t for e, t, _ in touch[(k, model)] if e == min(x for x, _, _ in touch[(k, model)]))]
        out["models"][model] = {
            "widths": [{"N": b, "w/L": w} for b, w in sorted(widths[model])],
            "pairs": len(pairs), "replicas": len(reps),
            "cpu_seconds": round(sum(r[2] for r in reps), 1),
            "wall_seconds_of_replicas": round(sum(r[3] for r in reps), 1),
            "converged": sum(bool(verdict.get(k)) for k in pairs),
            "by_crossings": {nc: {"knots": v[0], "converged": v[1]}
                             for nc, v in sorted(by_nc.items())},
            "not_converged": [k for k in pairs if not verdict.get(k)],
            "gap_to_second_of_ground_shape": dict(zip(GAP_LABELS, gaps, strict=True)),
            "ground_shape_reached_once": lone,
            "families": {f: {**v, "shapes": dict(v["shapes"].most_common()),
                             "structures": dict(sorted(v["structures"].items(),
                                                       key=lambda kv: (-len(kv[1]), kv[0])))}
                         for f, v in fam_rows.items()},
            "touching_crossings": touching,
        }
    per_knot: dict[str, dict[str, str | None]] = collections.defaultdict(dict)
    for g in grounds:
        per_knot[g["knot"]][g["exclusion"]] = g["structure"]
    both = sorted((k for k, v in per_knot.items() if len(v) == 2), key=knot_sort_key)
    same = [k for k in both if len(set(per_knot[k].values())) == 1]
    out["two_long_boxes"] = two_long_boxes(grounds)
    out["same_structure_in_both_models"] = {"knots": len(both), "same": len(same),
                                            "which": same}
    return out


TWO_LINE_BRAIDS = "2 line-braids (m = 2) + double point"


def two_long_boxes(grounds: list[dict]) -> dict:
    """Per model: the rational knots (Conway notation ``[a b c …]``, one digit a box) with
    exactly two twist boxes of ≥ 3 crossings, and how many of their grounds are two
    line-braids of m = 2 joined at a double point (docs/atlas.md, "Naming what the
    families miss")."""
    out: dict = {}
    for g in grounds:
        m = re.fullmatch(r"\[(\d+)\]", get_knot(g["knot"]).conway_notation or "")
        if not m or sum(int(c) >= 3 for c in m.group(1)) != 2:
            continue
        row = out.setdefault(g["exclusion"], {"knots": 0, "two_line_braids": 0})
        row["knots"] += 1
        row["two_line_braids"] += g["structure"] == TWO_LINE_BRAIDS
    return out


def _mean(xs: list[float]) -> float | None:
    return round(sum(xs) / len(xs), 4) if xs else None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("db", nargs="?", default="results/stiffknots.db")
    ap.add_argument("--json", nargs="?", const=str(stable_path("atlas_summary")),
                    help="also write the summary to FILE (default: bench/atlas_summary.json)")
    ap.add_argument("--structures", action="store_true",
                    help="list the knots of every ground structure, per family")
    a = ap.parse_args(argv)
    s = summarise(a.db)
    print(f"{s['db']}: {s['rule']}")
    for model, m in s["models"].items():
        w = ", ".join(f"N = {x['N']}, w/L = {x['w/L']}" for x in m["widths"])
        print(f"\n{model} ({w}): {m['pairs']} knots, {m['replicas']} replicas "
              f"({m['replicas'] / max(1, m['pairs']):.1f} per knot), {m['cpu_seconds']:.0f} CPU s "
              f"({m['cpu_seconds'] / max(1, m['replicas']):.1f} per replica)")
        print(f"  converged {m['converged']} of {m['pairs']} "
              f"({m['converged'] / max(1, m['pairs']):.0%}); by crossings: "
              + ", ".join(f"{nc}: {v['converged']}/{v['knots']}"
                          for nc, v in m["by_crossings"].items()))
        print("  gap from the lowest replica of the ground shape to the next one: "
              + ", ".join(f"{k} {v}" for k, v in m["gap_to_second_of_ground_shape"].items())
              + f"; reached once {m['ground_shape_reached_once']}")
        print(f"  not converged ({len(m['not_converged'])}): {', '.join(m['not_converged'])}")
        tc = m["touching_crossings"]
        for kind in ("own", "seeded"):
            t = tc[kind]
            if t["replicas"]:
                exc = ", ".join(f"{lab} {100 * v:.1f} %" for lab, v in (
                    ("touching", t["mean_excess_touching"]),
                    ("not", t["mean_excess_not_touching"])) if v is not None)
                print(f"  strands touching where they cross ({kind} searches): {t['touching']} "
                      f"of {t['replicas']}; mean excess over the knot's lowest: {exc}")
        print(f"  grounds that touch: {len(tc['grounds_touching'])} "
              f"({', '.join(tc['grounds_touching']) or '—'})")
        print("  | family | knots | ground = predicted shape | converged | ground shapes |")
        print("  |---|---|---|---|---|")
        for fam in ("n=i", "4C", "80", "none"):
            v = m["families"].get(fam)
            if v:
                shapes = ", ".join(f"{k} {n}" for k, n in v["shapes"].items())
                pred = "—" if fam == "none" else str(v["as_predicted"])
                print(f"  | {fam} | {v['knots']} | {pred} | {v['converged']} | {shapes} |")
        every: dict[str, set[str]] = collections.defaultdict(set)
        for v in m["families"].values():
            for name, ks in v["structures"].items():
                every[name].update(ks)
        common = sorted(every.items(), key=lambda kv: (-len(kv[1]), kv[0]))
        print(f"  ground structures (§V B): {sum(len(v) for v in every.values())} knots in "
              f"{len(common)} structures; the commonest: "
              + "; ".join(f"{name} {len(ks)}" for name, ks in common[:6]))
        print("  ground structures (§V B), per family — the commonest:")
        for fam in ("n=i", "4C", "80", "none"):
            v = m["families"].get(fam)
            if not v:
                continue
            top = list(v["structures"].items())
            print(f"    {fam}: " + "; ".join(f"{name} {len(ks)}" for name, ks in top[:4])
                  + (f"; {len(top) - 4} others" if len(top) > 4 else ""))
            if a.structures:
                for name, ks in top:
                    print(f"      {name} ({len(ks)}): "
                          + ", ".join(f"{k} {get_knot(k).conway_notation or ''}".strip()
                                      for k in ks))
    for model, v in s["two_long_boxes"].items():
        print(f"{model}: rational knots with two twist boxes of ≥ 3 crossings: {v['knots']}, "
              f"of which {v['two_line_braids']} end as {TWO_LINE_BRAIDS}")
    sb = s["same_structure_in_both_models"]
    if sb["knots"]:
        print(f"\nground structure the same in both models: {sb['same']} of {sb['knots']} knots")
    if a.json:
        with open(a.json, "w", encoding="utf-8") as fh:
            json.dump({"meta": run_meta(argv), **s}, fh, indent=1, ensure_ascii=False)
            fh.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
