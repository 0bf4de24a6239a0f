"""No control character in the sources: every ``.py`` file and every notebook cell under
``safepg/``, ``book/`` and ``tests/`` holds none but the newline.

A docstring that means LaTeX's ``\\text`` or ``\\big`` but is not a raw string holds a TAB
(``\\t``) or a BACKSPACE (``\\b``) instead, and the page shows ``ext{step}``, ``ig(``; written
back to the file, those characters stay there as they are, raw string or not. Ruff flags a
BACKSPACE (PLE2510) but not a TAB, and reads no notebook's JSON, where a cell's control
character is escaped (``"\\t"``, ``"\\b"``): a scan of the bytes misses it, so notebooks are read
through their parsed cells. A carriage return (CRLF line ends) fails too.

The files are those git tracks or would track (untracked, not ignored): no build output
(``_build``, ``_vendor``, ``.ipynb_checkpoints`` are skipped even if tracked). An escaped
``"\\t"`` in a string literal is two characters of the source, not a control character.
"""

from __future__ import annotations

import json
import subprocess
import unicodedata
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The folders checked, and the folders under them that are never checked (build output).
FOLDERS = ("safepg", "book", "tests")
SKIPPED = {"_build", "_vendor", ".ipynb_checkpoints"}
#: Names of the control characters most likely met (unicodedata has no name for them).
NAMES = {"\0": "NUL", "\a": "BELL", "\b": "BACKSPACE", "\t": "TAB", "\v": "VERTICAL TAB", "\f": "FORM FEED",
         "\r": "CARRIAGE RETURN", "\x1b": "ESCAPE", "\x7f": "DELETE"}


def checked_files(root: Path = ROOT) -> list[Path]:
    """The ``.py`` and ``.ipynb`` files under :data:`FOLDERS` that git tracks or would track."""
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z", "--", *FOLDERS],
                         cwd=root, capture_output=True, check=True).stdout.decode()
    paths = {root / p for p in out.split("\0") if p}
    return sorted(p for p in paths if p.suffix in (".py", ".ipynb") and p.is_file()
                  and not SKIPPED.intersection(p.relative_to(root).parts))


def describe(char: str) -> str:
    """``U+0009 TAB '\\t'``."""
    return f"U+{ord(char):04X} {NAMES.get(char, 'control character')} {char!r}"


def control_characters(text: str) -> Iterator[tuple[int, int, str]]:
    """Line, column (both from 1) and character of each control character of ``text`` but ``\\n``."""
    for number, line in enumerate(text.split("\n"), 1):
        for column, char in enumerate(line, 1):
            if unicodedata.category(char) == "Cc":
                yield number, column, char


def problems(path: Path, root: Path = ROOT) -> list[str]:
    """Each control character of the file ``path`` (of each cell's source for a notebook), located."""
    name = path.relative_to(root) if path.is_relative_to(root) else path
    try:
        text = path.read_bytes().decode("utf-8")  # bytes: read_text would turn CRLF into LF
    except UnicodeDecodeError as e:
        return [f"{name}: not UTF-8 ({e})"]
    if path.suffix != ".ipynb":
        return [f"{name}:{line}:{column}: {describe(char)}" for line, column, char in control_characters(text)]
    found = []
    for index, cell in enumerate(json.loads(text).get("cells", []), 1):
        source = cell.get("source", "")
        source = "".join(source) if isinstance(source, list) else source
        found += [f"{name}: cell {index} ({cell.get('cell_type')}), line {line}, column {column}: {describe(char)}"
                  for line, column, char in control_characters(source)]
    return found


def test_sources_hold_no_control_characters() -> None:
    files = checked_files()
    names = {p.relative_to(ROOT).as_posix() for p in files}
    # Not vacuous: the library, the tests and the book's notebooks are among the files read.
    assert {"safepg/thesis/authors.py", "tests/test_control_characters.py"} <= names
    assert sum(p.suffix == ".py" for p in files) > 100 and sum(p.suffix == ".ipynb" for p in files) >= 5
    found = [problem for path in files for problem in problems(path)]
    assert not found, (f"{len(found)} control characters (a non-raw docstring's \\t or \\b?):\n"
                       + "\n".join(found))


def test_checker_finds_a_tab_in_python(tmp_path: Path) -> None:
    path = tmp_path / "module.py"
    path.write_text('def f():\n    """For :math:`\text{step}`."""\n', encoding="utf-8")
    assert problems(path, tmp_path) == ["module.py:2:19: U+0009 TAB '\\t'"]


def test_checker_finds_a_backspace_in_a_notebook_cell(tmp_path: Path) -> None:
    """The cell's BACKSPACE is ``\\b`` in the file's JSON: no byte of the file is a control character."""
    notebook = {"cells": [{"cell_type": "markdown", "metadata": {}, "source": ["# Title\n"]},
                          {"cell_type": "code", "metadata": {}, "source": ["x = 1\n", "label = '$\big(x$'\n"],
                           "outputs": [], "execution_count": None}],
                "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    path = tmp_path / "chapter.ipynb"
    path.write_text(json.dumps(notebook, indent=1), encoding="utf-8")
    assert not any(b < 0x20 and b != 0x0A for b in path.read_bytes()), "a byte scan would have found it"
    assert problems(path, tmp_path) == ["chapter.ipynb: cell 2 (code), line 2, column 11: U+0008 BACKSPACE '\\x08'"]


def test_checker_finds_carriage_returns_and_passes_escapes(tmp_path: Path) -> None:
    crlf = tmp_path / "crlf.py"
    crlf.write_bytes(b"x = 1\r\ny = 2\r\n")
    assert problems(crlf, tmp_path) == ["crlf.py:1:6: U+000D CARRIAGE RETURN '\\r'",
                                        "crlf.py:2:6: U+000D CARRIAGE RETURN '\\r'"]
    clean = tmp_path / "clean.py"
    clean.write_text('s = "a\\tb\\x08"\nr = r"\\text{step} \\big("\n', encoding="utf-8")
    assert problems(clean, tmp_path) == []
