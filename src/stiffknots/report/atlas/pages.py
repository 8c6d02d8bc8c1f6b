"""Writing the atlas: its pages, plotly.js, the thumbnails and ``atlas.json`` into one folder."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from stiffknots._json import to_plain
from stiffknots._version import __version__
from stiffknots.report.atlas.figures import eps_figure, thumbnail_png
from stiffknots.report.atlas.index_page import index_page
from stiffknots.report.atlas.knot_page import knot_page
from stiffknots.report.atlas.schema import family_statistics, model_names, parse_knots

__all__ = ["DEFAULT_TITLE", "write_atlas"]

DEFAULT_TITLE = "Atlas of stiff knots"


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
        One dict per knot, in the order of the table, in the schema of
        :mod:`stiffknots.report.atlas.schema`.
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
    ks = parse_knots(knots)
    names = model_names(ks)
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
                (tdir / fname).write_bytes(thumbnail_png(m.ground.coords, m.ground.closed,
                                                         m.ground.radius))
                thumbs[(k.name, m.name)] = f"thumbs/{fname}"

    fig = eps_figure(ks, models, default_model)
    meta_all = {**(meta or {}), "stiffknots": __version__, "plotly.js": plotly_version}
    index = out / "index.html"
    index.write_text(index_page(ks, models, default_model, families, title, meta_all, thumbs,
                                fig), encoding="utf-8")
    for j, k in enumerate(ks):
        page = knot_page(k, models, default_model, title, ks[j - 1] if j > 0 else None,
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
