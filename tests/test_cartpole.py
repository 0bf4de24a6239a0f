"""Continuous cart-pole: physics against gymnasium's CartPoleEnv, the batched simulator
against single-env stepping, termination, seeding, input checks and the gymnasium env."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

from conftest import import_or_fail
from safepg.constants import TaskConstants
from safepg.envs.cartpole import ENV_ID, CartPole, step_dynamics
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key, trajectory_draws

gym = import_or_fail("gymnasium")
from gymnasium.envs.classic_control.cartpole import CartPoleEnv  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

from safepg.envs.cartpole import ContinuousCartPoleEnv, gymnasium_step  # noqa: E402

THR = math.radians(41.8)
# Balances the 1 m pole for the whole horizon (checked in test_simulate_reaches_every_ending).
STABLE = np.array([1.0, 2.0, 40.0, 8.0])


def gym_cartpole(half_length: float = 0.5) -> CartPoleEnv:
    """gymnasium's discrete CartPoleEnv with the thesis's termination angle and pole."""
    env = CartPoleEnv()
    env.reset(seed=0)
    env.theta_threshold_radians = THR
    env.length = half_length
    env.polemass_length = env.masspole * env.length  # cached in __init__: keep it consistent
    return env


def gym_step(env: CartPoleEnv, state: np.ndarray, force: float) -> tuple[np.ndarray, bool]:
    """One gymnasium step with an arbitrary force: the fixed force magnitude is set to |force|
    and the discrete action picks its sign."""
    env.state = np.array(state, dtype=float)
    env.steps_beyond_terminated = None
    env.force_mag = abs(force)
    _, _, terminated, _, _ = env.step(1 if force >= 0 else 0)
    return np.array(env.state, dtype=float), terminated


def random_states(rng: np.random.Generator, n: int) -> np.ndarray:
    # Inside and well outside the alive region, fast and slow: the equations, not the task.
    return rng.uniform([-3.0, -10.0, -1.5, -8.0], [3.0, 10.0, 1.5, 8.0], size=(n, 4))


@pytest.mark.parametrize("pole_length", [1.0, 2.0])
def test_step_matches_gymnasium(pole_length: float) -> None:
    rng = np.random.default_rng(1)
    states = random_states(rng, 300)
    forces = rng.uniform(-10, 10, size=300)
    forces[:3] = [0.0, 10.0, -10.0]
    ours = step_dynamics(states, forces, pole_length=pole_length)  # one vectorised call
    env = gym_cartpole(half_length=pole_length / 2)  # gymnasium's length is half the pole
    theirs = np.array([gym_step(env, s, f)[0] for s, f in zip(states, forces)])
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gymnasium_step(states, forces, pole_length), theirs, rtol=0, atol=0)
    if pole_length == 2.0:  # the doubled pole really changes the dynamics
        assert np.max(np.abs(ours - step_dynamics(states, forces))) > 1e-3


def test_step_broadcasts_and_task_step_uses_its_length() -> None:
    rng = np.random.default_rng(2)
    s = random_states(rng, 12).reshape(3, 4, 4)
    f = rng.uniform(-10, 10, size=(3, 4))
    batch = step_dynamics(s, f, 2.0)
    assert batch.shape == (3, 4, 4)
    np.testing.assert_array_equal(batch[1, 2], step_dynamics(s[1, 2], f[1, 2], 2.0))
    np.testing.assert_array_equal(CartPole(pole_length=2.0).step(s, f), batch)
    assert step_dynamics(s[0, 0], 3.0).shape == (4,)


def test_thesis_settings_and_bound_constants() -> None:
    task = CartPole.thesis()
    assert (task.cart_mass, task.pole_mass, task.pole_length) == (1.0, 0.1, 1.0)
    assert CartPole.thesis_doubled().pole_length == 2.0
    assert CartPole.thesis_doubled().pole_mass == 0.1
    assert task.angle_threshold == pytest.approx(0.7295476, abs=1e-6)
    assert (task.reward_bound, task.action_bound, task.action_volume) == (1.0, 10.0, 20.0)
    assert (task.gamma, task.horizon, task.state_dim, task.action_dim) == (0.99, 200, 4, 1)
    c = TaskConstants.from_task(task, sigma=1.0)
    assert (c.R, c.M_phi, c.action_volume, c.A_bar, c.H) == (1.0, task.feature_bound, 20.0, 10.0, 200)


def test_termination_thresholds() -> None:
    task = CartPole()
    eps = 1e-9
    inside = [[2.4, 0, 0, 0], [-2.4, 5, 0, 3], [0, 0, THR, 0], [0, 0, -THR, 0], [0, 0, math.radians(12.5), 0]]
    outside = [[2.4 + eps, 0, 0, 0], [-2.4 - eps, 0, 0, 0], [0, 0, THR + eps, 0], [0, 0, -THR - eps, 0]]
    assert task.alive(np.array(inside)).all()  # 12.5 degrees is alive: not gymnasium's 12
    assert not task.alive(np.array(outside)).any()
    assert not CartPole(angle_threshold_deg=12).alive(np.array([0, 0, math.radians(12.5), 0]))


def replay_gymnasium(task: CartPole, gain: np.ndarray, n: int, seed: int) -> dict[str, np.ndarray]:
    """Step n single gymnasium CartPoleEnvs with the simulator's documented random draws."""
    # One batch key from the seed; trajectory i: 4 uniforms (its initial state), then normals.
    uniforms, normals = trajectory_draws(batch_key(np.random.default_rng(seed)), n, 4, task.horizon)
    s0 = -0.05 + 0.1 * uniforms
    noise = normals[:, :, None]
    H = task.horizon
    out = {k: np.zeros((n, H, 4) if k == "features" else (n, H)) for k in ("features", "raw", "rewards")}
    out["mask"] = np.zeros((n, H), dtype=bool)
    env = gym_cartpole(task.pole_length / 2)
    for i in range(n):
        s = s0[i]
        for t in range(H):
            out["mask"][i, t] = True
            out["features"][i, t] = s
            a = gain @ s + noise[i, t, 0]
            out["raw"][i, t] = a
            s, terminated = gym_step(env, s, float(np.clip(a, -10, 10)))
            out["rewards"][i, t] = 1.0  # gymnasium rewards the failing step too
            if terminated:
                break
    return out


