"""The atlas: static HTML pages of the ground and metastable states of many knots.

:func:`write_atlas` writes, into one folder,

* ``index.html`` — a sortable, filterable table with one row per knot (name, crossing number,
  bridge number ``n``, braid index ``i``, the bounds, the ground shape, its ``ε`` and the width
  it was computed at, convergence, the metastable states with their counts, the minimum segment
  distance, a thumbnail of the ground state, a link to the knot's page), ``ε`` against ``n²``
  for all knots with the bounds of Gallotti & Pierre-Louis (PRE 2007), and the family
  statistics;
* ``knots/<name>.html`` — one page per knot: its data and an interactive 3D view of each state
  (ground and metastable), drawn as a tube;
* ``plotly.min.js`` — plotly.js, written once and loaded by every page with a relative
  ``<script src>``; ``thumbs/<name>-<model>.png`` — the thumbnails; ``atlas.json`` — the table's
  data (no coordinates) for scripts.

Every page opens from disk (``file://``) with no server and no network: the page scripts are
inline, plotly.js is the local copy, the pictures are local files.

The atlas is given plain data, described below; it never runs a simulation.

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

import hashlib
import html
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np

from stiffknots._json import to_plain
from stiffknots._version import __version__
from stiffknots.report.text import segment_distance_text
from stiffknots.theory import closed_bounds

__all__ = [
    "DEFAULT_TITLE",
    "format_width",
    "family_statistics",
    "state_mesh",
    "write_atlas",
]

DEFAULT_TITLE = "Atlas of stiff knots"

#: Colours along the arclength of a closed tube: the cyclic map of
#: :mod:`stiffknots.report.render` (no seam at bead 0), as a plotly colour scale.
_CYCLIC = ["#2f6db3", "#3aa3a0", "#e0b43a", "#d9623b", "#8e4fa3", "#2f6db3"]
_COLORSCALE = [[k / (len(_CYCLIC) - 1), c] for k, c in enumerate(_CYCLIC)]

#: plotly marker symbols for the matplotlib markers of :func:`figures.shape_style`.
_SYMBOLS = {"o": "circle", "s": "square", "^": "triangle-up", "v": "triangle-down",
            "D": "diamond", "P": "cross", "X": "x", "h": "hexagon", "*": "star"}

_THUMB_PX = 144  # thumbnail size in pixels (shown at half size: sharp on high-dpi screens)
_MESH_SIDES = 10  # vertices per ring of the 3D tube
_MAX_LABELLED = 16  # the ε–n² points carry their knot's name up to this many knots
_SPREAD = 0.8  # points of one n are spread over n² ± _SPREAD (at 0.2 apart while they fit)
_ZOOM = 1.8  # largest aspect ratio of the 3D scene (plotly's orthographic zoom)


# ----------------------------------------------------------------------------------------------
# input normalisation
# ----------------------------------------------------------------------------------------------


@dataclass
class _State:
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

    @property
    def shape_label(self) -> str | None:
        if self.shape is None:
            return None
        return f"{self.shape}({self.multiplicity})" if self.multiplicity else self.shape


@dataclass
class _Model:
    name: str
    slug: str
    ground: _State | None
    metastable: list[_State]
    replicas: int | None
    width: str | None

    @property
    def states(self) -> list[_State]:
        return ([self.ground] if self.ground is not None else []) + self.metastable


@dataclass
class _Knot:
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
    models: dict[str, _Model] = field(default_factory=dict)


def format_width(width: Any) -> str:
    """The width a Monte Carlo value was computed at, as one line of text.

    Parameters
    ----------
    width : str or mapping
        A description (``"bead rule d = 1/√2, N = 150"``), or a mapping of named values
        (``{"w/L": 0.01}`` → ``"w/L = 0.01"``).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        For a bare number or anything else that does not say what the width is.
    """
    if isinstance(width, str) and width.strip():
        return width.strip()
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


#: the kinds of contact zone a bead can lie in (``zones`` of a state; codes 0 … 3), and the
#: colours the 3D view gives them
ZONE_KINDS = ("free strand", "line-braid", "point-braid", "multiple point")
_ZONE_COLOURS = ("#c9c9c9", "#1f77b4", "#ff7f0e", "#d62728")


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


def _state(d: Any, role: str, model_width: str | None, where: str) -> _State:
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
    radius = _opt_float(d.get("radius"), f"{where}: radius")
    if radius is not None and radius <= 0:
        raise ValueError(f"{where}: the drawing radius must be > 0, got {radius}")
    coords = _coords(d.get("coords"), where)
    return _State(
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
    )


def _knots(knots: Sequence[Mapping]) -> list[_Knot]:
    if isinstance(knots, Mapping) or not isinstance(knots, Sequence):
        raise ValueError("knots must be a list of dicts, one per knot")
    out: list[_Knot] = []
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
        knot = _Knot(name=name, slug=slug,
                     crossing_number=_opt_int(d.get("crossing_number"),
                                              f"knot {name}: crossing_number"),
                     n=n, i=i, lower=lower, upper=upper,
                     attained_by=None if who is None else str(who), exact=exact,
                     families=[str(f) for f in fams],
                     note=None if d.get("note") is None else str(d["note"]))
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
            knot.models[mname] = _Model(
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


def _model_names(knots: list[_Knot]) -> list[str]:
    seen: list[str] = []
    for k in knots:
        for m in k.models:
            if m not in seen:
                seen.append(m)
    return seen


# ----------------------------------------------------------------------------------------------
# formatting helpers
# ----------------------------------------------------------------------------------------------


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _num(x: float | None, digits: int = 2) -> str:
    return "—" if x is None else f"{x:.{digits}f}"


def _natural(name: str) -> str:
    """A sort key in which the numbers of a name compare as numbers (3_1 < 10_1)."""
    return re.sub(r"\d+", lambda m: m.group().zfill(8), name.lower())


def _yes_no(v: bool | None) -> str:
    return "—" if v is None else ("yes" if v else "no")


def _json_script(obj: Any) -> str:
    """JSON for a ``<script>`` element (no ``</script>`` can close it early)."""
    s = json.dumps(to_plain(obj), ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    return s.replace("<", "\\u003c")  # "<" occurs only inside JSON strings


def _count_text(st: _State, replicas: int | None) -> str:
    if st.count is None:
        return "—"
    return f"{st.count} / {replicas}" if replicas else str(st.count)


# ----------------------------------------------------------------------------------------------
# pictures
# ----------------------------------------------------------------------------------------------


def _thumbnail_png(coords: np.ndarray, closed: bool, radius: float | None) -> bytes:
    """A small PNG of a chain drawn as a tube (matplotlib object API, Agg canvas)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from stiffknots.report.render import plot_tube

    size = _THUMB_PX / 100.0
    fig = Figure(figsize=(size, size))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d")
    plot_tube(coords, ax, closed=closed, radius=radius, n_sides=12)
    buf = BytesIO()
    fig.savefig(buf, format="png", dpi=100, facecolor="white")
    return buf.getvalue()


