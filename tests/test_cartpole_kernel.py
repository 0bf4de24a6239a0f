"""The fused cart-pole kernel (CartPole.gradient_batch) against the numpy reference path:
same samples and returns, seeding, thread-count independence and input checks."""

from __future__ import annotations

import itertools

import numba
import numpy as np
import pytest

from safepg.envs._cartpole_kernel import CHUNK, cartpole_gradient_samples
from safepg.envs.cartpole import CartPole
from safepg.estimators import gradient_samples
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key

# Balances the 1 m pole for the whole horizon (the gain of tests/test_cartpole.py).
STABLE = np.array([1.0, 2.0, 40.0, 8.0])
# (task, gain, sigma), chosen so that together they exercise every path of the kernel
# (checked in test_cases_cover_the_kernel_paths).
CASES = {
    # The thesis's starting point: every episode falls within a few dozen steps.
    "theta0": (CartPole.thesis(), np.zeros(4), 1.0),
    # Every episode lasts 200 steps (no early stop); no clipping.
    "stable": (CartPole.thesis(), STABLE, 1.0),
    # A weaker stabilising gain with more noise: most episodes last 200 steps, the others
    # fall at many different steps, and about 6% of the forces are clipped.
    "mixed": (CartPole.thesis(), np.array([-1.0, 0.0, 30.0, 5.0]), 5.0),
    # The doubled pole under heavy noise: a quarter of the forces clipped, a few falls.
    "doubled": (CartPole.thesis_doubled(), STABLE, 8.0),
    # Angles allowed beyond 0.78 rad, where sine and cosine need their argument reduction:
    # the kernel's other (unvectorised) sine path.
    "wide": (CartPole.thesis(angle_threshold_deg=60.0), np.zeros(4), 1.0),
}
N = 2000  # several chunks, the last one partial


def reference(task: CartPole, pol: LinearGaussianPolicy, n: int, seed: int, estimator: str, baseline: bool,
              score_action: str) -> tuple[np.ndarray, np.ndarray]:
    batch = task.simulate(pol, n, seed)
    return gradient_samples(pol, batch, estimator, baseline, score_action), task.undiscounted_returns(batch)


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_fused_matches_reference(case: str, estimator: str) -> None:
    task, K, sig = CASES[case]
    pol = LinearGaussianPolicy(K, sig)
    batch = task.simulate(pol, N, 5)
    lengths = task.undiscounted_returns(batch)
    for baseline, score_action in itertools.product([True, False], ["clipped", "raw"]):
        samples, returns = task.gradient_batch(pol, N, 5, estimator, baseline, score_action)
        ref = gradient_samples(pol, batch, estimator, baseline, score_action)
        assert samples.shape == (N, 4) and returns.shape == (N,)
        np.testing.assert_allclose(samples, ref, rtol=1e-9, atol=1e-9, err_msg=f"{baseline=} {score_action=}")
        np.testing.assert_array_equal(returns, lengths)


def test_cases_cover_the_kernel_paths() -> None:
    """Guards the test above against cases that silently stop exercising something."""
    lengths = {c: CASES[c][0].gradient_batch(LinearGaussianPolicy(CASES[c][1], CASES[c][2]), N, 5)[1]
               for c in CASES}
    assert lengths["theta0"].max() < CASES["theta0"][0].horizon
    assert np.all(lengths["stable"] == 200)
    for c in ("mixed", "doubled"):
        assert np.any(lengths[c] == 200) and np.any(lengths[c] < 200)
    assert len(np.unique(lengths["mixed"])) > 20  # trajectories end at many different steps
    wide, K, sig = CASES["wide"]
    _, _, peaks = cartpole_gradient_samples(
        K, sig, wide.pole_length, wide.cart_mass, wide.pole_mass, wide.gravity, wide.tau,
        batch_key(np.random.default_rng(5)), N, wide.horizon, wide.init_bound, wide.gamma, wide.action_bound,
        wide.x_threshold, wide.angle_threshold, True, False, True, peaks=True)
    # The poles fall over past 0.9 rad, a few hundredths of a radian a step: on the way they
    # lived at angles past 0.78 rad, whose sines and cosines take the reduction.
    assert np.mean(peaks[:, 2] > 0.9) > 0.5
    for c in ("mixed", "doubled"):  # clipping is active, so the two score actions differ
        task, K, sig = CASES[c]
        pol = LinearGaussianPolicy(K, sig)
        clipped = task.gradient_batch(pol, N, 5, score_action="clipped")[0]
        raw = task.gradient_batch(pol, N, 5, score_action="raw")[0]
        assert np.max(np.abs(clipped - raw)) > 1e-3


