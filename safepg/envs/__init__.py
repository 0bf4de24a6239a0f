"""Environments: the linear-quadratic Gaussian regulator and the continuous cart-pole."""

from safepg.envs.gym_task import FeatureMap, GymTask, with_bias
from safepg.envs.lqg import LQG

__all__ = ["LQG", "GymTask", "FeatureMap", "with_bias"]
