"""Environments: the linear-quadratic Gaussian regulator, the continuous cart-pole, gymnasium's pendulum."""

from safepg.envs.gym_task import FeatureMap, GymTask, with_bias
from safepg.envs.lqg import LQG
from safepg.envs.pendulum import Pendulum

__all__ = ["LQG", "GymTask", "FeatureMap", "Pendulum", "with_bias"]
