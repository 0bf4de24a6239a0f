"""Gradient estimators: unbiasedness and the clipped score's bias against quadrature (tests/lqg1d_dp.py),
variance, baselines."""

import lqg1d_dp
import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.estimators import gpomdp, gradient_samples, reinforce, trajectory_scores
from safepg.policies import LinearGaussianPolicy

ENV = LQG.thesis_1d()
N = 300_000
THETA = -0.3


@pytest.fixture(scope="module")
def batch():
    """A batch at theta = -0.3."""
    pol = LinearGaussianPolicy([[THETA]], 1.0)
    return pol, ENV.simulate(pol, N, 11)


@pytest.fixture(scope="module")
def derived():
    """What the estimators' means should be at theta = -0.3, by quadrature (tests/lqg1d_dp.py): the gradient
    of the clipped 20-step objective, -3.8688, and the mean of G(PO)MDP with the clipped action's score and
    the baseline, -3.6636."""
    return {"gradient": lqg1d_dp.gradient(THETA),
            "clipped": lqg1d_dp.gpomdp_mean(THETA, score="clipped", baseline=True)["mean"]}


def test_the_quadrature_is_converged_and_its_two_derivations_agree():
    # The likelihood-ratio gradient (forward recursion, raw score, no baseline) against the central
    # difference of the backward induction: two computations that share only the quadrature grids.
    forward = lqg1d_dp.gpomdp_mean(THETA, score="raw", baseline=False)
    assert forward["mean"] == pytest.approx(lqg1d_dp.gradient(THETA), rel=1e-7)
    assert forward["J"] == pytest.approx(lqg1d_dp.performance(THETA), rel=1e-12)
    # Half the grids' resolution moves J by 8e-6 relative and the gradient by 1e-6: far below the Monte
    # Carlo errors the tests hold the simulator to (about 3e-3 relative).
    assert lqg1d_dp.performance(THETA, m=401, q=401) == pytest.approx(lqg1d_dp.performance(THETA), rel=2e-5)
    assert lqg1d_dp.gradient(THETA, m=401, q=401) == pytest.approx(lqg1d_dp.gradient(THETA), rel=5e-6)


@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
@pytest.mark.parametrize("baseline", [True, False])
def test_raw_score_estimators_are_unbiased(batch, derived, estimator, baseline):
    pol, b = batch
    s = gradient_samples(pol, b, estimator, baseline, score_action="raw")[:, 0]
    se = s.std(ddof=1) / np.sqrt(N)
    assert abs(s.mean() - derived["gradient"]) < 4 * se, (s.mean(), derived["gradient"], se)


def test_clipped_score_is_biased(batch, derived):
    # The authors' clipped-action score: by quadrature, G(PO)MDP with the baseline has mean -3.6636 where the
    # gradient is -3.8688, a bias of +5.30% of |grad J| (its estimate of the baseline from the batch moves
    # the mean by O(1/N)).
    pol, b = batch
    g, clipped = derived["gradient"], derived["clipped"]
    assert (clipped - g) / abs(g) == pytest.approx(0.0530, abs=5e-4)
    s = gradient_samples(pol, b, "gpomdp", True, score_action="clipped")[:, 0]
    se = s.std(ddof=1) / np.sqrt(N)
    assert abs(s.mean() - clipped) < 4 * se, (s.mean(), clipped, se)
    assert s.mean() - g > 8 * se  # and the simulator's batch shows the bias, far outside its error


def test_gpomdp_has_lower_variance_than_reinforce(batch):
    pol, b = batch
    for baseline in (True, False):
        v_rf = gradient_samples(pol, b, "reinforce", baseline).var()
        v_gp = gradient_samples(pol, b, "gpomdp", baseline).var()
        assert v_gp < 0.5 * v_rf


@pytest.mark.parametrize("estimator", ["reinforce", "gpomdp"])
def test_baseline_reduces_variance(batch, estimator):
    pol, b = batch
    assert gradient_samples(pol, b, estimator, True).var() < gradient_samples(pol, b, estimator, False).var()


def _loop_reference(scores, rewards, gamma, estimator):
    """Direct transcription of Sections 2.3.9-2.3.10 with explicit loops."""
    N, H, m = scores.shape
    out = np.zeros((N, m))
    for i in range(m):
        if estimator == "reinforce":
            tot = [sum(scores[n, k, i] for k in range(H)) for n in range(N)]
            ret = [sum(gamma**l * rewards[n, l] for l in range(H)) for n in range(N)]
            b = sum(t * t * r for t, r in zip(tot, ret)) / sum(t * t for t in tot)
            for n in range(N):
                out[n, i] = tot[n] * (ret[n] - b)
        else:
            for l in range(H):
                cum = [sum(scores[n, k, i] for k in range(l + 1)) for n in range(N)]
                dr = [gamma**l * rewards[n, l] for n in range(N)]
                b = sum(c * c * r for c, r in zip(cum, dr)) / sum(c * c for c in cum)
                for n in range(N):
                    out[n, i] += cum[n] * (dr[n] - b)
    return out


@pytest.mark.parametrize("estimator,fn", [("reinforce", reinforce), ("gpomdp", gpomdp)])
def test_estimators_match_loop_transcription(estimator, fn):
    rng = np.random.default_rng(0)
    scores, rewards = rng.normal(size=(7, 5, 3)), rng.normal(size=(7, 5))
    np.testing.assert_allclose(fn(scores, rewards, 0.9), _loop_reference(scores, rewards, 0.9, estimator),
                               rtol=1e-12, atol=1e-12)


def test_multidimensional_gpomdp_matches_closed_form_gradient():
    # Without clipping and with a long horizon (0.95^200 ~ 4e-5 of the tail dropped), the
    # G(PO)MDP mean estimates the closed-form infinite-horizon gradient, all 4 components.
    env = LQG.thesis_2d(clip=False, horizon=200)
    K = np.array([[-0.3, 0.1], [0.0, -0.2]])
    pol = LinearGaussianPolicy(K, 1.0)
    n = 60_000
    s = gradient_samples(pol, env.simulate(pol, n, 4), "gpomdp", score_action="raw")
    assert s.shape == (n, 4)
    se = s.std(axis=0, ddof=1) / np.sqrt(n)
    assert np.all(np.abs(s.mean(axis=0) - env.gradient(K, 1.0)) < 4 * se)


def test_masked_steps_have_zero_score():
    pol = LinearGaussianPolicy([[-0.3]], 1.0)
    b = ENV.simulate(pol, 10, 0)
    mask = np.ones((10, ENV.horizon), bool)
    mask[:, 5:] = False
    from dataclasses import replace
    s = trajectory_scores(pol, replace(b, mask=mask))
    assert np.all(s[:, 5:] == 0) and np.all(s[:, :5] != 0)


def test_bad_inputs_raise():
    pol = LinearGaussianPolicy([[-0.3]], 1.0)
    b = ENV.simulate(pol, 10, 0)
    with pytest.raises(ValueError, match="^estimator"):
        gradient_samples(pol, b, "ppo")
    with pytest.raises(ValueError, match="^score_action"):
        gradient_samples(pol, b, "gpomdp", score_action="mean")
    with pytest.raises(ValueError, match="^scores"):
        gpomdp(np.zeros((3, 4, 1)), np.zeros((3, 5)), 0.9)
