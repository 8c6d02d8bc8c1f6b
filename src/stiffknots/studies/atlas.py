"""The atlas study: every prime knot through K crossings, swept, stored, tested against the
paper's families, and written as static pages.

:func:`run_atlas` runs a sweep (:func:`stiffknots.sweeps.run_sweep`: knots × models ×
replicas on Dask, resumable through the results store), then reads back from the store, for
every knot and model, the ground state and the metastable states of the sweep's ensemble
(:meth:`Store.states <stiffknots.store.sqlite.Store.states>`: one exclusion model, width, N
and settings), the chain of each state's representative replica (for the 3D views), and
writes the atlas pages (:func:`stiffknots.report.atlas.write_atlas`), ``eps_vs_n2.png`` and
``families.json``.

Every ε is a Monte Carlo value at the model's finite width (the bead rule d = 1/√2 or the
tube w, at N = 150: w/L ≈ 0.0047), stated with it; the thin-limit ε* lies below (§V A).

The families (paper §VI C and §VII, Fig. 8; :mod:`stiffknots.knots.families`)
------------------------------------------------------------------------------
:func:`family_study` sets the ground states found against the three conjectured families —
n = i → CB(i) (proven), the two-box rational knots [ab] → 4-fold cage, the 80 family → 80:

* from the catalogue alone, which knots each family holds and the fraction of the knots with
  n_c < 7 and n_c < 9 they cover (the paper: all, and 75 %);
* from the stored results, how many ground states are CB(i), 4C, 80 or other, how many are
  the shape their family predicts (:func:`stiffknots.knots.families.predicted_shape`), the
  knots whose ground state contradicts it, and the knots in no family with their shapes;
* ε against n² for n = 2, 3, 4 (:func:`stiffknots.report.figures.plot_eps_vs_n2`).

Convergence of an ensemble follows :func:`stiffknots.sweeps.ensemble_converged` (the ground
state's rule, after a replica from every default start).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from stiffknots import sweeps
from stiffknots._version import __version__
from stiffknots.fileio import replaced_entries, write_json
from stiffknots.store import Store
from stiffknots.store.thin import thin_knots
from stiffknots.sweeps import Budget, SweepListener, SweepResult
from stiffknots.sweeps.audit import latest_audits
from stiffknots.width import Width

__all__ = ["DEFAULT_OUT", "DEFAULT_DB", "bead_above_tube", "knot_records", "atlas_input",
           "json_entry", "family_study", "families_table", "eps_n2_points", "run_atlas",
           "structure_groups", "converged_counts", "not_converged_text", "thin_json",
           "thin_input"]

#: Where the pages go by default.
DEFAULT_OUT = Path("results") / "atlas"
#: The results database by default: the store's own default (one database for every sweep
#: and for ``stiffknots db``; the ensembles of different budgets or widths never mix).
DEFAULT_DB = Path("results") / "stiffknots.db"

_N_VALUES = (2, 3, 4)  # the bridge numbers of the ε–n² figure


def _states(store: Store, knot: str, model: Width, settings_hash: str) -> dict | None:
    """The states of one knot's ensemble under ``model`` and the sweep's settings; None if
    nothing is stored."""
    if not store.count(knot=knot, exclusion=model.exclusion, beads=model.beads,
                       thickness=model.thickness, settings_hash=settings_hash):
        return None
    return store.states(knot, model.exclusion, model.beads, model.thickness, settings_hash)


def knot_records(store: Store, knots: Sequence[str], models: Sequence[Width],
                 hashes: Mapping[str, str]) -> list[dict]:
    """Per knot: its catalogue entry, families, and each model's stored states.

    Returns
    -------
    list of dict
        ``name``, ``knot`` (catalogue entry), ``families``, ``models``: model name →
        ``{"model": Width, "states": Store.states(...) or None}``.
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.families import families_of

    out = []
    for name in knots:
        k = get_knot(name)
        out.append({"name": k.name, "knot": k, "families": families_of(k),
                    "models": {m.exclusion: {"model": m,
                                        "states": _states(store, k.name, m, hashes[m.exclusion])}
                               for m in models}})
    return out


