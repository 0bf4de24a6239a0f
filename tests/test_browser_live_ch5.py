"""The Chapter 5 live explorers (2-D LQG, cart-pole) in headless Chromium, each rendered into its
own page (no book build), opened from disk with every non-file request blocked: every control is
moved and must change the figure; no console error; nothing sticks out or is cut off at 390 px;
a long run draws as it goes and the next move cancels it; on the cart-pole, the default run
(the thesis's text) leaves theta frozen and says so, the authors' preset moves theta_xdot.
The same explorers in the built book are checked by tests/test_browser_book.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from browser_pages import OfflinePage
from ch5_node import CH5_MOVES

from safepg.thesis.explorers.ch5_live import PAGE_ONLY

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
pytestmark = pytest.mark.browser
#: Generous: the build machine is shared; a default run takes a few seconds.
TIMEOUT_MS = 120_000


def page_of(tmp: Path, name: str, explorer: Any) -> Path:
    path = tmp / f"{name}.html"
    path.write_text(f'<!doctype html><html><head><meta charset="utf-8"><meta name="viewport" '
                    f'content="width=device-width, initial-scale=1"><title>{name}</title></head>'
                    f"<body><main>{explorer.to_html()}</main></body></html>", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, tuple[Path, Any]]:
    from safepg.thesis.explorers.cartpole_learner import cartpole_explorer
    from safepg.thesis.explorers.lqg2d_learner import lqg2d_adaptive_explorer, lqg2d_steps_explorer

    tmp = tmp_path_factory.mktemp("ch5")
    out = {}
    for name, ex in (("steps", lqg2d_steps_explorer()), ("adaptive", lqg2d_adaptive_explorer()),
                     ("cartpole", cartpole_explorer())):
        out[name] = (page_of(tmp, name, ex), ex)
    return out


def wait_done(pg: OfflinePage, after: int = 0) -> dict:
    """The explorer's values once a run with a job number above ``after`` has finished."""
    pg.page.wait_for_function(
        """after => { const t = document.querySelector('.safepg-values').textContent;
                      if (!t) return false; const v = JSON.parse(t);
                      return v.job > after && v.result.values.done; }""", arg=after, timeout=TIMEOUT_MS)
    return pg.values()


def move(pg: OfflinePage, name: str, value: Any) -> None:
    el = pg.page.locator(f'[data-param="{name}"]').first
    kind = el.evaluate("e => e.type")
    if kind == "checkbox":
        # Through its <label>: the box must be named by the words beside it.
        label = el.evaluate("e => e.closest('label').textContent.trim()")
        box = pg.page.get_by_label(label, exact=True)
        box.check() if value else box.uncheck()
    elif kind == "select-one":
        el.select_option(str(value))
    else:
        el.fill(str(value))


def structure(res: dict) -> dict:
    """What the page and the kernel twin must share: plot ids, series labels, value keys."""
    vals = {k: sorted(v) if isinstance(v, dict) else v for k, v in res["values"].items() if k not in PAGE_ONLY}
    return {"plots": {k: [s["label"] for s in p["series"]] for k, p in res["plots"].items()}, "values": vals}


def no_overflow(pg: OfflinePage) -> None:
    a = pg.audit()
    assert not a["pageOverflow"] and not a["overflowing"] and not a["clipped"], a
    cut = pg.page.evaluate("""() => [...document.querySelectorAll(
        '.safepg-explorer label, .safepg-text, .safepg-explorer button, .safepg-status')].filter(e =>
        e.scrollWidth > e.clientWidth + 1 || e.getBoundingClientRect().right > document.documentElement.clientWidth + 1)
        .map(e => e.textContent.slice(0, 60))""")
    assert not cut, cut


def drive(browser, path: Path, explorer: Any, moves: list[tuple[str, Any]], shot: str) -> tuple[OfflinePage, dict]:
    pg = OfflinePage(browser, path, width=1000, height=2400)
    first = wait_done(pg)
    assert first["result"]["values"]["worker"], "the learner must run in a Web Worker"
    assert not first["result"]["values"]["error"], first["result"]["values"]["error"]
    py = explorer.compute_py({**first["params"], "budget": min(first["params"]["budget"], "30000", key=int)})
    assert structure(first["result"]) == structure(py)
    SHOTS.mkdir(parents=True, exist_ok=True)
    pg.page.locator(".safepg-explorer").first.screenshot(path=str(SHOTS / f"{shot}.png"))
    before = first
    for name, value in moves:
        move(pg, name, value)
        after = wait_done(pg, before["job"])
        assert after["params"][name] == value, (name, value, after["params"][name])
        assert not after["result"]["values"]["error"], (name, after["result"]["values"]["error"])
        assert after["result"]["plots"] != before["result"]["plots"], (name, value)
        before = after
    assert not pg.remote, pg.remote
    assert not pg.errors, pg.errors
    return pg, before