def state_mesh(coords, *, closed: bool = True, radius: float | None = None,
               n_sides: int = _MESH_SIDES, digits: int = 3) -> dict:
    """The tube of a chain as compact data for the 3D view of the knot pages.

    The chain is centred and turned (by a proper rotation, never a mirror) to its principal
    axes, as :func:`stiffknots.report.render.best_view` does for the still pictures, and the
    tube is :func:`stiffknots.report.render.tube_mesh`. The page's script joins the rings into
    triangles.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead coordinates, ``N >= 3``.
    closed : bool
        Join the last bead to the first.
    radius : float, optional
        Tube radius in bond units; default
        :data:`stiffknots.report.render.DEFAULT_RADIUS` (half the bead exclusion distance
        1/√2 of the paper's chain).
    n_sides : int
        Vertices per ring.
    digits : int
        Decimals kept of the vertex coordinates.

    Returns
    -------
    dict
        ``rings`` (N), ``sides`` (``n_sides``), ``closed``, ``v`` (the ``N * n_sides * 3``
        vertex coordinates, ring after ring), ``t`` (the arclength fraction of each ring, for
        the colour), ``eye`` (a camera position for the view of ``best_view``), ``range``
        (the extent of the tube along x, y, z) and ``aspect`` (the extents in proportion,
        equal scales on the three axes; their size sets the zoom of the orthographic view).
    """
    from stiffknots.report.render import DEFAULT_RADIUS, best_view, tube_mesh

    x = np.asarray(coords, dtype=float)
    x = x - x.mean(axis=0)
    rot, (elev, azim) = best_view(x)
    x = x @ rot
    mesh = tube_mesh(x, DEFAULT_RADIUS if radius is None else float(radius), closed=closed,
                     n_sides=n_sides)
    seg = np.linalg.norm(np.diff(np.vstack([x, x[:1]]) if closed else x, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])[: len(x)]
    total = float(arc[-1] + (seg[-1] if closed else 0.0)) or 1.0
    e, a = math.radians(elev), math.radians(azim)
    r = 1.25  # camera distance
    eye = {"x": r * math.cos(e) * math.cos(a), "y": r * math.cos(e) * math.sin(a),
           "z": r * math.sin(e)}
    pts = mesh.points
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    aspect = _ZOOM * span / span.max()  # plotly's orthographic view zooms by the aspect ratio
    return {"rings": int(mesh.vertices.shape[0]), "sides": int(n_sides), "closed": bool(closed),
            "v": np.round(pts, digits).ravel().tolist(),
            "t": np.round(arc / total, 4).tolist(), "eye": eye,
            "range": np.round(np.column_stack([lo, hi]), digits + 1).tolist(),
            "aspect": dict(zip("xyz", np.round(aspect, 4).tolist(), strict=True))}


# ----------------------------------------------------------------------------------------------
# statistics and the ε–n² figure
# ----------------------------------------------------------------------------------------------


def family_statistics(knots: Sequence[Mapping], *, model: str | None = None,
                      max_crossings: Sequence[int] = (7, 9)) -> dict:
    """Counts of the ground-state shapes of the knots, in the ``families`` schema.

    Parameters
    ----------
    knots : list of dict
        Knots in the input schema of :func:`write_atlas`.
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
    ks = _knots(knots)
    names = _model_names(ks)
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


def _bound_lines(knots: list[_Knot]) -> tuple[list[dict], float, float]:
    """Traces of the bounds for the ε–n² figure, the largest n² shown and the highest bound
    of the knots' (n, i)."""
    n_max = max([k.n for k in knots if k.n is not None], default=2)
    x_max = (n_max + 0.6) ** 2
    pbl_slope = closed_bounds(1, None).eps_pbl  # 2 pi^2 alpha^2
    eps0 = closed_bounds(1, None).lower  # 2 pi^2
    traces = [
        {"type": "scatter", "mode": "lines", "x": [0.0, x_max], "y": [0.0, eps0 * x_max],
         "name": "lower bound 2π²n²", "line": {"color": "#111", "width": 1.6},
         "hoverinfo": "name"},
        {"type": "scatter", "mode": "lines", "x": [0.0, x_max], "y": [0.0, pbl_slope * x_max],
         "name": "upper bound ε_PBL = 2π²α²n²", "line": {"color": "#111", "width": 1.2,
                                                          "dash": "dash"},
         "hoverinfo": "name"},
    ]
    pairs = sorted({(k.n, k.i) for k in knots if k.n is not None},
                   key=lambda t: (t[0], -1 if t[1] is None else t[1]))
    bx, by, btext, cx, cy, ctext = [], [], [], [], [], []
    per_n: dict[int, int] = {}
    top = eps0 * x_max
    for n, i in pairs:
        b = closed_bounds(n, i)
        j = per_n.get(n, 0)
        per_n[n] = j + 1
        x = max(0.02, n * n - _SPREAD - 0.15 - 0.12 * j)
        txt = (f"n = {n}, i = {i if i is not None else '?'}: "
               f"{_num(b.lower)} ≤ ε* ≤ {_num(b.upper)} (thin limit)")
        top = max(top, b.upper if b.upper is not None else 0.0)
        bx += [x, x, None]
        by += [b.lower, b.upper, None]
        btext += [txt, txt, None]
        if b.eps_cb is not None:
            cx.append(x)
            cy.append(b.eps_cb)
            ctext.append(f"circular braid CB({i}): 2π²i² = {_num(b.eps_cb)}")
    traces.append({"type": "scatter", "mode": "lines", "x": bx, "y": by, "text": btext,
                   "name": "bounds for (n, i)", "hoverinfo": "text",
                   "line": {"color": "rgba(90,90,90,0.55)", "width": 5}})
    if cx:
        traces.append({"type": "scatter", "mode": "markers", "x": cx, "y": cy, "text": ctext,
                       "name": "circular braid 2π²i²", "hoverinfo": "text",
                       "marker": {"symbol": "line-ew-open", "size": 16, "color": "#333",
                                  "line": {"color": "#333", "width": 2.5}}})
    return traces, x_max, top


