"""The page object the browser test files drive, and the pages they walk (fixtures are in tests/conftest.py)."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]


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
        """Wait until MathJax has typeset the page (at once when the page loads no MathJax: Sphinx adds
        it only to pages with maths, such as every page but the References)."""
        if not self.page.evaluate("() => [...document.scripts].some(s => /mathjax/i.test(s.src))"):
            return
        self.page.wait_for_function("() => window.MathJax && MathJax.startup && MathJax.startup.promise",
                                    timeout=20_000)
        self.page.evaluate("() => MathJax.startup.promise")

    def set_theme(self, theme: str) -> None:
        """Switch pydata-sphinx-theme's colour mode (``"light"`` or ``"dark"``) as its toggle does."""
        self.page.evaluate(SET_THEME_JS, theme)

    def audit(self) -> dict[str, Any]:
        """Page-wide layout facts (see :data:`AUDIT_JS`): what sticks out of the main column,
        what is clipped, the visible code and the numbered captions."""
        return self.page.evaluate(AUDIT_JS)

    def values(self, index: int = 0) -> dict:
        """The JSON an explorer writes after each redraw (its ``.safepg-values`` element)."""
        return json.loads(self.page.locator(".safepg-values").nth(index).text_content())


#: Switch the colour mode, then wait until the colour transitions it started have ended (the
#: theme fades colours in about 0.2 s; a contrast check in that fade reads a colour in between).
SET_THEME_JS = """async t => {
  const d = document.documentElement.dataset;
  d.theme = t;
  d.mode = t;
  getComputedStyle(document.body).color;  // apply the new colours now, so their transitions exist
  const fades = document.getAnimations().filter(a => a instanceof CSSTransition);
  await Promise.all(fades.map(a => a.finished.catch(() => null)));  // a cancelled fade rejects
}"""


#: Layout audit of a book page, run in the browser. Returns
#: ``pageOverflow`` (the document scrolls sideways: scrollWidth - clientWidth, px),
#: ``overflowing`` (outermost elements whose box leaves the main column and that no
#: scrolling box inside the column contains), ``clipped`` (boxes with ``overflow-x:
#: hidden`` whose content is cut off), ``scrollNoCue`` (boxes that scroll sideways but were
#: not given the ``safepg-scrollable`` class, i.e. no visible scroll cue), ``code`` (each
#: visible code cell: its source, its number of lines, how many are wider than the box and
#: how many of those are cut off: neither wrapped nor in a box that scrolls with a cue) and
#: ``captions`` (the numbers of the numbered figures and tables, e.g. "Figure 5.3").
AUDIT_JS = r"""() => {
  const art = document.querySelector('article.bd-article') || document.querySelector('main');
  const A = art.getBoundingClientRect();
  const shown = e => (e.checkVisibility ? e.checkVisibility({checkVisibilityCSS: true}) : !!e.offsetParent)
                     && e.getBoundingClientRect().width > 0;
  const ox = e => getComputedStyle(e).overflowX;
  // MathJax's internals (stretchy glyphs clip on purpose) and its hidden copy for screen
  // readers are not what a reader sees: a formula is judged by its mjx-container.
  const skip = e => e.closest('mjx-assistive-mml, .visually-hidden, .sr-only, [hidden], .headerlink')
                    || (e.tagName !== 'MJX-CONTAINER' && e.closest('mjx-container'));
  const outside = r => r.right > A.right + 1 || r.left < A.left - 1;
  const describe = e => (e.tagName.toLowerCase() + (e.className && typeof e.className === 'string'
                          ? '.' + e.className.trim().split(/\s+/).slice(0, 2).join('.') : '')
                         + ' ' + (e.textContent || '').trim().slice(0, 40));
  const overflowing = [];
  for (const el of art.querySelectorAll('*')) {
    if (skip(el)) continue;
    const r = el.getBoundingClientRect();
    if (r.width === 0 || r.height === 0 || !outside(r)) continue;
    // contained by a box inside the column that scrolls or clips?
    let p = el.parentElement, contained = false;
    while (p && p !== art) {
      if (ox(p) !== 'visible' && !outside(p.getBoundingClientRect())) { contained = true; break; }
      p = p.parentElement;
    }
    if (contained) continue;
    const parent = el.parentElement;
    if (parent && parent !== art && outside(parent.getBoundingClientRect()) && ox(parent) === 'visible') continue;
    overflowing.push({what: describe(el), left: Math.round(r.left - A.left), right: Math.round(r.right - A.right)});
  }
  const clipped = [], scrollNoCue = [];
  for (const el of art.querySelectorAll('*')) {
    if (skip(el) || el.clientWidth < 20 || !shown(el)) continue;
    if (el.scrollWidth <= el.clientWidth + 1) continue;
    const o = ox(el);
    if (o === 'hidden' || o === 'clip') clipped.push({what: describe(el), by: el.scrollWidth - el.clientWidth});
    else if ((o === 'auto' || o === 'scroll') && !el.classList.contains('safepg-scrollable'))
      scrollNoCue.push({what: describe(el), by: el.scrollWidth - el.clientWidth});
  }
  const canvas = document.createElement('canvas').getContext('2d');
  const code = [];
  for (const cell of art.querySelectorAll('div.cell')) {
    const input = cell.querySelector('.cell_input pre');
    if (!input || !shown(input)) continue;
    const cs = getComputedStyle(input);
    canvas.font = `${cs.fontSize} ${cs.fontFamily}`;
    const room = input.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight);
    const lines = input.textContent.replace(/\n$/, '').split('\n');
    const wide = lines.filter(l => canvas.measureText(l).width > room + 1).length;
    const wraps = /pre-wrap|break-spaces/.test(cs.whiteSpace);
    const cued = input.classList.contains('safepg-scrollable') || !!input.closest('.safepg-scrollable');
    code.push({source: input.textContent, lines: lines.length, wide, clippedLines: wraps || cued ? 0 : wide});
  }
  const captions = [...art.querySelectorAll('figure .caption-number, table caption .caption-number, '
                                            + 'div.figure .caption-number, .safepg-caption .caption-number')]
    .filter(e => shown(e)).map(e => e.textContent.trim().replace(/[\s:.]+$/, ''));
  const de = document.documentElement;
  return {pageOverflow: Math.max(0, de.scrollWidth - de.clientWidth), column: [Math.round(A.left), Math.round(A.right)],
          overflowing, clipped, scrollNoCue, code, captions};
}"""


def toc_pages() -> list[str]:
    """Document names in ``_toc.yml`` (root first), e.g. ``book/intro``."""
    toc = yaml.safe_load((ROOT / "_toc.yml").read_text())
    out = [toc["root"]]

    def walk(node: Any) -> None:
        if isinstance(node, dict):
            if "file" in node:
                out.append(re.sub(r"\.(md|ipynb)$", "", node["file"]))
            for v in node.values():
                walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)

    walk({k: v for k, v in toc.items() if k != "root"})
    return out
