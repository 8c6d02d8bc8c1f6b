"""Commands about the catalogue and the theory: ``knot``, ``elastica``, ``families``,
``version``."""

from __future__ import annotations

import math
import time
from typing import Annotated

import typer
from rich.table import Table

from stiffknots._version import __version__
from stiffknots.cli.app import (
    JsonOpt,
    UserError,
    count,
    dump,
    err,
    floats,
    fmt,
    out,
    prepare_folder,
)


def knot(name: Annotated[str, typer.Argument(help="Knot name: 4_1, 4.1, K11a1, T(2,3) ...")],
         json_: JsonOpt = False) -> None:
    """A knot's data (KnotInfo), its energy bounds and, when n = i, its ground state."""
    from stiffknots.knots.catalogue import mirror_note
    from stiffknots.knots.summary import knot_summary

    d = knot_summary(name)
    note = mirror_note(name)
    if note:
        d["mirror_note"] = note
    if json_:
        dump(d)
        return
    t = Table(title=f"knot {d['name']}" + (f" = {d['torus']}" if d["torus"] else ""),
              show_header=False)
    def known(v, rng):
        if v is not None:
            return fmt(v)
        return f"unknown (between {rng[0]} and {rng[1]})" if rng else "unknown"

    t.add_row("crossing number n_c", str(d["crossing_number"]))
    t.add_row("bridge number n", known(d["bridge_number"], d["bridge_number_range"]))
    t.add_row("braid index i", known(d["braid_index"], d["braid_index_range"]))
    w = d["braid_word"]
    t.add_row("braid word", " ".join(str(g) for g in w) if w else "— (none needed)")
    alt = d["alternating"]
    t.add_row("alternating", "unknown" if alt is None else ("yes" if alt else "no"))
    nr, ir = d["bridge_number_range"], d["braid_index_range"]
    ranged = d.get("bounds_from_ranges")
    t.add_row("ε lower bound 2π²n² (eq. (13))", fmt(d["lower_bound"]) + (
        f" (n ≥ {nr[0]})" if ranged and d["lower_bound"] is not None else ""))
    by = d["upper_bound_attained_by"]
    t.add_row("ε upper bound" + (f" ({by})" if by else "") + " (eq. (31))",
              fmt(d["upper_bound"]) + (f" (n ≤ {min(nr[1], ir[1])}, i ≤ {ir[1]})"
                                       if ranged and d["upper_bound"] is not None else ""))
    g = d["predicted_ground_state"]
    if g:
        ground = (f"circular braid, multiplicity {g['multiplicity']}, "
                  f"ε* = {g['epsilon']:.4f}")
    elif d["bridge_number"] is None or d["braid_index"] is None:
        ground = "not fixed: n and i are not both known"
    else:
        ground = "not fixed by the bounds (n < i)"
    t.add_row("ground state", ground)
    if "open_tension_bounds" in d:
        ob = d["open_tension_bounds"]
        t.add_row("open knot μ*L_e²/C (eq. (45))", f"[{fmt(ob['lower'])}, {fmt(ob['upper'])}]")
    rc = d["restricted_curvature_bounds"]
    t.add_row("restricted curvature L†/R (§IX D)",
              (f"[{fmt(rc['lower'])}, {fmt(rc['upper'])}]" if rc["upper"] is not None
               else f"≥ {fmt(rc['lower'])}") if rc["lower"] is not None
              else "unknown (n and i unknown)")
    out.print(t)
    if note:
        out.print(note, markup=False, highlight=False)