@pytest.mark.parametrize("n", [1, 7, CHUNK, CHUNK + 1])
def test_fused_matches_reference_at_chunk_edges(n: int) -> None:
    task, K, sig = CASES["mixed"]
    pol = LinearGaussianPolicy(K, sig)
    for estimator in ("reinforce", "gpomdp"):
        samples, returns = task.gradient_batch(pol, n, 11, estimator)
        ref, lengths = reference(task, pol, n, 11, estimator, True, "clipped")
        np.testing.assert_allclose(samples, ref, rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(returns, lengths)


def test_same_seed_same_bits_and_generator_advances_like_simulate() -> None:
    task, K, sig = CASES["mixed"]
    pol = LinearGaussianPolicy(K, sig)
    a = task.gradient_batch(pol, 500, 3)
    b = task.gradient_batch(pol, 500, np.random.default_rng(3))
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], task.gradient_batch(pol, 500, 4)[0])
    # The generator is left where simulate leaves it, so the two paths can be interleaved.
    r1, r2 = np.random.default_rng(9), np.random.default_rng(9)
    task.gradient_batch(pol, 300, r1)
    task.simulate(pol, 300, r2)
    assert r1.random() == r2.random()


@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_fused_result_does_not_depend_on_thread_count(estimator: str) -> None:
    task, K, sig = CASES["mixed"]
    pol = LinearGaussianPolicy(K, sig)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = task.gradient_batch(pol, 5 * CHUNK + 3, 2, estimator)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = task.gradient_batch(pol, 5 * CHUNK + 3, 2, estimator)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(one[0], two[0]) and np.array_equal(one[1], two[1])


def test_returns_are_episode_lengths_and_measured_returns() -> None:
    task, K, sig = CASES["mixed"]
    pol = LinearGaussianPolicy(K, sig)
    returns = task.gradient_batch(pol, 1000, 8)[1]
    batch = task.simulate(pol, 1000, 8)
    np.testing.assert_array_equal(returns, batch.mask.sum(axis=1))  # reward 1 per live step
    np.testing.assert_array_equal(task.measured_returns(batch), task.undiscounted_returns(batch))
    np.testing.assert_array_equal(task.measured_returns(batch), returns)
    assert returns.min() >= 1 and returns.max() <= task.horizon


def test_kernel_draws_the_batch_of_its_key() -> None:
    """Called directly with the key gradient_batch draws from a seed, the kernel gives its batch;
    a bad batch size or horizon is named."""
    task, K, sig = CASES["mixed"]
    pol = LinearGaussianPolicy(K, sig)
    args = (sig, task.pole_length, task.cart_mass, task.pole_mass, task.gravity, task.tau)
    tail = (task.gamma, task.action_bound, task.x_threshold, task.angle_threshold, True, False, True)
    key = batch_key(np.random.default_rng(3))
    got = cartpole_gradient_samples(K, *args, key, 40, task.horizon, task.init_bound, *tail)
    want = task.gradient_batch(pol, 40, 3)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    other = cartpole_gradient_samples(K, *args, key + np.uint64(1), 40, task.horizon, task.init_bound, *tail)
    assert not np.array_equal(other[0], got[0])
    with pytest.raises(ValueError, match="^n "):
        cartpole_gradient_samples(K, *args, key, 0, task.horizon, task.init_bound, *tail)
    with pytest.raises(ValueError, match="^horizon "):
        cartpole_gradient_samples(K, *args, key, 40, 2.5, task.init_bound, *tail)


def test_fused_bad_input() -> None:
    task = CartPole.thesis()
    pol = LinearGaussianPolicy(np.zeros(4), 1.0)
    with pytest.raises(ValueError, match="^estimator"):
        task.gradient_batch(pol, 10, 0, "a2c")
    with pytest.raises(ValueError, match="^score_action"):
        task.gradient_batch(pol, 10, 0, score_action="mean")
    for n in (0, -3, 2.5, True, float("nan"), "10"):
        with pytest.raises(ValueError, match="^n "):
            task.gradient_batch(pol, n, 0)
    with pytest.raises(ValueError, match="^policy"):
        task.gradient_batch(LinearGaussianPolicy(np.zeros(3), 1.0), 10, 0)
    with pytest.raises(ValueError, match="^policy"):
        task.gradient_batch(np.zeros(4), 10, 0)



