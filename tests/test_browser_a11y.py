"""Accessibility: axe-core on every page of the built book, and the explorers by keyboard.

axe-core (pinned in ``book/tools/vendor_assets.sh``, fetched from the npm registry into
``_build/vendor/axe-core``) runs on every page of ``_toc.yml`` at 1280 px, in the light and
the dark theme of pydata-sphinx-theme (switched as its toggle does, ``OfflinePage.set_theme``),
during the walk over the pages of ``tests/test_browser_book.py`` (``test_every_page_passes_axe``
there), which loads each page once for all its page-wide checks; this module holds the audit.
Any violation of impact "serious" or "critical" fails the test, printed as page, theme,
rule id, impact, the target selectors and axe's one-line help. The checker itself is
checked: on a probe page an unlabelled slider, checkbox and select must be reported, while
the same controls in an :class:`~safepg.explorers.component.Explorer` (labelled by
its markup, or named by its script when a control comes without a label) must not.

Every explorer control on the built pages has an accessible name, is reached with Tab, and
moves with the keyboard: ArrowRight on a slider must change the plotted SVG.

What the book does to pass: code is coloured with accessible-pygments' high-contrast light
and dark styles (``book/_static_safepg/safepg-book.css``; Jupyter Book 1's "sphinx" pygments
style failed ``color-contrast`` on most code cells, badly in the dark theme), and
``nameControls`` in ``book/_static_safepg/safepg-book.js`` gives myst-nb's "Show code cell
source" toggles and the theme's search field ("Search Ctrl+K") and colour-mode button
(icons titled Light / Dark) names that contain their visible words
(``label-content-name-mismatch``). Only pages of ``_toc.yml`` are audited: the build's
``reports/`` holds execution logs that no page links to.
"""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path
from typing import Any

import pytest
from browser_pages import OfflinePage, toc_pages

ROOT = Path(__file__).resolve().parents[1]
AXE_DIR = ROOT / "_build" / "vendor" / "axe-core"
pytestmark = pytest.mark.browser

#: The impacts that fail the audit.
FAILING = ("serious", "critical")

#: Violations we accept, each ``(rule id, regex on the target selector, why)``: only
#: third-party markup we cannot change from our files. Empty: every serious or critical
#: violation found so far is fixed in the book's own CSS/JS or the explorers.
EXCLUSIONS: list[tuple[str, str, str]] = []

#: Runs axe on the page (rules of every standard axe ships, experimental ones excluded) and
#: returns its violations, each with the targets of its nodes. ``preload: false``: axe would
#: fetch the stylesheets again with XMLHttpRequest, which a file:// page refuses (a console
#: error); only css-orientation-lock needs them, and the book's CSS locks no orientation.
AXE_RUN = """async () => {
  const r = await axe.run(document, {resultTypes: ['violations'], preload: false});
  return r.violations.map(v => ({id: v.id, impact: v.impact, help: v.help, helpUrl: v.helpUrl,
    nodes: v.nodes.map(n => ({target: n.target.map(t => Array.isArray(t) ? t.join(' ') : t).join(' '),
                              impact: n.impact, html: n.html.slice(0, 160)}))}));
}"""


def load_axe() -> str:
    """axe-core's source (``axe.min.js``), fetched once per machine by ``vendor_assets.sh axe``."""
    subprocess.run(["bash", "book/tools/vendor_assets.sh", "axe"], cwd=ROOT, check=True)
    return (AXE_DIR / "axe.min.js").read_text(encoding="utf-8")


def excluded(rule: str, target: str) -> bool:
    return any(rule == r and re.search(sel, target) for r, sel, _ in EXCLUSIONS)


def serious_violations(pg: OfflinePage, axe_js: str) -> list[dict[str, Any]]:
    """The page's axe violations of impact serious or critical, less :data:`EXCLUSIONS`:
    one entry per rule, with the targets of its failing nodes."""
    if not pg.page.evaluate("() => !!window.axe"):
        pg.page.add_script_tag(content=axe_js)
    out = []
    for v in pg.page.evaluate(AXE_RUN):
        nodes = [n for n in v["nodes"]
                 if (n["impact"] or v["impact"]) in FAILING and not excluded(v["id"], n["target"])]
        if nodes:
            out.append({**v, "nodes": nodes})
    return out


