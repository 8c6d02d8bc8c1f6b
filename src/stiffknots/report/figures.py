"""Figures of the reports: annealing curves, energies against the bounds, tension of open knots.

All plotting functions take an optional matplotlib axis ``ax`` (a new figure is made if None) and
return the axis they drew on; :func:`save_figure` writes a figure (or the figure of an axis) to a
file and closes it. The bounds are those of :mod:`stiffknots.theory.bounds` (Gallotti &
Pierre-Louis, "Stiff knots", PRE 2007):

* closed knots (eq. (13)), (eq. (31)):
  ``2 pi^2 n^2 <= eps* <= 2 pi^2 min(alpha^2 n^2, i^2)``;
* open knots (eq. (45)), ``n1 = n - 1``, ``i1 = i - 1``:
  ``2 pi^2 n1^2 <= mu* L_e^2 / C <= 2 pi^2 min(alpha^2 n1^2, i1^2)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from stiffknots.fileio import atomic_path
from stiffknots.theory.bounds import closed_bounds, open_bounds  # noqa: E402
from stiffknots.theory.elastica import (  # noqa: E402
    eight_curve,
    eighty_curve,
    elastica_constants,
    loop_curve,
)

__all__ = [
    "SHAPE_STYLES",
    "shape_style",
    "plot_annealing_curves",
    "plot_eps_vs_n2",
    "plot_tension",
    "save_figure",
]

EPS_0 = 2.0 * math.pi**2

#: Marker and colour of the equilibrium shapes of §VII (keys are lower case).
SHAPE_STYLES: dict[str, tuple[str, str]] = {
    "circular braid": ("o", "#2f6db3"),
    "cb": ("o", "#2f6db3"),
    "4-fold cage": ("s", "#d9623b"),
    "4c": ("s", "#d9623b"),
    "cage": ("s", "#d9623b"),
    "80": ("^", "#3a9a5b"),
    "pbl": ("v", "#8e4fa3"),
    "point braid and loops": ("v", "#8e4fa3"),
}
_OTHER_STYLES = [("D", "#b8860b"), ("P", "#7f7f7f"), ("X", "#17becf"), ("h", "#bcbd22"),
                 ("*", "#e377c2")]
_DEFAULT_STYLE = ("o", "#444444")


def shape_style(shape: str | None, _extra: dict | None = None) -> tuple[str, str]:
    """Marker and colour for a shape class (``None``: unclassified).

    Known names (case-insensitive): "circular braid"/"CB", "4-fold cage"/"4C", "80", "PBL".
    Other names get markers of their own, in order of first appearance within one plot.
    """
    if shape is None:
        return _DEFAULT_STYLE
    key = str(shape).strip().lower()
    if key in SHAPE_STYLES:
        return SHAPE_STYLES[key]
    if _extra is None:
        return _OTHER_STYLES[0]
    if key not in _extra:
        _extra[key] = _OTHER_STYLES[len(_extra) % len(_OTHER_STYLES)]
    return _extra[key]


def new_figure(figsize=(6.0, 4.5), layout: str | None = "constrained") -> Figure:
    """A matplotlib Figure on the Agg canvas (no pyplot: no global state, no backend change)."""
    fig = Figure(figsize=figsize, layout=layout)
    FigureCanvasAgg(fig)
    return fig


def _finish(ax, xlabel: str, ylabel: str, labels, title):
    """Axis labels, a light grid, the legend, optional point labels ``(xs, ys, names)`` and
    title; returns ``ax``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, color="0.92", lw=0.6)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    if labels is not None:
        _label_points(ax, *labels)
    if title:
        ax.set_title(title)
    return ax


def _new_ax(ax, figsize=(6.0, 4.5)):
    if ax is None:
        ax = new_figure(figsize).subplots()
    return ax


def _field(obj, name: str):
    """``obj[name]``, ``obj.name`` or ``obj.trace_name`` (a :class:`ReplicaResult`)."""
    if isinstance(obj, Mapping):
        if name in obj:
            return obj[name]
        if f"trace_{name}" in obj:
            return obj[f"trace_{name}"]
        raise ValueError(f"missing field {name!r} (have {sorted(obj)})")
    for attr in (name, f"trace_{name}"):
        if hasattr(obj, attr):
            return getattr(obj, attr)
    raise ValueError(f"missing field {name!r} in {type(obj).__name__}")


