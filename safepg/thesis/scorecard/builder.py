"""The row builder: each row gets its status by its rule, the column it holds on, and the notes;
and its link."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from safepg.thesis.scorecard.links import BOOK, book_link
from safepg.thesis.scorecard.rules import (
    AUTHORS_ERROR_STATUS,
    AUTHORS_STATUS,
    KINDS,
    NOTES,
    RULES,
    VACUOUS_STATUS,
    Note,
    Row,
    Status,
)
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
            ok: bool | None, rule: str, kind: str, page: str, heading: str, note_id: str | None = None,
            explanation: str | None = None, expected_seeds: int | None = None, authors_ok: bool | None = None,
            authors_note: str = "", slip_note: str = "", remark: str = "", interval: list[float] | None = None,
            interval_text: str = "", authors_interval: list[float] | None = None, authors_interval_text: str = "",
            vacuous: str = "", authors_vacuous: str = "", authors_error: bool = False, **extra: Any) -> None:
        """Append a row.

        ``ok``: the rule on ours (None: nothing to compare, missing runs). A row measured on
        fewer seeds than ``expected_seeds`` is not judged on ours (a partly computed campaign).
        ``authors_ok``: the same rule on ours under the authors' settings (None: no such run,
        or not all its seeds stored); ``authors_note`` says which setting reproduces the printed
        value, the row's explanation when the status is judged on that column; ``authors_error``: that
        column reproduces it only through an error of the authors' code. ``slip_note`` (the printed
        value is not the authors' own output) and ``remark`` are added to any explanation.
        ``kind``: one of :data:`~safepg.thesis.scorecard.rules.KINDS`. ``interval`` / ``authors_interval``
        (with their texts): the interval each column's rule was applied to. ``vacuous`` /
        ``authors_vacuous``: why that column's agreement carries no information ("" when it does).
        """
        if rule not in RULES:
            raise ValueError(f"rule must be one of {sorted(RULES)}, got {rule!r}")
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
        seeds = extra.get("seeds")
        if expected_seeds is not None and seeds is not None and 0 < seeds < expected_seeds:
            ok, explanation = None, f"Not judged: only {seeds} of {expected_seeds} seeds are in the results store."
        note = self.note(note_id or id)
        informative, a_informative = bool(ok) and not vacuous, bool(authors_ok) and not authors_vacuous
        judged_on = "ours" if ok is not None else ""
        if informative:
            status: Status = "reproduced"
        elif a_informative:
            status, judged_on = AUTHORS_ERROR_STATUS if authors_error else AUTHORS_STATUS, "authors' settings"
        elif ok and vacuous:
            status = VACUOUS_STATUS
        elif authors_ok and authors_vacuous:
            status, judged_on = VACUOUS_STATUS, "authors' settings"
        elif ok is not None and note is not None and note.explains:
            status = "differs (explained)"
        else:
            status = "open"
        # An agreement without information, on a column the status did not come from, is still said.
        no_information = (vacuous if ok else "") or (authors_vacuous if authors_ok else "")
        if status in (AUTHORS_STATUS, AUTHORS_ERROR_STATUS):
            explanation = authors_note or explanation or ""
            if ok and vacuous:
                explanation += f" Ours (the thesis's text) agrees too, without information: {vacuous}"
        elif status == VACUOUS_STATUS:
            explanation = " ".join(t for t in (vacuous if judged_on == "ours" else authors_vacuous, explanation) if t)
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
        if status in (AUTHORS_STATUS, AUTHORS_ERROR_STATUS):
            link = book_link(page, AUTHORS_HEADING, self.book)
        elif note is not None and not ok:
            link = book_link(note.page, note.heading, self.book)
        else:
            link = book_link(page, heading, self.book)
        on_authors = judged_on == "authors' settings"
        self.rows.append(Row(id=id, group=group, quantity=quantity, where=where, thesis=thesis, ours=ours,
                             difference=difference, status=status, rule=rule, explanation=explanation,
                             link=link, judged_on=judged_on, slip=bool(slip_note), kind=kind,
                             judged_interval=authors_interval if on_authors else interval,
                             judged_interval_text=authors_interval_text if on_authors else interval_text,
                             judged_seeds=extra.get("authors_seeds" if on_authors else "seeds"),
                             no_information=no_information, **extra))
