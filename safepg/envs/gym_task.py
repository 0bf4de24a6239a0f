r"""Any gymnasium environment with ``Box`` observations and actions as a safe-PG task.

:class:`GymTask` wraps a gymnasium environment (an id or a factory) so that
:func:`safepg.learning.adaptive_pg` and :func:`safepg.learning.vanilla_pg` accept it: it
simulates N episodes at once through gymnasium's vector API and exposes the constants
the bounds of Chapter 4 are written in. It is the core used as a library; the thesis's
reproduction (:mod:`safepg.thesis`) does not use it.

Episode model, with :math:`\phi` the feature map (default: the flattened observation):

.. math::
    a_t \sim \mathcal N\big(K\phi(o_t), \Sigma\big), \qquad
    u_t = \operatorname{clip}(a_t, \text{low}, \text{high}), \qquad
    (o_{t+1}, r_t, \text{end}_t) = \text{env.step}(u_t),

for t = 0, ..., H-1, where end_t is gymnasium's ``terminated or truncated``. Step t is
alive (``mask[:, t]``) iff no earlier step ended the episode, so the step into the
terminal state is still rewarded (as in gymnasium and :class:`~safepg.envs.cartpole.CartPole`)
and every later step has reward, features and actions 0.

gymnasium is an optional dependency (``pip install safepg[gym]``): this module imports
without it, and :class:`GymTask` raises ``ImportError`` when constructed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from safepg import portable
from safepg.constants import HORIZON_TERMS
from safepg.policies import LinearGaussianPolicy
from safepg.rng import RNGLike, as_generator
from safepg.tasks import ActionDimension, ConstantsSettings, Definition, FromDefinition, MeasuredReturns
from safepg.trajectories import Trajectories

if TYPE_CHECKING:  # pragma: no cover
    import gymnasium

#: A vectorised feature map: observations (N, d_obs) -> features (N, d_phi).
FeatureMap = Callable[[np.ndarray], np.ndarray]


def with_bias(obs: np.ndarray) -> np.ndarray:
    r"""Observation plus a constant feature: :math:`\phi(o) = (o, 1)`, shape (N, d_obs + 1).

    With it the policy mean :math:`K\phi(o) = K_{:, :d} o + K_{:, d}` has an offset, so
    M_phi = max(observation bound, 1).
    """
    obs = np.asarray(obs, dtype=float)
    return np.concatenate([obs, np.ones(obs.shape[:-1] + (1,))], axis=-1)


def _returning(env: gymnasium.Env) -> Callable[[], gymnasium.Env]:
    """A factory of ``env`` itself: the vector env steps the pool's environments, not copies."""
    return lambda: env


def _check_positive(name: str, value: float | None) -> float | None:
    if value is None:
        return None
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be finite and > 0 or None, got {value!r}")
    return v


def _constant_missing(name: str, what: str) -> ValueError:
    return ValueError(
        f"{name} must be given: {what}. GymTask(...) cannot infer it from the environment, and the "
        f"safe-PG bounds (penalty constant, error bounds) need it; adaptive_pg and vanilla_pg read it "
        f"when they start."
    )