def _points(points, required: Sequence[str]) -> list[dict]:
    """Normalise a list of dicts or objects to dicts with the ``required`` fields."""
    if isinstance(points, Mapping):
        raise ValueError("points must be a list of dicts (one per knot), not one dict")
    out = []
    for k, p in enumerate(points):
        d = dict(p) if isinstance(p, Mapping) else dict(vars(p))
        missing = [f for f in required if f not in d]
        if missing:
            raise ValueError(f"point {k} lacks the field(s) {missing}: {d}")
        out.append(d)
    return out


def plot_annealing_curves(traces, ax=None, *, labels: Sequence[str] | None = None,
                          logx: bool = True, references: Mapping[str, float] | None = None,
                          title: str | None = None):
    """Energy and temperature against the number of moves, one colour per replica.

    Parameters
    ----------
    traces : sequence
        One item per replica: a dict or object with arrays ``moves``, ``temperature`` and
        ``epsilon`` (a :class:`~stiffknots.engine.driver.ReplicaResult` with its ``trace_*``
        fields works too). ``temperature == 0`` marks the final quench.
    ax : matplotlib Axes, optional
        Axis for ε (left); the temperature goes on a twin axis on the right, in log scale, and is
        reachable as ``ax.temperature_axis``.
    labels : sequence of str, optional
        Legend labels (default "replica k", or the ``replica`` field if present).
    logx : bool
        Logarithmic moves axis (the power-law cooling is fastest at the start).
    references : mapping of str to float, optional
        Horizontal reference lines for ε, e.g. ``{"4-fold cage": 129.6}``.
    title : str, optional

    Returns
    -------
    matplotlib Axes
        The ε axis.

    Raises
    ------
    ValueError
        If ``traces`` is empty, a field is missing or the arrays of a trace differ in length.
    """
    traces = list(traces) if not isinstance(traces, Mapping) else [traces]
    if not traces:
        raise ValueError("no traces to plot")
    ax = _new_ax(ax)
    tax = ax.twinx()
    colours = matplotlib.colormaps["tab10"]
    quench_start = None
    for k, tr in enumerate(traces):
        m = np.asarray(_field(tr, "moves"), dtype=float)
        t = np.asarray(_field(tr, "temperature"), dtype=float)
        e = np.asarray(_field(tr, "epsilon"), dtype=float)
        if not (m.shape == t.shape == e.shape) or m.ndim != 1:
            raise ValueError(f"trace {k}: moves, temperature and epsilon must be 1D arrays of "
                             f"one length, got {m.shape}, {t.shape}, {e.shape}")
        if labels is not None:
            lab = labels[k]
        else:
            rep = tr.get("replica") if isinstance(tr, Mapping) else getattr(tr, "replica", None)
            lab = f"replica {rep if rep is not None else k}"
        c = colours(k % 10)
        ax.plot(m, e, color=c, lw=1.6, label=lab, zorder=3)
        hot = t > 0
        tax.plot(m[hot], t[hot], color=c, lw=1.0, ls="--", alpha=0.8)
        if np.any(~hot):
            q = float(m[~hot].min())
            # the quench starts right after the last hot point
            before = m[hot & (m < q)]
            q0 = float(before.max()) if len(before) else q
            quench_start = q0 if quench_start is None else min(quench_start, q0)
    if quench_start is not None:
        right = max(float(np.max(_field(tr, "moves"))) for tr in traces)
        ax.axvspan(quench_start, right, color="0.85", alpha=0.6, zorder=0, lw=0)
        ax.text(quench_start, 0.97, "quench T = 0 ", transform=ax.get_xaxis_transform(),
                va="top", ha="left", rotation=90, fontsize=8, color="0.3")
    if references:
        for name, val in references.items():
            ax.axhline(val, color="0.4", lw=0.8, ls=":", zorder=1)
            ax.text(0.01, val, f" {name}", transform=ax.get_yaxis_transform(), va="bottom",
                    fontsize=8, color="0.3")
    if logx:
        ax.set_xscale("log")
    if np.any(np.concatenate([np.asarray(_field(tr, "temperature")) > 0 for tr in traces])):
        tax.set_yscale("log")
    ax.set_xlabel("moves")
    ax.set_ylabel(r"$\varepsilon = E L / C$ (solid)")
    tax.set_ylabel(r"temperature $k_B T / C$ (dashed)")
    ax.set_zorder(tax.get_zorder() + 1)
    ax.patch.set_visible(False)
    ax.legend(loc="upper center", fontsize=8, frameon=False)
    if title:
        ax.set_title(title)
    ax.temperature_axis = tax
    return ax


