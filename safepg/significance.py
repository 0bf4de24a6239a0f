r"""Tests of "does this printed number come from the process our runs follow": p-values, their
correction over many rows, and the smallest difference each test would have detected.

A reproduction compares numbers someone printed with runs of its own. Each comparison here is a
frozen object built from the data; it has a two-sided :attr:`p_value` and a
:meth:`detectable_difference`: the smallest shift of the process, in the units of the compared
number, that the test rejects with probability 0.8 at a given level. Where it cannot reject at all
at that level (a permutation test with too few runs), the detectable difference is infinite.

- :class:`PredictionTest`: a number printed from **one run**, against :math:`k` runs of ours. Under
  normal runs, :math:`T = (x - \bar x) / (s\sqrt{1 + 1/k})` is Student-:math:`t` with
  :math:`k - 1` degrees of freedom.
- :class:`WelchTest`: a printed **mean over** :math:`n` **runs with its 95% interval**, against
  :math:`k` runs of ours: Welch's two-sample :math:`t`, the printed interval giving the other
  sample's standard deviation.
- :class:`CurvePredictionTest`: **one printed curve**, reduced to its means over :math:`B` blocks
  of the plotted range, against :math:`k` of ours: Hotelling's :math:`T^2` for one new
  observation, :math:`\frac{k - B}{B(k - 1)}T^2 \sim F(B, k - B)` under normal runs.
- :class:`PermutationTest`: :math:`m` **printed runs of a curve** against :math:`k` of ours, by the
  two-sample Hotelling :math:`T^2` of their block means and its exact permutation distribution.

The first three are exact only for normal runs: their level is measured, not assumed
(``safepg.thesis.false_alarms``). The permutation test is exact for any distribution.
:func:`benjamini_hochberg` controls the false discovery rate over a family of them.

Every probability is computed with mpmath (software arithmetic) and every matrix with
:mod:`safepg.portable`, so p-values and detectable differences are the same bits on any CPU.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any, ClassVar, Protocol

import numpy as np

from safepg import portable

#: The power at which a detectable difference is stated.
POWER = 0.8
#: Permutations enumerated exhaustively up to this many; beyond it, a seeded Monte Carlo sample.
EXHAUSTIVE_PERMUTATIONS = 200_000
#: Monte Carlo permutations when enumerating them all would be too many.
MONTE_CARLO_PERMUTATIONS = 99_999
#: A permutation test's detectable difference is stated only where its smallest p-value is at most this
#: share of the level: nearer the level, its discreteness, not the data, limits its power, and the
#: parametric power it is computed by would overstate it.
PERMUTATION_RESOLUTION = 0.1


# ------------------------------------------------------------------ distributions (mpmath)
def _mp() -> Any:
    import mpmath

    return mpmath


def _check_level(alpha: float) -> None:
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")


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
    _check_level(alpha)
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
    _check_level(alpha)
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
    _check_level(alpha)
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
    _check_level(level)
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


# ------------------------------------------------------------------ small statistics, CPU-independent
def _mean_sd(values: Sequence[float] | np.ndarray) -> tuple[float, float, int]:
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError(f"values must be a non-empty 1-D sequence of finite numbers, got shape {x.shape}")
    m = float(x.mean())
    sd = float(np.sqrt(np.sum((x - m) ** 2) / (x.size - 1))) if x.size > 1 else 0.0
    return m, sd, int(x.size)


def _covariance(y: np.ndarray) -> np.ndarray:
    """Sample covariance (ddof = 1) of the rows of ``y`` (n, B), elementwise and in a fixed order."""
    centred = y - y.mean(axis=0)
    # Elementwise products and NumPy's pairwise sum: no BLAS, no CPU-dispatched kernel (safepg.portable).
    return np.asarray((centred[:, :, None] * centred[:, None, :]).sum(axis=0) / (y.shape[0] - 1))


def _quadratic(s: np.ndarray, v: np.ndarray) -> float:
    r""":math:`v^\top S^{-1} v` by :func:`safepg.portable.solve` (NaN for a singular :math:`S`)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        x = portable.solve(s, v[:, None])[:, 0]
    if not np.all(np.isfinite(x)):
        return math.nan
    return portable.dot(v, x)


