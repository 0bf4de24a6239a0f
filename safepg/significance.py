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
- :class:`safepg.curve_tests.CurvePredictionTest`: **one printed curve**, reduced to its means over :math:`B` blocks
  of the plotted range, against :math:`k` of ours: Hotelling's :math:`T^2` for one new
  observation, :math:`\frac{k - B}{B(k - 1)}T^2 \sim F(B, k - B)` under normal runs.
- :class:`safepg.curve_tests.PermutationTest`: :math:`m` **printed runs of a curve** against :math:`k` of ours, by the
  two-sample Hotelling :math:`T^2` of their block means and its exact permutation distribution.

The first three are exact only for normal runs: their level is measured, not assumed
(``safepg.thesis.false_alarms``). The permutation test is exact for any distribution.
:func:`benjamini_hochberg` controls the false discovery rate over a family of them.

Every probability is computed with mpmath (software arithmetic, :mod:`safepg.distributions`) and
every matrix with :mod:`safepg.portable`, so p-values and detectable differences are the same bits on any CPU.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import numpy as np

from safepg.distributions import (
    POWER,
    check_level,
    t_critical,
    t_noncentrality,
    t_two_sided_p,
)


# ------------------------------------------------------------------ small statistics, CPU-independent
def _store_runs(test: Any, values: Sequence[float] | np.ndarray) -> None:
    """Set a frozen test's ``values`` (as floats), ``mean`` and ``sd`` (ddof = 1) from our runs, of which it
    needs two."""
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError(f"values must be a non-empty 1-D sequence of finite numbers, got shape {x.shape}")
    if x.size < 2:
        raise ValueError(f"values must hold at least two runs, got {x.size}")
    m = float(x.mean())
    object.__setattr__(test, "values", tuple(float(v) for v in x))
    object.__setattr__(test, "mean", m)
    object.__setattr__(test, "sd", float(np.sqrt(np.sum((x - m) ** 2) / (x.size - 1))))


# ------------------------------------------------------------------ the tests
@dataclass(frozen=True)
class PredictionTest:
    r"""A number printed from one run, against :math:`k` runs of ours.

    The printed number is an interval ``printed`` (its value give or take its rounding, or a reading
    precision: "≈ 500" is 450 to 550); the statistic is the distance of our mean from it, less a
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
        _store_runs(self, self.values)
        object.__setattr__(self, "printed", (lo, hi))

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
        check_level(self.interval_level, "interval_level")
        lo, hi = sorted(float(v) for v in self.printed_interval)
        if not all(math.isfinite(v) for v in (lo, hi, self.printed_mean)):
            raise ValueError(f"printed_mean and printed_interval must be finite, got {self.printed_mean!r}, "
                             f"{self.printed_interval!r}")
        if int(self.runs) != self.runs or self.runs < 2:
            raise ValueError(f"runs must be an integer >= 2, got {self.runs!r}")
        if self.resolution < 0:
            raise ValueError(f"resolution must be >= 0, got {self.resolution!r}")
        _store_runs(self, self.values)
        object.__setattr__(self, "printed_interval", (lo, hi))

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
        If ``q`` is not in (0, 1) or a p-value is NaN or outside 0 to 1.
    """
    check_level(q, "q")
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


__all__ = ["POWER", "AllOf", "PredictionTest", "Test", "WelchTest", "benjamini_hochberg", "seeds_for"]
