"""The scorecard page of the built book, read in headless Chromium.

The page must list every quantitative result the thesis prints. The list below is typed
here from the thesis, independently of ``safepg`` (whose scorecard module takes them
from the experiments' definitions and ``safepg.theory``): every cell of Tables 5.1-5.4,
the constants and closed forms of Chapter 4, theta* and J(theta*) of both LQG tasks, the
final parameters of Section 5.2.1, the batch and step sizes the text quotes and the
cart-pole's 72 iterations. Each row must have a status and a link that resolves to a
section of the book; the CSV/JSON downloads must be files next to the page; and the page
must never scroll sideways at 1280 or 390 px, in either theme (the tables scroll inside
their own boxes, with a visible cue).
"""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest
from browser_pages import OfflinePage

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
pytestmark = pytest.mark.browser

STATUSES = ("reproduced", "reproduced only with the authors' unprinted settings",
            "reproduced only through an error in the authors' code", "agrees, but carries no information",
            "inconclusive", "differs (explained)", "open")
#: The statuses judged on the authors' column, whose rows link to the chapter's section on their settings.
AUTHORS_COLUMN = STATUSES[1:3]

# ------------------------------------------------------------------ the thesis, as printed
# Table 5.1: improvement ratio by (sigma, N) for alpha = 1e-3, 1e-4, 1e-5, 1e-6.
TABLE_5_1 = {
    (0.5, 10000): ("95.96%", "100%", "98.99%", "100%"),
    (0.5, 1000): ("52.85%", "73.27%", "81.88%", "83.88%"),
    (0.5, 100): ("49.79%", "51.41%", "55.69%", "58.44%"),
    (1, 10000): ("24.24%", "100%", "100%", "100%"),
    (1, 1000): ("37.4%", "27.03%", "99.9%", "100%"),
    (1, 100): ("50.4%", "46.08%", "39.04%", "86.04%"),
}
ALPHAS = ("1e-03", "1e-04", "1e-05", "1e-06")
# Table 5.2: (estimator, bound, delta) -> (Upsilon-bar, CI low, CI high) (the e.r. CI's ends are printed swapped).
TABLE_5_2 = {
    "reinforce-chebyshev-delta=0.95": (-11.3266, -11.3277, -11.3256),
    "reinforce-chebyshev-delta=0.75": (-11.4303, -11.4308, -11.4297),
    "reinforce-chebyshev-delta=0.5": (-11.5947, -11.5958, -11.5937),
    "gpomdp-chebyshev-delta=0.95": (-10.6085, -10.6087, -10.6083),
    "gpomdp-chebyshev-delta=0.75": (-10.7141, -10.7145, -10.7136),
    "gpomdp-chebyshev-delta=0.5": (-10.9036, -10.9040, -10.9031),
    "gpomdp-chebyshev-delta=0.25": (-11.2355, -11.2363, -11.2346),
    "gpomdp-chebyshev-delta=0.05": (-11.836, -11.8368, -11.8352),
    "gpomdp-hoeffding-delta=0.95": (-11.914, -11.9143, -11.9136),
    "gpomdp-bernstein-delta=0.95": (-10.2159, -10.2162, -10.2155),
    "gpomdp-hoeffding-er-delta=0.95": (-9.8582, -9.8589, -9.8574),
    "gpomdp-bernstein-er-delta=0.95": (-9.6623, -9.6619, -9.6627),
}
# Tables 5.3 and 5.4: method -> (Upsilon-bar, improvement ratio).
TABLE_5_3 = {"adaptive": ("-20.50", "100%"), "N=1000": ("-22.39", "100%"), "N=100": ("-19.77", "89%")}
TABLE_5_4 = {"adaptive": ("193.12", "53.01%"), "N=4000": ("192.86", "44.76%")}
# Printed numbers quoted in the text of Chapter 5: row id -> the number.
TEXT_NUMBERS = {
    "section-5.1/theta-star": -0.59, "section-5.1/J-star": -13.21,  # Section 5.1
    "section-5.2/theta-star": -0.588, "section-5.2/J-star": -422.616,  # Section 5.2.1
    "section-5.2/theta-final-scalar/11": -0.014676, "section-5.2/theta-final-scalar/12": 1.4e-06,
    "section-5.2/theta-final-scalar/21": 1.7e-06, "section-5.2/theta-final-scalar/22": -0.013678,
    "section-5.2/theta-final-coordinate/11": -0.0275, "section-5.2/theta-final-coordinate/12": 0.0,
    "section-5.2/theta-final-coordinate/21": 0.0, "section-5.2/theta-final-coordinate/22": -0.0274,
    "section-5.2/batch-first": 500, "section-5.2/batch-last": 2500,  # "from N ~ 500 ... to N ~ 2500"
    "section-5.1/step-order": 1e-5, "section-5.2/step-order": 1e-6,  # "of the order of"
    "section-5.3/baseline-iterations": 72,
    "theory/thm_4_3_2_decimal": 0.16,  # "... >= 0.16 ||g||^2"
}
# Improvement ratios of 100% quoted in the text.
TEXT_RATIOS = ("section-5.1/improvement-ratio-adaptive", "figures-5.5-5.6/scalar/improvement-ratio",
               "figures-5.5-5.6/coordinate/improvement-ratio")