# ------------------------------------------------------------------ the tests
@dataclass(frozen=True)
class PredictionTest:
    r"""A number printed from one run, against :math:`k` runs of ours.

    The printed number is an interval ``printed`` (its value give or take its rounding, or a reading
    precision: "≈ 500" is [450, 550]); the statistic is the distance of our mean from it, less a
    ``resolution`` the quantity cannot resolve (an improvement ratio moves by whole updates),

    .. math:: T = \frac{\max(0,\ \mathrm{dist}(\bar x, [a, b]) - r)}{s_e\sqrt{1 + 1/k}},
        \qquad p = P(|T_{k-1}| \ge T),

    with :math:`s_e = s`, our runs' standard deviation, or, where every run of ours gave the same value
    (:math:`s = 0`: a ratio of 100% in every seed), ``sd_floor`` :math:`s_{\min}`, the spread the quantity
    has at the least (a binomial spread for a ratio). With :math:`s_e = 0`, :math:`p` is 1 when
    :math:`T`'s numerator is 0 and 0 otherwise.

    Parameters
    ----------
    printed : (float, float)
        The printed number as an interval [a, b] (a = b for an exact value).
    values : sequence of float
        Our runs' values, at least two.
    resolution : float
        The shift the quantity cannot resolve, >= 0.
    sd_floor : float
        The standard deviation of one run to use where all of ours agree, >= 0.

    Raises
    ------
    ValueError
        If ``printed`` is not an ordered pair of finite numbers, fewer than two values are given,
        or ``resolution`` or ``sd_floor`` is negative.
    """

    #: The test's name, as the scorecard states it.
    name: ClassVar[str] = "prediction t"

    printed: tuple[float, float]
    values: tuple[float, ...]
    resolution: float = 0.0
    sd_floor: float = 0.0
    mean: float = field(init=False)
    sd: float = field(init=False)

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.printed)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"printed must be an interval (low, high) of finite numbers, got {self.printed!r}")
        if self.resolution < 0 or self.sd_floor < 0:
            raise ValueError(f"resolution and sd_floor must be >= 0, got {self.resolution!r} and {self.sd_floor!r}")
        m, sd, k = _mean_sd(self.values)
        if k < 2:
            raise ValueError(f"values must hold at least two runs, got {k}")
        object.__setattr__(self, "printed", (lo, hi))
        object.__setattr__(self, "values", tuple(float(v) for v in self.values))
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "sd", sd)

    @property
    def seeds(self) -> int:
        """Our runs :math:`k`."""
        return len(self.values)

    @property
    def spread(self) -> float:
        """:math:`s_e`: :math:`s`, or :math:`s_{\\min}` where every run agrees."""
        return self.sd if self.sd > 0 else self.sd_floor

    @property
    def distance(self) -> float:
        """Our mean's distance from the printed interval, less the resolution (>= 0)."""
        lo, hi = self.printed
        return max(0.0, lo - self.mean - self.resolution, self.mean - hi - self.resolution)

    @property
    def statistic(self) -> float:
        """:math:`T` (inf when every seed agrees and the printed number lies off them)."""
        if self.distance == 0:
            return 0.0
        if self.spread == 0:
            return math.inf
        return self.distance / (self.spread * math.sqrt(1 + 1 / self.seeds))

    @property
    def p_value(self) -> float:
        """Two-sided :math:`p`."""
        return t_two_sided_p(self.statistic, self.seeds - 1)

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float:
        r"""The smallest shift of our process from the printed value that the test rejects with
        probability ``power`` at level ``alpha``, with ``seeds`` runs (default ours, at our spread):
        the printed interval's half-width, plus :math:`r`, plus :math:`\delta^* s_e\sqrt{1 + 1/k}`."""
        k = self.seeds if seeds is None else seeds
        half = (self.printed[1] - self.printed[0]) / 2
        if self.spread == 0:
            return half + self.resolution
        return half + self.resolution + t_noncentrality(k - 1, alpha, power) * self.spread * math.sqrt(1 + 1 / k)


