"""Number figures and tables as the thesis does, from their labels.

Sphinx numbers captioned figures and tables per page (1, 2, ...), which cannot give
the thesis's numbers: Figures 5.1-5.4 are on one page, 5.5-5.8 on the next. Here the
number comes from the label instead, so ``:name: fig-5-3`` is shown, and cited by
``{numref}``, as "Figure 5.3", ``table-5-2`` as "Table 5.2". Figures and tables that the
thesis does not have are labelled with a letter prefix, ``fig-s5-1`` -> "Figure S5.1"
(S for supplementary; ``table-e-1`` -> "Table E.1" on the errata page), so they can never
be mistaken for the thesis's.

A numbered (captioned) figure or table whose label does not follow the pattern, or two
objects with the same number, is a build warning (an error under ``-W``): every number
on the pages is chosen, none is Sphinx's running count.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from sphinx.environment.collectors.toctree import TocTreeCollector
from sphinx.util import logging

logger = logging.getLogger(__name__)

#: ``fig-5-3``, ``table-s5-2``, ``table-e-1``: kind, prefix (chapter digits or letters+digits), number.
LABEL = re.compile(r"^(fig|table)-([a-z]*\d*)-(\d+)$")
KINDS = {"fig": "figure", "table": "table"}


def thesis_number(label: str) -> tuple[str, tuple[str, int]] | None:
    """The figure type and number a label asks for, e.g. ``"fig-s5-1"`` -> ``("figure", ("S5", 1))``;
    None when the label does not follow the pattern."""
    m = LABEL.match(label)
    if m is None or not m[2]:
        return None
    return KINDS[m[1]], (m[2].upper(), int(m[3]))


def _renumber(env: Any) -> None:
    seen: dict[tuple[str, tuple[str, int]], str] = {}
    for docname, kinds in env.toc_fignumbers.items():
        for figtype, numbers in kinds.items():
            if figtype not in ("figure", "table"):
                continue
            for node_id in list(numbers):
                wanted = thesis_number(node_id)
                if wanted is None or wanted[0] != figtype:
                    logger.warning(
                        f"captioned {figtype} {node_id!r} has no thesis-style label: name it "
                        f"{'fig' if figtype == 'figure' else 'table'}-<chapter>-<n> (a thesis number) "
                        f"or {'fig' if figtype == 'figure' else 'table'}-s<chapter>-<n> (ours)",
                        type="safepg", subtype="numbering", location=docname)
                    continue
                if wanted in seen:
                    logger.warning(f"{figtype} number {'.'.join(map(str, wanted[1]))} is used twice "
                                   f"({seen[wanted]} and {docname})", type="safepg", subtype="numbering",
                                   location=docname)
                seen[wanted] = docname
                numbers[node_id] = wanted[1]


def _thesis_figure_numbers(assign: Callable[[Any, Any], list[str]]) -> Callable[[Any, Any], list[str]]:
    """Sphinx's figure numbering, then the thesis's numbers, and the pages whose numbers changed.

    Sphinx rewrites every page whose numbers differ from the last build's. Its own comparison
    sets its running numbers against the thesis numbers stored last time, so they always
    differ and every page with a figure was rewritten on every build: compare the thesis
    numbers with the thesis numbers instead.
    """
    def assign_figure_numbers(self: Any, env: Any) -> list[str]:
        old = env.toc_fignumbers
        assign(self, env)
        _renumber(env)
        return [doc for doc, numbers in env.toc_fignumbers.items() if numbers != old.get(doc)]

    assign_figure_numbers.thesis_numbers = True  # type: ignore[attr-defined]
    return assign_figure_numbers


def setup(app: Any) -> dict[str, Any]:
    if not getattr(TocTreeCollector.assign_figure_numbers, "thesis_numbers", False):
        TocTreeCollector.assign_figure_numbers = _thesis_figure_numbers(TocTreeCollector.assign_figure_numbers)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
