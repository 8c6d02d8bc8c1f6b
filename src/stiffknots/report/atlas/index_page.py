"""The index page of the atlas: the table of the knots, ε against n², the family statistics
and the knots grouped by ground structure."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from stiffknots.report.atlas.figures import shape_badge
from stiffknots.report.atlas.markup import (
    asset,
    audit_note,
    esc,
    json_script,
    num,
    page_head,
    yes_no,
)
from stiffknots.report.atlas.schema import KnotRow, ModelRow, natural_key
from stiffknots.report.text import segment_distance_text

__all__ = ["PAGE_ROWS", "index_page"]

#: Rows of the knots' table shown at once (the page's default; the reader picks 50 … all).
#: The rows after the first page wait in a ``<template>``: never laid out until shown, so an
#: index of thousands of knots opens as fast as one of a few hundred.
PAGE_ROWS = 200


def _model_css(models: list[ModelRow] | list[tuple[str, str]]) -> str:
    slugs = [m[1] if isinstance(m, tuple) else m.slug for m in models]
    return "\n".join(f'body[data-model="{s}"] .m-{s} {{ display: inline; }}' for s in slugs)


def _per_model_cell(knot: KnotRow, models: list[tuple[str, str]], render, sort_value,
                    cls: str = "") -> str:
    """A table cell with one span per model (CSS shows the active model's)."""
    attrs, spans = [], []
    for mname, mslug in models:
        m = knot.models.get(mname)
        v = sort_value(m) if m is not None else None
        if v is not None:
            attrs.append(f' data-v-{mslug}="{esc(v)}"')
        body = render(m) if m is not None else "—"
        spans.append(f'<span class="m m-{mslug}">{body}</span>')
    c = f' class="{cls}"' if cls else ""
    return f"<td{c}{''.join(attrs)}>{''.join(spans)}</td>"


def index_page(knots: list[KnotRow], models: list[tuple[str, str]], default: str | None,
               families: dict | None, title: str, meta: dict, thumbs: dict,
               fig: dict) -> str:
    """The HTML of ``index.html``: the table of the knots, ε against n² and the family
    statistics (module :mod:`stiffknots.report.atlas`)."""
    extra: dict = {}
    body_model = dict(models).get(default, "") if default else ""
    parts = [page_head(title, "", _model_css(models), plotly=False),
             f'<body data-model="{esc(body_model)}">\n<main>\n<h1>{esc(title)}</h1>\n']
    n_with = sum(1 for k in knots if any(m.ground for m in k.models.values()))
    parts.append(f'<p class="lede">{len(knots)} knots, {n_with} with a computed ground state'
                 + (f"; models: {', '.join(esc(m) for m, _ in models)}" if models else "")
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
                 + "".join(f'<option value="{esc(s)}">{esc(s)}</option>' for s in shapes)
                 + "</select></label>\n")
    if models:
        hidden = "" if len(models) > 1 else ' style="display:none"'
        parts.append(f'<label{hidden}>Model <select id="model">'
                     + "".join(f'<option value="{esc(s)}"{" selected" if m == default else ""}>'
                               f"{esc(m)}</option>" for m, s in models)
                     + "</select></label>\n")
    parts.append('<span id="count"></span>\n</div>\n')

    # table
    cols = [("", None, "", ""), ("knot", "text", "", "knot name"),
            ("n<sub>c</sub>", "num", "num", "crossing number"),
            ("n", "num", "num", "bridge number"), ("i", "num", "num", "braid index"),
            ("bounds (thin limit)", "num", "num",
             "2π²n² ≤ ε* ≤ 2π² min(α²n², i²): bounds on the thin-limit ground-state energy"),
            ("ε* (w → 0)", "num", "num",
             "the thin-limit ground: every state of the knot's tube census followed to w = 0 "
             "(stiffknots atlas --thin), the lowest extrapolated ε* with its error; its state "
             "and structure, whether the structure route (the state's structure solved at "
             "w = 0) agrees, and ≠ where it is not the ground at the census's width"),
            ("ground shape", "text", "", "shape class of the lowest state found"),
            ("ε (ground)", "num", "num",
             "ε = E L / C of the lowest state found, at the width in the next column"),
            ("width", "text", "", "the finite width the ε was computed at"),
            ("converged", "text", "",
             "whether independent searches reached the lowest ε found (within 0.1 %; three "
             "under the tube model, two under the bead rule): a "
             "statement about the searches, not proof that no lower state exists; how often "
             "a deeper search found lower: docs/methods/verdicts.md. audit: what "
             "stiffknots audit found when it searched the verdict again"),
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
            head.append(f'<th{c} data-type="{typ}" aria-sort="none" title="{esc(tip)}">'
                        f'<button type="button">{label}</button></th>')
    parts.append('<div class="table-wrap"><table id="knots" class="atlas">\n<thead><tr>'
                 + "".join(head)
                 + "</tr></thead>\n<tbody>\n")
    for j, k in enumerate(knots):
        if j == PAGE_ROWS:
            parts.append('</tbody>\n</table></div>\n<template id="knots-more">\n')
        href = f"knots/{esc(k.slug)}.html"
        attrs = [f'data-name="{esc(k.name)}"']
        for mname, mslug in models:
            m = k.models.get(mname)
            words = [k.name, *k.families]
            if m is not None:
                words += [s.shape_label for s in m.states if s.shape_label]
                words += [s.structure for s in m.states if s.structure]
                if m.ground is not None and m.ground.shape_label:
                    attrs.append(f'data-shape-{mslug}="{esc(m.ground.shape_label)}"')
            attrs.append(f'data-search-{mslug}="{esc(" ".join(words).lower())}"')
        attrs.append(f'data-search="{esc(" ".join([k.name, *k.families]).lower())}"')
        cells = []
        # thumbnail
        imgs = []
        for mname, mslug in models:
            src = thumbs.get((k.name, mname))
            body = (f'<img src="{esc(src)}" alt="{esc(k.name)} ground state ({esc(mname)})" '
                    f'loading="lazy">' if src else "")
            imgs.append(f'<span class="m m-{mslug}">{body}</span>')
        cells.append(f'<td class="thumb"><a href="{href}">{"".join(imgs)}</a></td>')
        cells.append(f'<td data-v="{esc(natural_key(k.name))}"><a href="{href}">{esc(k.name)}</a>'
                     "</td>")
        for v in (k.crossing_number, k.n, k.i):
            dv = "" if v is None else f' data-v="{v}"'
            cells.append(f'<td class="num"{dv}>{"—" if v is None else v}</td>')
        if k.lower is None and k.upper is None:
            cells.append('<td class="num">—</td>')
        else:
            extra_b = " (exact)" if k.exact else (
                f" ({esc(k.attained_by)})" if k.attained_by else "")
            dv = "" if k.lower is None else f' data-v="{k.lower:.6f}"'
            cells.append(f'<td class="num"{dv}>{num(k.lower)} – {num(k.upper)}'
                         f"{extra_b}</td>")

        cells.append(_thin_cell(k))

        def gs(m: ModelRow):
            return m.ground

        cells.append(_per_model_cell(
            k, models,
            lambda m: shape_badge(gs(m).shape_label, gs(m).shape, extra,
                                  gs(m).structure) if gs(m) else "—",
            lambda m: gs(m).shape_label.lower() if gs(m) and gs(m).shape_label else None))
        cells.append(_per_model_cell(
            k, models, lambda m: num(gs(m).epsilon) if gs(m) else "—",
            lambda m: (f"{gs(m).epsilon:.6f}" if gs(m) and gs(m).epsilon is not None
                       else None), "num"))
        cells.append(_per_model_cell(
            k, models, lambda m: esc(gs(m).width) if gs(m) and gs(m).width else "—",
            lambda m: gs(m).width if gs(m) and gs(m).width else None, "width"))
        cells.append(_per_model_cell(
            k, models, lambda m: (yes_no(gs(m).converged) + audit_note(gs(m).audit))
            if gs(m) else "—",
            lambda m: yes_no(gs(m).converged) if gs(m) and gs(m).converged is not None
            else None))

        def meta_text(m: ModelRow) -> str:
            if not m.metastable:
                return "none" if m.ground is not None else "—"
            return "<br>".join(
                f"{esc(s.shape_label or '?')} ×{s.count if s.count is not None else '?'}"
                f" ({num(s.epsilon)})" for s in m.metastable)

        cells.append(_per_model_cell(k, models, meta_text,
                                     lambda m: str(len(m.metastable)) if m.ground or
                                     m.metastable else None))
        cells.append(_per_model_cell(
            k, models,
            lambda m: segment_distance_text(gs(m).min_segment_distance) if gs(m) else "—",
            lambda m: (f"{gs(m).min_segment_distance:.6f}"
                       if gs(m) and gs(m).min_segment_distance is not None else None), "num"))
        fam = ", ".join(k.families)
        dv = f' data-v="{esc(fam.lower())}"' if fam else ""
        cells.append(f"<td{dv}>{esc(fam) if fam else '—'}</td>")
        parts.append(f"<tr {' '.join(attrs)}>" + "".join(cells) + "</tr>\n")
    parts.append("</template>\n" if len(knots) > PAGE_ROWS else "</tbody>\n</table></div>\n")
    sizes = "".join(f'<option value="{v}"{" selected" if v == PAGE_ROWS else ""}>'
                    f'{v or "all"}</option>' for v in (50, PAGE_ROWS, 1000, 0))
    parts.append(f'<nav id="pager" class="pager" aria-label="pages of the table" '
                 f'data-rows="{PAGE_ROWS}"'
                 + (' hidden' if len(knots) <= PAGE_ROWS else "") + '>\n'
                 '<button type="button" id="page-prev">‹ previous</button>\n'
                 '<span id="page-info"></span>\n'
                 '<button type="button" id="page-next">next ›</button>\n'
                 f'<label>rows per page <select id="page-size">{sizes}</select></label>\n'
                 "</nav>\n")

    # ε against n²
    parts.append('<h2 id="eps-title">ε against n²</h2>\n<div id="eps-plot" class="plot"></div>\n'
                 '<p class="figure-note">Each point is the ground state of one knot at its '
                 "finite width (hover for the knot, its ε and width; click to open its page); "
                 "the points of one n are spread sideways by at most ±0.8 so that none hides "
                 "another. Lines: the thin-limit lower bound 2π²n² and the point braid and loops "
                 "2π²α²n² (an upper bound for every knot); grey bars: the interval "
                 "[2π²n², 2π² min(α²n², i²)] for each (n, i); ticks: the circular braid "
                 "2π²i².</p>\n")
    parts.append('<script type="application/json" id="eps-data">' + json_script(fig)
                 + "</script>\n")

    # family statistics
    if families is not None:
        parts.append(_families_html(families, {k.name: k.slug for k in knots}))

    # meta
    parts.append("<footer>\n<table class=\"meta-list\">\n")
    for key, val in meta.items():
        parts.append(f"<tr><th>{esc(key)}</th><td>{esc(val)}</td></tr>\n")
    parts.append("</table>\n</footer>\n</main>\n<script>\n" + asset("atlas-index.js")
                 + "</script>\n</body>\n</html>\n")
    return "".join(parts)


def _thin_cell(k: KnotRow) -> str:
    """The ε* cell of a knot: the thin-limit ground of its thin stage, or —."""
    t = k.thin
    g = None if t is None or t["ground"] is None else t["states"][t["ground"]]
    if g is None:
        return '<td class="num">—</td>'
    routes = {True: "routes ✓", False: "routes ✗", None: "one route"}[g["agree"]]
    other = (f' · <span class="thin-differs" title="the ground at w/L = {t["w_over_L"]:.2g} '
             f'is {esc(t["states"][0]["name"])}">≠ finite</span>' if t["ground"] != 0 else "")
    struct = g["structure_name"] or g["name"]
    err = f" ± {g['error']:.2g}" if g["error"] is not None else ""
    return (f'<td class="num thin" data-v="{g["epsilon_thin"]:.6f}">'
            f'{num(g["epsilon_thin"])}{err}<br><small>{esc(g["name"])}: {esc(struct)} · '
            f"{routes}{other}</small></td>")


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
    out = [f'<h2 id="families-title">{esc(title)}</h2>\n']
    if families.get("model"):
        out.append(f'<p class="lede">Model: {esc(families["model"])}.</p>\n')
    out.append('<table id="families"><thead><tr><th>shape family</th>'
               + "".join(f'<th class="num">{esc(g["label"])}</th>' for g in groups)
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
        out.append(f"<tr><td>{esc(s)}</td>{''.join(cells)}</tr>\n")
    out.append("<tr><th>knots</th>" + "".join(f'<th class="num">{t}</th>' for t in totals)
               + "</tr>\n</tbody></table>\n")
    if families.get("note"):
        out.append(f'<p class="figure-note">{esc(families["note"])}</p>\n')
    if families.get("structures"):
        out.append(_structures_html(families["structures"], slugs or {}))
    return "".join(out)


def _structures_html(structures: Any, slugs: Mapping[str, str]) -> str:
    """The knots grouped by the contact structure of their ground state (§V B): one row per
    structure, its knots linked to their pages."""
    if not isinstance(structures, Mapping) or not isinstance(structures.get("rows"), Sequence):
        raise ValueError("families['structures'] must be a dict with 'rows': a list of "
                         "{'structure', 'knots', 'shapes', 'epsilon'}")
    out = [f'<h3 id="structures-title">{esc(structures.get("title") or "Ground structures")}'
           "</h3>\n"]
    if structures.get("note"):
        out.append(f'<p class="lede">{esc(structures["note"])}</p>\n')
    out.append('<table id="structures"><thead><tr><th>structure (§V B)</th>'
               '<th class="num">knots</th><th>ground shape</th><th class="num">ε</th>'
               "<th>which</th></tr></thead>\n<tbody>\n")
    for r in structures["rows"]:
        if not isinstance(r, Mapping) or not isinstance(r.get("structure"), str) \
                or not isinstance(r.get("knots"), Sequence) or isinstance(r["knots"], str):
            raise ValueError(f"each structure row needs 'structure' (text) and 'knots' "
                             f"(names), got {r!r}")
        names = [str(n) for n in r["knots"]]
        links = ", ".join(f'<a href="knots/{esc(slugs[n])}.html">{esc(n)}</a>' if n in slugs
                          else esc(n) for n in names)
        shapes = ", ".join(f"{esc(str(k))} {int(v)}" for k, v in (r.get("shapes") or {}).items())
        eps = r.get("epsilon") or []
        eps_text = (f"{num(eps[0])} – {num(eps[1])}" if len(eps) == 2 and eps[0] != eps[1]
                    else num(eps[0]) if eps else "—")
        out.append(f"<tr><td>{esc(r['structure'])}</td><td class=\"num\">{len(names)}</td>"
                   f"<td>{shapes or '—'}</td><td class=\"num\">{eps_text}</td>"
                   f"<td>{links}</td></tr>\n")
    out.append("</tbody></table>\n")
    return "".join(out)

