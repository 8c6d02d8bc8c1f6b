"""The input of the atlas: the schema of its knots and states, their validation, and the
rows every page reads.

:func:`~stiffknots.report.atlas.write_atlas` is given plain data, described here; it never runs a
simulation. :func:`parse_knots` checks the data and turns it into :class:`KnotRow`,
:class:`ModelRow` and :class:`StateRow`.

Input schema
------------
``knots`` is a list of dicts, one per knot, in the order of the table::

    {
      "name": "4_1",                     # required, unique
      "crossing_number": 4,              # n_c, int or None
      "n": 2,                            # bridge number, int or None
      "i": 3,                            # braid index, int or None
      "bounds": {"lower": 78.96, "upper": 177.65, "attained_by": "CB"},  # optional; default
                                         #   stiffknots.theory.closed_bounds(n, i)
      "families": ["4C"],                # optional: shape families the knot belongs to
      "note": "...",                     # optional free text for the knot's page
      "thin": THIN,                      # optional: its states followed to w = 0 (below)
      "models": {                        # optional: one entry per energy model, e.g. bead, tube
        "bead": {
          "width": "bead rule d = 1/√2, N = 150",   # optional default for the states below
          "replicas": 8,                 # optional: number of annealed replicas
          "ground": STATE,               # the lowest state found (or None)
          "metastable": [STATE, ...],    # the other states, in increasing ε
        },
        "tube": {...},
      },
    }

where a ``STATE`` is a dict::

    {
      "shape": "4C",                     # shape class ("CB", "4C", "80", "other") or None
      "multiplicity": None,              # e.g. 2 for CB(2); shown as "CB(2)"
      "structure": "2 point-braids",     # optional: its contact structure named (§V B)
      "epsilon": 128.39,                 # ε = E L / C of the best chain of this state
      "eps_mean": 128.6,                 # optional: mean ε of the replicas in this state
      "count": 5,                        # optional: replicas that ended in this state
      "converged": True,                 # optional: True, False or None (unknown)
      "audit": "held",                   # optional: what an audit of the verdict found
                                         #   (stiffknots audit), e.g. "false: 216.36 (80)"
      "min_segment_distance": 0.48,      # optional: closest approach of two segments
      "coords": array of shape (N, 3),   # optional: the chain (for the 3D view, thumbnail)
      "zones": [0, 0, 1, 1, 2, ...],     # optional, with coords: per bead, the kind of contact
                                         #   zone it lies in (0 free strand, 1 line-braid,
                                         #   2 point-braid, 3 multiple point: Structure.
                                         #   bead_kinds); the 3D view can colour by it
      "closed": True,                    # optional (default True)
      "radius": 0.354,                   # optional: tube radius of the pictures (bond units;
                                         #   default half the bead distance 1/√2)
      "width": "bead rule d = 1/√2, N = 150",   # str or a dict such as {"w/L": 0.01}
    }

Widths. Every ``ε`` is a Monte Carlo value at a finite width, and it is shown with that width,
never as the paper's thin-limit ``ε*`` (which lies below every finite-width value, since
``ε*_w`` rises with ``w``). A state with an ``epsilon`` therefore needs a ``width`` (its own or
its model's); a bare number is refused, since it would not say whether it is a bead distance or
``w/L``. The bounds are thin-limit quantities and are labelled so.

``THIN`` (optional, the atlas's thin stage, :mod:`stiffknots.studies.thin_stage`) is a dict::

    {
      "w_over_L": 0.0047,                # the width of the census the states were taken at
      "budget": "small", "seed": 0,      # optional
      "ground": 0,                       # index into states of the thin-limit ground (or None)
      "crossing": None,                  # optional: w/L below which it lies under state 0
      "states": [{                       # the census's states, by ε at that width
        "name": "other", "epsilon": 128.57,          # ε at w_over_L
        "epsilon_thin": 126.03, "error": 0.18,       # ε* extrapolated to w = 0 (or None)
        "structure_epsilon": 126.1586, "structure_name": "point-braid + 2 double points",
        "agree": True,                   # the two routes agree (None: not compared)
        "event": None,                   # "jumped" / "merged": the branch left its state
        "points": [{"w_over_L": 0.004, "epsilon": 127.95, "in_fit": True}, ...],
      }, ...],
      "chain": {"coords": array (N, 3), "w_over_L": 0.0005},   # optional: the ground's
                                         #   thinnest chain (the 3D view)
    }

Every ``epsilon_thin`` and ``structure_epsilon`` is a thin-limit number (w = 0); every
``epsilon`` of a point states its ``w_over_L``.

``families`` (optional) is the family statistics table::

    {
      "title": "Ground-state shape families",   # optional
      "model": "bead",                           # optional: the model counted
      "groups": [                                # the columns
        {"label": "n_c < 7", "total": 7, "counts": {"CB": 3, "4C": 2, "80": 2}},
        {"label": "n_c < 9", "total": 35, "counts": {...}},
      ],
      "note": "...",                             # optional free text
      "structures": {                            # optional: knots by ground structure
        "title": "...", "note": "...",           #   (§V B), each knot linked to its page
        "rows": [{"structure": "2 line-braids (m = 2) + double point",
                  "knots": ["7_4", "8_4"], "shapes": {"other": 2},
                  "epsilon": [171.2, 181.5]}],
      },
    }

Fractions are ``count / total``. Without ``families``, :func:`family_statistics` is computed
from the knots' ground shapes. ``meta`` (optional) is a flat dict of facts shown at the foot of
the index page (budget, seed, date, command); the stiffknots and plotly.js versions are added.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stiffknots.theory import closed_bounds
from stiffknots.width import Width

__all__ = [
    "ZONE_KINDS",
    "KnotRow",
    "ModelRow",
    "StateRow",
    "family_statistics",
    "format_width",
    "model_names",
    "natural_key",
    "parse_knots",
]

#: the kinds of contact zone a bead can lie in (``zones`` of a state; codes 0 … 3)
ZONE_KINDS = ("free strand", "line-braid", "point-braid", "multiple point")


@dataclass
class StateRow:
    """One state of one model of a knot (a ``STATE`` of the schema), checked; ``role`` is
    ``"ground"`` or ``"metastable k"``."""

    role: str  # "ground" or "metastable k"
    shape: str | None
    multiplicity: int | None
    structure: str | None
    epsilon: float | None
    eps_mean: float | None
    count: int | None
    converged: bool | None
    min_segment_distance: float | None
    coords: np.ndarray | None
    closed: bool
    width: str | None
    radius: float | None
    zones: np.ndarray | None = None
    audit: str | None = None

    @property
    def shape_label(self) -> str | None:
        if self.shape is None:
            return None
        return f"{self.shape}({self.multiplicity})" if self.multiplicity else self.shape


@dataclass
class ModelRow:
    """The results of one energy model for one knot: its ground and metastable states."""

    name: str
    slug: str
    ground: StateRow | None
    metastable: list[StateRow]
    replicas: int | None
    width: str | None

    @property
    def states(self) -> list[StateRow]:
        return ([self.ground] if self.ground is not None else []) + self.metastable


@dataclass
class KnotRow:
    """One knot of the table, checked: its invariants, bounds, families and models."""

    name: str
    slug: str
    crossing_number: int | None
    n: int | None
    i: int | None
    lower: float | None
    upper: float | None
    attained_by: str | None
    exact: bool
    families: list[str]
    note: str | None
    models: dict[str, ModelRow] = field(default_factory=dict)
    thin: dict | None = None


def format_width(width: Any) -> str:
    """The width a Monte Carlo value was computed at, as one line of text.

    Parameters
    ----------
    width : Width, str or mapping
        A :class:`~stiffknots.width.Width` or its :meth:`~stiffknots.width.Width.as_dict`
        (→ its ``text``), a description (``"bead rule d = 1/√2, N = 150"``), or a mapping of
        named values (``{"w/L": 0.01}`` → ``"w/L = 0.01"``).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        For a bare number or anything else that does not say what the width is.
    """
    if isinstance(width, Width):
        return width.text
    if isinstance(width, str) and width.strip():
        return width.strip()
    if isinstance(width, Mapping) and {"exclusion", "beads", "w_over_L"} <= set(width):
        return Width.from_dict(width).text
    if isinstance(width, Mapping) and width:
        parts = []
        for k, v in width.items():
            if isinstance(v, float):
                v = f"{v:.6g}"
            parts.append(f"{k} = {v}")
        return ", ".join(parts)
    raise ValueError(
        f"a width must be a description such as 'bead rule d = 1/√2, N = 150' or a mapping such "
        f"as {{'w/L': 0.01}}, got {width!r}: a bare number does not say what it measures")


def _opt_int(v: Any, what: str) -> int | None:
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, int | np.integer) and not (
            isinstance(v, float | np.floating) and float(v).is_integer()):
        raise ValueError(f"{what} must be an integer or None, got {v!r}")
    return int(v)


def _opt_float(v: Any, what: str) -> float | None:
    if v is None:
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number or None, got {v!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{what} must be finite, got {v!r}")
    return x


def _coords(v: Any, what: str) -> np.ndarray | None:
    if v is None:
        return None
    try:
        x = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: coords must be an (N, 3) array of numbers") from None
    if x.ndim != 2 or x.shape[1] != 3 or len(x) < 3:
        raise ValueError(f"{what}: coords must have shape (N, 3) with N >= 3, got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{what}: coords contain NaN or infinite values")
    return x


def _zones(v: Any, coords: np.ndarray | None, what: str) -> np.ndarray | None:
    if v is None:
        return None
    if coords is None:
        raise ValueError(f"{what}: zones (the kind of contact zone of each bead) need the "
                         "state's coords")
    try:
        z = np.asarray(v)
    except (TypeError, ValueError):
        z = np.asarray([None])
    ok = (z.ndim == 1 and len(z) == len(coords) and np.issubdtype(z.dtype, np.integer)
          and bool(np.all((z >= 0) & (z < len(ZONE_KINDS)))))
    if not ok:
        raise ValueError(f"{what}: zones must be {len(coords)} integers (one per bead of the "
                         f"coords), each 0 … {len(ZONE_KINDS) - 1} ("
                         + ", ".join(f"{k} {n}" for k, n in enumerate(ZONE_KINDS))
                         + f"), got {v!r:.80}")
    return z.astype(np.int8)


def _slug(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._-")
    return s or "knot"


def _state(d: Any, role: str, model_width: str | None, where: str) -> StateRow:
    if not isinstance(d, Mapping):
        raise ValueError(f"{where}: a state must be a dict, got {type(d).__name__}")
    eps = _opt_float(d.get("epsilon"), f"{where}: epsilon")
    width = d.get("width")
    width = format_width(width) if width is not None else model_width
    if eps is not None and width is None:
        raise ValueError(
            f"{where}: ε = {eps:g} has no width; give the state (or its model) a 'width' such "
            "as 'bead rule d = 1/√2, N = 150' or {'w/L': 0.01}: a finite-width ε must never "
            "pass for the thin-limit ε*")
    conv = d.get("converged")
    if conv is not None and not isinstance(conv, bool | np.bool_):
        raise ValueError(f"{where}: converged must be True, False or None, got {conv!r}")
    shape = d.get("shape")
    structure = d.get("structure")
    if structure is not None and not isinstance(structure, str):
        raise ValueError(f"{where}: structure must be a text such as '2 point-braids' or "
                         f"None, got {structure!r}")
    audit = d.get("audit")
    if audit is not None and not isinstance(audit, str):
        raise ValueError(f"{where}: audit must be a text such as 'held' or None, got "
                         f"{audit!r}")
    radius = _opt_float(d.get("radius"), f"{where}: radius")
    if radius is not None and radius <= 0:
        raise ValueError(f"{where}: the drawing radius must be > 0, got {radius}")
    coords = _coords(d.get("coords"), where)
    return StateRow(
        role=role,
        shape=None if shape is None else str(shape),
        multiplicity=_opt_int(d.get("multiplicity"), f"{where}: multiplicity"),
        structure=structure,
        epsilon=eps,
        eps_mean=_opt_float(d.get("eps_mean"), f"{where}: eps_mean"),
        count=_opt_int(d.get("count"), f"{where}: count"),
        converged=None if conv is None else bool(conv),
        min_segment_distance=_opt_float(d.get("min_segment_distance"),
                                        f"{where}: min_segment_distance"),
        coords=coords,
        closed=bool(d.get("closed", True)),
        width=width,
        radius=radius,
        zones=_zones(d.get("zones"), coords, where),
        audit=audit,
    )


def parse_knots(knots: Sequence[Mapping]) -> list[KnotRow]:
    """The knots of the input schema (module docstring), checked, as :class:`KnotRow`;
    ValueError names the first field that is wrong."""
    if isinstance(knots, Mapping) or not isinstance(knots, Sequence):
        raise ValueError("knots must be a list of dicts, one per knot")
    out: list[KnotRow] = []
    names: set[str] = set()
    slugs: set[str] = set()
    model_slugs: dict[str, str] = {}
    for k, d in enumerate(knots):
        if not isinstance(d, Mapping):
            raise ValueError(f"knot {k}: expected a dict, got {type(d).__name__}")
        name = d.get("name")
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"knot {k}: 'name' must be a non-empty string, got {name!r}")
        name = name.strip()
        if name in names:
            raise ValueError(f"knot {name!r} appears twice")
        names.add(name)
        slug = base = _slug(name)
        j = 2
        while slug.lower() in slugs:
            slug = f"{base}-{j}"
            j += 1
        slugs.add(slug.lower())
        n = _opt_int(d.get("n"), f"knot {name}: n")
        i = _opt_int(d.get("i"), f"knot {name}: i")
        b = d.get("bounds")
        if b is None:
            cb = closed_bounds(n, i)
            lower, upper, who, exact = cb.lower, cb.upper, cb.attained_by, cb.exact
        elif isinstance(b, Mapping):
            lower = _opt_float(b.get("lower"), f"knot {name}: bounds.lower")
            upper = _opt_float(b.get("upper"), f"knot {name}: bounds.upper")
            who = b.get("attained_by")
            exact = bool(b.get("exact", lower is not None and lower == upper))
        else:
            raise ValueError(f"knot {name}: bounds must be a dict with 'lower' and 'upper'")
        fams = d.get("families") or []
        if isinstance(fams, str):
            fams = [fams]
        knot = KnotRow(name=name, slug=slug,
                       crossing_number=_opt_int(d.get("crossing_number"),
                                                f"knot {name}: crossing_number"),
                       n=n, i=i, lower=lower, upper=upper,
                       attained_by=None if who is None else str(who), exact=exact,
                       families=[str(f) for f in fams],
                       note=None if d.get("note") is None else str(d["note"]))
        knot.thin = _thin(d.get("thin"), f"knot {name}: thin")
        models = d.get("models") or {}
        if not isinstance(models, Mapping):
            raise ValueError(f"knot {name}: models must be a dict of model name -> results")
        for mname, m in models.items():
            mname = str(mname)
            where = f"knot {name}, model {mname}"
            if not isinstance(m, Mapping):
                raise ValueError(f"{where}: expected a dict with 'ground' and 'metastable'")
            mslug = re.sub(r"[^a-z0-9]+", "-", mname.lower()).strip("-") or "model"
            if model_slugs.setdefault(mslug, mname) != mname:
                raise ValueError(f"model names {model_slugs[mslug]!r} and {mname!r} are too "
                                 "alike (they differ only in case or punctuation)")
            mw = m.get("width")
            mw = None if mw is None else format_width(mw)
            ground = m.get("ground")
            meta = m.get("metastable") or []
            if isinstance(meta, Mapping):
                raise ValueError(f"{where}: metastable must be a list of states")
            knot.models[mname] = ModelRow(
                name=mname, slug=mslug,
                ground=None if ground is None else _state(ground, "ground", mw,
                                                          f"{where}, ground"),
                metastable=[_state(s, f"metastable {j + 1}", mw,
                                   f"{where}, metastable {j + 1}")
                            for j, s in enumerate(meta)],
                replicas=_opt_int(m.get("replicas"), f"{where}: replicas"),
                width=mw)
        out.append(knot)
    return out


def _thin(t: Any, where: str) -> dict | None:
    """A knot's ``thin`` entry, checked (the schema above); None when absent."""
    if t is None:
        return None
    if not isinstance(t, Mapping):
        raise ValueError(f"{where}: expected a dict with 'w_over_L' and 'states'")
    wl = _opt_float(t.get("w_over_L"), f"{where}.w_over_L")
    if wl is None or not wl > 0:
        raise ValueError(f"{where}: w_over_L (the census's width) must be a number > 0")
    states = t.get("states")
    if not isinstance(states, Sequence) or isinstance(states, str):
        raise ValueError(f"{where}: states must be a list")
    out_states = []
    for j, s in enumerate(states):
        w = f"{where}, state {j}"
        if not isinstance(s, Mapping) or "name" not in s or "epsilon" not in s:
            raise ValueError(f"{w}: expected a dict with 'name' and 'epsilon'")
        pts = []
        for p in s.get("points") or []:
            pw = _opt_float(p.get("w_over_L"), f"{w}: points.w_over_L")
            pe = _opt_float(p.get("epsilon"), f"{w}: points.epsilon")
            if pw is None or pe is None:
                raise ValueError(f"{w}: every point needs w_over_L and epsilon")
            pts.append({"w_over_L": pw, "epsilon": pe, "in_fit": bool(p.get("in_fit", True))})
        out_states.append({
            "name": str(s["name"]), "epsilon": _opt_float(s["epsilon"], f"{w}: epsilon"),
            "epsilon_thin": _opt_float(s.get("epsilon_thin"), f"{w}: epsilon_thin"),
            "error": _opt_float(s.get("error"), f"{w}: error"),
            "structure_epsilon": _opt_float(s.get("structure_epsilon"),
                                            f"{w}: structure_epsilon"),
            "structure_name": None if s.get("structure_name") is None
            else str(s["structure_name"]),
            "agree": None if s.get("agree") is None else bool(s["agree"]),
            "event": None if s.get("event") is None else str(s["event"]),
            "points": pts})
    g = t.get("ground")
    if g is not None and not (isinstance(g, int) and 0 <= g < len(out_states)):
        raise ValueError(f"{where}: ground must be an index into states")
    chain = t.get("chain")
    if chain is not None:
        x = np.asarray(chain.get("coords"), dtype=float)
        if x.ndim != 2 or x.shape[1] != 3 or len(x) < 3:
            raise ValueError(f"{where}: chain.coords must be an (N ≥ 3, 3) array")
        chain = {"coords": x, "w_over_L": _opt_float(chain.get("w_over_L"),
                                                      f"{where}: chain.w_over_L")}
    return {"w_over_L": wl, "budget": t.get("budget"), "seed": t.get("seed"), "ground": g,
            "crossing": _opt_float(t.get("crossing"), f"{where}: crossing"),
            "states": out_states, "chain": chain}


