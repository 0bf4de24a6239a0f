"""The scorecard computed once per state of its inputs, stored in the results folder.

Every chapter quotes the scorecard's counts, and building it (reading the runs, scoring every
curve) takes seconds in each fresh kernel. :func:`stored_rows` keeps the rows of the last build
in ``<results>/.scorecard/<key>.json``, where the key (:func:`inputs_key`) hashes everything the
rows are made from: every stored run file (path, size and modification time: a run written
again is another input), every file of the ``safepg`` package (the code and the authors'
data), and the headings of the book's chapters (the rows' links). Any change among them gives
another key, and the rows are built again; nothing is ever read for another state. What the
key cannot see is code changed in memory (a rule patched in a session): ``scorecard(...,
store=False)`` builds the rows afresh.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from safepg.thesis.scorecard.links import headings
from safepg.thesis.scorecard.rules import Row

#: The folder of the stored scorecard, inside the results folder (not itself an input).
FOLDER = ".scorecard"
PACKAGE = Path(__file__).resolve().parents[2]


def inputs_key(root: Path, book: Path) -> str:
    """SHA-256 (hex) of the scorecard's inputs: the run files under ``root``, the package's files
    and the headings of ``book``'s chapters."""
    h = hashlib.sha256()
    hash_run_files(h, root, root)
    hash_package(h)
    for p in sorted(book.glob("*.ipynb")):
        h.update(f"page {p.stem} {headings(p.stem, book)!r}\n".encode())
    return h.hexdigest()


def hash_run_files(h: hashlib._Hash, root: Path, folder: Path) -> None:
    """Feed ``h`` every file under ``folder`` (a folder of the results folder ``root``, or ``root`` itself)
    by its path from ``root``, size and modification time (a run written again is another input); the
    stored scorecard's own folder is not an input."""
    if not folder.is_dir():
        return
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(root)
        if rel.parts[0] != FOLDER and p.is_file():
            st = p.stat()
            h.update(f"run {rel.as_posix()} {st.st_size} {st.st_mtime_ns}\n".encode())


def hash_package(h: hashlib._Hash) -> None:
    """Feed ``h`` every file of the ``safepg`` package (its path and bytes): the code and the authors' data."""
    for p in sorted(PACKAGE.rglob("*")):
        if p.is_file() and "__pycache__" not in p.parts:
            h.update(f"code {p.relative_to(PACKAGE).as_posix()}\n".encode())
            h.update(p.read_bytes())


def _read(path: Path) -> list[Row] | None:
    if not path.is_file():
        return None
    return [Row.from_dict(d) for d in json.loads(path.read_text(encoding="utf-8"))]


def rows_if_stored(root: Path, book: Path) -> list[Row] | None:
    """The rows stored for the present inputs, or None when there are none (nothing is built)."""
    return _read(root / FOLDER / f"{inputs_key(root, book)}.json")


def stored_rows(root: Path, book: Path, build: Callable[[], list[Row]]) -> list[Row]:
    """The rows stored for the present inputs, or ``build()``'s, stored for the next reader.

    The file is written atomically (a temporary file renamed), so a reader in another process
    sees either no file or a whole one; files of earlier states are removed.
    """
    folder = root / FOLDER
    path = folder / f"{inputs_key(root, book)}.json"  # the key hashes every input: once per call
    rows = _read(path)
    if rows is not None:
        return rows
    rows = build()
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        json.dump([r.to_dict() for r in rows], f)
    os.chmod(tmp, 0o644)  # as readable as the run files beside it (mkstemp makes it private)
    os.replace(tmp, path)
    for old in folder.glob("*.json"):
        if old != path:
            old.unlink(missing_ok=True)
    return rows