def _spread(values: list[float], min_gap: float) -> list[float]:
    """Move sorted positions apart to at least ``min_gap`` (keeps their mean)."""
    if not values:
        return []
    order = np.argsort(values)
    v = np.asarray(values, dtype=float)[order]
    out = v.copy()
    for _ in range(50):
        moved = False
        for k in range(1, len(out)):
            if out[k] - out[k - 1] < min_gap:
                mid = 0.5 * (out[k] + out[k - 1])
                out[k - 1], out[k] = mid - min_gap / 2, mid + min_gap / 2
                moved = True
        if not moved:
            break
    out += v.mean() - out.mean()
    res = np.empty_like(out)
    res[order] = out
    return list(res)


def _label_points(ax, xs, ys, names, dx_points: float = 7.0, fontsize: float = 8.0) -> None:
    """Label points to their right; labels of points at one abscissa are spread vertically."""
    if not names:
        return
    groups: dict[float, list[int]] = {}
    for k, x in enumerate(xs):
        groups.setdefault(round(float(x), 9), []).append(k)
    pt = 72.0 / ax.figure.dpi  # points per pixel
    gap = 1.3 * fontsize / pt  # pixels between label centres
    for idx in groups.values():
        disp_y = [ax.transData.transform((xs[k], ys[k]))[1] for k in idx]
        new_y = _spread(disp_y, gap)
        for k, y0, y1 in zip(idx, disp_y, new_y, strict=True):
            dy = (y1 - y0) * pt
            ax.annotate(names[k], (xs[k], ys[k]), xytext=(dx_points, dy),
                        textcoords="offset points", fontsize=fontsize, va="center", ha="left",
                        arrowprops=dict(arrowstyle="-", color="0.6", lw=0.5, shrinkA=0,
                                        shrinkB=3) if abs(dy) > 2 else None)


