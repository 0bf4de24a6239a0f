"""How the book names the works it cites, outside its prose.

The chapters' prose cites with MyST's ``{cite:t}`key``` role, resolved against
``references.bib`` at the repository's root and listed on the References page
(``book/references.md``). Text that no role can reach (generated tables, captions, plot
labels, the library's docstrings, the scorecard's CSV files) names a work by author and year
instead, always in one of the forms of :data:`MENTIONS`, such as "Pirotta et al. (2013)".
On the built pages, ``book/_ext/citations.py`` turns every such mention into a link to its
entry on the References page (:func:`anchor`), and :func:`link_mentions_html` does the same
in the HTML that the chapters print (the scorecard's tables).

The thesis numbers its references ([24], [15]), but its list is not in the extracted text;
``references.bib`` records, for each number the book uses, how it was identified.
"""

from __future__ import annotations

import html
import re

#: Every way generated text names a cited work -> its key in references.bib. Three or more
#: authors: "Surname et al. (year)"; two: "Surname and Surname (year)"; one: "Surname (year)".
MENTIONS: dict[str, str] = {
    "Pirotta et al. (2013)": "pirotta2013adaptive",
    "Mnih et al. (2008)": "mnih2008empirical",
    "Audibert et al. (2009)": "audibert2009exploration",
    "Maurer and Pontil (2009)": "maurer2009empirical",
    "Barto et al. (1983)": "barto1983neuronlike",
    "Florian (2007)": "florian2007correct",
}

#: The References page, relative to the chapters (all in book/).
REFERENCES_PAGE = "references.html"

MENTION_PATTERN = re.compile("|".join(re.escape(m) for m in sorted(MENTIONS, key=len, reverse=True)))


def anchor(key: str) -> str:
    """The id of ``key``'s entry on the References page (``bibtex_cite_id`` in ``_config.yml``)."""
    return f"cite-{key}"


def link_mentions_html(escaped: str, page: str = REFERENCES_PAGE) -> str:
    """``escaped`` (HTML-escaped text) with each mention of :data:`MENTIONS` made a link to its
    entry on the References page."""
    def link(m: re.Match[str]) -> str:
        return f'<a class="safepg-cite" href="{page}#{anchor(MENTIONS[m.group(0)])}">{m.group(0)}</a>'

    return MENTION_PATTERN.sub(link, escaped)


def escape_and_link(text: str, page: str = REFERENCES_PAGE) -> str:
    """:func:`html.escape` of ``text``, with its mentions linked (:func:`link_mentions_html`)."""
    return link_mentions_html(html.escape(text), page)
