r"""Tests of printed curves against runs of ours, on each curve's means over :math:`B` blocks of
the plotted range (:func:`block_means`).

- :class:`CurvePredictionTest`: **one printed curve** against :math:`k` of ours: Hotelling's
  :math:`T^2` for one new observation, :math:`\frac{k - B}{B(k - 1)}T^2 \sim F(B, k - B)` under
  normal runs.
- :class:`PermutationTest`: :math:`m` **printed runs of a curve** against :math:`k` of ours, by the
  two-sample Hotelling :math:`T^2` of their block means and its exact permutation distribution.

Both follow :class:`safepg.significance.Test`: a two-sided p-value and the detectable difference,
here a shift of every block by the same amount. Covariances are elementwise products and solves go
through :mod:`safepg.portable`, so their bits do not depend on the CPU.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from safepg import portable
from safepg.distributions import POWER, f_noncentrality, f_upper_p

#: Permutations enumerated exhaustively up to this many; beyond it, a seeded Monte Carlo sample.
EXHAUSTIVE_PERMUTATIONS = 200_000
#: Monte Carlo permutations when enumerating them all would be too many.
MONTE_CARLO_PERMUTATIONS = 99_999
#: A permutation test's detectable difference is stated only where its smallest p-value is at most this
#: share of the level: nearer the level, its discreteness, not the data, limits its power, and the
#: parametric power it is computed by would overstate it.
PERMUTATION_RESOLUTION = 0.1


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


__all__ = ["EXHAUSTIVE_PERMUTATIONS", "MONTE_CARLO_PERMUTATIONS", "PERMUTATION_RESOLUTION", "CurvePredictionTest",
           "PermutationTest", "block_means"]
