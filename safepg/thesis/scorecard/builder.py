"""The row builder: each row gets its status by its rule, the column it holds on, and the notes;
and its link."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from safepg.thesis.scorecard.links import BOOK, book_link
from safepg.thesis.scorecard.rules import AUTHORS_STATUS, NOTES, RULES, Note, Row, Status
from safepg.thesis.scorecard.text import fill

#: Where the chapters discuss the authors' settings (the heading's words; without such a heading
#: the link is the chapter's page).
AUTHORS_HEADING = "authors"


@dataclass
class Builder:
    """Collects rows, applying the status rule and the notes."""

    book: Path = BOOK
    rows: list[Row] = field(default_factory=list)
    values: dict[str, Any] = field(default_factory=dict)

    def note(self, row_id: str) -> Note | None:
        if row_id in NOTES:
            return NOTES[row_id]
        for key, n in NOTES.items():
            if key.endswith("/") and row_id.startswith(key):
                return n
        return None

    def add(self, *, id: str, group: str, quantity: str, where: str, thesis: str, ours: str, difference: str,
            ok: bool | None, rule: str, page: str, heading: str, note_id: str | None = None,
            explanation: str | None = None, expected_seeds: int | None = None, authors_ok: bool | None = None,
            authors_note: str = "", slip_note: str = "", remark: str = "", **extra: Any) -> None:
        """Append a row.

        ``ok``: the rule on ours (None: nothing to compare, missing runs). A row measured on
        fewer seeds than ``expected_seeds`` is not judged on ours (a partly computed campaign).
        ``authors_ok``: the same rule on ours under the authors' settings (None: no such run,
        or not all its seeds stored); ``authors_note`` says which setting reproduces the printed
        value, the row's explanation when the status is judged on that column. ``slip_note``
        (the printed value is not the authors' own output) and ``remark`` are added to any explanation.
        """
        if rule not in RULES:
            raise ValueError(f"rule must be one of {sorted(RULES)}, got {rule!r}")
        seeds = extra.get("seeds")
        if expected_seeds is not None and seeds is not None and 0 < seeds < expected_seeds:
            ok, explanation = None, f"Not judged: only {seeds} of {expected_seeds} seeds are in the results store."
        note = self.note(note_id or id)
        judged_on = "ours" if ok is not None else ""
        if ok:
            status: Status = "reproduced"
        elif authors_ok:
            status, judged_on = AUTHORS_STATUS, "authors' settings"  # type: ignore[assignment]
        elif ok is not None and note is not None and note.explains:
            status = "differs (explained)"
        else:
            status = "open"
        if status == AUTHORS_STATUS:
            explanation = authors_note or explanation or ""
        elif explanation is None:
            if ok is None:
                explanation = "Not computed: the runs behind this row are missing from the results store."
            elif note is not None and not ok:
                explanation = fill(note.text, self.values)
            elif status == "open":
                # No chapter explains this gap yet: say so, and what would settle it.
                also = ", and so does ours under the authors' settings" if authors_ok is False else ""
                explanation = (f"Open: ours misses this row's rule{also}, and no chapter explains the gap yet; "
                               "what is missing is the setting or the run that accounts for it.")
            else:
                explanation = ""
        explanation = " ".join(t for t in (explanation, slip_note, remark) if t)
        if status == AUTHORS_STATUS:
            link = book_link(page, AUTHORS_HEADING, self.book)
        elif note is not None and not ok:
            link = book_link(note.page, note.heading, self.book)
        else:
            link = book_link(page, heading, self.book)
        self.rows.append(Row(id=id, group=group, quantity=quantity, where=where, thesis=thesis, ours=ours,
                             difference=difference, status=status, rule=rule, explanation=explanation,
                             link=link, judged_on=judged_on, slip=bool(slip_note), **extra))