def _eps_figure(knots: list[_Knot], models: list[tuple[str, str]],
                default_model: str | None) -> dict:
    """The plotly figure of ε against n² (a plain dict)."""
    from stiffknots.report.figures import shape_style

    traces, x_max, y_top = _bound_lines(knots)  # the PBL line may leave through the top
    extra: dict = {}
    labels = len(knots) <= _MAX_LABELLED
    for mname, mslug in models:
        groups: dict[int, list[_Knot]] = {}
        for k in knots:
            m = k.models.get(mname)
            if k.n is None or m is None or m.ground is None or m.ground.epsilon is None:
                continue
            groups.setdefault(k.n, []).append(k)
        xs: dict[str, list] = {}
        for n, ks in groups.items():
            ks = sorted(ks, key=lambda k: _natural(k.name))
            half = min(_SPREAD, 0.1 * (len(ks) - 1))
            offs = np.linspace(-half, half, len(ks))
            for j, (k, dx) in enumerate(zip(ks, offs, strict=True)):
                st = k.models[mname].ground
                lab = st.shape_label or "unclassified"
                # neighbours' names alternate above and below their points
                xs.setdefault(lab, []).append((k, st, n * n + float(dx),
                                               "top center" if j % 2 == 0 else "bottom center"))
        for lab, items in xs.items():
            marker, colour = shape_style(None if lab == "unclassified" else
                                         items[0][1].shape, extra)
            traces.append({
                # plotly reads its texts as a little HTML: every given string is escaped
                "type": "scatter", "mode": "markers+text" if labels else "markers",
                "name": _e(lab), "text": [_e(k.name) for k, _, _, _ in items],
                "textposition": [p for _, _, _, p in items],
                "textfont": {"size": 10, "color": "#555"},
                "legendgroup": f"{mname}:{lab}",
                "x": [x for _, _, x, _ in items], "y": [st.epsilon for _, st, _, _ in items],
                "customdata": [[_e(k.name), k.n, "?" if k.i is None else k.i,
                                _num(st.epsilon), _e(st.width), f"knots/{k.slug}.html"]
                               for k, st, _, _ in items],
                "hovertemplate": ("<b>%{customdata[0]}</b> (n = %{customdata[1]}, "
                                  "i = %{customdata[2]})<br>" + _e(lab)
                                  + ": ε = %{customdata[3]}<br>at %{customdata[4]}"
                                  "<extra>" + _e(mname) + "</extra>"),
                "marker": {"symbol": _SYMBOLS.get(marker, "circle"), "size": 10,
                           "color": colour, "line": {"color": "#222", "width": 0.8}},
                "meta": {"model": mslug},
                "visible": mname == default_model,
            })
            y_top = max(y_top, max(st.epsilon for _, st, _, _ in items))
    n_max = int(round(math.sqrt(x_max) - 0.6))
    layout = {
        "xaxis": {"title": {"text": "n² (bridge number squared)"}, "range": [0, x_max],
                  "tickvals": [k * k for k in range(n_max + 1)], "zeroline": False,
                  "gridcolor": "#eee"},
        "yaxis": {"title": {"text": "ε = E L / C"}, "range": [0, 1.1 * y_top],
                  "zeroline": False, "gridcolor": "#eee"},
        "margin": {"l": 60, "r": 20, "t": 20, "b": 50},
        "height": 460, "hovermode": "closest", "plot_bgcolor": "#fff",
        "paper_bgcolor": "#fff",
    }
    return {"data": traces, "layout": layout}


# ----------------------------------------------------------------------------------------------
# page parts
# ----------------------------------------------------------------------------------------------

_CSS = """
:root { --ink: #1f2328; --muted: #59636e; --line: #d1d9e0; --head: #f0f3f6; --accent: #2f6db3; }
* { box-sizing: border-box; }
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; color: var(--ink);
       background: #fff; margin: 0; line-height: 1.45; }
main { max-width: 90rem; margin: 0 auto; padding: 1.2rem 1.6rem 3rem; }
.table-wrap { overflow-x: auto; }
h1 { margin: 0.3em 0 0.2em; font-size: 1.7rem; }
h2 { margin: 1.6em 0 0.5em; font-size: 1.25rem; border-bottom: 1px solid var(--line);
     padding-bottom: 0.2em; }
a { color: var(--accent); }
.lede { color: var(--muted); margin: 0 0 0.6em; }
.caveat { background: #fff8e6; border-left: 4px solid #e0b43a; padding: 0.45em 0.8em;
          margin: 0.8em 0; font-size: 0.92em; }
.controls { display: flex; flex-wrap: wrap; gap: 0.6em 1.4em; align-items: center;
            margin: 0.6em 0; }
.controls input, .controls select { font: inherit; padding: 0.25em 0.45em;
                                    border: 1px solid var(--line); border-radius: 4px; }
.controls input { width: 16em; }
#count { color: var(--muted); font-size: 0.92em; }
table { border-collapse: collapse; font-size: 0.9em; }
th, td { border-bottom: 1px solid var(--line); padding: 0.3em 0.55em; text-align: left;
         vertical-align: middle; }
thead th { background: var(--head); position: sticky; top: 0; z-index: 1; white-space: nowrap;
           border-bottom: 2px solid var(--line); }
th button { font: inherit; font-weight: 600; background: none; border: 0; padding: 0;
            cursor: pointer; color: inherit; }
th button::after { content: " ↕"; color: #aab; font-weight: 400; }
th[aria-sort="ascending"] button::after { content: " ▲"; color: var(--accent); }
th[aria-sort="descending"] button::after { content: " ▼"; color: var(--accent); }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
td.width { color: var(--muted); font-size: 0.85em; min-width: 9.5em; max-width: 14em; }
tbody tr:hover td { background: #f6f8fa; }
td.thumb { padding: 2px 4px; }
td.thumb img { width: 72px; height: 72px; display: block; }
.m { display: none; }
.visually-hidden { position: absolute; width: 1px; height: 1px; overflow: hidden;
                   clip: rect(0 0 0 0); white-space: nowrap; }
#structures td.num { white-space: nowrap; }
.shape { display: inline-block; min-width: 1.2em; padding: 0 0.35em; border-radius: 3px;
         color: #fff; font-weight: 600; font-size: 0.9em; }
.meta-list { color: var(--muted); font-size: 0.9em; }
.plot { width: 100%; min-height: 460px; }
.figure-note { color: var(--muted); font-size: 0.88em; }
dl.facts { display: grid; grid-template-columns: max-content 1fr; gap: 0.2em 1.2em;
           margin: 0.6em 0; }
dl.facts dt { color: var(--muted); }
dl.facts dd { margin: 0; }
nav.top { font-size: 0.92em; margin-bottom: 0.4em; color: var(--muted); }
tr.state-row { cursor: pointer; }
tr.state-row.active td { background: #e8f0fb; }
.viewer { display: grid; grid-template-columns: minmax(0, 1fr); gap: 0.4em; }
.view-frame { border: 1px solid var(--line); border-radius: 6px; overflow: hidden; }
#view3d { width: 100%; height: 560px; }
.view-link { color: var(--accent); text-decoration: underline; }
.view-controls { display: flex; gap: 1em; align-items: center; flex-wrap: wrap; }
.view-controls select { font: inherit; padding: 0.2em 0.4em; }
.zone-legend { display: flex; gap: 1.2em; flex-wrap: wrap; margin: 0.4em 0; }
.zone-legend[hidden], .zone-legend [hidden] { display: none; }
.zone-legend i { display: inline-block; width: 1.6em; height: 0.8em; margin-right: 0.35em;
  border-radius: 0.2em; vertical-align: middle; }
#view-caption { color: var(--muted); font-size: 0.92em; }
footer { margin-top: 2.5em; color: var(--muted); font-size: 0.85em; }
"""


def _model_css(models: list[_Model] | list[tuple[str, str]]) -> str:
    slugs = [m[1] if isinstance(m, tuple) else m.slug for m in models]
    return "\n".join(f'body[data-model="{s}"] .m-{s} {{ display: inline; }}' for s in slugs)


