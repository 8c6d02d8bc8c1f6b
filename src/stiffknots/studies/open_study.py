"""Open knots under tension (§VIII) and the restricted-curvature problem (§IX D), measured.

``python -m stiffknots.studies.open_study --budget small|full --out DIR`` writes
``report.md``, ``report.html``, ``summary.json`` and figures:

1. the open trefoil's ε_e against the excess length L_e at a thin tube (w = 0.05 bond
   lengths), with the fit ε_e = ε_∞ + a/√L_e (the contact where the string passes through the
   loop costs ≈ √(w/R) relative to the loop's energy) and its extrapolation next to 2π²;
2. μ against 1/L_e² for 3_1, 4_1, 5_1, 5_2 with the fit of μL_e²/C, the finite-difference
   check of μ = E/L_e, and the bounds 2π²n₁² ≤ μL_e²/C ≤ 2π² min(α²n₁², i₁²);
3. L†/R for 3_1, 4_1, 5_2 against 2πn ≤ L†/R ≤ 2π min(7n/3, i).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from stiffknots._version import __version__
from stiffknots.fileio import write_json

TWO_PI2 = 2 * np.pi**2
BUDGETS = {
    "small": {"trend": [30, 40, 60], "trend_moves_per_le": 400_000, "scan": [40, 60],
              "scan_moves": 20_000_000, "tight_beads": 120, "tight_moves": 20_000_000,
              "replicas": 2},
    "full": {"trend": [30, 40, 60, 80, 100], "trend_moves_per_le": 1_000_000,
             "scan": [40, 60, 80], "scan_moves": 40_000_000, "tight_beads": 150,
             "tight_moves": 60_000_000, "replicas": 2},
}
SCAN_KNOTS = ("3_1", "4_1", "5_1", "5_2")
TIGHT_KNOTS = ("3_1", "4_1", "5_2")
THIN_W = 0.05
SCAN_W = 0.1


def fit_thin_limit(les, eps) -> dict:
    """Least-squares fit ε_e = ε_∞ + a/√L_e; returns ε_∞, a and the residual RMS."""
    x = 1 / np.sqrt(np.asarray(les, dtype=float))
    y = np.asarray(eps, dtype=float)
    a = np.column_stack([np.ones_like(x), x])
    sol, *_ = np.linalg.lstsq(a, y, rcond=None)
    rms = float(np.sqrt(np.mean((a @ sol - y) ** 2)))
    return {"eps_inf": float(sol[0]), "a": float(sol[1]), "rms": rms}


def _plot_trend(points, fit, path):
    from stiffknots.report.figures import plot_open_trend, save_figure

    return save_figure(plot_open_trend(points, fit, label="annealed open trefoil (tube w = 0.05)"),
                       path)


def _done(res):
    """``res``, unless Ctrl-C stopped its replicas: then the study stops (KeyboardInterrupt)."""
    if res.interrupted:
        raise KeyboardInterrupt
    return res


def run_open_study(budget: str = "small", out_dir: str | Path = "results/open", seed: int = 0,
                   log: Callable[[str], None] | None = None) -> dict:
    """Run the study on ``budget`` and write the report; returns the summary dict."""
    from stiffknots.engine.params import MoveParams
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems.open_extension import OPEN_M_LAW, anneal_open, tension_scan
    from stiffknots.problems.tightest import tightest
    from stiffknots.report.document import Document
    from stiffknots.report.figures import plot_tension, save_figure
    from stiffknots.report.render import save_chain_png

    if budget not in BUDGETS:
        raise ValueError(f"unknown budget {budget!r}; allowed: {', '.join(BUDGETS)}")
    b = BUDGETS[budget]
    say = log or (lambda s: None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    summary: dict = {"budget": budget, "seed": seed, "version": __version__, "settings": b}

    # 1. the open trefoil towards the thin limit
    trend = []
    for le in b["trend"]:
        params = MoveParams(exclusion="tube", w=THIN_W, m_max=min(80, le), m_law=OPEN_M_LAW)
        r = _done(anneal_open("3_1", le, moves=b["trend_moves_per_le"] * le,
                              replicas=b["replicas"], seed=seed, params=params))
        d = r.to_dict()
        trend.append({"excess_length": le, "beads": d["beads"], "eps_e": d["eps_e"],
                      "tension": d["tension"], "shape": d["shape"],
                      "D_over_R": d["shape_features"].get("axis_distance_over_radius"),
                      "wall_time": d["wall_time"]})
        save_chain_png(r.best.coords, out / f"trefoil_Le{le}.png", closed=False,
                       title=f"open 3_1, L_e = {le}: ε_e = {d['eps_e']:.2f} ({d['shape']})")
        say(f"open 3_1 L_e = {le}: ε_e = {d['eps_e']:.3f} ({d['shape']}), "
            f"{d['wall_time']:.0f} s")
    fit = fit_thin_limit([p["excess_length"] for p in trend], [p["eps_e"] for p in trend])
    _plot_trend(trend, fit, out / "thin_limit.png")
    summary["trefoil_trend"] = {"w": THIN_W, "points": trend, "fit": fit,
                                "two_pi2": TWO_PI2,
                                "finest_rel_error": trend[-1]["eps_e"] / TWO_PI2 - 1}

    # 2. tension scans
    scans = {}
    tension_pts = []
    for name in SCAN_KNOTS:
        sc = tension_scan(name, b["scan"], moves=b["scan_moves"], replicas=b["replicas"],
                          seed=seed, params=MoveParams(exclusion="tube", w=SCAN_W, m_max=60,
                                                       m_law=OPEN_M_LAW))
        for res in sc.results:
            _done(res)
        scans[name] = sc.to_dict()
        lo, hi = sc.bounds["eps_e_lower"], sc.bounds["eps_e_upper"]
        fe = sc.fit_eps_e
        scans[name]["inside_bounds"] = bool(lo - 1e-9 <= fe <= hi + 1e-9)
        k = get_knot(name)
        for p in sc.points:
            tension_pts.append({"knot": name, "L_e": p["excess_length"], "mu": p["tension"],
                                "n": k.bridge_number, "i": k.braid_index})
        say(f"open {name}: μL_e²/C fit = {fe:.3f}, bounds [{lo:.3f}, {hi:.3f}]")
    save_figure(plot_tension(tension_pts), out / "tension.png")
    summary["tension"] = scans

    # 3. restricted curvature
    tight = {}
    for name in TIGHT_KNOTS:
        r = _done(tightest(name, b["tight_beads"], moves=b["tight_moves"],
                           replicas=b["replicas"], seed=seed))
        d = r.to_dict()
        d.pop("replicas")
        tight[name] = d
        save_chain_png(r.best.coords, out / f"tightest_{name}.png",
                       title=f"{name}: L†/R = {d['length_over_R']:.3f}")
        say(f"tightest {name}: L†/R = {d['length_over_R']:.3f}, bounds "
            f"[{d['lower_bound']:.3f}, {d['upper_bound']:.3f}]")
    summary["tightest"] = tight
    summary["wall_time"] = time.perf_counter() - t0
    write_json(out / "summary.json", summary)

    doc = Document("Open knots under tension and the restricted-curvature problem")
    doc.paragraph(f"stiffknots {__version__}, budget `{budget}`, seed {seed}; bond length 1, "
                  f"C = 1; wall time {summary['wall_time']:.0f} s. Ensemble: fixed excess "
                  "length L_e (ends clamped on the z axis); tension μ = E/L_e (§VIII).")
    doc.heading("Open trefoil towards the thin limit", 2)
    doc.table(["L_e", "N", "ε_e", "ε_e/2π² − 1", "shape", "D/R", "s"],
              [[p["excess_length"], p["beads"], round(p["eps_e"], 3),
                f"{p['eps_e'] / TWO_PI2 - 1:+.1%}", p["shape"],
                None if p["D_over_R"] is None else round(p["D_over_R"], 3),
                round(p["wall_time"])] for p in trend])
    doc.paragraph(f"Fit ε_e = ε_∞ + a/√L_e: ε_∞ = {fit['eps_inf']:.3f} (2π² = {TWO_PI2:.3f}), "
                  f"a = {fit['a']:.2f}. Tube diameter w = {THIN_W}.")
    doc.image("thin_limit.png", "ε_e of the open trefoil against 1/√L_e")
    doc.image(f"trefoil_Le{trend[-1]['excess_length']}.png", "finest open trefoil")
    doc.heading("Tension against excess length", 2)
    rows = []
    for name, sc in scans.items():
        fd = sc["finite_differences"]
        rows.append([name, sc["n"], sc["i"],
                     ", ".join(f"{p['eps_e']:.2f}" for p in sc["points"]),
                     round(sc["fit_eps_e"], 3), round(sc["bounds"]["eps_e_lower"], 3),
                     round(sc["bounds"]["eps_e_upper"], 3),
                     "yes" if sc["inside_bounds"] else "no",
                     ", ".join(f"{x['mu_finite_difference'] / x['mu_E_over_L']:.2f}"
                               for x in fd)])
    doc.table(["knot", "n", "i", f"ε_e at L_e = {b['scan']}", "fit μL_e²/C", "lower",
               "upper", "inside", "(−dE/dL_e)/(E/L_e)"], rows)
    doc.image("tension.png", "μ against 1/L_e² with the bounds of §VIII")
    doc.heading("Restricted curvature: shortest knot with curvature ≤ 1/R", 2)
    doc.table(["knot", "N", "L†/R", "lower 2πn", "upper 2π min(7n/3, i)", "inside"],
              [[n, d["beads"], round(d["length_over_R"], 4), round(d["lower_bound"], 4),
                round(d["upper_bound"], 4),
                "yes" if d["lower_bound"] - 1e-9 <= d["length_over_R"]
                <= d["upper_bound"] + 1e-9 else "no"] for n, d in tight.items()])
    for name in TIGHT_KNOTS:
        doc.image(f"tightest_{name}.png", f"{name}, shortest chain found")
    doc.write(out)
    say(f"report: {out / 'report.md'}, {out / 'report.html'}")
    return summary


def main() -> None:
    """The command line of the module docstring (``--budget``, ``--out``, ``--seed``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", default="small", choices=sorted(BUDGETS))
    ap.add_argument("--out", default="results/open")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    run_open_study(a.budget, a.out, a.seed, log=print)


if __name__ == "__main__":
    main()
