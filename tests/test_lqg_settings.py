"""Finite-horizon LQG values and the search for the setting behind Section 5.2's numbers."""

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.policies import LinearGaussianPolicy
from safepg.thesis.lqg_settings import (
    FIXED_POINTS,
    PRINTED_J_STAR,
    SettingsGrid,
    candidate_settings,
    clipped_return_bound,
    expected_rewards,
    finite_horizon_optimal_gain,
    finite_horizon_performance,
    horizon_matching_value,
    measured_return,
    search_printed_settings,
    second_moments,
)

# A coupled task, so that a wrong transpose or a missing cross term shows.
ENV = LQG(dim=2, gamma=0.9, horizon=15, A=np.array([[1.0, 0.1], [0.0, 0.9]]),
          B=np.array([[1.0, 0.0], [0.3, 1.0]]), Q=np.array([[1.0, 0.2], [0.2, 0.5]]),
          R=np.array([[0.8, 0.1], [0.1, 1.2]]), clip=False)
K = np.array([[-0.5, 0.05], [0.1, -0.4]])
SIG = np.array([[0.5, 0.1], [0.1, 0.3]])


def test_finite_horizon_matches_unclipped_monte_carlo():
    mean, se = measured_return(ENV, K, SIG, 100_000, rng=7)
    assert abs(mean - finite_horizon_performance(ENV, K, SIG)) < 4 * se


def test_finite_horizon_matches_monte_carlo_for_an_unstable_gain():
    # J_H is finite for any gain; gamma (A + BK) has spectral radius > 1 here.
    env = LQG.thesis_2d(gamma=0.95, horizon=10, clip=False)
    gain = np.diag([0.6, 0.5])
    assert not env.is_stable(gain)
    mean, se = measured_return(env, gain, 1.0, 100_000, rng=8)
    assert abs(mean - finite_horizon_performance(env, gain, 1.0)) < 4 * se


def test_second_moments_at_zero_gain_are_a_random_walk():
    # theta = 0, A = B = I: s_t = s_0 + sum of t N(0, sigma^2 I) actions.
    env = LQG.thesis_2d(state_bound=3.0)
    S = second_moments(env, np.zeros((2, 2)), 0.7, 6)
    expected = [(9.0 / 3 + t * 0.49) * np.eye(2) for t in range(6)]
    np.testing.assert_allclose(S, expected, rtol=1e-14)


def test_printed_setting_at_zero_gain_by_hand():
    # Q = R = I, m = 2, b = 2, sigma = 1: E r_t = -(4/3 + t + 1).
    env = LQG.thesis_2d()
    H = 20
    t = np.arange(H)
    np.testing.assert_allclose(expected_rewards(env, np.zeros(4), 1.0, H), -(7 / 3 + t), rtol=1e-14)
    assert finite_horizon_performance(env, np.zeros(4), 1.0) == pytest.approx(-(0.95**t) @ (7 / 3 + t), rel=1e-14)


def test_one_step_value():
    S0 = ENV.initial_second_moment()
    _, _, Q, R = ENV._mats
    r0 = -0.5 * (np.trace(Q @ S0) + np.trace(R @ (K @ S0 @ K.T + SIG)))
    assert finite_horizon_performance(ENV, K, SIG, 1) == pytest.approx(r0, rel=1e-14)


@pytest.mark.parametrize("env,gain,sigma", [(ENV, K, SIG), (LQG.thesis_2d(), np.diag([-0.3, -0.6]), 1.0)])
def test_long_horizon_converges_to_closed_form(env, gain, sigma):
    closed = env.performance(gain, sigma)
    gaps = [abs(finite_horizon_performance(env, gain, sigma, H) - closed) for H in (5, 20, 100)]
    assert gaps[0] > gaps[1] > gaps[2] > 0  # approaches from one side, geometrically
    assert abs(finite_horizon_performance(env, gain, sigma, 2000) - closed) < 1e-12 * abs(closed)


def test_horizon_matching_value_recovers_a_horizon():
    env = LQG.thesis_2d()
    target = finite_horizon_performance(env, np.zeros(4), 1.0, 37)
    assert horizon_matching_value(env, np.zeros(4), 1.0, target, 500) == (37, pytest.approx(target, rel=1e-14))


