"""Sphinx configuration of the stiffknots documentation (``make docs``).

The pages are Markdown (myst-parser); the API reference is generated from the numpy-style
docstrings (autodoc, napoleon, autosummary, recursive over the package, so it follows the
modules as they are renamed or split). No network at build time: no intersphinx, no linkcheck.
"""

from __future__ import annotations

import sys
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

from stiffknots import __version__  # noqa: E402

# ``python -m stiffknots.cli`` runs the command line when imported: autosummary's recursion
# imports every module, so this one is replaced by a marked stub it skips.
_cli_main = types.ModuleType("stiffknots.cli.__main__")
_cli_main.__sphinx_mock__ = True
sys.modules.setdefault("stiffknots.cli.__main__", _cli_main)

project = "stiffknots"
author = "stiffknots developers"
copyright = "stiffknots developers, GPL-3.0-or-later"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "README.md"]
templates_path = ["_templates"]

# --- Markdown ------------------------------------------------------------------------------
myst_enable_extensions = ["colon_fence", "deflist", "attrs_inline"]
myst_heading_anchors = 3  # links such as methods/search.md#rounds-and-verdicts resolve

# --- API reference -------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = False
# each object is documented once, in the module that defines it (a package's re-exports and a
# module's ``__all__`` of imported names would document it twice)
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
# numpy style: the docstrings carry the types, in words ("(N, 3) float array"); the signature
# shows the names and defaults only, and the types are rendered as text, not cross-references
# (nitpicky mode then checks the references that can be checked: roles such as :func:).
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_mock_imports: list[str] = []
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_param = False
napoleon_use_keyword = False

# No intersphinx (no network at build time): references to the types of other packages and of
# the standard library cannot resolve, so nitpicky mode ignores them; references into
# stiffknots itself are still checked.
nitpick_ignore_regex = [
    ("py:.*", r"(numpy|np|scipy|numba|matplotlib|mpl_toolkits|plotly|typer|click|rich"
              r"|distributed|dask|mpmath|topoly|snappy|spherogram|database_knotinfo"
              r"|knot_floer_homology|threadpoolctl|sqlite3|pathlib|collections|typing"
              r"|concurrent|multiprocessing|threading|subprocess|io|os|enum|dataclasses|abc"
              r"|types|datetime|signal|random|json|html|math|functools|itertools|re|time)"
              r"(\..*)?"),
    ("py:class", r"(int|float|str|bool|bytes|complex|object|list|dict|tuple|set|frozenset"
                 r"|type|callable|Callable|Iterable|Iterator|Sequence|Mapping|Any|None"
                 r"|Path|optional|array_like|array-like|ndarray|default .*|shape .*"
                 r"|Generator|Hashable|Literal\[.*\]|TextIO|BinaryIO|Exception"
                 r"|NDArray|ArrayLike|Self)"),
]

# --- HTML ----------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"stiffknots {release}"
html_static_path: list[str] = []
html_show_sourcelink = False


def setup(app):
    """Module and class attributes and properties are documented in prose (``#:`` comments,
    one-line docstrings). Napoleon reads the text before a first colon of such a docstring as
    its type (a Google-style inline type), which numpy style has not: they bypass napoleon."""
    from sphinx.ext.napoleon import _process_docstring

    for listener in list(app.events.listeners.get("autodoc-process-docstring", [])):
        if listener.handler is _process_docstring:
            app.disconnect(listener.id)

    def process(app, what, name, obj, options, lines):
        if what not in ("data", "attribute", "property"):
            _process_docstring(app, what, name, obj, options, lines)

    app.connect("autodoc-process-docstring", process)
