r"""Linear-quadratic Gaussian regulation (LQG), any dimension (thesis Sections 5.1-5.2).

Dynamics, reward and policy (state noise C_0 = 0, as in the thesis):

.. math::
    s_{t+1} = \operatorname{clip}(A s_t + B u_t), \qquad
    u_t = \operatorname{clip}(a_t), \quad a_t \sim \mathcal N(K s_t, \Sigma), \qquad
    r_t = -\tfrac12\,(s_t^\top Q s_t + u_t^\top R u_t)

with states and actions clipped to boxes and the initial state uniform in the state box.

The closed forms (``performance``, ``gradient``, ``optimal_gain``) are for the
*infinite-horizon, unclipped* problem, which is what the thesis plots as "expected
performance". They are not the objective the clipped, H-step simulator optimises
(see SETTINGS.md and the book's "Beyond the thesis" sections).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np

from safepg import portable
from safepg.estimators import check_estimator, check_score_action
from safepg.policies import LinearGaussianPolicy, check_sigma
from safepg.rng import RNGLike, as_generator
from safepg.streams import batch_key, trajectory_draws
from safepg.tasks import ActionDimension, Definition, FixedStepBatches, GradientBatch, Performance, PerformanceBatch
from safepg.trajectories import Trajectories


def _as_matrix(x: float | np.ndarray, m: int, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        return np.eye(m) * float(a)
    if a.shape != (m, m):
        raise ValueError(f"{name} must be a scalar or a ({m}, {m}) matrix, got shape {a.shape}")
    return a


def _largest_eigenvalue(M: np.ndarray) -> float:
    """lambda_max of a symmetric cost matrix. A diagonal one (every task of the thesis) is
    read off exactly; LAPACK, whose last bit can depend on the CPU, only for the others."""
    if np.count_nonzero(M - np.diag(np.diag(M))) == 0:
        return float(np.max(np.diag(M)))
    return float(np.max(np.linalg.eigvalsh(M)))


@dataclass(frozen=True)
class LQG(GradientBatch, FixedStepBatches, Performance, PerformanceBatch, ActionDimension, Definition):
    """LQG regulation task with box-bounded states and actions.

    Parameters
    ----------
    dim : int
        State and action dimension m.
    gamma : float
        Discount factor in (0, 1).
    horizon : int
        Trajectory length H used by the simulator.
    state_bound, action_bound : float
        Half-widths of the state box [-b_s, b_s]^m and action box [-b_a, b_a]^m.
    A, B, Q, R : float or ndarray (m, m)
        Dynamics and cost matrices (a scalar means that multiple of the identity).
    clip : bool
        Clip actions and next states to their boxes (the thesis's simulator). With
        ``clip=False`` the simulator samples the unbounded problem the closed forms
        describe (used to test them).
    """

    dim: int = 1
    gamma: float = 0.9
    horizon: int = 20
    state_bound: float = 2.0
    action_bound: float = 2.0
    A: np.ndarray | float = 1.0
    B: np.ndarray | float = 1.0
    Q: np.ndarray | float = 1.0
    R: np.ndarray | float = 1.0
    clip: bool = True
    _mats: tuple[np.ndarray, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if int(self.dim) != self.dim or self.dim < 1:
            raise ValueError(f"dim must be a positive integer, got {self.dim}")
        if not 0 < self.gamma < 1:
            raise ValueError(f"gamma must be in (0, 1), got {self.gamma}")
        if int(self.horizon) != self.horizon or self.horizon < 1:
            raise ValueError(f"horizon must be a positive integer, got {self.horizon}")
        # A whole float (dim=2.0) is that integer: it sizes the matrices and ranges over steps.
        object.__setattr__(self, "dim", int(self.dim))
        object.__setattr__(self, "horizon", int(self.horizon))
        for name in ("state_bound", "action_bound"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        mats = tuple(_as_matrix(getattr(self, k), self.dim, k) for k in "ABQR")
        object.__setattr__(self, "_mats", mats)

    def definition(self) -> dict[str, Any]:
        """The fields that make this task, each matrix written out (``A=1.0`` and ``A=[[1.0]]``
        are one task): what a stored run's key hashes (:mod:`safepg.definition`)."""
        A, B, Q, R = self._mats
        return {"dim": self.dim, "gamma": self.gamma, "horizon": self.horizon, "state_bound": self.state_bound,
                "action_bound": self.action_bound, "A": A, "B": B, "Q": Q, "R": R, "clip": self.clip}

    # ------------------------------------------------------------------ settings
    @classmethod
    def thesis_1d(cls, **overrides: Any) -> LQG:
        """The one-dimensional task of Section 5.1 with the settings of SETTINGS.md."""
        return cls(**{"dim": 1, "gamma": 0.9, "horizon": 20, **overrides})

    @classmethod
    def thesis_2d(cls, **overrides: Any) -> LQG:
        """The two-dimensional task of Section 5.2.1 as printed (Q = R = I, gamma = 0.95)."""
        return cls(**{"dim": 2, "gamma": 0.95, "horizon": 20, **overrides})

    # ------------------------------------------------------------ bound constants
    @property
    def reward_bound(self) -> float:
        """R = max |r| over the boxes: 0.5 (lambda_max(Q) m b_s^2 + lambda_max(R) m b_a^2)."""
        _, _, Q, R = self._mats
        q = _largest_eigenvalue(Q) * self.dim * self.state_bound**2
        r = _largest_eigenvalue(R) * self.dim * self.action_bound**2
        return float(0.5 * (q + r))

    @property
    def feature_bound(self) -> float:
        """M_phi: the features are the state, bounded by the state box."""
        return float(self.state_bound)

    @property
    def action_volume(self) -> float:
        """|A|: volume of the action box, (2 b_a)^m."""
        return float((2 * self.action_bound) ** self.dim)

    # ----------------------------------------------------------------- simulator
    @property
    def action_dim(self) -> int:
        """Actions have as many components as states (``dim``)."""
        return self.dim

    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories:
        """Simulate ``n`` trajectories of length H at once.

        Trajectory i reads stream i of one batch key drawn from ``rng``
        (:mod:`!safepg.streams`): its initial state, then its standard normals step by
        step. A seed fixes the batch bit for bit, and :meth:`gradient_batch` sees the same one.
        """
        self._check_policy(policy)
        if int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n}")
        rng = as_generator(rng)
        A, B, Q, R = self._mats
        m, H, bs, ba = self.dim, self.horizon, self.state_bound, self.action_bound
        uniforms, normals = trajectory_draws(batch_key(rng), n, m, H * m)
        s = -bs + (bs + bs) * uniforms  # the fused kernels' uniform on [-bs, bs)
        mm = portable.matmul  # fixed-order products: the batch is the same on every CPU
        raw = mm(normals.reshape(n, H, m), policy.cov_chol.T)
        feats = np.empty((n, H, m))
        acts = np.empty((n, H, m))
        rews = np.empty((n, H))
        # Time is sequential; each step is one whole-array operation over the n trajectories.
        for t in range(H):
            feats[:, t] = s
            raw[:, t] += mm(s, policy.gain.T)
            u = np.clip(raw[:, t], -ba, ba) if self.clip else raw[:, t]
            acts[:, t] = u
            rews[:, t] = -0.5 * (np.sum(mm(s, Q) * s, axis=1) + np.sum(mm(u, R) * u, axis=1))
            s = mm(s, A.T) + mm(u, B.T)
            if self.clip:
                s = np.clip(s, -bs, bs)
        return Trajectories(feats, raw, acts, rews, None, self.gamma)

    def _check_policy(self, policy: LinearGaussianPolicy) -> None:
        if policy.gain.shape != (self.dim, self.dim):
            raise ValueError(
                f"theta must be a ({self.dim}, {self.dim}) gain for this LQG, got {policy.gain.shape}"
            )

    # -------------------------------------------------------------- closed forms
    def _gain(self, theta: np.ndarray | float) -> np.ndarray:
        K = np.asarray(theta, dtype=float)
        if K.size != self.dim**2:
            raise ValueError(f"theta must have {self.dim ** 2} entries, got {K.size}")
        if not np.all(np.isfinite(K)):
            raise ValueError("theta must be finite")
        return K.reshape(self.dim, self.dim)

    def initial_second_moment(self) -> np.ndarray:
        """E[s_0 s_0^T] for s_0 uniform in the state box: diag(b_s^2 / 3)."""
        return np.eye(self.dim) * self.state_bound**2 / 3

    def is_stable(self, theta: np.ndarray | float) -> bool:
        """Whether sqrt(gamma) (A + B K) is a contraction, so J(theta) is finite."""
        return bool(self._stable(self._gain(theta)[None])[0])

    def _stable(self, K: np.ndarray) -> np.ndarray:
        """:meth:`is_stable` for a batch of gains K, shape (I, m, m) -> (I,) bool."""
        A, B, _, _ = self._mats
        F = A + portable.matmul(B, K)
        if self.dim == 1:
            radius = np.abs(F[:, 0, 0])
        else:
            # LAPACK's eigenvalues may differ across CPUs in the last bit; only the yes/no
            # answer is used, and it could flip only for a gain exactly on the boundary.
            radius = np.max(np.abs(np.linalg.eigvals(F)), axis=1)
        stable: np.ndarray = radius * np.sqrt(self.gamma) < 1
        return stable

    def _lyapunov(self, F: np.ndarray, M: np.ndarray) -> np.ndarray:
        r"""P solving :math:`P = M + \gamma F^\top P F` for a batch (I, m, m) of F and M.

        Solved as the linear system :math:`(I - \gamma F^\top\otimes F^\top)\,\mathrm{vec}(P)
        = \mathrm{vec}(M)` by :func:`safepg.portable.solve`, so J comes out bit-identical on
        every CPU (scipy's and NumPy's solvers go through BLAS; see :mod:`safepg.portable`).
        """
        d = self.dim
        Ft = np.swapaxes(F, 1, 2)
        kron = (Ft[:, :, None, :, None] * Ft[:, None, :, None, :]).reshape(-1, d * d, d * d)
        P = portable.solve(np.eye(d * d) - self.gamma * kron, M.reshape(-1, d * d, 1)).reshape(-1, d, d)
        return 0.5 * (P + np.swapaxes(P, 1, 2))

    def _value_matrices(self, K: np.ndarray) -> np.ndarray:
        """:meth:`value_matrix` for a batch of stable gains K, shape (I, m, m)."""
        A, B, Q, R = self._mats
        F = A + portable.matmul(B, K)
        M = 0.5 * (Q + portable.matmul(portable.matmul(np.swapaxes(K, 1, 2), R), K))
        return self._lyapunov(F, M)

    def value_matrix(self, theta: np.ndarray | float) -> np.ndarray:
        r"""P solving the discounted Lyapunov equation

        .. math:: P = \tfrac12 (Q + K^\top R K) + \gamma (A + BK)^\top P (A + BK),

        so that V(s) = -s^T P s - v_0 for the unclipped infinite-horizon problem.
        """
        K = self._gain(theta)
        if not self.is_stable(K):
            raise ValueError("theta makes the closed loop unstable: J(theta) = -inf")
        P: np.ndarray = self._value_matrices(K[None])[0]
        return P

    def performance(self, theta: np.ndarray | float, sigma: float | np.ndarray) -> float:
        r"""Closed-form expected performance J(theta) (infinite horizon, no clipping).

        .. math::
            J(\theta) = -\operatorname{tr}(P\,\mathbb E[s_0 s_0^\top])
                        - \frac{\tfrac12\operatorname{tr}(R\Sigma)
                                + \gamma\operatorname{tr}(B^\top P B \Sigma)}{1-\gamma}

        In one dimension this is SETTINGS.md's
        J = -(b^2/3) P - sigma^2 (0.5 + gamma P) / (1 - gamma),
        P = 0.5 (1 + theta^2) / (1 - gamma (1 + theta)^2). Returns -inf if unstable.
        """
        K = self._gain(theta)
        return float(self.performance_batch(K.reshape(1, -1), sigma)[0])

    def performance_batch(self, thetas: np.ndarray, sigma: float | np.ndarray) -> np.ndarray:
        r""":meth:`performance` for many parameters at once, shape (I,).

        The learning loops record J(theta_i) at every iteration; a run with a small fixed
        batch has 10^5 iterations, so the Lyapunov equations are solved together as one
        batched linear system, :math:`(I - \gamma F^\top\otimes F^\top)\,\mathrm{vec}(P)
        = \mathrm{vec}(\tfrac12(Q + K^\top R K))` with :math:`F = A + BK`.

        Parameters
        ----------
        thetas : ndarray, shape (I, m * m)
            One flattened gain per row.
        sigma : float or ndarray
            Policy standard deviation (or covariance), as in :meth:`performance`.
        """
        d = self.dim
        T = np.asarray(thetas, dtype=float)
        if T.ndim != 2 or T.shape[1] != d * d:
            raise ValueError(f"thetas must have shape (I, {d * d}), got {T.shape}")
        if not np.all(np.isfinite(T)):
            raise ValueError("thetas must be finite")
        _, B, _, R = self._mats
        S = check_sigma(sigma, d)
        K = T.reshape(-1, d, d)
        stable = self._stable(K)
        # Unstable rows get K = 0 (a regular system); they are -inf below.
        K = np.where(stable[:, None, None], K, 0.0)
        P = self._value_matrices(K)
        mm = portable.matmul
        noise = 0.5 * portable.trace(mm(R, S)) + self.gamma * portable.trace(mm(mm(mm(B.T, P), B), S))
        J = -portable.trace(mm(P, self.initial_second_moment())) - noise / (1 - self.gamma)
        return np.where(stable, J, -np.inf)

    def gradient(self, theta: np.ndarray | float, sigma: float | np.ndarray) -> np.ndarray:
        r"""Closed-form policy gradient :math:`\nabla_\theta J`, flattened like theta.

        Differentiating the Lyapunov equation gives

        .. math:: \nabla_K J = -\big(R K + 2\gamma B^\top P (A + BK)\big)\, Y,
                  \qquad Y = W + \gamma (A+BK)\, Y\, (A+BK)^\top,

        with :math:`W = \mathbb E[s_0 s_0^\top] + \gamma B\Sigma B^\top/(1-\gamma)`.
        """
        A, B, _, R = self._mats
        mm = portable.matmul
        K = self._gain(theta)
        S = check_sigma(sigma, self.dim)
        P = self.value_matrix(K)
        F = A + mm(B, K)
        W = self.initial_second_moment() + self.gamma * mm(mm(B, S), B.T) / (1 - self.gamma)
        Y = self._lyapunov(F.T[None], W[None])[0]  # Y = W + gamma F Y F^T
        return (-mm(mm(R, K) + 2 * self.gamma * mm(mm(B.T, P), F), Y)).ravel()

    def optimal_gain(self, tol: float = 1e-14, max_iter: int = 100_000) -> np.ndarray:
        r"""Optimal gain K* (the thesis's theta*) by Riccati value iteration.

        .. math::
            P \leftarrow \tfrac12 Q + \gamma A^\top P A - \gamma^2 A^\top P B
                         (\tfrac12 R + \gamma B^\top P B)^{-1} B^\top P A, \qquad
            K^* = -\gamma (\tfrac12 R + \gamma B^\top P B)^{-1} B^\top P A

        The policy noise adds a constant to J, so K* does not depend on Sigma.
        """
        A, B, Q, R = self._mats
        mm, g = portable.matmul, self.gamma

        def gain(P: np.ndarray) -> np.ndarray:
            return portable.solve(0.5 * R + g * mm(mm(B.T, P), B), g * mm(mm(B.T, P), A))

        P = 0.5 * Q
        for _ in range(max_iter):
            P_new = 0.5 * Q + g * mm(mm(A.T, P), A) - g * mm(mm(mm(A.T, P), B), gain(P))
            if np.max(np.abs(P_new - P)) < tol * max(1.0, np.max(np.abs(P))):
                P = P_new
                break
            P = P_new
        return -gain(P)

    # ------------------------------------------------------------------ fast path
    def gradient_batch(
        self,
        policy: LinearGaussianPolicy,
        n: int,
        rng: RNGLike = None,
        estimator: str = "gpomdp",
        baseline: bool = True,
        score_action: str = "clipped",
    ) -> tuple[np.ndarray, np.ndarray]:
        """Gradient samples (n, m) and discounted returns (n,) of a fresh batch, fused.

        Same random numbers as :meth:`simulate` (one batch key from ``rng``), and the same numbers
        as ``gradient_samples(policy, simulate(...), ...)`` up to rounding, without
        materialising the trajectories (see :mod:`!safepg.envs._lqg_kernel`).
        """
        from safepg.envs import _lqg_kernel as kernels

        self._check_policy(policy)
        if int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n}")
        check_estimator(estimator)
        check_score_action(score_action)
        rng = as_generator(rng)
        A, B, Q, R = self._mats
        head = (batch_key(rng), int(n), int(self.horizon))
        flags = (float(self.gamma), float(self.state_bound), float(self.action_bound), bool(self.clip),
                 score_action == "clipped", estimator == "reinforce", bool(baseline))
        # One chunk, or one thread (a campaign's worker): the serial build, the same numbers.
        serial = n <= kernels.CHUNK or numba.get_num_threads() == 1
        out: tuple[np.ndarray, np.ndarray]  # (samples, returns)
        if self.dim == 1:
            kernel = kernels.lqg1d_gradient_samples_serial if serial else kernels.lqg1d_gradient_samples
            out = kernel(float(policy.gain[0, 0]), float(policy.cov_chol[0, 0]),
                         float(A[0, 0]), float(B[0, 0]), float(Q[0, 0]), float(R[0, 0]), *head, *flags)
            return out
        # m = 2 (Section 5.2) has its own unrolled kernel; m >= 3 uses the generic loops.
        if self.dim == 2:
            kernel = kernels.lqg2d_gradient_samples_serial if serial else kernels.lqg2d_gradient_samples
        else:
            kernel = kernels.lqg_gradient_samples_serial if serial else kernels.lqg_gradient_samples
        # Writable copies: numba would compile the kernel again for a read-only array (a policy's gain).
        K, L, P = (np.array(a, dtype=np.float64) for a in (policy.gain, policy.cov_chol, policy.precision))
        out = kernel(K, L, P, A, B, Q, R, *head, *flags)
        return out

    def fixed_step_batches(
        self,
        policy: LinearGaussianPolicy,
        sizes: np.ndarray,
        keys: np.ndarray,
        alpha: float,
        kind: str = "scalar",
        estimator: str = "gpomdp",
        baseline: bool = True,
        score_action: str = "clipped",
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r"""Consecutive batches of vanilla policy gradient with a fixed step, in one compiled loop.

        Batch i draws ``sizes[i]`` trajectories with batch key ``keys[i]`` (the numbers
        :meth:`gradient_batch` draws with that key), and
        :math:`\theta_{i+1} = \theta_i + \alpha\hat\nabla J` (``kind="scalar"``) or only the
        first largest component moves (``"coordinate"``), in the order and with the bits of
        :func:`safepg.learning.vanilla_pg`'s loop (see :mod:`!safepg.envs._lqg_fixed_step`).

        Returns
        -------
        thetas : ndarray, shape (b + 1, m)
            The parameters before each batch, then the last ones; b rows only when the last
            gradient is not finite (no step was taken).
        grads : ndarray, shape (b, m)
            Each batch's gradient estimate.
        j_hat : ndarray, shape (b,)
            Each batch's mean discounted return.

        The loop stops after the first batch whose gradient, or whose new parameters, are not
        finite (b < ``len(keys)``); the caller decides what that means.
        """
        from safepg.envs._lqg_fixed_step import FIXED_STEP_BATCHES

        self._check_policy(policy)
        sizes = np.asarray(sizes, dtype=np.int64)
        keys = np.asarray(keys, dtype=np.uint64)
        if sizes.ndim != 1 or keys.shape != sizes.shape:
            raise ValueError(f"keys must have the shape of sizes {sizes.shape}, got {keys.shape}")
        if sizes.size and sizes.min() < 1:
            raise ValueError(f"sizes must be positive integers, got {sizes.min()}")
        if kind not in ("scalar", "coordinate"):
            raise ValueError(f"kind must be 'scalar' or 'coordinate', got {kind!r}")
        check_estimator(estimator)
        check_score_action(score_action)
        A, B, Q, R = self._mats
        loop = FIXED_STEP_BATCHES.get(self.dim, FIXED_STEP_BATCHES[0])
        out: tuple[np.ndarray, np.ndarray, np.ndarray] = loop(
            policy.gain.ravel().copy(), policy.cov_chol, policy.precision, A, B, Q, R, keys, sizes,
            int(self.horizon), float(self.gamma), float(self.state_bound), float(self.action_bound), bool(self.clip),
            score_action == "clipped", estimator == "reinforce", bool(baseline), float(alpha), kind == "coordinate")
        return out


__all__ = ["LQG"]
