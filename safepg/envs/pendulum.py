r"""gymnasium's ``Pendulum-v1`` as a task, N episodes at once, fused with the gradient estimate.

The swing-up pendulum of gymnasium (``PendulumEnv``): a rod of mass :math:`m` and length
:math:`l` hinged at one end, the angle :math:`\vartheta` measured from the upright position
(counter-clockwise positive), a torque :math:`u \in [-\bar u, \bar u]` at the hinge. With the
time step :math:`\Delta t`, gravity :math:`g` and the speed limit :math:`\bar\omega`, one step is

.. math::
    \dot\vartheta' = \operatorname{clip}\Big(\dot\vartheta + \Big(\frac{3g}{2l}\sin\vartheta
        + \frac{3}{ml^2}u\Big)\Delta t,\ -\bar\omega, \bar\omega\Big), \qquad
    \vartheta' = \vartheta + \dot\vartheta'\,\Delta t,

and the reward of the step, taken in the state it starts from, is

.. math:: r = -\big(\operatorname{norm}(\vartheta)^2 + 0.1\,\dot\vartheta^2 + 0.001\,u^2\big),
          \qquad \operatorname{norm}(\vartheta) = ((\vartheta + \pi) \bmod 2\pi) - \pi,

gymnasium's operations in gymnasium's order (``g = 10``, ``m = l = 1``, ``dt = 0.05``,
:math:`\bar\omega = 8`, :math:`\bar u = 2`). The episode has no terminal state and lasts
H = 200 steps, gymnasium's time limit. The start is gymnasium's default: :math:`\vartheta_0`
uniform in :math:`[-\pi, \pi]` and :math:`\dot\vartheta_0` uniform in :math:`[-1, 1]`.

The policy is linear Gaussian on gymnasium's observation,
:math:`\phi(s) = (\cos\vartheta, \sin\vartheta, \dot\vartheta)` (in float64; gymnasium returns
it in float32), :math:`a \sim \mathcal N(\theta^\top\phi(s), \sigma^2)`, and the torque applied
is :math:`u = \operatorname{clip}(a, -\bar u, \bar u)`.

The bounds of Assumption 4.2.1 are all known: :math:`|r| \le R = \pi^2 + 0.1\cdot 8^2 +
0.001\cdot 2^2` (the angle is normalised into :math:`[-\pi, \pi)`, the speed is clipped to 8, the
torque to 2), :math:`|\phi_i| \le M_\phi = 8`, :math:`|u| \le \bar A = 2`, :math:`|\mathcal A| = 4`.

Sines and cosines are :mod:`safepg.portable`'s and the random numbers :mod:`safepg.streams`'s, so
a seeded batch has the same bits on every CPU. gymnasium's own ``PendulumEnv`` computes with
NumPy's sine, which may differ from ours in the last bit: the two agree to 1e-12 over a step
and to 1e-9 over an episode (``tests/test_pendulum.py``).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from safepg import portable
from safepg.constants import HORIZON_TERMS
from safepg.estimators import check_estimator, check_score_action
from safepg.policies import LinearGaussianPolicy
from safepg.rng import RNGLike, as_generator
from safepg.streams import batch_key, trajectory_draws
from safepg.tasks import ActionDimension, ConstantsSettings, GradientBatch, GradientBatchConstants, MeasuredReturns
from safepg.trajectories import Trajectories

#: gymnasium's id of the task.
ENV_ID = "Pendulum-v1"
#: What :meth:`Pendulum.measured_returns` records as J_hat.
MEASURES = ("undiscounted", "discounted")


def angle_normalize(angle: np.ndarray | float) -> np.ndarray:
    r"""The angle into :math:`[-\pi, \pi)`: ``((angle + pi) % (2 pi)) - pi``, gymnasium's operations.

    NumPy's ``%`` on floats is Python's (the exact ``fmod``, then one rounded addition where the
    sign differs from 2 pi's), which is what the kernel computes too.
    """
    return np.asarray((np.asarray(angle, dtype=float) + math.pi) % (2 * math.pi) - math.pi)


def step_dynamics(state: np.ndarray, torque: np.ndarray | float, *, gravity: float = 10.0, mass: float = 1.0,
                  length: float = 1.0, dt: float = 0.05, max_speed: float = 8.0) -> np.ndarray:
    r"""One step of the pendulum from each state with each (already clipped) torque.

    Parameters
    ----------
    state : ndarray, shape (..., 2)
        States :math:`(\vartheta, \dot\vartheta)`, the angle in radians from upright.
    torque : float or ndarray, shape (...)
        The torque applied, in N m (no clipping here).
    gravity, mass, length, dt, max_speed : float
        g, m, l, the time step and the speed limit.

    Returns
    -------
    ndarray, shape (..., 2)
        The next states.
    """
    s = np.asarray(state, dtype=float)
    th, thdot = s[..., 0], s[..., 1]
    gravity_term, torque_term = _coefficients(gravity, mass, length)
    speed = thdot + (gravity_term * portable.sin_array(th) + torque_term * np.asarray(torque, dtype=float)) * dt
    speed = np.minimum(np.maximum(speed, -max_speed), max_speed)  # np.clip, without its checks
    out = np.empty(np.broadcast_shapes(s.shape, np.shape(torque) + (2,)))
    out[..., 0] = th + speed * dt
    out[..., 1] = speed
    return out


def step_reward(state: np.ndarray, torque: np.ndarray | float) -> np.ndarray:
    r""":math:`-(\operatorname{norm}(\vartheta)^2 + 0.1\dot\vartheta^2 + 0.001u^2)` of each state and
    applied torque, the three terms added left to right as gymnasium adds them."""
    s = np.asarray(state, dtype=float)
    na, thdot, u = angle_normalize(s[..., 0]), s[..., 1], np.asarray(torque, dtype=float)
    return np.asarray(-((na * na + 0.1 * (thdot * thdot)) + 0.001 * (u * u)))


def _coefficients(gravity: float, mass: float, length: float) -> tuple[float, float]:
    """3 g / (2 l) and 3 / (m l^2), formed as gymnasium forms them (l^2 as a product: the same
    correctly rounded square as Python's ``l**2``, without libm's ``pow``)."""
    return 3 * gravity / (2 * length), 3.0 / (mass * (length * length))


@dataclass(frozen=True)
class Pendulum(GradientBatch, GradientBatchConstants, MeasuredReturns, ActionDimension, ConstantsSettings):
    r"""gymnasium's ``Pendulum-v1``, simulated N episodes at a time (module docstring).

    Parameters
    ----------
    gamma : float
        Discount factor of the estimators, in (0, 1]. Ours: 0.99 (gymnasium states none).
    horizon : int
        H, gymnasium's time limit: 200.
    gravity, mass, length, dt : float
        gymnasium's ``g = 10``, ``m = 1``, ``l = 1`` and ``dt = 0.05``.
    max_speed, max_torque : float
        The speed limit (8) and the torque limit :math:`\bar u` (2), gymnasium's.
    init_angle, init_speed : float
        The start is uniform in ``[-init_angle, init_angle] x [-init_speed, init_speed]``:
        gymnasium's ``x_init = pi`` and ``y_init = 1`` (its reset options of these names).
    measure : {"undiscounted", "discounted"}
        What :meth:`measured_returns` and the second output of :meth:`gradient_batch` are, the
        J_hat of a learning record: gymnasium's episode return, the plain sum of the H rewards
        (default), or the discounted return the estimators optimise.
    horizon_term : {"effective", "truncated", "horizon"}
        The horizon factor of the penalty constant (:class:`~safepg.constants.TaskConstants`).
    constants_gamma : float or None
        The discount the bound constants are written in; None: ``gamma`` (the authors' cart-pole
        code put 0.9 there, see :class:`~safepg.envs.cartpole.CartPole`). With ``horizon_term``,
        the task's :class:`~safepg.tasks.ConstantsSettings`.
    """

    gamma: float = 0.99
    horizon: int = 200
    gravity: float = 10.0
    mass: float = 1.0
    length: float = 1.0
    dt: float = 0.05
    max_speed: float = 8.0
    max_torque: float = 2.0
    init_angle: float = math.pi
    init_speed: float = 1.0
    measure: Literal["undiscounted", "discounted"] = "undiscounted"
    horizon_term: str = "effective"
    constants_gamma: float | None = None

    #: The state (angle, speed), the features (cos, sin, speed) and the torque.
    state_dim: ClassVar[int] = 2
    feature_dim: ClassVar[int] = 3
    action_dim: ClassVar[int] = 1

    def __post_init__(self) -> None:
        if isinstance(self.gamma, bool) or not 0 < self.gamma <= 1:
            raise ValueError(f"gamma must be in (0, 1], got {self.gamma!r}")
        if isinstance(self.horizon, bool) or int(self.horizon) != self.horizon or self.horizon < 1:
            raise ValueError(f"horizon must be a positive integer, got {self.horizon!r}")
        for name in ("gravity", "mass", "length", "dt", "max_speed", "max_torque", "init_angle", "init_speed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        if self.init_speed > self.max_speed:
            raise ValueError(f"init_speed must be <= max_speed {self.max_speed}, got {self.init_speed}")
        # The kernel's sine is safepg.portable's below 1e5 rad; the angle moves by at most
        # max_speed * dt a step.
        if self.init_angle + self.horizon * self.max_speed * self.dt >= 1e5:
            raise ValueError(f"horizon must keep the angle below 1e5 rad, got {self.horizon}")
        if self.measure not in MEASURES:
            raise ValueError(f"measure must be one of {MEASURES}, got {self.measure!r}")
        if self.horizon_term not in HORIZON_TERMS:
            raise ValueError(f"horizon_term must be one of {HORIZON_TERMS}, got {self.horizon_term!r}")
        if self.constants_gamma is not None and not 0 < self.constants_gamma <= 1:
            raise ValueError(f"constants_gamma must be in (0, 1] or None, got {self.constants_gamma!r}")

    # ------------------------------------------------------------ bound constants
    @property
    def reward_bound(self) -> float:
        r"""R = :math:`\pi^2 + 0.1\,\bar\omega^2 + 0.001\,\bar u^2`, the largest |r| (16.2736... for
        gymnasium's limits): the normalised angle lies in :math:`[-\pi, \pi)`, the speed in
        :math:`[-\bar\omega, \bar\omega]`, the torque in :math:`[-\bar u, \bar u]`."""
        return math.pi * math.pi + 0.1 * (self.max_speed * self.max_speed) + 0.001 * (
            self.max_torque * self.max_torque)

    @property
    def feature_bound(self) -> float:
        r"""M_phi = max(1, :math:`\bar\omega`): cosine and sine are at most 1, the speed at most 8."""
        return max(1.0, float(self.max_speed))

    @property
    def action_bound(self) -> float:
        r"""A-bar = :math:`\bar u`, the torque limit."""
        return float(self.max_torque)

    @property
    def action_volume(self) -> float:
        r"""|A| = :math:`2\bar u`, the length of the torque interval."""
        return float(2 * self.max_torque)

    # ------------------------------------------------------------------ dynamics
    def step(self, state: np.ndarray, torque: np.ndarray | float) -> np.ndarray:
        """:func:`safepg.envs.pendulum.step_dynamics` with this task's constants (the torque is not clipped)."""
        return step_dynamics(state, torque, gravity=self.gravity, mass=self.mass, length=self.length, dt=self.dt,
                             max_speed=self.max_speed)

    @staticmethod
    def reward(state: np.ndarray, torque: np.ndarray | float) -> np.ndarray:
        """:func:`safepg.envs.pendulum.step_reward`: the reward of a step from ``state`` with the applied ``torque``."""
        return step_reward(state, torque)

    @staticmethod
    def features(state: np.ndarray) -> np.ndarray:
        r""":math:`\phi(s) = (\cos\vartheta, \sin\vartheta, \dot\vartheta)`, gymnasium's observation, (..., 3)."""
        s = np.asarray(state, dtype=float)
        th = s[..., 0]
        return np.stack([portable.cos_array(th), portable.sin_array(th), s[..., 1]], axis=-1)

    # ----------------------------------------------------------------- simulator
    def _check_policy_and_n(self, policy: LinearGaussianPolicy, n: int) -> int:
        if not isinstance(policy, LinearGaussianPolicy):
            raise ValueError(f"policy must be a LinearGaussianPolicy, got {type(policy).__name__}")
        if policy.gain.shape != (self.action_dim, self.feature_dim):
            raise ValueError(f"policy must have a (1, 3) gain for the pendulum, got {policy.gain.shape}")
        if isinstance(n, bool) or not isinstance(n, int | np.integer | float) or not (
                math.isfinite(n) and n == int(n) and n >= 1):
            raise ValueError(f"n must be a positive integer, got {n!r}")
        return int(n)

    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories:
        """``n`` episodes of H steps under ``policy``, as whole arrays (the reference path).

        Trajectory i reads stream i of one batch key from ``rng`` (:mod:`!safepg.streams`): two
        uniforms for its start, then one standard normal per step, the numbers
        :meth:`gradient_batch`'s kernel draws. The loop runs over time; each step is whole-array
        work on the n pendulums.

        Returns
        -------
        Trajectories
            features (n, H, 3), actions_raw (the sampled a) and actions (the applied torque u),
            rewards (n, H), no mask (no episode ends early), the task's gamma.
        """
        n = self._check_policy_and_n(policy, n)
        rng = as_generator(rng)
        H = self.horizon
        K = policy.gain[0]
        std = float(policy.cov_chol[0, 0])
        uniforms, normals = trajectory_draws(batch_key(rng), n, self.state_dim, H)
        s = np.empty((n, 2))
        s[:, 0] = -self.init_angle + (self.init_angle + self.init_angle) * uniforms[:, 0]
        s[:, 1] = -self.init_speed + (self.init_speed + self.init_speed) * uniforms[:, 1]
        feats = np.empty((n, H, 3))
        raw = np.empty((n, H))
        rewards = np.empty((n, H))
        for t in range(H):
            phi = self.features(s)
            feats[:, t] = phi
            # K phi summed left to right as in the kernel (``@`` would go through BLAS).
            raw[:, t] = ((K[0] * phi[:, 0] + K[1] * phi[:, 1]) + K[2] * phi[:, 2]) + std * normals[:, t]
            u = np.minimum(np.maximum(raw[:, t], -self.max_torque), self.max_torque)
            rewards[:, t] = self.reward(s, u)
            s = self.step(s, u)
        acts = np.minimum(np.maximum(raw, -self.max_torque), self.max_torque)[:, :, None]
        return Trajectories(feats, raw[:, :, None], acts, rewards, None, self.gamma)

    def measured_returns(self, batch: Trajectories) -> np.ndarray:
        """Per-episode J_hat, shape (N,): the sum of the rewards (``measure="undiscounted"``,
        gymnasium's episode return) or the discounted return."""
        if self.measure == "discounted":
            return batch.discounted_returns()
        total: np.ndarray = batch.rewards.sum(axis=1)
        return total

    # ---------------------------------------------------------------- fused paths
    def _fused(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike, estimator: str, baseline: bool,
               score_action: str) -> tuple[np.ndarray, ...]:
        from safepg.envs._pendulum_kernel import pendulum_gradient_samples

        n = self._check_policy_and_n(policy, n)
        check_estimator(estimator)
        check_score_action(score_action)
        gravity_term, torque_term = _coefficients(self.gravity, self.mass, self.length)
        return pendulum_gradient_samples(
            policy.gain[0], float(policy.cov_chol[0, 0]), gravity_term, torque_term, self.dt, self.max_speed,
            self.max_torque, self.init_angle, self.init_speed, batch_key(as_generator(rng)), n, self.horizon,
            self.gamma, score_action == "clipped", estimator == "reinforce", baseline)

    def gradient_batch(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None, estimator: str = "gpomdp",
                       baseline: bool = True, score_action: str = "clipped") -> tuple[np.ndarray, np.ndarray]:
        """Gradient samples (n, 3) and measured returns (n,) of a fresh batch, in one fused kernel.

        The batch :meth:`simulate` draws with the same ``rng``, and the numbers of
        ``gradient_samples(policy, simulate(...), estimator, baseline, score_action)`` and of
        :meth:`measured_returns` up to rounding (:mod:`!safepg.envs._pendulum_kernel`), without
        materialising the trajectories. The result does not depend on the number of numba threads.
        """
        out = self._fused(policy, n, rng, estimator, baseline, score_action)
        return out[0], out[2] if self.measure == "undiscounted" else out[1]

    def gradient_batch_constants(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None,
                                 estimator: str = "gpomdp", baseline: bool = True, score_action: str = "clipped",
                                 ) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
        """:meth:`gradient_batch` and the batch's measured (R, M_phi): the largest |r_t| and
        |phi_i(s_t)| over its H steps, what the learning loop measures on :meth:`simulate`'s batch
        with ``Departures(batch_constants=True)``."""
        out = self._fused(policy, n, rng, estimator, baseline, score_action)
        return out[0], out[2] if self.measure == "undiscounted" else out[1], (float(out[3].max()),
                                                                              float(out[4].max()))

    def episode_returns(self, policy: LinearGaussianPolicy, n: int,
                        rng: RNGLike = None) -> tuple[np.ndarray, np.ndarray]:
        """(discounted, undiscounted) returns of ``n`` fresh episodes, shape (n,) each.

        The batch :meth:`simulate` draws with the same ``rng``, through the fused kernel (no
        baseline is formed). Two policies given the same seed see the same starts and the same
        standard normals: common random numbers, as the paired safety measurement uses them
        (:mod:`safepg.safety`).
        """
        out = self._fused(policy, n, rng, "gpomdp", False, "raw")
        return out[1], out[2]


def gymnasium_step(states: np.ndarray, torques: np.ndarray, gravity: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """One step of gymnasium's own ``PendulumEnv`` from each state with each torque.

    The independent implementation :func:`step_dynamics` and :func:`step_reward` are checked
    against (the tests and the Pendulum chapter). One Python step per state: a reference, not a
    simulator. The torque goes in as float64 (``PendulumEnv`` clips it to [-2, 2] itself).

    Parameters
    ----------
    states : ndarray, shape (n, 2)
    torques : ndarray, shape (n,)
    gravity : float
        gymnasium's ``g``.

    Returns
    -------
    next_states : ndarray, shape (n, 2)
    rewards : ndarray, shape (n,)
    """
    from gymnasium.envs.classic_control.pendulum import PendulumEnv

    S = np.asarray(states, dtype=float).reshape(-1, 2)
    U = np.asarray(torques, dtype=float).reshape(-1)
    if U.shape[0] != S.shape[0]:
        raise ValueError(f"torques must have one entry per state, got {U.shape[0]} for {S.shape[0]} states")
    env = PendulumEnv(g=gravity)
    env.reset(seed=0)
    out = np.empty_like(S)
    rewards = np.empty(S.shape[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i, (s, u) in enumerate(zip(S, U)):
            env.state = s.copy()
            _, r, _, _, _ = env.step(np.array([u]))
            out[i] = env.state
            rewards[i] = r
    return out, rewards


__all__ = ["ENV_ID", "MEASURES", "Pendulum", "angle_normalize", "gymnasium_step", "step_dynamics", "step_reward"]
