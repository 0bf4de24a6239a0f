"""The fused pendulum kernel (Pendulum.gradient_batch) against the NumPy reference path
(Pendulum.simulate and safepg.estimators): the same samples and returns, seeding, thread-count
independence, the measured constants and the learning loops' use of it."""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np
import pytest

from safepg import portable
from safepg.envs._pendulum_kernel import CHUNK
from safepg.envs.pendulum import Pendulum
from safepg.estimators import gradient_samples
from safepg.learning import adaptive_pg, vanilla_pg
from safepg.options import Departures, ErrorModel, FixedStep, Gradient
from safepg.policies import LinearGaussianPolicy

# (gain, sigma): the start; a stabilising gain near upright; a pumping gain with heavy clipping.
CASES = {"zero": (np.zeros(3), 1.0), "stabilise": (np.array([-1.0, -6.0, -1.5]), 0.5),
         "pump": (np.array([0.0, 0.0, 3.0]), 3.0)}
N = 1100  # three chunks, the last one partial


def reference(task: Pendulum, pol: LinearGaussianPolicy, n: int, seed: int, estimator: str, baseline: bool,
              score_action: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    batch = task.simulate(pol, n, seed)
    return (gradient_samples(pol, batch, estimator, baseline, score_action), batch.discounted_returns(),
            batch.rewards.sum(axis=1))


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_fused_matches_reference(case: str, estimator: str) -> None:
    task = Pendulum()
    K, sig = CASES[case]
    pol = LinearGaussianPolicy(K[None, :], sig)
    batch = task.simulate(pol, N, 5)
    for baseline, score_action in itertools.product([True, False], ["clipped", "raw"]):
        samples, returns = task.gradient_batch(pol, N, 5, estimator, baseline, score_action)
        ref = gradient_samples(pol, batch, estimator, baseline, score_action)
        assert samples.shape == (N, 3) and returns.shape == (N,)
        scale = np.max(np.abs(ref))
        np.testing.assert_allclose(samples, ref, rtol=0, atol=1e-12 * scale, err_msg=f"{baseline=} {score_action=}")
        np.testing.assert_allclose(returns, batch.rewards.sum(axis=1), rtol=1e-12)
    discounted, undiscounted = task.episode_returns(pol, N, 5)
    np.testing.assert_allclose(discounted, batch.discounted_returns(), rtol=1e-12)
    np.testing.assert_allclose(undiscounted, batch.rewards.sum(axis=1), rtol=1e-12)


def test_cases_cover_the_kernel_paths() -> None:
    """Guards the test above: clipping is active where it should be, and the angles wind past pi
    (the sine's reduction) and the reward's normalisation wraps."""
    task = Pendulum()
    for case, clipped in (("zero", 0.02), ("pump", 0.4)):
        K, sig = CASES[case]
        batch = task.simulate(LinearGaussianPolicy(K[None, :], sig), N, 5)
        assert np.mean(np.abs(batch.actions_raw) > 2.0) > clipped
        assert np.max(np.abs(np.arctan2(batch.features[..., 1], batch.features[..., 0]))) > 3.1
    pump = task.simulate(LinearGaussianPolicy(CASES["pump"][0][None, :], 3.0), 50, 5)
    assert np.max(np.abs(pump.features[..., 2])) == 8.0  # the speed limit binds


@pytest.mark.parametrize("n", [1, 7, CHUNK, CHUNK + 1])
def test_fused_matches_reference_at_chunk_edges(n: int) -> None:
    task = Pendulum()
    pol = LinearGaussianPolicy(CASES["stabilise"][0][None, :], 0.5)
    for estimator in ("reinforce", "gpomdp"):
        samples, returns = task.gradient_batch(pol, n, 11, estimator)
        ref, _, total = reference(task, pol, n, 11, estimator, True, "clipped")
        # The scale of the terms: with one trajectory the baseline cancels its sample to rounding.
        scale = np.max(np.abs(reference(task, pol, n, 11, estimator, False, "clipped")[0]))
        np.testing.assert_allclose(samples, ref, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(returns, total, rtol=1e-12)


def test_measure_chooses_the_recorded_return() -> None:
    pol = LinearGaussianPolicy(CASES["zero"][0][None, :], 1.0)
    batch = Pendulum().simulate(pol, 200, 3)
    undiscounted = Pendulum().gradient_batch(pol, 200, 3)[1]
    discounted = Pendulum(measure="discounted").gradient_batch(pol, 200, 3)[1]
    np.testing.assert_allclose(undiscounted, Pendulum().measured_returns(batch), rtol=1e-12)
    np.testing.assert_allclose(discounted, Pendulum(measure="discounted").measured_returns(batch), rtol=1e-12)
    assert np.all(discounted > undiscounted)  # rewards are negative: discounting shrinks the sum


def test_batch_constants_are_the_simulated_batchs_maxima() -> None:
    task = Pendulum()
    pol = LinearGaussianPolicy(CASES["pump"][0][None, :], 3.0)
    batch = task.simulate(pol, 300, 9)
    samples, returns, (R, M) = task.gradient_batch_constants(pol, 300, 9)
    assert R == float(np.abs(batch.rewards).max()) and M == float(np.abs(batch.features).max())
    assert np.array_equal(samples, task.gradient_batch(pol, 300, 9)[0])


def test_same_seed_same_bits_and_generator_advances_like_simulate() -> None:
    task = Pendulum()
    pol = LinearGaussianPolicy(CASES["stabilise"][0][None, :], 0.5)
    a = task.gradient_batch(pol, 600, 3)
    b = task.gradient_batch(pol, 600, np.random.default_rng(3))
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], task.gradient_batch(pol, 600, 4)[0])
    r1, r2 = np.random.default_rng(9), np.random.default_rng(9)
    task.gradient_batch(pol, 300, r1)
    task.simulate(pol, 300, r2)
    assert r1.random() == r2.random()