def _state_json(s: Mapping, converged: bool | None) -> dict:
    return {"name": s["name"], "structure": s.get("structure"), "shape": s["shape"],
            "multiplicity": s["multiplicity"],
            "epsilon": s["epsilon"], "eps_mean": s["eps_mean"], "eps_max": s["eps_max"],
            "count": s["count"], "converged": converged,
            "min_segment_distance": s["min_segment_distance"], "starts": s["starts"],
            "representative": s["representative"], "seed": s["seed"],
            "replica": s["replica"], "start": s["start"]}


def _model_json(m: Width, st: Mapping | None) -> dict:
    width = m.as_dict()
    if st is None:
        return {"width": width, "replicas": 0, "ground": None, "metastable": [],
                "converged": False, "settings_hash": None}
    conv = sweeps.ensemble_converged(st)
    return {"width": width, "replicas": st["replicas"], "settings_hash": st["settings_hash"],
            "converged": conv, "ground": _state_json(st["ground"], conv),
            "metastable": [_state_json(s, None) for s in st["metastable"]]}


def bead_above_tube(rec: Mapping) -> dict | None:
    """A bead-rule ground state above the tube ground state of the same knot, N and
    thickness (d = w), or None. Every tube-admissible chain is bead-admissible (beads i, j
    with ``|i − j| ≥ 2`` are ends of segments that share no bead, hence ≥ w apart), so the bead
    rule's minimum is at most the tube's: a bead ground above it is a search that missed,
    by at least the difference (measured: 10_4 at N = 150, 260.73 against 223.89)."""
    found = {v["model"].exclusion: v for v in rec["models"].values()
             if v["states"] is not None and v["states"]["ground"] is not None}
    if "bead" not in found or "tube" not in found:
        return None
    b, t = found["bead"], found["tube"]
    if (b["model"].beads, b["model"].thickness) != (t["model"].beads, t["model"].thickness):
        return None
    eb, et = b["states"]["ground"]["epsilon"], t["states"]["ground"]["epsilon"]
    if eb <= et * (1 + 1e-9):
        return None
    return {"bead": eb, "tube": et, "missed_by": (eb - et) / et,
            "note": f"bead-rule ground {eb:.2f} above the tube's {et:.2f} (a tube chain of "
                    "this width is bead-admissible): the bead search missed"}


def json_entry(rec: Mapping, main_model: str) -> dict:
    """The ``--json`` entry of one knot: name, n, i, crossing number, families, the ground
    state of ``main_model`` (``shape``, ``multiplicity``, ``epsilon``, ``converged``) at top
    level, every model's states under ``models``."""
    k = rec["knot"]
    models = {name: _model_json(v["model"], v["states"]) for name, v in rec["models"].items()}
    g = models.get(main_model, {}).get("ground") or {}
    return {"name": k.name, "n": k.bridge_number, "i": k.braid_index,
            "crossing_number": k.crossing_number, "families": rec["families"],
            "model": main_model, "shape": g.get("shape"), "multiplicity": g.get("multiplicity"),
            "epsilon": g.get("epsilon"),
            "converged": bool(models.get(main_model, {}).get("converged", False)),
            "width": models.get(main_model, {}).get("width", {}).get("text"),
            "bead_above_tube": bead_above_tube(rec),
            "models": models}


def _bead_zones(x, d: float) -> list[int]:
    """The kind of contact zone of each bead of a stored chain (§V B,
    :meth:`~stiffknots.analysis.structure.Structure.bead_kinds`), for the pages' colouring by
    structure; only for a chain whose structure the store named (an admissible one)."""
    from stiffknots.analysis.structure import analyse_structure

    return analyse_structure(x, True, d=d).bead_kinds().tolist()


def audit_text(audit: Mapping | None) -> str | None:
    """What the newest audit of a verdict found, in words (``"held (3 searches)"``, ``"false:
    216.36 (80)"``); None where none was made."""
    if audit is None:
        return None
    if audit["false_verdict"]:
        return f"false: {audit['audit_epsilon']:.2f} ({audit['audit_state']})"
    return f"held ({audit['searches']} searches)"


def audit_of(audits: Mapping[tuple, Mapping], model: Width, st: Mapping) -> dict | None:
    """The newest audit of one ensemble's verdict (``audits``:
    :func:`stiffknots.sweeps.audit.latest_audits`)."""
    from stiffknots.store import thickness_key

    return audits.get((st["knot"], model.exclusion, model.beads,
                       thickness_key(model.thickness), st["settings_hash"]))


