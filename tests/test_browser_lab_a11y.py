"""The explorers' kernel views in JupyterLab, by keyboard and through axe-core.

JupyterLab is started as ``tests/test_browser_lab.py`` starts it (its ``Lab`` server and
notebook of the three explorers' ``.interactive()`` views). Then, on every view: axe-core
(``tests/test_browser_a11y.py``'s pinned copy) reports no serious or critical violation
inside the view, less :data:`EXCLUSIONS`, every control has an accessible name and the figure
has alt text; and a slider moved with the keyboard alone (focus its handle, ArrowRight)
redraws the figure for the new value.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from test_browser_a11y import FAILING, load_axe, report
from test_browser_lab import VIEWS, Lab, View, _serve, open_and_run

pytestmark = pytest.mark.browser

#: axe on the views only (JupyterLab's own chrome is not ours).
AXE_VIEWS = """async () => {
  const r = await axe.run({include: [['.safepg-interactive']]}, {resultTypes: ['violations'], preload: false});
  return r.violations.map(v => ({id: v.id, impact: v.impact, help: v.help,
    nodes: v.nodes.map(n => ({target: n.target.join(' '), impact: n.impact}))}));
}"""

#: Every focusable control of a view, its accessible name as axe computes it, and whether an
#: exclusion covers it.
NAMES = """(el, excluded) => { axe.setup(document); try {
  return [...el.querySelectorAll('input, select, textarea, button, [role=slider], [contenteditable=true]')]
    .filter(c => c.offsetParent !== null)
    .map(c => [c.tagName.toLowerCase() + (c.getAttribute('role') ? '[' + c.getAttribute('role') + ']' : '')
               + ' in ' + ((c.closest('[class*=safepg-control-]') || {}).className || '?'),
               axe.commons.text.accessibleTextVirtual(axe.utils.getNodeFromTree(c)).trim(),
               !!(excluded && c.matches(excluded))]);
} finally { axe.teardown(); } }"""


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Iterator[Lab]:
    yield from _serve(tmp_path_factory)


@pytest.fixture(scope="module")
def axe_js() -> str:
    return load_axe()


#: Violations inside the views that we cannot fix from our files, ``(rule, CSS selector of the
#: node, why)``; each is checked to exist, so a fixed one must leave the list.
EXCLUSIONS: list[tuple[str, str, str]] = [
    ("aria-input-field-name", ".widget-slider [role=slider]",
     "ipywidgets 8 draws a slider with noUiSlider, whose handle (role=slider) it does not name: "
     "its description is a separate <label> and no trait reaches the handle's aria-label"),
]


def _open(browser: Any, lab: Lab) -> tuple[Any, dict[str, View], list[str]]:
    page = browser.new_page(viewport={"width": 1400, "height": 2600})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    open_and_run(page, lab)
    views = {name: View(page, i) for i, name in enumerate(VIEWS)}
    for view in views.values():
        view.wait_drawn()
    return page, views, errors


def test_sliders_move_by_keyboard(browser, lab):
    """Focus each view's sigma slider handle, press ArrowRight: the figure is redrawn for the new value."""
    page, views, errors = _open(browser, lab)
    try:
        for name, view in views.items():
            view.el.scroll_into_view_if_needed()
            before = view.wait_drawn()
            digest = view.digest()
            handle = view.el.locator(".safepg-control-sigma [role=slider]")
            assert handle.get_attribute("tabindex") == "0", f"{name}: the slider is not in the tab order"
            handle.focus()
            assert handle.evaluate("e => e === document.activeElement")
            page.keyboard.press("ArrowRight")
            page.wait_for_function(
                """([el, old]) => { const s = el.querySelector('.safepg-status [data-params]');
                     return s && String(JSON.parse(s.dataset.params).sigma) !== String(old); }""",
                arg=[view.el.element_handle(), before["sigma"]], timeout=120_000)
            after = view.wait_drawn()
            assert float(after["sigma"]) > float(before["sigma"]), (name, before, after)
            assert view.digest() != digest, f"{name}: the figure did not change after ArrowRight on sigma"
        assert not errors, errors
    finally:
        page.close()


def test_views_pass_axe(browser, lab, axe_js):
    """axe-core inside the views (less :data:`EXCLUSIONS`), and every control named."""
    page, views, errors = _open(browser, lab)
    try:
        page.add_script_tag(content=axe_js)
        excluded = {rule: page.evaluate("s => [...document.querySelectorAll(s)].length", sel)
                    for rule, sel, _ in EXCLUSIONS}
        assert all(excluded.values()), f"an exclusion matches nothing any more: {excluded}"
        found = []
        for v in page.evaluate(AXE_VIEWS):
            sel = next((s for r, s, _ in EXCLUSIONS if r == v["id"]), None)
            nodes = [n for n in v["nodes"] if (n["impact"] or v["impact"]) in FAILING
                     and not (sel and page.evaluate(
                         "([t, s]) => { const e = document.querySelector(t); return !!(e && e.matches(s)); }",
                         [n["target"], sel]))]
            if nodes:
                found.append({**v, "nodes": nodes})
        problems = report("JupyterLab views", found)
        excluded_selectors = ", ".join(sel for _, sel, _ in EXCLUSIONS)
        for name, view in views.items():
            nameless = [what for what, label, node_ok in view.el.evaluate(NAMES, excluded_selectors)
                        if not label and not node_ok]
            if nameless:
                problems.append(f"{name}: controls without an accessible name: {nameless}")
        assert not errors, errors
        alts = page.evaluate("() => [...document.querySelectorAll('.safepg-interactive img.safepg-figure')]"
                             ".map(img => img.alt)")
        assert len(alts) == len(views) and all(len(a.split()) >= 8 for a in alts), alts
        assert not problems, "\n".join(problems)
    finally:
        page.close()
