"""A tiny report builder that writes the same document as Markdown and as self-contained HTML.

>>> doc = Document("3_1")
>>> _ = doc.paragraph("Energy **ε = 83.0** with `N = 150` beads, bound $8 pi^2$.")
>>> _ = doc.table(["knot", "ε"], [["3_1", 83.03]])
>>> print(doc.to_markdown())  # doctest: +NORMALIZE_WHITESPACE
# 3_1
<BLANKLINE>
Energy **ε = 83.0** with `N = 150` beads, bound $8 pi^2$.
<BLANKLINE>
| knot | ε |
| --- | ---: |
| 3_1 | 83.03 |
<BLANKLINE>

Inline markup in paragraphs, bullets, table cells and captions: ```code```, ``**bold**`` and
``$math$`` (kept as text, with its dollars; no renderer is needed). Everything else is plain text:
in HTML all text is escaped with :func:`html.escape`; in Markdown ``<``, ``>`` and ``&`` outside
code spans and math are written as entities and the characters of Markdown syntax are
backslash-escaped, so that plain text can never turn into raw HTML, emphasis or links.

Images are referenced, not embedded: a relative path is relative to the report's folder; an
absolute path is rewritten relative to the folder given to :meth:`Document.write` (or to the
``base`` of :meth:`Document.to_markdown` / :meth:`Document.to_html`).
"""

from __future__ import annotations

import html
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import quote

from stiffknots.fileio import write_text

__all__ = ["Document", "format_cell"]

_INLINE = re.compile(r"(`[^`\n]+`)|(\*\*[^*\n]+?\*\*)|(\$[^$\n]+\$)")

_CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; color: #222;
       background: #fff; margin: 0; line-height: 1.5; }
