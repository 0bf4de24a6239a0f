"""The book's citations: references.bib, the names generated text gives the works, and the built pages.

Source checks: every entry of ``references.bib`` parses, names the public sources of its fields
in the comment above it, and is cited by the book (a ``{cite}`` role in a page, or a mention of
:data:`safepg.thesis.citations.MENTIONS` in the code that generates text); every mention names
its entry's first author, its author count ("et al." for three or more) and its year.

Built pages (the ``book`` fixture): no page shows a bare thesis number such as "[24]" outside
code and maths; every mention and every ``{cite}`` link leads to its entry on the References
page, which lists every entry; every page's footer shows the version.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import pybtex.database
import pytest

import safepg
from safepg.thesis.citations import MENTION_PATTERN, MENTIONS, anchor, escape_and_link, link_mentions_html

ROOT = Path(__file__).resolve().parents[1]
BIB = ROOT / "references.bib"
#: A bracketed number as the thesis cites: [24], [3, 4], [40-42].
BARE = re.compile(r"\[\d{1,3}(?:\s*[,–-]\s*\d{1,3})*\]")
#: Elements whose text is code, maths or machinery, not prose.
NOT_PROSE = {"code", "pre", "script", "style", "kbd", "samp", "svg", "math", "mjx-container", "textarea"}


def _bib() -> pybtex.database.BibliographyData:
    return pybtex.database.parse_file(str(BIB))


def _surname(person: pybtex.database.Person) -> str:
    text = " ".join(person.prelast_names + person.last_names)
    return re.sub(r"[{}]|\\.", "", text).strip()


def mention_of(entry: pybtex.database.Entry) -> str:
    """How generated text names ``entry``: "Surname et al. (year)", "Surname and Surname (year)"
    or "Surname (year)"."""
    people = entry.persons["author"]
    names = (f"{_surname(people[0])} et al." if len(people) >= 3 else
             " and ".join(_surname(p) for p in people))
    return f"{names} ({entry.fields['year']})"


def test_every_entry_parses_and_names_its_sources():
    text = BIB.read_text(encoding="utf-8")
    entries = _bib().entries
    assert len(entries) >= 10
    for key in entries:
        head = text[:text.index("{" + key + ",")]
        comment = head[head.rfind("% ----"):]
        assert re.search(r"%\s*Sources?:", comment), f"{key}: no '% Sources:' comment above the entry"
        assert "http" in comment, f"{key}: its sources name no address"


def test_the_thesis_number_of_each_identified_entry_is_explained():
    text = BIB.read_text(encoding="utf-8")
    # the two numbers the pages once printed bare, each with how it was identified
    assert re.search(r"thesis's \[24\].*?\n@inproceedings\{pirotta2013adaptive,", text, re.S)
    assert re.search(r"\[15\].*?\n@inproceedings\{mnih2008empirical,", text, re.S)
    assert "not confirmed" in text


@pytest.mark.parametrize("mention", sorted(MENTIONS))
def test_each_mention_names_its_entry(mention):
    entry = _bib().entries[MENTIONS[mention]]
    assert mention == mention_of(entry)


def test_every_entry_is_cited():
    sources = "\n".join(p.read_text(encoding="utf-8") for p in
                        [*(ROOT / "book").glob("*.md"), *(ROOT / "book").glob("*.ipynb")])
    cited = set(re.findall(r"\{cite:?[a-z]*\}`([^`]+)`", sources.replace('\\"', '"')))
    cited = {k.strip() for group in cited for k in group.split(",")}
    generated = "\n".join(p.read_text(encoding="utf-8") for p in (ROOT / "safepg").rglob("*.py"))
    mentioned = {MENTIONS[m] for m in MENTION_PATTERN.findall(generated)}
    missing = set(_bib().entries) - cited - mentioned
    assert not missing, f"entries of references.bib that the book never cites: {sorted(missing)}"
    assert cited <= set(_bib().entries), f"{{cite}} keys without an entry: {sorted(cited - set(_bib().entries))}"


def test_link_mentions_html():
    html = escape_and_link("the scalar step of Pirotta et al. (2013) & Florian (2007); Pirotta et al. 2013")
    assert html == ('the scalar step of <a class="safepg-cite" href="references.html#cite-pirotta2013adaptive">'
                    'Pirotta et al. (2013)</a> &amp; <a class="safepg-cite" '
                    'href="references.html#cite-florian2007correct">Florian (2007)</a>; Pirotta et al. 2013')
    assert link_mentions_html("no citation here") == "no citation here"
    assert anchor("key") == "cite-key"


def test_no_bare_thesis_number_in_the_sources_of_the_pages():
    """The pages' prose and the text the library generates name works, never "[24]"."""
    cites = re.compile(r"(?:of|from|in|by|et al\.|step|/)\s\[\d{1,2}\]|\[\d{1,2}\]'s")
    offenders = []
    paths = [*(ROOT / "book").glob("*.md"), *(ROOT / "safepg").rglob("*.py")]
    for path in paths:
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if cites.search(line):
                offenders.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not offenders, "\n".join(offenders)
    assert len(paths) >= 80  # the book's Markdown pages and the library's modules were read


