"""Rewrite every page when the book's own CSS or JavaScript changes.

Sphinx copies ``html_static_path`` only when it writes at least one page, and it decides
what to write from the sources and the configuration, not from the static files. An edit to
``book/_static_safepg/safepg-book.js`` alone would therefore never reach ``_build/html``
("no targets are out of date"). The files' digest becomes a configuration value of the
``html`` kind: when it changes, Sphinx writes every page again (without reading the
notebooks again), which copies the new files and gives each page the new ``?v=`` checksum.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

#: The static folders that are the book's own (book/_vendor is pinned and vendored).
OWN_STATIC = ("book/_static_safepg",)


def static_digest(folders: list[Path]) -> str:
    """SHA-256 over every file's path (relative to its folder) and bytes, in sorted order."""
    h = hashlib.sha256()
    for folder in folders:
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            h.update(str(path.relative_to(folder)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def _set_digest(app: Any, config: Any) -> None:
    config.safepg_static_digest = static_digest([Path(app.confdir) / f for f in OWN_STATIC])


def setup(app: Any) -> dict[str, Any]:
    app.add_config_value("safepg_static_digest", "", "html")
    app.connect("config-inited", _set_digest)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