def thin_json(t: Mapping | None) -> dict:
    """The thin-stage fields of a knot's ``--json`` entry (from the summary of
    :func:`stiffknots.store.thin.thin_knots`; all None when no thin run is stored):
    ``epsilon_thin``,
    ``thin_error``, ``thin_structure``, ``thin_state`` (its name), ``thin_agree`` (the two
    routes), ``thin_width`` (the census's w/L), ``thin_budget`` and ``thin_states`` (per
    state: name, ε at the census's width, ε*, error, structure route, agree, event)."""
    if t is None:
        return {"epsilon_thin": None, "thin_error": None, "thin_structure": None,
                "thin_state": None, "thin_agree": None, "thin_width": None,
                "thin_budget": None, "thin_states": None}
    return {"epsilon_thin": t["epsilon_thin"], "thin_error": t["thin_error"],
            "thin_structure": t["thin_structure"], "thin_state": t["thin_shape"],
            "thin_agree": t["agree"], "thin_width": t["w_over_L"],
            "thin_budget": t["budget"],
            "thin_states": [{k: s[k] for k in ("state", "name", "epsilon", "epsilon_thin",
                                               "error", "structure_epsilon",
                                               "structure_name", "agree", "event")}
                            for s in t["states"]]}


def thin_input(store: Store, t: Mapping | None) -> dict | None:
    """A knot's thin stage in the input schema of the atlas pages (``thin``:
    :mod:`stiffknots.report.atlas.schema`), with the thinnest chain of its thin-limit
    ground for the 3D view; None when no thin run is stored."""
    from stiffknots.store.thin import thin_chain

    if t is None:
        return None
    g = t["ground"]
    states = []
    for s in t["states"]:
        pts = [{"w_over_L": p["w_over_L"], "epsilon": p["epsilon"], "beads": p.get("beads"),
                "in_fit": bool(p["in_fit"])} for p in s["details"]["points"]]
        states.append({"name": s["name"], "state": s["state"], "epsilon": s["epsilon"],
                       "epsilon_thin": s["epsilon_thin"], "error": s["error"],
                       "structure_epsilon": s["structure_epsilon"],
                       "structure_name": s["structure_name"], "agree": s["agree"],
                       "event": s["event"], "ground": s["ground"], "points": pts})
    chain = None
    if g is not None:
        p = g["details"]["points"][g["details"]["thin_point"]]
        chain = {"coords": thin_chain(store, g["id"]), "w_over_L": p["w_over_L"]}
    return {"budget": t["budget"], "seed": t["seed"], "w_over_L": t["w_over_L"],
            "ground": None if g is None else g["state"], "crossing": t["crossing"],
            "margin": t["margin"], "states": states, "chain": chain}


def atlas_input(store: Store, rec: Mapping, audits: Mapping[tuple, Mapping] | None = None
                ) -> dict:
    """One knot in the input schema of :func:`stiffknots.report.atlas.write_atlas`, with the
    chain of every state's representative replica, and the audit of each verdict where
    ``audits`` (:func:`stiffknots.sweeps.audit.latest_audits`) has one."""
    k = rec["knot"]
    models = {}
    for name, v in rec["models"].items():
        m, st = v["model"], v["states"]
        if st is None:
            continue
        radius = m.thickness / 2 if m.exclusion == "tube" else None
        conv = sweeps.ensemble_converged(st)

        def state(s: Mapping, converged: bool | None, radius=radius, d=m.thickness) -> dict:
            x = store.coords(s["representative"])
            return {"shape": s["shape"], "multiplicity": s["multiplicity"],
                    "structure": s.get("structure"), "epsilon": s["epsilon"],
                    "eps_mean": s["eps_mean"], "count": s["count"],
                    "converged": converged, "min_segment_distance": s["min_segment_distance"],
                    "coords": x, "closed": True, "radius": radius,
                    "zones": _bead_zones(x, d) if s.get("structure") else None}

        ground = state(st["ground"], conv)
        ground["audit"] = audit_text(audit_of(audits or {}, m, st))
        models[name] = {"width": m.text, "replicas": st["replicas"], "ground": ground,
                        "metastable": [state(s, None) for s in st["metastable"]]}
    fam = rec["families"]
    note = ("conjectured families: " + ", ".join(fam)) if fam else \
        "in none of the conjectured families (n = i, 4-fold cage, 80)"
    return {"name": k.name, "crossing_number": k.crossing_number, "n": k.bridge_number,
            "i": k.braid_index, "families": fam, "note": note, "models": models}