def test_lqg2d_steps_explorer(browser, pages):
    path, ex = pages["steps"]
    pg, last = drive(browser, path, ex, CH5_MOVES["steps"], "live-lqg2d-steps")
    v = last["result"]["values"]
    assert v["scalar"]["trajectories"] == v["coordinate"]["trajectories"] == 30_000
    assert [len(s["y"]) for s in last["result"]["plots"]["theta"]["series"]] == [31] * 4  # 30 updates and theta_0


def test_lqg2d_adaptive_explorer(browser, pages):
    path, ex = pages["adaptive"]
    pg, last = drive(browser, path, ex, CH5_MOVES["adaptive"], "live-lqg2d-adaptive")
    # Ticking the authors' switch selects their N_max (one run for both).
    assert last["params"]["n_max"] == "100000" and last["params"]["authors"] is True
    assert "Algorithm 4.1 (authors' settings)" in last["result"]["text"]
    # The Web Worker compiles the WebAssembly kernel, and every run's batches go through it.
    assert set(last["result"]["values"]["kernel"].values()) == {"webassembly"}, last["result"]["values"]["kernel"]
    assert "batches in WebAssembly" in pg.page.locator(".safepg-status").text_content()


def test_long_run_draws_progressively_and_is_cancelled(browser, pages):
    path, _ = pages["adaptive"]
    pg = OfflinePage(browser, path, width=1000, height=2400)
    job = wait_done(pg)["job"]
    move(pg, "budget", "3000000")
    pg.page.wait_for_function(
        """job => { const v = JSON.parse(document.querySelector('.safepg-values').textContent);
                    const a = v.result.values.adaptive;
                    return v.job === job && !v.result.values.done && a && a.trajectories > 0; }""",
        arg=job + 1, timeout=TIMEOUT_MS)
    assert pg.page.locator(".safepg-status").text_content().startswith("running: ")
    partial = pg.values()["result"]["values"]["adaptive"]["trajectories"]
    assert 0 < partial < 3_000_000
    move(pg, "budget", "30000")  # cancels the 3*10^6 run
    done = wait_done(pg, job + 1)
    assert done["job"] == job + 2 and done["result"]["values"]["adaptive"]["trajectories"] == 30_000
    assert pg.page.locator(".safepg-status").text_content().startswith("done in ")
    assert not pg.errors and not pg.remote


def test_cartpole_explorer(browser, pages):
    path, ex = pages["cartpole"]
    pg, _ = drive(browser, path, ex, CH5_MOVES["cartpole"], "live-cartpole")
    # The thesis's text, then the authors' settings: each one click.
    job = pg.values()["job"]
    pg.page.get_by_role("button", name="the thesis's text").click()
    thesis = wait_done(pg, job)
    assert thesis["job"] == job + 1  # one run for the whole preset
    a = thesis["result"]["values"]["adaptive"]
    assert a["frozen"] and max(a["theta_moved"]) < 1e-6
    assert "theta did not move: " in thesis["result"]["text"]
    pg.page.get_by_role("button", name="the authors' settings").click()
    authors = wait_done(pg, thesis["job"])
    a = authors["result"]["values"]["adaptive"]
    assert all(authors["params"][b] for b in ex.data["task_boxes"]) and authors["params"]["start"] == "theta_star"
    assert not a["frozen"] and a["theta_moved"][1] > 1e-4, a["theta_moved"]  # theta_xdot moves
    assert "theta moved: " in authors["result"]["text"]
    assert not pg.errors


def test_default_cartpole_run_is_frozen(browser, pages):
    path, _ = pages["cartpole"]
    pg = OfflinePage(browser, path, width=1000, height=2400)
    v = wait_done(pg)  # how long it takes is benchmarks/bench_js_learner.py's (the cart-pole's 3 s target)
    a = v["result"]["values"]["adaptive"]
    assert a["frozen"] and "theta did not move: " in v["result"]["text"]
    assert v["result"]["values"]["vanilla"]["theta_moved"][1] > 1e-3  # the fixed step moves it


@pytest.mark.parametrize("width", [1280, 390])
@pytest.mark.parametrize("name", ["steps", "adaptive", "cartpole"])
def test_nothing_cut_off(browser, pages, name, width):
    """At a laptop's and a phone's width: nothing sticks out or is cut off, and the axes' tick
    labels pass the book's check (tests/test_browser_book.py), under the thesis's and the authors' settings."""
    from test_browser_book import _explorer_axes

    path, _ = pages[name]
    pg = OfflinePage(browser, path, width=width, height=900)
    v = wait_done(pg)
    no_overflow(pg)
    assert not _explorer_axes(pg), _explorer_axes(pg)
    if name == "cartpole":
        pg.page.get_by_role("button", name="the authors' settings").click()
        wait_done(pg, v["job"])
        no_overflow(pg)
        assert not _explorer_axes(pg), _explorer_axes(pg)
    pg.page.screenshot(path=str(SHOTS / f"live-{name}-{width}.png"), full_page=True)
    assert not pg.errors



