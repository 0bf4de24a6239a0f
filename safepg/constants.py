"""The task constants the safe-PG bounds of Chapter 4 are written in."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


class BoundedTask(Protocol):
    reward_bound: float
    feature_bound: float
    action_volume: float
    action_bound: float
    gamma: float
    horizon: int


@dataclass(frozen=True)
class TaskConstants:
    """Constants of Assumption 4.2.1, Theorem 4.2.3 and Lemma 4.3.3.

    Attributes
    ----------
    R : float
        Bound on |reward|.
    M_phi : float
        Bound on |phi_i(s)| (Assumption 4.2.1).
    A_volume : float
        Volume |A| of the action space.
    A_bar : float
        Bound on |a| (Lemma 4.3.3).
    gamma : float
        Discount factor.
    H : int
        Horizon.
    sigma : float
        Policy standard deviation.
    """

    R: float
    M_phi: float
    A_volume: float
    A_bar: float
    gamma: float
    H: int
    sigma: float

    def __post_init__(self) -> None:
        for name in ("R", "M_phi", "A_volume", "A_bar", "sigma"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not 0 < self.gamma < 1:
            raise ValueError(f"gamma must be in (0, 1), got {self.gamma}")
        if int(self.H) != self.H or self.H < 1:
            raise ValueError(f"H must be a positive integer, got {self.H}")

    @classmethod
    def from_task(cls, task: BoundedTask, sigma: float) -> TaskConstants:
        """Read the constants off an environment for a policy of std ``sigma``."""
        return cls(
            R=task.reward_bound,
            M_phi=task.feature_bound,
            A_volume=task.action_volume,
            A_bar=task.action_bound,
            gamma=task.gamma,
            H=task.horizon,
            sigma=float(sigma),
        )