def _shape_class(g: Mapping | None) -> str | None:
    """``CB(i)``, ``4C``, ``80``, ``other``: the class of a ground state (CB of any i)."""
    if not g:
        return None
    return "CB(i)" if g["shape"] == "CB" else str(g["shape"])


def family_study(grounds: Mapping[str, Mapping | None], *, model: str, width: str,
                 limits: Sequence[int] = (7, 9)) -> dict:
    """The paper's families against the ground states found (module docstring).

    Parameters
    ----------
    grounds : mapping
        Knot name → its ground state under ``model`` (``shape``, ``multiplicity``,
        ``epsilon``, ``converged``), or None where nothing is stored. The knots swept.
    model : str
        The model of the ground states (``bead``).
    width : str
        The width they were computed at (every ε of the result carries it).
    limits : sequence of int
        The crossing-number columns ``n_c < c`` (the paper's 7 and 9).

    Returns
    -------
    dict
        ``model``, ``width``, ``catalogue`` (:func:`~stiffknots.knots.families.coverage` of
        the catalogue through 10 crossings, with the paper's claims), ``groups`` (per column:
        ``knots`` swept with a ground state, ``counts`` by class, ``in_family``,
        ``as_predicted``, ``converged``), ``knots`` (per swept knot: families, predicted and
        found shape, ε, converged), ``mismatch`` (a family's knot whose ground state is not
        the predicted shape), ``no_family`` (knots in no family, with their shapes and
        contact structures), ``no_family_structures`` (those knots grouped by the structure
        of their ground state: :func:`structure_groups`),
        ``eps_n2`` (n → points), ``rule`` (convergence).
    """
    from stiffknots.knots.catalogue import catalogue, get_knot
    from stiffknots.knots.families import (
        EIGHTY_FAMILY_MAX_CROSSINGS,
        coverage,
        families_of,
        predicted_shape,
    )

    per_knot: list[dict] = []
    for name, g in grounds.items():
        k = get_knot(name)
        pred = predicted_shape(k)
        found = None if not g else (g["shape"], g.get("multiplicity"))
        per_knot.append({
            "name": k.name, "crossing_number": k.crossing_number, "n": k.bridge_number,
            "i": k.braid_index, "families": families_of(k),
            "predicted": None if pred is None else _label(*pred),
            "shape": None if found is None else _label(*found),
            "class": _shape_class(g), "structure": None if not g else g.get("structure"),
            "epsilon": None if not g else g["epsilon"],
            "converged": None if not g else bool(g.get("converged")),
            "as_predicted": None if (found is None or pred is None) else found == pred,
        })
    groups = []
    top = max((r["crossing_number"] for r in per_knot), default=0)
    for c in [*sorted(set(limits)), None]:
        sel = [r for r in per_knot if r["shape"] is not None
               and (c is None or r["crossing_number"] < c)]
        counts: dict[str, int] = {}
        for r in sel:
            counts[r["class"]] = counts.get(r["class"], 0) + 1
        groups.append({"label": f"n_c < {c}" if c is not None else f"all swept (n_c ≤ {top})",
                       "limit": c, "knots": len(sel), "counts": counts,
                       "in_family": sum(1 for r in sel if r["families"]),
                       "as_predicted": sum(1 for r in sel if r["as_predicted"]),
                       "converged": sum(1 for r in sel if r["converged"])})
    cat = [k for k in catalogue(EIGHTY_FAMILY_MAX_CROSSINGS) if k.crossing_number >= 3]
    cov = coverage(cat, limits)
    paper = {"n_c < 7": 1.0, "n_c < 9": 0.75}
    for row in cov:
        row["paper"] = paper.get(row["label"])
    no_family = [r for r in per_knot if not r["families"]]
    return {
        "model": model, "width": width, "rule": sweeps.CONVERGENCE_RULE,
        "catalogue": cov, "groups": groups, "knots": per_knot,
        "mismatch": [r for r in per_knot if r["as_predicted"] is False],
        "no_family": no_family,
        "no_family_structures": structure_groups(no_family),
        "eps_n2": eps_n2_points(per_knot),
    }


