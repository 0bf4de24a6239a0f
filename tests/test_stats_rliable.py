"""The aggregate statistics of safepg.stats against rliable's definitions (rliable 1.2.0, metrics.py
and library.py): the IQM is ``scipy.stats.trim_mean(scores, 0.25)``, the probability of
improvement ``mannwhitneyu(x, y, alternative="greater").statistic / (n_x n_y)`` (0.5 for equal
arrays), and an interval the percentile interval of the statistic over resamples of the runs
drawn with replacement (``np.percentile`` of the bootstrap values at 2.5 and 97.5)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from safepg import stats


def rliable_iqm(x: np.ndarray) -> float:
    return float(scipy.stats.trim_mean(x, proportiontocut=0.25, axis=None))


def rliable_poi(x: np.ndarray, y: np.ndarray) -> float:
    if np.array_equal(x, y):
        return 0.5
    u, _ = scipy.stats.mannwhitneyu(x, y, alternative="greater")
    return float(u / (x.size * y.size))


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 7, 20, 21, 33])
def test_iqm_is_the_25_percent_trimmed_mean(n: int) -> None:
    rng = np.random.default_rng(n)
    for _ in range(20):
        x = rng.normal(-800, 300, n)
        assert stats.interquartile_mean(x) == pytest.approx(rliable_iqm(x), rel=1e-13, abs=1e-12)
    x = np.arange(20.0)
    assert stats.interquartile_mean(x) == np.mean(x[5:15])  # the middle half, 5 cut at each end


def test_probability_of_improvement_is_the_mann_whitney_statistic() -> None:
    rng = np.random.default_rng(2)
    for nx, ny in ((20, 20), (20, 25), (3, 1)):
        x, y = rng.normal(0, 1, nx), rng.normal(0.3, 1, ny)
        assert stats.probability_of_improvement(x, y) == pytest.approx(rliable_poi(x, y), abs=1e-15)
    x = np.array([1.0, 2.0, 2.0, 3.0])
    y = np.array([2.0, 2.0, 0.0, 5.0])  # ties count half
    assert stats.probability_of_improvement(x, y) == rliable_poi(x, y) == (1 + 1 + 1 + 3 + 0.5 * 4) / 16
    assert stats.probability_of_improvement(x, x) == 0.5
    assert stats.probability_of_improvement(np.ones(3), np.zeros(3)) == 1.0


@pytest.mark.parametrize("statistic", ["mean", "iqm"])
def test_bootstrap_interval_is_the_percentile_interval_of_resampled_runs(statistic: str) -> None:
    """The same resamples (the generator's draws), each row's statistic by rliable's definition,
    then np.percentile at 2.5 and 97.5: the interval, to rounding."""
    x = np.random.default_rng(3).normal(-500, 200, 20)
    reps = 3000
    idx = np.random.default_rng(7).integers(0, x.size, size=(reps, x.size))
    f = rliable_iqm if statistic == "iqm" else np.mean
    values = np.array([f(x[row]) for row in idx])
    expected = np.percentile(values, [2.5, 97.5])
    got = stats.bootstrap_interval(x, statistic, reps, rng=7, chunk=700)
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert got == stats.bootstrap_interval(x, statistic, reps, rng=7, chunk=3000)  # chunking changes nothing


def test_improvement_interval_resamples_each_method_independently() -> None:
    rng = np.random.default_rng(4)
    x, y = rng.normal(0, 1, 20), rng.normal(0.5, 1, 15)
    reps = 2000
    gen = np.random.default_rng(9)
    ia, ib = gen.integers(0, 20, size=(reps, 20)), gen.integers(0, 15, size=(reps, 15))
    values = np.array([rliable_poi(x[a], y[b]) for a, b in zip(ia, ib)])
    np.testing.assert_allclose(stats.improvement_interval(x, y, reps, rng=9, chunk=300),
                               np.percentile(values, [2.5, 97.5]), rtol=1e-12)


def test_intervals_cover_and_shrink() -> None:
    """A sanity check of the intervals themselves: about 95% of the mean's intervals over repeated
    samples hold the true mean; more runs, narrower intervals."""
    rng = np.random.default_rng(5)
    held = 0
    trials = 200
    for k in range(trials):
        lo, hi = stats.bootstrap_interval(rng.normal(1.0, 1.0, 40), "mean", 1000, rng=k)
        held += lo <= 1.0 <= hi
    assert 0.88 <= held / trials <= 0.99
    few = stats.bootstrap_interval(rng.normal(0, 1, 10), "iqm", 2000, rng=1)
    many = stats.bootstrap_interval(rng.normal(0, 1, 200), "iqm", 2000, rng=1)
    assert many[1] - many[0] < few[1] - few[0]


def test_aggregate_scores_and_seeding() -> None:
    x = np.random.default_rng(6).normal(-900, 100, 20)
    a = stats.aggregate_scores(x, reps=2000, rng=3)
    assert a == stats.aggregate_scores(x, reps=2000, rng=3)
    assert a["runs"] == 20 and a["mean"] == pytest.approx(np.mean(x)) and a["iqm"] == stats.interquartile_mean(x)
    assert a["mean_ci95"][0] < a["mean"] < a["mean_ci95"][1] and a["iqm_ci95"][0] < a["iqm"] < a["iqm_ci95"][1]
    assert a["mean_ci95"] != stats.aggregate_scores(x, reps=2000, rng=4)["mean_ci95"]


def test_bad_input_is_refused() -> None:
    with pytest.raises(ValueError, match="^scores"):
        stats.interquartile_mean([])
    with pytest.raises(ValueError, match="^x"):
        stats.probability_of_improvement([np.nan], [1.0])
    with pytest.raises(ValueError, match="^statistic"):
        stats.bootstrap_interval([1.0, 2.0], "median")
    with pytest.raises(ValueError, match="^reps"):
        stats.bootstrap_interval([1.0, 2.0], reps=0)
    with pytest.raises(ValueError, match="^level"):
        stats.improvement_interval([1.0], [2.0], level=1.0)