@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_fused_result_does_not_depend_on_thread_count(estimator: str) -> None:
    task = Pendulum()
    pol = LinearGaussianPolicy(CASES["pump"][0][None, :], 3.0)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = task.gradient_batch_constants(pol, 3 * CHUNK + 3, 2, estimator)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = task.gradient_batch_constants(pol, 3 * CHUNK + 3, 2, estimator)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(one[0], two[0]) and np.array_equal(one[1], two[1]) and one[2] == two[2]


def test_the_kernels_remainder_is_pythons() -> None:
    """The reward's normalised angle: numba's float % in the kernel is Python's (and NumPy's)."""
    from numba import njit

    @njit
    def normalise(x: np.ndarray) -> np.ndarray:
        out = np.empty_like(x)
        for i in range(x.size):
            out[i] = (x[i] + math.pi) % (2 * math.pi) - math.pi
        return out

    x = np.random.default_rng(6).uniform(-90, 90, 20_000)
    x[:4] = [math.pi, -math.pi, 0.0, -3 * math.pi]
    assert normalise(x).tolist() == [(v + math.pi) % (2 * math.pi) - math.pi for v in x.tolist()]


def test_sincos_is_portables_sine_and_cosine() -> None:
    x = np.random.default_rng(7).uniform(-100, 100, 20_000)
    x[:5] = [0.0, -0.0, 0.7799999999999999, math.pi, -math.pi / 2]
    got = [portable.sincos(v) for v in x.tolist()]
    assert [g[0] for g in got] == portable.sin_array(x).tolist()
    assert [g[1] for g in got] == portable.cos_array(x).tolist()


def test_learning_loops_take_the_fused_paths() -> None:
    """Algorithm 4.1 with the authors' per-batch constants, and vanilla PG, run on the kernel (the
    reference path would take seconds for these budgets); a seed fixes the record."""
    task = Pendulum()
    departures = Departures(batch_constants=True, maxima=True, unguarded_step=True)
    runs = [adaptive_pg(task, np.zeros(3), 1.0, gradient=Gradient(score_action="raw"),
                        error=ErrorModel("bernstein", range="empirical"), departures=departures, budget=3000, rng=0)
            for _ in range(2)]
    assert np.array_equal(runs[0].theta, runs[1].theta) and runs[0].iterations > 1
    assert np.any(runs[0].theta[-1] != 0)  # the authors' departures move theta
    assert np.all(runs[0].J_hat < 0) and np.all(np.isnan(runs[0].J))
    van = vanilla_pg(task, np.zeros(3), 1.0, batch_size=100, step=FixedStep(1e-4), budget=1000, rng=1)
    assert van.iterations == 10 and np.any(van.theta[-1] != 0)