def plot_eps_vs_n2(points, ax=None, *, bounds: bool = True, labels: bool = True,
                   title: str | None = None):
    """Normalised energies ``eps = E L / C`` of closed knots against ``n^2``, with the bounds.

    Parameters
    ----------
    points : sequence of dict
        One per knot (or per replica): ``knot`` (name), ``n`` (bridge number), ``i`` (braid
        index, may be None), ``epsilon``, and optionally ``shape`` (class name: "circular
        braid", "4-fold cage", "80", ...; it chooses the marker).
    ax : matplotlib Axes, optional
    bounds : bool
        Draw the general bounds as lines against ``n^2``: the lower bound
        ``eps = 2 pi^2 n^2`` (eq. (13)) and the upper bound of the point braid and
        loops, ``eps_PBL = 2 pi^2 alpha^2 n^2 = 4 n^2 eps_loop`` (valid for every knot), and for
        each ``(n, i)`` present the interval ``[2 pi^2 n^2, 2 pi^2 min(alpha^2 n^2, i^2)]``
        of :func:`~stiffknots.theory.bounds.closed_bounds`, with the circular braid
        ``eps_CB = 2 pi^2 i^2`` marked.
    labels : bool
        Write the knot names next to the points.
    title : str, optional

    Returns
    -------
    matplotlib Axes
        The axes, ε against n² with the bounds' band.

    Raises
    ------
    ValueError
        If a point lacks a field or its ``n``, ``i`` are inconsistent (see ``closed_bounds``).
    """
    pts = _points(points, ("knot", "n", "epsilon"))
    ax = _new_ax(ax)
    extra: dict = {}
    n_vals = [int(p["n"]) for p in pts if p["n"] is not None]
    n_max = max(n_vals, default=2)
    x_max = (n_max + 0.6) ** 2
    alpha2 = elastica_constants().alpha ** 2
    if bounds:
        xx = np.linspace(0.0, x_max, 2)
        ax.plot(xx, EPS_0 * xx, color="k", lw=1.2,
                label=r"lower bound $2\pi^2 n^2$")
        ax.plot(xx, EPS_0 * alpha2 * xx, color="k", lw=1.0, ls="--",
                label=r"upper bound $\varepsilon_{PBL} = 2\pi^2\alpha^2 n^2$")
        pairs = sorted({(int(p["n"]), None if p.get("i") is None else int(p["i"]))
                        for p in pts if p["n"] is not None},
                       key=lambda t: (t[0], -1 if t[1] is None else t[1]))
        by_n: dict[int, list] = {}
        for n, i in pairs:
            by_n.setdefault(n, []).append(i)
        first = True
        dx = 0.02 * x_max
        for n, i_list in by_n.items():
            x_label = n * n - (len(i_list) + 0.6) * dx
            for j, i in enumerate(i_list):
                b = closed_bounds(n, i)
                x = n * n - (j + 1) * dx
                ax.plot([x, x], [b.lower, b.upper], color="0.45", lw=2.2, alpha=0.7,
                        solid_capstyle="butt",
                        label=r"bounds for $(n, i)$" if first else None)
                if b.eps_cb is not None:
                    ax.plot([x], [b.eps_cb], marker="_", ms=9, mew=1.5, color="0.25",
                            label=r"circular braid $2\pi^2 i^2$" if first else None)
                    ax.plot([x_label, x], [b.eps_cb, b.eps_cb], color="0.6", lw=0.5, ls=":")
                    ax.annotate(f"i={i}", (x_label, b.eps_cb), xytext=(-2, 0),
                                textcoords="offset points", ha="right", va="center",
                                fontsize=7, color="0.3")
                first = False
    seen_shapes: set = set()
    xs, ys, names = [], [], []
    for p in pts:
        if p["n"] is None:
            continue
        n = int(p["n"])
        i = p.get("i")
        closed_bounds(n, None if i is None else int(i))  # validates n, i
        shape = p.get("shape")
        marker, colour = shape_style(shape, extra)
        key = None if shape is None else str(shape)
        lab = None
        if key not in seen_shapes:
            seen_shapes.add(key)
            lab = key if key is not None else "unclassified"
        x, y = n * n, float(p["epsilon"])
        ax.plot([x], [y], ls="none", marker=marker, ms=7, mfc=colour, mec="k", mew=0.6,
                label=lab, zorder=4)
        xs.append(x)
        ys.append(y)
        names.append(str(p["knot"]))
    ax.set_xlim(0.0, x_max)
    top = max([*ys, EPS_0 * alpha2 * n_max**2 if bounds else 0.0])
    ax.set_ylim(0.0, top * 1.08)
    ax.set_xticks([k * k for k in range(0, n_max + 1)])
    return _finish(ax, r"$n^2$ (bridge number squared)", r"$\varepsilon^* = E L / C$",
                   (xs, ys, names) if labels else None, title)


