"""LQG closed forms against independent computations."""

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are
from scipy.optimize import minimize, minimize_scalar

from safepg.envs.lqg import LQG
from safepg.policies import LinearGaussianPolicy


def j_1d_settings(theta: float, sigma: float, gamma: float = 0.9) -> float:
    """The 1-D closed form, derived by hand: under a = theta s + sigma z the value of a state is -P s^2 - w,
    where P = (1 + theta^2) / 2 + gamma (1 + theta)^2 P and w = sigma^2 (1/2 + gamma P) / (1 - gamma) (the
    noise's cost now and through the next state); J = -E[s_0^2] P - w with E[s_0^2] = 2^2 / 3."""
    P = 0.5 * (1 + theta**2) / (1 - gamma * (1 + theta) ** 2)
    return -(2**2 / 3) * P - sigma**2 * (0.5 + gamma * P) / (1 - gamma)


ENV2 = LQG(dim=2, gamma=0.9, A=np.array([[1.0, 0.1], [0.0, 0.9]]), B=np.array([[1.0, 0.0], [0.3, 1.0]]),
           Q=np.array([[1.0, 0.2], [0.2, 0.5]]), R=np.array([[0.8, 0.1], [0.1, 1.2]]))
K2 = np.array([[-0.5, 0.05], [0.1, -0.4]])
SIG2 = np.array([[0.5, 0.1], [0.1, 0.3]])


def test_thesis_1d_numbers():
    env = LQG.thesis_1d()
    # theta = 0: P = 0.5 / 0.1 = 5, J = -(4/3) 5 - (0.5 + 0.9 * 5) / 0.1 = -56.667 (j_1d_settings, by hand).
    assert env.performance(0.0, 1.0) == pytest.approx(-56.667, abs=5e-4)
    # theta* and J(theta*): the maximum of the hand-derived closed form, -0.5884 and -13.207.
    best = minimize_scalar(lambda t: -j_1d_settings(t, 1.0), bounds=(-1.0, 0.0), method="bounded",
                           options={"xatol": 1e-10})
    assert (round(best.x, 4), round(-best.fun, 3)) == (-0.5884, -13.207)
    theta_star = env.optimal_gain().item()
    assert theta_star == pytest.approx(best.x, abs=5e-8)
    assert env.performance(theta_star, 1.0) == pytest.approx(-best.fun, rel=1e-12)


@pytest.mark.parametrize("theta", [-0.9, -0.588, -0.3, 0.0, 0.05])
@pytest.mark.parametrize("sigma", [0.5, 1.0])
def test_1d_matches_settings_formula(theta, sigma):
    assert LQG.thesis_1d().performance(theta, sigma) == pytest.approx(j_1d_settings(theta, sigma), rel=1e-12)


def test_unstable_gain_has_minus_infinite_performance():
    env = LQG.thesis_1d()
    assert env.performance(0.5, 1.0) == -np.inf
    with pytest.raises(ValueError, match="unstable"):
        env.gradient(0.5, 1.0)


def _mc_unclipped(env: LQG, K: np.ndarray, sigma, n: int, seed: int) -> tuple[float, float]:
    long = LQG(dim=env.dim, gamma=env.gamma, horizon=250, A=env.A, B=env.B, Q=env.Q, R=env.R, clip=False)
    ret = long.simulate(LinearGaussianPolicy(K, sigma), n, seed).discounted_returns()
    return float(ret.mean()), float(ret.std(ddof=1) / np.sqrt(n))


@pytest.mark.parametrize("case", ["1d", "2d"])
def test_performance_matches_long_horizon_monte_carlo(case):
    # Horizon 250 truncates gamma^250 ~ 4e-12 of the return: far below the MC error.
    env, K, sig = (LQG.thesis_1d(), np.array([[-0.3]]), 1.0) if case == "1d" else (ENV2, K2, SIG2)
    mean, se = _mc_unclipped(env, K, sig, 100_000, seed=3)
    assert abs(mean - env.performance(K, sig)) < 4 * se


