"""`make lab`'s working copy of the chapters: book/'s notebooks and intro.md in lab/, never book/ itself.

Usage: python tools/lab_copy.py BOOK LAB   (tools/lab.sh runs it before JupyterLab starts)

JupyterLab saves the notebooks it shows (every two minutes and on Ctrl-S); the chapters in
book/ hold the outputs the nbval tests compare against, so JupyterLab serves a copy.
The refresh policy, on each run:

- a chapter missing from the copy is copied from book/;
- a chapter you never edited (its cells' sources are those of the book/ version it was copied
  from; running it, which changes only outputs, is not editing) is refreshed from book/ when
  book/'s version changed;
- a chapter you edited is never overwritten. If book/'s version changed since your copy was
  made, a notice says so and how to get the new one (delete or rename yours, run make lab again);
- files of the copy that are not chapters of book/ (your own notebooks) are left alone.

Which book/ version each chapter was copied from is recorded in LAB/.safepg-lab.json.
Plumbing (book/_ext, _vendor, _static_safepg, tools, _downloads) is not copied.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

MANIFEST = ".safepg-lab.json"


def chapters(book: Path) -> list[Path]:
    """The files of book/ a reader opens: its notebooks and its Markdown pages (intro.md)."""
    return sorted(p for p in book.iterdir() if p.is_file() and p.suffix in (".ipynb", ".md"))


def file_hash(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def content_hash(path: Path) -> str:
    """What a reader edits: a notebook's cell types and sources (not outputs, counts or
    metadata, which running a chapter changes); a Markdown page's bytes."""
    if path.suffix != ".ipynb":
        return file_hash(path)
    try:
        cells = json.loads(path.read_text())["cells"]
        blob = json.dumps([[c["cell_type"], "".join(c["source"]) if isinstance(c["source"], list) else c["source"]]
                           for c in cells])
    except (ValueError, KeyError, TypeError):
        return "unreadable:" + file_hash(path)
    return hashlib.sha256(blob.encode()).hexdigest()


def _copy(src: Path, dest: Path) -> None:
    """Copy so that a reader of ``dest`` sees the old file or the new one, never half."""
    fd, tmp = tempfile.mkstemp(dir=dest.parent, prefix=f".{dest.name}~", suffix=".tmp")
    with os.fdopen(fd, "wb") as f:
        f.write(src.read_bytes())
    os.replace(tmp, dest)


def _load_manifest(lab: Path) -> dict[str, dict[str, str]]:
    try:
        data = json.loads((lab / MANIFEST).read_text())
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def refresh(book: Path, lab: Path) -> list[str]:
    """Bring the copy ``lab`` up to date with ``book`` by the policy above; returns what it says."""
    lab.mkdir(parents=True, exist_ok=True)
    manifest = _load_manifest(lab)
    said, copied = [], []
    for src in chapters(book):
        dest, name = lab / src.name, src.name
        new = {"file": file_hash(src), "content": content_hash(src)}
        base = manifest.get(name)
        if not dest.exists():
            _copy(src, dest)
            manifest[name] = new
            copied.append(name)
            continue
        mine = content_hash(dest)
        if base is None:  # no record of where it came from (made by hand, or the record was removed)
            if mine == new["content"]:
                manifest[name] = new
            else:
                said.append(f"{name}: differs from book/{name} and was not copied by make lab: kept as it is")
            continue
        edited = mine != base["content"]
        book_changed = new["file"] != base["file"]
        if not book_changed:
            if edited:
                said.append(f"{name}: has your edits, kept")
            continue
        if edited:
            said.append(f"{name}: has your edits, kept; book/{name} has changed since it was copied: to start "
                        f"from the new version, rename or delete {dest} and run make lab again")
            continue
        ran = file_hash(dest) != base["file"]
        _copy(src, dest)
        manifest[name] = new
        said.append(f"{name}: refreshed from book/ (book/ changed; you had not edited it"
                    + ("; the outputs of your session were replaced)" if ran else ")"))
    if copied:
        said.insert(0, f"copied {len(copied)} file{'s' * (len(copied) > 1)} from book/: {', '.join(copied)}")
    fd, tmp = tempfile.mkstemp(dir=lab, prefix=f"{MANIFEST}~", suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(manifest, f, indent=1, sort_keys=True)
    os.replace(tmp, lab / MANIFEST)
    return said


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    for line in refresh(Path(argv[0]), Path(argv[1])):
        print(f"lab: {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
