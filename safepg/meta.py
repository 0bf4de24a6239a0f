r"""Meta-parameters of Chapter 4: penalty constant, step sizes and batch size.

Notation: ``g`` is :math:`\|\hat\nabla_\theta J_\mu(\theta)\|_\infty` (or the
magnitude of the updated component), ``eps`` the estimation error
:math:`\epsilon`, ``c`` the penalty constant of Theorem 4.2.3.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from safepg import portable
from safepg.bounds import ErrorBound
from safepg.constants import TaskConstants

#: (13 + 3 sqrt 17) / 2: N* = N_STAR_FACTOR * d^2 / g^2 (Theorem 4.3.2).
N_STAR_FACTOR = (13 + 3 * math.sqrt(17)) / 2
#: (13 - 3 sqrt 17) / 4: alpha* = ALPHA_STAR_FACTOR / c at N* (Theorem 4.3.2).
ALPHA_STAR_FACTOR = (13 - 3 * math.sqrt(17)) / 4


def penalty_constant(constants: TaskConstants) -> float:
    r"""Penalty constant c of Theorem 4.2.3.

    .. math:: c = \frac{R M_\phi^2}{(1-\gamma)^2\sigma^2}
              \Big(\frac{|\mathcal A|}{\sqrt{2\pi}\,\sigma} + \frac{\gamma}{2(1-\gamma)}\Big)
    """
    R, M, A, gamma, s = constants.R, constants.M_phi, constants.action_volume, constants.gamma, constants.sigma
    if constants.horizon_term != "effective":
        # The same constant with 1 / (1 - gamma) replaced by the horizon factor h
        # (TaskConstants.horizon_term): c = R M^2 h^2 / sigma^2 (|A| / (sqrt(2 pi) sigma) + gamma h / 2).
        h = constants.horizon_factor
        return R * (M * M) * (h * h) / (s * s) * (A / (math.sqrt(2 * math.pi) * s) + gamma * h / 2)
    # Squares as products (bit-exact, like the correctly rounded x**2); Python's ** calls
    # libm's pow, whose last bit depends on the CPU (safepg.portable).
    return R * (M * M) / ((1 - gamma) * (1 - gamma) * (s * s)) * (
        A / (math.sqrt(2 * math.pi) * s) + gamma / (2 * (1 - gamma))
    )


def _check_g(g: float) -> float:
    if not np.isfinite(g) or g < 0:
        raise ValueError(f"gradient norm g must be finite and >= 0, got {g}")
    return float(g)


def coordinate_step(g: float, eps: float, c: float, guarded: bool = True) -> float:
    r"""Step size of the updated coordinate (Corollary 4.2.8; eps = 0 gives 4.2.4).

    .. math:: \alpha_k^* = \frac{(\|\hat\nabla J\|_\infty - \epsilon)^2}
                                {2c\,(\|\hat\nabla J\|_\infty + \epsilon)^2}

    Zero when Assumption 4.2.7 fails (eps >= g): no improvement can be guaranteed, and
    the saturated bound of Theorem 4.2.6 is then maximised by not moving. With
    ``guarded=False`` the formula is evaluated there too (a positive step without any
    guarantee), as the authors' scripts did.
    """
    g = _check_g(g)
    if eps >= g and guarded:
        return 0.0
    lo, hi = g - eps, g + eps
    if hi == 0:  # g = eps = 0 (unguarded): nothing to follow
        return 0.0
    return lo * lo / (2 * c * (hi * hi))


def guaranteed_improvement(g: float, eps: float, c: float) -> float:
    r"""Improvement guaranteed by the step of Corollary 4.2.8, with probability :math:`(1-\delta)^m`.

    .. math:: \frac{(\|\hat\nabla J\|_\infty - \epsilon)^4}{4c(\|\hat\nabla J\|_\infty + \epsilon)^2}
    """
    g = _check_g(g)
    if eps >= g:
        return 0.0
    lo, hi = g - eps, g + eps
    return (lo * lo) * (lo * lo) / (4 * c * (hi * hi))


def scalar_step(grad: np.ndarray, eps: float, c: float) -> float:
    r"""Adaptive scalar step size of Pirotta et al. (2013) (Section 3.3.2), with estimation error.

    Maximising :math:`\alpha\|\underline{\hat\nabla J}\|_2^2 - c\,\alpha^2\|\overline{\hat\nabla J}\|_1^2`
    (the bound of Pirotta et al. (2013) with the lower and upper gradient bounds of Section 4.2.2) gives

    .. math:: \hat\alpha^* = \frac{\|\max(|\hat\nabla J| - \epsilon, 0)\|_2^2}
                                  {2c\,\||\hat\nabla J| + \epsilon\|_1^2}

    With eps = 0 this is :math:`\|\nabla J\|_2^2 / (2c\|\nabla J\|_1^2)`, the printed alpha* of 3.3.2.
    """
    a = np.abs(np.asarray(grad, dtype=float))
    lower = np.maximum(a - eps, 0.0)
    upper = math.fsum((a + eps).tolist())  # exact sums, not BLAS (safepg.portable)
    if upper == 0:
        return 0.0
    return float(portable.dot(lower, lower) / (2 * c * (upper * upper)))


def upsilon(
    n: float | np.ndarray, g: float, bound: ErrorBound, c: float, saturate: bool = True
) -> float | np.ndarray:
    r"""Cost-sensitive improvement :math:`\Upsilon_\delta(\Lambda^*, N)` (Definition 4.1, Section 4.3.3).

    .. math:: \Upsilon_\delta(N) = \frac{(\|\hat\nabla J\|_\infty - \epsilon(N))^4}
                                        {4cN\,(\|\hat\nabla J\|_\infty + \epsilon(N))^2}

    With ``saturate=True`` (default) Upsilon is 0 where eps(N) >= g (N <= N_0), where the
    saturated bound of Theorem 4.2.6 guarantees nothing. ``saturate=False`` evaluates
    the formula everywhere, as drawn in the thesis's Figure 4.1.
    """
    n_arr = np.asarray(n, dtype=float)
    eps = np.asarray(bound.eps(n_arr))
    # Products, not **: NumPy's power has CPU-specific SIMD versions (safepg.portable), and
    # N* is where consecutive values of Upsilon differ in their last bits.
    lo, hi = g - eps, g + eps
    val = (lo * lo) * (lo * lo) / (4 * c * n_arr * (hi * hi))
    if saturate:
        val = np.where(eps < g, val, 0.0)
    return float(val) if val.ndim == 0 else val


def n_zero(g: float, bound: ErrorBound) -> float:
    r"""Smallest batch size satisfying Assumption 4.2.7, eps(N_0) = g (Sections 4.3, 4.3.3).

    .. math:: N_0 = \Big(\frac{d_\delta + \sqrt{d_\delta^2 + 4 f_\delta g}}{2 g}\Big)^2

    which reduces to :math:`d_\delta^2/g^2` when f = 0.
    """
    g = _check_g(g)
    if g == 0:
        return math.inf
    d, f = bound.d, bound.f
    root = (d + math.sqrt(d * d + 4 * f * g)) / (2 * g)
    return root * root


def n_star_closed_form(g: float, bound: ErrorBound) -> float:
    r"""Optimal batch size of Theorem 4.3.2 when :math:`\epsilon = d_\delta/\sqrt N` (f = 0): an integer,
    or ``math.inf`` when g = 0 (no batch makes the step safe).

    .. math:: N^* = \Big\lceil \frac{(13 + 3\sqrt{17})\, d_\delta^2}{2\|\hat\nabla J\|_\infty^2}\Big\rceil
    """
    if bound.f != 0:
        raise ValueError("f must be 0 for the closed-form N* (use n_star_search for Bernstein)")
    g = _check_g(g)
    if g == 0:
        return math.inf
    return math.ceil(N_STAR_FACTOR * (bound.d * bound.d) / (g * g))


def n_star_search(g: float, bound: ErrorBound, c: float, n_max: int | None = None) -> float:
    """N* by the linear search of Section 4.3.3 (any f >= 0): an integer, or ``math.inf`` when
    g = 0 and no ``n_max`` is given.

    Start at ceil(N_0) and stop as soon as Upsilon begins to decrease; the stationary
    point is unique (Descartes' rule of signs), so this is the global maximiser on
    [N_0, inf). With ``n_max`` it stops there (larger batch sizes would be clipped anyway).
    The search is compiled and evaluates Upsilon with the operations of :func:`upsilon`, so it
    finds the N* of evaluating :func:`upsilon` on every N, bit for bit.
    """
    g = _check_g(g)
    if g == 0:
        return math.inf if n_max is None else n_max
    start = max(1, math.ceil(n_zero(g, bound)))
    if n_max is not None and start >= n_max:
        return n_max
    return int(_first_decrease(start, -1 if n_max is None else int(n_max), g, float(bound.d), float(bound.f),
                               float(c)))


@njit(cache=True)
def _upsilon_at(n: float, g: float, d: float, f: float, c: float) -> float:  # pragma: no cover - numba
    # upsilon() at one N, operation for operation (the same bits): eps(N), then the quotient.
    eps = d / np.sqrt(n) + f / n
    lo, hi = g - eps, g + eps
    val = (lo * lo) * (lo * lo) / (4 * c * n * (hi * hi))
    return val if eps < g else 0.0


@njit(cache=True)
def _first_decrease(start: int, n_max: int, g: float, d: float, f: float, c: float) -> int:  # pragma: no cover
    # The first N >= start with Upsilon(N + 1) < Upsilon(N), or n_max (>= 0) if none is below it.
    # Compiled: the adaptive loop runs this search after every batch of a Bernstein run.
    n = start
    v = _upsilon_at(float(n), g, d, f, c)
    while n_max < 0 or n < n_max:
        w = _upsilon_at(float(n + 1), g, d, f, c)
        if w - v < 0:
            return n
        n += 1
        v = w
    return n_max


def n_star_bernstein_root(g: float, bound: ErrorBound) -> float:
    r"""Continuous maximiser of Upsilon for eps = d/sqrt(N) + f/N, from the second factor of
    the derivative (Section 4.3.3) as a polynomial in x = sqrt(N):

    .. math:: -g^2 x^4 + 3 d g x^3 + (2 d^2 + 6 f g) x^2 + 5 d f x + 3 f^2 = 0

    Its coefficients change sign once, so it has one positive root; N* = x^2.
    """
    g = _check_g(g)
    d, f = bound.d, bound.f
    roots = np.roots([-(g**2), 3 * d * g, 2 * d * d + 6 * f * g, 5 * d * f, 3 * f * f])
    pos = [r.real for r in roots if abs(r.imag) < 1e-9 * max(1.0, abs(r)) and r.real > 0]
    return float(max(pos) ** 2)


def optimal_batch_size(
    g: float, bound: ErrorBound, c: float, n_min: int = 2, n_max: int | None = None
) -> int:
    """Next batch size of Algorithm 4.1: N* (closed form if f = 0, else the search),
    clipped to [n_min, n_max]."""
    n = n_star_closed_form(g, bound) if bound.f == 0 else n_star_search(g, bound, c, n_max)
    if n_max is not None:
        n = min(n, n_max)
    elif math.isinf(n):
        raise ValueError("n_max must be given when the gradient estimate is 0: N* is then infinite")
    return int(max(n_min, n))


__all__ = ["ALPHA_STAR_FACTOR", "N_STAR_FACTOR", "coordinate_step", "guaranteed_improvement", "n_star_bernstein_root",
           "n_star_closed_form", "n_star_search", "n_zero", "optimal_batch_size", "penalty_constant", "scalar_step",
           "upsilon"]
