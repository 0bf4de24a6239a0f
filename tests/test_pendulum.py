"""The pendulum task against gymnasium's PendulumEnv: one step from identical states, whole
episodes from random starts with random torques, the batched simulator against single
gymnasium envs, the declared bounds, and that the comparison detects a changed term."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import import_or_fail
from safepg.constants import TaskConstants
from safepg.envs.pendulum import Pendulum, angle_normalize, gymnasium_step, step_dynamics, step_reward
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key, trajectory_draws
from safepg.tasks import task_hooks

gym = import_or_fail("gymnasium")
from gymnasium.envs.classic_control.pendulum import PendulumEnv  # noqa: E402

ONE_STEP = 1e-12
EPISODE = 1e-9


def random_states(rng: np.random.Generator, n: int) -> np.ndarray:
    # Angles far past +-pi (the state is not wrapped, only the reward's angle is) and every speed.
    return rng.uniform([-30.0, -8.0], [30.0, 8.0], size=(n, 2))


def one_step_gap(task: Pendulum, states: np.ndarray, torques: np.ndarray) -> tuple[float, float]:
    """Largest |ours - gymnasium's| over one step from each state: (next states, rewards)."""
    applied = np.clip(torques, -task.max_torque, task.max_torque)
    theirs, rewards = gymnasium_step(states, torques, gravity=10.0)
    return (float(np.max(np.abs(task.step(states, applied) - theirs))),
            float(np.max(np.abs(task.reward(states, applied) - rewards))))


def episode_gap(task: Pendulum, episodes: int, seed: int) -> tuple[float, float]:
    """Largest |ours - gymnasium's| over whole episodes: gymnasium draws each start (its own reset,
    seeded) and both step with the same random torques (a third of them outside [-2, 2]).
    Ours steps every episode at once; gymnasium one env at a time."""
    rng = np.random.default_rng(seed)
    torques = rng.uniform(-3.0, 3.0, size=(episodes, task.horizon))
    env = gym.make("Pendulum-v1", max_episode_steps=task.horizon)
    starts = np.empty((episodes, 2))
    theirs_all = np.empty((episodes, task.horizon, 2))
    rewards_all = np.empty((episodes, task.horizon))
    for i in range(episodes):
        env.reset(seed=seed + i)
        starts[i] = env.unwrapped.state  # in [-pi, pi] x [-1, 1], gymnasium's draw
        for t in range(task.horizon):
            _, r, terminated, truncated, _ = env.step(np.array([torques[i, t]]))
            theirs_all[i, t] = env.unwrapped.state
            rewards_all[i, t] = r
            assert not terminated and truncated == (t == task.horizon - 1)
    states_gap = rewards_gap = 0.0
    ours = starts
    for t in range(task.horizon):
        u = np.clip(torques[:, t], -task.max_torque, task.max_torque)
        rewards_gap = max(rewards_gap, float(np.max(np.abs(task.reward(ours, u) - rewards_all[:, t]))))
        ours = task.step(ours, u)
        states_gap = max(states_gap, float(np.max(np.abs(ours - theirs_all[:, t]))))
    return states_gap, rewards_gap


def test_one_step_matches_gymnasium() -> None:
    rng = np.random.default_rng(1)
    states = random_states(rng, 2000)
    torques = rng.uniform(-3.0, 3.0, size=2000)
    torques[:3] = [0.0, 2.0, -2.0]
    states[:4] = [[0.0, 0.0], [math.pi, 0.0], [-math.pi, 8.0], [3 * math.pi, -8.0]]
    state_gap, reward_gap = one_step_gap(Pendulum(), states, torques)
    assert state_gap <= ONE_STEP and reward_gap <= ONE_STEP
    # The speed limit binds on some of these steps: the clip is exercised.
    speed = states[:, 1] + (15.0 * np.sin(states[:, 0]) + 3.0 * np.clip(torques, -2, 2)) * 0.05
    assert np.mean(np.abs(speed) > 8.0) > 0.02


