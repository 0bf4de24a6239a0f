"""GymTask: any gymnasium Box environment as a task of the learning loops.

Unit tests on a tiny environment whose rewards are known in closed form (termination,
masking, clipping, seeding, the bound constants and their errors), then end to end on
gymnasium's Pendulum-v1: vanilla PG improves J beyond Monte Carlo error, and Algorithm 4.1
runs to the end of its budget.
"""

from __future__ import annotations

import inspect
import pickle
import time
from typing import Any

import numpy as np
import pytest

from conftest import import_or_fail

gym = import_or_fail("gymnasium")
from gymnasium import spaces  # noqa: E402

from safepg.definition import UnnamedError  # noqa: E402
from safepg.envs import GymTask  # noqa: E402
from safepg.envs.gym_task import with_bias  # noqa: E402
from safepg.learning import adaptive_pg, vanilla_pg  # noqa: E402
from safepg.options import Batches, ErrorModel, FixedStep, Gradient, Vanilla  # noqa: E402
from safepg.policies import LinearGaussianPolicy  # noqa: E402
from safepg.runner import RunConfig  # noqa: E402

#: The counter env terminates once its state reaches this value.
END = 3


class CounterEnv(gym.Env):
    """s_0 in {0, 1, 2} (drawn from the env's seeded generator); s_{t+1} = s_t + 1;
    r_t = s_t + u_t with u_t the action received; terminated once s_{t+1} = END.

    So an episode starting at s_0 lasts END - s_0 steps and, with the applied actions
    u_t, its discounted return is sum_{t < END - s_0} gamma^t (s_0 + t + u_t).
    """

    def __init__(self, action_high: float = 0.5) -> None:
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(1,), dtype=np.float64)
        self.action_space = spaces.Box(-action_high, action_high, shape=(1,), dtype=np.float64)
        self.s = 0.0
        self.received: list[float] = []

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self.s = float(self.np_random.integers(0, END))
        return np.array([self.s]), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        u = float(np.asarray(action).reshape(-1)[0])
        self.received.append(u)
        r = self.s + u
        self.s += 1.0
        return np.array([self.s]), r, self.s >= END, False, {}


class UnboundedActionEnv(CounterEnv):
    def __init__(self) -> None:
        super().__init__()
        self.action_space = spaces.Box(-np.inf, np.inf, shape=(1,), dtype=np.float64)


def counter_task(**kw: Any) -> GymTask:
    args = {"horizon": 5, "gamma": 0.5, "reward_bound": 3.0, "feature_bound": 2.0, **kw}
    return GymTask(CounterEnv, **args)


# ------------------------------------------------------------------------- constants
@pytest.mark.parametrize("missing", ["horizon", "gamma"])
def test_simulation_constants_are_required_at_construction(missing: str) -> None:
    args = {"horizon": 5, "gamma": 0.5}
    del args[missing]
    assert inspect.signature(GymTask).parameters[missing].default is inspect.Parameter.empty
    with pytest.raises(TypeError, match=rf"required keyword-only argument: '{missing}'"):
        GymTask(CounterEnv, **args)


@pytest.mark.parametrize("missing", ["reward_bound", "feature_bound"])
def test_missing_bound_constant_is_named_where_the_bounds_need_it(missing: str) -> None:
    args = {"reward_bound": 3.0, "feature_bound": 2.0}
    del args[missing]
    task = GymTask(CounterEnv, horizon=5, gamma=0.5, **args)  # simulating needs no bound constant
    assert task.simulate(LinearGaussianPolicy([[0.0]], 1.0), 4, 0).n == 4
    with pytest.raises(ValueError, match=rf"^{missing} must be given: "):
        getattr(task, missing)
    with pytest.raises(ValueError, match=rf"^{missing} must be given: "):
        adaptive_pg(task, 0.0, 1.0, batches=Batches(n_min=4), budget=8, rng=0)
    with pytest.raises(ValueError, match=rf"^{missing} must be given: "):
        vanilla_pg(task, 0.0, 1.0, batch_size=4, budget=8, rng=0)


@pytest.mark.parametrize("missing", ["action_volume", "action_bound"])
def test_unbounded_action_box_needs_the_action_constants(missing: str) -> None:
    task = GymTask(UnboundedActionEnv, horizon=5, gamma=0.5, reward_bound=1.0, feature_bound=1.0)
    with pytest.raises(ValueError, match=rf"^{missing} must be given: .*unbounded"):
        getattr(task, missing)
    given = GymTask(UnboundedActionEnv, horizon=5, gamma=0.5, **{missing: 7.0})
    assert getattr(given, missing) == 7.0


