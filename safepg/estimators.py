r"""Likelihood-ratio policy-gradient estimators (thesis Sections 2.3.9-2.3.10).

Both return the N per-trajectory gradient samples :math:`\tilde\nabla_\theta J` as an
(N, m) array; the batch estimate :math:`\hat\nabla_\theta J` is their mean. The
concentration bounds of Section 4.3 need the samples, not only the mean.

``scores`` is the (N, H, m) array of eligibility vectors
:math:`\nabla_\theta\log\pi_\theta(a_k\mid s_k)` and ``rewards`` the (N, H) rewards;
time index k = 1..H in the thesis is 0..H-1 here, so discounting starts at gamma^0.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from safepg import portable
from safepg.policies import LinearGaussianPolicy
from safepg.trajectories import Trajectories

Estimator = Literal["reinforce", "gpomdp"]
ScoreAction = Literal["clipped", "raw"]
ESTIMATORS: tuple[Estimator, ...] = ("reinforce", "gpomdp")
SCORE_ACTIONS: tuple[ScoreAction, ...] = ("clipped", "raw")


def check_estimator(estimator: str) -> None:
    """Raise ``ValueError("estimator ...")`` unless ``estimator`` is one of :data:`ESTIMATORS`."""
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be 'reinforce' or 'gpomdp', got {estimator!r}")


def check_score_action(score_action: str) -> None:
    """Raise ``ValueError("score_action ...")`` unless it is ``"clipped"`` or ``"raw"``."""
    if score_action not in SCORE_ACTIONS:
        raise ValueError(f"score_action must be 'clipped' or 'raw', got {score_action!r}")


def _safe_ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den with 0 where den == 0 (a component whose score is identically 0)."""
    out = np.zeros_like(num)
    np.divide(num, den, out=out, where=den != 0)
    return out


def reinforce_baseline(total_score: np.ndarray, returns: np.ndarray) -> np.ndarray:
    r"""Variance-minimising REINFORCE baseline, one per component (Section 2.3.9).

    .. math:: b = \frac{\langle(\sum_k \nabla\log\pi_k)^2 \sum_l\gamma^{l-1}r_l\rangle_N}
                       {\langle(\sum_k \nabla\log\pi_k)^2\rangle_N}
    """
    sq = total_score**2
    return _safe_ratio(np.sum(sq * returns[:, None], axis=0), sq.sum(axis=0))  # not BLAS (safepg.portable)


def reinforce(
    scores: np.ndarray, rewards: np.ndarray, gamma: float, baseline: bool = True
) -> np.ndarray:
    r"""REINFORCE gradient samples (Section 2.3.9), shape (N, m).

    .. math:: \tilde\nabla^{RF}_n = \Big(\sum_{k=1}^H \nabla_\theta\log\pi_\theta(a_k^n\mid s_k^n)\Big)
              \Big(\sum_{l=1}^H \gamma^{l-1} r_l^n - b\Big)
    """
    _check_shapes(scores, rewards)
    total_score = scores.sum(axis=1)  # (N, m)
    returns = np.sum(rewards * portable.powers(gamma, rewards.shape[1]), axis=1)  # (N,)
    b = reinforce_baseline(total_score, returns) if baseline else np.zeros(scores.shape[2])
    samples: np.ndarray = total_score * (returns[:, None] - b[None, :])
    return samples


def gpomdp_baseline(cum_score: np.ndarray, disc_rewards: np.ndarray) -> np.ndarray:
    r"""Variance-minimising G(PO)MDP baseline, one per time step and component (2.3.10).

    .. math:: b_l = \frac{\langle(\sum_{k\le l}\nabla\log\pi_k)^2\,\gamma^{l-1}r_l\rangle_N}
                         {\langle(\sum_{k\le l}\nabla\log\pi_k)^2\rangle_N}

    Returns an (H, m) array.
    """
    sq = cum_score**2  # (N, H, m)
    return _safe_ratio(np.einsum("nhm,nh->hm", sq, disc_rewards), sq.sum(axis=0))


def gpomdp(
    scores: np.ndarray, rewards: np.ndarray, gamma: float, baseline: bool = True
) -> np.ndarray:
    r"""G(PO)MDP gradient samples (Section 2.3.10), shape (N, m).

    .. math:: \tilde\nabla^{G(PO)MDP}_n = \sum_{l=1}^H
              \Big(\sum_{k=1}^{l}\nabla_\theta\log\pi_\theta(a_k^n\mid s_k^n)\Big)
              \big(\gamma^{l-1} r_l^n - b_l\big)
    """
    _check_shapes(scores, rewards)
    cum_score = np.cumsum(scores, axis=1)  # (N, H, m)
    disc_rewards = rewards * portable.powers(gamma, rewards.shape[1])  # (N, H)
    if baseline:
        b = gpomdp_baseline(cum_score, disc_rewards)
        samples: np.ndarray = np.einsum("nhm,nhm->nm", cum_score, disc_rewards[:, :, None] - b[None])
    else:
        samples = np.einsum("nhm,nh->nm", cum_score, disc_rewards)
    return samples


def _check_shapes(scores: np.ndarray, rewards: np.ndarray) -> None:
    if scores.ndim != 3 or rewards.ndim != 2 or scores.shape[:2] != rewards.shape:
        raise ValueError(
            f"scores must be (N, H, m) and rewards (N, H); got {scores.shape} and {rewards.shape}"
        )


def trajectory_scores(
    policy: LinearGaussianPolicy, batch: Trajectories, score_action: ScoreAction = "clipped"
) -> np.ndarray:
    """Eligibility vectors of a batch, (N, H, m), zero after termination.

    ``score_action="clipped"`` scores the applied (clipped) action, as the authors'
    code did (biased when clipping is active, see SETTINGS.md); ``"raw"`` scores the
    action actually sampled from the policy, which gives an unbiased estimator.
    """
    check_score_action(score_action)
    actions = batch.actions if score_action == "clipped" else batch.actions_raw
    scores = policy.score(batch.features, actions)
    if batch.mask is not None:
        scores = scores * batch.mask[:, :, None]
    return scores


def gradient_samples(
    policy: LinearGaussianPolicy,
    batch: Trajectories,
    estimator: Estimator = "gpomdp",
    baseline: bool = True,
    score_action: ScoreAction = "clipped",
) -> np.ndarray:
    """Per-trajectory gradient samples of ``estimator`` for a simulated batch, (N, m)."""
    scores = trajectory_scores(policy, batch, score_action)
    if estimator == "reinforce":
        return reinforce(scores, batch.rewards, batch.gamma, baseline)
    check_estimator(estimator)
    return gpomdp(scores, batch.rewards, batch.gamma, baseline)


__all__ = ["ESTIMATORS", "Estimator", "SCORE_ACTIONS", "ScoreAction", "check_estimator", "check_score_action", "gpomdp",
           "gpomdp_baseline", "gradient_samples", "reinforce", "reinforce_baseline", "trajectory_scores"]
