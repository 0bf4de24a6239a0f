"""The authors' curves against our prediction bands (safepg.thesis.curve_bands, safepg.stats.prediction_band95)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.stats

from safepg.stats import prediction_band95
from safepg.thesis import authors
from safepg.thesis.curve_bands import (
    CURVE_SHARE,
    CurveScore,
    band_share,
    curve_holds,
    curve_score_rows,
    curve_scores,
    outside_sentence,
    written_rounding,
)


@pytest.mark.parametrize("runs", [1, 5])
def test_half_width_is_t_times_s_times_root(runs: int) -> None:
    rng = np.random.default_rng(0)
    values = rng.normal(3.0, 2.0, size=(6, 40))
    values[4:, 30:] = np.nan  # two seeds ended: k = 4 there
    values[1:, 38:] = np.nan  # one seed left: no band
    mean, half, k = prediction_band95(values, runs)
    for j in range(40):
        col = values[:, j][~np.isnan(values[:, j])]
        assert k[j] == col.size
        assert mean[j] == pytest.approx(col.mean(), rel=1e-14)
        if col.size < 2:
            assert math.isnan(half[j])
            continue
        direct = scipy.stats.t.ppf(0.975, col.size - 1) * col.std(ddof=1) * math.sqrt(1 / runs + 1 / col.size)
        assert half[j] == pytest.approx(direct, rel=1e-12)


def test_band_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="^runs"):
        prediction_band95(np.zeros((3, 2)), runs=0)
    with pytest.raises(ValueError, match="^values"):
        prediction_band95(np.zeros(3))


def _seeds(points: int) -> tuple[np.ndarray, float]:
    """Four seeds, -1, 1, -1, 1 at every point: mean 0, s = sqrt(4/3); and the one-run half-width."""
    ours = np.tile(np.array([[-1.0], [1.0], [-1.0], [1.0]]), (1, points))
    half = scipy.stats.t.ppf(0.975, 3) * math.sqrt(4 / 3) * math.sqrt(1 + 1 / 4)
    return ours, half


def test_curve_half_outside_scores_one_half_with_its_range_and_excess() -> None:
    ours, half = _seeds(20)
    x = 1000.0 * np.arange(1, 21)
    theirs = np.zeros(20)
    theirs[10:] = 2 * half  # outside by one half-width from x = 11000 to 20000
    s = band_share(x, theirs, ours)
    assert s["points"] == 20 and s["without_band"] == 0 and s["seeds"] == 4
    assert s["share_inside"] == 0.5
    (lo, hi, excess, widths), = s["outside"]
    assert (lo, hi) == (11000.0, 20000.0)
    assert excess == pytest.approx(half, rel=1e-12)
    assert widths == pytest.approx(1.0, rel=1e-12)


def test_ranges_break_at_inside_points_and_points_without_band_are_counted() -> None:
    ours, half = _seeds(10)
    ours[1:, 8:] = np.nan  # one seed only at the last two points: no band there
    theirs = np.zeros(10)
    theirs[[1, 2, 5]] = -3 * half
    theirs[8:] = 100.0  # not scored, whatever its value
    s = band_share(np.arange(1, 11), theirs, ours)
    assert s["points"] == 8 and s["without_band"] == 2
    assert s["share_inside"] == 5 / 8
    assert [r[:2] for r in s["outside"]] == [(2.0, 3.0), (6.0, 6.0)]
    assert s["outside"][0][3] == pytest.approx(2.0, rel=1e-12)
    # Beyond the range where ours exists, or the figure's right end: not plotted, not counted.
    longer = np.concatenate([ours, np.full((4, 5), np.nan)], axis=1)
    t = band_share(np.arange(1, 16), np.concatenate([theirs, np.zeros(5)]), longer, x_max=9)
    assert t["points"] == 8 and t["without_band"] == 1


def test_zero_width_band_excess_is_infinite_in_half_widths() -> None:
    s = band_share(np.arange(3), np.array([100.0, 101.0, 100.0]), np.full((3, 3), 100.0))
    assert s["share_inside"] == pytest.approx(2 / 3)
    assert s["outside"] == ((1.0, 1.0, 1.0, math.inf),)


def test_written_rounding_widens_a_zero_width_band_by_half_the_last_digit() -> None:
    """All seeds at theta_0 (J = -170/3): the authors wrote -56.666667, 3.3e-7 away; inside only
    when their rounding (6 decimals) is counted."""
    ours = np.full((5, 1), -170 / 3)
    theirs = np.array([-56.666667])
    assert band_share([1000], theirs, ours)["share_inside"] == 0.0
    r = written_rounding(theirs, decimals=6)
    assert r[0] == 5e-7 and band_share([1000], theirs, ours, rounding=r)["share_inside"] == 1.0
    np.testing.assert_allclose(written_rounding(np.array([-1813.33333333, 8.45497178988e-07, 0.0]), digits=12),
                               [5e-9, 5e-19, 0.0], rtol=1e-12)
    assert band_share([1000], np.array([-56.6668]), ours, rounding=r)["share_inside"] == 0.0


def test_curves_from_our_process_score_near_095() -> None:
    """Seeded Monte Carlo: 400 trials of k = 5 seeds and one new run, 50 independent normal points
    each; the mean share is 0.95 to within 0.01 (its standard error is about 0.0016)."""
    rng = np.random.default_rng(20240601)
    shares = []
    for _ in range(400):
        ours = rng.normal(-2.0, 0.3, size=(5, 50))
        theirs = rng.normal(-2.0, 0.3, size=50)
        shares.append(band_share(np.arange(50), theirs, ours)["share_inside"])
    assert abs(np.mean(shares) - 0.95) < 0.01


def test_mean_of_n_curve_uses_the_narrower_band() -> None:
    rng = np.random.default_rng(7)
    ours = rng.normal(0.0, 1.0, size=(5, 30))
    _, wide, _ = prediction_band95(ours, runs=1)
    mean, narrow, _ = prediction_band95(ours, runs=5)
    np.testing.assert_allclose(narrow / wide, math.sqrt((1 / 5 + 1 / 5) / (1 + 1 / 5)), rtol=1e-12)
    between = mean + (narrow + wide) / 2  # inside the one-run band, outside the mean-of-5 band
    assert band_share(np.arange(30), between, ours, runs=1)["share_inside"] == 1.0
    assert band_share(np.arange(30), between, ours, runs=5)["share_inside"] == 0.0
    # Means of 5 runs of the process: the mean-of-5 band holds them 95% of the time.
    shares = []
    for _ in range(300):
        seeds = rng.normal(0.0, 1.0, size=(5, 40))
        theirs = rng.normal(0.0, 1.0, size=(5, 40)).mean(axis=0)
        shares.append(band_share(np.arange(40), theirs, seeds, runs=5)["share_inside"])
    assert abs(np.mean(shares) - 0.95) < 0.012


def _fake(batch_size: np.ndarray, J: np.ndarray) -> SimpleNamespace:
    return SimpleNamespace(batch_size=batch_size, J=J, iterations=batch_size.size)


def test_curve_scores_hold_the_authors_means_against_the_mean_of_five_band() -> None:
    """Figure 5.2's Hoeffding curve against fake ``table-5.2`` seeds made around it: scored as a mean
    of 5 runs, on their grid; and Figure 5.4's five Hoeffding runs as one run each."""
    key = ("gpomdp", "hoeffding", False, 0.95)
    curve = authors.figure51_52_curves()[key]
    steps = curve["trajectories"].size
    rng = np.random.default_rng(3)
    recs = [_fake(np.full(steps, 1000.0), np.append(curve["J"], 0.0) + rng.normal(0, 1e-3, steps + 1))
            for _ in range(5)]
    scores = curve_scores({"table-5.2": {"gpomdp-hoeffding-delta=0.95": recs}})
    first = scores[0]
    assert (first.figure, first.curve, first.kind, first.seeds) == ("5.2", "gpomdp-hoeffding-delta=0.95",
                                                                    "mean of 5 runs", 5)
    assert first.points == steps and first.share_inside > 0.8
    assert first.source.startswith("processed_data/hoeffding_gpomdp_095.txt@")
    assert [s.figure for s in scores[1:]] == ["5.4"] * 5 and all(s.kind == "one run" for s in scores[1:])
    # Our fake batch sizes (1000) are not theirs: none of their points in the band.
    assert all(s.share_inside == 0.0 for s in scores[1:])