def elastica(
    out_dir: Annotated[str | None, typer.Option("--out", help="Write elastica.png here.")
                       ] = None,
    json_: JsonOpt = False,
) -> None:
    """The planar elastica constants of Appendix D (loop, 8, 80), computed from its integrals
    and checked two independent ways (Jacobi elliptic functions; shooting the elastica ODE)."""
    from stiffknots.report.figures import plot_elastica
    from stiffknots.theory.elastica import PAPER_VALUES, elastica_constants

    folder = prepare_folder(out_dir, "--out")  # checked before any work
    c = elastica_constants("integrals")
    c2 = elastica_constants("elliptic")
    c3 = elastica_constants("shooting")
    d = c.as_dict()
    d["eps_cb_i2"] = 2 * math.pi**2 * 4
    d["eps_cb_i3"] = 2 * math.pi**2 * 9
    d["eps_pbl_n2"] = 16 * c.eps_loop
    d["cross_check"] = {k: abs(v - c2.as_dict()[k]) for k, v in c.as_dict().items()}
    d["cross_check_shooting"] = {k: abs(v - c3.as_dict()[k]) for k, v in c.as_dict().items()}
    d["paper"] = dict(PAPER_VALUES)
    png = None
    if folder is not None:
        png = folder / "elastica.png"
        plot_elastica(str(png))  # written atomically
        d["figure"] = str(png)
    if json_:
        dump(d)
        return
    t = Table(title="planar elastica (Appendix D)")
    for col in ("constant", "computed", "elliptic |Δ|", "shooting |Δ|", "paper"):
        t.add_column(col)
    for k, v in c.as_dict().items():
        t.add_row(k, f"{v:.10f}", f"{d['cross_check'][k]:.1e}",
                  f"{d['cross_check_shooting'][k]:.1e}", str(PAPER_VALUES[k]))
    out.print(t)
    if png:
        out.print(f"figure: {png}")


def families(
    max_crossings: Annotated[int, typer.Option(help="Largest crossing number (3..13).")] = 10,
    json_: JsonOpt = False,
) -> None:
    """The n = i family (ground state = circular braid) and its fraction (§VI C)."""
    from stiffknots.knots.catalogue import n_equals_i_knots, n_equals_i_statistics

    if not 3 <= max_crossings <= 13:
        raise UserError(f"--max-crossings must be between 3 and 13, got {max_crossings}")
    st = n_equals_i_statistics(max_crossings)
    knots = n_equals_i_knots(max_crossings)
    tot = st["total"]
    d = {
        "max_crossings": max_crossings,
        "total": tot["knots"],
        "n_equals_i": tot["n_equals_i"],
        "unknown": tot["unknown"],
        "fraction": tot["fraction"],
        "by_crossing": st["by_crossing"],
        "knots": [k.name for k in knots],
    }
    if json_:
        dump(d)
        return
    t = Table(title=f"n = i prime knots, 3 ≤ n_c ≤ {max_crossings}",
              caption="fraction: of the knots whose n and i KnotInfo gives (unknown: "
                      "left out)" if tot["unknown"] else None)
    for col in ("n_c", "knots", "n = i", "unknown", "fraction"):
        t.add_column(col, justify="right")
    for c, row in st["by_crossing"].items():
        t.add_row(str(c), str(row["knots"]), str(row["n_equals_i"]), str(row["unknown"]),
                  fmt(row["fraction"], 3))
    t.add_row("all", str(tot["knots"]), str(tot["n_equals_i"]), str(tot["unknown"]),
              fmt(tot["fraction"], 3))
    out.print(t)
    out.print("n = i knots: " + ", ".join(d["knots"]))


