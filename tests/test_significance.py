"""safepg.significance against independent computations: scipy's distributions (a separate implementation
of the same special functions), Monte Carlo power and level, and hand-derived cases."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import stats

from safepg import curve_tests as ct
from safepg import distributions as dist
from safepg import significance as sg


@pytest.mark.parametrize("t, df", [(0.0, 3), (1.3, 4), (2.776, 4), (4.0, 9), (10.0, 2.5), (3.0, 200)])
def test_t_p_value_is_scipy_s(t: float, df: float) -> None:
    assert dist.t_two_sided_p(t, df) == pytest.approx(2 * stats.t.sf(abs(t), df), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("f, d1, d2", [(0.5, 3, 7), (3.0, 3, 7), (9.0, 1, 4), (2.0, 2, 30)])
def test_f_p_value_is_scipy_s(f: float, d1: float, d2: float) -> None:
    assert dist.f_upper_p(f, d1, d2) == pytest.approx(stats.f.sf(f, d1, d2), rel=1e-12)


@pytest.mark.parametrize("df, alpha", [(4, 0.05), (9, 0.01), (2.5, 0.2), (30, 0.0005)])
def test_t_critical_is_scipy_s(df: float, alpha: float) -> None:
    assert dist.t_critical(df, alpha) == pytest.approx(stats.t.ppf(1 - alpha / 2, df), rel=1e-10)


@pytest.mark.parametrize("d1, d2, alpha", [(3, 7, 0.05), (1, 4, 0.01), (2, math.inf, 0.01)])
def test_f_critical_is_scipy_s(d1: float, d2: float, alpha: float) -> None:
    expected = stats.chi2.ppf(1 - alpha, d1) / d1 if math.isinf(d2) else stats.f.ppf(1 - alpha, d1, d2)
    assert dist.f_critical(d1, d2, alpha) == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("df, alpha", [(4, 0.05), (9, 0.01), (19, 0.015), (math.inf, 0.05)])
def test_t_noncentrality_gives_the_power(df: float, alpha: float) -> None:
    """At the returned noncentrality, scipy's noncentral t (or normal, df = inf) rejects 80% of the time."""
    d = dist.t_noncentrality(df, alpha)
    if math.isinf(df):
        c = stats.norm.ppf(1 - alpha / 2)
        power = stats.norm.sf(c - d) + stats.norm.cdf(-c - d)
    else:
        c = stats.t.ppf(1 - alpha / 2, df)
        power = stats.nct.sf(c, df, d) + stats.nct.cdf(-c, df, d)
    assert power == pytest.approx(0.8, abs=1e-8)


@pytest.mark.parametrize("d1, d2, alpha", [(3, 7, 0.05), (3, 2, 0.01), (2, 30, 0.001), (3, math.inf, 0.01)])
def test_f_noncentrality_gives_the_power(d1: float, d2: float, alpha: float) -> None:
    lam = dist.f_noncentrality(d1, d2, alpha)
    if math.isinf(d2):
        power = stats.ncx2.sf(stats.chi2.ppf(1 - alpha, d1), d1, lam)
    else:
        power = stats.ncf.sf(stats.f.ppf(1 - alpha, d1, d2), d1, d2, lam)
    assert power == pytest.approx(0.8, abs=1e-8)


@pytest.mark.parametrize("x, n", [(0, 300), (15, 300), (300, 300), (3, 10)])
def test_clopper_pearson_is_the_beta_quantiles(x: int, n: int) -> None:
    lo, hi = dist.clopper_pearson(x, n)
    assert lo == pytest.approx(0.0 if x == 0 else stats.beta.ppf(0.025, x, n - x + 1), abs=1e-12)
    assert hi == pytest.approx(1.0 if x == n else stats.beta.ppf(0.975, x + 1, n - x), abs=1e-12)


def test_prediction_test_by_hand() -> None:
    """x = 0.5 against 0.1 .. 0.3: mean 0.2, s = sqrt(0.025/4), T = 0.3 / (s sqrt(1 + 1/5))."""
    t = sg.PredictionTest((0.5, 0.5), (0.1, 0.2, 0.3, 0.25, 0.15))
    s = math.sqrt(0.025 / 4)
    assert t.statistic == pytest.approx(0.3 / (s * math.sqrt(1.2)), rel=1e-12)
    assert t.p_value == pytest.approx(2 * stats.t.sf(t.statistic, 4), rel=1e-12)