@pytest.mark.parametrize(("gain", "pole_length"), [(np.zeros(4), 1.0), (STABLE, 1.0), (np.array([0.5, 1, 20, 3]), 2.0)])
def test_simulate_equals_single_gymnasium_envs(gain: np.ndarray, pole_length: float) -> None:
    task = CartPole(pole_length=pole_length)
    n = 12
    batch = task.simulate_gain(gain, 1.0, n, rng=7)
    ref = replay_gymnasium(task, gain, n, seed=7)
    np.testing.assert_array_equal(batch.mask, ref["mask"])
    np.testing.assert_array_equal(batch.rewards, ref["rewards"])
    np.testing.assert_allclose(batch.features, ref["features"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(batch.actions_raw[..., 0], ref["raw"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(batch.actions, np.clip(batch.actions_raw, -10, 10))


def test_simulate_equals_our_gymnasium_env() -> None:
    task = CartPole()
    gain = np.array([0.3, 1.0, 25.0, 4.0])
    n = 8
    batch = task.simulate_gain(gain, 1.0, n, rng=3)
    uniforms, normals = trajectory_draws(batch_key(np.random.default_rng(3)), n, 4, task.horizon)
    s0 = -0.05 + 0.1 * uniforms
    noise = normals[:, :, None]
    env = ContinuousCartPoleEnv()
    for i in range(n):
        s, _ = env.reset(options={"state": s0[i]})
        ret, t, done = 0.0, 0, False
        while not done:
            np.testing.assert_allclose(s, batch.features[i, t], rtol=0, atol=1e-9)
            s, r, terminated, truncated, _ = env.step(np.array([gain @ s + noise[i, t, 0]]))
            ret, t, done = ret + r, t + 1, terminated or truncated
        assert ret == batch.rewards[i].sum() == batch.mask[i].sum()
        assert truncated == (t == task.horizon) and terminated == (t < task.horizon)


def test_simulate_reaches_every_ending_and_respects_thresholds() -> None:
    task = CartPole()
    lengths, x_ends, angle_ends = [], 0, 0
    for gain in (np.zeros(4), STABLE, np.array([-1.0, 0, 30, 5])):
        b = task.simulate_gain(gain, 1.0, 400, rng=11)
        L = b.mask.sum(axis=1)
        lengths.append(L)
        # Alive prefix, dead suffix; alive states inside the thresholds; dead steps all zero.
        assert np.array_equal(b.mask, np.arange(task.horizon)[None, :] < L[:, None])
        assert task.alive(b.features[b.mask]).all()
        dead = ~b.mask
        assert not b.features[dead].any() and not b.actions[dead].any() and not b.rewards[dead].any()
        np.testing.assert_array_equal(b.rewards, b.mask.astype(float))
        np.testing.assert_array_equal(CartPole.undiscounted_returns(b), L)
        np.testing.assert_allclose(b.discounted_returns(), (1 - 0.99**L) / 0.01, rtol=1e-12)
        # Every early end is a step from the last alive state to a failing one.
        ended = np.flatnonzero(L < task.horizon)
        last = b.features[ended, L[ended] - 1]
        nxt = task.step(last, b.actions[ended, L[ended] - 1, 0])
        assert not task.alive(nxt).any()
        x_ends += int(np.sum(np.abs(nxt[:, 0]) > 2.4))
        angle_ends += int(np.sum(np.abs(nxt[:, 2]) > THR))
    assert lengths[0].mean() < 100 and (lengths[1] == task.horizon).all()
    assert x_ends > 0 and angle_ends > 0


def test_feature_bound_holds_in_simulation() -> None:
    """M_phi = 10 is an empirical bound: alive states of random (also aggressive) policies stay inside it."""
    rng = np.random.default_rng(5)
    for task in (CartPole(), CartPole.thesis_doubled()):
        worst = np.zeros(4)
        for scale in (1.0, 10.0, 100.0):
            for gain in rng.normal(0.0, scale, size=(8, 4)):
                b = task.simulate_gain(gain, 1.0, 250, rng)
                worst = np.maximum(worst, np.abs(b.features).max(axis=(0, 1)))
        assert worst.max() <= task.feature_bound
        assert worst[1] > 4.0  # the sweep does reach fast states (the bound is not vacuous)


def test_same_seed_same_batch() -> None:
    task = CartPole()
    a = task.simulate_gain(np.array([0.5, 1, 20, 3]), 1.0, 50, rng=123)
    b = task.simulate(LinearGaussianPolicy(np.array([[0.5, 1, 20, 3]]), 1.0), 50, np.random.default_rng(123))
    for field in ("features", "actions_raw", "actions", "rewards", "mask"):
        assert np.array_equal(getattr(a, field), getattr(b, field))
    c = task.simulate_gain(np.array([0.5, 1, 20, 3]), 1.0, 50, rng=124)
    assert not np.array_equal(a.features, c.features)
    # sigma as a (1,) std or a (1, 1) covariance is the same policy.
    d = task.simulate_gain(np.array([[0.5, 1, 20, 3]]), np.array([[4.0]]), 50, rng=9)
    e = task.simulate_gain(np.array([0.5, 1, 20, 3]), np.array([2.0]), 50, rng=9)
    assert np.array_equal(d.actions_raw, e.actions_raw)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"n": 0}, "n"),
        ({"n": -3}, "n"),
        ({"n": 2.5}, "n"),
        ({"n": float("nan")}, "n"),
        ({"n": float("inf")}, "n"),
        ({"sigma": 0.0}, "sigma"),
        ({"sigma": -1.0}, "sigma"),
        ({"sigma": float("nan")}, "sigma"),
        ({"gain": np.zeros((4, 1))}, "gain"),
        ({"gain": np.zeros((1, 3))}, "gain"),
        ({"gain": np.zeros((2, 4))}, "gain"),
        ({"gain": np.array([0.0, np.nan, 0.0, 0.0])}, "gain"),
        ({"gain": np.array([0.0, 0.0, np.inf, 0.0])}, "gain"),
    ],
)
def test_bad_inputs_raise(kwargs: dict, name: str) -> None:
    args = {"gain": np.zeros(4), "sigma": 1.0, "n": 5, "rng": 0, **kwargs}
    with pytest.raises(ValueError, match=rf"^{name} "):
        CartPole().simulate_gain(**args)


