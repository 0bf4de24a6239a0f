"""The front page (``book/intro``) quotes numbers that the chapters glue.

Its ``{glue:text}`scorecard.ipynb::n_reproduced``` roles are filled when the page is written, from
the chapters' glue caches; Sphinx rewrites a page only when its own source changes. Here the
front page is read again whenever any other page is, so its numbers follow the chapters'.
"""

from __future__ import annotations

from typing import Any

FRONT_PAGE = "book/intro"


def _outdated(app: Any, env: Any, added: set[str], changed: set[str], removed: set[str]) -> list[str]:
    if (added | changed | removed) - {FRONT_PAGE} and FRONT_PAGE in env.found_docs:
        return [FRONT_PAGE]
    return []


def setup(app: Any) -> dict[str, Any]:
    app.connect("env-get-outdated", _outdated)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
