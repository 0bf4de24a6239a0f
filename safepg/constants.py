"""The task constants the safe-PG bounds of Chapter 4 are written in."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from safepg import portable

# BoundedTask lives in safepg.tasks with the rest of a task's interface (this module reads
# tasks, safepg.tasks does not need it); it is imported here for the name it had.
from safepg.tasks import BoundedTask, constants_settings

#: Values of the ``horizon_term`` of :class:`TaskConstants`.
HORIZON_TERMS = ("effective", "truncated", "horizon")


@dataclass(frozen=True)
class TaskConstants:
    """Constants of Assumption 4.2.1, Theorem 4.2.3 and Lemma 4.3.3.

    Attributes
    ----------
    R : float
        Bound on |reward|.
    M_phi : float
        Bound on |phi_i(s)| (Assumption 4.2.1).
    action_volume : float
        Volume |A| of the action space (the tasks' ``action_volume``).
    A_bar : float
        Bound on |a| (Lemma 4.3.3).
    gamma : float
        Discount factor.
    H : int
        Horizon.
    sigma : float
        Policy standard deviation.
    horizon_term : {"effective", "truncated", "horizon"}
        What the horizon factor h (:attr:`horizon_factor`) of the penalty constant is.
        ``"effective"`` (default): h = 1 / (1 - gamma), Theorem 4.2.3 as printed, for
        infinite-horizon discounted returns. ``"truncated"``: h = (1 - gamma^H) / (1 - gamma),
        the discounted sums cut at the horizon H. ``"horizon"``: h = H, the undiscounted
        finite-horizon bound. The last two allow gamma = 1 (undiscounted returns).
    """

    R: float
    M_phi: float
    action_volume: float
    A_bar: float
    gamma: float
    H: int
    sigma: float
    horizon_term: str = "effective"

    def __post_init__(self) -> None:
        for name in ("R", "M_phi", "action_volume", "A_bar", "sigma"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if self.horizon_term not in HORIZON_TERMS:
            raise ValueError(f"horizon_term must be one of {HORIZON_TERMS}, got {self.horizon_term!r}")
        if self.horizon_term != "effective":  # a finite horizon keeps the sums finite at gamma = 1
            if not 0 < self.gamma <= 1:
                raise ValueError(f"gamma must be in (0, 1], got {self.gamma}")
        elif not 0 < self.gamma < 1:
            raise ValueError(f"gamma must be in (0, 1), got {self.gamma}")
        if int(self.H) != self.H or self.H < 1:
            raise ValueError(f"H must be a positive integer, got {self.H}")

    @property
    def horizon_factor(self) -> float:
        """h, the horizon factor of the penalty constant (see ``horizon_term``)."""
        if self.horizon_term == "effective":
            return 1.0 / (1.0 - self.gamma)
        if self.horizon_term == "horizon" or self.gamma == 1:
            return float(self.H)
        # portable.ipow: libm's pow is CPU-dependent in the last bit.
        return (1.0 - portable.ipow(self.gamma, self.H)) / (1.0 - self.gamma)

    @classmethod
    def from_task(cls, task: BoundedTask, sigma: float) -> TaskConstants:
        """Read the constants off an environment for a policy of std ``sigma``.

        The horizon term and the discount of the constants are the task's
        :class:`~safepg.tasks.ConstantsSettings` (:func:`~safepg.tasks.constants_settings`): a
        task that does not declare them gets ``"effective"`` (Theorem 4.2.3 as printed) and its
        own ``gamma``. A ``constants_gamma`` other than None writes the constants in that
        discount instead of the task's ``gamma`` (the cart-pole's authors' setting: undiscounted
        returns, gamma = 0.9 in the penalty constant).

        Raises
        ------
        TypeError
            The task defines ``horizon_term`` or ``constants_gamma`` without declaring
            :class:`~safepg.tasks.ConstantsSettings`, or declares it without both.
        """
        settings = constants_settings(task)
        return cls(
            R=task.reward_bound,
            M_phi=task.feature_bound,
            action_volume=task.action_volume,
            A_bar=task.action_bound,
            gamma=task.gamma if settings.constants_gamma is None else settings.constants_gamma,
            H=task.horizon,
            sigma=float(sigma),
            horizon_term=settings.horizon_term,
        )


__all__ = ["BoundedTask", "HORIZON_TERMS", "TaskConstants"]
