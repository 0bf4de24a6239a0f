"""Curves and tables drawn from records; the simulated objective against quadrature (tests/lqg1d_dp.py)."""

import math

import lqg1d_dp
import numpy as np
import pytest

from safepg.definition import to_dict
from safepg.learning import LearningRecord
from safepg.options import Adaptive, ErrorModel, FixedStep, Vanilla
from safepg.record import on_trajectories
from safepg.thesis.analysis import (
    by_iteration,
    markdown_table,
    mean_band,
    one_cell_spread,
    table_5_2,
    table_upsilon,
)


def rec(batch, J):
    I = len(batch)
    return LearningRecord(np.array(batch), np.zeros(I), np.zeros(I, int), np.zeros((I + 1, 1)), np.array(J),
                          np.array(J[:-1]) + 1, np.zeros((I, 1)), np.zeros(I), np.ones(I, bool))


def test_on_trajectories_holds_each_J_for_its_batch():
    r = rec([10, 20, 5], [-5.0, -4.0, -3.0, -2.5])
    got = on_trajectories([r], np.array([1, 10, 11, 30, 31, 35, 36]))[0]
    np.testing.assert_array_equal(got, [-5, -5, -4, -4, -3, -3, np.nan])


def test_by_iteration_and_band():
    a, b = rec([1, 2, 3], [0, 0, 0, 0]), rec([4, 5], [0, 0, 0])
    v = by_iteration([a, b])
    np.testing.assert_array_equal(v, [[1, 2, 3], [4, 5, np.nan]])
    m, lo, hi = mean_band(v)
    np.testing.assert_array_equal(m, [2.5, 3.5, 3])
    np.testing.assert_array_equal(lo, [1, 2, 3])


def test_table_5_2_differences():
    method = to_dict(Adaptive(error=ErrorModel("bernstein", 0.95, "empirical")))
    report = {"configs": [{"method": method, "seeds": 5, "upsilon_bar": {"mean": -9.7, "ci95": [-9.8, -9.6]},
                           "improvement_ratio": {"mean": 1.0}, "thesis": {"upsilon_bar": -9.6623, "ci95": [1, 2]}}]}
    row = table_5_2(report)[0]
    assert (row["estimator"], row["bound"], row["empirical_range"], row["delta"]) == ("gpomdp", "bernstein", True, 0.95)
    assert abs(row["difference"] - (-9.7 + 9.6623)) < 1e-12
    md = markdown_table([row], [("ours", "ours", ".3f"), ("ci95", "CI", ".1f"), ("missing", "x", "")])
    assert md.splitlines()[2] == "| -9.700 | [-9.8; -9.6] | - |"


def _returns(theta: float, n: int, seed: int) -> np.ndarray:
    """The discounted returns behind ``simulated_performance(env, [theta], 1.0, n, seed)``, one per trajectory."""
    from safepg.envs.lqg import LQG
    from safepg.policies import LinearGaussianPolicy

    pol = LinearGaussianPolicy(np.array([[theta]]), 1.0)
    return LQG.thesis_1d().gradient_batch(pol, n, np.random.default_rng(seed), "gpomdp", False, "clipped")[1]


def test_simulated_gradient_and_performance_match_the_quadrature():
    # The clipped 20-step objective at theta = -0.3 by quadrature (tests/lqg1d_dp.py): J = -10.1537, its
    # derivative -3.8688. The simulator's Monte Carlo estimates must lie within 4 of their standard errors
    # (from their own trajectories; about 0.011 for the derivative, 0.006 for J).
    from safepg.envs.lqg import LQG
    from safepg.thesis.analysis import simulated_gradient, simulated_performance

    env, h = LQG.thesis_1d(), 1e-4
    J, dJ = lqg1d_dp.performance(-0.3), lqg1d_dp.gradient(-0.3)
    assert (round(J, 4), round(dJ, 4)) == (-10.1537, -3.8688)
    g = simulated_gradient(env, -0.3, 1.0, 200_000, seed=1, h=h)
    diff = (_returns(-0.3 + h, 200_000, 1) - _returns(-0.3 - h, 200_000, 1)) / (2 * h)  # common random numbers
    assert g == pytest.approx(diff.mean(), rel=1e-12)
    assert abs(g - dJ) < 4 * diff.std(ddof=1) / math.sqrt(diff.size), (g, dJ)
    r = _returns(-0.3, 200_000, 2)
    assert abs(simulated_performance(env, [-0.3], 1.0, 200_000, 2)[0] - J) < 4 * r.std(ddof=1) / math.sqrt(r.size)


def test_gradient_estimates_share_batches_and_concentrate():
    from safepg.envs.lqg import LQG
    from safepg.thesis.analysis import gradient_estimates

    est = gradient_estimates(LQG.thesis_1d(), -0.3, 1.0, [100, 10_000], repeats=20, seed=0)
    assert est["gpomdp"].shape == (2, 20)
    for e in est.values():
        assert e[1].std() < e[0].std() / 4  # 100x the samples: about 10x less spread
    assert np.std(est["gpomdp"][0]) < np.std(est["reinforce"][0])


def test_improvement_ratio_on_other_objective():
    from safepg.thesis.analysis import improvement_ratio_on

    r = rec([1, 1, 1], [0, 0, 0, 0])
    r.theta[:, 0] = [0.0, 0.1, 0.05, 0.2]
    assert improvement_ratio_on([r], lambda t: t)[0] == 2 / 3
    assert improvement_ratio_on([r], lambda t: -t)[0] == 1 / 3