def test_prediction_test_widens_by_the_print_and_the_resolution() -> None:
    values = (0.1, 0.2, 0.3)
    inside = sg.PredictionTest((0.19, 0.21), values)
    assert inside.p_value == 1.0
    near = sg.PredictionTest((0.35, 0.36), values, resolution=0.2)
    assert near.distance == 0.0 and near.p_value == 1.0
    assert sg.PredictionTest((0.35, 0.36), values).distance == pytest.approx(0.15)


def test_prediction_test_when_every_seed_agrees() -> None:
    same = (1.0, 1.0, 1.0)
    assert sg.PredictionTest((1.0, 1.0), same).p_value == 1.0
    assert sg.PredictionTest((0.9, 0.9), same).p_value == 0.0
    floored = sg.PredictionTest((0.9, 0.9), same, sd_floor=0.05)
    assert 0 < floored.p_value < 1


@pytest.mark.parametrize("bad", [{"printed": (1.0, 0.0)}, {"values": (1.0,)}, {"resolution": -1.0},
                                 {"printed": (math.nan, 1.0)}])
def test_prediction_test_refuses_bad_input(bad: dict) -> None:
    kw = {"printed": (0.0, 0.0), "values": (1.0, 2.0), **bad}
    with pytest.raises(ValueError):
        sg.PredictionTest(**kw)


def test_welch_test_is_scipy_s_from_summaries() -> None:
    rng = np.random.default_rng(3)
    ours = rng.normal(0.0, 1.0, 8)
    theirs = rng.normal(0.7, 2.0, 5)
    h = stats.t.ppf(0.975, 4) * theirs.std(ddof=1) / math.sqrt(5)
    test = sg.WelchTest(float(theirs.mean()), (theirs.mean() - h, theirs.mean() + h), 5, tuple(ours))
    expected = stats.ttest_ind(ours, theirs, equal_var=False)
    assert test.p_value == pytest.approx(expected.pvalue, rel=1e-9)


def _power_by_monte_carlo(make, shift: float, alpha: float, trials: int, rng: np.random.Generator) -> float:
    return float(np.mean([make(shift, rng).p_value <= alpha for _ in range(trials)]))


def test_prediction_detectable_difference_has_its_power() -> None:
    """Normal runs: at the stated detectable difference (its estimate at sigma = 1), the test rejects 80%
    of the time (Monte Carlo, 4000 trials: standard error 0.0063), and at the level 5% of the time."""
    rng = np.random.default_rng(11)
    k, alpha = 6, 0.05
    delta = dist.t_noncentrality(k - 1, alpha) * math.sqrt(1 + 1 / k)

    def make(shift: float, rng: np.random.Generator) -> sg.PredictionTest:
        x = float(rng.normal(shift))
        return sg.PredictionTest((x, x), tuple(rng.normal(size=k)))

    assert _power_by_monte_carlo(make, delta, alpha, 4000, rng) == pytest.approx(0.8, abs=0.03)
    assert _power_by_monte_carlo(make, 0.0, alpha, 4000, rng) == pytest.approx(0.05, abs=0.012)


def test_curve_prediction_detectable_difference_has_its_power() -> None:
    """Three correlated blocks, normal: at Delta with lambda* = Delta^2 k/(k+1) 1'S^-1 1 (the true S), the
    F test rejects 80% of the time (3000 trials: standard error 0.0073)."""
    rng = np.random.default_rng(5)
    cov = np.array([[1.0, 0.5, 0.2], [0.5, 1.0, 0.5], [0.2, 0.5, 1.0]])
    chol = np.linalg.cholesky(cov)
    k, alpha = 12, 0.05
    q = np.ones(3) @ np.linalg.solve(cov, np.ones(3))
    delta = math.sqrt(dist.f_noncentrality(3, k - 3, alpha) / (k / (k + 1) * q))

    def make(shift: float, rng: np.random.Generator) -> ct.CurvePredictionTest:
        return ct.CurvePredictionTest(chol @ rng.normal(size=3) + shift, (chol @ rng.normal(size=(3, k))).T)

    assert _power_by_monte_carlo(make, delta, alpha, 3000, rng) == pytest.approx(0.8, abs=0.03)
    assert _power_by_monte_carlo(make, 0.0, alpha, 3000, rng) == pytest.approx(0.05, abs=0.013)


