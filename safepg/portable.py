r"""Fixed-order arithmetic: results that do not depend on the CPU.

Every number the book prints, embeds or compares must come out bit-identical on any
x86-64 machine. Three things can break that:

- **BLAS.** ``@``, ``np.dot``, ``np.linalg`` and ``scipy.linalg`` call OpenBLAS/LAPACK,
  which picks its kernel from the CPU (Haswell, SkylakeX, Nehalem, ...). The kernels
  sum in different orders and some use fused multiply-adds, so even a 2-term dot
  product can differ in the last bit.
- **NumPy's SIMD dispatch of transcendental ufuncs.** ``np.exp``, ``np.log``,
  ``np.power`` (``array ** 4``), ``np.sin``... have AVX-512 implementations that are
  not bit-identical to the scalar ones.
- **glibc's libm.** ``math.log``, ``math.sin``, Python's ``x ** y`` (``pow``) ... pick an
  FMA or a plain-SSE2 implementation from the CPU, and they differ in the last bit on a
  few inputs in a thousand (``GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA`` shows it).
- **FMA contraction** in compiled kernels. Numba emits separate multiplies and adds
  (no ``fastmath``), so its kernels are unaffected; ``tests/test_portable.py`` checks
  that by recomputing runs under ``NUMBA_CPU_NAME=generic``.

What *is* portable: IEEE-754 ``+ - * /`` and ``sqrt`` on single elements (NumPy's
elementwise loops, whatever their SIMD width, round each element once), and NumPy's
reductions (``sum`` adds in a fixed pairwise order that does not depend on the CPU).
The functions below build small linear algebra out of those operations only, in an
order fixed by the code. They are meant for the small matrices of the closed forms
(the LQG's Lyapunov and Riccati equations, a policy covariance), not for big ones.
"""

from __future__ import annotations

import functools
import math
from decimal import Context, Decimal

import numpy as np
from numba import njit


def fsum_mean(x: np.ndarray, weights: np.ndarray | None = None) -> float:
    r"""Mean of ``x`` (weighted by ``weights``), :math:`\sum_i w_i x_i / \sum_i w_i`.

    Both sums are :func:`math.fsum`, which rounds the exact sum once: the result does
    not depend on the order of the terms, let alone on the CPU. The products
    :math:`w_i x_i` are single IEEE multiplications.
    """
    x = np.asarray(x, dtype=float).ravel()
    if weights is None:
        return math.fsum(x.tolist()) / x.size
    w = np.asarray(weights, dtype=float).ravel()
    if w.shape != x.shape:
        raise ValueError(f"weights must have the shape of x {x.shape}, got {w.shape}")
    return math.fsum((w * x).tolist()) / math.fsum(w.tolist())


def dot(a: np.ndarray, b: np.ndarray) -> float:
    r"""Inner product :math:`\sum_i a_i b_i` of two vectors, summed by :func:`math.fsum`."""
    a = np.asarray(a, dtype=float).ravel()
    b = np.asarray(b, dtype=float).ravel()
    if a.shape != b.shape:
        raise ValueError(f"b must have the shape of a {a.shape}, got {b.shape}")
    return math.fsum((a * b).tolist())


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""Matrix product :math:`(AB)_{ij} = \sum_k A_{ik} B_{kj}`, summed over k in order.

    Broadcasts over leading dimensions like ``a @ b``, but never calls BLAS: each term
    is an elementwise product and the sum runs k = 0, 1, ... left to right.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim < 2 or b.ndim < 2 or a.shape[-1] != b.shape[-2]:
        raise ValueError(f"b must be a matrix with {a.shape[-1] if a.ndim else '?'} rows "
                         f"to multiply a {a.shape}, got {b.shape}")
    out: np.ndarray = a[..., :, 0:1] * b[..., 0:1, :]
    for k in range(1, a.shape[-1]):
        out = out + a[..., :, k:k + 1] * b[..., k:k + 1, :]
    return out


def trace(a: np.ndarray) -> np.ndarray:
    r""":math:`\operatorname{tr} A = \sum_i A_{ii}`, summed in order (broadcasts)."""
    a = np.asarray(a, dtype=float)
    out = a[..., 0, 0]
    for i in range(1, a.shape[-1]):
        out = out + a[..., i, i]
    return out


