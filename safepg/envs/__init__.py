"""Environments: the linear-quadratic Gaussian regulator and the continuous cart-pole."""

from safepg.envs.lqg import LQG

__all__ = ["LQG"]
