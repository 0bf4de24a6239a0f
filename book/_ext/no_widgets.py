"""Fail the build when a page carries a Jupyter widget output.

The book loads no widget manager (``nb_ipywidgets_js: {}`` in ``_config.yml``): its
interactive figures are plain HTML and JavaScript (``safepg.explorers.component``), which need no
kernel, no require.js and no CDN. A widget output (for example ``Explorer.interactive()``
left in a chapter) would render as nothing in the static page, silently; this turns that
into a build warning, an error under ``jupyter-book build -W``.
"""

from __future__ import annotations

from typing import Any

from sphinx.util import logging

logger = logging.getLogger(__name__)
WIDGET_MIME = "application/vnd.jupyter.widget-view+json"


def _check(app: Any, pagename: str, templatename: str, context: dict, doctree: Any) -> None:
    if WIDGET_MIME in context.get("body", ""):
        logger.warning(
            "a Jupyter widget output cannot render in the static book (no widget manager is "
            "loaded); display a safepg.explorers.component.Explorer instead of .interactive() or ipywidgets",
            type="safepg", subtype="widget", location=pagename)


def setup(app: Any) -> dict[str, Any]:
    app.connect("html-page-context", _check)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