# Chapter 4's closed forms: row id -> fragments of the printed expression (as the page writes it).
CLOSED_FORMS = {
    "theory/thm_4_2_3_c": ("M_phi^2", "R", "A_vol", "gamma"),  # c of Theorem 4.2.3
    "theory/cor_4_2_4_alpha": ("1/(2·c)",),
    "theory/cor_4_2_4_improvement": ("g^2/(4·c)",),
    "theory/cor_4_2_8_alpha": ("2·c",),
    "theory/cor_4_2_8_improvement": ("4·c",),
    "theory/thm_4_3_2_alpha": ("13 - 3·√17", "4·c"),  # alpha* = (13 - 3 sqrt 17) / (4c)
    "theory/thm_4_3_2_N_star": ("3·√17 + 13",),  # N* = (13 + 3 sqrt 17) d^2 / (2 g^2)
    "theory/thm_4_3_2_N0": ("d_delta^2/g^2",),
    "theory/thm_4_3_2_improvement": ("393", "95·√17"),  # (393 - 95 sqrt 17)/8 ||g||^2
    "theory/thm_4_3_2_upsilon_star": ("4977", "1207·√17"),
    "theory/chebyshev_d": ("Var",), "theory/chebyshev_N_star_reinforce": ("3·√17 + 13",),
    "theory/chebyshev_N_star_gpomdp": ("3·√17 + 13",), "theory/hoeffding_d": ("log(2/delta)",),
    "theory/bernstein_N0": ("f_delta",), "theory/lemma_4_3_3_range": ("A_bar", "H", "M_phi"),
}


def expected_ids() -> set[str]:
    ids = {f"table-5.1/sigma={s:g}/N={n}/alpha={a}" for (s, n) in TABLE_5_1 for a in ALPHAS}
    ids |= {f"table-5.2/{k}" for k in TABLE_5_2}
    ids |= {f"table-5.3/{m}/{q}" for m in TABLE_5_3 for q in ("upsilon", "improvement-ratio")}
    ids |= {f"table-5.4/{m}/{q}" for m in TABLE_5_4 for q in ("upsilon", "improvement-ratio")}
    return ids | set(TEXT_NUMBERS) | set(TEXT_RATIOS) | set(CLOSED_FORMS)


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?", text.replace("−", "-"))]


def page_rows(pg: OfflinePage) -> list[dict]:
    return pg.page.evaluate("""() => [...document.querySelectorAll('tr.sc-row')].map(tr => ({
        id: tr.dataset.id, status: tr.dataset.status, thesis: tr.dataset.thesis, ours: tr.dataset.ours,
        links: [...tr.querySelectorAll('a.sc-link')].map(a => a.href),
        statusText: tr.querySelector('.sc-status') ? tr.querySelector('.sc-status').textContent : ''}))""")


def resolve(url: str) -> tuple[Path, str]:
    u = urlparse(url)
    assert u.scheme == "file", url
    return Path(unquote(u.path)), u.fragment


