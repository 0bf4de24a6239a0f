"""Every page of the built book, and the LQG explorer driven like a reader would.

Complements ``test_browser.py`` (per-explorer checks against safepg): here every page
listed in ``_toc.yml`` is opened from disk (file://) in headless Chromium and must load
with no JavaScript error, no request leaving the disk, every formula typeset by the
vendored MathJax without a TeX error, and every image decoded. The 1-D LQG explorer is
then moved with the keyboard and its plotted numbers are compared with the closed form
of SETTINGS.md, written out here independently of safepg, and with safepg's own.
Screenshots (light and dark theme) go to ``_build/screenshots/``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from browser_pages import OfflinePage

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
pytestmark = pytest.mark.browser

LQG_TITLE = "1-D LQG: expected performance and estimator variance"


def lqg_performance(theta: float | np.ndarray, sigma: float, gamma: float = 0.9, b: float = 2.0) -> np.ndarray:
    """J(theta) of the 1-D LQG (SETTINGS.md), independent of safepg:
    J = -(b^2/3) P - sigma^2 (0.5 + gamma P) / (1 - gamma), P = 0.5 (1 + theta^2) / (1 - gamma (1 + theta)^2)."""
    theta = np.asarray(theta, dtype=float)
    P = 0.5 * (1 + theta**2) / (1 - gamma * (1 + theta) ** 2)
    return -(b**2 / 3) * P - sigma**2 * (0.5 + gamma * P) / (1 - gamma)


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


def test_every_page_loads_offline(browser, book):
    pages = toc_pages()
    assert len(pages) >= 2
    problems: dict[str, Any] = {}
    for name in pages:
        path = book / f"{name}.html"
        assert path.exists(), f"{name} is in _toc.yml but was not built"
        pg = OfflinePage(browser, path)
        pg.typeset()
        info = pg.page.evaluate(r"""() => ({
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
        })""")
        bad = {k: v for k, v in info.items() if k != "math" and v}
        errors = [e for e in pg.errors if "favicon" not in e]
        if errors:
            bad["console errors"] = errors
        if pg.remote:
            bad["requests that left the disk"] = pg.remote
        if bad:
            problems[name] = bad
        pg.page.close()
    assert not problems, json.dumps(problems, indent=1)


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
