"""The page object both browser test files drive (fixtures are in tests/conftest.py)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


class OfflinePage:
    """A page opened from disk that records console errors and blocks any non-file request."""

    def __init__(self, browser: Any, path: Path, width: int = 1200, height: int = 1400) -> None:
        self.page = browser.new_page(viewport={"width": width, "height": height})
        self.errors: list[str] = []
        self.remote: list[str] = []
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.route("**/*", self._route)
        self.page.goto(path.as_uri())
        self.page.wait_for_load_state("load")

    def _route(self, route: Any) -> None:
        if route.request.url.startswith("file://"):
            route.continue_()
        else:
            self.remote.append(route.request.url)
            route.abort()

    def typeset(self) -> None:
        """Wait until MathJax has typeset the page."""
        self.page.wait_for_function("() => window.MathJax && MathJax.startup && MathJax.startup.promise",
                                    timeout=20_000)
        self.page.evaluate("() => MathJax.startup.promise")

    def values(self, index: int = 0) -> dict:
        """The JSON an explorer writes after each redraw (its ``.safepg-values`` element)."""
        return json.loads(self.page.locator(".safepg-values").nth(index).text_content())
