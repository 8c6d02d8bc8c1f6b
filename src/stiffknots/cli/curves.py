"""Commands about curves brought by the user: ``identify`` (what knot is in this file) and
``resample`` (N unit bonds, same knot type)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from stiffknots.cli.app import JsonOpt, ReplicasOpt, UserError, count, dump, err, fmt, out

FileArg = Annotated[Path, typer.Argument(
    help="A curve: .xyz, .txt/.dat/.csv/.tsv (x y z), .json, .npz/.npy, .obj (ElasticKnots), "
         ".vect (KnotPlot, ridgerunner).", show_default=False)]
ClosedOpt = Annotated[bool | None, typer.Option(
    "--closed/--open",
    help="Read the curve as closed (a knot) or open; default: what the file records, a "
         "repeated first vertex means closed, and otherwise closed is assumed (and said).",
    show_default=False)]


#: the most vertices identify, resample and relax take: the time of the knot invariants
#: (topoly's reduction) grows as the square of the vertices (docs/curves.md)
MAX_VERTICES = 20_000


def _load(path: Path, closed: bool | None):
    from stiffknots.formats import load

    chain = load(path, closed=closed)
    if chain.n_beads > MAX_VERTICES:
        raise UserError(f"{path}: {chain.n_beads:,} vertices; identify, resample and relax take "
                        f"curves of at most {MAX_VERTICES:,} (the knot invariants' time grows as "
                        "the square of the vertices, docs/curves.md): give a coarser polygon")
    return chain


def _say_long(chain, path: Path) -> None:
    """One line on stderr before the knot invariants of a long polygon (seconds to
    minutes): what takes the time, and that Ctrl-C stops it."""
    from stiffknots.knots.identify import CHILD_FROM

    if chain.n_beads >= CHILD_FROM:
        err.print(f"{path}: {chain.n_beads:,} vertices: computing the knot invariants (this "
                  "can take minutes; Ctrl-C stops) ...", markup=False, highlight=False,
                  soft_wrap=True)


def _identify(chain) -> dict:
    from stiffknots.errors import IdentificationError
    from stiffknots.formats import closure_note
    from stiffknots.knots.identify import identify_details

    try:
        r = identify_details(chain.coords, closed=chain.closed)
    except IdentificationError as exc:
        raise UserError(f"cannot identify the knot: {exc}") from None
    except ValueError as exc:  # a polygon that meets itself
        raise UserError(f"cannot identify the knot: {exc}") from None
    from stiffknots.chain import Chain
    from stiffknots.knots.singular import rescaled

    # lengths and ε measured at order 1 (exact powers of two: ε is scale invariant, 1e300
    # coordinates overflowed to inf and nan)
    scaled = Chain(rescaled(chain.coords), chain.closed)
    big = float(np.max(np.abs(chain.coords)))
    factor = big / float(np.max(np.abs(scaled.coords))) if big else 1.0
    b = scaled.bond_lengths() * factor
    d = {
        "file": str(chain.meta.get("source", "")),
        "knot": r.name,
        "candidates": list(r.candidates),
        "chirality": r.chirality,
        "closure": closure_note(chain),
        "closed": chain.closed,
        "beads": chain.n_beads,
        "length": scaled.length * factor,
        "bond_length_range": [float(b.min()), float(b.max())],
        "input_epsilon": scaled.epsilon(),
        **{k: v for k, v in r.as_dict().items() if k not in ("knot", "candidates", "chirality")},
    }
    if r.name is not None and "#" not in r.name:
        from stiffknots.knots.catalogue import get_knot
        from stiffknots.knots.summary import knot_summary

        k = get_knot(r.name)
        s = knot_summary(r.name)
        d.update({
            "crossing_number": k.crossing_number,
            "bridge_number": k.bridge_number,
            "bridge_number_range": list(k.bridge_number_range or []) or None,
            "braid_index": k.braid_index,
            "braid_index_range": list(k.braid_index_range or []) or None,
            "torus": k.torus_notation,
            "epsilon_bounds": {"lower": s["lower_bound"], "upper": s["upper_bound"],
                               "upper_attained_by": s["upper_bound_attained_by"]},
        })
    return d


def identify(
    file: FileArg,
    closed: ClosedOpt = None,
    json_: JsonOpt = False,
) -> None:
    """Which knot is in a curve file: one name, its chirality, the closure used, ε as given.

    Ties of the HOMFLY-PT polynomial are broken by the knot complement (SnapPy)."""
    chain = _load(file, closed)
    _say_long(chain, file)
    d = _identify(chain)
    if json_:
        dump(d)
        return
    name = d["knot"] or ("tie: " + " | ".join(d["candidates"]) if d["candidates"]
                         else "not in the tables")
    t = Table(title=f"{file}", show_header=False)
    t.add_row("knot", name)
    t.add_row("chirality", {"+": "+ (KnotInfo's diagram)", "-": "- (mirror of KnotInfo's)"}
              .get(d["chirality"], "none") + f" — {d['chirality_by']}")
    t.add_row("decided by", ", ".join(d["decided_by"]))
    t.add_row("closure", d["closure"])
    t.add_row("beads", str(d["beads"]))
    lo, hi = d["bond_length_range"]
    t.add_row("bond lengths", f"{lo:.4g} … {hi:.4g} (length L = {d['length']:.6g})")
    t.add_row("ε of the polygon as given", fmt(d["input_epsilon"]))
    if "bridge_number" in d:
        t.add_row("crossing number n_c", str(d["crossing_number"]))
        t.add_row("bridge number n", fmt(d["bridge_number"]))
        t.add_row("braid index i", fmt(d["braid_index"]))
        eb = d["epsilon_bounds"]
        t.add_row("ε* bounds", f"[{fmt(eb['lower'])}, {fmt(eb['upper'])}]")
    out.print(t)


def resample(
    file: FileArg,
    dest: Annotated[Path, typer.Argument(
        help="Write the resampled chain here (.xyz, .json, .npz, .obj, .vect).",
        show_default=False)],
    beads: Annotated[int, typer.Option("--beads", help="Number of beads N (unit bonds).")] = 150,
    w_over_l: Annotated[float | None, typer.Option(
        "--w-over-L", help="Tube diameter over length: records w = (w/L)·N in bond units and "
                           "whether the resampled chain is that thick.")] = None,
    closed: ClosedOpt = None,
    json_: JsonOpt = False,
) -> None:
    """Resample a closed curve into N equal unit bonds that keep its knot type (checked)."""
    from stiffknots.cli.app import prepare_file
    from stiffknots.formats import check_readable, closure_note, save
    from stiffknots.knots.resample import resample as _resample
    from stiffknots.problems import validate as V

    V.beads(beads)
    if w_over_l is not None:  # the same rule as relax and anneal: a tube thinner than a bond
        V.w_over_L(w_over_l, beads)
    if dest.is_dir():
        raise UserError(f"DEST {dest} is a folder; give the path of a file")
    if dest.suffix.lower() not in (".xyz", ".json", ".npz", ".obj", ".vect"):
        raise UserError(f"{dest}: unknown suffix {dest.suffix!r}; use .xyz, .json, .npz, .obj "
                        "or .vect")
    check_readable(file)
    prepare_file(dest, "DEST")  # checked before any work
    chain = _load(file, closed)
    if not chain.closed:
        raise UserError(f"{file}: resample needs a closed curve (a knot); it was read as open")
    _say_long(chain, file)
    r = _resample(chain, beads, w_over_L=w_over_l)
    save(r, dest)
    d = {"file": str(file), "out": str(dest), "closure": closure_note(chain), "beads": beads,
         "input_beads": chain.n_beads, "input_epsilon": chain.epsilon(),
         "epsilon": r.epsilon(), **{k: v for k, v in r.meta.items()
                                    if k not in ("source", "closure")}}
    if json_:
        dump(d)
        return
    out.print(f"{file} ({chain.n_beads} vertices; {d['closure']}) → {dest}: {beads} unit bonds, "
              f"ε = {d['epsilon']:.4f} (as given {d['input_epsilon']:.4f}); HOMFLY-PT polynomial "
              "unchanged")
    if "w" in d:
        out.print(f"tube diameter w = {d['w']:.4g} bond lengths: "
                  + ("the chain is that thick" if d["tube_fits"] else
                     f"the chain is thinner ({d['thickness']:.4g}): relax it first"))


def relax(
    file: FileArg,
    beads: Annotated[int, typer.Option(help="Number of beads N of the relaxed chain.",
                                       parser=count)] = 150,
    exclusion: Annotated[str, typer.Option(
        help="bead (the paper's rule, d = 1/√2 bond) or tube (diameter w = (w/L)·N).")
    ] = "bead",
    w_over_l: Annotated[float | None, typer.Option(
        "--w-over-L", help="Tube diameter over length (sets --exclusion tube).")] = None,
    knot: Annotated[str | None, typer.Option(
        help="The knot's name, when the invariants cannot tell (a HOMFLY-PT tie).")] = None,
    moves: Annotated[int | None, typer.Option(
        help="Monte Carlo moves per replica (default: 40 % of the annealing budget at N; "
             "3e7 works too).", parser=count)] = None,
    replicas: ReplicasOpt = 2,
    seed: Annotated[int, typer.Option(help="Seed.")] = 0,
    closed: ClosedOpt = None,
    polish: Annotated[bool, typer.Option(
        "--polish/--no-polish", help="Finish with the final minimiser (local minimum).")
    ] = True,
    out_dir: Annotated[str | None, typer.Option("--out", help="Write the results here.")
                       ] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace an earlier run's "
                                            "results in --out.")] = False,
    json_: JsonOpt = False,
) -> None:
    """Relax a curve from a file (resampled to N unit bonds, type kept and checked) to the
    nearest stiff-knot equilibrium; reports its ε before and after and its shape."""
    from stiffknots.cli.app import (
        ReplicaProgress,
        check_interrupted,
        emit,
        finish,
        prepare_folder,
        prepare_out,
    )
    from stiffknots.formats import closure_note
    from stiffknots.problems.base import solve
    from stiffknots.problems.relax import Relax

    chain = _load(file, closed)
    prepare_folder(out_dir, "--out")  # writable (created now, removed if the command fails)
    # claimed before the problem is built (identifying the curve takes seconds), as anneal
    # does: a folder holding another run's results is refused at once
    out_path = prepare_out(out_dir, overwrite)
    _say_long(chain, file)
    problem = Relax(chain, beads, moves, replicas, seed, exclusion=exclusion,
                    w_over_L=w_over_l, knot=knot, polish=polish)
    with ReplicaProgress(f"relax {problem.knot_name}", replicas, disable=json_) as bars:
        res = solve(problem, on_replica_done=bars.done, on_progress=bars, isolate=True)
    check_interrupted(res)
    width = res.width
    d = res.to_dict() | {"file": str(file), "closure": closure_note(chain)}
    if emit(res, d, out_path, f"{res.knot}: ε = {res.epsilon:.3f} ({width.text})", "relax",
            json_, replicas):
        return
    out.print(f"{file}: {d['closure']}", markup=False, highlight=False)
    out.print(f"{res.knot}: ε = {d['input_epsilon']:.4f} as given → {d['epsilon']:.4f} relaxed "
              f"({d['shape']}, {width.text}); "
              + ("converged: " if res.converged else "NOT converged: ") + res.convergence,
              markup=False, highlight=False)
    note = res.best.observables.get("shape_note") if res.replicas else None
    if note:  # --w-over-L thinner than the shape analysis sees: one plain line
        out.print(f"note: its shape was read at the tube's diameter, where {note}",
                  markup=False, highlight=False, soft_wrap=True)
    if out_path is not None:
        out.print(f"results in {out_path}/", markup=False, highlight=False)
    finish(res, replicas)