def model_names(knots: list[KnotRow]) -> list[str]:
    """The names of the models of the knots, in the order first met."""
    seen: list[str] = []
    for k in knots:
        for m in k.models:
            if m not in seen:
                seen.append(m)
    return seen


def natural_key(name: str) -> str:
    """A sort key in which the numbers of a name compare as numbers (3_1 < 10_1)."""
    return re.sub(r"\d+", lambda m: m.group().zfill(8), name.lower())


def family_statistics(knots: Sequence[Mapping], *, model: str | None = None,
                      max_crossings: Sequence[int] = (7, 9)) -> dict:
    """Counts of the ground-state shapes of the knots, in the ``families`` schema.

    Parameters
    ----------
    knots : list of dict
        Knots in the input schema (this module's docstring).
    model : str, optional
        The model whose ground states are counted (default: the first model met).
    max_crossings : sequence of int
        One column per value ``c``: the knots with crossing number ``n_c < c``; a last column
        counts all knots. A column that would hold the same knots as the next is left out.

    Returns
    -------
    dict
        ``{"title", "model", "groups": [{"label", "total", "counts"}], "note"}``; ``total`` is
        the number of knots of the group with a ground state in ``model``.
    """
    ks = parse_knots(knots)
    names = model_names(ks)
    if model is None:
        model = names[0] if names else None
    groups: list[dict] = []
    limits = sorted({int(c) for c in max_crossings})
    cands = [(f"n_c < {c}", c) for c in limits] + [("all knots", None)]
    for label, c in cands:
        counts: dict[str, int] = {}
        members = []
        for k in ks:
            if c is not None and (k.crossing_number is None or k.crossing_number >= c):
                continue
            m = k.models.get(model) if model else None
            if m is None or m.ground is None:
                continue
            members.append(k.name)
            lab = m.ground.shape_label or "unclassified"
            counts[lab] = counts.get(lab, 0) + 1
        groups.append({"label": label, "total": len(members), "counts": counts,
                       "_members": members})
    # drop a column identical to the next one (e.g. every knot has n_c < 9)
    kept = [g for g, nxt in zip(groups, [*groups[1:], None], strict=True)
            if nxt is None or g["_members"] != nxt["_members"]]
    for g in kept:
        g.pop("_members")
    return {"title": "Ground-state shapes", "model": model, "groups": kept,
            "note": "Counted from the ground states of the table"
                    + (f" (model {model})." if model else ".")}

