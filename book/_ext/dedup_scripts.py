"""Drop duplicate inline scripts from each page.

sphinx-thebe (pulled in by Jupyter Book 1) registers its configuration script once per
read phase, so a page can carry ``const THEBE_JS_URL`` twice, which is a JavaScript
error in the browser. Keeping the first copy of each script fixes it.
"""

from __future__ import annotations

from typing import Any


def _dedup(app: Any, pagename: str, templatename: str, context: dict, doctree: Any) -> None:
    seen, kept = set(), []
    for script in context.get("script_files", []):
        attrs = getattr(script, "attributes", {}) or {}
        key = (getattr(script, "filename", None) or "", attrs.get("body"))
        if key not in seen:
            seen.add(key)
            kept.append(script)
    context["script_files"] = kept



def setup(app: Any) -> dict[str, Any]:
    app.connect("html-page-context", _dedup, priority=900)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
