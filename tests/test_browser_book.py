"""Every page of the built book, and the LQG explorer driven like a reader would.

Complements ``test_browser.py`` (per-explorer checks against safepg): here every page
listed in ``_toc.yml`` is opened from disk (file://) in headless Chromium and must load
with no JavaScript error, no request leaving the disk, every formula typeset by the
vendored MathJax without a TeX error, and every image decoded. The 1-D LQG explorer is
then moved with the keyboard and its plotted numbers are compared with the 1-D closed form
(derived by hand, see tests/test_lqg.py), written out here independently of safepg, and with safepg's own.
Screenshots (light and dark theme) go to ``_build/screenshots/``.

``test_every_page_reads_well`` opens every page at a desktop (1280 px) and a phone
(390 px) width, in the light and the dark theme, and checks what a reader sees: nothing
sticks out of the text column and the page never scrolls sideways, nothing is cut off
(a box that scrolls sideways carries the book's visible cue), no visible code line is
cut off, no visible code cell only imports, figures keep their proportions and sit on a
light card in the dark theme, explorer axes have distinct tick labels inside the plot, and every figure and
table number of the thesis is a caption on the page it belongs to
(:data:`THESIS_CAPTIONS`), while our own figures and tables carry numbers that cannot be
mistaken for the thesis's. A full-page screenshot of a page at a width and in a theme goes to
``_build/screenshots/`` when a check fails there, or of every page with ``SAFEPG_SCREENSHOTS=1``
(they took more than half of the test's time: 55 of about 100 s). The page-wide tests, these two
and axe-core's audit (``test_every_page_passes_axe``), read one walk over the pages (the ``walk``
fixture): every page is loaded once per width.
"""

from __future__ import annotations

import ast
import json
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from browser_pages import OfflinePage, toc_pages
from test_browser_a11y import report, serious_violations

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
pytestmark = pytest.mark.browser

LQG_TITLE = "1-D LQG: expected performance and estimator variance"


def lqg_performance(theta: float | np.ndarray, sigma: float, gamma: float = 0.9, b: float = 2.0) -> np.ndarray:
    """J(theta) of the 1-D LQG (the closed form derived by hand in tests/test_lqg.py), independent of safepg:
    J = -(b^2/3) P - sigma^2 (0.5 + gamma P) / (1 - gamma), P = 0.5 (1 + theta^2) / (1 - gamma (1 + theta)^2)."""
    theta = np.asarray(theta, dtype=float)
    P = 0.5 * (1 + theta**2) / (1 - gamma * (1 + theta) ** 2)
    return -(b**2 / 3) * P - sigma**2 * (0.5 + gamma * P) / (1 - gamma)


#: What a page must be once loaded from disk (run on every page at every width of the walk).
OFFLINE_JS = r"""() => ({
    math: document.querySelectorAll('.math').length,
    untypeset: [...document.querySelectorAll('.math')].filter(e => !e.querySelector('mjx-container'))
                 .map(e => e.textContent.slice(0, 80)),
    texErrors: [...document.querySelectorAll('mjx-merror')]
                 .map(e => e.getAttribute('data-mjx-error') || e.textContent),
    brokenImages: [...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src),
    explorersNotDrawn: [...document.querySelectorAll('.safepg-explorer')]
                 .filter(e => !e.querySelector('.safepg-values').textContent).length,
    // A Markdown table output that was not rendered shows its |---| row as text (after
    // Sphinx's smart quotes, as an em or en dash).
    rawMarkdownTables: [...document.querySelectorAll('.cell_output')]
                 .filter(e => /\|\s*(---|\u2014|\u2013)\s*\|/.test(e.textContent))
                 .map(e => e.textContent.slice(0, 80)),
})"""


def _offline_problems(pg: OfflinePage) -> dict[str, Any]:
    """A loaded, typeset page's offline problems: untypeset math, TeX errors, broken images, explorers
    not drawn, raw Markdown tables, console errors and requests that left the disk."""
    bad = {k: v for k, v in pg.page.evaluate(OFFLINE_JS).items() if k != "math" and v}
    errors = [e for e in pg.errors if "favicon" not in e]
    if errors:
        bad["console errors"] = errors
    if pg.remote:
        bad["requests that left the disk"] = pg.remote
    return bad


