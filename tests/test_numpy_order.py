"""safepg.numpy_order gives NumPy's bits: the learning loop's batch statistics compiled, not reordered.

Each function is compared with NumPy's own call by the bytes of the result, on sizes below, at and
around the pairwise blocks (8, 128 and their halvings), long arrays past NumPy's buffer of 8192, values
with exponents 60 orders of magnitude apart (where another order of additions changes the last
bits), and the strided columns the loop passes (``samples[:, k]`` of an (n, 4) array).
"""

from __future__ import annotations

import numpy as np
import pytest

from safepg.numpy_order import all_finite, column_means, pairwise_sum, sample_range, sample_variance

SIZES = [2, 3, 7, 8, 9, 15, 16, 17, 127, 128, 129, 255, 256, 257, 1000, 4099, 8192, 8193, 20_011]


def wide(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    return rng.standard_normal(shape) * np.exp(rng.uniform(-30, 30, shape))


@pytest.mark.parametrize("n", SIZES + list(np.random.default_rng(5).integers(2, 3000, 20)))
def test_sample_variance_and_range_are_numpys_on_columns(n: int) -> None:
    rng = np.random.default_rng(n)
    for x in (wide(rng, (n, 4)), rng.standard_normal((n, 4)) + 1e6):
        for k in range(4):
            col = x[:, k]  # strided, as the loop passes it
            assert np.float64(sample_variance(col)).tobytes() == np.float64(np.var(col, ddof=1)).tobytes(), (n, k)
            assert sample_variance(np.ascontiguousarray(col)) == sample_variance(col)
            assert np.float64(sample_range(col)).tobytes() == np.float64(np.ptp(col)).tobytes(), (n, k)


def test_the_variance_check_can_fail() -> None:
    """Another order of the same additions (sequential, or the deviations summed pairwise from the
    two-pass mean of a shuffled copy) differs from NumPy's in the last bits on such data: the test above
    compares orders, not just values."""
    rng = np.random.default_rng(3)
    x = wide(rng, 4099)
    mean = sum(x.tolist()) / x.size
    sequential = sum((v - mean) ** 2 for v in x.tolist()) / (x.size - 1)
    assert sequential != np.var(x, ddof=1)


def test_nan_and_infinity() -> None:
    x = np.array([1.0, np.nan, 3.0])
    assert np.isnan(sample_range(x)) and np.isnan(np.ptp(x))
    assert np.isnan(sample_variance(x)) and np.isnan(np.var(x, ddof=1))
    assert not all_finite(np.array([0.0, np.inf])) and not all_finite(np.array([np.nan]))
    assert all_finite(np.array([0.0, -1e308]))


@pytest.mark.parametrize("m", [1, 2, 4])
def test_column_means_and_sums_are_numpys(m: int) -> None:
    rng = np.random.default_rng(m)
    for n in SIZES:
        x = wide(rng, (n, m))
        assert column_means(x, n).tobytes() == (x.sum(axis=0) / n).tobytes(), (n, m)
        r = wide(rng, n)
        assert pairwise_sum(r) == r.sum()