@pytest.mark.parametrize("case", ["1d", "2d"])
def test_gradient_matches_finite_differences(case):
    env, K, sig = (LQG.thesis_1d(), np.array([[-0.3]]), 0.7) if case == "1d" else (ENV2, K2, SIG2)
    theta = K.ravel()
    h = 1e-6
    fd = np.array([(env.performance(theta + h * e, sig) - env.performance(theta - h * e, sig)) / (2 * h)
                   for e in np.eye(theta.size)])
    np.testing.assert_allclose(env.gradient(theta, sig), fd, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("env", [LQG.thesis_1d(), LQG.thesis_2d(), ENV2], ids=["1d", "2d-thesis", "2d-coupled"])
def test_optimal_gain_matches_scipy_dare(env):
    g, (A, B, Q, R) = env.gamma, env._mats
    X = solve_discrete_are(np.sqrt(g) * A, np.sqrt(g) * B, 0.5 * Q, 0.5 * R)
    K_dare = -np.linalg.solve(0.5 * R + g * B.T @ X @ B, g * B.T @ X @ A)
    np.testing.assert_allclose(env.optimal_gain(), K_dare, atol=1e-9)


def test_optimal_gain_matches_brute_force_search():
    env = LQG.thesis_1d()
    best = minimize_scalar(lambda t: -env.performance(t, 1.0), bounds=(-1.5, 0.2), method="bounded",
                           options={"xatol": 1e-10})
    assert env.optimal_gain().item() == pytest.approx(best.x, abs=1e-6)
    # m = 2: a direct search over all four gain entries, with a grid to start from.
    grid = np.linspace(-1.2, 0.2, 15)
    starts = [np.array([a, 0, 0, b]) for a in grid for b in grid]
    x0 = max(starts, key=lambda k: ENV2.performance(k, SIG2))
    res = minimize(lambda k: -ENV2.performance(k, SIG2), x0, method="Nelder-Mead",
                   options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000})
    np.testing.assert_allclose(ENV2.optimal_gain().ravel(), res.x, atol=1e-4)
    assert ENV2.performance(ENV2.optimal_gain(), SIG2) >= -res.fun - 1e-9


def test_optimum_is_independent_of_sigma():
    env = LQG.thesis_1d()
    ts = [minimize_scalar(lambda t, s=s: -env.performance(t, s), bounds=(-1.5, 0.2), method="bounded",
                          options={"xatol": 1e-10}).x for s in (0.3, 2.0)]
    assert ts[0] == pytest.approx(ts[1], abs=1e-6)


def test_simulator_clipping_and_reward():
    env = LQG.thesis_1d()
    batch = env.simulate(LinearGaussianPolicy([[0.5]], 3.0), 2000, 0)
    assert np.all(np.abs(batch.actions) <= 2) and np.all(np.abs(batch.features) <= 2)
    assert np.any(np.abs(batch.actions_raw) > 2)
    s, u = batch.features[..., 0], batch.actions[..., 0]
    np.testing.assert_allclose(batch.rewards, -0.5 * (s**2 + u**2))
    np.testing.assert_allclose(batch.features[:, 1:, 0], np.clip(s[:, :-1] + u[:, :-1], -2, 2))
    assert np.all(batch.rewards >= -env.reward_bound)


def test_simulator_is_seeded():
    env, pol = LQG.thesis_1d(), LinearGaussianPolicy([[-0.2]], 1.0)
    a, b = env.simulate(pol, 50, 7), env.simulate(pol, 50, 7)
    assert np.array_equal(a.rewards, b.rewards) and np.array_equal(a.actions_raw, b.actions_raw)
    assert not np.array_equal(a.rewards, env.simulate(pol, 50, 8).rewards)


def test_bound_constants_match_settings():
    env = LQG.thesis_1d()
    assert (env.reward_bound, env.feature_bound, env.action_volume) == (4.0, 2.0, 4.0)


@pytest.mark.parametrize(
    "kwargs, name",
    [({"gamma": 1.0}, "gamma"), ({"horizon": 0}, "horizon"), ({"state_bound": -1}, "state_bound"),
     ({"dim": 2, "A": np.eye(3)}, "A")],
)
def test_bad_settings_raise(kwargs, name):
    with pytest.raises(ValueError, match=f"^{name}"):
        LQG(**kwargs)


def test_bad_theta_raises():
    env = LQG.thesis_1d()
    with pytest.raises(ValueError, match="^theta"):
        env.performance([0.1, 0.2], 1.0)
    with pytest.raises(ValueError, match="^theta"):
        env.performance(np.nan, 1.0)
    with pytest.raises(ValueError, match="^sigma"):
        env.performance(-0.2, 0.0)
    with pytest.raises(ValueError, match="^theta"):
        env.simulate(LinearGaussianPolicy(np.zeros((2, 2)), 1.0), 10, 0)


@pytest.mark.parametrize("env", [LQG.thesis_1d(), LQG.thesis_2d(gamma=0.9), ENV2], ids=["1d", "2d", "2d-coupled"])
def test_performance_batch_equals_performance(env):
    # Half of these gains are unstable: the batched solve must give -inf exactly there.
    thetas = np.random.default_rng(3).uniform(-1.6, 0.6, size=(200, env.dim**2))
    one_by_one = np.array([env.performance(t, 0.7) for t in thetas])
    batched = env.performance_batch(thetas, 0.7)
    assert 0.2 < np.isfinite(one_by_one).mean() < 0.9
    assert np.array_equal(np.isinf(batched), np.isinf(one_by_one))
    ok = np.isfinite(one_by_one)
    np.testing.assert_allclose(batched[ok], one_by_one[ok], rtol=1e-12)


def test_performance_batch_bad_shape_names_thetas():
    with pytest.raises(ValueError, match="thetas"):
        LQG.thesis_2d().performance_batch(np.zeros((3, 3)), 1.0)
    with pytest.raises(ValueError, match="thetas"):
        LQG.thesis_2d().performance_batch(np.full((1, 4), np.nan), 1.0)