@pytest.fixture(scope="module")
def scorecard_page(browser, book):
    path = book / "book" / "scorecard.html"
    assert path.exists(), "the scorecard page was not built (is book/scorecard in _toc.yml?)"
    return path


def test_scorecard_lists_every_printed_result(browser, scorecard_page):
    pg = OfflinePage(browser, scorecard_page)
    pg.typeset()
    rows = page_rows(pg)
    by_id = {r["id"]: r for r in rows}
    assert len(by_id) == len(rows), "row ids must be unique"
    missing = expected_ids() - set(by_id)
    assert not missing, f"printed results without a row: {sorted(missing)}"
    for (s, n), cells in TABLE_5_1.items():
        for a, printed in zip(ALPHAS, cells):
            assert by_id[f"table-5.1/sigma={s:g}/N={n}/alpha={a}"]["thesis"] == printed
    for k, values in TABLE_5_2.items():
        got = numbers(by_id[f"table-5.2/{k}"]["thesis"])
        assert got[0] == pytest.approx(values[0], abs=1e-9), k
        assert sorted(got[1:3]) == pytest.approx(sorted(values[1:]), abs=1e-9), k
    for table, printed in (("table-5.3", TABLE_5_3), ("table-5.4", TABLE_5_4)):
        for m, (ups, ratio) in printed.items():
            assert numbers(by_id[f"{table}/{m}/upsilon"]["thesis"])[0] == pytest.approx(float(ups)), (table, m)
            assert by_id[f"{table}/{m}/improvement-ratio"]["thesis"] == ratio, (table, m)
    for rid, value in TEXT_NUMBERS.items():
        got = numbers(by_id[rid]["thesis"])
        assert got and got[-1] == pytest.approx(value, rel=1e-9, abs=1e-12), (rid, by_id[rid]["thesis"])
    for rid in TEXT_RATIOS:
        assert by_id[rid]["thesis"] == "100%", rid
    for rid, fragments in CLOSED_FORMS.items():
        for f in fragments:
            assert f in by_id[rid]["thesis"], (rid, f, by_id[rid]["thesis"])
    # Every row: one of the statuses, shown as text, and our value.
    for r in rows:
        assert r["status"] in STATUSES and r["statusText"] == r["status"], r["id"]
        assert r["ours"], r["id"]
    assert not pg.errors and not pg.remote


def test_every_row_links_to_a_section_that_exists(browser, scorecard_page):
    pg = OfflinePage(browser, scorecard_page)
    rows = page_rows(pg)
    targets: dict[Path, str] = {}
    for r in rows:
        assert len(r["links"]) == 1, f"{r['id']} has no link"
        path, anchor = resolve(r["links"][0])
        assert path.exists(), (r["id"], r["links"][0])
        if r["status"] in AUTHORS_COLUMN and not anchor:
            continue  # the chapter's page, while its section on the authors' settings has no heading of that name
        assert anchor, f"{r['id']} links to a page, not a section"
        text = targets.setdefault(path, path.read_text(encoding="utf-8"))
        assert f'id="{anchor}"' in text, (r["id"], r["links"][0])
    # The summary counts agree with the rows (its last column counts every part of the thesis).
    counts = pg.page.evaluate("""() => { const t = document.querySelector('table.sc-summary');
        return [...t.querySelectorAll('tbody tr')].map(
            tr => Number([...tr.querySelectorAll('td')].pop().textContent)); }""")
    by_status = [sum(r["status"] == s for r in rows) for s in STATUSES]
    flagged = pg.page.evaluate("() => document.querySelectorAll('tr.sc-row .sc-noinfo').length")
    assert counts == [*by_status, len(rows), flagged]


