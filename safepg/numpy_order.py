"""NumPy's summation orders, compiled: the batch statistics of a learning iteration with NumPy's bits.

The learning loop (:mod:`safepg.learning`) forms, at every batch, the gradient estimate
``samples.sum(axis=0) / n``, the mean return, and for the empirical bounds a sample variance
``np.var(x, ddof=1)`` and a range. At the batch sizes of Section 5.2 (a few hundred trajectories)
NumPy's call overhead for these is a fifth of an iteration. The functions here give the same
bits in compiled code, in NumPy's own orders (tested against NumPy on every size up to a few
thousand and on strided columns):

* a 1-D sum (``a.sum()``): NumPy's pairwise summation, blocks of at most 128 terms each summed
  with 8 running sums, halves above that (:func:`pairwise_sum`);
* the columns of an (n, m >= 2) C-ordered array (``a.sum(axis=0)``): row after row into zeros,
  one running sum per column (:func:`column_means`);
* ``np.var(x, ddof=1)``: the pairwise mean, then the pairwise sum of the squared deviations
  over n - 1 (:func:`sample_variance`); ``np.ptp`` is max - min, whatever the order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: NumPy's pairwise summation: blocks of at most 128 terms, each summed with 8 accumulators.
_BLOCK = 128
_UNROLL = 8


@njit(cache=True)
def _block_sum(a, lo, n):  # pragma: no cover - numba
    """NumPy's sum of a block of at most 128 terms: in order below 8, else 8 running sums."""
    if n < _UNROLL:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = _UNROLL
    whole = n - n % _UNROLL
    while i < whole:
        j = lo + i
        r0 += a[j]
        r1 += a[j + 1]
        r2 += a[j + 2]
        r3 += a[j + 3]
        r4 += a[j + 4]
        r5 += a[j + 5]
        r6 += a[j + 6]
        r7 += a[j + 7]
        i += _UNROLL
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def _pairwise(a, n):  # pragma: no cover - numba
    """NumPy's recursion (a block, or the sum of the two halves, the first a multiple of 8 terms),
    walked with an explicit stack: numba cannot load a cached recursive function."""
    if n <= _BLOCK:
        return _block_sum(a, 0, n)
    depth = 64  # halving from 2^63 terms reaches a block in fewer levels
    los = np.empty(depth, np.int64)
    ns = np.empty(depth, np.int64)
    phase = np.zeros(depth, np.int64)  # 0: left half to sum, 1: right half to sum, 2: both summed
    left = np.empty(depth)
    top, ret = 0, 0.0
    los[0], ns[0] = 0, n
    while top >= 0:
        lo, size = los[top], ns[top]
        if size <= _BLOCK:
            ret = _block_sum(a, lo, size)
            top -= 1
            continue
        half = size // 2
        half -= half % _UNROLL
        if phase[top] == 0:
            phase[top] = 1
            top += 1
            los[top], ns[top], phase[top] = lo, half, 0
        elif phase[top] == 1:
            left[top] = ret
            phase[top] = 2
            top += 1
            los[top], ns[top], phase[top] = lo + half, size - half, 0
        else:
            ret = left[top] + ret
            top -= 1
    return ret


@njit(cache=True)
def pairwise_sum(a):  # pragma: no cover - numba
    """``a.sum()`` of a contiguous 1-D float array, in NumPy's order: 0.0 plus the pairwise sum."""
    return 0.0 + _pairwise(a, a.size)


@njit(cache=True)
def column_means(samples, n):  # pragma: no cover - numba
    m = samples.shape[1]
    out = np.zeros(m)
    if m == 1:
        out[0] = pairwise_sum(np.ascontiguousarray(samples[:, 0]))
    else:
        for i in range(samples.shape[0]):
            for j in range(m):
                out[j] += samples[i, j]
    for j in range(m):
        out[j] = out[j] / n
    return out


@njit(cache=True)
def all_finite(x):  # pragma: no cover - numba
    for v in x.ravel():
        if not np.isfinite(v):
            return False
    return True


@njit(cache=True, error_model="numpy")
def sample_variance(x):  # pragma: no cover - numba
    """``np.var(x, ddof=1)`` of a 1-D float array (any stride), in NumPy's order."""
    n = x.size
    a = np.ascontiguousarray(x)
    mean = pairwise_sum(a) / n
    sq = np.empty(n)
    for i in range(n):
        d = a[i] - mean
        sq[i] = d * d
    return pairwise_sum(sq) / max(n - 1, 0)


@njit(cache=True)
def sample_range(x):  # pragma: no cover - numba
    """``np.ptp(x)`` of a 1-D float array: max - min (NaN if any entry is NaN, as NumPy's)."""
    lo = x[0]
    hi = x[0]
    for v in x:
        if np.isnan(v):
            return np.nan
        lo = min(lo, v)
        hi = max(hi, v)
    return hi - lo


__all__ = ["all_finite", "column_means", "pairwise_sum", "sample_range", "sample_variance"]