def _head(title: str, prefix: str, extra_css: str) -> str:
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        f"<title>{_e(title)}</title>\n<link rel=\"icon\" href=\"data:,\">\n"
        f"<style>{_CSS}\n{extra_css}</style>\n"
        f"<script src=\"{prefix}plotly.min.js\"></script>\n</head>\n"
    )


def _shape_badge(label: str | None, shape: str | None, extra: dict,
                 structure: str | None = None) -> str:
    """The shape class as a coloured badge; its contact structure (§V B) as its tooltip."""
    if label is None:
        return "—"
    from stiffknots.report.figures import shape_style

    colour = shape_style(shape, extra)[1]
    tip = f' title="{_e(structure)}"' if structure else ""
    return f'<span class="shape" style="background:{_e(colour)}"{tip}>{_e(label)}</span>'


def _per_model_cell(knot: _Knot, models: list[tuple[str, str]], render, sort_value,
                    cls: str = "") -> str:
    """A table cell with one span per model (CSS shows the active model's)."""
    attrs, spans = [], []
    for mname, mslug in models:
        m = knot.models.get(mname)
        v = sort_value(m) if m is not None else None
        if v is not None:
            attrs.append(f' data-v-{mslug}="{_e(v)}"')
        body = render(m) if m is not None else "—"
        spans.append(f'<span class="m m-{mslug}">{body}</span>')
    c = f' class="{cls}"' if cls else ""
    return f"<td{c}{''.join(attrs)}>{''.join(spans)}</td>"


_INDEX_JS = r"""
(function () {
  "use strict";
  var table = document.getElementById("knots");
  var tbody = table.tBodies[0];
  var rows = Array.prototype.slice.call(tbody.rows);
  rows.forEach(function (r, k) { r.setAttribute("data-order", k); });
  var filterBox = document.getElementById("filter");
  var shapeSel = document.getElementById("shape-filter");
  var modelSel = document.getElementById("model");
  var countEl = document.getElementById("count");
  var heads = Array.prototype.slice.call(table.tHead.rows[0].cells);
  var sortCol = -1, sortDir = 1;

  function model() { return document.body.getAttribute("data-model"); }
  function key(td) {
    var v = td.getAttribute("data-v-" + model());
    if (v === null) v = td.getAttribute("data-v");
    return v === null || v === "" ? null : v;
  }
  function compare(a, b) {
    var type = heads[sortCol].getAttribute("data-type");
    var ka = key(a.cells[sortCol]), kb = key(b.cells[sortCol]);
    if (ka === null || kb === null) {  // missing values last, in both directions
      if (ka === kb) return a.getAttribute("data-order") - b.getAttribute("data-order");
      return ka === null ? 1 : -1;
    }
    var d = type === "num" ? parseFloat(ka) - parseFloat(kb) : ka.localeCompare(kb);
    if (d === 0) return a.getAttribute("data-order") - b.getAttribute("data-order");
    return sortDir * d;
  }
  function sortBy(col, dir) {
    sortCol = col; sortDir = dir;
    heads.forEach(function (th, k) {
      if (th.hasAttribute("aria-sort"))
        th.setAttribute("aria-sort", k === col ? (dir > 0 ? "ascending" : "descending") : "none");
    });
    rows.slice().sort(compare).forEach(function (r) { tbody.appendChild(r); });
  }
  heads.forEach(function (th, k) {
    var b = th.querySelector("button");
    if (!b) return;
    b.addEventListener("click", function () {
      sortBy(k, sortCol === k ? -sortDir : 1);
    });
  });
  function applyFilter() {
    var q = filterBox.value.trim().toLowerCase();
    var s = shapeSel ? shapeSel.value : "";
    var m = model(), shown = 0;
    rows.forEach(function (r) {
      var text = r.getAttribute("data-search-" + m) || r.getAttribute("data-search") || "";
      var shape = r.getAttribute("data-shape-" + m) || "";
      var ok = (!q || text.indexOf(q) >= 0) && (!s || shape === s);
      r.hidden = !ok;
      if (ok) shown++;
    });
    countEl.textContent = shown + " of " + rows.length + " knots shown";
  }
  filterBox.addEventListener("input", applyFilter);
  if (shapeSel) shapeSel.addEventListener("change", applyFilter);

  var plot = document.getElementById("eps-plot");
  var FIG = JSON.parse(document.getElementById("eps-data").textContent);
  var CONFIG = {displaylogo: false, responsive: true,
                modeBarButtonsToRemove: ["sendDataToCloud", "lasso2d", "select2d"]};
  function visibility() {
    return FIG.data.map(function (t) {
      return !(t.meta && t.meta.model) || t.meta.model === model();
    });
  }
  if (window.Plotly && plot) {
    Plotly.newPlot(plot, FIG.data, FIG.layout, CONFIG);
    plot.on("plotly_click", function (ev) {
      var p = ev.points && ev.points[0];
      if (p && p.customdata && p.customdata[5]) window.location.href = p.customdata[5];
    });
  }
  if (modelSel) modelSel.addEventListener("change", function () {
    document.body.setAttribute("data-model", modelSel.value);
    if (sortCol >= 0) sortBy(sortCol, sortDir);
    applyFilter();
    if (window.Plotly && plot) Plotly.restyle(plot, {visible: visibility()});
  });
  applyFilter();
})();
"""


