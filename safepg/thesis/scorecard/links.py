"""Links from the scorecard's rows to the book: the book's folder, its headings' ids, :func:`book_link`."""

from __future__ import annotations

import json
import re
from functools import cache
from pathlib import Path

# The book sits beside the top-level package: as many levels up as this module's dotted name is deep.
BOOK = Path(__file__).resolve().parents[__name__.count(".")] / "book"


def heading_id(text: str) -> str:
    """The HTML id Sphinx gives a section with this (MyST) heading text."""
    from docutils.nodes import make_id

    return make_id(text.replace("$", ""))


@cache
def headings(page: str, book: Path = BOOK) -> tuple[tuple[int, str], ...]:
    """(level, text) of the Markdown headings of ``book/page.ipynb``, in order."""
    path = book / f"{page}.ipynb"
    if not path.exists():
        return ()
    nb = json.loads(path.read_text())
    out = []
    for c in nb.get("cells", []):
        if c.get("cell_type") != "markdown":
            continue
        src = "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
        in_fence = False
        for line in src.splitlines():
            if line.lstrip().startswith(("```", ":::")):
                in_fence = not in_fence
            m = None if in_fence else re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
            if m:
                out.append((len(m.group(1)), m.group(2)))
    return tuple(out)


def book_link(page: str, heading: str | None = None, book: Path = BOOK) -> str:
    """``page.html#anchor`` of the first heading of ``book/page.ipynb`` containing ``heading``.

    The anchor follows the chapters' headings as they are edited; a section heading
    (``##`` or deeper) is preferred to the page title, which often names every table of
    the chapter. Without a match (or without ``heading``) the link is the page itself.
    """
    if heading:
        matches = [(level, text) for level, text in headings(page, book) if heading.lower() in text.lower()]
        if matches:
            sections = [m for m in matches if m[0] > 1]
            return f"{page}.html#{heading_id((sections or matches)[0][1])}"
    return f"{page}.html"