def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""Solve :math:`A X = B` by Gaussian elimination with partial pivoting.

    ``a`` has shape (..., n, n) and ``b`` (..., n, k); leading dimensions are a batch
    (every system is eliminated at once, with its own pivots). The operations and
    their order are fixed by this code, unlike LAPACK's ``gesv``.
    """
    A = np.asarray(a, dtype=float)
    B = np.asarray(b, dtype=float)
    n = A.shape[-1]
    if A.ndim < 2 or A.shape[-2] != n:
        raise ValueError(f"a must have shape (..., n, n), got {A.shape}")
    if B.ndim < 2 or B.shape[-2] != n:
        raise ValueError(f"b must have shape (..., {n}, k), got {B.shape}")
    batch = np.broadcast_shapes(A.shape[:-2], B.shape[:-2])
    k = B.shape[-1]
    # One leading batch axis (copies: eliminated in place).
    A = np.broadcast_to(A, batch + (n, n)).reshape(-1, n, n).copy()
    X = np.broadcast_to(B, batch + (n, k)).reshape(-1, n, k).copy()
    rows = np.arange(A.shape[0])
    for j in range(n):
        # Partial pivoting: bring the largest |A[i, j]|, i >= j, to row j (per system).
        p = j + np.argmax(np.abs(A[:, j:, j]), axis=1)
        A[rows, j], A[rows, p] = A[rows, p].copy(), A[rows, j].copy()
        X[rows, j], X[rows, p] = X[rows, p].copy(), X[rows, j].copy()
        for i in range(j + 1, n):
            factor = A[:, i, j] / A[:, j, j]
            A[:, i, j:] = A[:, i, j:] - factor[:, None] * A[:, j, j:]
            X[:, i, :] = X[:, i, :] - factor[:, None] * X[:, j, :]
    for j in range(n - 1, -1, -1):
        acc = X[:, j, :]
        for i in range(j + 1, n):
            acc = acc - A[:, j, i][:, None] * X[:, i, :]
        X[:, j, :] = acc / A[:, j, j][:, None]
    return X.reshape(batch + (n, k))


def cholesky(a: np.ndarray) -> np.ndarray:
    r"""Lower-triangular L with :math:`L L^\top = A` (Cholesky-Banachiewicz, fixed order)."""
    A = np.asarray(a, dtype=float)
    n = A.shape[0]
    if A.shape != (n, n):
        raise ValueError(f"a must be a square matrix, got shape {A.shape}")
    L = np.zeros_like(A)
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s = s - L[i, k] * L[j, k]
            if i == j:
                if not s > 0:
                    raise ValueError("a must be symmetric positive definite")
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    return L


def powers(x: float, n: int) -> np.ndarray:
    r""":math:`(1, x, x^2, \dots, x^{n-1})` by repeated multiplication.

    ``x ** np.arange(n)`` goes through ``np.power``, which has CPU-specific SIMD
    versions; this is the product the fused kernels accumulate (``disc *= gamma``).
    """
    out = np.empty(n)
    p = 1.0
    for t in range(n):
        out[t] = p
        p = p * x
    return out


# ------------------------------------------------------------ scalar functions
#: Decimal digits of the software (CPU-independent) log, exp and pow: far more than a
#: double holds, so the float they round to is the correctly rounded one.
_CTX = Context(prec=40)


@functools.lru_cache(maxsize=256)  # the bounds ask for the same few constants every iteration
def log(x: float) -> float:
    """Natural logarithm, computed in decimal software arithmetic and rounded to a float.

    For the handful of constants of the bounds (ln(2/delta), ln(3/delta)), where a last
    bit that depends on the CPU's libm would reach every step of a run.
    """
    if not x > 0:
        raise ValueError(f"x must be > 0 for log, got {x}")
    return float(Decimal(float(x)).ln(_CTX))


@functools.lru_cache(maxsize=256)
def exp(x: float) -> float:
    """Exponential in decimal software arithmetic, rounded to a float (see :func:`log`)."""
    return float(Decimal(float(x)).exp(_CTX))


@functools.lru_cache(maxsize=256)
def ipow(x: float, k: int) -> float:
    """x ** k for an integer k >= 0, exact in decimal arithmetic and then rounded once
    (Python's ``**`` calls libm's ``pow``, whose last bit depends on the CPU)."""
    if int(k) != k or k < 0:
        raise ValueError(f"k must be an integer >= 0, got {k}")
    return float(_CTX.power(Decimal(float(x)), int(k)))


# -------------------------------------------------------------- trigonometry
# Cody-Waite reduction by pi/2 in three parts (the first two have trailing zero bits, so
# k * part is exact for |k| < 2^20), then Taylor polynomials on |r| <= pi/4 by Horner's
# rule. Only + - * and rounding, in a fixed order: the same bits on every CPU, within
# 2 ulp of the correctly rounded value (tests/test_portable.py).
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624879595063154e-21
_TWO_OVER_PI = 6.36619772367581382433e-01
#: Below this |x| (0.78 < pi/4) the reduction's k is 0 and r = ((x - 0) - 0) - 0 = x exactly:
#: the cart-pole's angles (under 0.73 rad while it lives) skip it.
_NO_REDUCTION = 0.78


@njit(cache=True)
def _reduce(x: float) -> tuple[float, int]:
    k = math.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    return r, int(k) & 3


@njit(cache=True)
def sin_poly(r: float) -> float:
    """sin r for |r| <= pi/4 (no reduction, no branch): :func:`sin` below 0.78 rad."""
    r2 = r * r
    p = -1.0 / 51090942171709440000.0
    p = p * r2 + 1.0 / 121645100408832000.0
    p = p * r2 - 1.0 / 355687428096000.0
    p = p * r2 + 1.0 / 1307674368000.0
    p = p * r2 - 1.0 / 6227020800.0
    p = p * r2 + 1.0 / 39916800.0
    p = p * r2 - 1.0 / 362880.0
    p = p * r2 + 1.0 / 5040.0
    p = p * r2 - 1.0 / 120.0
    p = p * r2 + 1.0 / 6.0
    return r - r * r2 * p


@njit(cache=True)
def cos_poly(r: float) -> float:
    """cos r for |r| <= pi/4 (no reduction, no branch): :func:`cos` below 0.78 rad."""
    r2 = r * r
    p = -1.0 / 1124000727777607680000.0
    p = p * r2 + 1.0 / 2432902008176640000.0
    p = p * r2 - 1.0 / 6402373705728000.0
    p = p * r2 + 1.0 / 20922789888000.0
    p = p * r2 - 1.0 / 87178291200.0
    p = p * r2 + 1.0 / 479001600.0
    p = p * r2 - 1.0 / 3628800.0
    p = p * r2 + 1.0 / 40320.0
    p = p * r2 - 1.0 / 720.0
    p = p * r2 + 1.0 / 24.0
    return 1.0 - r2 * (0.5 - r2 * p)


@njit(cache=True)
def _sin_quadrant(r: float, q: int) -> float:
    """sin(r + q pi/2) for |r| <= pi/4; cos x = sin(x + pi/2) is quadrant q + 1."""
    q = q & 3
    if q == 0:
        return sin_poly(r)
    if q == 1:
        return cos_poly(r)
    if q == 2:
        return -sin_poly(r)
    return -cos_poly(r)


@njit(cache=True)
def sin(x: float) -> float:
    """sin x with CPU-independent bits (|x| < 1e5; beyond that, libm's)."""
    if abs(x) < _NO_REDUCTION:  # k = 0: the reduction returns x itself, so this is the same value
        return sin_poly(x)
    if not abs(x) < 1e5:
        return math.sin(x)
    r, q = _reduce(x)
    return _sin_quadrant(r, q)


@njit(cache=True)
def cos(x: float) -> float:
    """cos x with CPU-independent bits (|x| < 1e5; beyond that, libm's)."""
    if abs(x) < _NO_REDUCTION:
        return cos_poly(x)
    if not abs(x) < 1e5:
        return math.cos(x)
    r, q = _reduce(x)
    return _sin_quadrant(r, q + 1)


@njit(cache=True)
def sincos(x: float) -> tuple[float, float]:
    """(:func:`sin` x, :func:`cos` x), the same bits, for |x| < 1e5, without a branch.

    One reduction for both, both polynomials, and the quadrant picked by selects on values
    already computed: a loop of these vectorises (the pendulum's angles, which wind past
    pi/4, :mod:`safepg.envs.pendulum`). Below 0.78 rad the reduction gives k = 0 and r = x
    exactly, so this is also :func:`sin`'s and :func:`cos`'s fast path there.
    """
    r, q = _reduce(x)
    s, c = sin_poly(r), cos_poly(r)
    odd = (q & 1) == 1
    sv = c if odd else s  # sin(r + q pi/2): s, c, -s, -c for q = 0, 1, 2, 3
    cv = -s if odd else c  # cos(r + q pi/2): c, -s, -c, s
    sv = -sv if (q & 2) == 2 else sv
    cv = -cv if (q & 2) == 2 else cv
    return sv, cv


@njit(cache=True)
def _sin_cos_many(x: np.ndarray, want_sin: bool) -> np.ndarray:
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = sin(x[i]) if want_sin else cos(x[i])
    return out


def sin_array(x: np.ndarray | float) -> np.ndarray:
    """:func:`sin` elementwise on an array (the cart-pole's reference path)."""
    a = np.asarray(x, dtype=float)
    return _sin_cos_many(a.ravel(), True).reshape(a.shape)


def cos_array(x: np.ndarray | float) -> np.ndarray:
    """:func:`cos` elementwise on an array."""
    a = np.asarray(x, dtype=float)
    return _sin_cos_many(a.ravel(), False).reshape(a.shape)



# -------------------------------------------------- exponential and logarithm (kernels)
# For the random-number kernels (safepg.streams): the ziggurat's wedge test and tail. Same
# recipe as sin and cos: Cody-Waite reduction by ln 2 (the high part has trailing zero bits,
# so k * part is exact), a Taylor or atanh series by Horner's rule, and an exact scaling by
# a power of two from a table (np.ldexp builds it bit by bit). Within a few ulp of the
# correctly rounded value (tests/test_portable.py), the same bits on every CPU.
_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_SQRT_HALF = 0.70710678118654752440
_POW2_MIN = -1022
_POW2 = np.ldexp(1.0, np.arange(_POW2_MIN, 1024))


@njit(cache=True)
def exp_kernel(x: float) -> float:
    """e^x with CPU-independent bits, for |x| <= 700 (0 below, inf above: beyond the kernels' use)."""
    if x < -700.0:
        return 0.0
    if x > 700.0:
        return math.inf
    return exp_in_range(x)


@njit(cache=True)
def exp_in_range(x: float) -> float:
    """:func:`exp_kernel` without its range tests, for -700 <= x <= 700: the same bits, and no
    branch, so that a loop of them vectorises (the ziggurat's wedge tests, :mod:`safepg.streams`)."""
    k = math.floor(x * _INV_LN2 + 0.5)
    r = (x - k * _LN2_HI) - k * _LN2_LO  # |r| <= ln(2)/2 (plus rounding)
    p = 1.0 / 87178291200.0  # 1/14!
    for d in (6227020800.0, 479001600.0, 39916800.0, 3628800.0, 362880.0, 40320.0, 5040.0, 720.0, 120.0,
              24.0, 6.0, 2.0, 1.0, 1.0):
        p = p * r + 1.0 / d
    scale: float = _POW2[int(k) - _POW2_MIN]
    return p * scale


@njit(cache=True)
def log_kernel(x: float) -> float:
    """ln x with CPU-independent bits, for normal x > 0 (the kernels take it of numbers in (0, 1])."""
    if not x > 0.0:
        return math.nan if x != 0.0 else -math.inf
    m = x
    k = 0
    while m < _SQRT_HALF:  # exact: multiplying by 2 only changes the exponent
        m = m * 2.0
        k -= 1
    while m > 2.0 * _SQRT_HALF:
        m = m * 0.5
        k += 1
    s = (m - 1.0) / (m + 1.0)  # ln m = 2 atanh(s), |s| <= 0.1716
    s2 = s * s
    p = 1.0 / 25.0
    for d in (23.0, 21.0, 19.0, 17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0, 1.0):
        p = p * s2 + 1.0 / d
    return k * _LN2_HI + (k * _LN2_LO + 2.0 * s * p)


__all__ = ["cholesky", "cos", "cos_array", "dot", "exp", "exp_in_range", "exp_kernel", "fsum_mean", "ipow", "log",
           "log_kernel", "matmul", "powers", "sin", "sin_array", "sincos", "solve", "trace"]
