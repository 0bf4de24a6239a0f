"""The scorecard page's HTML: the counts per status and one table per group, with the style sheet
``safepg/thesis/static/scorecard.css``."""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from functools import cache
from importlib import resources

from safepg.thesis.authors import REPOSITORY
from safepg.thesis.citations import escape_and_link
from safepg.thesis.scorecard.export import counts
from safepg.thesis.scorecard.links import heading_id
from safepg.thesis.scorecard.rules import (
    AUTHORS_ERROR_STATUS,
    AUTHORS_STATUS,
    INCONCLUSIVE_STATUS,
    STATUSES,
    VACUOUS_STATUS,
    Row,
)


# The tables scroll inside their own box (never the page) with "scroll shadows": a shadow
# at an edge that has more columns behind it, drawn by background layers that scroll with
# the content (the covers) over layers that stay put (the shadows). In the dark theme the
# book draws HTML outputs on a light card; the :has() rule gives ours the page's colours.
@cache
def _style_sheet() -> str:
    """The scorecard tables' style sheet, ``safepg/thesis/static/scorecard.css``, as a
    ``<style>`` element (read once per process through :mod:`importlib.resources`)."""
    css = resources.files("safepg.thesis").joinpath("static", "scorecard.css").read_text(encoding="utf-8")
    return f"\n<style>\n{css}</style>\n"


_STATUS_CLASS = {"reproduced": "sc-reproduced", AUTHORS_STATUS: "sc-authors", AUTHORS_ERROR_STATUS: "sc-error",
                 VACUOUS_STATUS: "sc-vacuous", INCONCLUSIVE_STATUS: "sc-inconclusive",
                 "differs (explained)": "sc-explained", "open": "sc-open"}
_HINT = ("<p class=\"sc-hint\">Wide table: it scrolls sideways inside its box (a shadow at an edge marks more "
         "columns).</p>")


def _status_html(status: str) -> str:
    return f'<span class="sc-status {_STATUS_CLASS[status]}">{html.escape(status)}</span>'


def _wrap(table: str, css: bool, label: str, hint: bool = True) -> str:
    box = (f'<div class="sc-scroll" tabindex="0" role="region" aria-label="{html.escape(label)} (scrolls sideways)">'
           f"{table}</div>")
    return f'{_style_sheet() if css else ""}<div class="sc-out">{_HINT if hint else ""}{box}</div>'


def summary_html(rows: Sequence[Row], css: bool = True) -> str:
    """The counts per status (rows) and part of the thesis (columns), each part linked to its
    section of the page.

    One column per part keeps the table narrow enough for a laptop's page width: the statuses'
    long names sit in the first column, where they wrap, instead of in a header row.
    ``css``: include the style sheet of the scorecard tables (once per page is enough).
    """
    c = counts(rows)
    flagged = {g: sum(bool(r.no_information) for r in rows if g in ("all", r.group)) for g in c}
    head = "<tr><th>status</th>" + "".join(
        "<th><strong>all</strong></th>" if g == "all" else f'<th><a href="#{heading_id(g)}">{html.escape(g)}</a></th>'
        for g in c) + "</tr>"
    lines = [(_status_html(s), [n[s] for n in c.values()]) for s in STATUSES]
    lines.append(("rows", [sum(n.values()) for n in c.values()]))
    lines.append(("of which one of ours agrees without information", list(flagged.values())))
    body = "".join(f"<tr><th scope=\"row\">{label}</th>" + "".join(f'<td class="sc-num">{v}</td>' for v in values)
                   + "</tr>" for label, values in lines)
    table = f'<table class="sc-table sc-summary"><thead>{head}</thead><tbody>{body}</tbody></table>'
    return _wrap(table, css, "rows per status", hint=False)


def _split(text: str) -> str:
    """A value and its detail (interval, seed range) on two lines."""
    m = re.fullmatch(r"(.*?) ((?:\[|\().*(?:\]|\)))", text)
    if m is None:
        return html.escape(text)
    return f'{html.escape(m.group(1))}<span class="sc-detail">{html.escape(m.group(2))}</span>'


def _cell(text: str, tex: str) -> str:
    if tex:
        # A formula cannot wrap: one longer than the cell scrolls inside its own box.
        return (f'<td class="sc-expr"><div class="sc-math"><span class="math notranslate nohighlight">'
                f"\\({html.escape(tex)}\\)</span></div></td>")
    # Numbers stay on one line, their interval below; a long statement in words wraps, whole.
    if len(text) <= 32:
        return f'<td class="sc-num">{_split(text)}</td>'
    return f'<td class="sc-words">{escape_and_link(text)}</td>'


def _source_link(source: str) -> str:
    """The authors' file(s) a cell comes from, as a short link to their repository at that commit
    (the whole ``path@commit`` is its title and is in the CSV/JSON)."""
    m = re.fullmatch(r"(.+)@([0-9a-f]{7,40})", source)
    if m is None:  # a file not in their repository
        return f'<span class="sc-src">{html.escape(source)}</span>'
    path, commit = m.groups()
    runs = re.search(r"\{1-(\d+)\}", path)
    if runs:  # several runs: their folder
        url, label = f"{REPOSITORY}/tree/{commit}/{path.rsplit('/', 1)[0]}", f"{runs.group(1)} files @{commit[:7]}"
    else:
        url, label = f"{REPOSITORY}/blob/{commit}/{path}", f"file @{commit[:7]}"
    return f'<a class="sc-src" href="{html.escape(url)}" title="{html.escape(source)}">{label}</a>'