def test_episodes_from_random_starts_with_random_torques_match_gymnasium() -> None:
    state_gap, reward_gap = episode_gap(Pendulum(), episodes=40, seed=11)
    assert state_gap <= EPISODE and reward_gap <= EPISODE


#: One term of the dynamics or the reward changed at a time: each must fail the equality checks.
CHANGED_TERMS = {
    "gravity": dict(gravity=10.0 + 1e-6),
    "mass": dict(mass=1.0 + 1e-6),
    "length": dict(length=1.0 + 1e-6),
    "time step": dict(dt=0.05 * (1 + 1e-9)),
    "speed limit": dict(max_speed=7.99),
}


@pytest.mark.parametrize("term", list(CHANGED_TERMS))
def test_a_changed_term_fails_the_comparison(term: str) -> None:
    """The checks above on a task whose dynamics differ from gymnasium's in one term: they fail."""
    task = replace(Pendulum(), **CHANGED_TERMS[term])
    rng = np.random.default_rng(1)
    states = random_states(rng, 2000)
    torques = rng.uniform(-3.0, 3.0, size=2000)
    state_gap, _ = one_step_gap(task, states, torques)
    assert state_gap > ONE_STEP
    if term != "speed limit":  # a small change of a coefficient grows over an episode
        assert episode_gap(task, episodes=5, seed=11)[0] > EPISODE


def test_a_changed_reward_term_fails_the_comparison(monkeypatch: pytest.MonkeyPatch) -> None:
    """The reward's weight on the speed, 0.1, made 0.1 + 1e-9: the one-step check fails."""
    from safepg.envs import pendulum

    def changed(state: np.ndarray, torque: np.ndarray) -> np.ndarray:
        s = np.asarray(state, dtype=float)
        na, w, u = angle_normalize(s[..., 0]), s[..., 1], np.asarray(torque, dtype=float)
        return np.asarray(-((na * na + (0.1 + 1e-9) * (w * w)) + 0.001 * (u * u)))

    monkeypatch.setattr(pendulum, "step_reward", changed)
    rng = np.random.default_rng(1)
    _, reward_gap = one_step_gap(Pendulum(), random_states(rng, 200), rng.uniform(-3, 3, 200))
    assert reward_gap > ONE_STEP


def replay_gymnasium(task: Pendulum, gain: np.ndarray, sigma: float, n: int, seed: int) -> dict[str, np.ndarray]:
    """Step n gymnasium PendulumEnvs with the simulator's documented random draws: trajectory i's
    two uniforms give its start, then a standard normal per step its action noise."""
    uniforms, normals = trajectory_draws(batch_key(np.random.default_rng(seed)), n, 2, task.horizon)
    env = PendulumEnv()
    env.reset(seed=0)
    out = {"features": np.empty((n, task.horizon, 3)), "raw": np.empty((n, task.horizon)),
           "rewards": np.empty((n, task.horizon))}
    for i in range(n):
        env.state = np.array([-math.pi + 2 * math.pi * uniforms[i, 0], -1.0 + 2.0 * uniforms[i, 1]])
        for t in range(task.horizon):
            th, thdot = env.state
            phi = np.array([np.cos(th), np.sin(th), thdot])
            a = float(gain @ phi) + sigma * normals[i, t]
            _, r, _, _, _ = env.step(np.array([a]))  # PendulumEnv clips the torque itself
            out["features"][i, t], out["raw"][i, t], out["rewards"][i, t] = phi, a, r
    return out


@pytest.mark.parametrize("gain", [np.zeros(3), np.array([-2.0, -6.0, -1.0]), np.array([0.5, 1.0, 3.0])])
def test_simulate_equals_single_gymnasium_envs(gain: np.ndarray) -> None:
    task = Pendulum()
    batch = task.simulate(LinearGaussianPolicy(gain[None, :], 1.0), 12, 7)
    ref = replay_gymnasium(task, gain, 1.0, 12, 7)
    assert batch.mask is None
    np.testing.assert_allclose(batch.features, ref["features"], rtol=0, atol=EPISODE)
    np.testing.assert_allclose(batch.actions_raw[..., 0], ref["raw"], rtol=0, atol=EPISODE)
    np.testing.assert_allclose(batch.rewards, ref["rewards"], rtol=0, atol=EPISODE)
    np.testing.assert_array_equal(batch.actions, np.clip(batch.actions_raw, -2.0, 2.0))