class GymTask(MeasuredReturns, ActionDimension, ConstantsSettings, Definition, FromDefinition):
    r"""A gymnasium environment (``Box`` observations and actions) as a safe-PG task.

    ``simulate(policy, n, rng)`` runs n episodes of horizon H at once in a
    :class:`!gymnasium.vector.SyncVectorEnv` (one vectorised ``step`` over all n
    environments per time step) with the linear Gaussian policy

    .. math:: a_t \sim \mathcal N\big(K\phi(o_t), \Sigma\big), \qquad
              u_t = \operatorname{clip}(a_t, \text{low}, \text{high}),

    and returns :class:`~safepg.trajectories.Trajectories` with ``actions_raw`` = a_t,
    ``actions`` = u_t (the action the environment received, in its dtype) and the alive
    ``mask``. The learning loops' ``score_action`` picks which one is scored, as for the
    LQG: ``"clipped"`` (their default) scores u_t, which is biased while clipping is
    active; ``"raw"`` scores a_t, the unbiased likelihood-ratio estimator.

    The bound constants are the thesis's (Assumption 4.2.1, Theorem 4.2.3, Lemma 4.3.3):
    the penalty constant

    .. math:: c = \frac{R M_\phi^2}{(1-\gamma)^2\sigma^2}
              \Big(\frac{|\mathcal A|}{\sqrt{2\pi}\,\sigma} + \frac{\gamma}{2(1-\gamma)}\Big)

    needs R, M_phi, |A|, gamma (and H, A-bar for the ranges of Hoeffding and Bernstein).

    Parameters
    ----------
    env : str or callable
        A registered gymnasium id (made with ``gymnasium.make(env, **env_kwargs)``) or a
        zero-argument factory returning a fresh ``gymnasium.Env``. Its observation and
        action spaces must be ``Box`` es.
    horizon : int
        H: every episode is cut after H steps. For an id, ``max_episode_steps`` defaults
        to H, so gymnasium's own time limit does not end episodes earlier; an episode a
        factory's env truncates sooner is masked from there on, like a terminated one.
    gamma : float
        Discount factor in (0, 1] (the bounds with ``horizon_term="effective"`` need < 1).
    reward_bound : float, optional
        R, a bound on |r_t| over every reachable state and action.
    feature_bound : float, optional
        M_phi, a bound on |phi_i(o)| over every reachable observation.
    action_volume : float, optional
        |A|, the volume of the action space; default: the Box's volume prod(high - low)
        when the Box is bounded.
    action_bound : float, optional
        A-bar, a bound on |u_i| (Lemma 4.3.3); default max(|low|, |high|) when bounded.
    features : callable, optional
        Vectorised feature map phi: observations (N, d_obs) float64 -> features
        (N, d_phi). Default: the flattened observation. See :func:`!safepg.envs.gym_task.with_bias`.
    horizon_term : {"effective", "truncated", "horizon"}
        The horizon factor of the penalty constant (see
        :class:`~safepg.constants.TaskConstants`). With ``constants_gamma`` (always None: the
        constants are written in ``gamma``) it is the task's :class:`~safepg.tasks.ConstantsSettings`.
    measure : {"discounted", "undiscounted"}
        What the learning loops record as J_hat (``measured_returns``): the discounted
        return (default, what the estimators optimise) or the plain sum of rewards
        (gymnasium's usual episode score).
    env_kwargs : dict, optional
        Keyword arguments of ``gymnasium.make`` (only with an id).
    reset_options : dict, optional
        ``options`` of every episode's ``reset`` (e.g. Pendulum-v1's
        ``{"x_init": 0.3, "y_init": 0.3}``, the half-widths of its initial angle and speed).
    name, features_name : str, optional
        The names a factory ``env`` and the feature map enter a stored run's definition by
        (:meth:`definition`). A function defined at the top of a module needs none (its
        ``module:qualname`` is its name); a lambda or a nested function does, and its name
        must change whenever the function does: the stored runs are found by it.

    Raises
    ------
    ValueError
        At construction: ``horizon`` or ``gamma`` invalid (simulation needs them), a given
        constant not finite and > 0, non-Box spaces, or a feature map that does not return
        (N, d_phi). When a bound constant is read (the learning loops
        read all of them when they start, see below): ``"reward_bound must be given: ..."``
        and likewise ``feature_bound``, and ``action_volume`` / ``action_bound`` when the
        action Box is unbounded.

    Notes
    -----
    Missing R and M_phi are reported where they are needed, not at construction, so a
    task without them can still simulate and estimate J by Monte Carlo. Both learning
    loops need them: they compute the penalty constant when they start, even
    ``vanilla_pg`` with a ``FixedStep`` (where it is only recorded in the config).

    Seeding: ``simulate`` draws, from ``rng`` and in this order, one 63-bit seed per
    episode (passed to the vector env's ``reset``) and then an (n, H, d_a) array of
    standard normals for the policy noise. The environments use no other randomness, so
    the same Generator state gives the same batch.

    Unlike the thesis's tasks (:class:`~safepg.envs.LQG`, the cart-pole), whose
    arithmetic is pinned down by :mod:`!safepg.portable`, the numbers here are not
    guaranteed bit-identical across CPUs: gymnasium's dynamics use NumPy and libm
    (``sin``, ``cos``, ...), whose last bits may differ. On one machine a seed still
    reproduces the batch exactly. The thesis layer (:mod:`!safepg.thesis`) does not use
    this class.

    The task has no closed-form J, so ``LearningRecord.J`` is NaN; ``J_hat`` holds the
    per-batch means of ``measured_returns``. The environments are made once, reused for
    every batch (a pool grown to the largest n so far) and released by :meth:`close`.
    """

    def __init__(
        self,
        env: str | Callable[[], gymnasium.Env],
        *,
        horizon: int,
        gamma: float,
        reward_bound: float | None = None,
        feature_bound: float | None = None,
        action_volume: float | None = None,
        action_bound: float | None = None,
        features: FeatureMap | None = None,
        horizon_term: str = "effective",
        measure: Literal["discounted", "undiscounted"] = "discounted",
        env_kwargs: dict[str, Any] | None = None,
        reset_options: dict[str, Any] | None = None,
        name: str | None = None,
        features_name: str | None = None,
    ) -> None:
        try:
            from gymnasium import spaces
        except ImportError as exc:  # pragma: no cover - only without the optional dependency
            raise ImportError("GymTask needs gymnasium: pip install 'safepg[gym]'") from exc

        if isinstance(horizon, bool) or not isinstance(horizon, int | np.integer) or horizon < 1:
            raise ValueError(f"horizon must be a positive integer, got {horizon!r}")
        if isinstance(gamma, bool) or not isinstance(gamma, int | float | np.floating) or not 0 < gamma <= 1:
            raise ValueError(f"gamma must be in (0, 1], got {gamma!r}")
        if horizon_term not in HORIZON_TERMS:
            raise ValueError(f"horizon_term must be one of {HORIZON_TERMS}, got {horizon_term!r}")
        if measure not in ("discounted", "undiscounted"):
            raise ValueError(f"measure must be 'discounted' or 'undiscounted', got {measure!r}")
        self.horizon = int(horizon)
        self.gamma = float(gamma)
        self._horizon_term = horizon_term
        self.measure = measure
        self.reset_options = None if reset_options is None else dict(reset_options)
        self._reward_bound = _check_positive("reward_bound", reward_bound)
        self._feature_bound = _check_positive("feature_bound", feature_bound)
        self._action_volume = _check_positive("action_volume", action_volume)
        self._action_bound = _check_positive("action_bound", action_bound)

        if isinstance(env, str):
            self.env_id: str | None = env
            self.env_kwargs = {"max_episode_steps": self.horizon, **(env_kwargs or {})}
        elif callable(env):
            if env_kwargs:
                raise ValueError("env_kwargs must be None with an environment factory (pass them to the factory)")
            self.env_id, self.env_kwargs = None, {}
        else:
            raise ValueError(f"env must be a gymnasium id or a factory of environments, got {env!r}")
        self._source = env
        self.name = name
        self.features_name = features_name
        self._env_name = env if isinstance(env, str) else getattr(env, "__qualname__", repr(env))

        first = self._make()
        self._pool: list[gymnasium.Env] = [first]
        obs_space, act_space = first.observation_space, first.action_space
        if not isinstance(obs_space, spaces.Box) or not isinstance(act_space, spaces.Box):
            first.close()
            name, space = ("observation_space", obs_space) if not isinstance(obs_space, spaces.Box) else (
                "action_space", act_space)
            raise ValueError(f"{name} must be a gymnasium Box, got {space!r}")
        self.observation_space: spaces.Box = obs_space
        self.action_space: spaces.Box = act_space
        self.obs_dim = math.prod(obs_space.shape)
        self._action_dim = math.prod(act_space.shape)
        self._low = np.asarray(act_space.low, dtype=np.float64).reshape(-1)
        self._high = np.asarray(act_space.high, dtype=np.float64).reshape(-1)
        self._bounded = bool(np.all(np.isfinite(self._low)) and np.all(np.isfinite(self._high)))

        self._features = features
        obs0, _ = first.reset(seed=0, options=self._options())  # any real observation, to size the feature map
        phi0 = self.features(np.asarray(obs0, dtype=float).reshape(1, -1))
        self.feature_dim = int(phi0.shape[1])
        self._vec: gymnasium.vector.SyncVectorEnv | None = None

    def _make(self) -> gymnasium.Env:
        """A fresh environment."""
        if not isinstance(self._source, str):
            return self._source()
        import gymnasium

        return gymnasium.make(self._source, **self.env_kwargs)

    @property
    def action_dim(self) -> int:
        """d_a, the number of components of the action Box."""
        return self._action_dim

    # ------------------------------------------------------------ bound constants
    @property
    def horizon_term(self) -> str:
        """The horizon factor of the penalty constant, as given (:class:`~safepg.tasks.ConstantsSettings`)."""
        return self._horizon_term

    @property
    def constants_gamma(self) -> None:
        """None: the constants are written in the task's ``gamma`` (:class:`~safepg.tasks.ConstantsSettings`)."""
        return None

    @property
    def reward_bound(self) -> float:
        """R: bound on |r_t| (constructor argument; ``ValueError`` if it was not given)."""
        if self._reward_bound is None:
            raise _constant_missing("reward_bound", "a bound R on |r_t| over every reachable state and action")
        return self._reward_bound

    @property
    def feature_bound(self) -> float:
        """M_phi: bound on |phi_i(o)| (constructor argument; ``ValueError`` if it was not given)."""
        if self._feature_bound is None:
            raise _constant_missing("feature_bound", "a bound M_phi on |phi_i(o)| over every reachable observation")
        return self._feature_bound

    @property
    def action_volume(self) -> float:
        """|A|: the given value, else the Box's volume prod(high - low) when it is bounded."""
        if self._action_volume is not None:
            return self._action_volume
        if not self._bounded:
            raise _constant_missing("action_volume", "the volume |A| of the action space (the action Box is unbounded)")
        return float(math.prod((self._high - self._low).tolist()))

    @property
    def action_bound(self) -> float:
        """A-bar: the given value, else max(|low|, |high|) of the Box when it is bounded."""
        if self._action_bound is not None:
            return self._action_bound
        if not self._bounded:
            raise _constant_missing("action_bound", "a bound A-bar on |u_i| (the action Box is unbounded)")
        return float(max(np.max(np.abs(self._low)), np.max(np.abs(self._high))))

    # ------------------------------------------------------------------ features
    def features(self, obs: np.ndarray) -> np.ndarray:
        """phi for a batch of observations (N, ...) -> (N, d_phi), float64."""
        obs = np.asarray(obs, dtype=float).reshape(len(obs), -1)
        if self._features is None:
            return obs
        phi = np.asarray(self._features(obs), dtype=float)
        if phi.ndim != 2 or phi.shape[0] != obs.shape[0]:
            raise ValueError(f"features must map ({obs.shape[0]}, d_obs) observations to ({obs.shape[0]}, d_phi), "
                             f"got shape {phi.shape}")
        return phi

    # ----------------------------------------------------------------- simulator
    def _vector_env(self, n: int) -> gymnasium.vector.SyncVectorEnv:
        """A SyncVectorEnv over the first n environments of the pool (grown as needed)."""
        from gymnasium.vector import AutoresetMode, SyncVectorEnv

        if self._vec is not None and self._vec.num_envs == n:
            return self._vec
        while len(self._pool) < n:
            self._pool.append(self._make())
        # NEXT_STEP autoreset: a sub-env whose episode ended is reset on the following step;
        # those steps are dead (masked) anyway.
        self._vec = SyncVectorEnv([_returning(e) for e in self._pool[:n]], copy=False,
                                  autoreset_mode=AutoresetMode.NEXT_STEP)
        return self._vec

    def _options(self) -> dict[str, Any] | None:
        """A fresh copy of ``reset_options`` (the vector env's reset may pop keys from it)."""
        return None if self.reset_options is None else dict(self.reset_options)

    def _check_policy(self, policy: LinearGaussianPolicy) -> None:
        if policy.gain.shape != (self.action_dim, self.feature_dim):
            raise ValueError(f"theta must be a ({self.action_dim}, {self.feature_dim}) gain for this task, "
                             f"got {policy.gain.shape}")

    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories:
        r"""Simulate n episodes of horizon H at once.

        Parameters
        ----------
        policy : LinearGaussianPolicy
            Gain K of shape (d_a, d_phi).
        n : int
            Number of episodes N.
        rng : Generator, int or None
            Source of the env seeds and the policy noise (see the class notes).

        Returns
        -------
        Trajectories
            features (N, H, d_phi), actions_raw and actions (N, H, d_a), rewards (N, H),
            mask (N, H): 0 / False from the step after the one that ended an episode.
        """
        self._check_policy(policy)
        if isinstance(n, bool) or int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n!r}")
        n = int(n)
        rng = as_generator(rng)
        seeds = rng.integers(0, np.iinfo(np.int64).max, size=n, dtype=np.int64)
        noise = portable.matmul(rng.standard_normal((n, self.horizon, self.action_dim)), policy.cov_chol.T)
        H, d_a = self.horizon, self.action_dim
        feats = np.zeros((n, H, self.feature_dim))
        raw = np.zeros((n, H, d_a))
        acts = np.zeros((n, H, d_a))
        rews = np.zeros((n, H))
        mask = np.zeros((n, H), dtype=bool)
        shape, dtype = self.action_space.shape, self.action_space.dtype

        vec = self._vector_env(n)
        obs, _ = vec.reset(seed=[int(s) for s in seeds], options=self._options())
        alive = np.ones(n, dtype=bool)
        for t in range(H):  # time is sequential; each step is one call over all n environments
            phi = self.features(obs)
            a = policy.mean(phi) + noise[:, t]
            # What the environment receives: clipped to the Box, in the Box's dtype.
            u = np.clip(a, self._low, self._high).astype(dtype).reshape((n,) + shape)
            # Stored before stepping: with copy=False, obs (and so phi) is the vector env's buffer.
            live = alive[:, None]
            feats[:, t] = np.where(live, phi, 0.0)
            raw[:, t] = np.where(live, a, 0.0)
            acts[:, t] = np.where(live, u.reshape(n, d_a), 0.0)
            obs, r, terminated, truncated, _ = vec.step(u)
            rews[:, t] = np.where(alive, r, 0.0)
            mask[:, t] = alive
            alive = alive & ~(np.asarray(terminated) | np.asarray(truncated))
            if not alive.any():  # the remaining steps stay 0 / False
                break
        return Trajectories(feats, raw, acts, rews, mask, self.gamma)

    def measured_returns(self, batch: Trajectories) -> np.ndarray:
        """Per-episode performance the learning loops record as J_hat, shape (N,).

        The discounted return, or the sum of rewards with ``measure="undiscounted"``.
        """
        if self.measure == "undiscounted":
            lengths: np.ndarray = batch.rewards.sum(axis=1)
            return lengths
        return batch.discounted_returns()

    # --------------------------------------------------------------------- misc
    def close(self) -> None:
        """Close every environment made so far (a later ``simulate`` makes new ones)."""
        for e in self._pool:
            e.close()
        self._pool = []
        self._vec = None

    def definition(self) -> dict[str, Any]:
        """The keyword arguments that make this task again: what a stored run's key hashes.

        An id enters as ``env``, a factory as ``env_factory``: its ``name``, else its
        ``module:qualname``; the feature map likewise (``features_name``).

        Raises
        ------
        safepg.definition.UnnamedError
            The factory or the feature map is a lambda or a nested function without a name.
        """
        from safepg.definition import function_name

        source: dict[str, Any]
        if isinstance(self._source, str):
            kwargs = {k: v for k, v in self.env_kwargs.items() if k != "max_episode_steps" or v != self.horizon}
            source = {"env": self._source, "env_kwargs": kwargs or None}
        else:
            source = {"env_factory": self.name or function_name(self._source)}
        features = None if self._features is None else self.features_name or function_name(self._features)
        return {**source, "horizon": self.horizon, "gamma": self.gamma, "reward_bound": self._reward_bound,
                "feature_bound": self._feature_bound, "action_volume": self._action_volume,
                "action_bound": self._action_bound, "features": features, "horizon_term": self.horizon_term,
                "measure": self.measure, "reset_options": self.reset_options}

    @classmethod
    def from_definition(cls, *, env: str | None = None, env_factory: str | None = None, features: str | None = None,
                        **kwargs: Any) -> GymTask:
        """The task :meth:`definition` describes (factories and feature maps imported by name)."""
        from safepg.definition import import_name

        if (env is None) == (env_factory is None):
            raise ValueError("exactly one of env and env_factory must be given")
        source = env if env is not None else import_name(str(env_factory))
        return cls(source, features=None if features is None else import_name(features), **kwargs)

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the environments (for process pools); they are made again on use."""
        state = dict(self.__dict__)
        state["_pool"], state["_vec"] = [], None
        return state

    def __repr__(self) -> str:
        given = {"reward_bound": self._reward_bound, "feature_bound": self._feature_bound,
                 "action_volume": self._action_volume, "action_bound": self._action_bound}
        extra = "".join(f", {k}={v!r}" for k, v in given.items() if v is not None)
        feats = "" if self._features is None else f", features={getattr(self._features, '__name__', '?')}"
        opts = "" if self.reset_options is None else f", reset_options={self.reset_options!r}"
        return (f"GymTask({self._env_name!r}, horizon={self.horizon}, gamma={self.gamma!r}{extra}{feats}{opts}, "
                f"horizon_term={self.horizon_term!r}, measure={self.measure!r})")


__all__ = ["FeatureMap", "GymTask", "with_bias"]