def test_bad_policy_and_settings_raise() -> None:
    with pytest.raises(ValueError, match=r"^policy "):
        CartPole().simulate(LinearGaussianPolicy(np.zeros((1, 3)), 1.0), 5, 0)
    for field, value in (("gamma", 0.0), ("gamma", 1.5), ("horizon", 0), ("pole_length", -1.0),
                         ("feature_bound", np.inf), ("init_bound", 3.0)):
        with pytest.raises(ValueError, match=rf"^{field} "):
            CartPole(**{field: value})


def test_gymnasium_env_checks_and_registration() -> None:
    with warnings.catch_warnings():
        # Our choices, flagged as style hints by the checker: a force in newtons (not
        # [-1, 1]) and an unbounded observation box (the velocities are unbounded).
        warnings.filterwarnings("ignore", message=".*symmetric and normalized space.*")
        warnings.filterwarnings("ignore", message=".*infinity.*")
        # A directly constructed env has no spec; the registered one is checked below.
        warnings.filterwarnings("ignore", message=".*alternative render modes.*")
        check_env(ContinuousCartPoleEnv())
        env = gym.make(ENV_ID, pole_length=2.0)
        check_env(env.unwrapped)
    assert env.unwrapped.task.pole_length == 2.0
    assert env.action_space.low[0] == -10.0 and env.action_space.high[0] == 10.0