def structure_groups(rows: Sequence[Mapping]) -> list[dict]:
    """The knots of ``rows`` grouped by the contact structure of their ground state
    (:func:`stiffknots.analysis.structure_name`), largest group first: ``structure``,
    ``count``, ``knots`` (names, table order), ``shapes`` (class → count), ``epsilon``
    (lowest and highest). Knots without a result are left out. Names the shapes the
    classifier calls ``other`` (§V B), so that knots outside the conjectured families that
    share one structure show as a group."""
    groups: dict[str, list[Mapping]] = {}
    for r in rows:
        if r.get("structure") is None or r.get("epsilon") is None:
            continue
        groups.setdefault(str(r["structure"]), []).append(r)
    out = []
    for name, members in groups.items():
        shapes: dict[str, int] = {}
        for r in members:
            shapes[str(r["shape"])] = shapes.get(str(r["shape"]), 0) + 1
        eps = [float(r["epsilon"]) for r in members]
        out.append({"structure": name, "count": len(members),
                    "knots": [r["name"] for r in members], "shapes": shapes,
                    "epsilon": [min(eps), max(eps)]})
    return sorted(out, key=lambda g: (-g["count"], g["structure"]))


def _label(shape: str, multiplicity: int | None) -> str:
    return f"CB(i={multiplicity})" if shape == "CB" else shape


def eps_n2_points(per_knot: Sequence[Mapping]) -> dict[str, list[dict]]:
    """n → the points (knot, n, i, ε, shape) of the knots with bridge number n = 2, 3, 4 and
    a ground state (the input of :func:`stiffknots.report.figures.plot_eps_vs_n2`)."""
    out: dict[str, list[dict]] = {str(n): [] for n in _N_VALUES}
    for r in per_knot:
        if r.get("epsilon") is None or r.get("n") not in _N_VALUES:
            continue
        out[str(r["n"])].append({"knot": r["name"], "n": r["n"], "i": r["i"],
                                 "epsilon": r["epsilon"], "shape": r["class"]})
    return out


def families_table(study: Mapping) -> dict:
    """The ``families`` argument of :func:`~stiffknots.report.atlas.write_atlas`: per column
    (n_c < 7, n_c < 9, all swept) the ground-state classes, the knots in a family and those
    whose ground state is the predicted shape, over the swept knots with a ground state; the
    catalogue coverage and the paper's claims in the note."""
    groups = []
    for g in study["groups"]:
        counts = {f"ground {c}": g["counts"].get(c, 0) for c in ("CB(i)", "4C", "80", "other")}
        counts["in a conjectured family"] = g["in_family"]
        counts["ground = the family's shape"] = g["as_predicted"]
        counts["converged"] = g["converged"]
        groups.append({"label": g["label"], "total": g["knots"], "counts": counts})
    cov = "; ".join(f"{r['label']}: {r['covered']} of {r['knots']} "
                    f"({100 * (r['fraction'] or 0):.0f} %"
                    + (f", paper {100 * r['paper']:.0f} %" if r.get("paper") is not None
                       else "") + ")"
                    for r in study["catalogue"])
    groups_nf = study.get("no_family_structures", [])
    no_fam = (f"{sum(g['count'] for g in groups_nf)} with results, in {len(groups_nf)} contact "
              "structures (the table below)") if groups_nf else "none with results"
    unswept = [r["name"] for r in study["no_family"] if r["shape"] is None]
    if unswept:
        no_fam += f"; no result yet: {', '.join(unswept)}"
    mism = ", ".join(f"{r['name']} ({r['shape']}, predicted {r['predicted']})"
                     for r in study["mismatch"]) or "none"
    note = (f"Conjectured families (§VI C, §VII, Fig. 8): n = i → CB(i); two-box rational "
            f"[ab] → 4-fold cage; the 80 family → 80. Ground states of the {study['model']} "
            f"model at {study['width']}. Knots of the catalogue the three families hold — "
            f"{cov}. Swept knots in no family: {no_fam}. Ground state other than the "
            f"family's: {mism}. Converged: {study['rule']}.")
    structures = {
        "title": "The knots in no family, by the structure of their ground state",
        "note": (f"{study['model']} model at {study['width']}. The contact structure of §V B "
                 "— line-braids of m strands, point-braids (strands meeting tangentially), "
                 "double and triple points (strands crossing) — read from the ground state's "
                 "chain; it names the shapes the classifier calls 'other' and groups the "
                 "knots that share one."),
        "rows": [{k: g[k] for k in ("structure", "knots", "shapes", "epsilon")}
                 for g in groups_nf]}
    return {"title": "Conjectured families and the ground states found", "model":
            study["model"], "groups": groups, "note": note,
            **({"structures": structures} if groups_nf else {})}


