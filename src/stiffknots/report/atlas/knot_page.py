"""The page of one knot: its data, a table of its states per model and the 3D view of each
state."""

from __future__ import annotations

from stiffknots._version import __version__
from stiffknots.report.atlas.figures import (
    COLORSCALE,
    ZONE_COLOURS,
    branch_figure,
    shape_badge,
    state_mesh,
)
from stiffknots.report.atlas.markup import (
    asset,
    audit_note,
    esc,
    json_script,
    num,
    page_head,
    yes_no,
)
from stiffknots.report.atlas.schema import ZONE_KINDS, KnotRow, StateRow
from stiffknots.report.text import segment_distance_text

__all__ = ["knot_page", "THIN_RADIUS"]

#: tube radius (bonds) of the drawing of a thin-limit chain: its own w is far too thin to see
THIN_RADIUS = 0.25


def _count_text(st: StateRow, replicas: int | None) -> str:
    if st.count is None:
        return "—"
    return f"{st.count} / {replicas}" if replicas else str(st.count)


def knot_page(k: KnotRow, models: list[tuple[str, str]], default: str | None, title: str,
              prev: KnotRow | None, nxt: KnotRow | None) -> str:
    """The HTML of ``knots/<name>.html``: one knot's data and the 3D view of each of its
    states, with links to the previous and the next knot."""
    extra: dict = {}
    parts = [page_head(f"{k.name} — {title}", "../", ""), "<body>\n<main>\n"]
    nav = ['<a href="../index.html">← all knots</a>']
    if prev is not None:
        nav.append(f'<a href="{esc(prev.slug)}.html" rel="prev">‹ {esc(prev.name)}</a>')
    if nxt is not None:
        nav.append(f'<a href="{esc(nxt.slug)}.html" rel="next">{esc(nxt.name)} ›</a>')
    parts.append(f'<nav class="top">{" · ".join(nav)}</nav>\n<h1>{esc(k.name)}</h1>\n')
    facts = [("crossing number n<sub>c</sub>", "—" if k.crossing_number is None
              else str(k.crossing_number)),
             ("bridge number n", "—" if k.n is None else str(k.n)),
             ("braid index i", "—" if k.i is None else str(k.i))]
    if k.lower is not None or k.upper is not None:
        b = f"{num(k.lower)} ≤ ε* ≤ {num(k.upper)}"
        if k.exact:
            b += " (exact: the circular braid is the ground state)"
        elif k.attained_by:
            b += f" (upper bound from {esc(k.attained_by)})"
        facts.append(("bounds, thin limit w/L → 0", b))
    if k.families:
        facts.append(("families", esc(", ".join(k.families))))
    parts.append('<dl class="facts">' + "".join(f"<dt>{a}</dt><dd>{b}</dd>" for a, b in facts)
                 + "</dl>\n")
    if k.note:
        parts.append(f"<p>{esc(k.note)}</p>\n")

    states_js: list[dict] = []
    order = [m for m, _ in models if m in k.models]
    if default in order:
        order.remove(default)
        order.insert(0, default)
    if not order:
        parts.append("<p>No computed states for this knot.</p>\n")
    for mname in order:
        m = k.models[mname]
        parts.append(f'<h2>Model “{esc(mname)}”</h2>\n')
        if m.width:
            parts.append(f'<p class="lede">Width: {esc(m.width)}'
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
                       f"{named}, ε = {num(st.epsilon)} at {st.width or 'unknown width'}")
                states_js.append({**state_mesh(st.coords, closed=st.closed,
                                               radius=st.radius),
                                  "zones": None if st.zones is None else st.zones.tolist(),
                                  "caption": cap,
                                  "label": f"{mname} — {st.role}: "
                                           f"{st.shape_label or 'unclassified'} "
                                           f"(ε = {num(st.epsilon)})"})
                view = '<span class="view-link">view</span>'
            parts.append(
                f'<tr class="state-row" data-state="{idx}" data-model="{esc(mname)}">'
                f"<td>{esc(st.role)}</td>"
                f"<td>{shape_badge(st.shape_label, st.shape, extra)}</td>"
                f"<td>{esc(st.structure) if st.structure else '—'}</td>"
                f'<td class="num">{num(st.epsilon)}</td>'
                f'<td class="num">{num(st.eps_mean)}</td>'
                f'<td class="num">{_count_text(st, m.replicas)}</td>'
                f"<td>{yes_no(st.converged)}{audit_note(st.audit)}</td>"
                f'<td class="num">{segment_distance_text(st.min_segment_distance)}</td>'
                f'<td class="width">{esc(st.width) if st.width else "—"}</td>'
                f"<td>{view}</td></tr>\n")
        parts.append("</tbody></table>\n")
    if k.thin is not None:
        parts.append(_thin_section(k, states_js))
    if states_js:
        parts.append(
            '<h2 id="view-title">3D view</h2>\n<div class="viewer">\n<div class="view-controls">'
            '<label>State <select id="state-select">'
            + "".join(f'<option value="{j}">{esc(s["label"])}</option>'
                      for j, s in enumerate(states_js))
            + '</select></label>'
            + ('<label>Colour <select id="colour-select"><option value="arc">along the '
               'chain</option><option value="zones">by contact structure (§V B)</option>'
               '</select></label>' if any(s["zones"] is not None for s in states_js) else "")
            + '<span id="view-caption"></span></div>\n'
            '<div class="view-frame"><div id="view3d"></div></div>\n'
            '<p class="zone-legend" id="zone-legend" hidden>'
            + "".join(f'<span><i style="background:{c}"></i>{esc(n)}</span>'
                      for c, n in zip(ZONE_COLOURS, ZONE_KINDS, strict=True))
            + '<span id="zone-missing" hidden>(no contact structure for this state: coloured '
              "along the chain)</span></p>\n"
            '<p class="figure-note">Drag to turn, scroll to zoom. The tube is drawn with the '
            "radius given with the state, by default half the bead exclusion distance 1/√2 (so "
            "that beads in contact show touching tubes); its colour runs along the "
            "arclength, or, by contact structure, marks the beads of each line-braid, "
            "point-braid and multiple point (every strand passing through it). Click a row "
            "of the tables to show that state.</p>\n</div>\n")
        parts.append('<script type="application/json" id="states-data">'
                     + json_script(states_js) + "</script>\n"
                     '<script type="application/json" id="colorscale-data">'
                     + json_script(COLORSCALE) + "</script>\n"
                     '<script type="application/json" id="zone-colours-data">'
                     + json_script(list(ZONE_COLOURS)) + "</script>\n"
                     "<script>\n" + asset("atlas-knot.js") + "</script>\n")
    if k.thin is not None:
        parts.append("<script>\n" + asset("atlas-branches.js") + "</script>\n")
    parts.append(f"<footer>stiffknots {esc(__version__)}</footer>\n</main>\n</body>\n</html>\n")
    return "".join(parts)