def _book_explorer_values(pg: OfflinePage, root: Any, after: int = 0) -> dict:
    """The values of the explorer ``root`` on a book page once a run with a job above ``after`` is done."""
    root.scroll_into_view_if_needed()
    root.locator(".safepg-values").wait_for(state="attached", timeout=TIMEOUT_MS)
    handle = root.element_handle()
    pg.page.wait_for_function(
        """([el, after]) => { const t = el.querySelector('.safepg-values').textContent;
                              if (!t) return false; const v = JSON.parse(t);
                              return v.job > after && v.result.values.done; }""",
        arg=[handle, after], timeout=TIMEOUT_MS)
    return json.loads(root.locator(".safepg-values").text_content())


def test_book_lqg2d_page(browser, book):
    """The 2-D chapter of the built book, from file://: both explorers run in a Web Worker and draw."""
    pg = OfflinePage(browser, book / "book" / "lqg2d.html", width=1280, height=1400)
    roots = pg.page.locator(".safepg-explorer:has(.safepg-status)")
    assert roots.count() == 2
    for i in range(2):
        v = _book_explorer_values(pg, roots.nth(i))
        assert v["result"]["values"]["worker"], "the run did not go to a Web Worker"
        assert set(v["result"]["values"]["kernel"].values()) == {"webassembly"}, v["result"]["values"]["kernel"]
        assert roots.nth(i).locator("svg path").count() > 0
    assert not pg.errors and not pg.remote


def test_book_cartpole_page(browser, book):
    """The cart-pole chapter of the built book, from file://: the default run (the thesis's text)
    leaves theta frozen and says so; the authors' preset moves theta_xdot."""
    pg = OfflinePage(browser, book / "book" / "cartpole.html", width=1280, height=1400)
    root = pg.page.locator(".safepg-explorer:has([data-preset])").first
    v = _book_explorer_values(pg, root)
    assert v["result"]["values"]["worker"] and v["result"]["values"]["adaptive"]["frozen"]
    assert "theta did not move: " in v["result"]["text"]
    root.get_by_role("button", name="the authors' settings").click()
    authors = _book_explorer_values(pg, root, after=v["job"])["result"]["values"]["adaptive"]
    assert authors["theta_moved"][1] > 1e-4 and not authors["frozen"]
    assert not pg.errors and not pg.remote


def test_book_cartpole_explorer_fits_a_phone(browser, book):
    """At 390 px in the built chapter (whose start menu names the stored baseline, a long option),
    no control of the cart-pole explorer runs past the page's width."""
    pg = OfflinePage(browser, book / "book" / "cartpole.html", width=390, height=900)
    root = pg.page.locator(".safepg-explorer:has([data-preset])").first
    _book_explorer_values(pg, root)
    cut = root.evaluate("""el => [...el.querySelectorAll('label, select, button, .safepg-text, .safepg-status')]
        .filter(e => e.getBoundingClientRect().right > document.documentElement.clientWidth + 1)
        .map(e => e.tagName + ': ' + e.textContent.slice(0, 60))""")
    assert not cut, cut
    assert not pg.errors and not pg.remote


@pytest.mark.parametrize("name", ["steps", "cartpole"])
def test_runs_on_the_page_thread_without_workers(browser, pages, name):
    """A browser without Web Workers (static/live_jobs.js's fallback): the runs go to slices of
    the page's thread, finish and draw, and a moved control still replaces the run."""
    path, _ = pages[name]
    page = browser.new_page(viewport={"width": 1280, "height": 1400})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.add_init_script("delete window.Worker;")
    try:
        page.goto(path.as_uri())
        done = """after => { const t = document.querySelector('.safepg-values').textContent;
                             if (!t) return false; const v = JSON.parse(t);
                             return v.job > after && v.result.values.done; }"""
        page.wait_for_function(done, arg=0, timeout=TIMEOUT_MS)
        first = json.loads(page.locator(".safepg-values").text_content())
        assert first["result"]["values"]["worker"] is False and not first["result"]["values"].get("error")
        assert "page thread" in page.locator(".safepg-status").text_content()
        page.locator('[data-param="seed"]').fill("3")
        page.wait_for_function(done, arg=first["job"], timeout=TIMEOUT_MS)
        second = json.loads(page.locator(".safepg-values").text_content())
        assert second["params"]["seed"] == 3 and second["result"]["text"] != first["result"]["text"]
        assert not errors, errors
    finally:
        page.close()