def _plot_eps_n2(study: Mapping, path: Path) -> Path | None:
    from stiffknots.report.figures import plot_eps_vs_n2, save_figure

    pts = [p for n in _N_VALUES for p in study["eps_n2"][str(n)]]
    if not pts:
        return None
    ax = plot_eps_vs_n2(pts, labels=len(pts) <= 40,
                        title=f"ground states, {study['model']} model, {study['width']}")
    return save_figure(ax, path)


def budget_text(budget: Budget, models: Sequence[Width], max_replicas: int | None = None
                ) -> str:
    """The budget in one line, per model: its replicas and their moves (or dynamics steps),
    and the most replicas it may get (``max_replicas``: the sweep's override), e.g.
    ``default: bead 2 × Langevin dynamics of 1,000,000 steps, up to 12 until converged; tube
    2 × 15,000,000 moves, up to 6 until converged``."""
    parts = []
    for m in models:
        moves, _ = budget.search_of(m)
        top = budget.most_replicas(m) if max_replicas is None else max_replicas
        what = (f"Langevin dynamics of {moves:,} steps" if budget.langevin(m)
                else f"{moves:,} moves")
        parts.append(f"{m.exclusion} {budget.replicas} × {what}"
                     + (f", up to {top} until converged" if top > budget.replicas else ""))
    return f"{budget.name}: " + "; ".join(parts)


def converged_counts(entries: Sequence[Mapping], models: Sequence[Width]) -> dict[str, dict]:
    """Per model, over the knots with results in it (a part-way atlas has others): how many
    ground states converged (:mod:`stiffknots.sweeps.convergence`), of how many knots, and the
    knots whose did not, in catalogue order — the list the issue's 90 % target asks for.

    ``entries`` are :func:`json_entry` dicts."""
    counts = {}
    for m in models:
        done = [e for e in entries if e["models"][m.exclusion]["ground"]]
        counts[m.exclusion] = {
            "converged": sum(1 for e in done if e["models"][m.exclusion]["converged"]),
            "knots": len(done),
            "not_converged": [e["name"] for e in done if not e["models"][m.exclusion]["converged"]]}
    return counts


def not_converged_text(counts: Mapping[str, Mapping]) -> str:
    """:func:`converged_counts` in one line, e.g. ``bead 2 of 8: 7_4, 10_1; tube none of 8``."""
    return "; ".join(
        f"{name} {len(c['not_converged']) or 'none'} of {c['knots']}"
        + (f": {', '.join(c['not_converged'])}" if c["not_converged"] else "")
        for name, c in counts.items() if c["knots"]) or "no results stored yet"


#: what an atlas writes into its folder (replaced whole by the next atlas written there)
ATLAS_ENTRIES = ("index.html", "atlas.json", "families.json", "eps_vs_n2.png", "plotly.min.js",
                 "knots", "thumbs")