_KNOT_JS = r"""
(function () {
  "use strict";
  var STATES = JSON.parse(document.getElementById("states-data").textContent);
  var COLORSCALE = JSON.parse(document.getElementById("colorscale-data").textContent);
  var ZONE_COLOURS = JSON.parse(document.getElementById("zone-colours-data").textContent);
  var colourSel = document.getElementById("colour-select");
  var legend = document.getElementById("zone-legend");
  var missing = document.getElementById("zone-missing");
  var current = 0;
  var div = document.getElementById("view3d");
  var sel = document.getElementById("state-select");
  var caption = document.getElementById("view-caption");
  var CONFIG = {displaylogo: false, responsive: true};

  function meshTrace(st) {
    // a closed tube gets a copy of its first ring at the end, coloured 1 instead of 0, so that
    // the cyclic colour does not run back through the whole scale on the last band
    var n = st.rings, s = st.sides, v = st.v;
    var m = st.closed ? n + 1 : n, N = m * s;
    var x = new Array(N), y = new Array(N), z = new Array(N), c = new Array(N);
    for (var p = 0; p < N; p++) {
      var q = p % (n * s), r = Math.floor(p / s);
      x[p] = v[3 * q]; y[p] = v[3 * q + 1]; z[p] = v[3 * q + 2];
      c[p] = r < n ? st.t[r] : 1.0;
    }
    // by contact structure: one flat colour a face (no blend through the other kinds'
    // colours), the larger code of the two beads of its bond, so a one-bead zone shows
    var byZone = colourSel && colourSel.value === "zones" && st.zones;
    var I = [], J = [], K = [], F = [];
    for (var k = 0; k < m - 1; k++) {
      var fc = byZone ? ZONE_COLOURS[Math.max(st.zones[k % n], st.zones[(k + 1) % n])] : null;
      for (var j = 0; j < s; j++) {
        var j1 = (j + 1) % s;
        var a = k * s + j, b = k * s + j1, cc = (k + 1) * s + j1, d = (k + 1) * s + j;
        I.push(a, a); J.push(cc, d); K.push(b, cc);
        if (byZone) F.push(fc, fc);
      }
    }
    if (!st.closed) {  // flat end caps as triangle fans
      [0, n - 1].forEach(function (r) {
        for (var j = 1; j < s - 1; j++) {
          I.push(r * s); J.push(r * s + j); K.push(r * s + j + 1);
          if (byZone) F.push(ZONE_COLOURS[st.zones[r]]);
        }
      });
    }
    var colour = byZone ? {facecolor: F}
      : {intensity: c, colorscale: COLORSCALE, cmin: 0, cmax: 1};
    return Object.assign({type: "mesh3d", x: x, y: y, z: z, i: I, j: J, k: K,
            showscale: false, hoverinfo: "skip",
            flatshading: false,
            lighting: {ambient: 0.5, diffuse: 0.7, specular: 0.15, roughness: 0.5,
                       fresnel: 0.1},
            // plotly's mesh3d lights the side facing away from lightposition: put the light
            // opposite the camera, so that the side seen first is lit
            lightposition: {x: -1e5 * st.eye.x, y: -1e5 * st.eye.y, z: -1e5 * st.eye.z}},
            colour);
  }
  function layout(st) {
    function axis(k) { return {visible: false, showspikes: false, range: st.range[k]}; }
    return {margin: {l: 0, r: 0, t: 0, b: 0}, paper_bgcolor: "#fff", showlegend: false,
            scene: {aspectmode: "manual", aspectratio: st.aspect,
                    xaxis: axis(0), yaxis: axis(1), zaxis: axis(2),
                    bgcolor: "#fff",
                    camera: {eye: st.eye, up: {x: 0, y: 0, z: 1}, center: {x: 0, y: 0, z: 0},
                             projection: {type: "orthographic"}}}};
  }
  function show(k) {
    var st = STATES[k];
    if (!st) return;
    current = k;
    // a new plot, not Plotly.react: react keeps a mesh's old colouring when it switches
    // between intensity and face colours
    Plotly.newPlot(div, [meshTrace(st)], layout(st), CONFIG);
    if (legend) {
      var on = !!(colourSel && colourSel.value === "zones");
      legend.hidden = !on;
      missing.hidden = !on || !!st.zones;
    }
    sel.value = String(k);
    caption.textContent = st.caption;
    Array.prototype.forEach.call(document.querySelectorAll("tr.state-row"), function (r) {
      r.classList.toggle("active", r.getAttribute("data-state") === String(k));
    });
  }
  if (sel) sel.addEventListener("change", function () { show(parseInt(sel.value, 10)); });
  if (colourSel) colourSel.addEventListener("change", function () { show(current); });
  Array.prototype.forEach.call(document.querySelectorAll("tr.state-row"), function (r) {
    r.addEventListener("click", function () {
      var k = r.getAttribute("data-state");
      if (k !== null && k !== "") { show(parseInt(k, 10)); div.scrollIntoView({block: "nearest"}); }
    });
  });
  if (window.Plotly && div && STATES.length) show(0);
})();
"""


