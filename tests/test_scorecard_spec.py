"""The scorecard's typed inputs: a row is a :class:`RowSpec` whose every field is declared, and a note
quotes only the measured values it declares, which the row must give.

A value left out fails where the scorecard is built (an exception, hence a test failure), never as text
on the page; a row whose runs are missing says so by its own sentence.
"""

from __future__ import annotations

from dataclasses import FrozenInstanceError
from typing import NamedTuple

import pytest

from safepg.thesis import scorecard as sc
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.outputs import Output
from safepg.thesis.scorecard.text import MissingValueError, fill, template_fields

PLACE = dict(group="Section 5.3", quantity="q", where="Table 5.4", page="cartpole", heading="Table 5.4")
CELLS = dict(thesis="53.01%", ours="48.64%", difference="-4.37 points")
# A row judged by its rule (``ok``); rows judged on runs take a test (tests/test_scorecard.py).
JUDGEMENT = dict(rule="prediction", kind="closed form")


class Reason(NamedTuple):
    reason: str
    size: float


def spec(row_id: str = "t/row", ok: bool | None = False, **more) -> RowSpec:
    return RowSpec(id=row_id, ok=ok, **PLACE, **CELLS, **JUDGEMENT, **more)


# ------------------------------------------------------------------ templates
def test_template_fields_are_the_names_before_any_format_spec():
    assert template_fields("{J_used:.3f} at {theta} and {x.real}, {y[0]}, {z!r}") == {"J_used", "theta", "x", "y",
                                                                                      "z"}
    assert template_fields("no fields") == frozenset()


def test_fill_raises_on_a_field_not_given():
    assert fill("a {reason} of {size:.1f}", {"reason": "why", "size": 2.0}) == "a why of 2.0"
    with pytest.raises(MissingValueError, match="size"):
        fill("a {reason} of {size:.1f}", {"reason": "why"})
    with pytest.raises(KeyError):  # a MissingValueError is a KeyError
        fill("{anything}", {})


def test_a_note_naming_a_field_it_does_not_declare_cannot_be_made():
    with pytest.raises(MissingValueError, match="size"):
        sc.Note("Because of {reason}, by {size}.", "lqg1d", "Table 5.1")  # declares none
    with pytest.raises(MissingValueError, match="extent"):
        sc.Note("Because of {reason}, by {extent}.", "lqg1d", "Table 5.1", measured=Reason)
    note = sc.Note("Because of {reason}, by {size:.0f}.", "lqg1d", "Table 5.1", measured=Reason)
    assert note.fill(Reason("a reason", 3.0)) == "Because of a reason, by 3."


def test_a_note_filled_without_its_values_raises():
    note = sc.Note("Because of {reason}.", "lqg1d", "Table 5.1", measured=Reason)
    with pytest.raises(MissingValueError, match="Reason"):
        note.fill(None)

    class Other(NamedTuple):
        reason: str

    with pytest.raises(MissingValueError, match="Reason"):
        note.fill(Other("a reason"))  # the same field names, not the values this note declares
    with pytest.raises(TypeError):
        sc.Note("No fields.", "lqg1d", "Table 5.1").fill(Reason("a reason", 1.0))
    with pytest.raises(TypeError):
        Reason("a reason")  # type: ignore[call-arg]  # a value left out of the tuple itself


def test_every_note_declares_the_values_it_names():
    for key, note in sc.NOTES.items():
        declared = set(getattr(note.measured, "_fields", ()))
        assert template_fields(note.text) <= declared, key


def test_a_failing_row_whose_note_lacks_its_values_fails_the_build(monkeypatch):
    monkeypatch.setitem(sc.NOTES, "t/", sc.Note("Because of {reason}.", "lqg1d", "Table 5.1", measured=Reason))
    b = Builder()
    b.add(spec("t/failing", False))
    with pytest.raises(MissingValueError):
        b.rows  # noqa: B018  # judged when the rows are read
    b = Builder()
    # Its runs missing or partly stored, the row is not judged and says so; the note is not needed.
    b.add(spec("t/missing", None))
    b.add(spec("t/partial", False, seeds=2, expected_seeds=5))
    b.add(spec("t/reproduced", True))
    b.add(spec("t/given", False, note_values=Reason("a reason", 1.0)))
    got = {r.id: r.explanation for r in b.rows}
    assert got["t/missing"].startswith("Not computed: the runs behind this row are missing")
    assert got["t/partial"] == "Not judged: only 2 of 5 seeds are in the results store."
    assert got["t/reproduced"] == "" and got["t/given"] == "Because of a reason."
    assert not any("(not computed)" in text for text in got.values())


# ------------------------------------------------------------------ the row specification
def test_a_row_spec_missing_a_required_field_cannot_be_built():
    for missing in ("id", "group", "quantity", "where", "page", "heading", "thesis", "ours", "difference", "ok",
                    "rule", "kind"):
        given = {"id": "t/row", "ok": True, **PLACE, **CELLS, **JUDGEMENT}
        del given[missing]
        with pytest.raises(TypeError, match=missing):
            RowSpec(**given)


def test_a_row_judged_on_runs_takes_a_test_and_its_relevance():
    with pytest.raises(ValueError, match="takes a test"):
        RowSpec(id="t/row", ok=True, **PLACE, **CELLS, rule="prediction", kind="one run")
    with pytest.raises(ValueError, match="relevance"):
        RowSpec(id="t/row", ok=None, **PLACE, **CELLS, rule="prediction", kind="one run", test=object())


def test_a_row_spec_has_no_undeclared_field():
    with pytest.raises(TypeError, match="authors_seeds"):
        spec(authors_seeds=5)  # the authors' seeds belong to their column
    with pytest.raises(TypeError, match="number"):
        AuthorsColumn(number=1.0)  # type: ignore[call-arg]
    with pytest.raises(TypeError):
        RowSpec("t/row", "Section 5.3")  # type: ignore[misc]  # keywords only: no field by position
    with pytest.raises(FrozenInstanceError):
        spec().ok = True  # type: ignore[misc]


def test_the_row_takes_every_field_of_its_spec():
    authors = AuthorsColumn(experiment="table-5.4-authors", text="52.6% [40%; 60%]", value=0.526, ci95=[0.4, 0.6],
                            seeds=5, ok=True, interval=[40.0, 60.0], interval_text="[40%; 60%]", note="Their run.")
    out = Output(value=0.5301, text="53.01% (152/286)", source="cartpole/results/x.npy@1234567")
    b = Builder()
    b.add(spec("table-5.4/adaptive/improvement-ratio", False, thesis_value=0.5301, ours_value=0.4864,
               ours_ci95=[0.45, 0.52], seeds=5, fields={"method": "adaptive"}, interval=[41.8, 55.4],
               interval_text="[41.8%; 55.4%]", expected_seeds=5, authors=authors, output=out))
    r = b.rows[0]
    assert (r.status, r.judged_on, r.explanation) == (sc.AUTHORS_STATUS, "authors' settings", "Their run.")
    assert (r.authors, r.authors_value, r.authors_ci95, r.authors_seeds, r.authors_experiment) == (
        authors.text, authors.value, authors.ci95, authors.seeds, authors.experiment)
    assert (r.authors_output, r.authors_output_value, r.authors_output_source) == (out.text, out.value, out.source)
    assert r.judged_interval == [40.0, 60.0] and r.judged_seeds == 5 and r.judged_interval_text == "[40%; 60%]"
    assert (r.thesis_value, r.ours_value, r.ours_ci95, r.seeds, r.fields) == (0.5301, 0.4864, [0.45, 0.52], 5,
                                                                              {"method": "adaptive"})

