"""Linear Gaussian policy: density, score and sampling against independent computations."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from safepg.policies import LinearGaussianPolicy

K = np.array([[0.3, -0.2, 0.1], [0.05, 0.4, -0.3]])
COV = np.array([[0.6, 0.1], [0.1, 0.3]])


def test_log_density_matches_scipy():
    pol = LinearGaussianPolicy(K, COV)
    rng = np.random.default_rng(0)
    phi, a = rng.normal(size=(20, 3)), rng.normal(size=(20, 2))
    ref = [multivariate_normal(K @ p, COV).logpdf(x) for p, x in zip(phi, a)]
    np.testing.assert_allclose(pol.log_density(phi, a), ref, rtol=1e-12)


@pytest.mark.parametrize("gain,sigma", [(K, COV), (np.array([[-0.3]]), 0.7), (K, np.array([0.5, 1.5]))])
def test_score_is_the_gradient_of_the_log_density(gain, sigma):
    pol = LinearGaussianPolicy(gain, sigma)
    rng = np.random.default_rng(1)
    phi = rng.normal(size=(5, gain.shape[1]))
    a = rng.normal(size=(5, gain.shape[0]))
    h = 1e-6
    fd = np.stack([(pol.with_theta(pol.theta + h * e).log_density(phi, a)
                    - pol.with_theta(pol.theta - h * e).log_density(phi, a)) / (2 * h)
                   for e in np.eye(gain.size)], axis=-1)
    np.testing.assert_allclose(pol.score(phi, a), fd, rtol=1e-6, atol=1e-8)


def test_scalar_score_is_the_thesis_formula():
    # Section 2.3.13: (a - theta^T phi) phi / sigma^2
    pol = LinearGaussianPolicy([[0.4, -1.0]], 0.5)
    phi, a = np.array([[1.5, 2.0]]), np.array([[0.3]])
    expected = (0.3 - (0.4 * 1.5 - 2.0)) * phi[0] / 0.25
    np.testing.assert_allclose(pol.score(phi, a)[0], expected)


def test_sampling_moments():
    pol = LinearGaussianPolicy(K, COV)
    phi = np.tile([[1.0, -2.0, 0.5]], (200_000, 1))
    a = pol.sample(phi, 3)
    np.testing.assert_allclose(a.mean(axis=0), K @ phi[0], atol=0.01)
    np.testing.assert_allclose(np.cov(a.T), COV, atol=0.01)
    assert np.array_equal(a, pol.sample(phi, 3))


@pytest.mark.parametrize("sigma,name", [(0.0, "sigma"), (-1.0, "sigma"), (np.nan, "sigma"),
                                        (np.ones(3), "sigma"), (np.array([[1.0, 2.0], [2.0, 1.0]]), "sigma")])
def test_bad_sigma(sigma, name):
    with pytest.raises(ValueError, match=f"^{name}"):
        LinearGaussianPolicy(K, sigma)


def test_bad_theta():
    with pytest.raises(ValueError, match="^theta"):
        LinearGaussianPolicy([[np.nan]], 1.0)
    pol = LinearGaussianPolicy(K, COV)
    with pytest.raises(ValueError, match="^theta"):
        pol.with_theta(np.zeros(5))
    with pytest.raises(ValueError, match="^theta"):
        pol.with_theta(np.full(6, np.inf))
