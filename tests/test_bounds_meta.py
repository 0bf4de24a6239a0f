"""Error bounds and the meta-parameters of Chapter 4."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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
    # R = 4, M_phi = 2, |A| = 4, gamma = 0.9, sigma = 1 (SETTINGS.md)
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


@pytest.mark.parametrize("which", ["hoeffding", "bernstein"])
def test_bounds_hold_with_probability_at_least_one_minus_delta(which):
    # Bounded variables in [0, 1]: the bound fails in at most a delta share of batches.
    rng = np.random.default_rng(1)
    delta, n, reps = 0.2, 50, 20_000
    x = rng.beta(0.3, 0.3, size=(reps, n))
    mean = 0.5
    if which == "hoeffding":
        eps = np.full(reps, hoeffding(delta, 1.0).eps(n))
    else:
        eps = np.array([bernstein(delta, np.var(r, ddof=1), 1.0).eps(n) for r in x])
    assert np.mean(np.abs(x.mean(axis=1) - mean) >= eps) <= delta


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
