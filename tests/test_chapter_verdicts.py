"""The chapters state no verdict of their own: every status a chapter sentence gives a scorecard row is glued
from the scorecard (``{glue:text}`status__<row id>```, :func:`safepg.thesis.scorecard.status_key`), and what the
notebook stored under that key is the row's status now."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from conftest import skip_or_fail
from safepg.thesis.prefetch import chapters
from safepg.thesis.scorecard import STATUSES, row_id_of, scorecard
from safepg.thesis.scorecard.export import STATUS_PREFIX

BOOK = Path(__file__).resolve().parents[1] / "book"
RESULTS = BOOK.parent / "results"
GLUE_ROLE = re.compile(r"\{glue:text\}`([^`:]+)(?::[^`]*)?`")
#: Sentences that state a verdict in the chapters' own words (outside a glue role): the scorecard's
#: statuses, and "is reproduced", "are open", "left open" and the like.
VERDICT_WORDS = [re.escape(s) for s in STATUSES if " " in s] + [
    r"\b(?:is|are|was|were|be|been|stays?|remains?)\s+(?:reproduced|open|inconclusive)\b",
    r"\bleft open\b", r"\bdiffers? \(explained\)",
    r"\bthe scorecard (?:counts|marks|keeps|calls|judges) (?:it|this one|them|these)\b",
]


def _markdown(notebook: Path) -> str:
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")


def _glued(notebook: Path) -> dict[str, str]:
    """The notebook's stored glue values (text/plain of each scrapbook record), by name."""
    out = {}
    for cell in json.loads(notebook.read_text(encoding="utf-8"))["cells"]:
        for o in cell.get("outputs", []):
            name = o.get("metadata", {}).get("scrapbook", {}).get("name")
            text = o.get("data", {}).get("application/papermill.record/text/plain")
            if name is not None and text is not None:
                out[name] = text.strip("'\"")
    return out


PAGES = [nb for nb in chapters(BOOK) if nb.stem != "scorecard"]


def test_the_chapters_are_found() -> None:
    assert len(PAGES) >= 7 and {p.stem for p in PAGES} >= {"lqg1d", "lqg2d", "cartpole"}


@pytest.mark.parametrize("notebook", PAGES, ids=[p.stem for p in PAGES])
def test_no_sentence_states_a_verdict_in_its_own_words(notebook: Path) -> None:
    text = GLUE_ROLE.sub("<glued>", _markdown(notebook))
    found = [m.group(0) for pattern in VERDICT_WORDS for m in re.finditer(pattern, text, flags=re.I)]
    assert not found, f"{notebook.stem} states verdicts in its own words (glue them): {found}"


def test_the_verdict_patterns_catch_a_verdict() -> None:
    """The check can fail: each kind of sentence it forbids is caught."""
    for sentence in ("Table 5.4 is reproduced by the authors' settings.", "Figure 5.5 is the one curve left open.",
                     "the row is reproduced only with the authors' unprinted settings",
                     "and the scorecard counts this one as a difference"):
        assert any(re.search(p, sentence, flags=re.I) for p in VERDICT_WORDS), sentence


def test_every_glued_status_is_its_row_s_status_now() -> None:
    if not (RESULTS / "table-5.2").is_dir():
        skip_or_fail("the book's runs are not stored: run `make book`")
    rows = {r.id: r.status for r in scorecard(root=RESULTS)}
    quoted = 0
    for notebook in [*PAGES, BOOK / "intro.md"]:
        text = notebook.read_text(encoding="utf-8") if notebook.suffix == ".md" else _markdown(notebook)
        keys = [k for k in GLUE_ROLE.findall(text) if k.startswith(STATUS_PREFIX)]
        glued = _glued(notebook) if notebook.suffix == ".ipynb" else {}
        for key in keys:
            row = row_id_of(key)
            assert row in rows, f"{notebook.stem} quotes the status of {row!r}, which is no scorecard row"
            assert glued.get(key) == rows[row], (f"{notebook.stem} quotes {row!r} as {glued.get(key)!r}; its "
                                                 f"status is {rows[row]!r}")
            quoted += 1
    assert quoted >= 6, f"the chapters quote {quoted} statuses; their verdicts must be glued"