def _judged_html(r: Row) -> str:
    """What the status was judged on: the column and its test (a row judged on runs) or its interval
    (nothing for a closed form)."""
    text = r.verdict or r.judged_interval_text
    if not text:
        return ""
    on = "ours, authors' settings" if r.judged_on == "authors' settings" else "ours"
    return f'<span class="sc-detail sc-on">on {html.escape(on)}: {html.escape(text)}</span>'


def _authors_cells(r: Row) -> str:
    judged = " sc-judged" if r.judged_on == "authors' settings" else ""
    ours = f'<td class="sc-num{judged}">{_split(r.authors or "")}</td>'
    slip = '<span class="sc-slip">slip</span>' if r.slip else ""
    src = f'<span class="sc-detail">{_source_link(r.authors_output_source)}</span>' if r.authors_output_source else ""
    return f'{ours}<td class="sc-num sc-output">{html.escape(r.authors_output)}{slip}{src}</td>'


def row_anchor(row_id: str) -> str:
    """The id of a row's ``<tr>`` on the scorecard page: ``sc-`` and the row's id with every run of
    characters other than letters, digits and dots made one hyphen (``section-5.2/J-star`` ->
    ``sc-section-5.2-J-star``), so that other pages can link to the row."""
    return "sc-" + re.sub(r"[^A-Za-z0-9.]+", "-", row_id).strip("-")


def group_html(rows: Sequence[Row], group: str, css: bool = False) -> str:
    """The rows of one group as an HTML table that scrolls inside its own box.

    Each row carries ``data-id``, ``data-status``, ``data-kind``, ``data-judged-on``, ``data-thesis``,
    ``data-ours`` and ``data-authors`` (the plain texts, also for closed forms shown as typeset math);
    the result's cell names its kind, the status's cell the interval it was judged on; its
    explanation, if any, is the line below it. A group with rows run under the authors'
    settings or with the authors' outputs has those two columns too; the cell a status was
    judged on is marked.
    """
    sel = [r for r in rows if r.group == group]
    n = counts(sel).get(group, dict.fromkeys(STATUSES, 0))
    line = ", ".join(f"{n[s]} {s}" for s in STATUSES if n[s])
    wide = any(r.authors or r.authors_output for r in sel)
    cols = ("result", "status", "thesis", "ours", "ours − thesis", *(("ours, authors' settings", "authors' output")
                                                                      if wide else ()), "discussed in")
    head = "<tr>" + "".join(f"<th>{c}</th>" for c in cols) + "</tr>"
    body = []
    for r in sel:
        ours = _cell(r.ours, r.ours_tex)
        if r.judged_on == "ours" and r.status in ("reproduced", AUTHORS_STATUS) and not r.ours_tex:
            ours = ours.replace('<td class="', '<td class="sc-judged ', 1)
        if r.no_information:  # flagged where it stands, whatever the status
            ours = ours.replace("</td>", '<span class="sc-slip sc-noinfo">no information</span></td>', 1)
        body.append(
            f'<tr class="sc-row" id="{row_anchor(r.id)}" data-id="{html.escape(r.id)}" '
            f'data-status="{html.escape(r.status)}" '
            f'data-kind="{html.escape(r.kind)}" data-judged-on="{html.escape(r.judged_on)}" '
            f'data-thesis="{html.escape(r.thesis)}" data-ours="{html.escape(r.ours)}" '
            f'data-authors="{html.escape(r.authors)}">'
            f'<td class="sc-result">{escape_and_link(r.quantity)}'
            f'<span class="sc-detail">{escape_and_link(r.where)} · {html.escape(r.kind)}</span></td>'
            f"<td>{_status_html(r.status)}{_judged_html(r)}</td>{_cell(r.thesis, r.thesis_tex)}{ours}"
            f'<td class="sc-num">{html.escape(r.difference)}</td>{_authors_cells(r) if wide else ""}'
            f'<td><a class="sc-link" href="{html.escape(r.link)}">{html.escape(_link_label(r.link))}</a></td></tr>')
        if r.explanation:
            body.append(f'<tr class="sc-note" data-for="{html.escape(r.id)}"><td colspan="{len(cols)}">'
                        f'<div class="sc-pin">{escape_and_link(r.explanation)}</div></td></tr>')
    table = (f'<table class="sc-table sc-rows"><caption><div class="sc-pin">{html.escape(group)}: {line}</div>'
             f"</caption><thead>{head}</thead>"
             f"<tbody>{''.join(body)}</tbody></table>")
    return _wrap(table, css, group)


_PAGE_TITLES = {"preliminaries": "Preliminaries", "adaptive_step": "Adaptive step size",
                "adaptive_batch": "Adaptive batch size", "lqg1d": "One-dimensional LQG", "lqg2d": "Two-dimensional LQG",
                "cartpole": "Cart-pole", "errata": "Errata"}


def _link_label(link: str) -> str:
    page = link.split(".html")[0]
    return _PAGE_TITLES.get(page, page)
