"""Environments: the linear-quadratic Gaussian regulator and the continuous cart-pole."""

from safepg.envs.gym_task import GymTask
from safepg.envs.lqg import LQG

__all__ = ["LQG", "GymTask"]