def _index_page(knots: list[_Knot], models: list[tuple[str, str]], default: str | None,
                families: dict | None, title: str, meta: dict, thumbs: dict,
                fig: dict) -> str:
    extra: dict = {}
    body_model = dict(models).get(default, "") if default else ""
    parts = [_head(title, "", _model_css(models)),
             f'<body data-model="{_e(body_model)}">\n<main>\n<h1>{_e(title)}</h1>\n']
    n_with = sum(1 for k in knots if any(m.ground for m in k.models.values()))
    parts.append(f'<p class="lede">{len(knots)} knots, {n_with} with a computed ground state'
                 + (f"; models: {', '.join(_e(m) for m, _ in models)}" if models else "")
                 + ". Click a knot for its states in 3D.</p>\n")
    parts.append(
        '<p class="caveat">Every ε = E L / C below is a Monte Carlo value at the finite width '
        "shown beside it (bead rule and N, or w/L), not the thin-limit ε* of Gallotti &amp; "
        "Pierre-Louis: ε*<sub>w</sub> rises with w, so ε* lies below every finite-width value. "
        "The bounds 2π²n² ≤ ε* ≤ 2π² min(α²n², i²) are thin-limit quantities.</p>\n")

    # controls
    shapes = sorted({m.ground.shape_label for k in knots for m in k.models.values()
                     if m.ground is not None and m.ground.shape_label})
    parts.append('<h2 id="table-title">Knots</h2>\n<div class="controls">\n'
                 '<label>Filter <input id="filter" type="search" '
                 'placeholder="name, shape or family" autocomplete="off"></label>\n'
                 '<label>Ground shape <select id="shape-filter"><option value="">all</option>'
                 + "".join(f'<option value="{_e(s)}">{_e(s)}</option>' for s in shapes)
                 + "</select></label>\n")
    if models:
        hidden = "" if len(models) > 1 else ' style="display:none"'
        parts.append(f'<label{hidden}>Model <select id="model">'
                     + "".join(f'<option value="{_e(s)}"{" selected" if m == default else ""}>'
                               f"{_e(m)}</option>" for m, s in models)
                     + "</select></label>\n")
    parts.append('<span id="count"></span>\n</div>\n')

    # table
    cols = [("", None, "", ""), ("knot", "text", "", "knot name"),
            ("n<sub>c</sub>", "num", "num", "crossing number"),
            ("n", "num", "num", "bridge number"), ("i", "num", "num", "braid index"),
            ("bounds (thin limit)", "num", "num",
             "2π²n² ≤ ε* ≤ 2π² min(α²n², i²): bounds on the thin-limit ground-state energy"),
            ("ground shape", "text", "", "shape class of the lowest state found"),
            ("ε (ground)", "num", "num",
             "ε = E L / C of the lowest state found, at the width in the next column"),
            ("width", "text", "", "the finite width the ε was computed at"),
            ("converged", "text", "",
             "whether two independent searches reached the lowest ε found (within 0.1 %): a "
             "statement about the searches, not proof that no lower state exists — under the "
             "bead rule at the default budget 9 of 21 verdicts checked against a deeper "
             "search lay above its lowest (bench/RESULTS.md, 2026-12-05)"),
            ("metastable", "num", "", "the other states found: shape ×count (ε)"),
            ("d<sub>min</sub>", "num", "num",
             "minimum distance between non-adjacent segments of the ground state (the bead "
             "rule keeps beads, not segments, apart: two segments may close to the 1e-4 gap "
             "its no-passage guard keeps)"),
            ("families", "text", "", "shape families the knot belongs to")]
    head = []
    for label, typ, cls, tip in cols:
        c = f' class="{cls}"' if cls else ""
        if typ is None:
            head.append(f'<th{c}><span class="visually-hidden">picture</span></th>')
        else:
            head.append(f'<th{c} data-type="{typ}" aria-sort="none" title="{_e(tip)}">'
                        f'<button type="button">{label}</button></th>')
    parts.append('<div class="table-wrap"><table id="knots" class="atlas">\n<thead><tr>'
                 + "".join(head)
                 + "</tr></thead>\n<tbody>\n")
    for k in knots:
        href = f"knots/{_e(k.slug)}.html"
        attrs = [f'data-name="{_e(k.name)}"']
        for mname, mslug in models:
            m = k.models.get(mname)
            words = [k.name, *k.families]
            if m is not None:
                words += [s.shape_label for s in m.states if s.shape_label]
                words += [s.structure for s in m.states if s.structure]
                if m.ground is not None and m.ground.shape_label:
                    attrs.append(f'data-shape-{mslug}="{_e(m.ground.shape_label)}"')
            attrs.append(f'data-search-{mslug}="{_e(" ".join(words).lower())}"')
        attrs.append(f'data-search="{_e(" ".join([k.name, *k.families]).lower())}"')
        cells = []
        # thumbnail
        imgs = []
        for mname, mslug in models:
            src = thumbs.get((k.name, mname))
            body = (f'<img src="{_e(src)}" alt="{_e(k.name)} ground state ({_e(mname)})" '
                    f'loading="lazy">' if src else "")
            imgs.append(f'<span class="m m-{mslug}">{body}</span>')
        cells.append(f'<td class="thumb"><a href="{href}">{"".join(imgs)}</a></td>')
        cells.append(f'<td data-v="{_e(_natural(k.name))}"><a href="{href}">{_e(k.name)}</a>'
                     "</td>")
        for v in (k.crossing_number, k.n, k.i):
            dv = "" if v is None else f' data-v="{v}"'
            cells.append(f'<td class="num"{dv}>{"—" if v is None else v}</td>')
        if k.lower is None and k.upper is None:
            cells.append('<td class="num">—</td>')
        else:
            extra_b = " (exact)" if k.exact else (
                f" ({_e(k.attained_by)})" if k.attained_by else "")
            dv = "" if k.lower is None else f' data-v="{k.lower:.6f}"'
            cells.append(f'<td class="num"{dv}>{_num(k.lower)} – {_num(k.upper)}'
                         f"{extra_b}</td>")

        def gs(m: _Model):
            return m.ground

        cells.append(_per_model_cell(
            k, models,
            lambda m: _shape_badge(gs(m).shape_label, gs(m).shape, extra,
                                   gs(m).structure) if gs(m) else "—",
            lambda m: gs(m).shape_label.lower() if gs(m) and gs(m).shape_label else None))
        cells.append(_per_model_cell(
            k, models, lambda m: _num(gs(m).epsilon) if gs(m) else "—",
            lambda m: (f"{gs(m).epsilon:.6f}" if gs(m) and gs(m).epsilon is not None
                       else None), "num"))
        cells.append(_per_model_cell(
            k, models, lambda m: _e(gs(m).width) if gs(m) and gs(m).width else "—",
            lambda m: gs(m).width if gs(m) and gs(m).width else None, "width"))
        cells.append(_per_model_cell(
            k, models, lambda m: _yes_no(gs(m).converged) if gs(m) else "—",
            lambda m: _yes_no(gs(m).converged) if gs(m) and gs(m).converged is not None
            else None))

        def meta_text(m: _Model) -> str:
            if not m.metastable:
                return "none" if m.ground is not None else "—"
            return "<br>".join(
                f"{_e(s.shape_label or '?')} ×{s.count if s.count is not None else '?'}"
                f" ({_num(s.epsilon)})" for s in m.metastable)

        cells.append(_per_model_cell(k, models, meta_text,
                                     lambda m: str(len(m.metastable)) if m.ground or
                                     m.metastable else None))
        cells.append(_per_model_cell(
            k, models,
            lambda m: segment_distance_text(gs(m).min_segment_distance) if gs(m) else "—",
            lambda m: (f"{gs(m).min_segment_distance:.6f}"
                       if gs(m) and gs(m).min_segment_distance is not None else None), "num"))
        fam = ", ".join(k.families)
        dv = f' data-v="{_e(fam.lower())}"' if fam else ""
        cells.append(f"<td{dv}>{_e(fam) if fam else '—'}</td>")
        parts.append(f"<tr {' '.join(attrs)}>" + "".join(cells) + "</tr>\n")
    parts.append("</tbody>\n</table></div>\n")

    # ε against n²
    parts.append('<h2 id="eps-title">ε against n²</h2>\n<div id="eps-plot" class="plot"></div>\n'
                 '<p class="figure-note">Each point is the ground state of one knot at its '
                 "finite width (hover for the knot, its ε and width; click to open its page); "
                 "the points of one n are spread sideways by at most ±0.8 so that none hides "
                 "another. Lines: the thin-limit lower bound 2π²n² and the point braid and loops "
                 "2π²α²n² (an upper bound for every knot); grey bars: the interval "
                 "[2π²n², 2π² min(α²n², i²)] for each (n, i); ticks: the circular braid "
                 "2π²i².</p>\n")
    parts.append('<script type="application/json" id="eps-data">' + _json_script(fig)
                 + "</script>\n")

    # family statistics
    if families is not None:
        parts.append(_families_html(families, {k.name: k.slug for k in knots}))

    # meta
    parts.append("<footer>\n<table class=\"meta-list\">\n")
    for key, val in meta.items():
        parts.append(f"<tr><th>{_e(key)}</th><td>{_e(val)}</td></tr>\n")
    parts.append("</table>\n</footer>\n</main>\n<script>" + _INDEX_JS + "</script>\n"
                 "</body>\n</html>\n")
    return "".join(parts)


def _families_html(families: Mapping, slugs: Mapping[str, str] | None = None) -> str:
    if not isinstance(families, Mapping):
        raise ValueError("families must be a dict with 'groups' (see write_atlas)")
    groups = families.get("groups")
    if not isinstance(groups, Sequence) or isinstance(groups, str | bytes):
        raise ValueError("families['groups'] must be a list of {'label', 'total', 'counts'}")
    shapes: list[str] = []
    for g in groups:
        if not isinstance(g, Mapping) or "label" not in g or not isinstance(
                g.get("counts"), Mapping):
            raise ValueError(f"each family group needs 'label' and 'counts', got {g!r}")
        for s in g["counts"]:
            if str(s) not in shapes:
                shapes.append(str(s))
    title = families.get("title") or "Family statistics"
    out = [f'<h2 id="families-title">{_e(title)}</h2>\n']
    if families.get("model"):
        out.append(f'<p class="lede">Model: {_e(families["model"])}.</p>\n')
    out.append('<table id="families"><thead><tr><th>shape family</th>'
               + "".join(f'<th class="num">{_e(g["label"])}</th>' for g in groups)
               + "</tr></thead>\n<tbody>\n")
    totals = []
    for g in groups:
        t = g.get("total")
        totals.append(int(t) if t is not None else sum(int(v) for v in g["counts"].values()))
    for s in shapes:
        cells = []
        for g, t in zip(groups, totals, strict=True):
            c = int(g["counts"].get(s, 0))
            frac = f" ({100.0 * c / t:.0f} %)" if t else ""
            cells.append(f'<td class="num">{c}{frac}</td>')
        out.append(f"<tr><td>{_e(s)}</td>{''.join(cells)}</tr>\n")
    out.append("<tr><th>knots</th>" + "".join(f'<th class="num">{t}</th>' for t in totals)
               + "</tr>\n</tbody></table>\n")
    if families.get("note"):
        out.append(f'<p class="figure-note">{_e(families["note"])}</p>\n')
    if families.get("structures"):
        out.append(_structures_html(families["structures"], slugs or {}))
    return "".join(out)