def test_permutation_test_counts_every_split() -> None:
    """5 against 5 in one block: p is the share of the 252 splits whose T^2 is at least the observed, by an
    independent enumeration; perfectly separated samples give the smallest p, 2/252."""
    rng = np.random.default_rng(2)
    a, o = rng.normal(size=(5, 1)), rng.normal(size=(5, 1)) + 0.3
    test = ct.PermutationTest(a, o)
    both = np.vstack([a, o])[:, 0]

    def t2(first: tuple[int, ...]) -> float:
        x = both[list(first)]
        y = np.delete(both, list(first))
        s = ((x - x.mean()) ** 2).sum() + ((y - y.mean()) ** 2).sum()
        return 5 * 5 / 10 * (x.mean() - y.mean()) ** 2 / (s / 8)

    stats_ = [t2(c) for c in itertools.combinations(range(10), 5)]
    observed = t2((0, 1, 2, 3, 4))
    assert test.p_value == pytest.approx(np.mean(np.asarray(stats_) >= observed * (1 - 1e-12)), abs=1e-12)
    apart = ct.PermutationTest(np.arange(5.0)[:, None], np.arange(5.0)[:, None] + 100)
    assert apart.p_value == pytest.approx(2 / 252) and apart.smallest_p == pytest.approx(2 / 252)


def test_permutation_test_level_is_exact_for_skewed_runs() -> None:
    """Exponential runs (far from normal), 5 against 7 in two blocks: rejections at 10% over 600 trials
    (standard error 0.012)."""
    rng = np.random.default_rng(8)
    rejected = [ct.PermutationTest(rng.exponential(size=(5, 2)), rng.exponential(size=(7, 2))).p_value <= 0.1
                for _ in range(600)]
    assert np.mean(rejected) == pytest.approx(0.1, abs=0.036)


def test_permutation_detectable_difference_needs_resolution() -> None:
    """Against five of ours the smallest p (2/252) is above a tenth of 0.05: no difference is detectable;
    against ten (1/3003) one is."""
    rng = np.random.default_rng(4)
    a = rng.normal(size=(5, 3))
    assert ct.PermutationTest(a, rng.normal(size=(5, 3))).detectable_difference(0.05) == math.inf
    assert math.isfinite(ct.PermutationTest(a, rng.normal(size=(10, 3))).detectable_difference(0.05))


def test_benjamini_hochberg_by_hand() -> None:
    """m = 5, q = 0.05: thresholds 0.01, 0.02, ..., 0.05. Sorted 0.001, 0.03, 0.04, 0.2, 0.5: only the first
    is below its threshold, so R = 1 and the next level is 2q/m = 0.02. Sorted 0.005, 0.012, 0.039, 0.04,
    0.2: the fourth is at 0.04 although the third is above 0.03, so R = 4 (the step-up)."""
    rejected, level = sg.benjamini_hochberg([0.2, 0.001, 0.04, 0.5, 0.03], 0.05)
    assert rejected.tolist() == [False, True, False, False, False] and level == pytest.approx(0.02)
    rejected, level = sg.benjamini_hochberg([0.039, 0.005, 0.2, 0.012, 0.04], 0.05)
    assert rejected.tolist() == [True, True, False, True, True] and level == pytest.approx(0.05)


def test_seeds_for_is_the_first_block_that_suffices() -> None:
    t = sg.PredictionTest((0.0, 0.0), tuple(np.linspace(-1, 1, 5)))
    target = t.detectable_difference(0.05, 15)
    assert sg.seeds_for(t, 0.05, target, block=5) == 15
    assert sg.seeds_for(t, 0.05, target * 1.0001, block=5) == 15
    assert sg.seeds_for(t, 0.05, t.detectable_difference(0.05, math.inf) * 0.99) is None


def test_all_of_is_bonferroni() -> None:
    a, b = sg.PredictionTest((0.0, 0.0), (1.0, 1.1, 1.2)), sg.PredictionTest((0.0, 0.0), (0.0, 0.1, -0.1))
    both = sg.AllOf((a, b))
    assert both.p_value == pytest.approx(min(1.0, 2 * min(a.p_value, b.p_value)))
    assert both.detectable_difference(0.05) == pytest.approx(max(a.detectable_difference(0.025),
                                                                 b.detectable_difference(0.025)))
