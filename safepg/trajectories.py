"""The batch of trajectories every environment's ``simulate`` returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from safepg import portable


@dataclass(frozen=True)
class Trajectories:
    """N trajectories of horizon H, stored as whole arrays.

    Attributes
    ----------
    features : ndarray, shape (N, H, d_phi)
        Policy features phi(s_t) (for the LQG and the cart-pole, the state).
    actions_raw : ndarray, shape (N, H, d_a)
        Actions sampled from the Gaussian policy, before clipping.
    actions : ndarray, shape (N, H, d_a)
        Actions applied to the system (clipped to the action box).
    rewards : ndarray, shape (N, H)
        Rewards r_t (0 after termination).
    mask : ndarray of bool, shape (N, H), or None
        True while the episode is alive at step t; ``None`` means always alive.
    gamma : float
        Discount factor; discounting starts at gamma^0 on the first reward.
    """

    features: np.ndarray
    actions_raw: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    mask: np.ndarray | None
    gamma: float

    @property
    def n(self) -> int:
        """Number of trajectories N."""
        return int(self.rewards.shape[0])

    @property
    def horizon(self) -> int:
        """Horizon H."""
        return int(self.rewards.shape[1])

    def discounts(self) -> np.ndarray:
        """gamma^t for t = 0, ..., H-1."""
        return portable.powers(self.gamma, self.horizon)  # gamma * gamma * ..., as the kernels do

    def discounted_returns(self) -> np.ndarray:
        """Per-trajectory discounted return sum_t gamma^t r_t, shape (N,)."""
        returns: np.ndarray = np.sum(self.rewards * self.discounts(), axis=1)  # not BLAS (safepg.portable)
        return returns


__all__ = ["Trajectories"]