def test_sweep_settings_at_their_defaults_change_no_bit() -> None:
    """The sweep's settings spelled out at their default values give the default task's exact bits
    (the Euler branch of the kernel is the one the default takes)."""
    explicit = CartPole(integrator="euler", feature_scale=None, reward_bound=1.0, action_space_volume=None,
                        horizon_term="effective")
    assert explicit == CartPole()
    for task, K, sig in CASES.values():
        pol = LinearGaussianPolicy(K, sig)
        name = task.setting_name()
        spelled = CartPole.from_name(name[:-1] + ",integrator=euler]" if name.endswith("]") else name
                                     + "[integrator=euler]")
        for est in ("gpomdp", "reinforce"):
            a, b = task.gradient_batch(pol, 700, 7, est), spelled.gradient_batch(pol, 700, 7, est)
            assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    # The unit scale is the identity, bit for bit (x / 1 = x).
    task, K, sig = CASES["mixed"]
    unit = CartPole(feature_scale=(1.0, 1.0, 1.0, 1.0))
    pol = LinearGaussianPolicy(K, sig)
    a, b = task.gradient_batch(pol, 700, 3), unit.gradient_batch(pol, 700, 3)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert np.array_equal(task.simulate(pol, 50, 1).features, unit.simulate(pol, 50, 1).features)

def test_semi_implicit_kernel_flag() -> None:
    """The kernel's semi_implicit flag integrates like step_dynamics(..., integrator="semi-implicit")."""
    task = CartPole(integrator="semi-implicit")
    pol = LinearGaussianPolicy(np.array([-1.0, 0.0, 30.0, 5.0]), 5.0)
    for estimator in ("gpomdp", "reinforce"):
        samples, returns = task.gradient_batch(pol, 700, 12, estimator)
        ref, lengths = reference(task, pol, 700, 12, estimator, True, "clipped")
        np.testing.assert_allclose(samples, ref, rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(returns, lengths)


# ------------------------------------------------------------------ the authors' settings
AUTHORS = CartPole.thesis_doubled(angle_threshold_deg=12.0, gamma=1.0, constants_gamma=0.9, polemass_length=0.05)


@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_authors_task_fused_matches_reference(estimator: str) -> None:
    """The stale m l and the undiscounted estimator (gamma = 1) in the kernel, against the numpy path."""
    pol = LinearGaussianPolicy(np.array([-0.9, 2.1, 3.49, 7.25]), 1.0)  # the authors' baseline policy, rounded
    samples, returns = AUTHORS.gradient_batch(pol, 1500, 9, estimator)
    ref, lengths = reference(AUTHORS, pol, 1500, 9, estimator, True, "clipped")
    np.testing.assert_allclose(samples, ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(returns, lengths)
    assert 150 < returns.mean() < 200 and returns.min() < AUTHORS.horizon  # some episodes fall at 12 deg
    consistent = CartPole.thesis_doubled(angle_threshold_deg=12.0, gamma=1.0)
    assert not np.array_equal(consistent.gradient_batch(pol, 1500, 9, estimator)[1], returns)


def _reference_peak(task: CartPole, pol: LinearGaussianPolicy, n: int, seed: int) -> float:
    """max |phi_i(s)| over every state of the simulated batch: the live ones and the one each episode
    ended in (one more step from its last live state with its last force)."""
    batch = task.simulate(pol, n, seed)
    scale = 1.0 if task.feature_scale is None else np.asarray(task.feature_scale)
    last = batch.mask.sum(axis=1) - 1
    rows = np.arange(n)
    final = task.step(batch.features[rows, last] * scale, batch.actions[rows, last, 0]) / scale
    return float(max(np.abs(batch.features[batch.mask]).max(), np.abs(final).max()))


@pytest.mark.parametrize("case", ["theta0", "stable", "doubled"])
def test_batch_maxima_are_the_largest_reward_and_feature(case: str) -> None:
    task, K, sig = CASES[case]
    pol = LinearGaussianPolicy(K, sig)
    samples, returns, (R, M_phi) = task.gradient_batch_constants(pol, N, 5)
    plain = task.gradient_batch(pol, N, 5)
    assert np.array_equal(samples, plain[0]) and np.array_equal(returns, plain[1])  # the same batch
    assert R == 1.0
    assert M_phi == pytest.approx(_reference_peak(task, pol, N, 5), rel=1e-12)
    # Normalised features: the largest normalised component.
    from safepg.envs.cartpole import NORMALISED_SCALE

    scaled = CartPole(feature_scale=NORMALISED_SCALE, feature_bound=1.0)
    pol_scaled = LinearGaussianPolicy(K * np.asarray(NORMALISED_SCALE), sig)  # the same policy in those units
    assert scaled.gradient_batch_constants(pol_scaled, 300, 5)[2][1] == pytest.approx(
        _reference_peak(scaled, pol_scaled, 300, 5), rel=1e-12)
