"""What a reader of the release meets first: the front page's summary, and the packed site opened
from disk.

``test_front_page_first_screen``: at 1280 x 800 px the intro's first screen holds the counts of
the scorecard and the three findings, each finding with its link; the counts are the ones the
scorecard page exported (``book/_downloads/scorecard.json``), so they were generated, not typed.

``test_unpacked_site_works_from_disk``: the tarball of ``make dist`` (``tools/dist.sh``),
unpacked outside the clone and opened from ``file://`` with every other request blocked,
typesets its maths, runs an explorer of the two-dimensional chapter in its Web Worker, and
its search page lists hits.
"""

from __future__ import annotations

import json
import subprocess
import tarfile
from pathlib import Path

import pytest
from browser_pages import OfflinePage
from test_browser_live_ch5 import _book_explorer_values
from test_dist import _needs_build_tools, _tool_env

import safepg
from conftest import extract_archive

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.browser

#: Text of the status counts as the front page says them, per status of the scorecard's JSON.
PHRASES = {"reproduced": "reproduced from the text",
           "reproduced only with the authors' unprinted settings": "only with the authors' unprinted settings",
           "reproduced only through an error in the authors' code": "only through an error in their code",
           "differs (explained)": "differ for a reason the book explains", "open": "are open"}


def test_front_page_first_screen(browser, book):
    pg = OfflinePage(browser, book / "book" / "intro.html", width=1280, height=800)
    pg.typeset()
    facts = pg.page.evaluate("""() => {
        const section = document.querySelector('section#reproducibility-summary');
        const results = [...section.querySelectorAll('p')].find(p => p.textContent.startsWith('Results.'));
        const items = [...results.nextElementSibling.querySelectorAll(':scope > li')];
        const box = e => e.getBoundingClientRect();
        return {results: results.textContent.replace(/\\s+/g, ' ').replace(/\u2019/g, "'"),
                resultsBottom: box(results).bottom,
                items: items.map(li => ({text: li.textContent.replace(/\\s+/g, ' '), bottom: box(li).bottom,
                                         links: [...li.querySelectorAll('a')].map(a => a.getAttribute('href'))})),
                height: window.innerHeight, scrolled: window.scrollY};
    }""")
    assert facts["scrolled"] == 0 and facts["height"] == 800
    counts = json.loads((ROOT / "book" / "_downloads" / "scorecard.json").read_text())["counts"]["all"]
    for status, phrase in PHRASES.items():
        assert f"{counts[status]} {phrase}" in facts["results"], (status, facts["results"])
    assert facts["resultsBottom"] <= 800, "the counts are below the first screen"
    assert len(facts["items"]) == 3, facts["items"]
    for item in facts["items"]:
        assert item["bottom"] <= 800, f"below the first screen: {item['text'][:80]}"
        assert item["links"], f"a finding without a link: {item['text'][:80]}"
    pg.page.screenshot(path=str(ROOT / "_build" / "screenshots" / "intro-1280x800.png"))
    assert not pg.errors and not pg.remote


def test_unpacked_site_works_from_disk(browser, book, tmp_path):
    _needs_build_tools()
    out = tmp_path / "dist"
    proc = subprocess.run(["bash", str(ROOT / "tools" / "dist.sh"), str(out)], cwd=ROOT, capture_output=True,
                          text=True, env=_tool_env())
    assert proc.returncode == 0, proc.stderr[-3000:]
    with tarfile.open(out / f"safepg-book-{safepg.__version__}.tar.gz") as tar:
        extract_archive(tar, tmp_path / "site")
    site = tmp_path / "site" / f"safepg-book-{safepg.__version__}"
    assert not site.is_relative_to(ROOT)

    pg = OfflinePage(browser, site / "book" / "adaptive_batch.html", width=1280, height=900)
    pg.typeset()
    assert pg.page.locator("mjx-container").count() > 10
    assert pg.page.locator("mjx-merror").count() == 0
    assert not pg.errors and not pg.remote

    pg = OfflinePage(browser, site / "book" / "lqg2d.html", width=1280, height=1400)
    root = pg.page.locator(".safepg-explorer:has(.safepg-status)").first
    values = _book_explorer_values(pg, root)["result"]["values"]
    assert values["worker"], "the explorer did not run in a Web Worker"
    assert not pg.errors and not pg.remote

    search = OfflinePage(browser, site / "search.html", width=1280, height=900)
    search.page.goto((site / "search.html").as_uri() + "?q=batch")
    search.page.locator("#search-results ul.search li").first.wait_for(timeout=30_000)
    assert search.page.locator("#search-results ul.search li").count() > 3
    assert not search.remote
