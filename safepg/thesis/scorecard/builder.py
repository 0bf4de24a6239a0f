"""The row builder: each row gets its status by its rule and the notes, and its link."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from safepg.thesis.scorecard.links import BOOK, book_link
from safepg.thesis.scorecard.rules import NOTES, RULES, Note, Row, Status
from safepg.thesis.scorecard.text import fill


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
            explanation: str | None = None, expected_seeds: int | None = None, **extra: Any) -> None:
        """Append a row. ``ok=None``: nothing to compare (missing runs): open. A row measured on
        fewer seeds than ``expected_seeds`` is not judged either (a partly computed campaign)."""
        if rule not in RULES:
            raise ValueError(f"rule must be one of {sorted(RULES)}, got {rule!r}")
        seeds = extra.get("seeds")
        if expected_seeds is not None and seeds is not None and 0 < seeds < expected_seeds:
            ok, explanation = None, f"Not judged: only {seeds} of {expected_seeds} seeds are in the results store."
        note = self.note(note_id or id)
        if ok:
            status: Status = "reproduced"
        elif ok is not None and note is not None and note.explains:
            status = "differs (explained)"
        else:
            status = "open"
        if explanation is None:
            if ok is None:
                explanation = "Not computed: the runs behind this row are missing from the results store."
            elif note is not None and not ok:
                explanation = fill(note.text, self.values)
            else:
                explanation = ""
        link = book_link(note.page, note.heading, self.book) if note is not None and not ok else \
            book_link(page, heading, self.book)
        self.rows.append(Row(id=id, group=group, quantity=quantity, where=where, thesis=thesis, ours=ours,
                             difference=difference, status=status, rule=rule, explanation=explanation,
                             link=link, **extra))
