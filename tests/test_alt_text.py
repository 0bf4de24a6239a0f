"""Every figure of the book has alt text that says what it shows.

The figures are notebook cells with ``mystnb: figure:`` metadata (caption and name); myst-nb
1.4 puts ``mystnb: image: alt:`` on the figure's ``<img>`` (without it the alt is the image's
file path). The alt text must describe the plot -- what is drawn against what and what one
sees -- not restate the figure's number or name.
"""

import re
from pathlib import Path

import nbformat
import pytest

BOOK = Path(__file__).resolve().parent.parent / "book"


def _figure_cells():
    for path in sorted(BOOK.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        for cell in nb.cells:
            meta = cell.metadata.get("mystnb", {})
            if "figure" in meta:
                yield path.name, cell, meta


FIGURES = list(_figure_cells())


def test_the_book_has_figures():
    assert len(FIGURES) >= 20


@pytest.mark.parametrize(
    "notebook,cell,meta", FIGURES, ids=[f"{n}:{m['figure'].get('name', c.id)}" for n, c, m in FIGURES]
)
def test_figure_has_descriptive_alt_text(notebook, cell, meta):
    alt = (meta.get("image") or {}).get("alt", "")
    assert isinstance(alt, str) and alt.strip(), f"{notebook} cell {cell.id}: no mystnb.image.alt"
    name = meta["figure"].get("name", "")
    caption = meta["figure"].get("caption", "")
    number_only = re.fullmatch(r"\s*(fig(ure)?\.?\s*)?[\w.-]*\d[\w.-]*\s*\.?\s*", alt, re.I)
    assert not number_only, f"{notebook}:{name}: the alt text is only a number: {alt!r}"
    assert alt.strip().lower() not in {name.lower(), caption.strip().lower()}
    # a sentence about the plot: long enough to name the axes and what they show
    words = alt.split()
    assert len(words) >= 15, f"{notebook}:{name}: alt text too short to describe the plot: {alt!r}"
    assert re.search(r"\bagainst\b|\bover\b|\bper\b", alt), f"{notebook}:{name}: say what is plotted against what"
    # plain text: screen readers read alt text verbatim, so no TeX or MyST roles
    assert "$" not in alt and "{" not in alt and "\\" not in alt, f"{notebook}:{name}: TeX or roles in alt"
