r"""The reference distributions of :mod:`safepg.significance`: Student's :math:`t`, Fisher's :math:`F`
(central and noncentral) and the binomial.

Each function answers one question a test asks of its distribution: a p-value
(:func:`t_two_sided_p`, :func:`f_upper_p`), a critical value (:func:`t_critical`,
:func:`f_critical`), the noncentrality a test detects with probability :data:`POWER`
(:func:`t_noncentrality`, :func:`f_noncentrality`), or an interval for a rate
(:func:`clopper_pearson`). All are computed with mpmath, software arithmetic, so they are the
same bits on any CPU (:mod:`safepg.portable`).
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

#: The power at which a detectable difference is stated.
POWER = 0.8


def _mp() -> Any:
    import mpmath

    return mpmath


def check_level(alpha: float, name: str = "alpha") -> None:
    """Raise a ValueError naming ``name`` unless ``0 < alpha < 1``."""
    if not 0 < alpha < 1:
        raise ValueError(f"{name} must be in (0, 1), got {alpha!r}")


@cache
def t_two_sided_p(t: float, df: float) -> float:
    r"""Two-sided p-value of Student's :math:`t`, :math:`P(|T_{df}| \ge |t|) = I_{df/(df + t^2)}(df/2, 1/2)`.

    Raises
    ------
    ValueError
        If ``df`` is not positive or ``t`` is NaN.
    """
    if not df > 0:
        raise ValueError(f"df must be positive, got {df!r}")
    if math.isnan(t):
        raise ValueError("t must not be NaN")
    if math.isinf(t):
        return 0.0
    mp = _mp()
    with mp.workdps(30):
        x = mp.mpf(df) / (mp.mpf(df) + mp.mpf(t) ** 2)
        return float(mp.betainc(mp.mpf(df) / 2, mp.mpf(1) / 2, 0, x, regularized=True))


@cache
def f_upper_p(f: float, d1: float, d2: float) -> float:
    r"""Upper tail of Fisher's :math:`F(d_1, d_2)`, :math:`P(F \ge f) = I_{d_2/(d_2 + d_1 f)}(d_2/2, d_1/2)`.

    Raises
    ------
    ValueError
        If a degree of freedom is not positive or ``f`` is NaN.
    """
    if not (d1 > 0 and d2 > 0):
        raise ValueError(f"d1 and d2 must be positive, got {d1!r} and {d2!r}")
    if math.isnan(f):
        raise ValueError("f must not be NaN")
    if f <= 0:
        return 1.0
    if math.isinf(f):
        return 0.0
    mp = _mp()
    with mp.workdps(30):
        x = mp.mpf(d2) / (mp.mpf(d2) + mp.mpf(d1) * mp.mpf(f))
        return float(mp.betainc(mp.mpf(d2) / 2, mp.mpf(d1) / 2, 0, x, regularized=True))


def _bisect(fun: Any, lo: Any, hi: Any, iterations: int = 60) -> Any:
    """The root of an increasing function ``fun`` on [lo, hi] (mpmath numbers), by bisection."""
    for _ in range(iterations):
        mid = (lo + hi) / 2
        if fun(mid) < 0:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def _root(fun: Any, lo: Any, hi: Any, tolerance: float = 1e-12) -> Any:
    """The root of an increasing function ``fun`` on [lo, hi] by the Illinois method (regula falsi that
    halves the stale end's value): a few evaluations where each costs an integral."""
    f_lo, f_hi = fun(lo), fun(hi)
    if f_lo > 0 or f_hi < 0:
        raise ValueError(f"no root in [{float(lo)}, {float(hi)}]")
    side = 0
    for _ in range(200):
        x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        fx = fun(x)
        if abs(hi - lo) <= tolerance * max(1, abs(x)) or fx == 0:
            return x
        if fx < 0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi /= 2
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo /= 2
            side = 1
    return x


@cache
def t_critical(df: float, alpha: float) -> float:
    r"""The two-sided critical value :math:`c` of Student's :math:`t`: :math:`P(|T_{df}| \ge c) = \alpha`."""
    check_level(alpha)
    mp = _mp()
    with mp.workdps(30):
        half, a = mp.mpf(1) / 2, mp.mpf(df) / 2
        # x = df / (df + c^2) solves I_x(df/2, 1/2) = alpha; I_x increases in x.
        x = _root(lambda x: mp.betainc(a, half, 0, x, regularized=True) - mp.mpf(repr(alpha)), mp.mpf(0),
                  mp.mpf(1), 1e-25)
        return float(mp.sqrt(df * (1 - x) / x))


@cache
def f_critical(d1: float, d2: float, alpha: float) -> float:
    r"""The critical value :math:`c` of :math:`F(d_1, d_2)`: :math:`P(F \ge c) = \alpha`; for :math:`d_2 = \infty`,
    :math:`\chi^2_{d_1}/d_1`'s."""
    check_level(alpha)
    mp = _mp()
    if math.isinf(d2):
        with mp.workdps(30):
            half = mp.mpf(d1) / 2
            # Q(d1/2, x) = alpha for x = c d1 / 2; Q falls as x grows, so its negative increases.
            x = _root(lambda x: mp.mpf(repr(alpha)) - mp.gammainc(half, x, mp.inf, regularized=True), mp.mpf(0),
                      mp.mpf(10 * d1 + 200), 1e-25)
            return float(2 * x / d1)
    with mp.workdps(30):
        a, b = mp.mpf(d2) / 2, mp.mpf(d1) / 2
        x = _root(lambda x: mp.betainc(a, b, 0, x, regularized=True) - mp.mpf(repr(alpha)), mp.mpf(0),
                  mp.mpf(1), 1e-25)
        return float(mp.mpf(d2) * (1 - x) / (mp.mpf(d1) * x))


def _f_power(lam: Any, d1: float, d2: float, c: Any) -> Any:
    r"""Power of the :math:`F` test, :math:`P(F' \ge c)` for noncentral :math:`F'(d_1, d_2, \lambda)`: the
    Poisson mixture :math:`\sum_j e^{-\lambda/2}(\lambda/2)^j/j!\,[1 - I_{x_c}(d_1/2 + j, d_2/2)]`,
    :math:`x_c = d_1 c / (d_1 c + d_2)`, with :math:`I_x(a + 1, b) = I_x(a, b) - x^a (1 - x)^b / (a B(a, b))`
    for the next term (one incomplete beta function in all)."""
    mp = _mp()
    mean = lam / 2
    if math.isinf(d2):  # d1 F' is noncentral chi-square: Q(a + 1, y) = Q(a, y) + y^a e^{-y} / Gamma(a + 1)
        a, y = mp.mpf(d1) / 2, mp.mpf(d1) * c / 2
        upper = mp.gammainc(a, y, mp.inf, regularized=True)
        step = mp.exp(a * mp.log(y) - y - mp.loggamma(a + 1))
        weight, total, j = mp.exp(-mean), mp.mpf(0), 0
        while True:
            total += weight * upper
            upper += step
            step *= y / (a + j + 1)
            j += 1
            weight *= mean / j
            if j > mean and weight < mp.mpf(10) ** -18:
                return total
    x = mp.mpf(d1) * c / (mp.mpf(d1) * c + d2)
    a, b = mp.mpf(d1) / 2, mp.mpf(d2) / 2
    below = mp.betainc(a, b, 0, x, regularized=True)  # I_x(a + j, b)
    step = mp.exp(a * mp.log(x) + b * mp.log(1 - x) - mp.log(a) - mp.log(mp.beta(a, b)))
    weight = mp.exp(-mean)
    total, j = mp.mpf(0), 0
    while True:
        total += weight * (1 - below)
        below -= step
        step *= x * (a + j + b) / (a + j + 1)
        j += 1
        weight *= mean / j
        if j > mean and weight < mp.mpf(10) ** -18:
            return total


def _increasing_bracket(fun: Any, start: Any) -> tuple[Any, Any]:
    """[lo, hi] with ``fun(lo) <= 0 <= fun(hi)`` for an increasing ``fun`` with ``fun(0) <= 0``: ``start``
    doubled until the sign changes."""
    lo, hi = 0 * start, start
    while fun(hi) < 0:
        lo, hi = hi, 2 * hi
    return lo, hi


@cache
def t_noncentrality(df: float, alpha: float, power: float = POWER) -> float:
    r"""The noncentrality :math:`\delta` at which the two-sided :math:`t` test with ``df`` degrees of freedom
    at level ``alpha`` rejects with probability ``power``: a shift of :math:`\delta` standard errors. As
    :math:`T'^2 \sim F'(1, df, \delta^2)`, :math:`\delta = \sqrt{\lambda^*}` of :func:`f_noncentrality`."""
    return math.sqrt(f_noncentrality(1, df, alpha, power))


@cache
def f_noncentrality(d1: float, d2: float, alpha: float, power: float = POWER) -> float:
    r"""The noncentrality :math:`\lambda` at which the :math:`F(d_1, d_2)` test at level ``alpha`` rejects with
    probability ``power``."""
    check_level(alpha)
    mp = _mp()
    with mp.workdps(16):
        c = mp.mpf(f_critical(d1, d2, alpha))

        def excess(lam: Any) -> Any:
            return _f_power(lam, d1, d2, c) - mp.mpf(power)

        # The chi-square limit's lambda, (z_{1-alpha} + z_power)^2 per degree of freedom, is the first guess.
        guess = (mp.sqrt(2) * (mp.erfinv(1 - 2 * mp.mpf(repr(alpha))) + mp.erfinv(2 * mp.mpf(power) - 1))) ** 2
        return float(_root(excess, *_increasing_bracket(excess, guess * d1), 1e-9))


def clopper_pearson(successes: int, trials: int, level: float = 0.95) -> tuple[float, float]:
    r"""The two-sided Clopper-Pearson interval of a binomial proportion: the :math:`p` whose one-sided
    tail probabilities of the observed count are at least :math:`(1 - \text{level})/2` each.

    Raises
    ------
    ValueError
        If the counts are not ``0 <= successes <= trials``, ``trials >= 1``, or ``level`` is not in (0, 1).
    """
    if trials < 1 or not 0 <= successes <= trials:
        raise ValueError(f"need 0 <= successes <= trials and trials >= 1, got {successes} of {trials}")
    check_level(level, "level")
    mp = _mp()
    tail = mp.mpf(repr(1 - level)) / 2
    with mp.workdps(30):
        # The lower end solves I_p(x, n - x + 1) = tail, the upper I_p(x + 1, n - x) = 1 - tail.
        lo = mp.mpf(0) if successes == 0 else _bisect(
            lambda p: mp.betainc(successes, trials - successes + 1, 0, p, regularized=True) - tail, mp.mpf(0),
            mp.mpf(1), 100)
        hi = mp.mpf(1) if successes == trials else _bisect(
            lambda p: mp.betainc(successes + 1, trials - successes, 0, p, regularized=True) - (1 - tail),
            mp.mpf(0), mp.mpf(1), 100)
        return float(lo), float(hi)


__all__ = ["POWER", "check_level", "clopper_pearson", "f_critical", "f_noncentrality", "f_upper_p", "t_critical",
           "t_noncentrality", "t_two_sided_p"]