def _thin_section(k: KnotRow, states_js: list[dict]) -> str:
    """The page's thin-limit section: the states of the tube census followed to w = 0 (a
    table, the branch diagram) and the thin-limit ground's thinnest chain added to the 3D
    view's states (``states_js``)."""
    t = k.thin
    g = None if t["ground"] is None else t["states"][t["ground"]]
    parts = ['<h2 id="thin-title">Thin limit (w → 0)</h2>\n']
    lede = (f"The states of the tube census at w/L = {t['w_over_L']:.2g}, each followed down "
            f"a ladder of widths and extrapolated to w = 0 (budget {esc(t['budget'] or '?')},"
            f" seed {esc(t['seed'])}), and each solved at w = 0 by the structure route (its "
            "structure read from its thinnest chain).")
    if g is not None:
        err = f" ± {g['error']:.2g}" if g["error"] is not None else ""
        lede += (f" Thin-limit ground: <b>{esc(g['name'])}</b>, ε* = "
                 f"{g['epsilon_thin']:.4f}{err}")
        if g["structure_epsilon"] is not None:
            lede += (f"; structure route ({esc(g['structure_name'] or '')}) "
                     f"{g['structure_epsilon']:.4f}, "
                     + {True: "agreeing", False: "not agreeing",
                        None: "not compared"}[g["agree"]])
        lede += "."
        if t["ground"] != 0:
            lede += (f" It is not the ground at the census's width ({esc(t['states'][0]['name'])}"
                     ")" + (f": the branches cross near w/L = {t['crossing']:.2g}"
                            if t["crossing"] is not None else "") + ".")
    else:
        lede += " No state reached w = 0 in its own state (every branch jumped or merged)."
    parts.append(f'<p class="lede">{lede}</p>\n')
    parts.append('<table class="states thin-states"><thead><tr><th>state</th>'
                 f'<th class="num">ε at w/L = {t["w_over_L"]:.2g}</th>'
                 '<th class="num" title="extrapolated along the branch">ε* (branch)</th>'
                 '<th class="num" title="its structure solved at w = 0">ε* (structure)</th>'
                 "<th>structure</th><th>routes</th><th>event</th></tr></thead>\n<tbody>\n")
    for j, s in enumerate(t["states"]):
        mark = " (ground)" if t["ground"] == j else ""
        branch = "—"
        if s["epsilon_thin"] is not None:
            branch = f"{s['epsilon_thin']:.4f}" + (
                f" ± {s['error']:.2g}" if s["error"] is not None else "")
        route = "—" if s["structure_epsilon"] is None else f"{s['structure_epsilon']:.4f}"
        agree = {True: "agree", False: "differ", None: "—"}[s["agree"]]
        view = (f' class="thin-row state-row" data-state="{len(states_js)}"'
                if t["ground"] == j and t.get("chain") is not None else ' class="thin-row"')
        parts.append(
            f'<tr{view} data-thin-state="{j}"><td>{j}: {esc(s["name"])}{mark}</td>'
            f'<td class="num">{num(s["epsilon"])}</td><td class="num">{branch}</td>'
            f'<td class="num">{route}</td>'
            f"<td>{esc(s['structure_name']) if s['structure_name'] else '—'}</td>"
            f"<td>{agree}</td><td>{esc(s['event']) if s['event'] else '—'}</td></tr>\n")
    parts.append("</tbody></table>\n")
    parts.append('<div id="branch-plot" class="plot"></div>\n'
                 '<p class="figure-note">ε against w/L for each state (lines: the points '
                 "fitted; open circles: after the branch left its state). At w = 0: the "
                 "extrapolated ε* with its error (filled) and the structure route (diamond). "
                 "Every ε at w/L &gt; 0 is a finite-width value at the width of its point.</p>\n"
                 '<script type="application/json" id="branch-data">'
                 + json_script(branch_figure(t, k.name)) + "</script>\n")
    ch = t.get("chain")
    if ch is not None and g is not None:
        wl = f"w/L = {ch['w_over_L']:.2g}" if ch["w_over_L"] is not None else "its thinnest width"
        err = f" ± {g['error']:.2g}" if g["error"] is not None else ""
        cap = (f"{k.name}, thin-limit ground {g['name']}, ε* = {g['epsilon_thin']:.2f}{err} "
               f"(w → 0): its chain at {wl}, N = {len(ch['coords'])} (the computed chain "
               "nearest the w = 0 structure)")
        states_js.append({**state_mesh(ch["coords"], closed=True, radius=THIN_RADIUS),
                          "zones": None, "caption": cap,
                          "label": f"thin limit — ground {g['name']} at {wl}"})
    return "".join(parts)