def test_gymnasium_env_episode_end() -> None:
    env = ContinuousCartPoleEnv()
    obs, _ = env.reset(seed=4)
    assert np.all(np.abs(obs) <= 0.05)
    steps = 0
    while True:  # the stabilising policy is truncated at H = 200
        obs, r, terminated, truncated, _ = env.step(np.array([STABLE @ obs]))
        steps += 1
        assert r == 1.0
        if terminated or truncated:
            break
    assert (steps, terminated, truncated) == (200, False, True)
    assert env.step(np.array([0.0]))[1:4] == (0.0, False, True)  # over: no more reward
    env.reset(options={"state": [0.0, 0.0, 0.7, 3.0]})  # about to fall
    _, r, terminated, truncated, _ = env.step(np.array([50.0]))  # clipped to 10 N, still rewarded
    assert (r, terminated, truncated) == (1.0, True, False)
    assert env.step(np.array([0.0]))[1:3] == (0.0, True)
    with pytest.raises(ValueError, match=r"^action "):
        env.step(np.array([np.nan]))


def test_works_without_gymnasium() -> None:
    code = (
        "import sys; sys.modules['gymnasium'] = None\n"
        "import numpy as np, safepg.envs.cartpole as m\n"
        "assert not hasattr(m, 'ContinuousCartPoleEnv')\n"
        "m.register_envs()\n"
        "assert m.CartPole().simulate_gain(np.zeros(4), 1.0, 3, 0).n == 3\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


@pytest.mark.parametrize("pole_length", [1.0, 2.0])
def test_semi_implicit_step_matches_gymnasium(pole_length: float) -> None:
    rng = np.random.default_rng(21)
    states, forces = random_states(rng, 300), rng.uniform(-10, 10, 300)
    ours = step_dynamics(states, forces, pole_length, integrator="semi-implicit")
    np.testing.assert_allclose(ours, gymnasium_step(states, forces, pole_length, "semi-implicit"), rtol=0, atol=1e-12)
    # ... and it is another scheme: positions move with the new velocities.
    assert np.abs(ours - step_dynamics(states, forces, pole_length)).max() > 1e-3
    np.testing.assert_array_equal(ours[:, 0], states[:, 0] + 0.02 * ours[:, 1])
    with pytest.raises(ValueError, match="^integrator "):
        step_dynamics(states, forces, integrator="rk4")


def test_gymnasium_env_uses_the_task_settings() -> None:
    env = ContinuousCartPoleEnv(integrator="semi-implicit", tau=0.01)
    s0 = np.array([0.01, -0.02, 0.03, 0.01])
    env.reset(options={"state": s0})
    obs, *_ = env.step(np.array([3.0]))
    np.testing.assert_array_equal(obs, step_dynamics(s0, 3.0, tau=0.01, integrator="semi-implicit"))


# ------------------------------------------------------------------ the authors' settings
def test_authors_doubled_pole_one_step_by_hand() -> None:
    """One step of the authors' doubled pole (half-length 1 m in the angular equation only, m l kept
    at the 1 m pole's 0.05) against the equations written out by hand, beside the consistent 2 m pole."""
    x, x_dot, beta, beta_dot, force = 0.1, -0.2, 0.15, 0.8, 6.0
    s, c = math.sin(beta), math.cos(beta)
    g, tau, m, total = 9.8, 0.02, 0.1, 1.1

    def by_hand(half: float, ml: float) -> list[float]:
        temp = (force + ml * beta_dot**2 * s) / total
        beta_acc = (g * s - c * temp) / (half * (4 / 3 - m * c**2 / total))
        x_acc = temp - ml * beta_acc * c / total
        return [x + tau * x_dot, x_dot + tau * x_acc, beta + tau * beta_dot, beta_dot + tau * beta_acc]

    state = np.array([x, x_dot, beta, beta_dot])
    authors = step_dynamics(state, force, 2.0, polemass_length=0.05)
    consistent = step_dynamics(state, force, 2.0)
    np.testing.assert_allclose(authors, by_hand(1.0, 0.05), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(consistent, by_hand(1.0, 0.1), rtol=1e-14, atol=1e-15)
    # The stale m l changes both accelerations; positions move with the old velocities either way.
    assert authors[1] != consistent[1] and authors[3] != consistent[3]
    assert authors[0] == consistent[0] and authors[2] == consistent[2]
    # Spelled out at its consistent value, polemass_length changes no bit.
    rng = np.random.default_rng(5)
    states, forces = random_states(rng, 200), rng.uniform(-10, 10, 200)
    for length in (1.0, 2.0):
        assert np.array_equal(step_dynamics(states, forces, length),
                              step_dynamics(states, forces, length, polemass_length=0.1 * length / 2))


def test_authors_doubled_pole_is_gymnasium_with_length_doubled_after_construction() -> None:
    """The authors' ``env.length *= 2.0`` on a built env (polemass_length stays cached at 0.05)."""
    rng = np.random.default_rng(6)
    states, forces = random_states(rng, 200), rng.uniform(-10, 10, 200)
    env = CartPoleEnv()
    env.reset(seed=0)
    env.length *= 2.0
    assert env.polemass_length == 0.05
    theirs = np.array([gym_step(env, s, f)[0] for s, f in zip(states, forces)])
    task = CartPole.thesis_doubled(polemass_length=0.05)
    np.testing.assert_allclose(task.step(states, forces), theirs, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gymnasium_step(states, forces, 2.0, polemass_length=0.05), theirs, rtol=0, atol=0)
    assert np.abs(theirs - step_dynamics(states, forces, 2.0)).max() > 1e-3
    # The gymnasium env of a task with the setting steps the same way.
    single = ContinuousCartPoleEnv(pole_length=2.0, polemass_length=0.05)
    single.reset(options={"state": states[0]})
    np.testing.assert_array_equal(single.step(np.array([forces[0]]))[0], task.step(states[0], forces[0]))


def test_authors_settings_names_and_constants() -> None:
    authors = CartPole.thesis_doubled(angle_threshold_deg=12.0, gamma=1.0, constants_gamma=0.9, polemass_length=0.05)
    name = authors.setting_name()
    assert name == "cartpole-doubled[gamma=1,angle_threshold_deg=12,polemass_length=0.05,constants_gamma=0.9]"
    assert CartPole.from_name(name) == authors
    # Unset, the new fields stay out of the names (and so out of the runs' keys).
    assert CartPole().setting_name() == "cartpole" and CartPole.thesis_doubled().setting_name() == "cartpole-doubled"
    assert CartPole(gamma=0.9).setting_name() == "cartpole[gamma=0.9]"
    # The constants are written in constants_gamma; the simulation keeps gamma = 1 (undiscounted).
    k = TaskConstants.from_task(authors, 1.0)
    assert (k.gamma, k.R, k.M_phi, k.action_volume) == (0.9, 1.0, 10.0, 20.0)
    assert authors.simulate_gain(np.zeros(4), 1.0, 5, 0).gamma == 1.0
    assert TaskConstants.from_task(CartPole(), 1.0).gamma == 0.99
    with pytest.raises(ValueError, match="^gamma "):  # gamma = 1 in the printed constant: 1 / (1 - gamma)
        TaskConstants.from_task(CartPole(gamma=1.0), 1.0)
    for field, value in (("constants_gamma", 0.0), ("constants_gamma", 1.5), ("polemass_length", -0.05),
                         ("polemass_length", float("inf"))):
        with pytest.raises(ValueError, match=rf"^{field} "):
            CartPole(**{field: value})
