"""The book's version is the library's: ``safepg.__version__``, shown in every page's footer.

The version is defined once, in ``safepg/__init__.py``; ``pyproject.toml`` reads it
(``dynamic``), ``CITATION.cff`` repeats it under a test, and here it becomes Sphinx's
``version`` and ``release`` and the footer's line.
"""

from __future__ import annotations

from typing import Any

import safepg


def _set_version(app: Any, config: Any) -> None:
    config.version = config.release = safepg.__version__
    options = dict(config.html_theme_options or {})
    footer = options.get("extra_footer") or ""
    line = f'<p class="safepg-version">safepg {safepg.__version__}</p>'
    options["extra_footer"] = footer + line
    config.html_theme_options = options


def setup(app: Any) -> dict[str, Any]:
    app.connect("config-inited", _set_version)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
