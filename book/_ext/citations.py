"""Link every mention of a cited work on the built pages to its entry on the References page.

The prose cites with ``{cite:t}``; text that no role reaches (generated Markdown tables,
captions, the library's docstrings on the API page) names a work as one of
:data:`safepg.thesis.citations.MENTIONS` ("Pirotta et al. (2013)"). After each page is resolved,
every such mention outside code, maths, headings and existing links becomes a link to the entry's
anchor (``bibtex_cite_id = "cite-{key}"``) on ``book/references``. A mention of a work that
``references.bib`` does not hold is a build warning (an error under ``-W``). The References
page's entries are list items for assistive technology.
"""

from __future__ import annotations

from typing import Any

from docutils import nodes
from sphinx import addnodes
from sphinx.util import logging

from safepg.thesis.citations import MENTION_PATTERN, MENTIONS, anchor

logger = logging.getLogger(__name__)

REFERENCES_DOC = "book/references"
#: Where a mention stays text: code, maths, raw output, headings, signatures and links. (Not every
#: FixedTextElement: autosummary's table is a comment node, and its summaries are prose.)
SKIP = (nodes.literal, nodes.literal_block, nodes.doctest_block, nodes.math, nodes.math_block, nodes.raw,
        nodes.title, nodes.reference, addnodes.desc_signature, addnodes.pending_xref)


def _skipped(node: nodes.Node) -> bool:
    parent = node.parent
    while parent is not None:
        if isinstance(parent, SKIP):
            return True
        parent = parent.parent
    return False


def _check_keys(app: Any, env: Any) -> None:
    known = set(env.get_domain("cite").bibdata.data.entries)
    for mention, key in MENTIONS.items():
        if key not in known:
            logger.warning(f"{mention!r} names the key {key!r}, which references.bib does not hold",
                           type="safepg", subtype="citation")


def _link(app: Any, doctree: nodes.document, docname: str) -> None:
    if docname == REFERENCES_DOC or app.builder.format != "html":
        return
    target = app.builder.get_relative_uri(docname, REFERENCES_DOC)
    for text in list(doctree.findall(nodes.Text)):
        value = str(text)
        if not MENTION_PATTERN.search(value) or _skipped(text):
            continue
        parts: list[nodes.Node] = []
        pos = 0
        for m in MENTION_PATTERN.finditer(value):
            parts.append(nodes.Text(value[pos:m.start()]))
            parts.append(nodes.reference("", m.group(0), refuri=f"{target}#{anchor(MENTIONS[m.group(0)])}",
                                         internal=True, classes=["safepg-cite"]))
            pos = m.end()
        parts.append(nodes.Text(value[pos:]))
        text.parent.replace(text, [p for p in parts if not (isinstance(p, nodes.Text) and not str(p))])


def _list_items(app: Any, pagename: str, templatename: str, context: dict, doctree: Any) -> None:
    # docutils writes the bibliography as role="list" holding role="doc-biblioentry" entries; a
    # list's children must be list items (axe: aria-required-children), and DPUB-ARIA has deprecated
    # doc-biblioentry.
    if pagename == REFERENCES_DOC and "body" in context:
        context["body"] = context["body"].replace('role="doc-biblioentry"', 'role="listitem"')


def setup(app: Any) -> dict[str, Any]:
    app.connect("env-check-consistency", _check_keys)
    app.connect("doctree-resolved", _link)
    app.connect("html-page-context", _list_items)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
