"""The stored scorecard (safepg.thesis.scorecard.stored): one build per state of its inputs.

The key changes with every input (a run file rewritten, a file of the package, a chapter's
heading) and with nothing else; rows are read back equal to the rows built; a new state
replaces the old file; ``scorecard`` gives the same rows stored or not.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from safepg.thesis.scorecard import rows as rows_module
from safepg.thesis.scorecard import scorecard, stored
from safepg.thesis.scorecard.links import headings
from safepg.thesis.scorecard.rules import Row


def _notebook(path: Path, heading: str) -> None:
    path.write_text(json.dumps({"cells": [{"cell_type": "markdown", "source": [f"# {heading}\n", "text\n"]}],
                                "metadata": {}, "nbformat": 4, "nbformat_minor": 5}))


@pytest.fixture
def inputs(tmp_path, monkeypatch):
    """A results folder with one run file, a package of one module and a book of one chapter."""
    root, package, book = tmp_path / "results", tmp_path / "pkg", tmp_path / "book"
    for d in (root / "table-5.1", package, book):
        d.mkdir(parents=True)
    (root / "table-5.1" / "run.npz").write_bytes(b"run")
    (package / "module.py").write_text("x = 1\n")
    _notebook(book / "ch.ipynb", "A chapter")
    monkeypatch.setattr(stored, "PACKAGE", package)
    headings.cache_clear()
    yield root, package, book
    headings.cache_clear()


def test_the_key_follows_every_input_and_nothing_else(inputs):
    root, package, book = inputs
    key = stored.inputs_key(root, book)
    assert stored.inputs_key(root, book) == key
    (root / stored.FOLDER).mkdir()
    (root / stored.FOLDER / "old.json").write_text("[]")
    assert stored.inputs_key(root, book) == key, "the stored scorecard is not an input"

    run = root / "table-5.1" / "run.npz"
    st = run.stat()
    os.utime(run, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    assert stored.inputs_key(root, book) != key, "a run file written again"
    key = stored.inputs_key(root, book)
    (root / "table-5.1" / "run2.npz").write_bytes(b"another run")
    assert stored.inputs_key(root, book) != key, "a new run"
    key = stored.inputs_key(root, book)
    (package / "module.py").write_text("x = 2\n")
    assert stored.inputs_key(root, book) != key, "the code"
    key = stored.inputs_key(root, book)
    (package / "__pycache__").mkdir()
    (package / "__pycache__" / "module.pyc").write_bytes(b"compiled")
    assert stored.inputs_key(root, book) == key, "compiled files are not inputs"
    _notebook(book / "ch.ipynb", "A chapter, renamed")
    headings.cache_clear()
    assert stored.inputs_key(root, book) != key, "a heading (the rows' links)"


def test_rows_are_built_once_per_state_and_read_back_equal(inputs):
    root, package, book = inputs
    row = Row(id="x/y", group="Section 5.1", quantity="q", where="w", kind="closed form", thesis="1",
              ours="1.0", difference="0", status="reproduced", rule="r", explanation="", link="lqg1d.html")
    built = []

    def build():
        built.append(1)
        return [row]

    assert stored.stored_rows(root, book, build) == [row] and len(built) == 1
    assert stored.stored_rows(root, book, build) == [row] and len(built) == 1, "read, not built again"
    first = list((root / stored.FOLDER).glob("*.json"))
    assert len(first) == 1 and first[0].stat().st_mode & 0o777 == 0o644
    (package / "module.py").write_text("x = 3\n")
    assert stored.stored_rows(root, book, build) == [row] and len(built) == 2, "a new state is built"
    files = list((root / stored.FOLDER).iterdir())
    assert len(files) == 1 and files[0] != first[0], "the earlier state's file is removed, no temporary left"


def test_scorecard_is_the_same_stored_or_not(tmp_path, monkeypatch):
    """On an empty results folder (every run row open): built, stored, read back, and equal to a
    build that bypasses the store."""
    calls = []
    build = rows_module._build
    monkeypatch.setattr(rows_module, "_build", lambda *a, **k: calls.append(1) or build(*a, **k))
    first = scorecard(root=tmp_path)
    again = scorecard(root=tmp_path)
    assert len(calls) == 1 and again == first
    assert scorecard(root=tmp_path, store=False) == first and len(calls) == 2
    assert [r.id for r in scorecard(root=tmp_path, pages=["lqg2d"])] == [r.id for r in first
                                                                        if r.link.startswith("lqg2d.html")]


def test_a_theory_page_reads_the_stored_rows_and_else_derives_only_its_closed_forms(tmp_path, monkeypatch):
    """A chapter without runs takes its rows from the build's stored scorecard when there is one
    (the same rows: test_rows_of_some_pages_equal_the_full_cards_rows), else derives its closed
    forms alone; it never builds the whole card."""
    from safepg.thesis.scorecard import closed_forms as closed_forms_module

    derived = []
    closed_forms = closed_forms_module.closed_form_rows
    monkeypatch.setattr(closed_forms_module, "closed_form_rows", lambda b: derived.append(1) or closed_forms(b))
    monkeypatch.setattr(rows_module, "_build", lambda *a, **k: pytest.fail("a theory page built the whole card"))
    alone = scorecard(root=tmp_path, pages=["errata"])
    assert alone and len(derived) == 1 and not (tmp_path / stored.FOLDER).exists()

    marked = [replace(r, explanation="read from the stored card") for r in alone]
    stored.stored_rows(tmp_path, rows_module.BOOK, lambda: marked)
    assert scorecard(root=tmp_path, pages=["errata"]) == marked and len(derived) == 1
    assert scorecard(root=tmp_path, pages=["errata"], store=False) == alone and len(derived) == 2


def test_reading_the_stored_card_imports_no_sympy(tmp_path):
    """A chapter's count sentence reads the stored rows: importing the scorecard and reading them loads
    no sympy (3 s of every chapter's execution before); deriving the closed forms does."""
    code = ("import sys; from pathlib import Path; from safepg.thesis import scorecard as sc; "
            "from safepg.thesis.scorecard import stored; from safepg.thesis.scorecard.rows import BOOK; "
            "sys.argv[2] == 'store' and stored.stored_rows(Path(sys.argv[1]), BOOK, lambda: []); "
            "sc.counts_text(sc.scorecard(root=Path(sys.argv[1]), pages=['errata'])); "
            "print('sympy' in sys.modules)")
    run = lambda how: subprocess.run([sys.executable, "-c", code, str(tmp_path), how],  # noqa: E731
                                     capture_output=True, text=True, check=True).stdout.strip()
    assert run("store") == "False"
    shutil.rmtree(tmp_path / stored.FOLDER)  # no stored card: the closed forms are derived, with sympy
    assert run("derive") == "True"
