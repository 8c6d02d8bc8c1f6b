"""The pictures of the atlas: the thumbnail of a state, the tube of its 3D view, the figure of
ε against n² with the bounds of Gallotti & Pierre-Louis (PRE 2007, §IV, §VI A), and the badge
of a shape class in its colour."""

from __future__ import annotations

import math
from io import BytesIO

import numpy as np

from stiffknots.report.atlas.markup import esc, num
from stiffknots.report.atlas.schema import KnotRow, natural_key
from stiffknots.theory import closed_bounds

__all__ = ["COLORSCALE", "ZONE_COLOURS", "eps_figure", "shape_badge", "state_mesh",
           "thumbnail_png"]

#: Colours along the arclength of a closed tube: the cyclic map of
#: :mod:`stiffknots.report.render` (no seam at bead 0), as a plotly colour scale.
_CYCLIC = ["#2f6db3", "#3aa3a0", "#e0b43a", "#d9623b", "#8e4fa3", "#2f6db3"]
COLORSCALE = [[k / (len(_CYCLIC) - 1), c] for k, c in enumerate(_CYCLIC)]

#: plotly marker symbols for the matplotlib markers of
#: :func:`stiffknots.report.figures.shape_style`.
_SYMBOLS = {"o": "circle", "s": "square", "^": "triangle-up", "v": "triangle-down",
            "D": "diamond", "P": "cross", "X": "x", "h": "hexagon", "*": "star"}

_THUMB_PX = 144  # thumbnail size in pixels (shown at half size: sharp on high-dpi screens)
_MESH_SIDES = 10  # vertices per ring of the 3D tube
_MAX_LABELLED = 16  # the ε–n² points carry their knot's name up to this many knots
_SPREAD = 0.8  # points of one n are spread over n² ± _SPREAD (at 0.2 apart while they fit)
_ZOOM = 1.8  # largest aspect ratio of the 3D scene (plotly's orthographic zoom)

#: the colours the 3D view gives the kinds of contact zone (:data:`.schema.ZONE_KINDS`)
ZONE_COLOURS = ("#c9c9c9", "#1f77b4", "#ff7f0e", "#d62728")


def thumbnail_png(coords: np.ndarray, closed: bool, radius: float | None) -> bytes:
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


def _bound_lines(knots: list[KnotRow]) -> tuple[list[dict], float, float]:
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
               f"{num(b.lower)} ≤ ε* ≤ {num(b.upper)} (thin limit)")
        top = max(top, b.upper if b.upper is not None else 0.0)
        bx += [x, x, None]
        by += [b.lower, b.upper, None]
        btext += [txt, txt, None]
        if b.eps_cb is not None:
            cx.append(x)
            cy.append(b.eps_cb)
            ctext.append(f"circular braid CB({i}): 2π²i² = {num(b.eps_cb)}")
    traces.append({"type": "scatter", "mode": "lines", "x": bx, "y": by, "text": btext,
                   "name": "bounds for (n, i)", "hoverinfo": "text",
                   "line": {"color": "rgba(90,90,90,0.55)", "width": 5}})
    if cx:
        traces.append({"type": "scatter", "mode": "markers", "x": cx, "y": cy, "text": ctext,
                       "name": "circular braid 2π²i²", "hoverinfo": "text",
                       "marker": {"symbol": "line-ew-open", "size": 16, "color": "#333",
                                  "line": {"color": "#333", "width": 2.5}}})
    return traces, x_max, top


def eps_figure(knots: list[KnotRow], models: list[tuple[str, str]],
               default_model: str | None) -> dict:
    """The plotly figure of ε against n² (a plain dict)."""
    from stiffknots.report.figures import shape_style

    traces, x_max, y_top = _bound_lines(knots)  # the PBL line may leave through the top
    extra: dict = {}
    labels = len(knots) <= _MAX_LABELLED
    for mname, mslug in models:
        groups: dict[int, list[KnotRow]] = {}
        for k in knots:
            m = k.models.get(mname)
            if k.n is None or m is None or m.ground is None or m.ground.epsilon is None:
                continue
            groups.setdefault(k.n, []).append(k)
        xs: dict[str, list] = {}
        for n, ks in groups.items():
            ks = sorted(ks, key=lambda k: natural_key(k.name))
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
                "name": esc(lab), "text": [esc(k.name) for k, _, _, _ in items],
                "textposition": [p for _, _, _, p in items],
                "textfont": {"size": 10, "color": "#555"},
                "legendgroup": f"{mname}:{lab}",
                "x": [x for _, _, x, _ in items], "y": [st.epsilon for _, st, _, _ in items],
                "customdata": [[esc(k.name), k.n, "?" if k.i is None else k.i,
                                num(st.epsilon), esc(st.width), f"knots/{k.slug}.html"]
                               for k, st, _, _ in items],
                "hovertemplate": ("<b>%{customdata[0]}</b> (n = %{customdata[1]}, "
                                  "i = %{customdata[2]})<br>" + esc(lab)
                                  + ": ε = %{customdata[3]}<br>at %{customdata[4]}"
                                  "<extra>" + esc(mname) + "</extra>"),
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