def test_download_links_are_files(browser, scorecard_page):
    pg = OfflinePage(browser, scorecard_page)
    links = pg.page.evaluate("() => [...document.querySelectorAll('a.download')].map(a => a.href)")
    names = {resolve(h)[0].name: resolve(h)[0] for h in links}
    wanted = {"scorecard.csv", "scorecard.json"} | {f"table-5.{k}.{x}" for k in range(1, 5) for x in ("csv", "json")}
    assert wanted <= set(names), f"missing downloads: {sorted(wanted - set(names))}"
    for name, path in names.items():
        assert path.is_file() and path.stat().st_size > 0, name
        assert path.is_relative_to(scorecard_page.parents[1]), f"{path} is not part of the built book"
    page_ids = [r["id"] for r in page_rows(pg)]
    with names["scorecard.csv"].open(newline="", encoding="utf-8") as f:
        csv_rows = list(csv.DictReader(f))
    assert [r["id"] for r in csv_rows] == page_ids
    assert {"thesis", "ours", "difference", "status", "link", "judged_on", "authors", "authors_output",
            "slip"} <= set(csv_rows[0])
    data = json.loads(names["scorecard.json"].read_text(encoding="utf-8"))
    assert [r["id"] for r in data["rows"]] == page_ids and data["rules"]
    for k, n in ((1, 24), (2, 12), (3, 6), (4, 4)):
        with names[f"table-5.{k}.csv"].open(newline="", encoding="utf-8") as f:
            assert len(list(csv.DictReader(f))) == n
        assert len(json.loads(names[f"table-5.{k}.json"].read_text(encoding="utf-8"))["rows"]) == n


@pytest.mark.parametrize("width", [1280, 390])
@pytest.mark.parametrize("theme", ["light", "dark"])
def test_no_horizontal_overflow_and_a_visible_cue(browser, scorecard_page, width, theme):
    pg = OfflinePage(browser, scorecard_page, width=width, height=900)
    pg.page.evaluate(f"() => {{ document.documentElement.dataset.theme = '{theme}'; }}")
    pg.typeset()
    info = pg.page.evaluate("""() => {
        const doc = document.documentElement;
        const boxes = [...document.querySelectorAll('.sc-scroll')].map(b => {
            const r = b.getBoundingClientRect(), p = b.parentElement.getBoundingClientRect();
            // The table's own hint, or the cue the book adds under any box that scrolls (safepg-book.js).
            const hint = b.parentElement.querySelector('.sc-hint')
                || (b.nextElementSibling && b.nextElementSibling.matches('.safepg-scroll-hint') ? b.nextElementSibling
                    : null);
            const h = hint ? hint.getBoundingClientRect() : null;
            return {scrolls: b.scrollWidth > b.clientWidth + 1, overflowX: getComputedStyle(b).overflowX,
                    right: r.right, parentRight: p.right, hintVisible: !!h && h.width > 0 && h.height > 0};
        });
        const bg = getComputedStyle(document.querySelector('.sc-out')).backgroundColor;
        const fg = getComputedStyle(document.querySelector('table.sc-rows td')).color;
        return {scrollWidth: doc.scrollWidth, clientWidth: doc.clientWidth, boxes, bg, fg};
    }""")
    SHOTS.mkdir(parents=True, exist_ok=True)
    pg.page.screenshot(path=str(SHOTS / f"scorecard-{width}-{theme}.png"))
    assert info["scrollWidth"] <= info["clientWidth"] + 1, f"the page scrolls sideways at {width} px: {info}"
    assert len(info["boxes"]) >= 6
    for b in info["boxes"]:
        assert b["right"] <= b["parentRight"] + 1 and b["right"] <= width, b
        assert b["overflowX"] == "auto"
        if b["scrolls"]:
            assert b["hintVisible"], "a table that scrolls sideways must say so"
    if width == 390:
        assert any(b["scrolls"] for b in info["boxes"]), "at 390 px the row tables scroll inside their boxes"

    def luminance(css: str) -> float:
        r, g, b = (int(x) for x in re.findall(r"\d+", css)[:3])
        return (0.2126 * r + 0.7152 * g + 0.0722 * b) / 255

    # Readable in both themes: text and background far apart, and the page's own background
    # in the dark theme (not the light card the theme puts behind HTML outputs).
    assert abs(luminance(info["bg"]) - luminance(info["fg"])) > 0.5, info
    assert (luminance(info["bg"]) < 0.3) == (theme == "dark"), info
    assert not pg.errors
