"""The paper's five knots (§VII: 3_1, 4_1, 5_2, 6_2, 6_3): theory and annealed energies.

This is what ``make run`` runs. It writes a report folder with ``report.md``, ``summary.json``,
the elastica figure and a picture of the best chain of every knot. Shape classification and
metastable states are the subject of a later stage; here every state is reported with its ε,
its minimum segment–segment distance and its verified knot type, next to the paper's bounds.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

from stiffknots._version import __version__

PAPER_KNOTS = ("3_1", "4_1", "5_2", "6_2", "6_3")
# ε of the Monte Carlo shapes as read in the paper (§VII, Fig. 7 caption and text)
PAPER_MC = {"3_1": "CB (i = 2), 8π² ≈ 78.96 in the thin limit", "4_1": "4C, 129.6",
            "5_2": "4C (ground) and 80 (metastable)", "6_2": "80", "6_3": "80"}
BUDGETS = {
    "small": {"moves": 20_000_000, "replicas": 2},
    "full": {"moves": 100_000_000, "replicas": 8},
}


def run_paper(budget: str = "small", out_dir: str | Path = "results/paper", seed: int = 0,
              log: Callable[[str], None] | None = None) -> dict:
    """Run the paper's study on ``budget`` and write the report; returns the summary dict."""
    from stiffknots.annealing import anneal
    from stiffknots.cli import knot_summary
    from stiffknots.report.render import save_chain_png
    from stiffknots.theory.elastica import elastica_constants, hierarchy, plot_elastica

    say = log or (lambda s: None)
    b = BUDGETS[budget]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    c = elastica_constants()
    plot_elastica(str(out / "elastica.png"))
    h = hierarchy()
    say(f"elastica: ε_loop = {c.eps_loop:.6f}, ε_8 = {c.eps_8:.6f}, ε_80 = {c.eps_80:.6f}, "
        f"α = {c.alpha:.6f}; figure {out / 'elastica.png'}")
    rows = []
    for name in PAPER_KNOTS:
        th = knot_summary(name)
        say(f"{name}: n = {th['bridge_number']}, i = {th['braid_index']}, "
            f"bounds [{th['lower_bound']:.3f}, {th['upper_bound']:.3f}] — annealing "
            f"{b['replicas']} × {b['moves']:,} moves …")
        res = anneal(name, moves=b["moves"], replicas=b["replicas"], seed=seed)
        res.save(out / name)
        best = res.best
        save_chain_png(best.coords, out / name / "best.png",
                       title=f"{name}: ε = {best.epsilon:.3f} (N = 150)")
        eps = [r.epsilon for r in res.replicas]
        row = {
            "knot": name,
            "bridge_number": th["bridge_number"],
            "braid_index": th["braid_index"],
            "lower_bound": th["lower_bound"],
            "upper_bound": th["upper_bound"],
            "best_epsilon": best.epsilon,
            "replica_epsilons": eps,
            "min_segment_distance": best.min_segment_distance,
            "knot_verified": all(r.knot_verified for r in res.replicas),
            "within_bounds": th["lower_bound"] <= best.epsilon,
            "paper": PAPER_MC[name],
            "seeds": [r.seed for r in res.replicas],
        }
        rows.append(row)
        say(f"  best ε = {best.epsilon:.3f}; replicas {', '.join(f'{e:.2f}' for e in eps)}; "
            f"verified {row['knot_verified']}")
    summary = {
        "version": __version__,
        "budget": budget,
        "settings": BUDGETS[budget],
        "seed": seed,
        "elastica": c.as_dict(),
        "hierarchy": {"order": [(lab, v) for lab, v in h.entries], "holds": h.holds},
        "knots": rows,
        "wall_time": time.perf_counter() - t0,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    _write_markdown(out / "report.md", summary)
    say(f"report: {out / 'report.md'} ({summary['wall_time']:.0f} s)")
    return summary


def _write_markdown(path: Path, s: dict) -> None:
    e = s["elastica"]
    lines = [
        "# Stiff knots: the paper's five knots",
        "",
        f"stiffknots {s['version']}, budget `{s['budget']}` ({s['settings']['replicas']} "
        f"replicas × {s['settings']['moves']:,} moves, N = 150, bead exclusion d = 1/√2), "
        f"seed {s['seed']}, {s['wall_time']:.0f} s.",
        "",
        "## Elastica constants (Appendix D)",
        "",
        "| constant | value |",
        "|---|---|",
    ]
    lines += [f"| {k} | {v:.8f} |" for k, v in e.items()]
    lines += ["", "![elastica](elastica.png)", "", "## Annealed knots (ε = E_d·N/C)", "",
              "| knot | n | i | 2π²n² | upper bound | best ε | replicas | min seg. dist. | "
              "verified | paper |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in s["knots"]:
        lines.append(
            f"| {r['knot']} | {r['bridge_number']} | {r['braid_index']} | "
            f"{r['lower_bound']:.2f} | {r['upper_bound']:.2f} | {r['best_epsilon']:.3f} | "
            f"{', '.join(f'{x:.2f}' for x in r['replica_epsilons'])} | "
            f"{r['min_segment_distance']:.3f} | {r['knot_verified']} | {r['paper']} |")
    lines += ["", "Hierarchy (e:hierarchy): " + " < ".join(
        f"{lab} ({v:.2f})" for lab, v in s["hierarchy"]["order"])
        + f" — holds: {s['hierarchy']['holds']}", ""]
    for r in s["knots"]:
        lines += [f"### {r['knot']}", "", f"![{r['knot']}]({r['knot']}/best.png)", ""]
    path.write_text("\n".join(lines))
