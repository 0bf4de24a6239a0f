"""The lab library's reading of the 2-D J (Section 5.2's printed J(theta*) = -422.616)."""

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.thesis.lqg_settings import (
    PRINTED_J_STAR,
    lab_performance_at_states,
    lab_performance_moments,
    lab_readings,
    lab_value_matrix,
)


@pytest.mark.parametrize("gamma,weight", [(0.9, 0.5), (0.95, 0.9), (0.99, 1.0)])
def test_lab_value_matrix_is_the_lyapunov_solution_for_a_diagonal_gain(gamma, weight):
    K = np.diag([-0.588, -0.3])
    # safepg's reward is -1/2 (s'Qs + a'Ra): the library's weight w is Q = R = 2w there.
    env = LQG(dim=2, gamma=gamma, Q=2 * weight, R=2 * weight, clip=False)
    np.testing.assert_allclose(lab_value_matrix(K, weight, gamma), env.value_matrix(K), rtol=1e-12)


def test_lab_value_matrix_squares_the_gain_elementwise():
    K = np.array([[-0.5, 0.2], [0.1, -0.4]])
    env = LQG(dim=2, gamma=0.9, Q=1.0, R=1.0, clip=False)
    lab = lab_value_matrix(K, 0.5, 0.9)
    assert not np.allclose(lab, env.value_matrix(K), rtol=1e-3)  # K * K is not K @ K
    eye = np.eye(2)
    by_hand = (0.5 * eye + 0.5 * K.T @ K) @ np.linalg.inv(eye - 0.9 * (eye + 2 * K + K**2))
    np.testing.assert_allclose(lab, by_hand, rtol=1e-14)


def test_lab_mean_is_the_thesis_closed_form_with_its_reward_and_box():
    K = np.diag([-0.588, -0.588])
    mean, _ = lab_performance_moments(K, 1.0, 0.5, 0.95, 2.0)
    assert mean == pytest.approx(LQG.thesis_2d().performance(K, 1.0), rel=1e-12)


def test_lab_moments_match_the_monte_carlo_value_they_describe():
    K, cov, w, g, b = np.diag([-0.3, -0.5]), 0.7, 0.9, 0.95, 3.0
    mean, sd = lab_performance_moments(K, cov, w, g, b, n_x0=100)
    P = lab_value_matrix(K, w, g)
    W = np.trace(cov * (w * np.eye(2) + g * P)) / (1 - g)
    x = np.random.default_rng(0).uniform(-b, b, size=(20_000, 100, 2))
    draws = -np.einsum("rni,ij,rnj->rn", x, P, x).mean(axis=1) - W
    assert draws.mean() == pytest.approx(mean, abs=4 * sd / np.sqrt(draws.size))
    assert draws.std(ddof=1) == pytest.approx(sd, rel=0.03)


def test_lab_moments_off_diagonal_variance():
    K = np.array([[-0.5, 0.2], [0.1, -0.4]])
    mean, sd = lab_performance_moments(K, 1.0, 0.5, 0.9, 2.0, n_x0=50)
    P = lab_value_matrix(K, 0.5, 0.9)
    W = np.trace(0.5 * np.eye(2) + 0.9 * P) / 0.1
    x = np.random.default_rng(1).uniform(-2, 2, size=(20_000, 50, 2))
    draws = -np.einsum("rni,ij,rnj->rn", x, P, x).mean(axis=1) - W
    assert draws.std(ddof=1) == pytest.approx(sd, rel=0.03)
    assert draws.mean() == pytest.approx(mean, abs=4 * sd / np.sqrt(draws.size))


def test_lab_fixed_states_by_hand_at_zero_gain():
    # K = 0: P = w / (1 - gamma) I; states (x, 0), x = 1, 2, 5, 7, 10.
    w, g = 0.9, 0.99
    P = w / (1 - g)
    expected = -P * np.mean([1, 4, 25, 49, 100]) - 2 * (w + g * P) / (1 - g)
    assert lab_performance_at_states(np.zeros((2, 2)), 1.0, w, g) == pytest.approx(expected, rel=1e-13)


def test_no_lab_reading_at_an_optimum_is_near_the_printed_value():
    rows = lab_readings()
    at_optimum = [r for r in rows if r["point"] != "zero"]
    assert min(abs(r["z"]) for r in at_optimum) > 20
    assert min(abs(r["J_fixed_states"] - PRINTED_J_STAR) for r in at_optimum) > 0.1 * abs(PRINTED_J_STAR)
    best = rows[0]  # sorted by |z|
    assert best["point"] == "zero"


@pytest.mark.parametrize("kwargs,name", [({"gamma": 1.0}, "gamma"), ({"weight": 0.0}, "weight")])
def test_lab_value_matrix_rejects_bad_input(kwargs, name):
    args = {"theta": np.eye(2) * -0.5, "weight": 0.5, "gamma": 0.9, **kwargs}
    with pytest.raises(ValueError, match=f"^{name}"):
        lab_value_matrix(**args)


def test_lab_moments_reject_bad_input():
    with pytest.raises(ValueError, match="^n_x0"):
        lab_performance_moments(np.eye(2) * -0.5, 1.0, 0.5, 0.9, 2.0, n_x0=0)
    with pytest.raises(ValueError, match="^state_bound"):
        lab_performance_moments(np.eye(2) * -0.5, 1.0, 0.5, 0.9, -1.0)
