"""The reproduction scorecard (safepg.thesis.scorecard): tolerances, completeness, statuses, export.

The rows are built from a tiny store: every experiment the scorecard reads, scaled to 2
seeds and a few thousand trajectories (the cart-pole runs start from theta = 0 instead of
the baseline, so no baseline search is needed). The numbers are meaningless at that scale;
what is tested is that every printed result gets a row, that the status follows the
stated rule, that every row links to a section of the book, and that the files round-trip.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from typing import NamedTuple

import numpy as np
import pytest
import sympy as sp
from scorecard_fakes import FakeTest

from safepg import theory
from safepg.thesis import errata
from safepg.thesis import scorecard as sc
from safepg.thesis.experiment_store import run_experiment
from safepg.thesis.experiments import get_experiment, scaled
from safepg.thesis.scorecard import links as sc_links
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec

BOOK_PAGES = {"preliminaries", "adaptive_step", "adaptive_batch", "lqg1d", "lqg2d", "cartpole", "errata"}


def tiny_experiments() -> dict:
    exps = {n: scaled(get_experiment(n), seeds=2, budget=4000) for n in sc.NEEDED}
    for n in ("table-5.1", "table-5.1-printed-theta0", "table-5.1-authors", "table-5.1-authors-tail"):
        # >= twice its largest batch: the authors' count needs two batch starts.
        exps[n] = scaled(get_experiment(n), seeds=2, budget=20_000)
    for n in sc.RANGE_VARIANTS:
        exps[n] = scaled(get_experiment(n), seeds=2, budget=4000)
    for n in ("table-5.2-authors", "figures-5.1-5.2-authors", "table-5.3-authors"):
        exps[n] = scaled(get_experiment(n), seeds=2, budget=4000)
    for n in ("cartpole-baseline", "cartpole-baseline-authors"):
        exps[n] = scaled(get_experiment(n), seeds=2, budget=8000)
    # The doubled-pole runs start from theta = 0 (no baseline search); 16000 trajectories give the
    # authors' count two batches of the vanilla N = 4000 before the budget.
    for n, budget in (("table-5.4", 8000), ("table-5.4-authors", 16_000), ("table-5.4-authors-theta-star", 16_000)):
        e = get_experiment(n)
        exps[n] = replace(e, seeds=2, configs=tuple(replace(c, warm_start=None, warm_start_key=None,
                                                            theta0=c.theta0 if c.warm_start is None else (0.0,) * 4,
                                                            budget=budget) for c in e.configs))
    return exps


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    root = tmp_path_factory.mktemp("store")
    exps = tiny_experiments()
    for n in sc.AUTHORS_VARIANTS:  # read, never computed, by the scorecard
        run_experiment(exps[n], root=root, jobs=1, progress=False)
    rows = sc.scorecard(root, run=True, experiments=exps, jobs=1)
    return root, exps, rows


@pytest.fixture(scope="module")
def rows(store):
    return store[2]


def by_id(rows):
    return {r.id: r for r in rows}


# ------------------------------------------------------------------ tolerances
@pytest.mark.parametrize("printed, half", [("-0.59", 0.005), ("-13.21", 0.005), ("-0.588", 0.0005),
                                           ("1.4e-06", 5e-8), ("-0.014676", 5e-7), ("72", 0.5), ("2500", 50),
                                           ("500", 50), ("0.16", 0.005), ("-422.616", 0.0005), ("0", 0.5)])
def test_half_unit_of_the_last_printed_digit(printed, half):
    assert sc.half_unit(printed) == pytest.approx(half)


def test_half_unit_refuses_text():
    with pytest.raises(ValueError, match="printed"):
        sc.half_unit("about 5")


def test_rounding_rule_boundaries():
    assert sc.within_rounding(-0.585, "-0.59") and sc.within_rounding(-0.595, "-0.59")
    assert not sc.within_rounding(-0.5849, "-0.59") and not sc.within_rounding(-0.5951, "-0.59")
    # A printed 0 (the coordinate step's off-diagonal entries) must be exactly 0.
    assert sc.within_rounding(0.0, "0") and not sc.within_rounding(1e-12, "0")


def test_interval_rules_boundaries():
    assert sc.intervals_overlap([-1.0, -0.5], [-0.5, 0.0])  # touching ends overlap
    assert not sc.intervals_overlap([-1.0, -0.51], [-0.5, 0.0])
    assert sc.intervals_overlap([-9.6619, -9.6627], [-9.6626, -9.6600])  # swapped ends as printed
    assert sc.in_prediction("-20.50", [-20.495, -20.40])  # widened by 0.005
    assert not sc.in_prediction("-20.50", [-20.494, -20.40])
    assert sc.in_prediction("72", [68.9, 71.6]) and not sc.in_prediction("72", [68.9, 71.4])
    assert sc.in_prediction("0", None, [0.0, 0.0]) and not sc.in_prediction("0", [-1.0, 1.0], [0.0, 1e-9])
    assert sc.in_prediction("72", None) is None  # no interval (fewer than two seeds): not judged


def test_ratio_rule_is_five_points():
    assert sc.within_points(0.55, 0.50) and sc.within_points(0.45, 0.50)
    assert not sc.within_points(0.5501, 0.50) and not sc.within_points(0.4499, 0.50)


def test_order_rule():
    assert sc.order_of_magnitude(1e-5) == -5 and sc.order_of_magnitude(9.99e-6) == -6
    assert sc.order_of_magnitude(6.19e-6) == -6
    with pytest.raises(ValueError, match="x must"):
        sc.order_of_magnitude(0.0)


def test_every_rule_is_stated():
    assert set(sc.RULES) == {"closed-form", "rounded", "welch", "prediction", "reading", "ratio-points", "order",
                             "set", "curve"}
    assert all(len(text) > 40 for text in sc.RULES.values())
    assert set(sc.KIND_RULE) == set(sc.KINDS) and all(len(text) > 40 for text in sc.KIND_RULE.values())
    assert len(sc.RELEVANCE) >= 5 and all(len(text) > 10 for text in sc.RELEVANCE.values())
    assert "Benjamini-Hochberg" in sc.CORRECTION and f"{sc.FDR_LEVEL:.0%}" in sc.CORRECTION


# ------------------------------------------------------------------ statuses
class Why(NamedTuple):
    why: str


def _spec(row_id: str, ok: bool | None, **more) -> RowSpec:
    """A synthetic row of Section 5.1 judged by the rounding rule (a closed form: no test)."""
    judgement = {"rule": "rounded", "kind": "closed form", **more}
    return RowSpec(id=row_id, group="Section 5.1", quantity="q", where="w", page="lqg2d", heading="Table 5.3",
                   thesis="1", ours="2", difference="+1", ok=ok, **judgement)


def test_status_follows_rule_and_note(monkeypatch):
    monkeypatch.setitem(sc.NOTES, "x/explained", sc.Note("Because of {why}.", "lqg1d", "Table 5.1", measured=Why))
    monkeypatch.setitem(sc.NOTES, "x/known", sc.Note("Open: {why}.", "lqg1d", "Table 5.2", explains=False,
                                                     measured=Why))
    b = Builder()
    why = Why("a reason")
    b.add(_spec("x/ok", True))
    b.add(_spec("x/explained", False, note_values=why))
    b.add(_spec("x/known", False, note_values=why))
    b.add(_spec("x/unknown", False))
    b.add(_spec("x/missing", None))
    b.add(_spec("x/explained", None))  # no runs: nothing was compared, whatever the note says
    got = [(r.status, r.explanation) for r in b.rows]
    assert got[0] == ("reproduced", "")
    assert got[1] == ("differs (explained)", "Because of a reason.")
    assert got[2] == ("open", "Open: a reason.")
    assert got[3][0] == "open" and got[3][1].startswith("Open: ours misses this row's rule")
    assert got[4][0] == "open" and "Not computed" in got[4][1]
    assert got[5][0] == "open"
    # A failing row links where its explanation points; a reproduced one where it is discussed.
    assert b.rows[0].link.startswith("lqg2d.html#") and b.rows[1].link.startswith("lqg1d.html#table-5-1")
    assert [r.judged_on for r in b.rows] == ["ours", "ours", "ours", "ours", "", ""]
    with pytest.raises(ValueError, match="rule"):
        _spec("x/bad", True, rule="nope")
    with pytest.raises(ValueError, match="kind"):
        _spec("x/bad", True, kind="a guess")


def test_status_judged_on_the_authors_column(monkeypatch):
    monkeypatch.setitem(sc.NOTES, "y/explained", sc.Note("Because.", "lqg1d", "Table 5.1"))
    b = Builder()

    def authors(ok: bool | None) -> AuthorsColumn:
        return AuthorsColumn(text="1.0", ok=ok, note="Their θ0 did it.")

    b.add(_spec("y/both", True, authors=authors(True)))  # ours first: the text's settings suffice
    b.add(_spec("y/authors", False, authors=authors(True)))
    b.add(_spec("y/explained", False, authors=authors(False)))
    b.add(_spec("y/none", False, authors=authors(None)))  # authors' runs missing: judged on ours alone
    b.add(_spec("y/slip", True, slip_note="Slip: 37.64% against 37.4%.", authors=authors(None)))
    got = [(r.status, r.judged_on, r.explanation) for r in b.rows]
    assert got[0] == ("reproduced", "ours", "")
    assert got[1] == (sc.AUTHORS_STATUS, "authors' settings", "Their θ0 did it.")
    assert got[2] == ("differs (explained)", "ours", "Because.")
    assert got[3][:2] == ("open", "ours") and "no chapter explains" in got[3][2]
    assert got[4][0] == "reproduced" and b.rows[4].slip and "37.64%" in got[4][2]
    assert not any(r.slip for r in b.rows[:4])
    assert sc.AUTHORS_STATUS in sc.STATUSES and "authors'" in sc.AUTHORS_STATUS and "only" in sc.AUTHORS_STATUS
    assert sc.AUTHORS_STATUS in sc.STATUS_RULE


def _random(row_id: str, ours: FakeTest | None, theirs: FakeTest | None = None, **more) -> RowSpec:
    """A synthetic row judged on runs, relevance 1.0."""
    authors = AuthorsColumn(text="1", test=theirs, note="Their setting did it.") if theirs else AuthorsColumn()
    return RowSpec(id=row_id, group="Section 5.1", quantity="q", where="w", page="lqg2d", heading="Table 5.3",
                   thesis="1", ours="2", difference="+1", ok=None, rule="prediction", kind="one run", test=ours,
                   relevance=1.0, authors=authors, **more)


def test_random_rows_get_their_status_from_the_corrected_tests(monkeypatch):
    """Every branch of STATUS_RULE for a row judged on runs: p-values corrected together (Benjamini-Hochberg
    at 5% over the six tests: 0.001 and 0.002 rejected, the level of the others 3 x 0.05 / 7), and a column
    that is not rejected held to the relevance (1.0) by its detectable difference, 0.1 + spread / sqrt(k)."""
    monkeypatch.setitem(sc.NOTES, "z/explained", sc.Note("Because.", "lqg1d", "Table 5.1"))
    b = Builder()
    b.add(_random("z/reproduced", FakeTest(0.5, spread=1.0)))  # 0.1 + 1/sqrt(5) = 0.55 <= 1
    b.add(_random("z/inconclusive", FakeTest(0.5, spread=4.0)))  # 1.89 > 1, and 1.5 x the floor 0.1 < 1
    b.add(_random("z/authors", FakeTest(0.001), FakeTest(0.3)))
    b.add(_random("z/explained", FakeTest(0.002), FakeTest(0.2, spread=4.0)))  # theirs inconclusive
    b.add(_random("z/missing", None))
    rows = b.rows
    got = {r.id.split("/")[1]: r for r in rows}
    assert got["reproduced"].status == "reproduced" and got["reproduced"].state == "conclusive"
    assert got["reproduced"].detectable == pytest.approx(0.1 + 1 / np.sqrt(5))
    assert got["reproduced"].level == pytest.approx(3 * 0.05 / 6)
    assert got["inconclusive"].status == sc.INCONCLUSIVE_STATUS and got["inconclusive"].seeds_needed == 20
    assert "inconclusive" in got["inconclusive"].explanation and "20 seeds would" in got["inconclusive"].explanation
    assert got["authors"].status == sc.AUTHORS_STATUS and got["authors"].judged_on == "authors' settings"
    assert got["authors"].state == "rejected" and got["authors"].authors_state == "conclusive"
    assert got["authors"].explanation.startswith("Their setting did it.")
    assert got["explained"].status == sc.INCONCLUSIVE_STATUS and got["explained"].judged_on == "authors' settings"
    assert got["missing"].status == "open" and "Not computed" in got["missing"].explanation
    assert [r.p_value for r in rows[:4]] == [0.5, 0.5, 0.001, 0.002]
    # Both columns rejected: the note decides between "differs (explained)" and "open".
    b = Builder()
    b.add(_random("z/explained", FakeTest(0.001), FakeTest(0.001)))
    b.add(_random("z/unexplained", FakeTest(0.001)))
    b.add(_random("z/other", FakeTest(0.9)))
    first, second, _ = b.rows
    assert first.status == "differs (explained)" and first.explanation.startswith("Because.")
    assert second.status == "open" and "differs" in second.explanation
    # The same p-values alone (no correction) would reject at 0.01; corrected over many tests they do not.
    b = Builder()
    for i in range(40):
        b.add(_random(f"z/many-{i}", FakeTest(0.01 if i == 0 else 0.9)))
    assert b.rows[0].status == "reproduced" and b.rows[0].level == pytest.approx(0.05 / 40)


def test_an_exact_claim_needs_every_run_to_agree():
    """Relevance 0 (a parameter that never moves): held to exactness, whatever the floor."""
    b = Builder()
    spec = _random("z/exact", FakeTest(1.0, spread=0.0, floor=0.0))
    b.add(replace(spec, relevance=0.0))
    b.add(replace(spec, id="z/moves", relevance=0.0, test=FakeTest(1.0, spread=0.5, floor=0.0)))
    exact, moves = b.rows
    assert exact.status == "reproduced" and moves.status == sc.INCONCLUSIVE_STATUS
    assert moves.seeds_needed is None and "no number" in moves.explanation


def test_slip_is_neither_rounding_nor_truncation():
    assert sc.is_slip(37.64, "37.4") and sc.is_slip(-0.0136766, "-0.014676")
    assert not sc.is_slip(37.44, "37.4") and not sc.is_slip(-0.0136782, "-0.013678")
    assert not sc.is_slip(1.475e-6, "1.4e-06")  # a truncation, one unit of the last digit at most
    assert sc.is_slip(1.51e-6, "1.4e-06")


def test_status_is_the_rule_applied(store):
    """Each row's status follows STATUS_RULE from what it carries: the closed forms' rules re-derived, the
    random rows' from their columns' states. Every rule is met, and the rejected and conclusive states
    (counted); the inconclusive state is met in :func:`test_random_rows_get_their_status_from_the_corrected_tests`."""
    _, exps, rows = store
    met: dict[str, int] = {}
    for r in rows:
        assert r.status in sc.STATUSES and r.judged_on in (*sc.JUDGED_ON, ""), r.id
        met[r.rule] = met.get(r.rule, 0) + 1
        if r.status in ("differs (explained)", "open", sc.AUTHORS_STATUS, sc.INCONCLUSIVE_STATUS):
            assert r.explanation, r.id  # no row that is not reproduced without its sentence
        if r.rule == "ratio-points" and r.ours_value is not None and r.seeds:
            ok = abs(r.ours_value - r.thesis_value) * 100 <= sc.RATIO_POINTS + 1e-9
            assert (r.status == "reproduced") == ok, r.id
        if not r.test:
            assert r.p_value is None and r.state == "", r.id
            continue
        for state in (r.state, r.authors_state):
            met[f"state {state}"] = met.get(f"state {state}", 0) + 1
        if r.state in ("rejected", "conclusive"):  # an untestable column (too few runs) has no p-value
            assert r.p_value is not None, r.id
        if r.status == "reproduced":
            assert r.state == "conclusive" and r.judged_on == "ours" and not r.no_information, r.id
        elif r.status == sc.AUTHORS_STATUS:
            assert r.state != "conclusive" and r.authors_state == "conclusive", r.id
            assert r.judged_on == "authors' settings" and r.authors not in ("", "-"), r.id
        elif r.status == sc.INCONCLUSIVE_STATUS:
            assert "inconclusive" in (r.state, r.authors_state) and "conclusive" not in (r.state, r.authors_state)
        elif r.status in ("differs (explained)", "open") and r.state:
            assert r.state == "rejected" and r.authors_state in ("", "rejected"), r.id
        if r.state == "conclusive" or (r.status == sc.AUTHORS_STATUS):
            assert r.detectable is not None and r.level is not None, r.id
    assert set(met) >= {"closed-form", "rounded", "welch", "prediction", "reading", "ratio-points", "order",
                        "set", "curve", "state rejected", "state conclusive"}, met


def test_rows_carry_the_authors_columns(store):
    _, exps, rows = store
    ids = by_id(rows)
    t51 = [r for r in rows if r.id.startswith("table-5.1/")]
    assert len(t51) == 24
    tail = _tail_cell()
    for r in t51:  # ours from the printed theta_0, the authors' settings beside (the tail cell's on its own
        # runs: test_the_tail_cell_is_judged_on_its_larger_sample), their output
        assert r.fields["theta0"] == -0.55 and r.authors_seeds == 2
        assert r.authors_experiment == ("table-5.1-authors-tail" if r.id == tail else "table-5.1-authors"), r.id
        assert r.authors_output.endswith(("/99)", "/999)", "/9999)")) and r.authors_output_source.startswith(
            "lqg/results/final/rate_N")
    for rid in ("table-5.3/adaptive/upsilon", "table-5.3/adaptive/improvement-ratio"):
        assert ids[rid].authors_experiment == "table-5.3-authors" and ids[rid].authors not in ("", "-")
    assert ids["table-5.3/adaptive/upsilon"].authors_output == "-20.4973"
    for rid in ("table-5.4/adaptive/upsilon", "table-5.4/N=4000/improvement-ratio"):
        assert ids[rid].authors_experiment == "table-5.4-authors" and ids[rid].authors not in ("", "-")
        assert "table-5.4-authors-theta-star" in ids[rid].explanation or ids[rid].status == sc.AUTHORS_STATUS
    assert ids["table-5.4/adaptive/upsilon"].authors_output == "193.1249"
    assert ids["table-5.4/N=4000/improvement-ratio"].authors_output == "44.76% (128/286)"
    assert ids["section-5.3/baseline-iterations"].authors_experiment == "cartpole-baseline-authors"
    assert ids["section-5.3/baseline-iterations"].authors_output == "72"
    # The Table 5.2 theoretical-range rows: Lemma 4.3.3's range as ours, the authors' settings beside
    # (their range 1280 and their unguarded step); ours with their range alone named in the note.
    for rid in ("table-5.2/gpomdp-hoeffding-delta=0.95", "table-5.2/gpomdp-bernstein-delta=0.95"):
        assert ids[rid].fields["theoretical_range"] is None and ids[rid].authors_experiment == "table-5.2-authors"
        assert ids[rid].authors not in ("", "-") and ids[rid].authors_seeds == 2
    assert ids["table-5.2/gpomdp-bernstein-delta=0.95"].authors_output == "-10.2159 [-10.2162; -10.2155]"


def test_a_row_judged_on_the_authors_column(rows):
    # The 2-D J(theta*): only the authors' formula (16 x the expectation, gamma = 0.9) gives -422.616, an
    # error of their code and no setting: counted apart.
    j = by_id(rows)["section-5.2/J-star"]
    assert j.status == sc.AUTHORS_ERROR_STATUS and j.judged_on == "authors' settings"
    assert j.authors_value == pytest.approx(-422.61602, abs=1e-5) and j.ours_value == pytest.approx(-26.4135, abs=1e-4)
    assert "16 times the expectation" in j.explanation and "lqgnd/lqgnd.py@92ac378" in j.explanation


def test_slips_are_named_with_both_numbers(rows):
    ids = by_id(rows)
    t51 = ids["table-5.1/sigma=1/N=1000/alpha=1e-03"]
    assert t51.slip and "37.64%" in t51.explanation and "37.4%" in t51.explanation
    assert t51.authors_output_value == pytest.approx(376 / 999)
    th = ids["section-5.2/theta-final-scalar/11"]
    assert th.slip and "-0.0136766" in th.explanation and "-0.014676" in th.explanation
    assert th.status == "differs (explained)"
    # A truncated print (1.475e-6 printed 1.4e-06) is not a slip; nor are the other cells of Table 5.1.
    assert not ids["section-5.2/theta-final-scalar/12"].slip
    assert [r.id for r in rows if r.slip and r.id.startswith("table-5.")] == [t51.id]


def test_open_rows_say_what_evidence_is_missing(rows):
    ids = by_id(rows)
    for r in rows:
        if r.status == "open":
            assert len(r.explanation) > 40, r.id
    # Table 5.3's N = 100 run: the authors' file was committed, its blob is not in their repository.
    for q in ("upsilon", "improvement-ratio"):
        r = ids[f"table-5.3/N=100/{q}"]
        assert r.authors_output == "not in their repository" and r.authors_output_value is None
        assert "2b2178b" in r.explanation and "absent" in r.explanation
    # A rejected θ22 says what is missing, with the authors' run and our seeds.
    b = Builder()
    b.add(replace(_random("section-5.2/theta-final-scalar/22", FakeTest(1e-9)), page="lqg2d",
                  note_values=sc.rules.FinalTheta("-0.0136782", "-0.01367 to -0.01362")))
    theta22 = b.rows[0]
    assert theta22.status == "open" and "What is missing" in theta22.explanation
    assert "-0.0136782" in theta22.explanation


def test_authors_runs_missing_or_partial_are_shown_not_judged(store):
    root, exps, _ = store
    more = dict(exps)
    for n in ("table-5.1-authors", "table-5.1-authors-tail"):  # one seed missing (the tail cell falls back)
        more[n] = replace(exps[n], seeds=3)
    rows = sc.scorecard(root, run=False, experiments=more)
    t51 = [r for r in rows if r.id.startswith("table-5.1/")]
    assert all("2 of 3 seeds: not judged" in r.authors and r.status != sc.AUTHORS_STATUS for r in t51)
    empty = sc.scorecard(root / "nothing", run=False, experiments=exps)
    assert all(r.authors in ("", "-") for r in empty if r.id.startswith(("table-5.", "section-5.3")))
    assert not any(r.status == sc.AUTHORS_STATUS for r in empty if r.id.startswith("table-5."))


def test_cartpole_table_is_settled_by_the_sweep():
    """The chapter's sweep settles Table 5.4 as described as not reproducible: a cell rejected on both
    columns is explained, and links there."""
    b = Builder()
    b.add(replace(_random("table-5.4/adaptive/upsilon", FakeTest(1e-6), FakeTest(1e-6)), page="cartpole",
                  note_values=sc.rules.CertifiedSteps("1e-8 to 2e-8")))
    r = b.rows[0]
    assert r.status == "differs (explained)" and r.explanation.startswith("Not reproducible")
    assert r.link == "cartpole.html#what-the-sweep-says"


def test_theory_rows_follow_safepg_theory(rows):
    ids = by_id(rows)
    for v in errata.verified():
        assert ids[f"theory/{v.id}"].status == "reproduced", v.id
    for e in errata.errata():
        if e.kind in ("reference", "proof"):
            assert f"theory/{e.id}" not in ids
        else:
            r = ids[f"theory/{e.id}"]
            assert r.status == "differs (explained)" and r.link.startswith("errata.html"), e.id
    star = ids["theory/thm_4_3_2_improvement"]
    assert "393" in star.thesis and "4·c" in star.difference
    alpha = ids["theory/thm_4_3_2_alpha"]
    text = alpha.thesis.replace("·", "*").replace("^", "**").replace("√17", "sqrt(17)")
    assert sp.sympify(text, locals={"c": theory.c}) == (13 - 3 * sp.sqrt(17)) / (4 * theory.c)


# ------------------------------------------------------------------ completeness
def test_every_printed_result_has_a_row(store):
    _, exps, rows = store
    ids = by_id(rows)
    assert len(ids) == len(rows), "row ids must be unique"
    t51 = exps["table-5.1"]
    for c in t51.configs:
        r = ids[f"table-5.1/sigma={c.sigma:g}/N={c.method.batch_size}/alpha={c.method.step.alpha:.0e}"]
        assert r.thesis_value == t51.thesis[c.name]["improvement_ratio"]
    assert sum(i.startswith("table-5.1/") for i in ids) == 24
    t52 = exps["table-5.2"]
    got52 = {(r.fields["estimator"], r.fields["bound"], r.fields["empirical_range"], r.fields["delta"]): r
             for r in rows if r.id.startswith("table-5.2/")}
    assert len(got52) == 12
    for c in t52.configs:
        e = c.method.error
        r = got52[(c.method.gradient.estimator, e.bound, e.empirical_range, e.delta)]
        assert r.thesis_value == t52.thesis[c.name]["upsilon_bar"]
        assert r.fields["thesis_ci95"] == list(t52.thesis[c.name]["ci95"])
    for table, n in (("table-5.3", 3), ("table-5.4", 2)):
        exp = exps[table]
        for c in exp.configs:
            assert ids[f"{table}/{c.name}/upsilon"].thesis_value == exp.thesis[c.name]["upsilon_bar"]
            assert ids[f"{table}/{c.name}/improvement-ratio"].thesis_value == exp.thesis[c.name]["improvement_ratio"]
        assert sum(i.startswith(f"{table}/") for i in ids) == 2 * n
    f = exps["figures-5.5-5.6"]
    for c in f.configs:
        printed = np.asarray(f.thesis[c.name]["theta_final"])
        for (i, j), p in np.ndenumerate(printed):
            assert ids[f"section-5.2/theta-final-{c.name}/{i + 1}{j + 1}"].thesis_value == p
        assert ids[f"figures-5.5-5.6/{c.name}/improvement-ratio"].thesis_value == 1.0
    assert ids["section-5.3/baseline-iterations"].thesis == "72"
    for rid in ("section-5.1/theta-star", "section-5.1/J-star", "section-5.2/theta-star", "section-5.2/J-star",
                "section-5.1/step-order", "section-5.2/step-order", "section-5.2/batch-first",
                "section-5.2/batch-last", "section-5.3/components", "theory/thm_4_3_2_decimal",
                "section-5.1/improvement-ratio-adaptive"):
        assert rid in ids
    assert ids["section-5.2/J-star"].thesis_value == -422.616
    printed = exps["table-5.1-printed-theta0"].configs
    assert all(ids[f"table-5.1/sigma={c.sigma:g}/N={c.method.batch_size}/alpha={c.method.step.alpha:.0e}"]
               .fields["theta0"] == -0.55 for c in printed)
    assert ids["section-5.2/theta-star"].thesis_value == -0.588
    assert set(r.group for r in rows) == set(sc.GROUPS)


def test_closed_forms_are_ours(rows):
    ids = by_id(rows)
    assert ids["section-5.1/theta-star"].ours_value == pytest.approx(-0.5884, abs=1e-4)
    assert ids["section-5.1/J-star"].ours_value == pytest.approx(-13.2068, abs=1e-4)
    assert ids["section-5.1/theta-star"].status == "reproduced"
    assert ids["section-5.2/theta-star"].status == "reproduced"  # with gamma = 0.9, said in the row
    assert "0.95" in ids["section-5.2/theta-star"].explanation


def test_missing_runs_are_open_not_reproduced(tmp_path):
    exps = {n: scaled(e, seeds=1, budget=2000) for n, e in tiny_experiments().items()}
    rows = sc.scorecard(tmp_path, run=False, experiments=exps)
    measured = [r for r in rows if r.id.startswith(("table-5.", "figures-5.5", "section-5.3/"))]
    assert measured and all(r.status == "open" and r.ours_value is None for r in measured)
    assert all(r.explanation for r in measured)
    # A missing run is said by its own sentence; no note is left with an unfilled value.
    assert all("(not computed)" not in r.explanation for r in rows)
    assert all(r.explanation.startswith("Not computed: the runs behind this row are missing") for r in measured)


def test_unknown_experiment_name_is_refused():
    with pytest.raises(ValueError, match="experiments"):
        sc.scorecard(experiments={"table-9.9": get_experiment("table-5.1")})


# ------------------------------------------------------------------ links
def test_every_row_links_to_a_section_of_the_book(rows):
    for r in rows:
        m = re.fullmatch(r"([a-z_0-9]+)\.html(?:#([a-z0-9-]+))?", r.link)
        assert m, (r.id, r.link)
        page, anchor = m.groups()
        assert page in BOOK_PAGES, r.id
        if r.status == sc.AUTHORS_STATUS and not anchor:
            continue  # the chapter's section on the authors' settings, while it has no heading of that name
        assert anchor, f"{r.id} links to {page} without an anchor"
        headings = [sc_links.heading_id(text) for _, text in sc_links.headings(page)]
        assert anchor in headings, (r.id, r.link)


def test_links_follow_headings(tmp_path):
    import nbformat

    cell = nbformat.v4.new_markdown_cell("# Chapter: Table 5.9\n\n## Table 5.9 and $\\alpha$")
    nb = nbformat.v4.new_notebook(cells=[cell])
    nbformat.write(nb, tmp_path / "page.ipynb")
    assert sc.book_link("page", "Table 5.9", tmp_path) == "page.html#table-5-9-and-alpha"  # section over title
    assert sc.book_link("page", "Chapter", tmp_path) == "page.html#chapter-table-5-9"
    assert sc.book_link("page", "nowhere", tmp_path) == "page.html"


# ------------------------------------------------------------------ export
def test_json_and_csv_round_trip(rows, tmp_path):
    files = sc.write_scorecard(tmp_path, rows)
    assert set(files) == {"scorecard.csv", "scorecard.json"} | {f"table-5.{k}.{x}" for k in range(1, 5)
                                                                 for x in ("csv", "json")}
    assert sc.read_scorecard_json(files["scorecard.json"]) == rows
    data = json.loads(files["scorecard.json"].read_text())
    assert data["rules"] == sc.RULES and data["counts"]["all"] == sc.counts(rows)["all"]
    csv_rows = sc.read_csv(files["scorecard.csv"])
    assert [d["id"] for d in csv_rows] == [r.id for r in rows]
    for d, r in zip(csv_rows, rows):
        assert d["status"] == r.status and d["link"] == r.link and d["thesis"] == r.thesis
        if r.ours_value is not None:
            assert float(d["ours_value"]) == r.ours_value
    for k, n in ((1, 24), (2, 12), (3, 6), (4, 4)):
        table = sc.read_csv(files[f"table-5.{k}.csv"])
        assert len(table) == n and all(t["id"].startswith(f"table-5.{k}/") for t in table)
        assert len(json.loads(files[f"table-5.{k}.json"].read_text())["rows"]) == n
    t51 = sc.read_csv(files["table-5.1.csv"])
    assert {"sigma", "N", "alpha", "thesis", "ours", "status", "judged_on", "authors", "authors_output",
            "authors_output_source", "slip"} <= set(t51[0])
    new_columns = {"judged_on", "authors", "authors_value", "authors_ci95_low", "authors_ci95_high", "authors_seeds",
                   "authors_experiment", "authors_output", "authors_output_value", "authors_output_source", "slip"}
    assert new_columns <= set(sc.CSV_COLUMNS) and new_columns <= set(csv_rows[0])
    for d, r in zip(csv_rows, rows):
        assert d["judged_on"] == r.judged_on and d["authors"] == r.authors and d["slip"] == str(r.slip)
        assert d["authors_output"] == r.authors_output
        if r.authors_ci95:
            assert float(d["authors_ci95_low"]) == r.authors_ci95[0]
    t51json = json.loads(files["table-5.1.json"].read_text())["rows"]
    assert all("authors_output" in d and "judged_on" in d for d in t51json)


def test_counts_and_html(rows):
    c = sc.counts(rows)
    assert list(c)[:-1] == list(sc.GROUPS) and list(c)[-1] == "all"
    assert sum(c["all"].values()) == len(rows)
    assert sum(sum(v.values()) for g, v in c.items() if g != "all") == len(rows)
    page = sc.summary_html(rows) + "".join(sc.group_html(rows, g) for g in sc.GROUPS)
    assert page.count("<tr class=\"sc-row\" id=\"sc-") == len(rows)
    # each row has its own anchor, which other pages (the front page) link to
    assert len({sc.row_anchor(r.id) for r in rows}) == len(rows)
    assert sc.row_anchor("section-5.2/J-star") == "sc-section-5.2-J-star"
    assert sc.row_anchor("figure-5.1/gpomdp-chebyshev-delta=0.95") == "sc-figure-5.1-gpomdp-chebyshev-delta-0.95"
    judged = sum(r.judged_on == "authors' settings" for r in rows)
    assert judged and page.count('data-judged-on="authors&#x27; settings"') == judged
    assert all(s.replace("'", "&#x27;") in page for s in sc.STATUSES)
    # The authors' columns appear in the groups of Chapter 5 only (the closed forms have none).
    assert "authors&#x27; output" in sc.group_html(rows, "Section 5.1")
    assert "authors&#x27; output" not in sc.group_html(rows, "Appendix B")
    assert 'class="sc-slip"' in sc.group_html(rows, "Section 5.1")
    assert "https://github.com/T3p/adaptive-batch-size/blob/47aac1b/lqg/results/final/" in page
    assert page.count('class="sc-scroll"') == len(sc.GROUPS) + 1 and page.count("<style>") == 1
    assert all(f'href="{r.link}"' in page for r in rows)


def test_reconstructed_settings_are_said(rows):
    t51 = [r for r in rows if r.id.startswith("table-5.1/")]
    assert t51
    for r in t51:
        if r.status == sc.AUTHORS_STATUS:  # which setting did it, and our reconstruction beside
            assert "-0.55" in r.explanation and "-0.575853" in r.explanation and "reconstruction" in r.explanation
        if r.status == "open" and r.p_value is not None:
            assert "-0.55" in r.explanation and "-0.575853" in r.explanation, r.id


def test_partly_computed_store_is_not_judged(store):
    root, exps, _ = store
    more = {n: replace(e, seeds=e.seeds + 1) for n, e in exps.items()}  # one seed missing everywhere
    rows = sc.scorecard(root, run=False, experiments=more)
    measured = [r for r in rows if r.id.startswith(("table-5.", "figures-5.5", "section-5.3/", "section-5.2/batch",
                                                    "section-5.2/step", "section-5.1/step",
                                                    "section-5.1/improvement", "section-5.2/theta-final"))]
    assert measured and all(r.status == "open" for r in measured), [r.id for r in measured if r.status != "open"]
    assert any("2 of 3 seeds" in r.explanation for r in measured)


def test_rows_of_some_pages_equal_the_full_cards_rows(store):
    """``pages`` keeps the rows linking to those pages, in the card's order; a theory page's
    rows (all closed forms) come without reading any run, the same rows as the full card's."""
    root, exps, rows = store
    page_of = {r.id: r.link.split(".html", 1)[0] for r in rows}
    assert set(page_of.values()) <= BOOK_PAGES
    for page in sorted(BOOK_PAGES - set(sc.RUN_PAGES)):
        want = [r for r in rows if page_of[r.id] == page]
        assert want and sc.scorecard(root, experiments=exps, pages=[page]) == want
    want = [r for r in rows if page_of[r.id] in ("lqg2d", "errata")]
    assert sc.scorecard(root, experiments=exps, pages=("lqg2d", "errata")) == want


