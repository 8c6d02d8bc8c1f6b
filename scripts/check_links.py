"""Check the relative links of Markdown files (``make docs``): every link and image that is not
a URL must name a file that exists, and a ``#fragment`` into a Markdown file a heading of it.

Sphinx (myst) checks the links of the pages it builds; this covers what it does not build —
the README, whose links go into docs/ — and checks the pages too. No network: URLs
(``http:``, ``https:``, ``mailto:``) are not followed.

    python scripts/check_links.py README.md docs      # files, or folders searched for *.md
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^(```|~~~)")
SKIP_DIRS = {"_build", "api", "node_modules"}


def anchor(title: str) -> str:
    """The anchor myst (``myst_heading_anchors``) and GitHub give a heading."""
    title = re.sub(r"`|\*\*|\*", "", title.strip().lower())
    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)
    return re.sub(r"[^\w\- ]", "", title).replace(" ", "-")


def _prose(text: str) -> list[tuple[int, str]]:
    """The lines outside fenced code blocks, numbered from 1; inline code removed."""
    lines, fenced = [], False
    for i, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line.lstrip()):
            fenced = not fenced
            continue
        if not fenced:
            lines.append((i, re.sub(r"`[^`]*`", "``", line)))
    return lines


def anchors(path: Path) -> set[str]:
    out, seen = set(), {}
    for _, line in _prose(path.read_text(encoding="utf-8")):
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            a = anchor(m.group(1))
            n = seen.get(a, 0)
            seen[a] = n + 1
            out.add(a if n == 0 else f"{a}-{n}")
    # headings written with inline code keep their text for the anchor
    for line in path.read_text(encoding="utf-8").splitlines():
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            out.add(anchor(m.group(1)))
    return out


def check(path: Path) -> list[str]:
    problems = []
    for lineno, line in _prose(path.read_text(encoding="utf-8")):
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"[a-z][a-z0-9+.-]*:", target, re.I):
                continue  # a URL: not followed
            file, _, frag = target.partition("#")
            dest = (path.parent / file).resolve() if file else path.resolve()
            where = f"{path}:{lineno}: {target}"
            if not dest.exists():
                problems.append(f"{where}: no such file")
            elif frag and dest.suffix == ".md" and frag not in anchors(dest):
                problems.append(f"{where}: no heading #{frag} in {dest.name}")
    return problems


def files(args: list[str]) -> list[Path]:
    out = []
    for a in args:
        p = Path(a)
        if p.is_dir():
            out += sorted(f for f in p.rglob("*.md")
                          if not SKIP_DIRS.intersection(f.relative_to(p).parts))
        else:
            out.append(p)
    return out


def main(argv: list[str]) -> int:
    paths = files(argv or ["README.md", "docs"])
    problems = [p for f in paths for p in check(f)]
    for p in problems:
        print(p)
    print(f"links: {len(paths)} files checked, {len(problems)} broken")
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