def test_action_constants_default_to_the_box() -> None:
    task = counter_task()
    assert task.action_volume == 1.0 and task.action_bound == 0.5
    pendulum = GymTask("Pendulum-v1", horizon=5, gamma=0.9)
    assert pendulum.action_volume == 4.0 and pendulum.action_bound == 2.0
    assert counter_task(action_volume=3.0, action_bound=1.5).action_volume == 3.0


@pytest.mark.parametrize(("name", "value"), [("reward_bound", -1.0), ("feature_bound", np.inf),
                                             ("action_volume", 0.0), ("action_bound", np.nan)])
def test_bad_constants_are_rejected(name: str, value: float) -> None:
    with pytest.raises(ValueError, match=rf"^{name} must be finite and > 0"):
        counter_task(**{name: value})


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="^horizon must be a positive integer"):
        counter_task(horizon=2.5)
    with pytest.raises(ValueError, match=r"^gamma must be in \(0, 1\]"):
        counter_task(gamma=1.5)
    with pytest.raises(ValueError, match="^action_space must be a gymnasium Box"):
        GymTask("CartPole-v1", horizon=5, gamma=0.9)
    with pytest.raises(ValueError, match="^features must map"):
        counter_task(features=lambda o: o[0])
    with pytest.raises(ValueError, match="^env_kwargs must be None"):
        counter_task(env_kwargs={"x": 1})
    task = counter_task()
    with pytest.raises(ValueError, match=r"^theta must be a \(1, 1\) gain"):
        task.simulate(LinearGaussianPolicy([[0.0, 1.0]], 1.0), 3, 0)
    with pytest.raises(ValueError, match="^n must be a positive integer"):
        task.simulate(LinearGaussianPolicy([[0.0]], 1.0), 0, 0)


# -------------------------------------------------------------------------- simulate
def test_shapes_with_a_feature_map() -> None:
    task = GymTask("Pendulum-v1", horizon=6, gamma=0.9, features=with_bias)
    assert (task.obs_dim, task.feature_dim, task.action_dim) == (3, 4, 1)
    batch = task.simulate(LinearGaussianPolicy(np.zeros((1, 4)), 0.5), 7, 0)
    assert batch.features.shape == (7, 6, 4)
    assert batch.actions_raw.shape == batch.actions.shape == (7, 6, 1)
    assert batch.rewards.shape == batch.mask.shape == (7, 6)
    assert batch.mask.all()  # Pendulum never terminates
    assert np.all(batch.features[..., 3] == 1.0)
    assert np.all(np.abs(batch.actions) <= 2.0)


def test_returns_match_a_hand_computation() -> None:
    """Episodes of different lengths: rewards, features and actions stop at termination,
    the env receives the clipped action, and the return is the hand-computed sum."""
    gamma, bound = 0.5, 0.5
    task = counter_task(gamma=gamma)
    policy = LinearGaussianPolicy([[0.3]], 1.0)  # mean 0.3 s_t: clipping is active often
    batch = task.simulate(policy, 64, 11)
    s0 = batch.features[:, 0, 0]
    assert set(s0.tolist()) == {0.0, 1.0, 2.0}
    expected = np.zeros(batch.n)
    for i in range(batch.n):  # the hand computation, one episode at a time
        length = END - int(s0[i])
        assert batch.mask[i].tolist() == [t < length for t in range(task.horizon)]
        for t in range(length):
            s = s0[i] + t
            assert batch.features[i, t, 0] == s
            u = min(max(batch.actions_raw[i, t, 0], -bound), bound)
            assert batch.actions[i, t, 0] == u
            expected[i] += gamma**t * (s + u)
        assert np.all(batch.rewards[i, length:] == 0) and np.all(batch.features[i, length:] == 0)
        assert np.all(batch.actions[i, length:] == 0) and np.all(batch.actions_raw[i, length:] == 0)
    np.testing.assert_allclose(batch.discounted_returns(), expected, rtol=0, atol=1e-12)
    assert np.any(np.abs(batch.actions_raw[batch.mask]) > bound)  # the clip did something
    # Undiscounted measure: the plain sum of rewards.
    undiscounted = counter_task(gamma=gamma, measure="undiscounted")
    np.testing.assert_array_equal(undiscounted.measured_returns(batch), batch.rewards.sum(axis=1))
    np.testing.assert_array_equal(task.measured_returns(batch), batch.discounted_returns())


def test_env_truncation_before_the_horizon_is_masked() -> None:
    def short() -> gym.Env:
        return gym.wrappers.TimeLimit(CounterEnv(), max_episode_steps=1)

    batch = GymTask(short, horizon=4, gamma=0.5).simulate(LinearGaussianPolicy([[0.0]], 1.0), 5, 0)
    assert batch.mask.tolist() == [[True, False, False, False]] * 5