def report(where: str, violations: list[dict[str, Any]]) -> list[str]:
    """One line per violated rule: where, rule id, impact, target selectors, short help."""
    lines = []
    for v in violations:
        targets = "; ".join(n["target"] for n in v["nodes"][:6]) + (" ..." if len(v["nodes"]) > 6 else "")
        lines.append(f"{where}: {v['id']} ({v['impact']}) x{len(v['nodes'])} at {targets} -- {v['help']}")
    return lines


def _probe_explorer_html() -> str:
    """An explorer with one control of every type, plus a control added without a label."""
    from safepg.thesis.explorers import component as c

    kinds = [k for k in ("Slider", "Select", "Checkbox") if hasattr(c, k)]
    controls: list[Any] = [c.Slider("a", "Noise σ", 0.1, 2.0, 0.1, 1.0),
                           c.Select("shape", "Shape", (("line", "a line"), ("square", "a parabola")), "line")]
    if "Checkbox" in kinds:
        controls.append(c.Checkbox("flip", "Flip the curve", False))
    js = """const xs = [...Array(21).keys()].map(i => i / 10);
      const f = x => (p.shape === 'square' ? x * x : x) * p.a * (p.flip ? -1 : 1) + (p.extra || 0);
      return {plots: {y: {series: [{label: 'y', x: xs, y: xs.map(f)}]}}, values: {a: p.a}, text: 'a = ' + p.a};"""
    ex = c.Explorer(title="Probe explorer", controls=controls, plots=[c.Plot("y", xlabel="x", ylabel="y")],
                    compute_js=js, compute_py=lambda p: {})
    # A control a future explorer might add by hand, with no <label>: the script must name it.
    bare = '<input type="range" data-param="extra" data-label="Offset" min="0" max="1" step="0.1" value="0">'
    return ex.to_html().replace('<svg data-plot', bare + '<svg data-plot', 1)


def test_axe_catches_unlabelled_controls(browser, axe_js, tmp_path):
    """The audit is not vacuous: bare controls are reported with rule, impact, target and
    help, the explorer's own controls (of every type) are not."""
    probe = tmp_path / "probe.html"
    probe.write_text(
        '<!doctype html><html lang="en"><head><meta charset="utf-8"><title>a11y probe</title></head><body><main>'
        "<h1>Probe</h1>"
        '<div id="bare"><input type="range" id="bare-slider" min="0" max="1" step="0.1" value="0.5">'
        '<input type="checkbox" id="bare-box"><select id="bare-select"><option>one</option></select></div>'
        f'<div id="explorer">{_probe_explorer_html()}</div></main></body></html>', encoding="utf-8")
    pg = OfflinePage(browser, probe, width=1280, height=900)
    found = serious_violations(pg, axe_js)
    lines = report("probe", found)
    targets = {(v["id"], n["target"]) for v in found for n in v["nodes"]}
    assert ("label", "#bare-slider") in targets, lines
    assert ("label", "#bare-box") in targets, lines
    assert any(t == "#bare-select" for _, t in targets), lines
    assert all(t.startswith("#bare") for _, t in targets), lines  # nothing in the explorer
    line = next(x for x in lines if x.startswith("probe: label ("))
    assert "(critical)" in line and "#bare-slider" in line and "-- Form elements must have labels" in line, line
    names = _control_names(pg, "#explorer .safepg-explorer")
    assert names == {"a": "Noise σ", "shape": "Shape", "extra": "Offset",
                     **({"flip": "Flip the curve"} if "flip" in names else {})}, names
    # the numbers under the plot are read out after a move
    assert pg.page.locator("#explorer .safepg-text").get_attribute("aria-live") == "polite"
    assert not pg.errors