def shape_badge(label: str | None, shape: str | None, extra: dict,
                structure: str | None = None) -> str:
    """The shape class as a coloured badge; its contact structure (§V B) as its tooltip."""
    if label is None:
        return "—"
    from stiffknots.report.figures import shape_style

    colour = shape_style(shape, extra)[1]
    tip = f' title="{esc(structure)}"' if structure else ""
    return f'<span class="shape" style="background:{esc(colour)}"{tip}>{esc(label)}</span>'


#: colours of the branches of a branch diagram (plotly's default sequence)
BRANCH_COLOURS = ("#636efa", "#ef553b", "#00cc96", "#ab63fa", "#ffa15a", "#19d3f3",
                  "#ff6692", "#b6e880", "#ff97ff", "#fecb52")


def branch_figure(thin: dict, name: str) -> dict:
    """The branch diagram of a knot's thin stage as a plotly figure (data and layout): ε
    against w/L, one curve per state (the points fitted solid, those after the branch left
    its state open), and at w = 0 each state's extrapolated ε* with its error bar (filled
    circle) and its structure route's value (diamond)."""
    data = []
    for j, s in enumerate(thin["states"]):
        c = BRANCH_COLOURS[j % len(BRANCH_COLOURS)]
        lab = f"{j}: {s['name']}" + (" (thin-limit ground)" if thin["ground"] == j else "")
        fit = [p for p in s["points"] if p["in_fit"]]
        out = [p for p in s["points"] if not p["in_fit"]]
        data.append({"type": "scatter", "mode": "lines+markers", "name": lab,
                     "legendgroup": str(j), "line": {"color": c},
                     "x": [thin["w_over_L"]] + [p["w_over_L"] for p in fit],
                     "y": [s["epsilon"]] + [p["epsilon"] for p in fit],
                     "hovertemplate": "w/L = %{x:.3g}<br>ε = %{y:.3f}<extra>" + lab
                                      + "</extra>"})
        if out:
            data.append({"type": "scatter", "mode": "markers", "showlegend": False,
                         "legendgroup": str(j), "name": f"{lab}: left its state",
                         "marker": {"color": c, "symbol": "circle-open", "size": 8},
                         "x": [p["w_over_L"] for p in out], "y": [p["epsilon"] for p in out],
                         "hovertemplate": "w/L = %{x:.3g}<br>ε = %{y:.3f}<extra>" + lab
                                          + ": left its state (" + str(s["event"]) + ")"
                                          + "</extra>"})
        if s["epsilon_thin"] is not None:
            data.append({"type": "scatter", "mode": "markers", "showlegend": False,
                         "legendgroup": str(j), "name": f"{lab}: ε* extrapolated",
                         "marker": {"color": c, "size": 10}, "x": [0.0],
                         "y": [s["epsilon_thin"]],
                         "error_y": {"type": "data", "array": [s["error"] or 0.0],
                                     "color": c},
                         "hovertemplate": "w = 0 (extrapolated)<br>ε* = %{y:.4f}<extra>"
                                          + lab + "</extra>"})
        if s["structure_epsilon"] is not None:
            data.append({"type": "scatter", "mode": "markers", "showlegend": False,
                         "legendgroup": str(j), "name": f"{lab}: structure route",
                         "marker": {"color": c, "size": 11, "symbol": "diamond-open"},
                         "x": [0.0], "y": [s["structure_epsilon"]],
                         "hovertemplate": "w = 0 (structure route: "
                                          + str(s["structure_name"] or "") + ")<br>"
                                          "ε* = %{y:.4f}<extra>" + lab + "</extra>"})
    layout = {"title": {"text": f"{name}: every state followed to w = 0"},
              "xaxis": {"title": {"text": "w/L"}, "rangemode": "tozero"},
              "yaxis": {"title": {"text": "ε = E L / C"}},
              "margin": {"l": 60, "r": 10, "t": 40, "b": 50}, "height": 420,
              "legend": {"orientation": "h", "y": -0.2}}
    return {"data": data, "layout": layout}