main { max-width: 60rem; margin: 0 auto; padding: 1.5rem 2rem 3rem; }
h1, h2, h3, h4, h5, h6 { line-height: 1.25; margin: 1.6em 0 0.5em; }
h1 { border-bottom: 2px solid #ddd; padding-bottom: 0.3em; margin-top: 0.5em; }
h2 { border-bottom: 1px solid #eee; padding-bottom: 0.2em; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.92em; }
th, td { border: 1px solid #bbb; padding: 0.3em 0.7em; vertical-align: top; }
th { background: #f0f2f5; text-align: left; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
tr:nth-child(even) td { background: #fafafa; }
code { font-family: "SFMono-Regular", Menlo, Consolas, monospace; font-size: 0.9em;
       background: #f3f3f3; padding: 0.05em 0.3em; border-radius: 3px; }
pre { background: #f6f8fa; border: 1px solid #e1e4e8; padding: 0.8em 1em; overflow-x: auto;
      border-radius: 4px; }
pre code { background: none; padding: 0; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #555; margin-top: 0.3em; }
.math { font-style: italic; font-family: "Times New Roman", serif; }
"""


def format_cell(value) -> str:
    """Text of a table cell: None as an em dash, floats to 6 significant digits.

    Integers and strings are written as they are, booleans as "yes"/"no", non-finite floats as
    "nan", "inf", "-inf".
    """
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        return f"{value:.6g}"
    if hasattr(value, "item") and not isinstance(value, str):  # numpy scalars
        try:
            return format_cell(value.item())
        except (TypeError, ValueError):
            pass
    return str(value)


def _is_number(value) -> bool:
    if isinstance(value, bool):
        return False
    if isinstance(value, int | float):
        return True
    return hasattr(value, "dtype") and getattr(value.dtype, "kind", "") in "iuf"


_MD_ORDERED = re.compile(r"^(\d{1,9})([.)])(\s|$)")


def _md_text(text: str) -> str:
    """Plain text for Markdown: no raw HTML, entities or emphasis can come out of it.

    ``&``, ``<``, ``>`` become entities; ``\\``, ``*``, `````, ``[``, ``]`` and underscores at a
    word boundary are backslash-escaped (intraword underscores, as in ``3_1``, are never
    emphasis in CommonMark and are kept).
    """
    text = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    text = re.sub(r"([\\*`\[\]])", r"\\\1", text)
    return re.sub(r"(?<![0-9A-Za-z])_|_(?![0-9A-Za-z])", r"\\_", text)


def _inline_md(text: str) -> str:
    """Markdown of text with inline markup; code spans and math kept, plain text escaped."""
    out, pos = [], 0
    for m in _INLINE.finditer(text):
        out.append(_md_text(text[pos:m.start()]))
        tok = m.group(0)
        if m.group(2):
            out.append(f"**{_inline_md(tok[2:-2])}**")
        else:
            out.append(tok)
        pos = m.end()
    out.append(_md_text(text[pos:]))
    return "".join(out)


def _md_block(text: str) -> str:
    """:func:`_inline_md` of a whole block (paragraph, list item): it must not start like a
    heading, a list item or a thematic break."""
    s = _inline_md(text)
    if s[:1] in ("#", "-", "+"):
        return "\\" + s
    m = _MD_ORDERED.match(s)
    if m:
        return m.group(1) + "\\" + s[len(m.group(1)):]
    return s


def _inline_html(text: str) -> str:
    """HTML of text with inline markup (`code`, **bold**, $math$); all text escaped."""
    out, pos = [], 0
    for m in _INLINE.finditer(text):
        out.append(html.escape(text[pos:m.start()]))
        tok = m.group(0)
        if m.group(1):
            out.append(f"<code>{html.escape(tok[1:-1])}</code>")
        elif m.group(2):
            out.append(f"<strong>{_inline_html(tok[2:-2])}</strong>")
        else:
            out.append(f'<span class="math">{html.escape(tok)}</span>')
        pos = m.end()
    out.append(html.escape(text[pos:]))
    return "".join(out)


def _plain(text: str) -> str:
    """Text without inline markup (for alternative texts): `a` → a, **b** → b, $m$ kept."""
    def strip(m: re.Match) -> str:
        tok = m.group(0)
        if m.group(1):
            return tok[1:-1]
        if m.group(2):
            return _plain(tok[2:-2])
        return tok

    return _INLINE.sub(strip, text)


def _md_cell(value) -> str:
    s = _inline_md(format_cell(value))
    return s.replace("|", "\\|").replace("\r", " ").replace("\n", "<br>")


@dataclass
class _Block:
    kind: str
    data: dict = field(default_factory=dict)


class Document:
    """A report: a title and a sequence of blocks, written as Markdown and HTML.

    Parameters
    ----------
    title : str
        The title (level-1 heading, and the HTML page title).

    Notes
    -----
    All block methods return the document, so calls can be chained.
    """

    def __init__(self, title: str):
        if not isinstance(title, str) or not title.strip():
            raise ValueError("the document title must be a non-empty string")
        self.title = title
        self.blocks: list[_Block] = []

    # ------------------------------------------------------------------ building
    def heading(self, text: str, level: int = 2) -> Document:
        """Add a heading; ``level`` 1–6 (the title is the level-1 heading)."""
        if isinstance(level, bool) or not isinstance(level, int) or not 1 <= level <= 6:
            raise ValueError(f"heading level must be an integer 1–6, got {level!r}")
        self.blocks.append(_Block("heading", {"text": str(text), "level": level}))
        return self

    def paragraph(self, text: str) -> Document:
        """Add a paragraph of text with inline markup (`code`, **bold**, $math$)."""
        self.blocks.append(_Block("paragraph", {"text": " ".join(str(text).split())}))
        return self

    def table(self, header: Sequence, rows: Iterable[Sequence], *,
              align: Sequence[str] | None = None) -> Document:
        """Add a table.

        Parameters
        ----------
        header : sequence
            Column titles.
        rows : iterable of sequences
            One sequence per row, as long as ``header``. Cells are formatted with
            :func:`format_cell` (None → "—", floats to 6 significant digits).
        align : sequence of {"left", "right"}, optional
            Column alignment; default right for columns whose cells are all numbers (or None).

        Raises
        ------
        ValueError
            If the header is empty or a row has the wrong length.
        """
        header = [str(h) for h in header]
        if not header:
            raise ValueError("a table needs at least one column")
        rows = [list(r) for r in rows]
        for k, r in enumerate(rows):
            if len(r) != len(header):
                raise ValueError(f"table row {k} has {len(r)} cells, the header {len(header)}")
        if align is None:
            align = []
            for c in range(len(header)):
                vals = [r[c] for r in rows if r[c] is not None]
                align.append("right" if vals and all(_is_number(v) for v in vals) else "left")
        else:
            align = list(align)
            if len(align) != len(header) or any(a not in ("left", "right") for a in align):
                raise ValueError(f"align must give 'left' or 'right' for each of the "
                                 f"{len(header)} columns, got {align}")
        self.blocks.append(_Block("table", {"header": header, "rows": rows, "align": align}))
        return self

    def image(self, path, caption: str = "", width: int | str | None = None) -> Document:
        """Add an image (referenced by path, not embedded) with a caption.

        Parameters
        ----------
        path : str or Path
            Relative to the report folder, or absolute (made relative on writing).
        caption : str
            Caption, with inline markup; also the image's alternative text.
        width : int or str, optional
            Display width: pixels (int) or a CSS length ("60%").
        """
        self.blocks.append(_Block("image", {"path": os.fspath(path), "caption": str(caption),
                                            "width": width}))
        return self

    def code(self, text: str, language: str = "") -> Document:
        """Add a preformatted block (a command, a listing)."""
        self.blocks.append(_Block("code", {"text": str(text).rstrip("\n"),
                                           "language": str(language)}))
        return self

    def bullets(self, items: Iterable) -> Document:
        """Add a bulleted list; each item is text with inline markup."""
        self.blocks.append(_Block("bullets", {"items": [" ".join(str(i).split())
                                                        for i in items]}))
        return self

    # ------------------------------------------------------------------ output
    @staticmethod
    def _src(path: str, base) -> str:
        p = Path(path)
        if base is not None and p.is_absolute():
            p = Path(os.path.relpath(p, Path(base).resolve()))
        return p.as_posix()

    def to_markdown(self, base=None) -> str:
        """The document as (CommonMark / GitHub) Markdown.

        Parameters
        ----------
        base : str or Path, optional
            Folder the Markdown file will be in: absolute image paths are made relative to it.
        """
        parts = [f"# {_inline_md(self.title)}"]
        for b in self.blocks:
            d = b.data
            if b.kind == "heading":
                parts.append(f"{'#' * d['level']} {_inline_md(d['text'])}")
            elif b.kind == "paragraph":
                parts.append(_md_block(d["text"]))
            elif b.kind == "table":
                lines = ["| " + " | ".join(_md_cell(h) for h in d["header"]) + " |",
                         "| " + " | ".join("---:" if a == "right" else "---"
                                           for a in d["align"]) + " |"]
                lines += ["| " + " | ".join(_md_cell(c) for c in r) + " |" for r in d["rows"]]
                parts.append("\n".join(lines))
            elif b.kind == "image":
                src = quote(self._src(d["path"], base), safe="/:.-_~")
                alt = _md_text(_plain(d["caption"]))
                if d["width"] is not None:
                    img = (f'<img src="{html.escape(src)}" '
                           f'alt="{html.escape(_plain(d["caption"]))}" '
                           f'width="{html.escape(str(d["width"]))}">')
                else:
                    img = f"![{alt}]({src})"
                parts.append(img + (f"\n\n*{_inline_md(d['caption'])}*" if d["caption"]
                                    else ""))
            elif b.kind == "code":
                text = d["text"]
                run = max((len(m) for m in re.findall(r"`+", text)), default=0)
                fence = "`" * max(3, run + 1)
                parts.append(f"{fence}{d['language']}\n{text}\n{fence}")
            elif b.kind == "bullets":
                parts.append("\n".join(f"- {_md_block(i)}" for i in d["items"]))
        return "\n\n".join(parts) + "\n"

    def to_html(self, base=None) -> str:
        """The document as one self-contained HTML page (inline CSS; images by relative path,
        made relative to the folder ``base`` the page will be in, as for :meth:`to_markdown`).
        """
        body = [f"<h1>{_inline_html(self.title)}</h1>"]
        for b in self.blocks:
            d = b.data
            if b.kind == "heading":
                lv = d["level"]
                body.append(f"<h{lv}>{_inline_html(d['text'])}</h{lv}>")
            elif b.kind == "paragraph":
                body.append(f"<p>{_inline_html(d['text'])}</p>")
            elif b.kind == "table":
                def cls(a):
                    return ' class="num"' if a == "right" else ""
                head = "".join(f"<th{cls(a)}>{_inline_html(h)}</th>"
                               for h, a in zip(d["header"], d["align"], strict=True))
                rows = "\n".join(
                    "<tr>" + "".join(f"<td{cls(a)}>{_inline_html(format_cell(c))}</td>"
                                     for c, a in zip(r, d["align"], strict=True)) + "</tr>"
                    for r in d["rows"])
                body.append(f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{rows}\n"
                            "</tbody>\n</table>")
            elif b.kind == "image":
                src = quote(self._src(d["path"], base), safe="/:.-_~")
                w = d["width"]
                style = ""
                if w is not None:
                    w = f"{w}px" if isinstance(w, int | float) else str(w)
                    style = f' style="width: {html.escape(w)}"'
                cap = (f"\n<figcaption>{_inline_html(d['caption'])}</figcaption>"
                       if d["caption"] else "")
                body.append(f'<figure>\n<img src="{html.escape(src)}" '
                            f'alt="{html.escape(_plain(d["caption"]))}"{style}>{cap}\n</figure>')
            elif b.kind == "code":
                lang = (f' class="language-{html.escape(d["language"])}"'
                        if d["language"] else "")
                body.append(f"<pre><code{lang}>{html.escape(d['text'])}</code></pre>")
            elif b.kind == "bullets":
                items = "\n".join(f"<li>{_inline_html(i)}</li>" for i in d["items"])
                body.append(f"<ul>\n{items}\n</ul>")
        return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                f"<title>{html.escape(self.title)}</title>\n<style>{_CSS}</style>\n</head>\n"
                "<body>\n<main>\n" + "\n".join(body) + "\n</main>\n</body>\n</html>\n")

    def write(self, folder, stem: str = "report") -> dict[str, Path]:
        """Write ``{stem}.md`` and ``{stem}.html`` into ``folder`` (created if needed).

        Returns
        -------
        dict
            ``{"markdown": path, "html": path}``.
        """
        folder = Path(folder)
        if not stem or any(c in stem for c in "/\\"):
            raise ValueError(f"stem must be a plain file name without a suffix, got {stem!r}")
        folder.mkdir(parents=True, exist_ok=True)
        md = folder / f"{stem}.md"
        ht = folder / f"{stem}.html"
        write_text(md, self.to_markdown(base=folder))  # atomically: never a half report
        write_text(ht, self.to_html(base=folder))
        return {"markdown": md, "html": ht}