def test_horizon_overrides_the_registered_time_limit() -> None:
    task = GymTask("Pendulum-v1", horizon=230, gamma=0.99)  # Pendulum-v1's own limit is 200
    batch = task.simulate(LinearGaussianPolicy(np.zeros((1, 3)), 0.5), 2, 0)
    assert batch.mask.all() and np.all(batch.rewards[:, 200:] < 0)


def test_same_rng_gives_the_same_batch() -> None:
    task = GymTask("Pendulum-v1", horizon=10, gamma=0.9)
    policy = LinearGaussianPolicy(np.array([[0.1, -0.2, 0.05]]), 0.5)
    a = task.simulate(policy, 3, np.random.default_rng(5))
    task.simulate(policy, 6, 1)  # grows the pool and rebuilds the vector env
    b = task.simulate(policy, 3, np.random.default_rng(5))
    other = task.simulate(policy, 3, np.random.default_rng(6))
    for field in ("features", "actions_raw", "actions", "rewards", "mask"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert not np.array_equal(a.rewards, other.rewards)
    # A shared Generator moves on: consecutive batches differ.
    rng = np.random.default_rng(5)
    assert not np.array_equal(task.simulate(policy, 3, rng).rewards, task.simulate(policy, 3, rng).rewards)


def test_pickled_task_simulates_the_same_batch() -> None:
    """A task crosses process boundaries (joblib) without its environments."""
    task = GymTask("Pendulum-v1", horizon=8, gamma=0.9, features=with_bias)
    policy = LinearGaussianPolicy(np.array([[0.1, -0.2, 0.05, 0.3]]), 0.5)
    a = task.simulate(policy, 4, 3)
    b = pickle.loads(pickle.dumps(task)).simulate(policy, 4, 3)
    np.testing.assert_array_equal(a.rewards, b.rewards)
    np.testing.assert_array_equal(a.features, b.features)


def test_learning_loops_accept_the_task() -> None:
    task = counter_task()
    rec = vanilla_pg(task, 0.0, 1.0, batch_size=8, step=FixedStep(0.01), budget=32, rng=0)
    assert rec.iterations == 4 and np.all(np.isnan(rec.J)) and np.all(np.isfinite(rec.J_hat))
    # No closed-form J: its improvement ratio is unknown (NaN), not 0; J_hat's is measured, and is
    # what the run is judged on by default.
    assert np.isnan(rec.improvement_ratio("J")) and rec.performance_field == "J_hat"
    assert rec.improvement_ratio() == rec.improvement_ratio("J_hat") == rec.summary()["improvement_ratio"]
    # J_hat's is measured: the share of the 3 updates after which the next batch's average return did not fall.
    rises = np.diff(rec.J_hat) >= 0
    assert 0 < rises.sum() < 3  # this run rises and falls, so counting falls instead would give another share
    assert rec.improvement_ratio("J_hat") == rises.sum() / 3
    assert rec.config["task"]["type"] == "GymTask" and rec.config["task"]["env_factory"].endswith(":CounterEnv")
    task.close()
    rec = adaptive_pg(task, 0.0, 1.0, batches=Batches(8, 16), budget=40, rng=0)  # simulating again after close
    assert rec.trajectories == 40


# ------------------------------------------------------------------- end to end: Pendulum
SIGMA = 0.5


def upright_pendulum() -> GymTask:
    """Pendulum-v1 started near the top (angle and speed uniform in [-0.3, 0.3]): balancing,
    which a linear policy on phi = (sin angle, speed / 8) can learn.

    R = pi^2 + 0.1 * 8^2 + 0.001 * 2^2, the largest |reward| of Pendulum-v1, and M_phi = 1.
    """
    return GymTask(
        "Pendulum-v1", horizon=50, gamma=0.95,
        reward_bound=np.pi**2 + 0.1 * 8**2 + 0.001 * 2**2, feature_bound=1.0,
        features=sin_and_speed, reset_options={"x_init": 0.3, "y_init": 0.3},
    )


def sin_and_speed(obs: np.ndarray) -> np.ndarray:
    """(cos a, sin a, a_dot) -> (sin a, a_dot / 8): both in [-1, 1]."""
    return obs[:, 1:] / np.array([1.0, 8.0])


def monte_carlo_J(task: GymTask, theta: np.ndarray, n: int = 500, z: float = 2.576) -> tuple[float, float]:
    """Mean discounted return of n episodes and the half-width of its 99% interval."""
    returns = task.simulate(LinearGaussianPolicy(theta.reshape(1, -1), SIGMA), n, 2024).discounted_returns()
    return float(returns.mean()), float(z * returns.std(ddof=1) / np.sqrt(n))


def test_vanilla_pg_improves_pendulum() -> None:
    task = upright_pendulum()
    start = time.perf_counter()
    rec = vanilla_pg(task, np.zeros(2), SIGMA, batch_size=20, step=FixedStep(0.05), budget=600,
                     gradient=Gradient(score_action="raw"), rng=0)
    J0, h0 = monte_carlo_J(task, rec.theta[0])
    J1, h1 = monte_carlo_J(task, rec.theta_final)
    print(f"vanilla PG on Pendulum-v1: J {J0:.2f} +- {h0:.2f} -> {J1:.2f} +- {h1:.2f} (99%), "
          f"theta {rec.theta_final.round(3).tolist()}, {time.perf_counter() - start:.1f} s")
    assert J1 - h1 > J0 + h0


def test_adaptive_pg_runs_on_pendulum() -> None:
    task = upright_pendulum()
    start = time.perf_counter()
    rec = adaptive_pg(task, np.zeros(2), SIGMA, error=ErrorModel("bernstein", range="empirical"),
                      batches=Batches(100, 2000), budget=5000, gradient=Gradient(score_action="raw"), rng=0)
    assert rec.trajectories == 5000
    assert np.all(rec.batch_size[:-1] >= 100) and np.all(rec.batch_size <= 2000)  # the last one is cut to the budget
    assert np.all(np.isfinite(rec.alpha)) and np.all(rec.alpha >= 0)
    assert np.all(np.isfinite(rec.eps)) and np.all(np.isfinite(rec.theta))
    J0, h0 = monte_carlo_J(task, rec.theta[0])
    J1, h1 = monte_carlo_J(task, rec.theta_final)
    print(f"adaptive PG on Pendulum-v1: c = {rec.config['c']:.3g}, batch sizes {rec.batch_size.tolist()}, "
          f"alpha {rec.alpha.tolist()}, safe {rec.safe.tolist()}; J {J0:.4f} +- {h0:.2f} -> {J1:.4f} +- {h1:.2f} "
          f"(moved {J1 - J0:+.2e}; same episodes), {time.perf_counter() - start:.1f} s")


# ------------------------------------------------------------------------- stored runs
def _bias_features(obs: np.ndarray) -> np.ndarray:
    return with_bias(obs)


PENDULUM = dict(horizon=20, gamma=0.9, reward_bound=16.3, feature_bound=8.0)


def test_every_argument_of_a_stored_task_is_in_its_run_key() -> None:
    """A run is found by its task's whole definition: change any argument and it is another run."""
    def key(**kw: Any) -> str:
        return RunConfig("own", method=Vanilla(8, FixedStep(0.01)), task=GymTask("Pendulum-v1", **{**PENDULUM, **kw}),
                         theta0=(0.0,) * 3, budget=32).key()

    base = key()
    changed = [key(horizon=21), key(gamma=0.8), key(reward_bound=17.0), key(feature_bound=9.0),
               key(action_volume=4.0), key(action_bound=2.5), key(features=_bias_features),
               key(horizon_term="truncated"), key(measure="undiscounted"), key(env_kwargs={"g": 9.81}),
               key(reset_options={"x_init": 0.3, "y_init": 0.3})]
    assert base not in changed and len(set(changed)) == len(changed)
    task = GymTask("Pendulum-v1", **PENDULUM, features=_bias_features)
    cfg = RunConfig("own", task=task, theta0=(0.0,) * 4)
    again = RunConfig.from_definition("own", cfg.definition())
    assert again.key() == cfg.key() and again.make_task().features_name is None  # found again by its import name


def test_a_stored_run_refuses_a_lambda_until_it_is_named() -> None:
    lam = GymTask(lambda: CounterEnv(), horizon=5, gamma=0.5, reward_bound=3.0, feature_bound=2.0)
    with pytest.raises(UnnamedError, match="give it a name"):
        RunConfig("own", method=Vanilla(8, FixedStep(0.01)), task=lam, budget=32).key()
    feats = GymTask(CounterEnv, horizon=5, gamma=0.5, reward_bound=3.0, feature_bound=2.0, features=lambda o: o)
    with pytest.raises(UnnamedError):
        RunConfig("own", task=feats).key()
    # A record of a direct run keeps what it can, a run key needs the names.
    rec = vanilla_pg(lam, 0.0, 1.0, batch_size=8, step=FixedStep(0.01), budget=16, rng=0)
    assert rec.config["task"]["type"] == "unnamed"
    named = [GymTask(lambda: CounterEnv(), horizon=5, gamma=0.5, reward_bound=3.0, feature_bound=2.0, name=n,
                     features=lambda o: o, features_name=f) for n, f in (("counter-v1", "id"), ("counter-v2", "id"),
                                                                         ("counter-v1", "id2"))]
    keys = {RunConfig("own", task=t).key() for t in named}
    assert len(keys) == 3