def starts(
    max_crossings: Annotated[int, typer.Option(help="Largest crossing number (3..13).")] = 12,
    crossings: Annotated[str | None, typer.Option(
        help="Only these crossing numbers, comma-separated (e.g. 11,12).")] = None,
    families: Annotated[str, typer.Option(
        help="Start families, comma-separated: braid, cage, eighty.")] = "braid,cage,eighty",
    beads: Annotated[int, typer.Option(help="Beads N of every chain.", parser=count)] = 150,
    workers: Annotated[int, typer.Option(help="Processes side by side.", parser=count)] = 2,
    json_: JsonOpt = False,
) -> None:
    """Build every knot's starting chains — the braid closure, the 4-fold cage where the knot
    has two boxes, the 80 where its family has it — at N beads and verify each one's knot
    type (HOMFLY-PT and the invariants that break its ties); list any that cannot be built
    or is another knot, with the reason. Built once and kept in the cache (the 2,977 knots
    through 12 crossings: about 10 CPU minutes the first time, seconds after). See
    docs/methods/search.md#the-start-table."""
    from stiffknots.knots.catalogue import MAX_CROSSINGS
    from stiffknots.knots.start_table import FAMILIES, start_table, summarise

    if not 3 <= max_crossings <= MAX_CROSSINGS:
        raise UserError(f"--max-crossings must be between 3 and {MAX_CROSSINGS}, "
                        f"got {max_crossings}")
    cs = None
    if crossings is not None:
        vals = floats(crossings, "--crossings")
        if any(v != int(v) or not 3 <= v <= max_crossings for v in vals):
            raise UserError(f"--crossings: whole numbers between 3 and --max-crossings "
                            f"({max_crossings}), got {crossings!r}")
        cs = sorted({int(v) for v in vals})
    fams = [f.strip() for f in families.split(",") if f.strip()]
    bad = [f for f in fams if f not in FAMILIES]
    if bad or not fams:
        raise UserError(f"--families {families!r}: choose from {', '.join(FAMILIES)}")
    if not 20 <= beads <= 100_000:
        raise UserError(f"--beads must be between 20 and 100000, got {beads}")
    if not 1 <= workers <= 64:
        raise UserError(f"--workers must be between 1 and 64, got {workers}")
    t0 = time.perf_counter()

    def progress(done, total, label):
        err.print(f"{time.strftime('%H:%M:%S')} chunk {done}/{total} ({label}), "
                  f"{time.perf_counter() - t0:.0f} s", highlight=False)

    rows = start_table(max_crossings, crossings=cs, families=fams, n_beads=beads,
                       workers=workers, progress=None if json_ else progress)
    summ = summarise(rows)
    d = {"max_crossings": max_crossings, "crossings": cs, "families": fams, "n_beads": beads,
         "version": __version__, "wall_seconds": time.perf_counter() - t0, **summ,
         "rows": [r.as_dict() for r in rows]}
    d["by_crossing"] = {str(c): v for c, v in summ["by_crossing"].items()}
    if json_:
        dump(d)
        return
    t = Table(title=f"starting chains at N = {beads}: built and verified")
    for col in ("n_c", "knots", *fams, "another family", "failed"):
        t.add_column(col, justify="right")
    for c, v in summ["by_crossing"].items():
        fam = v["families"]

        def cell(f, fam=fam):
            g = fam.get(f, {})
            text = str(g.get("verified", 0))
            if g.get("verified") and g.get("tube_ok") != g.get("verified"):
                text += f" ({g['tube_ok']} tube)"
            return text + (f" (+{g['tie']} tie)" if g.get("tie") else "")

        t.add_row(str(c), str(v["knots"]), *[cell(f) for f in fams], str(v["another_family"]),
                  str(sum(fam.get(f, {}).get("failed", 0) for f in fams)))
    t.caption = ("verified chains; (k tube): k of them also admissible for the tube model "
                 "(segments ≥ 1/√2 apart), where not all are")
    out.print(t)
    for r in summ["failed"]:
        out.print(f"failed: {r['knot']} {r['family']}: {r['reason']}", highlight=False)
    for r in summ["not_tube"]:
        out.print(f"not for the tube: {r['knot']} {r['family']}: segments "
                  f"{r['segment_distance']:.4f} apart (< 1/√2)", highlight=False)
    for r in summ["ties"]:
        out.print(f"tie: {r['knot']} {r['family']}: {r['reason']}", highlight=False)
    out.print(f"{summ['knots']} knots at N = {beads}; {len(summ['failed'])} failed; building "
              f"and naming took {summ['seconds']:.0f} s summed over the rows (kept in the "
              "cache: the next run reads them)", highlight=False)


def version(json_: JsonOpt = False) -> None:
    """Print the package version."""
    if json_:
        dump({"version": __version__})
        return
    out.print(__version__)
