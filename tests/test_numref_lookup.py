"""book/_ext/numref_lookup.py: a ``{numref}`` reads its target page's doctree once per build.

A small Sphinx project, built with and without the extension: the same HTML, and with it
each target page's doctree is unpickled once for all the references to it, where Sphinx
unpickles it once per reference.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
from sphinx.application import Sphinx
from sphinx.domains.std import StandardDomain
from sphinx.environment import BuildEnvironment
from sphinx.util.docutils import docutils_namespace

ROOT = Path(__file__).resolve().parents[1]
REFERENCES = 5
#: Sphinx's own, before either build counts its calls.
GET_DOCTREE = BuildEnvironment.get_doctree

FIGURES = """Figures
=======

.. _fig-a:

.. figure:: dot.png

   The first figure.

.. _fig-b:

.. figure:: dot.png

   The second figure.
"""

CITING = """Citing
======

""" + "\n\n".join(f"See :numref:`fig-a` and :numref:`Figure {{number}} <fig-b>` ({k})." for k in range(REFERENCES))


def _project(folder: Path, extensions: list[str]) -> Path:
    src = folder / "src"
    src.mkdir(parents=True)
    (src / "conf.py").write_text(f"import sys\nsys.path.insert(0, {str(ROOT / 'book' / '_ext')!r})\n"
                                 f"extensions = {extensions!r}\nnumfig = True\n")
    (src / "index.rst").write_text("Book\n====\n\n.. toctree::\n\n   figures\n   citing\n")
    (src / "figures.rst").write_text(FIGURES)
    (src / "citing.rst").write_text(CITING)
    # A 1x1 PNG: the figures need an image file, not a particular one.
    (src / "dot.png").write_bytes(bytes.fromhex(
        "89504e470d0a1a0a0000000d4948445200000001000000010806000000"
        "1f15c4890000000d49444154789c63f8ffff3f0005fe02fea7d6a4c40000000049454e44ae426082"))
    return src


def _build(folder: Path, extensions: list[str], monkeypatch: pytest.MonkeyPatch) -> tuple[str, Counter[str]]:
    """The HTML of the citing page, and how many times each page's doctree was unpickled."""
    src = _project(folder, extensions)
    reads: Counter[str] = Counter()

    def counted(self: BuildEnvironment, docname: str):
        reads[docname] += 1
        return GET_DOCTREE(self, docname)

    monkeypatch.setattr(BuildEnvironment, "get_doctree", counted)
    with docutils_namespace():  # each build registers its nodes afresh, as sphinx-build's process would
        app = Sphinx(str(src), str(src), str(folder / "html"), str(folder / "doctrees"), "html",
                     status=None, warningiserror=True, freshenv=True)
        app.build()
    return (folder / "html" / "citing.html").read_text(), reads


def test_references_read_each_target_page_once_and_render_the_same(tmp_path, monkeypatch):
    # The extension patches Sphinx's class: monkeypatch restores it after this test.
    monkeypatch.setattr(StandardDomain, "_resolve_numref_xref", StandardDomain._resolve_numref_xref)
    plain_html, plain_reads = _build(tmp_path / "plain", [], monkeypatch)
    shared_html, shared_reads = _build(tmp_path / "shared", ["numref_lookup"], monkeypatch)

    assert "Fig. 1" in plain_html and "Figure 2" in plain_html
    assert shared_html == plain_html.replace(str(tmp_path / "plain"), str(tmp_path / "shared"))
    # Sphinx reads the figures' page once per reference (two per paragraph), the extension once
    # for all of them; the other reads (writing the page, its table of contents) are the same.
    assert plain_reads["figures"] - shared_reads["figures"] == 2 * REFERENCES - 1
    del plain_reads["figures"], shared_reads["figures"]
    assert shared_reads == plain_reads


def test_the_book_loads_the_extension():
    assert "numref_lookup: book/_ext" in (ROOT / "_config.yml").read_text()