def test_simulated_objective_optimum_differs_from_closed_form():
    # By quadrature (tests/lqg1d_dp.py) the clipped 20-step objective peaks at theta = -0.6503, J = -9.5571,
    # not at the closed form's optimum -0.5884. The simulator's spline (common random numbers, 10^5
    # trajectories a point) must find it within its Monte Carlo error: its argmax within 5 standard errors
    # of the derivative over the curvature (0.0098 / 7.56 = 0.0013 each), its peak within 4 of J's (0.0076).
    from scipy.optimize import minimize_scalar

    from safepg.envs.lqg import LQG
    from safepg.thesis.analysis import simulated_objective

    env, h = LQG.thesis_1d(), 1e-4
    peak = minimize_scalar(lambda t: -lqg1d_dp.performance(t, m=401, q=401), bounds=(-0.9, -0.4), method="bounded",
                           options={"xatol": 1e-6})
    theta_peak, J_peak = peak.x, lqg1d_dp.performance(peak.x)
    assert (round(theta_peak, 4), round(J_peak, 4)) == (-0.6503, -9.5571)
    assert theta_peak < env.optimal_gain().item() - 0.05
    curvature = (lqg1d_dp.performance(theta_peak + 1e-3) - 2 * J_peak + lqg1d_dp.performance(theta_peak - 1e-3)) / 1e-6
    slope = (_returns(theta_peak + h, 100_000, 3) - _returns(theta_peak - h, 100_000, 3)) / (2 * h)
    r = _returns(theta_peak, 100_000, 3)

    f = simulated_objective(env, 1.0, -0.9, -0.4, points=26, n=100_000, seed=3)
    t = np.linspace(-0.9, -0.4, 2001)
    best = t[np.argmax(f(t))]
    assert abs(best - theta_peak) < 5 * slope.std(ddof=1) / math.sqrt(slope.size) / abs(curvature), best
    assert abs(f(best) - J_peak) < 4 * r.std(ddof=1) / math.sqrt(r.size), f(best)


def test_on_trajectories_holds_each_batch_average():
    r = rec([10, 20], [-5.0, -4.0, -3.0])  # J_hat = J[:-1] + 1
    got = on_trajectories([r], np.array([1, 10, 11, 30, 31]), "J_hat")[0]
    np.testing.assert_array_equal(got, [-4, -4, -3, -3, np.nan])


def test_table_upsilon_differences():
    report = {"configs": [
        {"name": "adaptive", "method": to_dict(Adaptive()), "seeds": 5,
         "upsilon_bar": {"mean": 184.2, "ci95": [183.0, 185.4]},
         "improvement_ratio": {"mean": 0.55, "ci95": [0.5, 0.6]},
         "thesis": {"upsilon_bar": 193.12, "improvement_ratio": 0.5301}},
        {"name": "extra", "method": to_dict(Vanilla(10, FixedStep(0.1))), "seeds": 1,
         "upsilon_bar": {"mean": 1.0, "ci95": [1.0, 1.0]}, "improvement_ratio": {"mean": 1.0, "ci95": [1, 1]},
         "thesis": None}]}
    a, extra = table_upsilon(report)
    assert a["upsilon_difference"] == pytest.approx(184.2 - 193.12)
    assert a["improvement_difference"] == pytest.approx(0.55 - 0.5301)
    assert a["batch_size"] is None and extra["thesis_upsilon_bar"] is None and extra["upsilon_difference"] is None
    assert (extra["batch_size"], extra["alpha"]) == (10, 0.1)


def test_comparison_figures_draw_the_seed_means():
    import matplotlib

    matplotlib.use("Agg")
    from safepg.thesis.figures import figure_5_6, figure_comparison

    recs = {"a": [rec([10, 20], [-5.0, -4.0, -3.0])], "b": [rec([30], [-6.0, -1.0])]}
    fig = figure_comparison(recs, {"a": "A", "b": "B"}, measured=True)
    lines = fig.axes[0].get_lines()
    assert [ln.get_label() for ln in lines] == ["A", "B"]
    assert set(lines[0].get_ydata()[:10]) == {-4.0} and "batch" in fig.axes[0].get_ylabel()
    recs["a"][0].alpha[:] = [1e-3, 1e-4]
    fig = figure_5_6(recs, {"a": "A"})
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_ydata(), [1e-3, 1e-4])


def test_one_cell_spread_by_hand():
    def run(J, theta):
        r = rec([10] * (len(J) - 1), J)
        r.theta[:, 0] = theta
        return r

    # Two runs: 2 and 1 strict increases in 3 updates; theta crosses -0.5 after 2 and after 1 updates.
    runs = [run([1.0, 2.0, 3.0, 2.0, 0.0], [-0.2, -0.4, -0.6, -0.7, -0.8]),
            run([1.0, 2.0, 2.0, 1.0, 0.0], [-0.2, -0.6, -0.7, -0.8, -0.9])]
    s = one_cell_spread(runs, 1.0, np.array([-0.1, -0.2, -0.3, -0.6]), -0.5)
    np.testing.assert_allclose(s["ratios"], [2 / 3, 1 / 3])
    assert s["mean"] == pytest.approx(0.5) and s["sd"] == pytest.approx(np.std([2 / 3, 1 / 3], ddof=1))
    assert s["at_least"] == 0 and s["z"] == pytest.approx(0.5 / s["sd"])
    assert s["crossing"].tolist() == [2, 1] and s["crossing_theirs"] == 3
    with pytest.raises(ValueError, match="^records "):
        one_cell_spread(runs[:1], 1.0, np.array([-0.1]), -0.5)
