"""The fused numba kernel against the reference numpy path."""

import itertools

import numba
import numpy as np
import pytest

from safepg.envs._lqg_kernel import CHUNK, lqg1d_gradient_samples, lqg2d_gradient_samples, lqg_gradient_samples
from safepg.envs.lqg import LQG
from safepg.estimators import gradient_samples
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key

# Every entry of every 2-D matrix differs, so a swapped index in the unrolled m = 2
# kernel cannot go unnoticed; Q and R are not symmetric on purpose (the kernels must use
# them as given, like the reference path).
MATS_2D = dict(A=np.array([[1.0, 0.1], [-0.05, 0.9]]), B=np.array([[1.0, 0.0], [0.2, 0.8]]),
               Q=np.array([[1.0, 0.3], [0.2, 2.0]]), R=np.array([[0.5, 0.1], [0.05, 0.7]]))
GAIN_2D = [[-0.3, 0.1], [0.05, -0.2]]
COV_2D = np.array([[1.0, 0.2], [0.2, 0.5]])

CASES = {
    "1d": (LQG.thesis_1d(), [[-0.3]], 1.0),
    "1d-unclipped": (LQG.thesis_1d(clip=False), [[-0.5]], 0.5),
    "2d": (LQG.thesis_2d(**MATS_2D), GAIN_2D, COV_2D),
    "2d-unclipped": (LQG.thesis_2d(clip=False, **MATS_2D), [[-0.6, 0.1], [0.05, -0.5]], 0.3 * COV_2D),
    "3d": (LQG(dim=3, Q=np.diag([1.0, 2.0, 0.5])), -0.3 * np.eye(3) + 0.05, np.diag([1.0, 0.5, 0.8])),
}
FLAGS = list(itertools.product([True, False], repeat=4))  # clip, score_clipped, reinforce, baseline


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("estimator,baseline,score_action",
                         list(itertools.product(["reinforce", "gpomdp"], [True, False], ["clipped", "raw"])))
def test_fused_matches_reference(case, estimator, baseline, score_action):
    env, K, sig = CASES[case]
    pol = LinearGaussianPolicy(K, sig)
    samples, returns = env.gradient_batch(pol, 3000, 5, estimator, baseline, score_action)
    batch = env.simulate(pol, 3000, 5)
    ref = gradient_samples(pol, batch, estimator, baseline, score_action)
    np.testing.assert_allclose(samples, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())
    np.testing.assert_allclose(returns, batch.discounted_returns(), rtol=1e-12)


@pytest.mark.parametrize("case,estimator", [("1d", "gpomdp"), ("2d", "gpomdp"), ("2d", "reinforce")])
def test_fused_result_does_not_depend_on_thread_count(case, estimator):
    env, K, sig = CASES[case]
    pol = LinearGaussianPolicy(K, sig)
    n = 4 * CHUNK + 77  # five chunks, the last one partial
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = env.gradient_batch(pol, n, 2, estimator)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        many = env.gradient_batch(pol, n, 2, estimator)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(one[0], many[0]) and np.array_equal(one[1], many[1])


def _kernel_inputs(env, pol, n, seed):
    key = batch_key(np.random.default_rng(seed))  # what gradient_batch draws from this seed
    A, B, Q, R = env._mats
    return (pol.gain, pol.cov_chol, pol.precision, A, B, Q, R, key, n, env.horizon,
            env.gamma, env.state_bound, env.action_bound)


@pytest.mark.parametrize("clip,score_clipped,reinforce,baseline", FLAGS)
def test_2d_kernel_matches_generic_kernel(clip, score_clipped, reinforce, baseline):
    """The unrolled m = 2 kernel against the generic m x m loops on identical inputs, bit for bit:
    the same terms in the same order, however the unrolled kernel's loops are vectorised (the
    generic kernel's baseline pass is a plain loop over t for each sample)."""
    env, K, sig = CASES["2d"]
    pol = LinearGaussianPolicy(K if clip else CASES["2d-unclipped"][1], sig)
    # Two chunks, the second partial, so the chunked baseline reduction is exercised.
    args = _kernel_inputs(env, pol, CHUNK + 301, 11) + (clip, score_clipped, reinforce, baseline)
    fast, generic = lqg2d_gradient_samples(*args), lqg_gradient_samples(*args)
    assert fast[0].shape == generic[0].shape == (CHUNK + 301, 4)
    for got, want in zip(fast, generic):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("case", ["1d", "1d-unclipped"])
@pytest.mark.parametrize("clip,score_clipped,reinforce,baseline", FLAGS)
def test_1d_kernel_matches_generic_kernel(case, clip, score_clipped, reinforce, baseline):
    """The scalar kernel against the generic loops at m = 1, bit for bit, over two chunks."""
    env, K, sig = CASES[case]
    args = _kernel_inputs(env, LinearGaussianPolicy(K, sig), CHUNK + 301, 12)
    gain, cov_chol, _, A, B, Q, R = (np.asarray(x) for x in args[:7])
    scalars = (gain[0, 0], cov_chol[0, 0], A[0, 0], B[0, 0], Q[0, 0], R[0, 0])
    flags = (clip, score_clipped, reinforce, baseline)
    fast = lqg1d_gradient_samples(*(float(x) for x in scalars), *args[7:], *flags)
    generic = lqg_gradient_samples(*args, *flags)
    assert fast[0].shape == generic[0].shape == (CHUNK + 301, 1)
    for got, want in zip(fast, generic):
        np.testing.assert_array_equal(got, want)


def test_gradient_batch_dispatch():
    """dim 2 goes to the m = 2 kernel and dim 3 to the generic one, same random numbers."""
    for case, kernel in (("2d", lqg2d_gradient_samples), ("3d", lqg_gradient_samples)):
        env, K, sig = CASES[case]
        pol = LinearGaussianPolicy(K, sig)
        got = env.gradient_batch(pol, 500, 4, "gpomdp", True, "clipped")
        want = kernel(*_kernel_inputs(env, pol, 500, 4), env.clip, True, False, True)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def test_fused_bad_input():
    env = LQG.thesis_1d()
    pol = LinearGaussianPolicy([[-0.3]], 1.0)
    with pytest.raises(ValueError, match="^estimator"):
        env.gradient_batch(pol, 10, 0, "a2c")
    with pytest.raises(ValueError, match="^n "):
        env.gradient_batch(pol, 0, 0)
