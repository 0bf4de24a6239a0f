"""The fused numba kernel against the reference numpy path."""

import itertools

import numba
import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.estimators import gradient_samples
from safepg.policies import LinearGaussianPolicy

CASES = {
    "1d": (LQG.thesis_1d(), [[-0.3]], 1.0),
    "1d-unclipped": (LQG.thesis_1d(clip=False), [[-0.5]], 0.5),
    "2d": (LQG.thesis_2d(Q=np.array([[1.0, 0.3], [0.3, 2.0]])), [[-0.3, 0.1], [0.05, -0.2]],
           np.array([[1.0, 0.2], [0.2, 0.5]])),
}


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


@pytest.mark.parametrize("case", ["1d", "2d"])
def test_fused_result_does_not_depend_on_thread_count(case):
    env, K, sig = CASES[case]
    pol = LinearGaussianPolicy(K, sig)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = env.gradient_batch(pol, 10_000, 2)
        numba.set_num_threads(before)
        many = env.gradient_batch(pol, 10_000, 2)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(one[0], many[0]) and np.array_equal(one[1], many[1])


def test_fused_bad_input():
    env = LQG.thesis_1d()
    pol = LinearGaussianPolicy([[-0.3]], 1.0)
    with pytest.raises(ValueError, match="^estimator"):
        env.gradient_batch(pol, 10, 0, "a2c")
    with pytest.raises(ValueError, match="^n "):
        env.gradient_batch(pol, 0, 0)