def test_bounds_are_declared_exactly() -> None:
    task = Pendulum()
    assert task.reward_bound == np.pi**2 + 0.1 * 8**2 + 0.001 * 2**2
    assert task.reward_bound == pytest.approx(16.2736044, abs=1e-7)  # gymnasium's documented minimum reward
    assert (task.feature_bound, task.action_bound, task.action_volume) == (8.0, 2.0, 4.0)
    assert (task.gamma, task.horizon, task.init_angle, task.init_speed) == (0.99, 200, math.pi, 1.0)
    c = TaskConstants.from_task(task, 1.0)
    assert (c.R, c.M_phi, c.action_volume, c.A_bar, c.H) == (task.reward_bound, 8.0, 4.0, 2.0, 200)
    assert task_hooks(task).action_dim == 1
    # The bound is reached: upright-down (angle -pi after normalisation), top speed, full torque.
    assert step_reward(np.array([math.pi, 8.0]), 2.0) == -task.reward_bound


def test_bounds_hold_on_rollouts() -> None:
    task = Pendulum()
    for gain, sigma in ((np.zeros(3), 1.0), (np.array([0.0, 0.0, 3.0]), 3.0)):
        batch = task.simulate(LinearGaussianPolicy(gain[None, :], sigma), 300, 1)
        assert np.all(batch.rewards <= 0) and np.all(-batch.rewards <= task.reward_bound)
        assert np.all(np.abs(batch.features) <= task.feature_bound)
        assert np.all(np.abs(batch.actions) <= task.action_bound)
    assert np.abs(batch.features[..., 2]).max() == 8.0  # the pumping gain reaches the speed limit


def test_angle_normalize_is_gymnasiums() -> None:
    from gymnasium.envs.classic_control.pendulum import angle_normalize as theirs

    x = np.random.default_rng(4).uniform(-100, 100, 10_000)
    x[:5] = [math.pi, -math.pi, 3 * math.pi, 0.0, -0.0]
    assert np.array_equal(angle_normalize(x), theirs(x))
    assert np.all((angle_normalize(x) >= -math.pi) & (angle_normalize(x) < math.pi))


def test_step_broadcasts() -> None:
    s = random_states(np.random.default_rng(2), 12).reshape(3, 4, 2)
    u = np.random.default_rng(3).uniform(-2, 2, size=(3, 4))
    out = step_dynamics(s, u)
    assert out.shape == (3, 4, 2)
    np.testing.assert_array_equal(out[1, 2], step_dynamics(s[1, 2], u[1, 2]))
    assert Pendulum().features(s).shape == (3, 4, 3)


@pytest.mark.parametrize("field, value, message", [
    ("gamma", 1.5, "^gamma"), ("horizon", 0, "^horizon"), ("dt", -0.1, "^dt"), ("max_torque", math.inf, "^max_torque"),
    ("init_speed", 9.0, "^init_speed"), ("measure", "median", "^measure"), ("horizon_term", "x", "^horizon_term"),
    ("constants_gamma", 0.0, "^constants_gamma"), ("horizon", 10**7, "^horizon")])
def test_bad_settings_are_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Pendulum(**{field: value})  # type: ignore[arg-type]


def test_simulate_refuses_bad_policies_and_sizes() -> None:
    task = Pendulum()
    with pytest.raises(ValueError, match="^policy"):
        task.simulate(LinearGaussianPolicy(np.zeros((1, 4)), 1.0), 3)
    with pytest.raises(ValueError, match="^n must"):
        task.simulate(LinearGaussianPolicy(np.zeros((1, 3)), 1.0), 0)
