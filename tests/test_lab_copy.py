"""`make lab`'s working copy (tools/lab_copy.py): book/'s chapters in lab/, refreshed without losing edits."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import nbformat
import pytest
from script_module import load

ROOT = Path(__file__).resolve().parents[1]
lab_copy = load("tools/lab_copy.py")


def notebook(path: Path, *sources: str, output: str | None = None) -> None:
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(s) for s in sources]
    if output is not None:
        nb.cells[0].outputs = [nbformat.v4.new_output("stream", name="stdout", text=output)]
    nbformat.write(nb, path)


@pytest.fixture
def book(tmp_path: Path) -> Path:
    book = tmp_path / "book"
    for d in ("_ext", "_vendor", "_static_safepg", "tools", "_downloads"):
        (book / d).mkdir(parents=True)
        (book / d / "x.py").write_text("plumbing")
    notebook(book / "ch1.ipynb", "print(1)", output="1\n")
    notebook(book / "ch2.ipynb", "print(2)")
    (book / "intro.md").write_text("# Intro\n")
    return book


def sources(path: Path) -> list[str]:
    return [c.source for c in nbformat.read(path, 4).cells]


def test_first_copy_holds_the_chapters_and_no_plumbing(book, tmp_path):
    lab = tmp_path / "lab"
    said = lab_copy.refresh(book, lab)
    assert said == ["copied 3 files from book/: ch1.ipynb, ch2.ipynb, intro.md"]
    assert sorted(p.name for p in lab.iterdir() if not p.name.startswith(".")) == ["ch1.ipynb", "ch2.ipynb",
                                                                                    "intro.md"]
    assert (lab / "ch1.ipynb").read_bytes() == (book / "ch1.ipynb").read_bytes()
    assert lab_copy.refresh(book, lab) == []  # nothing changed: nothing done, nothing said


def test_unedited_chapters_follow_book_edited_ones_are_kept(book, tmp_path):
    lab = tmp_path / "lab"
    lab_copy.refresh(book, lab)
    # The reader edits ch1 and only runs ch2 (new outputs, same sources); book/ then changes both.
    notebook(lab / "ch1.ipynb", "print(1)  # mine", output="1\n")
    notebook(lab / "ch2.ipynb", "print(2)", output="2\n")
    assert lab_copy.refresh(book, lab) == ["ch1.ipynb: has your edits, kept"]
    notebook(book / "ch1.ipynb", "print(10)")
    notebook(book / "ch2.ipynb", "print(20)")
    (book / "intro.md").write_text("# Intro, revised\n")
    said = lab_copy.refresh(book, lab)
    assert sources(lab / "ch1.ipynb") == ["print(1)  # mine"]  # the edit survives
    assert sources(lab / "ch2.ipynb") == ["print(20)"]  # only run: follows book/
    assert (lab / "intro.md").read_text() == "# Intro, revised\n"
    assert said[0].startswith("ch1.ipynb: has your edits, kept; book/ch1.ipynb has changed since it was copied")
    assert "rename or delete" in said[0]
    assert said[1] == "ch2.ipynb: refreshed from book/ (book/ changed; you had not edited it; the outputs of your " \
                      "session were replaced)"
    assert said[2] == "intro.md: refreshed from book/ (book/ changed; you had not edited it)"
    # The notice stays until the reader acts: deleting their copy brings the new one.
    assert lab_copy.refresh(book, lab)[0].startswith("ch1.ipynb: has your edits, kept; book/ch1.ipynb has changed")
    (lab / "ch1.ipynb").unlink()
    assert lab_copy.refresh(book, lab) == ["copied 1 file from book/: ch1.ipynb"]
    assert sources(lab / "ch1.ipynb") == ["print(10)"]
    # A reader who undoes their edit follows book/ again.
    notebook(lab / "ch2.ipynb", "print(20)  # mine")
    lab_copy.refresh(book, lab)
    notebook(lab / "ch2.ipynb", "print(20)")
    notebook(book / "ch2.ipynb", "print(200)")
    lab_copy.refresh(book, lab)
    assert sources(lab / "ch2.ipynb") == ["print(200)"]


def test_files_of_unknown_origin_and_own_notebooks_are_left_alone(book, tmp_path):
    lab = tmp_path / "lab"
    lab.mkdir()
    notebook(lab / "ch1.ipynb", "print('written by hand')")
    notebook(lab / "scratch.ipynb", "x = 1")
    said = lab_copy.refresh(book, lab)
    assert "ch1.ipynb: differs from book/ch1.ipynb and was not copied by make lab: kept as it is" in said
    assert sources(lab / "ch1.ipynb") == ["print('written by hand')"]
    assert sources(lab / "scratch.ipynb") == ["x = 1"]
    assert json.loads((lab / lab_copy.MANIFEST).read_text()).keys() == {"ch2.ipynb", "intro.md"}


def test_lab_sh_serves_the_copy_and_turns_the_news_off():
    text = (ROOT / "tools" / "lab.sh").read_text()
    assert 'c.ServerApp.root_dir = "$lab_dir"' in text and '"$root/tools/lab_copy.py" "$root/book"' in text
    assert '"fetchNews": "false"' in text and "overrides.d" in text
    ignored = subprocess.run(["git", "check-ignore", "-q", "lab/x.ipynb"], cwd=ROOT)
    assert ignored.returncode == 0, "lab/ must be git-ignored"


def test_the_real_book_copies_without_plumbing(tmp_path):
    lab = tmp_path / "lab"
    lab_copy.refresh(ROOT / "book", lab)
    names = {p.name for p in lab.iterdir()}
    assert {"intro.md", "lqg1d.ipynb", "scorecard.ipynb"} <= names
    assert not names & {"_ext", "_vendor", "_static_safepg", "tools", "_downloads"}