def _control_names(pg: OfflinePage, root: str) -> dict[str, str]:
    """Each ``[data-param]`` control's accessible name, as axe computes it."""
    return pg.page.evaluate("""root => { axe.setup(document); try {
        return Object.fromEntries([...document.querySelector(root).querySelectorAll('[data-param]')].map(e =>
          [e.dataset.param, axe.commons.text.accessibleTextVirtual(axe.utils.getNodeFromTree(e)).trim()]));
      } finally { axe.teardown(); } }""", root)


#: The live learner (``safepg-live``) has finished the run of its current setting.
LIVE_DONE = """id => { const t = document.getElementById(id).querySelector('.safepg-values').textContent;
                      if (!t) return false; const v = JSON.parse(t);
                      return !!(v.result && v.result.values && v.result.values.done); }"""


def _svg_state(root: Any) -> str:
    return root.evaluate("e => [...e.querySelectorAll('svg[data-plot]')].map(s => s.innerHTML).join('|')")


def test_explorers_by_keyboard(browser, book, axe_js):
    """On every page with explorers: each control has a name that contains its visible label,
    Tab walks through the controls in order, and ArrowRight on each slider redraws the plot."""
    seen = 0
    for name in toc_pages():
        path = book / f"{name}.html"
        if "safepg-explorer" not in path.read_text(encoding="utf-8"):
            continue
        pg = OfflinePage(browser, path, width=1280, height=900)
        pg.page.wait_for_function("() => document.readyState === 'complete'")
        pg.page.add_script_tag(content=axe_js)
        roots = pg.page.locator(".safepg-explorer")
        for k in range(roots.count()):
            root = roots.nth(k)
            uid = root.get_attribute("id")
            names = _control_names(pg, f"#{uid}")
            assert names and all(names.values()), (name, uid, names)
            # the words of each control's <label>, less the control and its shown value
            labels = root.evaluate("""e => Object.fromEntries([...e.querySelectorAll('[data-param]')].map(c =>
                [c.dataset.param, c.closest('label') ? [...c.closest('label').childNodes]
                   .filter(n => n.nodeType === 3).map(n => n.textContent).join(' ').trim() : '']))""")
            for param, words in labels.items():
                assert words and " ".join(words.split()) in names[param], (name, param, names[param], words)
            controls = root.locator("[data-param]")
            # Tab from each control reaches the next one: all are in the tab order, in order.
            controls.first.focus()
            for i in range(1, controls.count()):
                pg.page.keyboard.press("Tab")
                assert controls.nth(i).evaluate("e => e === document.activeElement"), (name, uid, i)
            live = "safepg-live" in (root.get_attribute("class") or "")
            for slider in root.locator('input[type="range"]').all():
                if live:  # the learner's run for the last setting has finished: the plot is still
                    pg.page.wait_for_function(LIVE_DONE, arg=uid, timeout=60_000)
                # a slider at its top moves down instead
                key = "ArrowLeft" if slider.input_value() == slider.get_attribute("max") else "ArrowRight"
                before, value = _svg_state(root), slider.input_value()
                slider.focus()
                pg.page.keyboard.press(key)
                assert slider.input_value() != value, (name, slider.get_attribute("data-param"))
                # the live learner redraws from a Web Worker: wait for its new curves
                pg.page.wait_for_function(
                    """([id, old]) => [...document.getElementById(id).querySelectorAll('svg[data-plot]')]
                         .map(s => s.innerHTML).join('|') !== old""", arg=[uid, before], timeout=30_000)
                seen += 1
        assert not pg.errors, (name, pg.errors)
        pg.page.close()
    assert seen >= 3, f"only {seen} sliders moved by keyboard on the built pages"


def test_exclusions_are_documented():
    for rule, selector, why in EXCLUSIONS:
        assert rule and selector and len(why.split()) >= 5, (rule, selector, why)
    json.dumps(EXCLUSIONS)  # plain data, printable in a report
