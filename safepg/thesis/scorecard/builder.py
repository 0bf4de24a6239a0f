"""The row builder: each row, given as a :class:`RowSpec`, gets its status by its rule, the column it
holds on, and the notes; and its link."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

from safepg.thesis.scorecard.links import BOOK, book_link
from safepg.thesis.scorecard.outputs import Output
from safepg.thesis.scorecard.rules import (
    AUTHORS_ERROR_STATUS,
    AUTHORS_STATUS,
    INCONCLUSIVE_STATUS,
    KINDS,
    NOTES,
    RULES,
    VACUOUS_STATUS,
    Note,
    Row,
    Status,
)
from safepg.thesis.scorecard.verdicts import (
    RANDOM_KINDS,
    ColumnVerdict,
    column_verdict,
    correct,
    short_verdict,
    verdict_sentence,
)

#: Where the chapters discuss the authors' settings (the heading's words; without such a heading
#: the link is the chapter's page).
AUTHORS_HEADING = "authors"


@dataclass(frozen=True, kw_only=True)
class AuthorsColumn:
    """Ours under the authors' settings, beside a row (the default: the row has no such column).

    Attributes
    ----------
    experiment : str
        The experiment behind the column (e.g. ``"table-5.1-authors"``), or what was computed.
    text : str
        The cell ("-" when its runs are not stored).
    value, ci95, seeds
        The number, our 95% interval and the seeds behind ``text``.
    ok : bool or None
        The row's rule on this column (None: no such run, or not all its seeds stored).
    interval, interval_text : list of float or None, str
        The interval the rule was applied to, and as the page shows it.
    vacuous : str
        Why the column's agreement carries no information ("" when it does).
    note : str
        Which setting reproduces the printed value: the row's explanation when its status is
        judged on this column.
    error : bool
        The column reproduces the printed value only through an error of the authors' code.
    test : safepg.significance.Test or None
        The column's test, for a row judged on runs (None: not judged, its runs missing).
    sources : tuple of str
        The configurations behind the column, ``"experiment/config"``.
    """

    experiment: str = ""
    text: str = ""
    value: float | None = None
    ci95: list[float] | None = None
    seeds: int | None = None
    ok: bool | None = None
    interval: list[float] | None = None
    interval_text: str = ""
    vacuous: str = ""
    note: str = ""
    error: bool = False
    test: Any = None
    sources: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class RowSpec:
    """What a row says before it is judged: :meth:`Builder.add` turns it into a :class:`Row`.

    Where the row stands: ``id``, ``group``, ``quantity``, ``where``, and the book's ``page`` and
    ``heading`` that discuss it. The printed and our values: ``thesis``, ``ours``, ``difference`` (the
    cells), ``thesis_value``, ``ours_value``, ``ours_ci95``, ``seeds``, ``thesis_tex``, ``ours_tex`` and
    ``fields`` (as in :class:`Row`). The judgement: ``ok`` (the rule on ours; None: nothing to
    compare, missing runs), ``rule`` (a key of :data:`RULES`), ``kind`` (one of :data:`KINDS`),
    ``interval`` and ``interval_text`` (what the rule was applied to), ``vacuous`` (why ours agrees
    without information, "" when it does not) and ``expected_seeds`` (a row measured on fewer seeds
    is not judged on ours: a partly computed campaign). A row of a kind judged on runs
    (:data:`~safepg.thesis.scorecard.verdicts.RANDOM_KINDS`) is judged by ``test`` instead of ``ok`` (None:
    its runs are missing), against ``relevance`` (the difference that matters, in the units of
    ``ours_value``, as ``relevance_text`` says), numbers shown by ``show``; ``sources`` names the
    configurations behind ours, ``"experiment/config"`` (the authors' column names its own). Beside it:
    ``authors``, ours under the authors' settings, and ``output``, the authors' own output. The notes: ``note_id`` (the
    :data:`NOTES` entry, default the row's id), ``note_values`` (the values that note quotes, an
    instance of its :attr:`Note.measured`), ``explanation`` (instead of the note's), ``slip_note``
    (the printed value is not the authors' own output) and ``remark``, both added to any explanation.

    Raises
    ------
    ValueError
        If ``rule`` or ``kind`` is not one of the stated ones.
    """

    id: str
    group: str
    quantity: str
    where: str
    page: str
    heading: str
    thesis: str
    ours: str
    difference: str
    thesis_value: float | None = None
    ours_value: float | None = None
    ours_ci95: list[float] | None = None
    seeds: int | None = None
    thesis_tex: str = ""
    ours_tex: str = ""
    fields: dict[str, Any] = field(default_factory=dict)
    ok: bool | None
    rule: str
    kind: str
    interval: list[float] | None = None
    interval_text: str = ""
    vacuous: str = ""
    expected_seeds: int | None = None
    authors: AuthorsColumn = AuthorsColumn()
    output: Output | None = None
    note_id: str | None = None
    note_values: NamedTuple | None = None
    explanation: str | None = None
    slip_note: str = ""
    remark: str = ""
    test: Any = None
    relevance: float | None = None
    relevance_text: str = ""
    sources: tuple[str, ...] = ()
    show: Callable[[float], str] = field(default=lambda v: f"{v:.3g}", repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind in RANDOM_KINDS and self.ok is not None:
            raise ValueError(f"row {self.id!r}: a row judged on runs takes a test, not ok")
        if self.kind in RANDOM_KINDS and (self.test is not None or self.authors.test is not None) \
                and self.relevance is None:
            raise ValueError(f"row {self.id!r}: a row judged on runs needs its relevance")
        if self.rule not in RULES:
            raise ValueError(f"rule must be one of {sorted(RULES)}, got {self.rule!r}")
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")


def note_of(row_id: str) -> Note | None:
    """The :data:`NOTES` entry of a row: by its id, else by the first prefix (ending in "/") of it."""
    if row_id in NOTES:
        return NOTES[row_id]
    for key, n in NOTES.items():
        if key.endswith("/") and row_id.startswith(key):
            return n
    return None


def partly_computed(spec: RowSpec) -> bool:
    """The row's runs are stored for some of its seeds only (none stored is the missing runs' case)."""
    return spec.expected_seeds is not None and spec.seeds is not None and 0 < spec.seeds < spec.expected_seeds


def _status(ok: bool | None, spec: RowSpec, note: Note | None) -> tuple[Status, str]:
    """The row's status and the column it was judged on, by :data:`~safepg.thesis.scorecard.rules.STATUS_RULE`."""
    a = spec.authors
    judged_on = "ours" if ok is not None else ""
    if ok and not spec.vacuous:
        return "reproduced", judged_on
    if a.ok and not a.vacuous:
        return (AUTHORS_ERROR_STATUS if a.error else AUTHORS_STATUS), "authors' settings"
    if ok and spec.vacuous:
        return VACUOUS_STATUS, judged_on
    if a.ok and a.vacuous:
        return VACUOUS_STATUS, "authors' settings"
    if ok is not None and note is not None and note.explains:
        return "differs (explained)", judged_on
    return "open", judged_on


def _number(x: float | None) -> float | None:
    """A row's number as the files hold it: None where there is none (no test, or one without a p-value)."""
    return None if x is None or not math.isfinite(x) else float(x)


def _state(v: ColumnVerdict | None) -> str:
    """A column's test within the family, in one word ("" without a test)."""
    if v is None:
        return ""
    return "rejected" if v.rejected else "conclusive" if v.conclusive else "inconclusive"


def _random_status(ours: ColumnVerdict | None, theirs: ColumnVerdict | None, spec: RowSpec,
                   note: Note | None) -> tuple[Status, str]:
    """The status of a row judged on runs and the column it was judged on, by
    :data:`~safepg.thesis.scorecard.rules.STATUS_RULE`."""
    a = spec.authors
    ours_ok = ours is not None and ours.conclusive
    theirs_ok = theirs is not None and theirs.conclusive
    if ours_ok and not spec.vacuous:
        return "reproduced", "ours"
    if theirs_ok and not a.vacuous:
        return (AUTHORS_ERROR_STATUS if a.error else AUTHORS_STATUS), "authors' settings"
    if ours_ok:
        return VACUOUS_STATUS, "ours"
    if theirs_ok:
        return VACUOUS_STATUS, "authors' settings"
    if ours is not None and not ours.rejected:
        return INCONCLUSIVE_STATUS, "ours"
    if theirs is not None and not theirs.rejected:
        return INCONCLUSIVE_STATUS, "authors' settings"
    if ours is None:
        return "open", ""
    return ("differs (explained)" if note is not None and note.explains else "open"), "ours"


def _explanation(ok: bool | None, explanation: str | None, status: Status, judged_on: str, spec: RowSpec,
                 note: Note | None) -> str:
    """The row's sentence: the setting that did it, why it agrees without information, the note, or
    what is missing; then its slip and its remark."""
    a = spec.authors
    if status in (AUTHORS_STATUS, AUTHORS_ERROR_STATUS):
        explanation = a.note or explanation or ""
        if ok and spec.vacuous:
            explanation += f" Ours (the thesis's text) agrees too, without information: {spec.vacuous}"
    elif status == VACUOUS_STATUS:
        explanation = " ".join(t for t in (spec.vacuous if judged_on == "ours" else a.vacuous, explanation) if t)
    elif status == INCONCLUSIVE_STATUS:
        explanation = explanation or ""
    elif explanation is None:
        if ok is None:
            explanation = "Not computed: the runs behind this row are missing from the results store."
        elif note is not None and not ok:
            explanation = note.fill(spec.note_values)
        elif status == "open":
            # No chapter explains this gap yet: say so, and what would settle it.
            also = ", and so does ours under the authors' settings" if a.ok is False else ""
            explanation = (f"Open: ours misses this row's rule{also}, and no chapter explains the gap yet; "
                           "what is missing is the setting or the run that accounts for it.")
        else:
            explanation = ""
    return " ".join(t for t in (explanation, spec.slip_note, spec.remark) if t)


@dataclass
class Builder:
    """Collects rows; :attr:`rows` judges them: the rules of the closed forms, and the tests of the rows
    judged on runs, corrected together (:mod:`~safepg.thesis.scorecard.verdicts`)."""

    book: Path = BOOK
    specs: list[RowSpec] = field(default_factory=list)

    def add(self, spec: RowSpec) -> None:
        """Add the row ``spec`` describes (judged with the others by :attr:`rows`)."""
        self.specs.append(spec)

    @property
    def rows(self) -> list[Row]:
        """Every row added, judged.

        Raises
        ------
        MissingValueError
            If a row's note is filled and quotes values the row does not give.
        """
        judged = [self._judged_spec(spec) for spec in self.specs]
        tests = [(i, side, t) for i, (spec, columns) in enumerate(zip(self.specs, judged))
                 for side, t in columns.items() if t is not None]
        # A test with too few runs for its statistic (Hotelling's with no more runs than blocks) tests nothing:
        # it is not in the family, and its column is inconclusive.
        family = [(i, side, t) for i, side, t in tests if math.isfinite(t.p_value)]
        rejected, level, own = correct([t.p_value for _, _, t in family])
        verdicts: dict[tuple[int, str], ColumnVerdict] = {}
        for (i, side, t), r, o in zip(family, rejected, own):
            verdicts[(i, side)] = column_verdict(t, bool(r), level, float(self.specs[i].relevance or 0.0), float(o))
        for i, side, t in tests:
            if (i, side) not in verdicts:
                verdicts[(i, side)] = column_verdict(t, False, level, float(self.specs[i].relevance or 0.0))
        return [self._row(spec, verdicts.get((i, "ours")), verdicts.get((i, "authors")))
                for i, spec in enumerate(self.specs)]

    @staticmethod
    def _judged_spec(spec: RowSpec) -> dict[str, Any]:
        """The tests that enter the family: a row judged on runs, on its columns whose campaign is whole."""
        if spec.kind not in RANDOM_KINDS:
            return {}
        ours = None if partly_computed(spec) else spec.test
        return {"ours": ours, "authors": spec.authors.test}

    def _row(self, spec: RowSpec, ours_v: ColumnVerdict | None, theirs_v: ColumnVerdict | None) -> Row:
        ok, explanation = spec.ok, spec.explanation
        if partly_computed(spec):
            ok, explanation = None, (f"Not judged: only {spec.seeds} of {spec.expected_seeds} seeds are in the "
                                     "results store.")
        note = note_of(spec.note_id or spec.id)
        a, out = spec.authors, spec.output or Output(value=None, text="", source="")
        random = spec.kind in RANDOM_KINDS
        if random:
            ok = None if ours_v is None else ours_v.conclusive
            status, judged_on = _random_status(ours_v, theirs_v, spec, note)
            a_ok = None if theirs_v is None else theirs_v.conclusive
        else:
            status, judged_on = _status(ok, spec, note)
            a_ok = a.ok
        on_authors = judged_on == "authors' settings"
        # An agreement without information, on a column the status did not come from, is still said.
        no_information = (spec.vacuous if ok else "") or (a.vacuous if a_ok else "")
        judged = theirs_v if on_authors else ours_v
        tests = " ".join(verdict_sentence(v, t.name, spec.show, float(spec.relevance or 0.0), on)
                         for v, t, on in ((ours_v, spec.test, "ours"),
                                          (theirs_v, a.test, "ours under the authors' settings"))
                         if v is not None and t is not None)
        if random and ok is False and status == INCONCLUSIVE_STATUS and explanation is None:
            explanation = tests
        text = _explanation(ok if not random or ok else (None if ours_v is None else False), explanation, status,
                            judged_on, spec, note)
        if random and status not in (INCONCLUSIVE_STATUS, "reproduced") and tests:
            text = " ".join(t for t in (text, tests) if t)
        return Row(
            id=spec.id, group=spec.group, quantity=spec.quantity, where=spec.where, thesis=spec.thesis,
            ours=spec.ours, difference=spec.difference, status=status, rule=spec.rule, explanation=text,
            link=self._link(status, ok, spec, note), thesis_value=spec.thesis_value, ours_value=spec.ours_value,
            ours_ci95=spec.ours_ci95, seeds=spec.seeds, thesis_tex=spec.thesis_tex, ours_tex=spec.ours_tex,
            fields=spec.fields, judged_on=judged_on, authors=a.text, authors_value=a.value, authors_ci95=a.ci95,
            authors_seeds=a.seeds, authors_experiment=a.experiment, authors_output=out.text,
            authors_output_value=out.value, authors_output_source=out.source, slip=bool(spec.slip_note),
            kind=spec.kind, judged_interval=a.interval if on_authors else spec.interval,
            judged_interval_text=a.interval_text if on_authors else spec.interval_text,
            judged_seeds=a.seeds if on_authors else spec.seeds, no_information=no_information,
            test=(spec.test or a.test).name if random and (spec.test or a.test) is not None else "",
            p_value=_number(None if ours_v is None else ours_v.p_value),
            authors_p_value=_number(None if theirs_v is None else theirs_v.p_value),
            level=_number(None if judged is None else judged.level),
            detectable=None if judged is None or judged.rejected or not math.isfinite(judged.detectable)
            else judged.detectable,
            relevance=_number(spec.relevance) if random else None, relevance_text=spec.relevance_text,
            seeds_needed=None if ours_v is None else ours_v.seeds_needed,
            authors_seeds_needed=None if theirs_v is None else theirs_v.seeds_needed,
            test_text=tests, sources=list(spec.sources), authors_sources=list(a.sources),
            state=_state(ours_v), authors_state=_state(theirs_v),
            verdict="" if judged is None else short_verdict(judged, (a.test if on_authors else spec.test).name,
                                                             spec.show))

    def _link(self, status: Status, ok: bool | None, spec: RowSpec, note: Note | None) -> str:
        """Where the row's status is discussed: the authors' settings, its note's section, or its own."""
        if status in (AUTHORS_STATUS, AUTHORS_ERROR_STATUS):
            return book_link(spec.page, AUTHORS_HEADING, self.book)
        if note is not None and not ok:
            return book_link(note.page, note.heading, self.book)
        return book_link(spec.page, spec.heading, self.book)