def _structures_html(structures: Any, slugs: Mapping[str, str]) -> str:
    """The knots grouped by the contact structure of their ground state (§V B): one row per
    structure, its knots linked to their pages."""
    if not isinstance(structures, Mapping) or not isinstance(structures.get("rows"), Sequence):
        raise ValueError("families['structures'] must be a dict with 'rows': a list of "
                         "{'structure', 'knots', 'shapes', 'epsilon'}")
    out = [f'<h3 id="structures-title">{_e(structures.get("title") or "Ground structures")}'
           "</h3>\n"]
    if structures.get("note"):
        out.append(f'<p class="lede">{_e(structures["note"])}</p>\n')
    out.append('<table id="structures"><thead><tr><th>structure (§V B)</th>'
               '<th class="num">knots</th><th>ground shape</th><th class="num">ε</th>'
               "<th>which</th></tr></thead>\n<tbody>\n")
    for r in structures["rows"]:
        if not isinstance(r, Mapping) or not isinstance(r.get("structure"), str) \
                or not isinstance(r.get("knots"), Sequence) or isinstance(r["knots"], str):
            raise ValueError(f"each structure row needs 'structure' (text) and 'knots' "
                             f"(names), got {r!r}")
        names = [str(n) for n in r["knots"]]
        links = ", ".join(f'<a href="knots/{_e(slugs[n])}.html">{_e(n)}</a>' if n in slugs
                          else _e(n) for n in names)
        shapes = ", ".join(f"{_e(str(k))} {int(v)}" for k, v in (r.get("shapes") or {}).items())
        eps = r.get("epsilon") or []
        eps_text = (f"{_num(eps[0])} – {_num(eps[1])}" if len(eps) == 2 and eps[0] != eps[1]
                    else _num(eps[0]) if eps else "—")
        out.append(f"<tr><td>{_e(r['structure'])}</td><td class=\"num\">{len(names)}</td>"
                   f"<td>{shapes or '—'}</td><td class=\"num\">{eps_text}</td>"
                   f"<td>{links}</td></tr>\n")
    out.append("</tbody></table>\n")
    return "".join(out)


def _knot_page(k: _Knot, models: list[tuple[str, str]], default: str | None, title: str,
               prev: _Knot | None, nxt: _Knot | None) -> str:
    extra: dict = {}
    parts = [_head(f"{k.name} — {title}", "../", ""), "<body>\n<main>\n"]
    nav = ['<a href="../index.html">← all knots</a>']
    if prev is not None:
        nav.append(f'<a href="{_e(prev.slug)}.html" rel="prev">‹ {_e(prev.name)}</a>')
    if nxt is not None:
        nav.append(f'<a href="{_e(nxt.slug)}.html" rel="next">{_e(nxt.name)} ›</a>')
    parts.append(f'<nav class="top">{" · ".join(nav)}</nav>\n<h1>{_e(k.name)}</h1>\n')
    facts = [("crossing number n<sub>c</sub>", "—" if k.crossing_number is None
              else str(k.crossing_number)),
             ("bridge number n", "—" if k.n is None else str(k.n)),
             ("braid index i", "—" if k.i is None else str(k.i))]
    if k.lower is not None or k.upper is not None:
        b = f"{_num(k.lower)} ≤ ε* ≤ {_num(k.upper)}"
        if k.exact:
            b += " (exact: the circular braid is the ground state)"
        elif k.attained_by:
            b += f" (upper bound from {_e(k.attained_by)})"
        facts.append(("bounds, thin limit w/L → 0", b))
    if k.families:
        facts.append(("families", _e(", ".join(k.families))))
    parts.append('<dl class="facts">' + "".join(f"<dt>{a}</dt><dd>{b}</dd>" for a, b in facts)
                 + "</dl>\n")
    if k.note:
        parts.append(f"<p>{_e(k.note)}</p>\n")

    states_js: list[dict] = []
    order = [m for m, _ in models if m in k.models]
    if default in order:
        order.remove(default)
        order.insert(0, default)
    if not order:
        parts.append("<p>No computed states for this knot.</p>\n")
    for mname in order:
        m = k.models[mname]
        parts.append(f'<h2>Model “{_e(mname)}”</h2>\n')
        if m.width:
            parts.append(f'<p class="lede">Width: {_e(m.width)}'
                         + (f"; {m.replicas} replicas" if m.replicas else "") + ".</p>\n")
        elif m.replicas:
            parts.append(f'<p class="lede">{m.replicas} replicas.</p>\n')
        if not m.states:
            parts.append("<p>No states.</p>\n")
            continue
        parts.append('<table class="states"><thead><tr><th>state</th><th>shape</th>'
                     '<th title="line-braids (m: strands), point-braids and multiple points '
                     'of the chain at its width (§V B)">structure</th>'
                     '<th class="num">ε</th><th class="num">mean ε</th><th class="num">count'
                     '</th><th>converged</th><th class="num">min segment distance</th>'
                     "<th>width</th><th>3D</th></tr></thead>\n<tbody>\n")
        for st in m.states:
            idx = ""
            view = "—"
            if st.coords is not None:
                idx = str(len(states_js))
                named = f" ({st.structure})" if st.structure else ""
                cap = (f"{k.name}, {mname}, {st.role}: {st.shape_label or 'unclassified'}"
                       f"{named}, ε = {_num(st.epsilon)} at {st.width or 'unknown width'}")
                states_js.append({**state_mesh(st.coords, closed=st.closed,
                                               radius=st.radius),
                                  "zones": None if st.zones is None else st.zones.tolist(),
                                  "caption": cap,
                                  "label": f"{mname} — {st.role}: "
                                           f"{st.shape_label or 'unclassified'} "
                                           f"(ε = {_num(st.epsilon)})"})
                view = '<span class="view-link">view</span>'
            parts.append(
                f'<tr class="state-row" data-state="{idx}" data-model="{_e(mname)}">'
                f"<td>{_e(st.role)}</td>"
                f"<td>{_shape_badge(st.shape_label, st.shape, extra)}</td>"
                f"<td>{_e(st.structure) if st.structure else '—'}</td>"
                f'<td class="num">{_num(st.epsilon)}</td>'
                f'<td class="num">{_num(st.eps_mean)}</td>'
                f'<td class="num">{_count_text(st, m.replicas)}</td>'
                f"<td>{_yes_no(st.converged)}</td>"
                f'<td class="num">{segment_distance_text(st.min_segment_distance)}</td>'
                f'<td class="width">{_e(st.width) if st.width else "—"}</td>'
                f"<td>{view}</td></tr>\n")
        parts.append("</tbody></table>\n")
    if states_js:
        parts.append(
            '<h2 id="view-title">3D view</h2>\n<div class="viewer">\n<div class="view-controls">'
            '<label>State <select id="state-select">'
            + "".join(f'<option value="{j}">{_e(s["label"])}</option>'
                      for j, s in enumerate(states_js))
            + '</select></label>'
            + ('<label>Colour <select id="colour-select"><option value="arc">along the '
               'chain</option><option value="zones">by contact structure (§V B)</option>'
               '</select></label>' if any(s["zones"] is not None for s in states_js) else "")
            + '<span id="view-caption"></span></div>\n'
            '<div class="view-frame"><div id="view3d"></div></div>\n'
            '<p class="zone-legend" id="zone-legend" hidden>'
            + "".join(f'<span><i style="background:{c}"></i>{_e(n)}</span>'
                      for c, n in zip(_ZONE_COLOURS, ZONE_KINDS, strict=True))
            + '<span id="zone-missing" hidden>(no contact structure for this state: coloured '
              "along the chain)</span></p>\n"
            '<p class="figure-note">Drag to turn, scroll to zoom. The tube is drawn with the '
            "radius given with the state, by default half the bead exclusion distance 1/√2 (so "
            "that beads in contact show touching tubes); its colour runs along the "
            "arclength, or, by contact structure, marks the beads of each line-braid, "
            "point-braid and multiple point (every strand passing through it). Click a row "
            "of the tables to show that state.</p>\n</div>\n")
        parts.append('<script type="application/json" id="states-data">'
                     + _json_script(states_js) + "</script>\n"
                     '<script type="application/json" id="colorscale-data">'
                     + _json_script(_COLORSCALE) + "</script>\n"
                     '<script type="application/json" id="zone-colours-data">'
                     + _json_script(list(_ZONE_COLOURS)) + "</script>\n"
                     "<script>" + _KNOT_JS + "</script>\n")
    parts.append(f"<footer>stiffknots {_e(__version__)}</footer>\n</main>\n</body>\n</html>\n")
    return "".join(parts)


