"""The pieces of HTML both kinds of atlas page use: escaping, numbers, the page head with the
style sheet, and the files of ``stiffknots/report/assets`` (the pages' CSS and
scripts, inlined into every page so that it opens from disk)."""

from __future__ import annotations

import functools
import html
import json
from importlib.resources import files
from typing import Any

from stiffknots._json import to_plain

__all__ = ["asset", "audit_note", "esc", "json_script", "num", "page_head", "yes_no"]


@functools.cache
def asset(name: str) -> str:
    """The text of the file ``name`` of ``stiffknots/report/assets`` (shipped as package
    data)."""
    return (files("stiffknots.report") / "assets" / name).read_text(encoding="utf-8")


def esc(x: Any) -> str:
    """Text escaped for HTML (quotes too: safe inside an attribute)."""
    return html.escape(str(x), quote=True)


def num(x: float | None, digits: int = 2) -> str:
    """A number with ``digits`` decimals; "—" for None."""
    return "—" if x is None else f"{x:.{digits}f}"


def yes_no(v: bool | None) -> str:
    """"yes", "no", or "—" for unknown."""
    return "—" if v is None else ("yes" if v else "no")


def audit_note(audit: str | None) -> str:
    """The audit of a verdict beside it (``<br><small class="audit">audit: held</small>``;
    nothing where no audit was made)."""
    if not audit:
        return ""
    return f'<br><small class="audit">audit: {esc(audit)}</small>'


def json_script(obj: Any) -> str:
    """JSON for a ``<script>`` element (no ``</script>`` can close it early)."""
    s = json.dumps(to_plain(obj), ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    return s.replace("<", "\\u003c")  # "<" occurs only inside JSON strings


def page_head(title: str, prefix: str, extra_css: str, plotly: bool = True) -> str:
    """The start of a page up to ``</head>``: the style sheet inline, plotly.js from
    ``prefix`` (the folder of the atlas, relative to the page) unless ``plotly`` is False (the
    index loads it itself once its table is shown)."""
    script = f"<script src=\"{prefix}plotly.min.js\"></script>\n" if plotly else ""
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        f"<title>{esc(title)}</title>\n<link rel=\"icon\" href=\"data:,\">\n"
        f"<style>\n{asset('atlas.css')}\n{extra_css}</style>\n"
        f"{script}</head>\n"
    )
