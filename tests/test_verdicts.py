"""The statistics of the scorecard's verdicts: one run judged as one run, vacuous agreement named, an
agreement through an error of the authors' code counted apart, and every row's kind and judged interval
in the files.

Synthetic rows only (no store): each rule is shown to pass and to fail.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats as scipy_stats
from scorecard_fakes import failing, passing

from safepg.stats import mean_ci95, prediction_interval95, seed_summary95
from safepg.thesis import scorecard as sc
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec


# ------------------------------------------------------------------ the prediction interval
@pytest.mark.parametrize("k", [2, 3, 5, 30])
@pytest.mark.parametrize("runs", [1, 5])
def test_prediction_interval_is_the_student_t_formula(k, runs):
    x = np.random.default_rng(k).normal(3.0, 2.0, k)
    got = prediction_interval95(x, runs=runs)
    h = scipy_stats.t.ppf(0.975, k - 1) * x.std(ddof=1) * math.sqrt(1 / runs + 1 / k)
    assert got["mean"] == pytest.approx(x.mean(), rel=1e-14)
    assert got["pi95"] == pytest.approx([x.mean() - h, x.mean() + h], rel=1e-10)
    assert got["seeds"] == k and got["runs"] == runs


def test_prediction_interval_is_wider_than_the_mean_interval_by_sqrt_k_plus_1():
    x = [70.0, 71.0, 70.0, 71.0, 71.0]  # the cart-pole baseline's iteration counts, five seeds
    ci, pi = mean_ci95(x)["ci95"], prediction_interval95(x)["pi95"]
    assert (pi[1] - pi[0]) == pytest.approx((ci[1] - ci[0]) * math.sqrt(len(x) + 1), rel=1e-12)
    # The interval of the mean rejects the printed 72; one run of the same process reaches it.
    assert not sc.in_prediction("72", ci) and sc.in_prediction("72", pi)
    assert seed_summary95(x) == {**mean_ci95(x), "pi95": pi}


def test_prediction_interval_covers_one_new_run_95_percent_of_the_time():
    # 4000 experiments of 5 seeds and one new run from the same normal process: the new run lies in
    # the interval with probability 0.95 exactly; 4000 draws put the share within 0.015 (4.4 sd).
    rng = np.random.default_rng(7)
    draws = rng.normal(0.0, 1.0, (4000, 6))
    hits = 0
    for row in draws:
        lo, hi = prediction_interval95(row[:5])["pi95"]
        hits += lo <= row[5] <= hi
    assert abs(hits / 4000 - 0.95) < 0.015


def test_prediction_interval_needs_two_seeds_and_a_run_count():
    assert prediction_interval95([1.0])["pi95"] == [None, None]
    assert prediction_interval95([])["mean"] is None
    with pytest.raises(ValueError, match="runs must"):
        prediction_interval95([1.0, 2.0], runs=0)


# ------------------------------------------------------------------ statuses
COMMON = dict(group="Section 5.3", quantity="q", where="Table 5.4", thesis="53.01%", ours="48.64%",
              difference="-4.37 points", rule="prediction", kind="one run", page="cartpole", heading="Table 5.4",
              relevance=1.0, ok=None)
FROZEN = "θ moved by at most 3.0e-07 over the run: the ratio carries no information."


def test_single_run_judged_by_its_test():
    b = Builder()
    b.add(RowSpec(id="r/inside", test=passing(), interval=[41.8, 55.4], interval_text="[41.8%; 55.4%]", seeds=5,
                  **COMMON))
    b.add(RowSpec(id="r/outside", test=failing(), interval=[41.8, 52.9], interval_text="[41.8%; 52.9%]", seeds=5,
                  **COMMON))
    assert [r.status for r in b.rows] == ["reproduced", "open"]
    assert b.rows[0].judged_interval == [41.8, 55.4] and b.rows[0].judged_seeds == 5 and b.rows[0].kind == "one run"
    assert b.rows[0].verdict.startswith("p = 0.9 (fake, 5 seeds); detects") and "differs" in b.rows[1].verdict


def test_a_vacuous_ratio_is_not_reproduced():
    b = Builder()
    b.add(RowSpec(id="v/ours", test=passing(), vacuous=FROZEN, **COMMON))
    # The authors' column moved and holds: the row is judged there, not on the frozen run.
    b.add(RowSpec(id="v/authors", test=passing(), vacuous=FROZEN, **COMMON,
                  authors=AuthorsColumn(test=passing(), text="52.6%", seeds=5, note="Their settings move θ.",
                                        interval=[40.0, 60.0], interval_text="[40%; 60%]")))
    # Both columns frozen: vacuous, judged on the authors' column where only it holds.
    b.add(RowSpec(id="v/both", test=failing(), authors=AuthorsColumn(test=passing(), vacuous=FROZEN, text="50%"),
                  **COMMON))
    b.add(RowSpec(id="v/moved", test=passing(), vacuous="", **COMMON))
    got = {r.id: r for r in b.rows}
    assert got["v/ours"].status == sc.VACUOUS_STATUS and got["v/ours"].explanation.startswith("θ moved by")
    assert got["v/authors"].status == sc.AUTHORS_STATUS and got["v/authors"].judged_on == "authors' settings"
    assert got["v/authors"].judged_interval == [40.0, 60.0] and got["v/authors"].judged_seeds == 5
    assert got["v/both"].status == sc.VACUOUS_STATUS and got["v/both"].judged_on == "authors' settings"
    assert got["v/moved"].status == "reproduced"
    assert sc.counts(b.rows)["all"]["reproduced"] == 1 and sc.counts(b.rows)["all"][sc.VACUOUS_STATUS] == 2


def test_agreement_through_an_error_of_the_authors_code_is_counted_apart():
    b = Builder()
    common = {**{k: v for k, v in COMMON.items() if k not in ("ok", "relevance")}, "rule": "rounded",
              "kind": "closed form", "thesis": "≈ -422.616"}
    b.add(RowSpec(id="e/error", ok=False, authors=AuthorsColumn(ok=True, error=True, text="-422.61600",
                                                                note="Their J is 16 times the expectation."),
                  **common))
    b.add(RowSpec(id="e/setting", ok=False, authors=AuthorsColumn(ok=True, text="-422.61600", note="A setting."),
                  **common))
    assert [r.status for r in b.rows] == [sc.AUTHORS_ERROR_STATUS, sc.AUTHORS_STATUS]
    assert "16 times" in b.rows[0].explanation
    c = sc.counts(b.rows)["all"]
    assert c[sc.AUTHORS_ERROR_STATUS] == 1 and c[sc.AUTHORS_STATUS] == 1 and list(c) == list(sc.STATUSES)


def test_the_status_rule_names_the_new_statuses():
    assert sc.VACUOUS_STATUS in sc.STATUS_RULE and sc.AUTHORS_ERROR_STATUS in sc.STATUS_RULE
    assert sc.STATUSES.index(sc.VACUOUS_STATUS) < sc.STATUSES.index("differs (explained)")


def test_kind_and_judged_interval_reach_the_files_and_the_page(tmp_path):
    b = Builder()
    b.add(RowSpec(id="table-5.4/adaptive/improvement-ratio", test=passing(), vacuous=FROZEN, interval=[41.8, 55.4],
                  interval_text="[41.8%; 55.4%]: 95% prediction interval for one run, 5 seeds", seeds=5, **COMMON))
    files = sc.write_scorecard(tmp_path, b.rows)
    row = json.loads(files["scorecard.json"].read_text())["rows"][0]
    assert row["kind"] == "one run" and row["judged_interval"] == [41.8, 55.4] and row["judged_seeds"] == 5
    csv_row = sc.read_csv(files["scorecard.csv"])[0]
    assert csv_row["kind"] == "one run" and float(csv_row["judged_interval_low"]) == 41.8
    assert csv_row["judged_seeds"] == "5" and csv_row["status"] == sc.VACUOUS_STATUS
    table = sc.read_csv(files["table-5.4.csv"])[0]
    assert table["judged_interval_text"].startswith("[41.8%; 55.4%]")
    assert sc.read_scorecard_json(files["scorecard.json"]) == b.rows
    page = sc.group_html(b.rows, "Section 5.3") + sc.summary_html(b.rows)
    assert 'data-kind="one run"' in page and "p = 0.9 (fake, 5 seeds); detects" in page
    assert 'class="sc-status sc-vacuous"' in page
    assert csv_row["test"] == "fake" and float(csv_row["p_value"]) == 0.9 and csv_row["state"] == "conclusive"


def test_a_ratio_is_tested_within_half_an_update_of_its_print():
    from safepg.thesis.scorecard.judged import ratio_test

    # Five seeds at 100% over 100 iterations (n = 98 updates in the smaller count): a printed 98.99% lies
    # half an update (0.51 points) and its last digit (0.005 points) from 100% less one update; the spread
    # is the binomial one of 0.5 worsening updates in 491, 0.32 points.
    row = {"improvement_ratio": {"values": [1.0] * 5}, "updates": [99] * 5}
    test = ratio_test(0.9899, row)
    n = 98
    q = 0.5 / (n * 5 + 1)
    assert test.resolution == pytest.approx(0.5 / n) and test.spread == pytest.approx(math.sqrt(q * (1 - q) / n))
    assert test.distance == pytest.approx(1 - 0.98995 - 0.5 / n)
    assert test.p_value == pytest.approx(2 * scipy_stats.t.sf(test.distance / (test.spread * math.sqrt(1.2)), 4))
    assert ratio_test(1.0, row).p_value == 1.0  # 100% against 100% in every seed
    assert ratio_test(0.5, {"improvement_ratio": {"values": [0.5]}, "updates": [9]}) is None  # one seed


def test_a_column_that_agrees_without_information_is_flagged_whatever_the_status(tmp_path):
    b = Builder()
    b.add(RowSpec(id="f/authors", test=passing(), vacuous=FROZEN, **COMMON,
                  authors=AuthorsColumn(test=passing(), text="53.06%", note="Their run.")))
    b.add(RowSpec(id="f/clean", test=passing(), **COMMON))
    flagged, clean = b.rows
    assert flagged.status == sc.AUTHORS_STATUS and flagged.no_information == FROZEN
    assert "agrees too, without information" in flagged.explanation and not clean.no_information
    page = sc.group_html(b.rows, "Section 5.3")
    assert page.count("no information</span>") == 1
    summary = sc.summary_html(b.rows)
    assert "of which one of ours agrees without information" in summary


def test_the_chapters_count_sentence_names_every_status_with_rows():
    b = Builder()
    b.add(RowSpec(id="c/ok", test=passing(), **COMMON))
    b.add(RowSpec(id="c/vacuous", test=passing(), vacuous=FROZEN, **COMMON))
    b.add(RowSpec(id="c/open", test=failing(), **COMMON))
    assert sc.counts_text(b.rows) == ("3 printed results: 1 reproduced, 1 that agree without carrying information, "
                                      "1 open; in 1 of them one of our columns agrees with the print without "
                                      "information")
