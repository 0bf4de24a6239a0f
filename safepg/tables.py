"""Tables for the book's pages: Markdown that a notebook renders and nbval compares as text.

:func:`markdown_table` writes rows as a Markdown table, optionally captioned and labelled in a MyST
``table`` directive, so that the book numbers it and the prose can cite it with ``{numref}``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


class Markdown(str):
    """Markdown text that renders as Markdown in notebooks and prints as its text
    (so nbval compares the text, not an object's address)."""

    def _repr_markdown_(self) -> str:
        return str(self)

    def __repr__(self) -> str:
        return str(self)


class Table(Markdown):
    """A Markdown table that renders as a table in notebooks and prints as its text
    (so nbval compares the numbers, not an object's address)."""

    def _repr_markdown_(self) -> str:
        return str(self)

    def __repr__(self) -> str:
        return str(self)


def markdown_table(rows: Sequence[dict[str, Any]], columns: Sequence[tuple[str, str, str]],
                   caption: str | None = None, name: str | None = None) -> Table:
    """A Markdown table from rows; ``columns`` holds (key, header, format spec).

    Parameters
    ----------
    rows : one dict per row; a missing or None value prints as "-", a list or tuple
        (a confidence interval) as ``[a; b]``
    columns : (key, header, format spec) per column, in order
    caption : with a caption the table is wrapped in a MyST ``table`` directive (a colon
        fence), so the book numbers it and ``{numref}`` can cite it; in plain Jupyter the
        fence's lines show as text above the table
    name : the table's label, which sets its number in the book: ``"table-5-2"`` is shown
        as Table 5.2, ``"table-s5-1"`` (a table the thesis does not have) as Table S5.1
        (book/_ext/thesis_numbers.py); only with a caption

    Returns
    -------
    Table
        The Markdown text, which renders as a table in notebooks and prints as itself.
    """
    if name is not None and caption is None:
        raise ValueError("name needs a caption: only captioned tables are numbered")
    if caption is not None and "\n" in caption.strip():
        raise ValueError(f"caption must be one line, got {caption!r}")

    def fmt(v: Any, spec: str) -> str:
        if v is None:
            return "-"
        if isinstance(v, (list, tuple)):
            return "[" + "; ".join(fmt(x, spec) for x in v) + "]"
        text = format(v, spec) if spec else str(v)
        return text.replace("|", "\\|")  # a bare | would end the cell

    head = "| " + " | ".join(h.replace("|", "\\|") for _, h, _ in columns) + " |"  # "mean |diff|" too
    sep = "|" + "|".join("---" for _ in columns) + "|"
    body = ["| " + " | ".join(fmt(r.get(k), s) for k, _, s in columns) + " |" for r in rows]
    table = "\n".join([head, sep, *body])
    if caption is None:
        return Table(table)
    options = f":name: {name}\n" if name else ""
    return Table(f":::{{table}} {caption.strip()}\n{options}\n{table}\n:::")


__all__ = ["Markdown", "Table", "markdown_table"]