def test_finite_horizon_optimum():
    env = LQG.thesis_1d(clip=False)
    # Long horizon: the infinite-horizon Riccati gain.
    assert finite_horizon_optimal_gain(env, 1.0, 400) == pytest.approx(env.optimal_gain().item(), abs=1e-6)
    # H = 1: only the action cost counts, so the best gain is 0 (the bracket's edge).
    assert finite_horizon_optimal_gain(env, 1.0, 1) == pytest.approx(0.0, abs=1e-6)
    # H = 20 is a genuine interior optimum: J_20 is larger there than nearby.
    t = finite_horizon_optimal_gain(env, 1.0, 20)
    j = finite_horizon_performance(env, t, 1.0, 20)
    assert j > finite_horizon_performance(env, t + 1e-3, 1.0, 20)
    assert j > finite_horizon_performance(env, t - 1e-3, 1.0, 20)


def test_clipped_returns_respect_the_reward_bound():
    env = LQG.thesis_2d(gamma=0.95, horizon=20)
    bound = clipped_return_bound(env.gamma, env.horizon, env.reward_bound)
    ret = env.simulate(LinearGaussianPolicy(np.eye(2), 3.0), 2000, 1).discounted_returns()
    assert ret.min() >= -bound
    assert bound == pytest.approx(8 * (1 - 0.95**20) / 0.05)


SMALL = SettingsGrid(gammas=(0.9, 0.95, 0.99), state_bounds=(1.0, 2.0), horizons=(None, 20))


@pytest.fixture(scope="module")
def small_rows():
    return list(candidate_settings(SMALL))


def test_candidate_rows_reproduce_the_closed_forms(small_rows):
    row = next(r for r in small_rows if r["gamma"] == 0.95 and r["state_bound"] == 2.0 and r["horizon"] is None
               and r["point"] == "optimum" and r["reward_scale"] == 0.5 and not r["per_dimension"]
               and r["sigma_reading"] == "std")
    assert row["theta_star"] == pytest.approx(-0.60373, abs=1e-5)
    assert row["J"] == pytest.approx(-52.609, abs=5e-4)
    zero = [r for r in small_rows if r["gamma"] == 0.95 and r["state_bound"] == 2.0 and r["horizon"] is None
            and r["point"] == "zero" and r["sigma_reading"] == "std"]
    by = {(r["reward_scale"], r["per_dimension"]): r["J"] for r in zero}
    assert by[(0.5, False)] == pytest.approx(-426.667, abs=5e-4)
    assert by[(1.0, False)] == pytest.approx(2 * by[(0.5, False)])
    assert by[(0.5, True)] == pytest.approx(by[(0.5, False)] / 2)


def test_printed_theta_star_is_the_gamma_0_9_value(small_rows):
    hits = [r for r in search_printed_settings(rows=small_rows) if r["quantity"] == "theta_star"]
    assert hits
    assert {r["gamma"] for r in hits} == {0.9}


def test_printed_J_star_is_not_reproduced_but_J_of_zero_is_found(small_rows):
    assert not [r for r in search_printed_settings(rows=small_rows) if r["quantity"] == "J"]
    # The search does find a number that is in the grid: J(0) of the printed setting.
    hits = search_printed_settings(rows=small_rows, J_target=-426.6667, rel_tol=1e-6)
    assert {(r["gamma"], r["point"], r["state_bound"], r["horizon"]) for r in hits if r["quantity"] == "J"} == {
        (0.95, "zero", 2.0, None)
    }
    assert min(abs(r["J"] - PRINTED_J_STAR) for r in small_rows) > 1e-3 * abs(PRINTED_J_STAR)


def test_search_includes_clipped_monte_carlo_rows():
    grid = SettingsGrid(gammas=(0.95,), sigma_readings=("std",), state_bounds=(2.0,), horizons=(),
                        clipped_horizons=(20,), points=("zero",), per_dimension=(False,), reward_scales=(0.5,),
                        mc_trajectories=4000)
    (row,) = list(candidate_settings(grid))
    assert row["clipped"] and row["se"] > 0
    assert -40 < row["J"] < -32  # clipped: far from the unclipped J_20(0) = -130.3
    hit = search_printed_settings(grid, J_target=row["J"] + 2 * row["se"])
    assert [r["quantity"] for r in hit] == ["J"]  # within 4 standard errors


def test_search_rejects_bad_tolerance(small_rows):
    with pytest.raises(ValueError, match="rel_tol"):
        search_printed_settings(rows=small_rows, rel_tol=0.0)


def test_fixed_points_are_the_printed_matrices():
    assert FIXED_POINTS["printed_final_scalar"][0, 1] == pytest.approx(1.4e-6)
    assert np.count_nonzero(FIXED_POINTS["printed_final_coordinate"]) == 2
