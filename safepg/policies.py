"""Linear Gaussian policy pi_theta(a | s) = N(a; K phi(s), Sigma) with fixed covariance.

The parameter vector theta is the row-major flattening of the gain matrix K
(shape (d_a, d_phi)), so for a scalar action theta^T phi(s) is the thesis's mean
(Section 2.3.13).
"""

from __future__ import annotations

import numpy as np

from safepg import portable
from safepg.rng import RNGLike, as_generator


def check_sigma(sigma: float | np.ndarray, action_dim: int) -> np.ndarray:
    """Return the covariance matrix for ``sigma`` (a std, a vector of stds or a covariance)."""
    s = np.asarray(sigma, dtype=float)
    if not np.all(np.isfinite(s)):
        raise ValueError(f"sigma must be finite, got {sigma!r}")
    if s.ndim == 0:
        if s <= 0:
            raise ValueError(f"sigma must be > 0, got {float(s)}")
        return np.eye(action_dim) * float(s) ** 2
    if s.ndim == 1:
        if s.shape != (action_dim,):
            raise ValueError(f"sigma must have shape ({action_dim},), got {s.shape}")
        if np.any(s <= 0):
            raise ValueError(f"sigma must be > 0, got {s}")
        return np.diag(s**2)
    if s.shape != (action_dim, action_dim):
        raise ValueError(f"sigma must be ({action_dim}, {action_dim}) covariance, got {s.shape}")
    if not np.allclose(s, s.T) or np.any(np.linalg.eigvalsh(s) <= 0):
        raise ValueError("sigma covariance must be symmetric positive definite")
    return s


class LinearGaussianPolicy:
    r"""Gaussian policy with mean linear in the features and fixed covariance.

    .. math:: \pi_\theta(a \mid s) = \mathcal N\big(a;\ K\phi(s),\ \Sigma\big),
              \qquad \theta = \operatorname{vec}(K)

    Parameters
    ----------
    gain : array_like, shape (d_a, d_phi) or (d_phi,)
        Gain matrix K; a 1-D array is a single-action policy (d_a = 1).
    sigma : float, array_like (d_a,) or (d_a, d_a)
        Standard deviation (scalar or per action) or full covariance Sigma.
    """

    def __init__(self, gain: np.ndarray | float, sigma: float | np.ndarray) -> None:
        K = np.atleast_2d(np.asarray(gain, dtype=float))
        if K.ndim != 2:
            raise ValueError(f"gain must be a (d_a, d_phi) matrix, got shape {K.shape}")
        if not np.all(np.isfinite(K)):
            raise ValueError("theta must be finite (got NaN or inf in the gain)")
        self.gain = K
        self.cov = check_sigma(sigma, K.shape[0])
        # Fixed-order factorisations (safepg.portable): LAPACK's last bit depends on the CPU.
        self.cov_chol = portable.cholesky(self.cov)
        self.precision = portable.solve(self.cov, np.eye(self.cov.shape[0]))

    @property
    def action_dim(self) -> int:
        return int(self.gain.shape[0])

    @property
    def feature_dim(self) -> int:
        return int(self.gain.shape[1])

    @property
    def theta(self) -> np.ndarray:
        """Flat parameter vector theta = vec(K), shape (m,)."""
        return self.gain.ravel().copy()

    @property
    def sigma(self) -> float:
        """Smallest action standard deviation (the sigma of the thesis's scalar bounds)."""
        cov = self.cov
        if np.count_nonzero(cov - np.diag(np.diag(cov))) == 0:  # read off exactly, not by LAPACK
            return float(np.sqrt(np.min(np.diag(cov))))
        return float(np.sqrt(np.min(np.linalg.eigvalsh(cov))))

    def with_theta(self, theta: np.ndarray) -> LinearGaussianPolicy:
        """The same policy with parameter vector ``theta``."""
        theta = np.asarray(theta, dtype=float)
        if theta.size != self.gain.size:
            raise ValueError(f"theta must have {self.gain.size} entries, got {theta.size}")
        if not np.all(np.isfinite(theta)):
            raise ValueError("theta must be finite (got NaN or inf)")
        # Same covariance: reuse its factorisations instead of validating it again.
        new = object.__new__(LinearGaussianPolicy)
        new.gain = theta.reshape(self.gain.shape).copy()
        new.cov, new.cov_chol, new.precision = self.cov, self.cov_chol, self.precision
        return new

    def mean(self, features: np.ndarray) -> np.ndarray:
        """K phi(s) for features of shape (..., d_phi) -> (..., d_a)."""
        return portable.matmul(features, self.gain.T)

    def sample(self, features: np.ndarray, rng: RNGLike = None) -> np.ndarray:
        """Draw a ~ N(K phi(s), Sigma) for each row of ``features``."""
        rng = as_generator(rng)
        noise = rng.standard_normal(features.shape[:-1] + (self.action_dim,))
        actions: np.ndarray = self.mean(features) + portable.matmul(noise, self.cov_chol.T)
        return actions

    def log_density(self, features: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """log pi_theta(a | s), shape features.shape[:-1]."""
        diff = actions - self.mean(features)
        maha = np.einsum("...i,ij,...j->...", diff, self.precision, diff)
        _, logdet = np.linalg.slogdet(2 * np.pi * self.cov)
        log_pi: np.ndarray = -0.5 * (maha + logdet)
        return log_pi

    def score(self, features: np.ndarray, actions: np.ndarray) -> np.ndarray:
        r"""Eligibility vector :math:`\nabla_\theta \log\pi_\theta(a\mid s)` (Section 2.3.13).

        .. math:: \nabla_K \log\pi = \Sigma^{-1}\,(a - K\phi(s))\,\phi(s)^\top

        flattened row-major to shape (..., m) with m = d_a * d_phi.
        """
        diff = portable.matmul(actions - self.mean(features), self.precision)  # precision is symmetric
        outer: np.ndarray = diff[..., :, None] * features[..., None, :]
        return outer.reshape(features.shape[:-1] + (self.gain.size,))


__all__ = ["LinearGaussianPolicy", "check_sigma"]