def _welch_df(a: float, b: float, k: float, n: int) -> float:
    """Welch-Satterthwaite degrees of freedom of variances of the mean ``a`` (k runs) and ``b`` (n runs)."""
    if a == 0 and b == 0:
        return float(k + n - 2)
    return (a + b) ** 2 / ((a * a / (k - 1) if 1 < k < math.inf else 0.0) + (b * b / (n - 1)))


@dataclass(frozen=True)
class WelchTest:
    r"""A printed mean over :math:`n` runs with its two-sided interval, against :math:`k` runs of ours.

    The printed interval :math:`\bar y \pm h`, at level :math:`1 - a`, gives the other sample's standard
    deviation, :math:`s_y = h\sqrt n / t_{1 - a/2,\,n-1}`; Welch's statistic is

    .. math:: T = \frac{\max(0, |\bar x - \bar y| - r)}{\sqrt{s_x^2/k + s_y^2/n}},

    Student-:math:`t` with the Welch-Satterthwaite degrees of freedom; :math:`r` is half a unit of the
    printed mean's last digit.

    Parameters
    ----------
    printed_mean : float
    printed_interval : (float, float)
        The printed interval of the mean (either order of ends).
    runs : int
        The printed mean's runs :math:`n` (>= 2).
    values : sequence of float
        Our runs' values (at least two).
    resolution : float
        :math:`r`, >= 0.
    interval_level : float
        The level :math:`1 - a` the printed interval was computed at (what it is, not what it is called).

    Raises
    ------
    ValueError
        On fewer than two runs on either side, a negative resolution, or non-finite numbers.
    """

    name: ClassVar[str] = "Welch t"

    printed_mean: float
    printed_interval: tuple[float, float]
    runs: int
    values: tuple[float, ...]
    resolution: float = 0.0
    interval_level: float = 0.95
    mean: float = field(init=False)
    sd: float = field(init=False)

    def __post_init__(self) -> None:
        _check_level(self.interval_level)
        lo, hi = sorted(float(v) for v in self.printed_interval)
        if not all(math.isfinite(v) for v in (lo, hi, self.printed_mean)):
            raise ValueError(f"printed_mean and printed_interval must be finite, got {self.printed_mean!r}, "
                             f"{self.printed_interval!r}")
        if int(self.runs) != self.runs or self.runs < 2:
            raise ValueError(f"runs must be an integer >= 2, got {self.runs!r}")
        if self.resolution < 0:
            raise ValueError(f"resolution must be >= 0, got {self.resolution!r}")
        m, sd, k = _mean_sd(self.values)
        if k < 2:
            raise ValueError(f"values must hold at least two runs, got {k}")
        object.__setattr__(self, "printed_interval", (lo, hi))
        object.__setattr__(self, "values", tuple(float(v) for v in self.values))
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "sd", sd)

    @property
    def seeds(self) -> int:
        return len(self.values)

    @property
    def printed_sd(self) -> float:
        r""":math:`s_y = h\sqrt n / t_{1 - a/2,\,n-1}`."""
        lo, hi = self.printed_interval
        return (hi - lo) / 2 * math.sqrt(self.runs) / t_critical(self.runs - 1, round(1 - self.interval_level, 12))

    def _variances(self, seeds: float) -> tuple[float, float]:
        return self.sd**2 / seeds, self.printed_sd**2 / self.runs

    @property
    def df(self) -> float:
        return _welch_df(*self._variances(self.seeds), self.seeds, self.runs)

    @property
    def statistic(self) -> float:
        d = max(0.0, abs(self.mean - self.printed_mean) - self.resolution)
        se = math.sqrt(sum(self._variances(self.seeds)))
        if d == 0:
            return 0.0
        return math.inf if se == 0 else d / se

    @property
    def p_value(self) -> float:
        return t_two_sided_p(self.statistic, self.df)

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float:
        """The smallest difference of the means the test detects with probability ``power`` at ``alpha``."""
        k = self.seeds if seeds is None else seeds
        a, b = self._variances(k)
        if a + b == 0:
            return self.resolution
        # Its degrees of freedom rounded down to a tenth: a slightly larger difference, and one noncentrality
        # for the many tests whose Welch-Satterthwaite counts differ in the second decimal.
        df = math.floor(10 * _welch_df(a, b, k, self.runs)) / 10
        return self.resolution + t_noncentrality(df, alpha, power) * math.sqrt(a + b)