def _luminance(css: str) -> float:
    """WCAG relative luminance of a CSS ``rgb(...)`` colour."""
    c = np.array([int(v) for v in re.findall(r"\d+", css)[:3]]) / 255
    c = np.where(c <= 0.03928, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(c @ [0.2126, 0.7152, 0.0722])


def _contrast(a: str, b: str) -> float:
    """WCAG contrast ratio of two CSS colours (1 to 21)."""
    hi, lo = sorted((_luminance(a), _luminance(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def _find_explorer_page(html: Path, title: str) -> Path:
    for name in toc_pages():
        path = html / f"{name}.html"
        if title in path.read_text(encoding="utf-8"):
            return path
    pytest.fail(f"no page of _toc.yml shows the explorer {title!r}")


def test_lqg_explorer_by_keyboard(browser, book):
    from safepg.envs.lqg import LQG

    env = LQG.thesis_1d()
    pg = OfflinePage(browser, _find_explorer_page(book, LQG_TITLE), width=900)
    root = pg.page.locator(".safepg-explorer", has_text=LQG_TITLE).first
    root.scroll_into_view_if_needed()
    slider = root.locator('input[type="range"][data-param="sigma"]')

    def state() -> dict[str, Any]:
        return json.loads(root.locator(".safepg-values").text_content())

    def check(st: dict[str, Any]) -> None:
        sigma = st["params"]["sigma"]
        J = st["result"]["plots"]["J"]
        theta = np.asarray(J["series"][0]["x"])
        y = np.asarray(J["series"][0]["y"], dtype=float)
        np.testing.assert_allclose(y, lqg_performance(theta, sigma), rtol=1e-9)
        np.testing.assert_allclose(y, [env.performance(t, sigma) for t in theta], rtol=1e-9)
        star = J["markers"][0]
        assert star["x"] == pytest.approx(-0.5884, abs=5e-5)  # the LQR gain, independent of sigma
        assert star["y"] == pytest.approx(float(lqg_performance(star["x"], sigma)), rel=1e-9)
        assert st["result"]["values"]["J_star"] == pytest.approx(star["y"], rel=1e-12)
        # theta* maximises the curve drawn
        assert star["y"] >= y.max() - 1e-12

    SHOTS.mkdir(parents=True, exist_ok=True)
    before = state()
    assert before["params"] == {"sigma": 1.0}
    check(before)
    theta = np.asarray(before["result"]["plots"]["J"]["series"][0]["x"])
    i0 = int(np.argmin(np.abs(theta)))
    assert abs(theta[i0]) < 1e-12
    assert before["result"]["plots"]["J"]["series"][0]["y"][i0] == pytest.approx(-56.667, abs=5e-4)  # J(0)
    root.screenshot(path=str(SHOTS / "lqg-keyboard-sigma-1.0.png"))

    step = float(slider.get_attribute("step"))
    slider.focus()
    for _ in range(10):
        slider.press("ArrowLeft")
    after = state()
    assert after["params"]["sigma"] == pytest.approx(1.0 - 10 * step, abs=1e-12)
    assert root.locator('output[data-show="sigma"]').text_content() == slider.input_value()
    assert after["result"]["plots"]["J"]["series"][0]["y"] != before["result"]["plots"]["J"]["series"][0]["y"]
    check(after)
    root.screenshot(path=str(SHOTS / f"lqg-keyboard-sigma-{after['params']['sigma']}.png"))

    slider.press("End")
    top = state()
    assert top["params"]["sigma"] == float(slider.get_attribute("max"))
    check(top)
    # J decreases with the noise: sigma^2 (0.5 + gamma P) / (1 - gamma) > 0
    j_star = [st["result"]["values"]["J_star"] for st in (top, before, after)]  # sigma 2 < 1 < 0.5
    assert j_star[0] < j_star[1] < j_star[2]
    assert not pg.errors and not pg.remote


def test_explorer_follows_the_theme(browser, book):
    """Axis text is readable on whatever the explorer sits on, in the light and the dark
    theme (pydata-sphinx-theme puts HTML outputs on a light card in dark mode), and the
    curves stand out from it."""
    pg = OfflinePage(browser, _find_explorer_page(book, LQG_TITLE), width=900)
    root = pg.page.locator(".safepg-explorer", has_text=LQG_TITLE).first
    root.scroll_into_view_if_needed()
    js = """e => {
      let b = e, bg = 'rgba(0, 0, 0, 0)';
      while (b && /rgba\\(.*, 0\\)$|transparent/.test(bg)) {
        bg = getComputedStyle(b).backgroundColor;
        b = b.parentElement;
      }
      return {text: getComputedStyle(e.querySelector('svg text')).fill, background: bg,
              series: [...e.querySelectorAll('.safepg-series')].map(p => getComputedStyle(p).stroke)};
    }"""
    SHOTS.mkdir(parents=True, exist_ok=True)
    for theme in ("light", "dark"):
        pg.page.evaluate("t => { const d = document.documentElement.dataset; d.theme = t; d.mode = t; }", theme)
        got = root.evaluate(js)
        assert _contrast(got["text"], got["background"]) >= 4.5, (theme, got)
        for stroke in got["series"]:
            assert _contrast(stroke, got["background"]) >= 2.5, (theme, stroke, got)
        root.screenshot(path=str(SHOTS / f"lqg-{theme}.png"))
    assert not pg.errors


#: Every figure and table the thesis numbers, and the page of the book that reproduces it.
THESIS_CAPTIONS = {
    "book/adaptive_batch": ["Figure 4.1"],
    "book/lqg1d": ["Table 5.1", "Table 5.2", "Figure 5.1", "Figure 5.2", "Figure 5.3", "Figure 5.4"],
    "book/lqg2d": ["Figure 5.5", "Figure 5.6", "Figure 5.7", "Table 5.3", "Figure 5.8"],
    "book/cartpole": ["Figure 5.9", "Table 5.4"],
}
#: A caption number of our own: a letter prefix (S for supplementary, E for the errata page).
OUR_NUMBER = re.compile(r"^(Figure|Table) [A-Z]+\d*\.\d+$")
WIDTHS = (1280, 390)


def is_setup_cell(source: str) -> bool:
    """A code cell that mostly imports: more than half of its statements are imports."""
    try:
        body = ast.parse(source).body
    except SyntaxError:
        return False
    return bool(body) and 2 * sum(isinstance(n, ast.Import | ast.ImportFrom) for n in body) > len(body)


def _explorer_axes(pg: OfflinePage) -> list[str]:
    """Problems of the explorers' tick labels: fewer than two per plot, two equal labels on
    one axis, overlapping labels, or a label outside its plot."""
    return pg.page.evaluate(r"""() => {
      const bad = [];
      document.querySelectorAll('.safepg-explorer svg[data-plot]').forEach((svg, k) => {
        if (!svg.querySelector('path.safepg-series')) return;  // "no data for this choice"
        const S = svg.getBoundingClientRect();
        const ticks = [...svg.querySelectorAll('text.safepg-tick')]
          .map(t => ({t: t.textContent, r: t.getBoundingClientRect()}));
        if (ticks.length < 2) { bad.push(`plot ${k}: ${ticks.length} tick labels`); return; }
        for (const a of ticks) {
          if (a.r.left < S.left - 1 || a.r.right > S.right + 1 || a.r.top < S.top - 1 || a.r.bottom > S.bottom + 1)
            bad.push(`plot ${k}: tick "${a.t}" outside the plot`);
        }
        const low = Math.max(...ticks.map(b => b.r.bottom));  // the x axis's labels are the lowest
        for (const axis of [ticks.filter(a => low - a.r.bottom < 2), ticks.filter(a => low - a.r.bottom >= 2)]) {
          const texts = axis.map(a => a.t);
          if (new Set(texts).size !== texts.length) bad.push(`plot ${k}: repeated tick labels ${texts}`);
          for (let i = 0; i < axis.length; i++) for (let j = i + 1; j < axis.length; j++) {
            const p = axis[i].r, q = axis[j].r;
            if (p.left < q.right && q.left < p.right && p.top < q.bottom && q.top < p.bottom)
              bad.push(`plot ${k}: tick labels "${axis[i].t}" and "${axis[j].t}" overlap`);
          }
        }
      });
      return bad;
    }""")


def _dark_figures(pg: OfflinePage) -> list[str]:
    """Figures (cell-output images) without a light card behind them in the dark theme."""
    backgrounds = pg.page.evaluate("""() => [...document.querySelectorAll('.bd-article .cell_output img')]
        .map(i => [i.src.split('/').pop(), getComputedStyle(i).backgroundColor])""")
    return [src for src, bg in backgrounds if "rgba(0, 0, 0, 0)" in bg or _luminance(bg) < 0.8]


def _distorted_images(pg: OfflinePage) -> list[str]:
    """Images drawn with another aspect ratio than their own (a shrunk width, a fixed height)."""
    return pg.page.evaluate("""() => [...document.querySelectorAll('.bd-article img')].map(i => {
        const cs = getComputedStyle(i), px = v => parseFloat(v) || 0;  // the picture: the box less its padding
        const w = i.clientWidth - px(cs.paddingLeft) - px(cs.paddingRight);
        const h = i.clientHeight - px(cs.paddingTop) - px(cs.paddingBottom);
        return {i, w, h};
      }).filter(({i, w, h}) => i.naturalWidth && i.naturalHeight && h > 0
                && Math.abs((w / h) / (i.naturalWidth / i.naturalHeight) - 1) > 0.02)
        .map(({i, w, h}) => `${i.src.split('/').pop()} drawn ${Math.round(w)}x${Math.round(h)}`)""")


@pytest.fixture(scope="module")
def walk(browser: Any, book: Path, axe_js: str) -> dict[str, Any]:
    """Every page of ``_toc.yml`` opened once at each width (1280 and 390 px), where each load is
    read in the light and the dark theme, audited by axe-core at 1280 px in both themes
    (``tests/test_browser_a11y.py``), and checked offline (:func:`_offline_problems`); the
    findings by check, for the tests below. One walk for the three: each page load costs about 2 s."""
    axe: list[str] = []
    offline: dict[str, Any] = {}
    problems: dict[str, Any] = {}
    captions_by_page: dict[str, list[str]] = {}
    SHOTS.mkdir(parents=True, exist_ok=True)
    pages = toc_pages()
    assert len(pages) >= 9
    for name in pages:
        path = book / f"{name}.html"
        assert path.exists(), f"{name} is in _toc.yml but was not built"
        for width in WIDTHS:
            pg = OfflinePage(browser, path, width=width, height=900)
            pg.typeset()
            pg.page.wait_for_function("() => document.readyState === 'complete'")
            pg.page.wait_for_function("() => document.documentElement.dataset.safepgCues === 'marked'")
            for theme in ("light", "dark"):
                pg.set_theme(theme)
                a = pg.audit()
                where = f"{name} @{width}px {theme}"
                bad: dict[str, Any] = {}
                if a["pageOverflow"]:
                    bad["page scrolls sideways by (px)"] = a["pageOverflow"]
                for key, label in (("overflowing", "sticks out of the column"), ("clipped", "cut off"),
                                   ("scrollNoCue", "scrolls sideways with no cue")):
                    if a[key]:
                        bad[f"{len(a[key])} boxes {label}"] = [
                            f"{e['what']} ({e.get('by', max(e.get('right', 0), -e.get('left', 0)))} px)"
                            for e in a[key][:4]]
                cut = [c["source"][:60] for c in a["code"] if c["clippedLines"]]
                if cut:
                    bad["code cells with lines cut off"] = cut
                setup = [c["source"][:60] for c in a["code"] if is_setup_cell(c["source"])]
                if setup:
                    bad["visible code cells that only import"] = setup
                if theme == "dark":
                    light_less = _dark_figures(pg)
                    if light_less:
                        bad["figures without a light card in the dark theme"] = light_less
                distorted = _distorted_images(pg)
                if distorted:
                    bad["images drawn out of proportion"] = distorted
                axes = _explorer_axes(pg)
                if axes:
                    bad["explorer axes"] = axes
                if bad:
                    problems[where] = bad
                if width == WIDTHS[0] and theme == "light":
                    captions_by_page[name] = a["captions"]
                if bad or os.environ.get("SAFEPG_SCREENSHOTS") == "1":
                    pg.page.screenshot(path=str(SHOTS / f"{name.split('/')[-1]}-{width}-{theme}.png"),
                                       full_page=True)
                if width == WIDTHS[0]:
                    assert pg.page.evaluate("() => document.documentElement.dataset.theme") == theme
                    axe += report(f"{name} [{theme}]", serious_violations(pg, axe_js))
            off = _offline_problems(pg)  # after both themes: errors and requests of the load and the switches
            if off:
                offline[f"{name} @{width}px"] = off
            pg.page.close()
    return {"offline": offline, "reading": problems, "captions": captions_by_page, "axe": axe}


def test_every_page_passes_axe(walk):
    """axe-core on every page at 1280 px, light and dark: no serious or critical violation
    (``tests/test_browser_a11y.py`` says what the audit runs and checks that it can fail)."""
    assert not walk["axe"], "axe-core: serious or critical violations\n" + "\n".join(walk["axe"])


def test_every_page_loads_offline(walk):
    """Every page, at both widths, from disk: no console error, no request leaving the disk, every
    formula typeset, every image decoded, every explorer drawn, no raw Markdown table."""
    assert not walk["offline"], json.dumps(walk["offline"], indent=1, ensure_ascii=False)


def test_every_page_reads_well(walk):
    """The page-wide reading checks (see the module docstring), on every page of
    ``_toc.yml``, at 1280 and 390 px, in the light and the dark theme."""
    problems, captions_by_page = dict(walk["reading"]), walk["captions"]
    # every thesis number on its page, once; every other number visibly ours
    thesis_numbers = {n for numbers in THESIS_CAPTIONS.values() for n in numbers}
    for name, captions in captions_by_page.items():
        expected = THESIS_CAPTIONS.get(name, [])
        missing = [n for n in expected if captions.count(n) != 1]
        misplaced = [n for n in captions if n in thesis_numbers and n not in expected]
        unclear = [n for n in captions if n not in thesis_numbers and not OUR_NUMBER.match(n)]
        for label, items in (("thesis numbers missing (or repeated)", missing),
                             ("thesis numbers on the wrong page", misplaced),
                             ("numbers that are neither the thesis's nor marked as ours", unclear)):
            if items:
                problems.setdefault(name, {})[label] = items
    assert set(THESIS_CAPTIONS) <= set(captions_by_page), "a page of THESIS_CAPTIONS is not in _toc.yml"
    assert not problems, json.dumps(problems, indent=1, ensure_ascii=False)