def test_rows_threshold_and_sentence() -> None:
    base = dict(figure="5.7", curve="adaptive", quantity="batch size", where="Figure 5.7", source="p@abcdef0",
                kind="one run", seeds=5, points_without_band=0, x_unit="iterations")
    good = CurveScore(**base, experiment="table-5.3", points=100, share_inside=CURVE_SHARE, outside=())
    bad = CurveScore(**base, experiment="table-5.3-authors", points=100, share_inside=0.5,
                     outside=((1.0, 50.5, 3.0, 1.5), (60.0, 60.0, 1.0, math.inf)))
    assert curve_holds(good) and not curve_holds(bad)
    rows = curve_score_rows([good, bad])
    assert [r["id"] for r in rows] == ["figure-5.7/adaptive/table-5.3", "figure-5.7/adaptive/table-5.3-authors"]
    assert rows[1]["share"] == "50.0% of 100 points" and rows[1]["share_inside"] == 0.5
    assert outside_sentence(good) == "inside the band at every scored point."
    assert rows[1]["outside"] == ("leaves it on 2 ranges of iterations: 1–50.5 (by up to 3, 1.5 half-widths); "
                                  "60 (by up to 1, ∞ half-widths).")
    assert curve_score_rows([good])[0]["id"] == "figure-5.7/adaptive"