def block_means(x: np.ndarray, curves: np.ndarray, blocks: int, x_range: tuple[float, float]) -> np.ndarray:
    r"""Each curve's mean over ``blocks`` equal parts of ``x_range`` (closed at both ends of the range):
    shape (curves, blocks). A block where a curve has no value (NaN) gives NaN.

    Raises
    ------
    ValueError
        If ``curves`` is not 2-D with one column per ``x``, or a block holds no x.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(curves, dtype=float)
    if y.ndim != 2 or y.shape[1] != x.size:
        raise ValueError(f"curves must be (curves, {x.size}), got {y.shape}")
    lo, hi = x_range
    edges = lo + (hi - lo) * np.arange(blocks + 1) / blocks
    out = np.empty((y.shape[0], blocks))
    for b in range(blocks):
        inside = (x >= edges[b]) & ((x < edges[b + 1]) if b < blocks - 1 else (x <= hi))
        if not inside.any():
            raise ValueError(f"block {b + 1} of {blocks} over {x_range} holds no x")
        with np.errstate(invalid="ignore"):
            out[:, b] = y[:, inside].mean(axis=1)
    return out


def _varying(ours: np.ndarray, theirs: np.ndarray) -> tuple[np.ndarray, bool]:
    """The blocks where our runs differ (columns with spread), and whether a constant block of ours
    differs from theirs (then no spread can account for it)."""
    spread = np.ptp(ours, axis=0) > 0
    off = bool(np.any(np.abs(theirs[..., ~spread] - ours[0, ~spread]) > 0)) if (~spread).any() else False
    return spread, off


@dataclass(frozen=True)
class CurvePredictionTest:
    r"""One printed curve against :math:`k` of ours, each reduced to its means over :math:`B` blocks.

    .. math:: T^2 = \frac{k}{k + 1} (y - \bar y)^\top S^{-1} (y - \bar y), \qquad
        F = \frac{k - B}{B(k - 1)} T^2 \sim F(B, k - B),

    :math:`S` our block means' sample covariance. Blocks where all our runs agree are left out (and
    the test rejects outright, :math:`p = 0`, where theirs differs there). Also the exact rank of their
    :math:`T^2` among the leave-one-out :math:`T^2` of all :math:`k + 1` curves (:attr:`rank_p_value`).

    Parameters
    ----------
    theirs : array_like, shape (B,)
    ours : array_like, shape (k, B)

    Raises
    ------
    ValueError
        On shapes that do not match or non-finite values.
    """

    name: ClassVar[str] = "Hotelling F, one curve"

    theirs: np.ndarray
    ours: np.ndarray

    def __post_init__(self) -> None:
        y, o = np.asarray(self.theirs, dtype=float), np.asarray(self.ours, dtype=float)
        if y.ndim != 1 or o.ndim != 2 or o.shape[1] != y.size:
            raise ValueError(f"theirs must be (B,) and ours (k, B), got {y.shape} and {o.shape}")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(o))):
            raise ValueError("theirs and ours must be finite")
        object.__setattr__(self, "theirs", y)
        object.__setattr__(self, "ours", o)

    @property
    def seeds(self) -> int:
        return int(self.ours.shape[0])

    @property
    def dims(self) -> int:
        """The blocks :math:`B` kept (with spread)."""
        return int(_varying(self.ours, self.theirs)[0].sum())

    def _t2(self, y: np.ndarray, o: np.ndarray) -> float:
        keep, _ = _varying(o, y)
        k = o.shape[0]
        v = y[keep] - o[:, keep].mean(axis=0)
        return float(k / (k + 1) * _quadratic(_covariance(o[:, keep]), v))

    @property
    def testable(self) -> bool:
        """More runs than kept blocks (else :math:`S` has no inverse)."""
        return self.seeds > self.dims

    @property
    def p_value(self) -> float:
        if _varying(self.ours, self.theirs)[1]:
            return 0.0
        b, k = self.dims, self.seeds
        if b == 0:
            return 1.0
        if not self.testable:
            return math.nan
        f = (k - b) / (b * (k - 1)) * self._t2(self.theirs, self.ours)
        return f_upper_p(f, b, k - b)

    @property
    def rank_p_value(self) -> float:
        """Exact: the share of the :math:`k + 1` curves (theirs among them) whose leave-one-out :math:`T^2` is
        at least theirs."""
        every = np.vstack([self.theirs[None, :], self.ours])
        if every.shape[0] - 1 <= self.dims:
            return math.nan
        t2 = [self._t2(every[i], np.delete(every, i, axis=0)) for i in range(every.shape[0])]
        return float(np.sum(np.asarray(t2) >= t2[0] * (1 - 1e-12))) / len(t2)

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float:
        r"""The smallest shift :math:`\Delta`, the same in every block, detected with probability ``power``:
        :math:`\lambda^* = \Delta^2 \frac{k}{k + 1} \mathbf 1^\top S^{-1} \mathbf 1`."""
        keep, _ = _varying(self.ours, self.theirs)
        b, k = int(keep.sum()), self.seeds if seeds is None else seeds
        if b == 0:
            return 0.0
        if k <= b:
            return math.inf
        ones = np.ones(b)
        q = _quadratic(_covariance(self.ours[:, keep]), ones)
        if not (math.isfinite(q) and q > 0):
            return math.inf
        return math.sqrt(f_noncentrality(b, k - b, alpha, power) / (q / (1 + 1 / k)))


def _hotelling_two_sample(groups: np.ndarray, mask: np.ndarray) -> np.ndarray:
    r"""Two-sample Hotelling :math:`T^2` for every split: ``groups`` (n, B) and ``mask`` (splits, n), True for
    the first sample. Pooled covariance; 2x2 and 3x3 inverses written out, so only ``+ - * /``."""
    n, b = groups.shape
    m = mask.sum(axis=1)[:, None].astype(float)
    first = (mask[:, :, None] * groups[None, :, :]).sum(axis=1) / m
    second = ((~mask)[:, :, None] * groups[None, :, :]).sum(axis=1) / (n - m)
    dev = np.where(mask[:, :, None], groups[None, :, :] - first[:, None, :], groups[None, :, :] - second[:, None, :])
    s = (dev[:, :, :, None] * dev[:, :, None, :]).sum(axis=1) / (n - 2)
    d = first - second
    w = (m[:, 0] * (n - m[:, 0]) / n)
    if b == 1:
        return np.asarray(w * d[:, 0] ** 2 / s[:, 0, 0])
    if b == 2:
        det = s[:, 0, 0] * s[:, 1, 1] - s[:, 0, 1] * s[:, 1, 0]
        q = (s[:, 1, 1] * d[:, 0] ** 2 - 2 * s[:, 0, 1] * d[:, 0] * d[:, 1] + s[:, 0, 0] * d[:, 1] ** 2) / det
        return np.asarray(w * q)
    if b == 3:
        a = s
        c00 = a[:, 1, 1] * a[:, 2, 2] - a[:, 1, 2] * a[:, 2, 1]
        c01 = a[:, 1, 2] * a[:, 2, 0] - a[:, 1, 0] * a[:, 2, 2]
        c02 = a[:, 1, 0] * a[:, 2, 1] - a[:, 1, 1] * a[:, 2, 0]
        c11 = a[:, 0, 0] * a[:, 2, 2] - a[:, 0, 2] * a[:, 2, 0]
        c12 = a[:, 0, 1] * a[:, 2, 0] - a[:, 0, 0] * a[:, 2, 1]
        c22 = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
        det = a[:, 0, 0] * c00 + a[:, 0, 1] * c01 + a[:, 0, 2] * c02
        x, y, z = d[:, 0], d[:, 1], d[:, 2]
        q = (c00 * x * x + c11 * y * y + c22 * z * z + 2 * c01 * x * y + 2 * c02 * x * z + 2 * c12 * y * z) / det
        return np.asarray(w * q)
    raise ValueError(f"blocks must be 1, 2 or 3, got {b}")


@dataclass(frozen=True)
class PermutationTest:
    r"""Their :math:`m` runs of a curve against :math:`k` of ours, each reduced to :math:`B \le 3` block means:
    the two-sample Hotelling :math:`T^2` (pooled covariance) and its exact permutation distribution,

    .. math:: p = \frac{\#\{\text{splits } \pi : T^2_\pi \ge T^2_{\text{observed}}\}}{\#\text{splits}},

    over every split of the :math:`m + k` runs into :math:`m` and :math:`k` (the observed one included),
    or, beyond :data:`EXHAUSTIVE_PERMUTATIONS` splits, over :data:`MONTE_CARLO_PERMUTATIONS` splits drawn
    with ``seed``, :math:`p = (1 + \#) / (1 + n)`. Blocks where every run agrees are left out.

    Raises
    ------
    ValueError
        On shapes that do not match, more than 3 blocks, or fewer than 2 runs a side.
    """

    name: ClassVar[str] = "permutation, Hotelling T²"

    theirs: np.ndarray
    ours: np.ndarray
    seed: int = 0

    def __post_init__(self) -> None:
        a, o = np.asarray(self.theirs, dtype=float), np.asarray(self.ours, dtype=float)
        if a.ndim != 2 or o.ndim != 2 or a.shape[1] != o.shape[1]:
            raise ValueError(f"theirs and ours must be (runs, B) with the same B, got {a.shape} and {o.shape}")
        if a.shape[1] > 3:
            raise ValueError(f"at most 3 blocks, got {a.shape[1]}")
        if a.shape[0] < 2 or o.shape[0] < 2:
            raise ValueError(f"at least 2 runs a side, got {a.shape[0]} and {o.shape[0]}")
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(o))):
            raise ValueError("theirs and ours must be finite")
        object.__setattr__(self, "theirs", a)
        object.__setattr__(self, "ours", o)

    @property
    def seeds(self) -> int:
        return int(self.ours.shape[0])

    @property
    def runs(self) -> int:
        """Their runs :math:`m`."""
        return int(self.theirs.shape[0])

    def _kept(self) -> np.ndarray:
        both = np.vstack([self.theirs, self.ours])
        return np.vstack([both[:, np.ptp(both, axis=0) > 0]])

    @property
    def splits(self) -> int:
        """How many splits of the runs there are, :math:`\\binom{m + k}{m}`."""
        return math.comb(self.runs + self.seeds, self.runs)

    @property
    def smallest_p(self) -> float:
        """The smallest p the test can give: one split in all (two when :math:`m = k`, where a split and its
        complement have the same :math:`T^2`), or :math:`1/(1 + n)` by Monte Carlo."""
        if self.splits > EXHAUSTIVE_PERMUTATIONS:
            return 1 / (1 + MONTE_CARLO_PERMUTATIONS)
        return (2 if self.runs == self.seeds else 1) / self.splits

    @property
    def p_value(self) -> float:
        groups = self._kept()
        n, m = groups.shape[0], self.runs
        if groups.shape[1] == 0:
            return 1.0
        observed = np.zeros((1, n), dtype=bool)
        observed[0, :m] = True
        with np.errstate(invalid="ignore", divide="ignore"):
            t_obs = float(_hotelling_two_sample(groups, observed)[0])
        if not math.isfinite(t_obs):  # a singular pooled covariance: too few runs for the blocks
            return math.nan
        if self.splits <= EXHAUSTIVE_PERMUTATIONS:
            idx = np.array(list(itertools.combinations(range(n), m)))
            mask = np.zeros((idx.shape[0], n), dtype=bool)
            np.put_along_axis(mask, idx, True, axis=1)
            count, total = 0, 0
            for lo in range(0, mask.shape[0], 20_000):
                with np.errstate(invalid="ignore", divide="ignore"):
                    t = _hotelling_two_sample(groups, mask[lo:lo + 20_000])
                count += int(np.sum(t >= t_obs * (1 - 1e-12)))
                total += t.size
            return count / total
        rng = np.random.default_rng(self.seed)
        count = 0
        for lo in range(0, MONTE_CARLO_PERMUTATIONS, 20_000):
            size = min(20_000, MONTE_CARLO_PERMUTATIONS - lo)
            order = np.argsort(rng.random((size, n)), axis=1)
            mask = np.zeros((size, n), dtype=bool)
            np.put_along_axis(mask, order[:, :m], True, axis=1)
            with np.errstate(invalid="ignore", divide="ignore"):
                count += int(np.sum(_hotelling_two_sample(groups, mask) >= t_obs * (1 - 1e-12)))
        return (1 + count) / (1 + MONTE_CARLO_PERMUTATIONS)

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float:
        r"""The smallest uniform shift :math:`\Delta` of their curves detected with probability ``power`` at
        ``alpha``, by the power of the parametric two-sample test the permutation test matches under normal
        runs, :math:`F(B, m + k - B - 1)` with :math:`\lambda = \Delta^2 \frac{mk}{m + k}\mathbf 1^\top
        S_p^{-1}\mathbf 1`; infinite where the permutation test's smallest p-value (:attr:`smallest_p`) is above
        :data:`PERMUTATION_RESOLUTION` times ``alpha``."""
        k = self.seeds if seeds is None else seeds
        m = self.runs
        # With unlimited runs of ours the permutation p-value can be as small as any level.
        if math.isinf(k):
            smallest = 0.0
        elif math.comb(m + int(k), m) > EXHAUSTIVE_PERMUTATIONS:
            smallest = 1 / (1 + MONTE_CARLO_PERMUTATIONS)
        else:
            smallest = (2 if m == k else 1) / math.comb(m + int(k), m)
        if smallest > PERMUTATION_RESOLUTION * alpha:
            return math.inf
        groups = self._kept()
        b = groups.shape[1]
        if b == 0:
            return 0.0
        a, o = groups[:m], groups[m:]
        pooled = ((m - 1) * _covariance(a) + (self.seeds - 1) * _covariance(o)) / (m + self.seeds - 2)
        with np.errstate(invalid="ignore", divide="ignore"):
            q = _quadratic(pooled, np.ones(b))
        if not (math.isfinite(q) and q > 0):
            return math.inf
        d2 = m + k - b - 1
        if d2 <= 0:
            return math.inf
        return math.sqrt(f_noncentrality(b, d2, alpha, power) / (q * m / (1 + m / k)))


class Test(Protocol):
    """What every test here offers: its name, its runs of ours, a two-sided p-value and the detectable
    difference."""

    @property
    def name(self) -> str: ...

    @property
    def seeds(self) -> int: ...

    @property
    def p_value(self) -> float: ...

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float: ...


@dataclass(frozen=True)
class AllOf:
    r"""A claim made of several (every configuration's step "of the order of 1e-5"): it fails when any
    part fails. Bonferroni over the :math:`n` parts, :math:`p = \min(1, n \min_i p_i)`; its detectable
    difference is the largest of the parts' at level :math:`\alpha / n`.

    Raises
    ------
    ValueError
        If no part is given.
    """

    parts: tuple[Test, ...]

    def __post_init__(self) -> None:
        if not self.parts:
            raise ValueError("parts must hold at least one test")
        object.__setattr__(self, "parts", tuple(self.parts))

    @property
    def name(self) -> str:
        return f"{self.parts[0].name}, each of {len(self.parts)} (Bonferroni)" if len(self.parts) > 1 else \
            self.parts[0].name

    @property
    def seeds(self) -> int:
        return int(min(t.seeds for t in self.parts))

    @property
    def p_value(self) -> float:
        return float(min(1.0, len(self.parts) * min(t.p_value for t in self.parts)))

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = POWER) -> float:
        return float(max(t.detectable_difference(alpha / len(self.parts), seeds, power) for t in self.parts))


def seeds_for(test: Test, alpha: float, difference: float, block: int = 5, limit: int = 400,
              power: float = POWER) -> int | None:
    """The fewest runs of ours, the present count plus whole ``block``s, at which ``test`` would detect
    ``difference`` with probability ``power`` at level ``alpha`` (at the spread it has now); None when not
    even ``limit`` runs would (one run of the process scatters more than ``difference``).

    Raises
    ------
    ValueError
        If ``block`` is not a positive integer.
    """
    if int(block) != block or block < 1:
        raise ValueError(f"block must be a positive integer, got {block!r}")

    def enough(k: int) -> bool:
        return test.detectable_difference(alpha, k, power) <= difference * (1 + 1e-12)

    steps = max(0, (limit - test.seeds) // block)
    if enough(test.seeds):
        return test.seeds
    if steps == 0 or not enough(test.seeds + steps * block):
        return None
    lo, hi = 0, steps  # not enough at lo, enough at hi: the detectable difference falls with the runs
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if enough(test.seeds + mid * block):
            hi = mid
        else:
            lo = mid
    return test.seeds + hi * block


# ------------------------------------------------------------------ many tests at once
def benjamini_hochberg(p_values: Sequence[float], q: float) -> tuple[np.ndarray, float]:
    r"""The Benjamini-Hochberg procedure at false discovery rate ``q``: reject the :math:`R` smallest
    p-values, :math:`R = \max\{i : p_{(i)} \le i q / m\}`.

    Returns
    -------
    rejected : ndarray of bool, shape (m,)
    level : float
        The threshold a test not rejected would have had to meet to join them, :math:`(R + 1) q / m`
        (at most 1): the level at which its detectable difference is stated.

    Raises
    ------
    ValueError
        If ``q`` is not in (0, 1) or a p-value is outside [0, 1] or NaN.
    """
    _check_level(q)
    p = np.asarray(p_values, dtype=float)
    if p.ndim != 1 or np.any(~((p >= 0) & (p <= 1))):
        raise ValueError(f"p_values must be a 1-D sequence of numbers in [0, 1], got {p_values!r}")
    m = p.size
    if m == 0:
        return np.zeros(0, dtype=bool), q
    order = np.argsort(p, kind="stable")
    below = np.flatnonzero(p[order] <= q * np.arange(1, m + 1) / m)
    r = int(below[-1]) + 1 if below.size else 0
    rejected = np.zeros(m, dtype=bool)
    rejected[order[:r]] = True
    return rejected, min(1.0, (r + 1) * q / m)


__all__ = ["EXHAUSTIVE_PERMUTATIONS", "MONTE_CARLO_PERMUTATIONS", "PERMUTATION_RESOLUTION", "POWER", "AllOf",
           "CurvePredictionTest", "PermutationTest", "PredictionTest", "Test", "WelchTest", "benjamini_hochberg",
           "block_means", "clopper_pearson", "f_critical", "f_noncentrality", "f_upper_p", "seeds_for", "t_critical",
           "t_noncentrality", "t_two_sided_p"]
