"""Error bounds and the meta-parameters of Chapter 4."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from safepg.bounds import (
    ErrorBound,
    bernstein,
    chebyshev,
    error_bound,
    gpomdp_variance_factor,
    gradient_range_bound,
    hoeffding,
    reinforce_variance_factor,
)
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.meta import (
    ALPHA_STAR_FACTOR,
    coordinate_step,
    guaranteed_improvement,
    n_star_bernstein_root,
    n_star_closed_form,
    n_star_search,
    n_zero,
    optimal_batch_size,
    penalty_constant,
    scalar_step,
    upsilon,
)

K1 = TaskConstants.from_task(LQG.thesis_1d(), 1.0)
pos = st.floats(min_value=1e-2, max_value=1e2, allow_nan=False)


def test_penalty_constant_by_hand():
    # LQG.thesis_1d() with sigma = 1: R = (b_s^2 + b_a^2) / 2 = 4 with b_s = b_a = 2, M_phi = b_s = 2,
    # |A| = 2 b_a = 4, gamma = 0.9
    by_hand = 4 * 4 / (0.1**2 * 1) * (4 / math.sqrt(2 * math.pi) + 0.9 / (2 * 0.1))
    assert penalty_constant(K1) == pytest.approx(by_hand, rel=1e-14)
    assert penalty_constant(K1) == pytest.approx(9753.3, abs=0.1)


def test_variance_factors_by_hand():
    g, H = 0.9, 20
    rf = (4 * 2 * (1 - g**H) / (1 - g)) ** 2 * H
    br = (1 - g ** (2 * H)) / (1 - g**2) + H * g ** (2 * H) - 2 * g**H * (1 - g**H) / (1 - g)
    assert reinforce_variance_factor(K1) == pytest.approx(rf, rel=1e-14)
    assert gpomdp_variance_factor(K1) == pytest.approx((4 * 2 / 0.1) ** 2 * br, rel=1e-14)
    assert gpomdp_variance_factor(K1) < reinforce_variance_factor(K1)
    assert gradient_range_bound(K1) == pytest.approx(2 * 20 * 2 * 2 * 4 / 0.1)


def test_bound_d_and_f():
    assert chebyshev(0.5, 8.0).d == pytest.approx(4.0)
    assert hoeffding(0.1, 3.0).d == pytest.approx(3.0 * math.sqrt(math.log(20) / 2))
    b = bernstein(0.3, 2.0, 5.0)
    assert (b.d, b.f) == pytest.approx((math.sqrt(4 * math.log(10)), 15 * math.log(10)))
    assert ErrorBound(2.0, 3.0).eps(4.0) == pytest.approx(1.75)


def test_error_bound_selects_the_right_ingredients():
    rng = np.random.default_rng(0)
    x = rng.normal(size=1000)
    er = error_bound("hoeffding", x, 0.2, K1, range="empirical")
    assert er.d == pytest.approx(np.ptp(x) * math.sqrt(math.log(10) / 2))
    th = error_bound("hoeffding", x, 0.2, K1)
    assert th.d == pytest.approx(gradient_range_bound(K1) * math.sqrt(math.log(10) / 2))
    be = error_bound("bernstein", x, 0.2, K1, range="empirical")
    assert be.d == pytest.approx(math.sqrt(2 * np.var(x, ddof=1) * math.log(15)))
    assert error_bound("chebyshev", x, 0.2, K1, "reinforce").d > error_bound("chebyshev", x, 0.2, K1).d


# ------------------------------------------------------- coverage where each bound is nearly tight
# Each bound is tested where it is close to attained, so that a bound made smaller by a factor 0.7 fails
# (the negative control: at 0.7 eps the miss rate exceeds delta), and with enough batches that both
# assertions hold by many Monte Carlo standard errors (SE), computed below from the exact miss rates.
#: Batches per Monte Carlo estimate of a miss rate: at a rate p its SE is sqrt(p (1 - p) / BATCHES),
#: 7.1e-5 at p = 0.001 and 6.7e-4 at p = 0.1.
BATCHES = 200_000
#: Hoeffding and Bernstein: batches of N = 10^5 samples of the two-point distribution {0, 1} with
#: p = 1/2 (the largest variance of a range of 1, so the tail Hoeffding bounds is the heaviest), at
#: delta = 0.001, where the smallest eps that covers is 0.84 of Hoeffding's and 0.79 of Bernstein's.
TWO_POINT_N, TWO_POINT_DELTA = 100_000, 0.001
#: The margin, in SE, that makes an assertion on a miss rate decisive.
DECISIVE_SE = 8.0


def _two_point_miss_rates(which: str, scale: float) -> tuple[float, float]:
    """Share of batches whose mean misses 1/2 by at least scale * eps: Monte Carlo over BATCHES batches, and
    exact (the binomial sum over the count of ones, which is all that a batch's mean, sample variance and
    range depend on)."""
    n, delta = TWO_POINT_N, TWO_POINT_DELTA
    k = np.arange(n + 1)
    # eps of a batch with k ones: its sample variance (ddof = 1) is k (n - k) / (n (n - 1)), its range 1.
    variance = k * (n - k) / (n * (n - 1.0))
    if which == "hoeffding":
        eps = np.full(n + 1, hoeffding(delta, 1.0).eps(n))
    else:
        eps = np.array([bernstein(delta, v, 1.0).eps(n) for v in variance])
    miss = np.abs(k / n - 0.5) >= scale * eps
    exact = float(stats.binom.pmf(k, n, 0.5)[miss].sum())
    ones = np.random.default_rng(55).binomial(n, 0.5, size=BATCHES)
    return float(miss[ones].mean()), exact


def _se(p: float) -> float:
    return math.sqrt(p * (1 - p) / BATCHES)


@pytest.mark.parametrize("which", ["hoeffding", "bernstein"])
def test_two_point_coverage_where_the_bound_is_nearly_tight(which):
    """At eps the miss rate is at most delta; at 0.7 eps it exceeds delta (the negative control).

    Exact miss rates (binomial sums): Hoeffding 9.7e-5 at eps and 6.4e-3 at 0.7 eps; Bernstein 3.3e-5 and
    3.7e-3; delta = 1e-3. With SE 7.1e-5 at delta, 1.8e-4 and 1.4e-4 at 0.7 eps: the first assertion holds by
    12.7 and 13.6 SE, the second by 30 and 19 SE.
    """
    delta = TWO_POINT_DELTA
    at_eps, exact_eps = _two_point_miss_rates(which, 1.0)
    at_07, exact_07 = _two_point_miss_rates(which, 0.7)
    # The setting is decisive: both exact rates lie many SE from delta (sizes chosen so).
    assert (delta - exact_eps) / _se(delta) > DECISIVE_SE and (exact_07 - delta) / _se(exact_07) > DECISIVE_SE
    # The Monte Carlo estimates agree with the exact rates (5 SE), and each lies on its side of delta.
    assert abs(at_eps - exact_eps) <= 5 * _se(max(exact_eps, 1 / BATCHES)) and at_eps <= delta, (at_eps, exact_eps)
    assert abs(at_07 - exact_07) <= 5 * _se(exact_07) and at_07 > delta, (at_07, exact_07)


#: Chebyshev: the mean of N = 10 draws of X in {0, +-7.5, +-10}, P(|X| = 7.5) = 0.006, P(|X| = 10) = 0.0065
#: (rare values: a batch's mean is one of them / 10 with probability about 0.06 and 0.065), at delta = 0.1.
#: Var X = 0.9875, eps = sqrt(Var X / (delta N)) = 0.9937: a batch holding one 10 misses by 1 >= eps, one
#: holding one 7.5 misses by 0.75 >= 0.7 eps = 0.6956. Chebyshev's inequality is nearly an equality here:
#: the smallest eps that covers is 0.755 of its eps.
CHEBYSHEV_X = np.array([0.0, 7.5, -7.5, 10.0, -10.0])
CHEBYSHEV_P = np.array([1 - 0.0125, 0.003, 0.003, 0.00325, 0.00325])
CHEBYSHEV_N, CHEBYSHEV_DELTA = 10, 0.1


def _chebyshev_exact_miss(eps: float) -> float:
    """P(|mean of N draws of X| >= eps), from the distribution of their sum (X in units of 2.5: 0, +-3, +-4)."""
    pmf = np.zeros(9)
    pmf[[4, 7, 1, 8, 0]] = CHEBYSHEV_P  # units -4 .. 4 at indices 0 .. 8
    total = np.array([1.0])
    for _ in range(CHEBYSHEV_N):
        total = np.convolve(total, pmf)
    mean = 2.5 * (np.arange(total.size) - 4 * CHEBYSHEV_N) / CHEBYSHEV_N
    return float(total[np.abs(mean) >= eps].sum())


def test_chebyshev_coverage_where_the_bound_is_nearly_tight():
    """At eps the miss rate is at most delta; at 0.7 eps it exceeds delta (the negative control).

    Exact miss rates: 0.0614 at eps, 0.1150 at 0.7 eps (delta = 0.1). With SE 6.7e-4 at delta and 7.1e-4 at
    0.7 eps, the first assertion holds by 57 SE, the second by 21 SE.
    """
    variance = float(CHEBYSHEV_P @ CHEBYSHEV_X**2)
    assert variance == pytest.approx(0.9875, rel=1e-12) and abs(CHEBYSHEV_P @ CHEBYSHEV_X) < 1e-15  # mean 0
    eps = chebyshev(CHEBYSHEV_DELTA, variance).eps(CHEBYSHEV_N)
    draws = np.random.default_rng(56).choice(CHEBYSHEV_X, p=CHEBYSHEV_P, size=(BATCHES, CHEBYSHEV_N))
    dev = np.abs(draws.mean(axis=1))
    for scale, above in ((1.0, False), (0.7, True)):
        exact = _chebyshev_exact_miss(scale * eps)
        observed = float(np.mean(dev >= scale * eps))
        assert abs(exact - CHEBYSHEV_DELTA) / _se(exact if above else CHEBYSHEV_DELTA) > DECISIVE_SE, (scale, exact)
        assert abs(observed - exact) <= 5 * _se(exact), (scale, observed, exact)
        assert (observed > CHEBYSHEV_DELTA) if above else (observed <= CHEBYSHEV_DELTA), (scale, observed)


@settings(max_examples=60, deadline=None)
@given(d=pos, g=pos, c=pos)
def test_n_star_maximises_upsilon_on_a_dense_grid(d, g, c):
    bound = ErrorBound(d)
    n_star = n_star_closed_form(g, bound)
    n0 = n_zero(g, bound)
    assert n0 <= n_star
    if n_star > 2_000_000:
        return
    grid = np.arange(max(1, math.floor(n0)), 4 * n_star + 10)
    best = grid[np.argmax(upsilon(grid, g, bound, c))]
    # The closed form is the ceiling of the continuous maximiser: the grid argmax is it or its floor.
    assert n_star - 1 <= best <= n_star
    # Rounding up loses O(1/N*^2) of Upsilon relative (it is flat at its peak): well under 1/N*.
    assert upsilon(n_star, g, bound, c) >= upsilon(best, g, bound, c) * (1 - 1 / n_star)


@settings(max_examples=60, deadline=None)
@given(d=pos, f=pos, g=pos, c=pos)
def test_bernstein_search_returns_grid_argmax(d, f, g, c):
    bound = ErrorBound(d, f)
    root = n_star_bernstein_root(g, bound)
    if root > 2_000_000:
        return
    n = n_star_search(g, bound, c)
    grid = np.arange(max(1, math.ceil(n_zero(g, bound))), 3 * math.ceil(root) + 10)
    assert n == grid[np.argmax(upsilon(grid, g, bound, c))]
    assert abs(n - root) <= 1


@settings(max_examples=200, deadline=None)
@given(d=pos, f=pos, g=pos, c=pos, n_max=st.one_of(st.none(), st.integers(2, 200_000)))
def test_bernstein_search_is_the_first_decrease_of_upsilon(d, f, g, c, n_max):
    # The compiled search against upsilon() on the whole grid, in NumPy: the first N whose successor
    # has a smaller Upsilon, where rounding decides near the top, so it must match bit for bit.
    bound = ErrorBound(d, f)
    root = n_star_bernstein_root(g, bound)
    if root > 2_000_000:
        return
    start = max(1, math.ceil(n_zero(g, bound)))
    stop = 3 * math.ceil(root) + 10 if n_max is None else n_max
    grid = np.arange(start, max(stop, start) + 1, dtype=float)
    drops = np.nonzero(np.diff(upsilon(grid, g, bound, c)) < 0)[0]
    expected = int(grid[drops[0]]) if drops.size else n_max
    assert n_star_search(g, bound, c, n_max) == expected


def test_search_agrees_with_closed_form_when_f_is_zero():
    for d, g in [(3.0, 0.5), (100.0, 7.0), (0.4, 0.01)]:
        b = ErrorBound(d)
        assert n_star_search(g, b, 1.0) in (n_star_closed_form(g, b) - 1, n_star_closed_form(g, b))


@settings(max_examples=40, deadline=None)
@given(d=pos, g=pos, c=pos)
def test_step_size_at_n_star(d, g, c):
    # At the continuous N*, Corollary 4.2.8's step equals (13 - 3 sqrt 17) / (4c).
    n_cont = (13 + 3 * math.sqrt(17)) / 2 * d**2 / g**2
    alpha = coordinate_step(g, d / math.sqrt(n_cont), c)
    assert alpha == pytest.approx(ALPHA_STAR_FACTOR / c, rel=1e-9)
    imp = guaranteed_improvement(g, d / math.sqrt(n_cont), c)
    # The thesis prints (393 - 95 sqrt 17)/8 ||g||^2: four times this and without the 1/c
    # (see the book's errata).
    assert imp == pytest.approx((393 - 95 * math.sqrt(17)) / 32 * g**2 / c, rel=1e-9)


def test_search_respects_n_max():
    b = ErrorBound(100.0, 50.0)
    assert n_star_search(0.01, b, 1.0, n_max=500_000) == 500_000
    assert optimal_batch_size(0.01, b, 1.0, 100, 500_000) == 500_000
    assert optimal_batch_size(1e6, ErrorBound(1.0), 1.0, 100, 500_000) == 100


def test_coordinate_step_beats_scalar_step_guarantee():
    # Corollary 4.2.5: ||g||_inf^2/(4c) >= ||g||_2^4 / (4c ||g||_1^2).
    rng = np.random.default_rng(2)
    for _ in range(200):
        grad, c = rng.normal(size=5), 3.0
        a = scalar_step(grad, 0.0, c)
        scalar_gain = a * grad @ grad - c * a**2 * np.sum(np.abs(grad)) ** 2
        assert guaranteed_improvement(np.max(np.abs(grad)), 0.0, c) >= scalar_gain - 1e-12


def test_no_step_without_guarantee():
    assert coordinate_step(1.0, 1.5, 2.0) == 0.0
    assert upsilon(1.0, 1.0, ErrorBound(2.0), 1.0) == 0.0
    assert upsilon(1.0, 1.0, ErrorBound(2.0), 1.0, saturate=False) > 0


@pytest.mark.parametrize("delta", [0.0, 1.0, -0.1, 1.5, float("nan")])
def test_bad_delta_raises(delta):
    with pytest.raises(ValueError, match="^delta"):
        hoeffding(delta, 1.0)
    with pytest.raises(ValueError, match="^delta"):
        error_bound("bernstein", np.arange(5.0), delta, K1)


def test_bad_constants_raise():
    with pytest.raises(ValueError, match="^sigma"):
        TaskConstants(4, 2, 4, 2, 0.9, 20, 0.0)
    with pytest.raises(ValueError, match="^samples"):
        error_bound("bernstein", np.ones((3, 2)), 0.5, K1)
    with pytest.raises(ValueError, match="^bound"):
        error_bound("markov", np.ones(3), 0.5, K1)
    with pytest.raises(ValueError, match="^gradient norm"):
        coordinate_step(float("nan"), 0.1, 1.0)


def test_theoretical_range_override():
    x = np.arange(10.0)
    assert error_bound("hoeffding", x, 0.5, K1, range=1280.0).d == pytest.approx(
        1280.0 * math.sqrt(math.log(4) / 2))
    assert error_bound("hoeffding", x, 0.5, K1, range="lemma").d == error_bound("hoeffding", x, 0.5, K1).d
    for bad in (-1.0, 0.0, float("nan"), float("inf"), "foo", True):
        with pytest.raises(ValueError, match="^range"):
            error_bound("hoeffding", x, 0.5, K1, range=bad)


def test_a_zero_gradient_needs_n_max_for_the_batch_size():
    """With g = 0 no batch makes the step safe: N* is infinite, and the batch size is N_max."""
    bound = ErrorBound(2.0, 0.0)
    assert n_star_closed_form(0.0, bound) == math.inf
    assert optimal_batch_size(0.0, bound, 1.0, n_min=10, n_max=5000) == 5000
    with pytest.raises(ValueError, match="^n_max must be given"):
        optimal_batch_size(0.0, bound, 1.0, n_min=10)