def plot_tension(points, ax=None, *, bounds: bool = True, labels: bool = True,
                 title: str | None = None):
    """Tension ``mu`` of open knots against ``1 / L_e^2``, with the bounds of §VIII.

    Parameters
    ----------
    points : sequence of dict
        One per simulation: ``knot``, ``L_e`` (excess length, > 0), ``mu`` (tension), ``n``,
        ``i`` (of the closed knot; may be None). Units ``C = 1``.
    ax : matplotlib Axes, optional
    bounds : bool
        For each ``(n, i)`` present, the lines ``mu = lower / L_e^2`` (solid) and
        ``mu = upper / L_e^2`` (dashed) of :func:`~stiffknots.theory.bounds.open_bounds`
        (eq. (45)), i.e. ``2 pi^2 n1^2`` and ``2 pi^2 min(alpha^2 n1^2, i1^2)`` with
        ``n1 = n - 1``, ``i1 = i - 1``; one line when they coincide (the open trefoil:
        ``mu* = 2 pi^2 / L_e^2``).
    labels, title
        As for :func:`plot_eps_vs_n2`.

    Returns
    -------
    matplotlib Axes
        The axes, μ against 1/L_e² with the bounds' lines.

    Raises
    ------
    ValueError
        If a point lacks a field or has ``L_e <= 0``.
    """
    pts = _points(points, ("knot", "L_e", "mu", "n"))
    ax = _new_ax(ax)
    for k, p in enumerate(pts):
        if not float(p["L_e"]) > 0:
            raise ValueError(f"point {k} ({p['knot']}): L_e must be > 0, got {p['L_e']}")
    inv = [1.0 / float(p["L_e"]) ** 2 for p in pts]
    x_max = 1.1 * max(inv, default=1.0)
    colours = matplotlib.colormaps["tab10"]
    pairs = sorted({(int(p["n"]), None if p.get("i") is None else int(p["i"])) for p in pts},
                   key=lambda t: (t[0], -1 if t[1] is None else t[1]))
    colour_of = {pair: colours(k % 10) for k, pair in enumerate(pairs)}
    y_top = 0.0
    if bounds:
        xx = np.array([0.0, x_max])
        for pair in reversed(pairs):  # the smallest knots on top
            b = open_bounds(*pair)
            c = colour_of[pair]
            tag = f"n={pair[0]}" + ("" if pair[1] is None else f", i={pair[1]}")
            lo, hi = b.tension_bounds(1.0 / math.sqrt(x_max))
            if b.lower is not None:
                name = (r"$\mu^* = 2\pi^2 i_1^2/L_e^2$" if b.exact
                        else r"lower $2\pi^2 n_1^2/L_e^2$")
                ax.plot(xx, b.lower * xx, color=c, lw=1.2, label=f"{name} ({tag})")
                y_top = max(y_top, lo)
            if b.upper is not None and not b.exact:
                ax.plot(xx, b.upper * xx, color=c, lw=1.0, ls="--",
                        label=rf"upper $2\pi^2\min(\alpha^2 n_1^2, i_1^2)/L_e^2$ ({tag})")
                y_top = max(y_top, hi)
    xs, ys, names = [], [], []
    for p, x in zip(pts, inv, strict=True):
        pair = (int(p["n"]), None if p.get("i") is None else int(p["i"]))
        y = float(p["mu"])
        ax.plot([x], [y], ls="none", marker="o", ms=6, mfc=colour_of[pair], mec="k", mew=0.6,
                zorder=4)
        xs.append(x)
        ys.append(y)
        names.append(str(p["knot"]))
        y_top = max(y_top, y)
    ax.set_xlim(0.0, x_max)
    ax.set_ylim(0.0, 1.08 * y_top if y_top > 0 else 1.0)
    return _finish(ax, r"$1 / L_e^2$", r"tension $\mu$ ($C = 1$)",
                   (xs, ys, names) if labels else None, title)


