r"""Continuous-action cart-pole (thesis Section 5.3), batched, plus a gymnasium environment.

State :math:`s = [x, \dot x, \beta, \dot\beta]` (cart position in m, cart velocity in m/s,
pole angle from the vertical in rad, angular velocity in rad/s); the action is the
horizontal force on the cart in N, clipped to [-10, 10] before it is applied. The policy
is linear Gaussian, :math:`a \sim \mathcal N(\theta^\top s, \sigma^2)`, so the features are
the state itself.

Physics: the frictionless cart-pole of Barto et al. (1983) with the equations of motion
of Florian (2007), "Correct equations for the dynamics of the cart-pole system", integrated
with the explicit Euler scheme that gymnasium's
``CartPoleEnv`` uses (``kinematics_integrator = "euler"``: positions advance with the
*old* velocities). The pole is a uniform rod hinged at its lower end, so its centre of
mass sits at half its length and its moment of inertia about the centre is
:math:`m (2l)^2 / 12`, which gives the 4/3 factor below.

.. math::
    \ddot\beta = \frac{g\sin\beta - \cos\beta\,\dfrac{F + m l\dot\beta^2\sin\beta}{M}}
                      {l\left(\tfrac43 - \dfrac{m\cos^2\beta}{M}\right)}, \qquad
    \ddot x = \frac{F + m l (\dot\beta^2\sin\beta - \ddot\beta\cos\beta)}{M}

with :math:`l` the *half* pole length, :math:`m` the pole mass and :math:`M = m + m_c`.

What the thesis states and what is ours (every choice is a field of :class:`CartPole`):

- stated: cart 1 kg, pole 0.1 kg, pole 1 m long, force in [-10, 10] N, reward 1 per step,
  H = 200, termination when :math:`|\beta| > 41.8^\circ` or :math:`|x| > 2.4` m, initial
  state "in a small neighbourhood of 0", sigma = 1, theta_0 = 0, and (for the adaptation
  experiment) the pole length doubled with its mass kept.
- ours: gravity 9.8, time step 0.02 s, Euler integration, initial state uniform in
  [-0.05, 0.05]^4 (all gymnasium's), the discount gamma = 0.99 and the feature bound
  M_phi = 10 (see :class:`CartPole`).

"1 m long" is the whole pole: gymnasium's ``length = 0.5`` is documented there as
"actually half the pole's length", and the original pole.c of Barto et al. uses the same
0.5 m half-length, i.e. a 1 m pole. So the thesis's pole *is* gymnasium's default pole, and
doubling it gives gymnasium ``length = 1.0``. ``pole_length`` below is always the full length.

41.8 degrees is not gymnasium's (or gym's) termination angle, which is 12 degrees. Most
likely it comes from the "Pole Angle -41.8 deg ... 41.8 deg" row of the observation table
in old gym's CartPole-v0 documentation, which mislabels the observation *box* half-width,
0.418 rad (= 2 x 12 degrees = 24 degrees), as degrees. The thesis prints 41.8 degrees, so
that is the default; ``angle_threshold_deg=12`` gives gym's task.

The authors' code ran gym's 12 degrees, doubled the pole by changing gym's half-length after
the env had cached the pole's m l (``polemass_length``), and estimated the gradient of the
undiscounted return with gamma = 0.9 in the penalty constant: ``angle_threshold_deg=12``,
``polemass_length=0.05``, ``gamma=1``, ``constants_gamma=0.9`` (the fields below).

Rewards and the mask: at step t the episode is alive if s_t is inside the thresholds;
then the agent acts, gets r_t = 1 and the system moves to s_{t+1}. If s_{t+1} is outside,
steps t+1, ..., H-1 are dead (mask False, reward 0, features and actions 0). So, as in
gymnasium, the step into the failing state is still rewarded and the undiscounted return
is the episode length (at most H = 200).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from safepg import portable
from safepg.constants import HORIZON_TERMS
from safepg.estimators import check_estimator, check_score_action
from safepg.policies import LinearGaussianPolicy, check_sigma
from safepg.rng import RNGLike, as_generator
from safepg.streams import batch_key, trajectory_draws
from safepg.tasks import ActionDimension, ConstantsSettings, GradientBatch, GradientBatchConstants, MeasuredReturns
from safepg.trajectories import Trajectories

#: gymnasium id under which :class:`ContinuousCartPoleEnv` is registered.
ENV_ID = "safepg/ContinuousCartPole-v0"

# Defaults shared by the pure step function, the batched task and the gymnasium env.
_CART_MASS = 1.0  # kg (thesis)
_POLE_MASS = 0.1  # kg (thesis)
_POLE_LENGTH = 1.0  # m, whole pole (thesis "1m long" = gymnasium half-length 0.5)
_GRAVITY = 9.8  # m/s^2, gymnasium's value (the thesis does not state one)
_TAU = 0.02  # s, gymnasium's time step (the thesis does not state one)


def step_dynamics(
    state: np.ndarray,
    force: np.ndarray | float,
    pole_length: float = _POLE_LENGTH,
    *,
    cart_mass: float = _CART_MASS,
    pole_mass: float = _POLE_MASS,
    gravity: float = _GRAVITY,
    tau: float = _TAU,
    integrator: str = "euler",
    polemass_length: float | None = None,
) -> np.ndarray:
    r"""One explicit-Euler (or semi-implicit Euler) step of the cart-pole, vectorised over leading axes.

    Parameters
    ----------
    state : ndarray, shape (..., 4)
        States [x, x_dot, beta, beta_dot] (beta in radians).
    force : float or ndarray, shape (...)
        Force applied to the cart in N (already clipped: no clipping happens here).
    pole_length : float
        *Whole* pole length in m (gymnasium's ``length`` is half of it).
    cart_mass, pole_mass, gravity, tau : float
        Cart and pole masses (kg), gravitational acceleration (m/s^2), time step (s).
    integrator : {"euler", "semi-implicit"}
        ``"euler"``: positions advance with the *old* velocities (gymnasium's default
        ``kinematics_integrator="euler"``). ``"semi-implicit"``: velocities first, then
        positions with the *new* velocities (gymnasium's ``"semi-implicit euler"``).
    polemass_length : float or None
        m l, the pole mass times the half-length, in the two terms of the pole's momentum
        (the centrifugal pull and the reaction on the cart). None: ``pole_mass * pole_length / 2``,
        a consistent pole. gymnasium caches it as ``polemass_length`` when the env is built, so
        changing its ``length`` afterwards changes l only in the angular acceleration's
        denominator (see :class:`CartPole`).

    Returns
    -------
    ndarray, shape (..., 4)
        The next states.
    """
    _check_integrator(integrator)
    s = np.asarray(state, dtype=float)
    x, x_dot, beta, beta_dot = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
    half = 0.5 * pole_length  # the equations use the distance hinge -> centre of mass
    # The same product the consistent pole's equations form first (same bits either way).
    ml = pole_mass * half if polemass_length is None else polemass_length
    total = cart_mass + pole_mass
    # The kernel's sine and cosine (safepg.portable): the same bits on every CPU, unlike libm's.
    sin, cos = portable.sin_array(beta), portable.cos_array(beta)
    # Force on the cart plus the centrifugal pull of the pole, per unit of total mass.
    push = (force + ml * beta_dot * beta_dot * sin) / total
    beta_acc = (gravity * sin - cos * push) / (half * (4.0 / 3.0 - pole_mass * cos * cos / total))
    x_acc = push - ml * beta_acc * cos / total
    out = np.empty(np.broadcast_shapes(s.shape, np.shape(force) + (4,)))
    out[..., 1] = x_dot + tau * x_acc
    out[..., 3] = beta_dot + tau * beta_acc
    if integrator == "euler":
        out[..., 0] = x + tau * x_dot
        out[..., 2] = beta + tau * beta_dot
    else:  # semi-implicit: the positions move with the velocities just computed
        out[..., 0] = x + tau * out[..., 1]
        out[..., 2] = beta + tau * out[..., 3]
    return out


#: ``feature_scale`` of the normalised-feature setting: each state component divided by its
#: bound, 2.4 m and 41.8 deg for the alive region, 10 for the two velocities (the measured
#: bound of ``CartPole.feature_bound``), so that |phi_i| <= 1 and M_phi = 1.
NORMALISED_SCALE = (2.4, 10.0, round(math.radians(41.8), 4), 10.0)


def _fmt(v: Any) -> str:
    """A setting's value as it appears in a task name (shortest exact float repr)."""
    return repr(float(v)) if isinstance(v, float) and not float(v).is_integer() else (
        f"{int(v)}" if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v))


def _parse_setting(key: str, text: str) -> Any:
    """Read one ``field=value`` of a task name (see :meth:`CartPole.from_name`)."""
    if key == "feature_scale":
        if text == "None":
            return None
        try:
            return tuple(float(x) for x in text.split("/"))
        except ValueError:
            raise ValueError(f"feature_scale must be four numbers separated by '/', got {text!r}") from None
    if key in ("integrator", "horizon_term"):
        return text
    if text == "None":
        return None
    try:
        return int(text) if key == "horizon" else float(text)
    except ValueError:
        raise ValueError(f"{key} must be a number, got {text!r}") from None


#: Integration schemes of :func:`step_dynamics` (gymnasium's two ``kinematics_integrator`` values).
INTEGRATORS = ("euler", "semi-implicit")


def _check_integrator(integrator: str) -> None:
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")


@dataclass(frozen=True)
class CartPole(GradientBatch, GradientBatchConstants, MeasuredReturns, ActionDimension, ConstantsSettings):
    r"""The continuous cart-pole task of Section 5.3, simulated N carts at a time.

    Parameters
    ----------
    pole_length : float
        Whole pole length in m: 1.0 in the thesis, 2.0 after "doubling the length of the
        pole, keeping its mass constant" (gymnasium ``length`` 0.5 and 1.0).
    gamma : float
        Discount factor in (0, 1]. Ours: 0.99. The bounds of Chapter 4 need gamma < 1
        (the penalty constant has (1 - gamma)^-2), and 0.99 is the usual choice for a
        200-step task (the horizon 1 / (1 - gamma) = 100 steps spans most of the episode).
        The thesis's reported performances (195, 193.12) exceed the largest 0.99-discounted
        return, (1 - 0.99^200) / 0.01 = 86.6, so they are *undiscounted* returns: use
        :meth:`undiscounted_returns` (the episode length) to compare with them.
    horizon : int
        Maximum episode length H (thesis: 200).
    angle_threshold_deg : float
        Termination angle in degrees (thesis: 41.8; gymnasium: 12).
    x_threshold : float
        Termination cart position in m (thesis and gymnasium: 2.4).
    action_bound : float
        Force limit A-bar in N; the Gaussian action is clipped to [-A-bar, A-bar] (thesis: 10).
    feature_bound : float
        M_phi, a bound on |s_i| over alive states. Ours: 10. x and beta are bounded by the
        thresholds (2.4 m, 0.7295 rad), but the velocities are not bounded a priori. The
        largest |x_dot| and |beta_dot| we could reach in an alive state within 200 steps,
        searching with the cross-entropy method over saturated linear feedback laws
        (gain, bias, initial state) and over open-loop force sequences, were 9.53 m/s and
        6.13 rad/s for the 1 m pole and 9.57 m/s and 4.25 rad/s for the 2 m pole (the
        theta = 0, sigma = 1 policy stays below 1 m/s and 3 rad/s). 10 is that empirical
        maximum rounded up; it is a measured, not a proven, bound.
    cart_mass, pole_mass : float
        Masses in kg (thesis: 1 and 0.1).
    gravity : float
        m/s^2. Ours (unstated in the thesis): gymnasium's 9.8.
    tau : float
        Integration time step in s. Ours (unstated): gymnasium's 0.02.
    init_bound : float
        The initial state is uniform in [-init_bound, init_bound]^4. The thesis says "a
        small neighborhood of 0"; ours: gymnasium's 0.05.
    integrator : {"euler", "semi-implicit"}
        Integration scheme (unstated in the thesis). Ours: gymnasium's default ``"euler"``.
    feature_scale : tuple of 4 floats or None
        None (default): the features are the raw state, phi(s) = s. Otherwise the policy
        sees the *normalised* state phi(s) = s / feature_scale, a = theta^T phi(s) + noise,
        and theta and the gradient are in those units (set ``feature_bound`` to the bound
        on the normalised features, e.g. 1). :data:`NORMALISED_SCALE` divides each
        component by its alive-region bound (2.4 m, 41.8 deg) or by the measured
        velocity bound (10).
    reward_bound : float
        R of the bounds, max |r_t|. The reward is 1 while alive, so 1 (default) is the
        tight value; a larger R (e.g. H, a bound on the return) only makes the step smaller.
    action_space_volume : float or None
        The given |A| of the penalty constant, read as :attr:`action_volume`; None (default):
        the length of the force interval, 2 A-bar = 20. A frozen dataclass cannot have a field
        and a property of one name, and renaming the field would change what the run keys hash.
    horizon_term : {"effective", "truncated", "horizon"}
        The horizon factor h that replaces 1 / (1 - gamma) in the penalty constant
        (Theorem 4.2.3 is stated for infinite-horizon discounted returns):
        ``"effective"`` (default) h = 1 / (1 - gamma), as printed; ``"truncated"``
        h = (1 - gamma^H) / (1 - gamma), the discounted sums cut at H; ``"horizon"``
        h = H = 200. Only the bound constants change, not the simulation.
    polemass_length : float or None
        m l, the pole mass times the half-length, in the pole's momentum terms of both
        equations (see :func:`step_dynamics`). None (default): ``pole_mass * pole_length / 2``,
        a consistent pole. The authors doubled the pole with ``env.length *= 2`` after gym had
        cached ``polemass_length = 0.1 * 0.5 = 0.05`` in ``__init__``, so their doubled pole is
        ``pole_length=2, polemass_length=0.05``: the new half-length (1 m) enters only the
        denominator of the angular acceleration, the m l terms stay those of the 1 m pole.
    constants_gamma : float or None
        The discount the bound constants (penalty constant, Chebyshev variances, Lemma 4.3.3's
        range) are written in; None (default): ``gamma``. Only the constants change, not the
        simulation nor the estimators. The authors' cart-pole scripts estimate the gradient of
        the undiscounted return (``gamma=1``, a ``sigma**l`` typed for ``gamma**l``) and put
        gamma = 0.9 into the penalty constant. With ``horizon_term``, the task's
        :class:`~safepg.tasks.ConstantsSettings`.
    """

    pole_length: float = _POLE_LENGTH
    gamma: float = 0.99
    horizon: int = 200
    angle_threshold_deg: float = 41.8
    x_threshold: float = 2.4
    action_bound: float = 10.0
    feature_bound: float = 10.0
    cart_mass: float = _CART_MASS
    pole_mass: float = _POLE_MASS
    gravity: float = _GRAVITY
    tau: float = _TAU
    init_bound: float = 0.05
    integrator: str = "euler"
    feature_scale: tuple[float, float, float, float] | None = None
    #: R = max |r|: the reward is 1 while alive and 0 afterwards.
    reward_bound: float = 1.0
    action_space_volume: float | None = None
    horizon_term: str = "effective"
    polemass_length: float | None = None
    constants_gamma: float | None = None

    #: State and action dimensions (the features are the state, or its normalisation: d_phi = 4).
    state_dim: ClassVar[int] = 4
    action_dim: ClassVar[int] = 1

    def __post_init__(self) -> None:
        if not 0 < self.gamma <= 1:
            raise ValueError(f"gamma must be in (0, 1], got {self.gamma}")
        if int(self.horizon) != self.horizon or self.horizon < 1:
            raise ValueError(f"horizon must be a positive integer, got {self.horizon}")
        for name in ("pole_length", "angle_threshold_deg", "x_threshold", "action_bound", "feature_bound",
                     "cart_mass", "pole_mass", "gravity", "tau", "init_bound", "reward_bound"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        _check_integrator(self.integrator)
        if self.horizon_term not in HORIZON_TERMS:
            raise ValueError(f"horizon_term must be one of {HORIZON_TERMS}, got {self.horizon_term!r}")
        for name in ("action_space_volume", "polemass_length"):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0 or None, got {v}")
        if self.constants_gamma is not None and not 0 < self.constants_gamma <= 1:
            raise ValueError(f"constants_gamma must be in (0, 1] or None, got {self.constants_gamma}")
        if self.feature_scale is not None:
            sc = self.feature_scale
            if (not isinstance(sc, tuple) or len(sc) != self.state_dim
                    or not all(isinstance(x, (int, float)) and math.isfinite(x) and x > 0 for x in sc)):
                raise ValueError(f"feature_scale must be None or a tuple of 4 finite numbers > 0, got {sc!r}")
        if self.init_bound >= min(self.x_threshold, self.angle_threshold):
            raise ValueError(f"init_bound must leave the initial state alive, got {self.init_bound}")

    # ------------------------------------------------------------------ settings
    @classmethod
    def thesis(cls, **overrides: Any) -> CartPole:
        """The task of Section 5.3 with our choices for the unstated constants."""
        return cls(**overrides)

    @classmethod
    def thesis_doubled(cls, **overrides: Any) -> CartPole:
        """The modified task of Section 5.3: pole length doubled (2 m), mass unchanged."""
        return cls(**{"pole_length": 2 * _POLE_LENGTH, **overrides})

    # ------------------------------------------------------------ bound constants
    @property
    def angle_threshold(self) -> float:
        """Termination angle in radians (41.8 degrees = 0.72955 rad by default)."""
        return math.radians(self.angle_threshold_deg)

    @property
    def action_volume(self) -> float:
        """|A|: ``action_space_volume`` if set, else the length of the force interval, 2 A-bar = 20."""
        if self.action_space_volume is not None:
            return float(self.action_space_volume)
        return float(2 * self.action_bound)

    # ------------------------------------------------------------ named settings
    @classmethod
    def from_name(cls, name: str) -> CartPole:
        """The task named ``"cartpole"`` or ``"cartpole-doubled"``, optionally followed by
        field overrides in brackets: ``"cartpole-doubled[gamma=0.9,feature_bound=1]"``.

        Values are read as int, float or string; ``feature_scale`` takes four numbers
        separated by ``/`` (``feature_scale=2.4/10/0.7295/10``). :meth:`setting_name` is the inverse.
        The experiments use these names to run the settings of the cart-pole sweep.
        """
        if not isinstance(name, str):
            raise ValueError(f"name must be a string, got {name!r}")
        base, bracket, rest = name.partition("[")
        makers = {"cartpole": cls.thesis, "cartpole-doubled": cls.thesis_doubled}
        if base not in makers or (bracket and not rest.endswith("]")):
            raise ValueError(f"name must be 'cartpole' or 'cartpole-doubled', optionally with [field=value,...], "
                             f"got {name!r}")
        fields = {f for f in cls.__dataclass_fields__}
        overrides: dict[str, Any] = {}
        for item in filter(None, rest[:-1].split(",")) if bracket else ():
            key, eq, text = item.partition("=")
            if not eq or key not in fields or key == "pole_length":
                raise ValueError(f"name has an unknown or malformed setting {item!r} in {name!r}")
            overrides[key] = _parse_setting(key, text)
        return makers[base](**overrides)

    def setting_name(self) -> str:
        """The :meth:`from_name` name of this task: the base task and the fields that differ from it."""
        doubled = self.pole_length == 2 * _POLE_LENGTH
        base = type(self).thesis_doubled() if doubled else type(self).thesis()
        if not doubled and self.pole_length != _POLE_LENGTH:
            raise ValueError(f"pole_length must be 1 or 2 m to have a name, got {self.pole_length}")
        parts = []
        for key in self.__dataclass_fields__:
            v = getattr(self, key)
            if v != getattr(base, key):
                parts.append(f"{key}={'/'.join(f'{x:g}' for x in v) if key == 'feature_scale' else _fmt(v)}")
        return ("cartpole-doubled" if doubled else "cartpole") + (f"[{','.join(parts)}]" if parts else "")

    # ------------------------------------------------------------------ dynamics
    def step(self, state: np.ndarray, force: np.ndarray | float) -> np.ndarray:
        """:func:`step_dynamics` with this task's physical constants (force not clipped)."""
        return step_dynamics(state, force, self.pole_length, cart_mass=self.cart_mass, pole_mass=self.pole_mass,
                             gravity=self.gravity, tau=self.tau, integrator=self.integrator,
                             polemass_length=self.polemass_length)

    def features(self, state: np.ndarray) -> np.ndarray:
        """phi(s): the state itself, or ``state / feature_scale`` with normalised features."""
        s = np.asarray(state, dtype=float)
        return s if self.feature_scale is None else s / np.asarray(self.feature_scale)

    def alive(self, state: np.ndarray) -> np.ndarray:
        """Whether states (..., 4) are inside the thresholds (|x| <= 2.4, |beta| <= 41.8 deg)."""
        s = np.asarray(state, dtype=float)
        inside: np.ndarray = (np.abs(s[..., 0]) <= self.x_threshold) & (np.abs(s[..., 2]) <= self.angle_threshold)
        return inside

    # ----------------------------------------------------------------- simulator
    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories:
        """Simulate ``n`` episodes of at most H steps under ``policy`` at once.

        Same signature as :meth:`safepg.envs.LQG.simulate` (the learning loops call it);
        :meth:`simulate_gain` takes the gain and sigma instead of a policy.

        Random numbers are drawn in a fixed order: the (n, 4) initial states, then one
        (n, H, 1) array of standard normals, so a seed fixes the batch bit for bit.
        The loop runs over time steps only; each step is whole-array work on n carts.

        Parameters
        ----------
        policy : LinearGaussianPolicy
            Policy with a (1, 4) gain: a = K s + sigma * noise.
        n : int
            Number of trajectories (>= 1).
        rng : Generator, int or None
            Random source (see :func:`!safepg.rng.as_generator`).

        Returns
        -------
        Trajectories
            features = states (or their normalisation, see ``feature_scale``), actions_raw = sampled forces,
            actions = clipped forces,
            rewards = 1 while alive, mask = alive; zeros at dead steps.
        """
        n = self._check_policy_and_n(policy, n)
        rng = as_generator(rng)
        H, b = self.horizon, self.action_bound
        K = policy.gain[0]
        std = float(policy.cov_chol[0, 0])
        scale = None if self.feature_scale is None else np.asarray(self.feature_scale)

        # Trajectory i reads stream i of one batch key (safepg.streams), as the fused kernel does.
        uniforms, normals = trajectory_draws(batch_key(rng), n, self.state_dim, H)
        s = -self.init_bound + (self.init_bound + self.init_bound) * uniforms
        noise = normals[:, :, None]

        # Time-major buffers, so step t writes one contiguous block; transposed once at the end.
        feats = np.zeros((H, n, self.state_dim))
        raw = np.zeros((H, n))
        alive_t = np.zeros((H, n), dtype=bool)
        alive = np.ones(n, dtype=bool)  # s_0 is inside the thresholds (init_bound is checked)
        for t in range(H):
            if not alive.any():  # every episode has ended: the rest stays zero
                break
            alive_t[t] = alive
            phi = s if scale is None else s / scale
            feats[t] = phi
            # K phi summed left to right as in the kernel (``@`` would go through BLAS).
            raw[t] = (((K[0] * phi[:, 0] + K[1] * phi[:, 1]) + K[2] * phi[:, 2]) + K[3] * phi[:, 3]
                      + std * noise[:, t, 0])
            # Dead carts are frozen, not integrated: a fallen pole under linear feedback can
            # grow without bound (overflow warnings) and its state is never used again.
            s = np.where(alive[:, None], self.step(s, np.clip(raw[t], -b, b)), s)
            alive &= self.alive(s)
        mask = np.ascontiguousarray(alive_t.T)
        # Zero the dead steps (scores there must vanish, nothing stale should leak out).
        # The frozen states are finite, so multiplying by the mask gives exact zeros.
        feats = np.ascontiguousarray(feats.transpose(1, 0, 2)) * mask[:, :, None]
        raw = np.ascontiguousarray(raw.T * mask)[:, :, None]
        acts = np.clip(raw, -b, b)  # the forces applied (clip(0) = 0 at dead steps)
        return Trajectories(feats, raw, acts, mask.astype(float), mask, self.gamma)

    def _check_policy_and_n(self, policy: LinearGaussianPolicy, n: int) -> int:
        """Validate a cart-pole policy and a batch size; returns ``n`` as an int."""
        if not isinstance(policy, LinearGaussianPolicy):
            raise ValueError(f"policy must be a LinearGaussianPolicy, got {type(policy).__name__}")
        if policy.gain.shape != (self.action_dim, self.state_dim):
            raise ValueError(f"policy must have a (1, 4) gain for the cart-pole, got {policy.gain.shape}")
        integral = (isinstance(n, (int, np.integer, float)) and not isinstance(n, bool)
                    and math.isfinite(n) and n == int(n))
        if not (integral and n >= 1):
            raise ValueError(f"n must be a positive integer, got {n!r}")
        return int(n)

    def gradient_batch(
        self,
        policy: LinearGaussianPolicy,
        n: int,
        rng: RNGLike = None,
        estimator: str = "gpomdp",
        baseline: bool = True,
        score_action: str = "clipped",
    ) -> tuple[np.ndarray, np.ndarray]:
        """Gradient samples and undiscounted returns of a fresh batch, fused.

        The same random numbers as :meth:`simulate` (one batch key from ``rng``; trajectory i
        reads stream i: its initial state, then a standard normal per step), and the same numbers as
        ``gradient_samples(policy, simulate(...), estimator, baseline, score_action)`` and
        ``undiscounted_returns(simulate(...))`` up to rounding, without materialising the
        trajectories: each episode is followed only until it terminates (see
        :mod:`!safepg.envs._cartpole_kernel`). The result does not depend on the number of
        numba threads.

        Parameters
        ----------
        policy : LinearGaussianPolicy
            Policy with a (1, 4) gain.
        n : int
            Number of trajectories (>= 1).
        rng : Generator, int or None
            Random source (see :func:`!safepg.rng.as_generator`).
        estimator : {"gpomdp", "reinforce"}
            Likelihood-ratio estimator (discounted with ``gamma``).
        baseline : bool
            Subtract the variance-minimising baseline.
        score_action : {"clipped", "raw"}
            Score the applied (clipped) force or the sampled one.

        Returns
        -------
        samples : ndarray, shape (n, 4)
            Per-trajectory gradient samples.
        returns : ndarray, shape (n,)
            *Undiscounted* returns, i.e. the episode lengths (at most H): the performance
            the thesis reports for the cart-pole (:meth:`measured_returns`). Note that
            :meth:`safepg.envs.LQG.gradient_batch` returns *discounted* returns instead.
        """
        samples, returns, _ = self._fused_batch(policy, n, rng, estimator, baseline, score_action, peaks=False)
        return samples, returns

    def gradient_batch_constants(
        self,
        policy: LinearGaussianPolicy,
        n: int,
        rng: RNGLike = None,
        estimator: str = "gpomdp",
        baseline: bool = True,
        score_action: str = "clipped",
    ) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
        """:meth:`gradient_batch` and the reward and feature bounds measured on the batch.

        The same batch (the same random numbers) as :meth:`gradient_batch`, plus what the
        authors' cart-pole script put into the penalty constant in place of R and M_phi: the
        largest |reward| and the largest |phi_i(s)| over every state the batch visited, the
        initial states and the states the episodes ended in (the failing state, or s_H)
        included. The learning loop calls it with ``Departures(batch_constants=True)``.

        Returns
        -------
        samples, returns : ndarray
            As :meth:`gradient_batch`.
        maxima : (float, float)
            (R, M_phi) of the batch. R is 1: every episode is rewarded on its first step.
        """
        samples, returns, peak = self._fused_batch(policy, n, rng, estimator, baseline, score_action, peaks=True)
        if self.feature_scale is not None:
            peak = peak / np.asarray(self.feature_scale)
        return samples, returns, (1.0, float(peak.max()))

    def _fused_batch(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike, estimator: str, baseline: bool,
                     score_action: str, peaks: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The fused kernel on a fresh batch: samples, undiscounted returns and (with ``peaks``) each
        trajectory's largest |state component| (else an empty array)."""
        from safepg.envs._cartpole_kernel import cartpole_gradient_samples

        n = self._check_policy_and_n(policy, n)
        check_estimator(estimator)
        check_score_action(score_action)
        rng = as_generator(rng)
        gain = policy.gain[0]
        if self.feature_scale is not None:
            # theta^T (s / scale) = (theta / scale)^T s: the kernel runs on the raw state with
            # the equivalent gain, and the score of theta is the raw-state score / scale
            # (the variance-minimising baselines are unchanged by a per-component scale).
            scale = np.asarray(self.feature_scale)
            gain = gain / scale
        # The wrapper normalises the argument types (one compiled specialisation).
        out = cartpole_gradient_samples(
            gain, policy.cov_chol[0, 0], self.pole_length, self.cart_mass, self.pole_mass, self.gravity,
            self.tau, batch_key(rng), n, self.horizon, self.init_bound, self.gamma, self.action_bound,
            self.x_threshold, self.angle_threshold,
            score_action == "clipped", estimator == "reinforce", baseline,
            semi_implicit=self.integrator == "semi-implicit", polemass_length=self.polemass_length, peaks=peaks)
        samples, returns = out[0], out[1]
        if self.feature_scale is not None:
            samples /= scale
        return samples, returns, out[2] if peaks else np.empty(0)

    def simulate_gain(self, gain: np.ndarray, sigma: float | np.ndarray, n: int,
                      rng: RNGLike = None) -> Trajectories:
        """:meth:`simulate` for the policy N(gain @ s, sigma^2).

        Parameters
        ----------
        gain : array_like, shape (1, 4) or (4,)
            Policy gain K (theta = K.ravel()).
        sigma : float, array_like (1,) or (1, 1)
            Action standard deviation, or a (1, 1) covariance.
        n, rng
            As in :meth:`simulate`.
        """
        K = np.asarray(gain, dtype=float)
        if K.shape == (self.state_dim,):
            K = K[None, :]
        if K.shape != (self.action_dim, self.state_dim):
            raise ValueError(f"gain must have shape (1, 4) or (4,), got {np.shape(gain)}")
        if not np.all(np.isfinite(K)):
            raise ValueError(f"gain must be finite, got {K.ravel()}")
        check_sigma(sigma, self.action_dim)  # raises "sigma ..." errors before the policy does
        return self.simulate(LinearGaussianPolicy(K, sigma), n, rng)

    # ------------------------------------------------------------------- metrics
    @staticmethod
    def undiscounted_returns(batch: Trajectories) -> np.ndarray:
        """Sum of rewards per trajectory = episode length, shape (N,).

        This is the performance the thesis reports for the cart-pole (at most H = 200).
        """
        lengths: np.ndarray = batch.rewards.sum(axis=1)
        return lengths

    def measured_returns(self, batch: Trajectories) -> np.ndarray:
        """The per-trajectory performance the learning loop records (J_hat), shape (N,).

        For the cart-pole this is :meth:`undiscounted_returns`, the episode length the
        thesis reports, not the discounted return the estimators use; it matches the
        second output of :meth:`gradient_batch`.
        """
        return self.undiscounted_returns(batch)


# ---------------------------------------------------------------------- gymnasium
# gymnasium is an optional dependency (``pip install safepg[gym]``): without it the
# batched task above works, ContinuousCartPoleEnv is absent and register_envs does nothing.
try:
    import gymnasium as _gym
    from gymnasium import spaces as _spaces

    _HAVE_GYMNASIUM = True
except ImportError:  # pragma: no cover - exercised only without gymnasium
    _HAVE_GYMNASIUM = False


if _HAVE_GYMNASIUM:

    class ContinuousCartPoleEnv(_gym.Env):
        """Single cart-pole as a gymnasium environment, the same task as :class:`CartPole`.

        The action is a force in N, clipped to [-10, 10] (the action space) before it is
        applied, like the Gaussian samples in :meth:`CartPole.simulate`. Reward 1 per step
        taken from an alive state (the step into the failing state included); the episode
        terminates when |x| > 2.4 or |beta| > 41.8 deg and is truncated after ``horizon``
        steps (internally, so the env behaves the same with or without ``gymnasium.make``).
        Stepping after the end returns reward 0 and the same flags.

        Parameters
        ----------
        render_mode : None
            Rendering is not implemented.
        **task : Any
            Fields of :class:`CartPole` (e.g. ``pole_length=2.0``).

        Notes
        -----
        ``reset(options={"state": s0})`` starts from a given state instead of a uniform
        draw (used to replay the batched simulator's initial states).
        """

        metadata: dict[str, Any] = {"render_modes": []}  # gymnasium.Env's class attribute

        def __init__(self, render_mode: str | None = None, **task: Any) -> None:
            if render_mode is not None:
                raise ValueError(f"render_mode must be None (rendering is not implemented), got {render_mode!r}")
            self.render_mode = render_mode
            self.task = CartPole(**task)
            b = self.task.action_bound
            self.action_space = _spaces.Box(-b, b, shape=(1,), dtype=np.float64)
            # The state leaves the alive region on the terminating step, by an amount that
            # depends on the (unbounded) velocities: no finite box is guaranteed.
            self.observation_space = _spaces.Box(-np.inf, np.inf, shape=(4,), dtype=np.float64)
            self.state: np.ndarray | None = None
            self._t = 0  # steps taken in the current episode
            self._terminated = False
            self._truncated = False

        def reset(self, *, seed: int | None = None,
                  options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
            super().reset(seed=seed)
            if options is not None and "state" in options:
                s0 = np.array(options["state"], dtype=float)
                if s0.shape != (4,) or not np.all(np.isfinite(s0)):
                    raise ValueError(f"options['state'] must be 4 finite numbers, got {options['state']!r}")
            else:
                c = self.task.init_bound
                s0 = self.np_random.uniform(-c, c, size=4)
            self.state = s0
            self._t = 0
            self._terminated = not bool(self.task.alive(s0))  # only possible with options["state"]
            self._truncated = False
            return s0.copy(), {}

        def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
            if self.state is None:
                raise RuntimeError("call reset() before step()")
            a = np.asarray(action, dtype=float).reshape(-1)
            if a.shape != (1,) or not np.isfinite(a[0]):
                raise ValueError(f"action must be one finite force, got {action!r}")
            if self._terminated or self._truncated:  # the episode is over: nothing moves, no reward
                return self.state.copy(), 0.0, self._terminated, self._truncated, {}
            u = float(np.clip(a[0], -self.task.action_bound, self.task.action_bound))
            # The same vectorised step as the batched simulator, on a batch of one.
            self.state = self.task.step(self.state[None, :], u)[0]
            self._t += 1
            self._terminated = not bool(self.task.alive(self.state))
            self._truncated = not self._terminated and self._t >= self.task.horizon
            return self.state.copy(), 1.0, self._terminated, self._truncated, {}

    def gymnasium_step(states: np.ndarray, forces: np.ndarray, pole_length: float = _POLE_LENGTH,
                       integrator: str = "euler", polemass_length: float | None = None) -> np.ndarray:
        """One step of gymnasium's own ``CartPoleEnv`` from each state with each force.

        The independent implementation :func:`step_dynamics` is checked against (tests
        and the cart-pole chapter). gymnasium's env has a fixed force magnitude and a
        binary action, so each step sets ``force_mag = |force|`` and picks the sign with
        the action; its ``length`` is half the pole. One Python step per state: a
        reference, not a simulator.

        Parameters
        ----------
        states : ndarray, shape (n, 4)
        forces : ndarray, shape (n,)
        pole_length : float
            Whole pole length in m.
        integrator : {"euler", "semi-implicit"}
            gymnasium's ``kinematics_integrator`` ``"euler"`` or ``"semi-implicit euler"``.
        polemass_length : float or None
            The env's cached ``polemass_length``; None: ``masspole * length``, consistent with
            ``pole_length``. 0.05 with ``pole_length=2`` is the authors' doubled pole
            (``env.length *= 2`` after construction).
        """
        from gymnasium.envs.classic_control.cartpole import CartPoleEnv

        _check_integrator(integrator)

        S = np.asarray(states, dtype=float).reshape(-1, 4)
        F = np.asarray(forces, dtype=float).reshape(-1)
        if F.shape[0] != S.shape[0]:
            raise ValueError(f"forces must have one entry per state, got {F.shape[0]} for {S.shape[0]} states")
        env = CartPoleEnv()
        env.reset(seed=0)
        env.length = 0.5 * pole_length
        # Cached in __init__: keep it consistent, unless asked for the authors' stale value.
        env.polemass_length = env.masspole * env.length if polemass_length is None else polemass_length
        env.kinematics_integrator = "euler" if integrator == "euler" else "semi-implicit euler"
        out = np.empty_like(S)
        with warnings.catch_warnings():  # stepping "after termination" is what we want here
            warnings.simplefilter("ignore")
            for i, (s, f) in enumerate(zip(S, F)):
                env.state = s.copy()
                env.steps_beyond_terminated = None
                env.force_mag = abs(f)
                env.step(1 if f >= 0 else 0)
                out[i] = env.state
        return out

    def register_envs() -> None:
        """Register :class:`ContinuousCartPoleEnv` as ``"safepg/ContinuousCartPole-v0"``.

        Idempotent. Truncation at H happens inside the env, so no ``max_episode_steps``.
        """
        if ENV_ID not in _gym.registry:
            _gym.register(id=ENV_ID, entry_point="safepg.envs.cartpole:ContinuousCartPoleEnv")

    register_envs()

else:  # pragma: no cover

    def register_envs() -> None:
        """No-op without gymnasium (an optional dependency)."""


__all__ = ["CartPole", "ContinuousCartPoleEnv", "ENV_ID", "INTEGRATORS", "NORMALISED_SCALE", "gymnasium_step",
           "register_envs", "step_dynamics"]