def _write_plotly_js(out_dir: Path) -> str:
    """Copy plotly.js into ``out_dir`` (unless an identical copy is there); its version."""
    from plotly.offline import get_plotlyjs, get_plotlyjs_version

    js = get_plotlyjs().encode("utf-8")
    path = out_dir / "plotly.min.js"
    if not (path.is_file() and path.stat().st_size == len(js)
            and hashlib.sha256(path.read_bytes()).digest() == hashlib.sha256(js).digest()):
        path.write_bytes(js)
    return get_plotlyjs_version()


def write_atlas(out_dir, knots: list[dict], *, families: dict | None = None,
                title: str = DEFAULT_TITLE, meta: dict | None = None,
                default_model: str | None = None, thumbnails: bool = True) -> Path:
    """Write the atlas pages of a set of knots into a folder.

    Parameters
    ----------
    out_dir : str or Path
        The folder (created if needed). Files of the same names in it are overwritten.
    knots : list of dict
        One dict per knot, in the order of the table, in the schema of this module's docstring.
    families : dict, optional
        The family statistics (``{"groups": [{"label", "total", "counts"}], ...}``); default:
        :func:`family_statistics` of ``knots``.
    title : str
        Title of the index page.
    meta : dict, optional
        Facts shown at the foot of the index page (e.g. budget, seed, date).
    default_model : str, optional
        The model shown first (default: the first model met in ``knots``). The index page has
        a model selector when the knots have more than one.
    thumbnails : bool
        Draw a thumbnail of each ground state with coordinates (matplotlib, about 0.03 s each).

    Returns
    -------
    Path
        ``out_dir / "index.html"``.

    Raises
    ------
    ValueError
        If the input does not follow the schema: a missing or repeated name, a state with an
        ``epsilon`` but no width, coordinates that are not an ``(N, 3)`` array of finite
        numbers, a non-integer ``n``, an unknown ``default_model``, ...
    """
    ks = _knots(knots)
    names = _model_names(ks)
    if default_model is None or not names:  # no model has results yet: nothing to default
        default_model = names[0] if names else None
    elif default_model not in names:
        raise ValueError(f"default_model {default_model!r} is not among the models {names}")
    slug_of = {}
    for k in ks:
        for m in k.models.values():
            slug_of[m.name] = m.slug
    models = [(m, slug_of[m]) for m in names]
    if families is None and names:
        families = family_statistics(knots, model=default_model)

    out = Path(out_dir)
    (out / "knots").mkdir(parents=True, exist_ok=True)
    plotly_version = _write_plotly_js(out)

    thumbs: dict[tuple[str, str], str] = {}
    if thumbnails:
        tdir = out / "thumbs"
        for k in ks:
            for m in k.models.values():
                if m.ground is None or m.ground.coords is None:
                    continue
                tdir.mkdir(exist_ok=True)
                fname = f"{k.slug}-{m.slug}.png"
                (tdir / fname).write_bytes(_thumbnail_png(m.ground.coords, m.ground.closed,
                                                           m.ground.radius))
                thumbs[(k.name, m.name)] = f"thumbs/{fname}"

    fig = _eps_figure(ks, models, default_model)
    meta_all = {**(meta or {}), "stiffknots": __version__, "plotly.js": plotly_version}
    index = out / "index.html"
    index.write_text(_index_page(ks, models, default_model, families, title, meta_all, thumbs,
                                 fig), encoding="utf-8")
    for j, k in enumerate(ks):
        page = _knot_page(k, models, default_model, title, ks[j - 1] if j > 0 else None,
                          ks[j + 1] if j + 1 < len(ks) else None)
        (out / "knots" / f"{k.slug}.html").write_text(page, encoding="utf-8")

    summary = []
    for k in ks:
        row: dict[str, Any] = {"name": k.name, "page": f"knots/{k.slug}.html",
                               "crossing_number": k.crossing_number, "n": k.n, "i": k.i,
                               "bounds": {"lower": k.lower, "upper": k.upper,
                                          "attained_by": k.attained_by, "exact": k.exact},
                               "families": k.families, "models": {}}
        for m in k.models.values():
            row["models"][m.name] = {
                "replicas": m.replicas,
                "states": [{"role": s.role, "shape": s.shape, "multiplicity": s.multiplicity,
                            "epsilon": s.epsilon, "eps_mean": s.eps_mean, "count": s.count,
                            "converged": s.converged,
                            "min_segment_distance": s.min_segment_distance,
                            "width": s.width} for s in m.states]}
        summary.append(row)
    (out / "atlas.json").write_text(
        json.dumps(to_plain({"title": title, "meta": meta_all, "families": families,
                             "knots": summary}), indent=1, ensure_ascii=False) + "\n",
        encoding="utf-8")
    return index