def test_every_authors_curve_is_a_figure_row(rows):
    figures = [r for r in rows if r.kind == "whole curve"]
    assert {r.id.split("/")[0] for r in figures} >= {f"figure-5.{k}" for k in (1, 2, 3, 4, 5, 6, 8, 9)}
    assert len(figures) >= 7 and all(r.id.startswith("figure-5.") and r.rule == "curve" for r in figures)
    tests = {r.test for r in figures if r.test}
    assert {"permutation, Hotelling T²", "Hotelling F, one curve"} <= tests, tests
    for r in figures:
        # Figures 5.1-5.4 against their five runs, the others against their one run.
        five = (r.id.split("/")[0] in ("figure-5.1", "figure-5.2", "figure-5.3", "figure-5.4")
                and "bernstein-er" not in r.id)
        assert r.test in ("", "permutation, Hotelling T²" if five else "Hotelling F, one curve"), r.id
        # The share inside our band stays, as a description.
        assert "prediction band" in r.judged_interval_text or r.judged_on == "", r.id


def _tail_cell() -> str:
    """The id of the Table 5.1 row that table-5.1-authors-tail runs again with more seeds."""
    tail = get_experiment("table-5.1-authors-tail").single_config()
    return f"table-5.1/sigma={tail.sigma:g}/N={tail.method.batch_size}/alpha={tail.method.step.alpha:.0e}"


def test_the_tail_cell_is_judged_on_its_larger_sample(store):
    """That row's authors' column is judged on the tail's runs once all are stored, on
    table-5.1-authors' while some are missing."""
    root, exps, rows = store
    tail = _tail_cell()
    assert by_id(rows)[tail].authors_experiment == "table-5.1-authors-tail"
    partial = sc.scorecard(root, run=False, experiments={
        **exps, "table-5.1-authors-tail": replace(exps["table-5.1-authors-tail"], seeds=3)})
    assert by_id(partial)[tail].authors_experiment == "table-5.1-authors"