def run_atlas(knots: Sequence[str], models: Sequence[Width], budget: Budget, *,
              db: str | Path = DEFAULT_DB, out: str | Path = DEFAULT_OUT, seed: int = 0,
              scheduler: str | None = None, workers: int | None = None,
              max_replicas: int | None = None, listener: SweepListener | None = None,
              thumbnails: bool = True, command: str | None = None,
              run: bool = True, thin: str | None = None, thin_states: int | None = None,
              thin_listener: Any = None) -> dict:
    """Sweep ``knots`` × ``models`` on ``budget``, then write the atlas from the store.

    Parameters
    ----------
    knots : sequence of str
        Catalogue names (:func:`stiffknots.sweeps.resolve_knots`).
    models : sequence of Width
        The first is the model of the top-level fields, the family study and the default
        view of the pages (``bead`` when present).
    budget : Budget
    db : path
        The results database (created if missing; what it holds is reused).
    out : path
        The atlas folder (``index.html``, ``knots/``, ``atlas.json``, ``families.json``,
        ``eps_vs_n2.png``).
    seed, scheduler, workers, max_replicas, listener
        See :func:`stiffknots.sweeps.run_sweep` (``max_replicas``: replicas added to the
        (knot, model)s not converged, up to that many in all).
    thumbnails : bool
        Draw the ground-state thumbnails.
    command : str, optional
        The command line, shown at the foot of the index page.
    run : bool
        False: run nothing, write the atlas of what is stored (``sweep["left"]``: the jobs
        not yet run; a knot without results gets a row and a page that say so).
    thin : str, optional
        Run the thin stage after the sweep with this budget (``small`` or ``default``,
        :func:`stiffknots.studies.thin_stage.run_thin`): every state of each knot's tube census
        followed to w = 0; ``thin_states`` limits the states per knot, ``thin_listener``
        hears its progress. Thin results stored before are shown either way.

    Returns
    -------
    dict
        ``db``, ``html`` (None when interrupted: no pages are written then), ``sweep``
        (:meth:`SweepResult.to_dict`), ``knots`` (:func:`json_entry` per knot),
        ``families`` (:func:`family_study`), ``converged`` (model → the fraction of the
        knots with results in the model whose ground state converged), ``converged_counts``
        (model → ``{"converged", "knots", "not_converged"}``: the counts, and the knots with
        results whose ground state did not converge, :func:`converged_counts`), ``files``.
    """
    from stiffknots.report.atlas import write_atlas

    db, out = Path(db), Path(out)
    main = next((m.exclusion for m in models if m.exclusion == "bead"), models[0].exclusion)
    # run=False only reads: an existing database opens read-only (read-only media too)
    with Store(db, readonly=not run and db.is_file()) as store:
        sweep: SweepResult = sweeps.run_sweep(knots, models, budget, store, seed=seed,
                                       scheduler=scheduler, workers=workers,
                                       max_replicas=max_replicas, listener=listener,
                                       run=run)
        result: dict[str, Any] = {"db": str(db), "html": None, "sweep": sweep.to_dict()}
        if sweep.interrupted:
            return result
        if thin is not None and run:
            from stiffknots.studies.thin_stage import run_thin

            stage = run_thin(store, list(knots), budget=thin, seed=seed, states=thin_states,
                             scheduler=scheduler, workers=workers, listener=thin_listener)
            result["thin"] = stage.to_dict()
            if stage.interrupted:
                return result
        t0 = time.perf_counter()
        hashes = sweep.settings_hash
        recs = knot_records(store, knots, models, hashes)
        thins = {t["knot"]: t for t in thin_knots(store, list(knots))}
        entries = [{**json_entry(r, main), **thin_json(thins.get(r["knot"].name))}
                   for r in recs]
        width = next(m.text for m in models if m.exclusion == main)
        grounds = {e["name"]: e["models"][main]["ground"] for e in entries}
        study = family_study(grounds, model=main, width=width)
        counts = converged_counts(entries, models)
        meta = {"budget": budget_text(budget, models, max_replicas),
                "seed": seed, "models": "; ".join(m.text for m in models),
                "database": str(db), "converged": sweeps.CONVERGENCE_RULE,
                "not converged": not_converged_text(counts),
                "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                **({"command": command} if command else {})}
        # written aside and swapped in whole: a full disk or Ctrl-C leaves the earlier atlas,
        # and no page of an earlier, larger atlas stays behind
        with replaced_entries(out, ATLAS_ENTRIES, "atlas") as stage:
            audits = latest_audits(store)
            write_atlas(stage, [{**atlas_input(store, r, audits),
                                 "thin": thin_input(store, thins.get(r["knot"].name))}
                                for r in recs],
                        families=families_table(study), meta=meta, default_model=main,
                        thumbnails=thumbnails)
            fig = _plot_eps_n2(study, stage / "eps_vs_n2.png")
            write_json(stage / "families.json", {
                "version": __version__, "seed": seed, "budget": budget.as_dict(),
                "settings": {m.exclusion: sweeps.sweep_settings(m, budget) for m in models},
                **study})
    html = out / "index.html"
    files = {"html": str(html)}
    if fig is not None:
        files["eps_vs_n2"] = str(out / "eps_vs_n2.png")
    files["families"] = str(out / "families.json")
    converged = {k: (c["converged"] / c["knots"] if c["knots"] else None)
                 for k, c in counts.items()}
    result.update({"html": str(html), "knots": entries, "families": study,
                   "converged": converged, "converged_counts": counts, "files": files,
                   "atlas_seconds": time.perf_counter() - t0})
    return result
