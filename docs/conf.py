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


def _prefer_submodules() -> None:
    """A package that imports a function or object under the name of one of its submodules
    (``stiffknots.problems.tightest``, the function; ``stiffknots.cli.app``, the Typer app;
    ``stiffknots.cli.main``) hides that submodule from autosummary, which reads
    ``package.name`` as an attribute first: the recursion would document the function under
    the module's name and never the module. A name that imports as a stiffknots module is
    read as that module."""
    import importlib

    from sphinx.ext import autosummary

    by_attribute = autosummary._import_by_name

    def _import_by_name(name: str, grouped_exception: bool = True):
        if name.startswith("stiffknots."):
            try:
                return importlib.import_module(name), None, name
            except ImportError:
                pass
        return by_attribute(name, grouped_exception)

    autosummary._import_by_name = _import_by_name


_prefer_submodules()

# --- HTML ----------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"stiffknots {release}"
html_static_path: list[str] = []
html_show_sourcelink = False


def _import_dotted(dotted: str):
    """The object a dotted name reaches by importing its longest module prefix, else None."""
    import importlib

    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except Exception:
            continue
        try:
            for attr in parts[k:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _defining_name(obj) -> str | None:
    """Where ``obj`` is defined (``module.qualname``), for a module, class, function, property."""
    if isinstance(obj, types.ModuleType):
        return obj.__name__
    if isinstance(obj, property):
        obj = obj.fget
    obj = getattr(obj, "py_func", obj)  # a numba dispatcher: the Python function it compiles
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if isinstance(module, str) and isinstance(qualname, str):
        return f"{module}.{qualname}"
    return None


def _resolve_through_imports(app, env, node, contnode):
    """Resolve a reference to a name that a stiffknots module or package imports (a package's
    re-export such as ``stiffknots.analysis.classify``, or ``:class:`Chain``` in a module that
    imports it, the type of an attribute included) to the entry of the module that defines it.

    Each object is documented once, where it is defined (``autosummary_imported_members`` off,
    ``ignore-module-all``), but the docstrings name it as a user imports it, from the package;
    this looks the name up the way Python would and links to the defining module's entry. A name
    that does not import, or imports to an object with no entry, still fails (nitpicky)."""
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    if target.startswith(("~", ".")):
        target = target.lstrip("~.")
    modname, clsname = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if modname:
        candidates.insert(0, f"{modname}.{target}")
        if clsname:
            candidates.insert(0, f"{modname}.{clsname}.{target}")
    domain = env.get_domain("py")
    for dotted in candidates:
        if not dotted.startswith("stiffknots."):
            continue
        obj = _import_dotted(dotted)
        defined = _defining_name(obj)
        if defined is None and obj is not None and "." in dotted:
            head, _, last = dotted.rpartition(".")
            owner = _import_dotted(head)
            if isinstance(owner, type) and _defining_name(owner):  # a class's field
                defined = f"{_defining_name(owner)}.{last}"
            else:  # a constant: the documented one of that name that is this very object
                same = [name for name in domain.objects
                        if name.rpartition(".")[2] == last and _import_dotted(name) is obj]
                defined = same[0] if len(same) == 1 else None
        if defined and defined != dotted and defined in domain.objects:
            return domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], defined,
                                       node, contnode)
    return None


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

    app.connect("missing-reference", _resolve_through_imports)