def test_figures_51_52_under_the_authors_processing() -> None:
    """Seeds made of their own run 1 (with tiny noise), stored as our runs under their settings: their
    curve, which is that run through scaleData.m, lies inside the band for one run at every point; held
    as the text reads it (the policy in use, against the band for a five-run mean), the same seeds are
    one update ahead of it and leave it."""
    key = ("gpomdp", "chebyshev", False, 0.75)
    name = "gpomdp-chebyshev-delta=0.75"
    run1 = authors.table52_runs()[key][0]
    rng = np.random.default_rng(5)
    recs = [_fake(run1["N"].copy(), np.append(run1["J"], run1["J"][-1]) + rng.normal(0, 1e-4, run1.iterations + 1))
            for _ in range(5)]
    records = {"table-5.2": {name: recs}, "figures-5.1-5.2-authors": {name: recs}}
    scores = {s.processing: s for s in curve_scores(records) if "/run-" not in s.curve}
    theirs, text = scores["authors"], scores["text"]
    assert (theirs.kind, theirs.experiment, theirs.points) == ("one run", "figures-5.1-5.2-authors", 30_001)
    assert theirs.share_inside > 0.99  # a band of 5 noisy seeds: a few points where s happens to be small
    assert (text.kind, text.experiment) == ("mean of 5 runs", "table-5.2") and text.share_inside < 0.5
    ids = [r["id"] for r in curve_score_rows([text, theirs])]
    assert ids == [f"figure-5.1/{name}/table-5.2", f"figure-5.1/{name}/figures-5.1-5.2-authors/authors-processing"]
    # Without runs under their settings, only the text's score.
    assert {s.processing for s in curve_scores({"table-5.2": {name: recs}})} == {"text"}


def test_hypotheses_and_spread_of_figures_51_52() -> None:
    """Our "seeds" are their runs 2-5; their run 1, held out, is scored under their processing against the
    band of those four, recomputed here from scipy's t quantile (an independent band)."""
    from safepg.thesis.curve_spread import FIGURES_51_52_HYPOTHESES, figures51_52_hypotheses, figures51_52_spread

    key, name = ("gpomdp", "chebyshev", False, 0.75), "gpomdp-chebyshev-delta=0.75"
    runs = authors.table52_runs()[key]
    recs = [_fake(r["N"].copy(), np.append(r["J"], r["J"][-1])) for r in runs[1:]]
    records = {"table-5.2": {name: recs}, "figures-5.1-5.2-authors": {name: recs}}
    rows = {h["curve"]: h for h in figures51_52_hypotheses(records)}
    assert set(rows[name]) == {"curve"} | {h.label for h in FIGURES_51_52_HYPOTHESES}
    assert math.isnan(rows["gpomdp-chebyshev-delta=0.95"][FIGURES_51_52_HYPOTHESES[0].label])  # no runs
    x, theirs = authors.grid_curve(runs[0]["N"], runs[0]["J"])
    ours = np.array([authors.grid_curve(r["N"], r["J"])[1] for r in runs[1:]])
    h = scipy.stats.t.ppf(0.975, 3) * ours.std(axis=0, ddof=1) * math.sqrt(1 + 1 / 4)
    written = authors.figure51_52_curves()[key]["J"]  # their plotted curve: run 1, written with 6 decimals
    assert np.allclose(written, theirs, atol=5e-7)
    inside = np.abs(written - ours.mean(axis=0)) <= h + 5e-7
    expected = inside.mean()
    assert 0.05 < expected < 0.999  # a held-out run: neither everywhere inside nor nowhere
    assert rows[name][FIGURES_51_52_HYPOTHESES[-1].label] == pytest.approx(expected, abs=2 / x.size)
    spread = {s["curve"]: s for s in figures51_52_spread(records)}
    assert set(spread) == {name} and len(spread[name]["theirs"]) == 5 and len(spread[name]["ours"]) == 4
    assert spread[name]["theirs"][0] == pytest.approx(expected, abs=2 / x.size)


def test_curve_test_two_samples_and_one_run() -> None:
    """The curve's test takes block means over the range every curve covers: their five runs against ours by
    the permutation test, one run by Hotelling's test; a shift of theirs by many standard deviations is found
    (the smallest p of 5 against 10), the same process is not."""
    from safepg.curve_tests import CurvePredictionTest, PermutationTest
    from safepg.thesis.curve_bands import curve_test

    rng = np.random.default_rng(3)
    x = np.arange(1, 301, dtype=float)
    base = -50 + 40 * (1 - np.exp(-x / 60))

    def runs(n: int, shift: float = 0.0) -> np.ndarray:
        return base + shift + rng.normal(0, 0.5, (n, 1)) + rng.normal(0, 0.05, (n, x.size))

    ours = runs(10)
    ours[:, 280:] = np.nan  # a run that ended early: the range stops where every curve has a value
    same, y_range, x_range = curve_test(x, runs(5), ours)
    assert isinstance(same, PermutationTest) and same.p_value > 0.01 and x_range == (1.0, 280.0)
    moved, *_ = curve_test(x, runs(5, shift=5.0), ours)
    assert moved.p_value == pytest.approx(1 / 3003)
    one, *_ = curve_test(x, runs(1, shift=5.0)[0], ours)
    assert isinstance(one, CurvePredictionTest) and one.p_value < 0.05
    assert y_range[1] - y_range[0] == pytest.approx(40 * (np.exp(-1 / 60) - np.exp(-280 / 60)), abs=3.0)
    assert curve_test(x, runs(5), ours[:1])[0] is None  # one run of ours: no test