# --- the built pages ---------------------------------------------------------------------------


class _Page(HTMLParser):
    """A page's prose text (outside :data:`NOT_PROSE` and MathJax's spans), its links and its ids."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, bool]] = []
        self.text: list[str] = []
        self.links: list[tuple[str, str]] = []  # (href, text)
        self.ids: set[str] = set()
        self._href: str | None = None
        self._link_text: list[str] = []
        self.footer = ""
        self._in_footer = 0

    def _hidden(self) -> bool:
        return any(skip for _, skip in self.stack)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        classes = (a.get("class") or "").split()
        skip = tag in NOT_PROSE or "math" in classes
        if tag not in ("br", "img", "meta", "link", "input", "hr", "source", "wbr"):
            self.stack.append((tag, skip))
        if tag == "a":
            self._href, self._link_text = a.get("href"), []
        if tag == "footer" or "bd-footer-content" in classes:
            self._in_footer += 1

    def handle_endtag(self, tag):
        while self.stack:
            t, _ = self.stack.pop()
            if t == tag:
                break
        if tag == "a" and self._href is not None:
            self.links.append((self._href, "".join(self._link_text)))
            self._href = None
        if tag == "footer" and self._in_footer:
            self._in_footer -= 1

    def handle_data(self, data):
        if self._in_footer:
            self.footer += data
        if self._href is not None:
            self._link_text.append(data)
        if not self._hidden():
            self.text.append(data if self._href is None else f"\x00{data}\x01")


def _pages(book: Path) -> dict[str, _Page]:
    out = {}
    for path in sorted((book / "book").glob("*.html")):
        page = _Page()
        page.feed(path.read_text(encoding="utf-8"))
        out[str(path.relative_to(book))] = page
    return out


def test_no_page_shows_a_bare_thesis_number(book):
    found = []
    pages = _pages(book)
    for name, page in pages.items():
        text = "".join(page.text)
        found += [f"{name}: ...{text[max(0, m.start() - 60):m.end() + 20]!r}" for m in BARE.finditer(text)]
    assert not found, "bare citation numbers on the pages:\n" + "\n".join(found)
    assert len(pages) >= 10  # every chapter, the scorecard, the API and the references


def test_every_citation_links_to_its_reference(book):
    pages = _pages(book)
    references = pages["book/references.html"]
    keys = set(_bib().entries)
    assert {anchor(k) for k in keys} <= references.ids, "the References page lacks entries"
    cite_links = 0
    for name, page in pages.items():
        if name == "book/references.html":
            continue
        # every mention in prose sits inside a link (marked \x00...\x01 by the parser)
        text = "".join(page.text)
        for m in MENTION_PATTERN.finditer(text):
            assert text[max(0, m.start() - 1)] == "\x00", f"{name}: {m.group(0)!r} is not a link"
        for href, label in page.links:
            if "#cite-" in href:
                cite_links += 1
                target, frag = href.split("#", 1)
                assert target.endswith("references.html"), (name, href)
                assert frag in references.ids, (name, href)
                assert label.strip(), (name, href)
    assert cite_links >= 20


def test_every_page_shows_the_version(book):
    for name, page in _pages(book).items():
        assert f"safepg {safepg.__version__}" in page.footer, f"{name}: no version in the footer"
