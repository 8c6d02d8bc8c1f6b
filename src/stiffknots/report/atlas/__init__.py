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

The atlas is given plain data in the schema of :mod:`stiffknots.report.atlas.schema`; it never
runs a simulation. Its modules: :mod:`~.schema` (the input, checked, as the rows the pages read),
:mod:`~.figures` (thumbnails, the 3D view's tube, ε against n²), :mod:`~.markup` (the HTML both
pages share, the CSS and scripts of ``stiffknots/report/assets``), :mod:`~.index_page`,
:mod:`~.knot_page` and :mod:`~.pages` (:func:`write_atlas`).
"""

from stiffknots.report.atlas.figures import state_mesh
from stiffknots.report.atlas.pages import DEFAULT_TITLE, write_atlas
from stiffknots.report.atlas.schema import ZONE_KINDS, family_statistics, format_width

__all__ = [
    "DEFAULT_TITLE",
    "ZONE_KINDS",
    "format_width",
    "family_statistics",
    "state_mesh",
    "write_atlas",
]