def save_figure(fig_or_ax, path, *, dpi: int = 120, close: bool = True) -> Path:
    """Write a figure (or the figure of an axis) to ``path`` and close it.

    Parameters
    ----------
    fig_or_ax : matplotlib Figure or Axes
    path : str or Path
        Output file; the format follows the suffix (``.png``, ``.svg``, ``.pdf``). Its folder is
        created if needed.
    dpi : int
        Resolution of raster formats.
    close : bool
        Close the figure afterwards (frees its memory).

    Returns
    -------
    Path
    """
    fig = fig_or_ax.figure if hasattr(fig_or_ax, "figure") and not hasattr(
        fig_or_ax, "savefig") else fig_or_ax
    if not hasattr(fig, "savefig"):
        raise ValueError(f"expected a matplotlib Figure or Axes, got {type(fig_or_ax).__name__}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, facecolor="white", format=path.suffix.lstrip(".") or "png")
    if close:
        fig.clear()
    return path


def plot_elastica(path: str | None = None, *, axes: Sequence[Any] | None = None,
                  n_points: int = 800, dpi: int = 150) -> Any:
    """Draw the loop, the 8 and the 80 in three panels, with their energies in the titles.

    Uses matplotlib's object API with the Agg canvas (no pyplot, no global backend change).

    Parameters
    ----------
    path : str, optional
        Write a PNG there.
    axes : sequence of three matplotlib Axes, optional
        Draw into these instead of a new figure.
    n_points : int
        Points per curve.
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure
    """
    c = elastica_constants()
    if axes is None:
        fig = new_figure(figsize=(11.0, 4.0))
        axes = fig.subplots(1, 3)
    else:
        fig = axes[0].figure
    loop = loop_curve(n_points)
    eight = eight_curve(n_points)
    e8, e0 = eighty_curve(n_points, split=True)
    colour, colour2 = "#1f4e79", "#c0504d"
    panels = [
        (axes[0], [(loop, colour)], rf"loop: $\epsilon_{{loop}}$ = {c.eps_loop:.4f}",
         [loop[0]]),
        (axes[1], [(eight, colour)], rf"8: $\epsilon_8$ = {c.eps_8:.4f}", []),
        (axes[2], [(e8, colour), (e0, colour2)],
         rf"80: $\epsilon_{{80}}$ = {c.eps_80:.3f}", [e8[0]]),
    ]
    for ax, curves, title, dots in panels:
        for pts, col in curves:
            ax.plot(pts[:, 0], pts[:, 1], color=col, lw=2.0, solid_capstyle="round")
        for d in dots:
            ax.plot([d[0]], [d[1]], "o", color="black", ms=4, zorder=3)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(title, fontsize=11)
        ax.set_xticks([])
        ax.set_yticks([])
        for side in ax.spines.values():
            side.set_visible(False)
        ax.margins(0.08)
    if path is not None:
        save_figure(fig, path, dpi=dpi, close=False)
    return fig


def plot_open_trend(points: Sequence[Mapping], fit: Mapping, ax=None, *,
                    label: str = "annealed open trefoil"):
    """ε_e against 1/√L_e with the fit ε_∞ + a/√L_e and the thin limit 2π² (§VIII).

    ``points``: dicts with ``excess_length`` and ``eps_e``; ``fit``: ``eps_inf`` and ``a``.
    """
    ax = _new_ax(ax, (6, 4.2))
    x = np.array([1 / np.sqrt(p["excess_length"]) for p in points])
    y = np.array([p["eps_e"] for p in points])
    ax.plot(x, y, "o", color="C0", label=label)
    xx = np.linspace(0, x.max() * 1.05, 50)
    ax.plot(xx, fit["eps_inf"] + fit["a"] * xx, "-", color="C0", lw=1,
            label=f"fit ε_∞ + a/√L_e, ε_∞ = {fit['eps_inf']:.2f}")
    ax.axhline(2 * math.pi**2, color="k", ls="--", lw=1, label="2π² (thin limit, §VIII)")
    for p, xi, yi in zip(points, x, y, strict=True):
        ax.annotate(f"L_e={p['excess_length']:.0f}", (xi, yi), textcoords="offset points",
                    xytext=(4, 4), fontsize=7)
    ax.set_xlabel("1/√L_e  (bond lengths^-½)")
    ax.set_ylabel("ε_e = E L_e / C")
    ax.set_xlim(0, None)
    ax.legend(fontsize=8)
    return ax


def plot_thin_limit(result: Mapping, ax=None):
    """ε*_w against w/L with the fit ε* + a (w/L)^p, the thin limit ε* ± error and the
    structure route's value at w = 0 (§V A, §V B).

    ``result``: the dict of :func:`stiffknots.studies.thin_limit.thin_limit`.
    """
    ax = _new_ax(ax, (6, 4.2))
    pts = result["points"]
    n = pts[0]["beads"] if pts else 0
    for inside, mk, lab in ((True, "o", "fitted"), (False, "x", "other shape (not fitted)")):
        sel = [p for p in pts if p.get("in_fit", True) == inside]
        if sel:
            ax.errorbar([p["w_over_L"] for p in sel], [p["epsilon"] for p in sel],
                        yerr=[p["sigma"] for p in sel], fmt=mk, color="C0" if inside else "C3",
                        label=f"ε*_w, N = {n} ({lab})", capsize=2)
            for p in sel:
                ax.annotate(p["shape"], (p["w_over_L"], p["epsilon"]),
                            textcoords="offset points", xytext=(4, 4), fontsize=7)
    fit, eps, err = result.get("fit"), result.get("epsilon_thin"), result.get("error")
    wmax = max(p["w_over_L"] for p in pts) if pts else 1.0
    if fit is not None and eps is not None:
        xx = np.linspace(0, wmax * 1.05, 200)
        ax.plot(xx, fit["epsilon"] + fit["a"] * xx ** fit["p"], "-", color="C0", lw=1,
                label=f"fit ε* + a (w/L)^p, p = {fit['p']:.2f}")
        ax.errorbar([0.0], [eps], yerr=[err], fmt="s", color="k", capsize=3,
                    label=f"thin limit ε* = {eps:.4f} ± {err:.2g}")
    s = result.get("structure")
    if s is not None:
        ax.axhline(s["epsilon"], color="C2", ls="--", lw=1,
                   label=f"structure {s['name']} at w = 0: {s['epsilon']:.4f}")
    ax.set_xlabel("w/L")
    ax.set_ylabel("ε = E L / C")
    ax.set_xlim(-0.02 * wmax, wmax * 1.08)
    ax.set_title(f"{result.get('knot', '')}: thin limit (tube model)")
    ax.legend(fontsize=7)
    return ax


def plot_branches(result: Mapping, ax=None):
    """The branch diagram of a knot: ε (corrected for the discretisation) against w/L, one
    curve per state of its census, each state's extrapolated ε*_s ± error at w = 0 (filled
    square) and the structure route's value where it has one (open diamond); points after a
    branch's event (class change, jump, merger) are crosses, not fitted.

    ``result``: the dict of :func:`stiffknots.studies.thin_states.thin_limit_states`.
    """
    ax = _new_ax(ax, (6.4, 4.4))
    wmax = 0.0
    for i, s in enumerate(result["states"]):
        col = f"C{i % 10}"
        pts = s["points"]
        if not pts:
            continue
        wmax = max(wmax, max(p["w_over_L"] for p in pts))
        inside = [p for p in pts if p["in_fit"]]
        after = [p for p in pts if not p["in_fit"]]
        ground = " — thin-limit ground" if result.get("ground") == i else ""
        label = f"{i}: {s['shape']} (ε = {s['epsilon']:.2f} at the atlas width){ground}"
        if inside:
            ax.plot([p["w_over_L"] for p in inside], [p["epsilon"] for p in inside], "o-",
                    color=col, ms=3, lw=1, label=label)
        if after:
            ax.plot([p["w_over_L"] for p in after], [p["epsilon"] for p in after], "x",
                    color=col, ms=5, label=None if inside else label)
        if s.get("epsilon_thin") is not None:
            ax.errorbar([0.0], [s["epsilon_thin"]], yerr=[s["error"] or 0.0], fmt="s",
                        color=col, capsize=3, ms=5)
        if s.get("structure_epsilon") is not None:
            ax.plot([0.0], [s["structure_epsilon"]], "D", mfc="none", color=col, ms=8)
    ax.plot([], [], "ks", label="ε*_s at w = 0 (extrapolated)")
    ax.plot([], [], "kD", mfc="none", label="structure route at w = 0")
    n = next((s["points"][0]["beads"] for s in result["states"] if s["points"]), None)
    ax.set_xlabel(f"w/L (tube model, N = {n})" if n else "w/L")
    ax.set_ylabel("ε = E L / C")
    ax.set_xlim(-0.03 * (wmax or 1.0), (wmax or 1.0) * 1.06)
    ax.set_title(f"{result.get('knot', '')}: every state followed to w = 0")
    ax.legend(fontsize=7)
    return ax
