"""Summaries over seeds: the mean and its 95% Student-t interval, computed the same on every CPU."""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache
from typing import Any

import numpy as np


def mean_ci95(values: Iterable[float]) -> dict[str, Any]:
    r"""Mean and 95% Student-t confidence interval over seeds.

    .. math:: \bar x \pm t_{0.975,\,n-1}\, s / \sqrt n,

    with :math:`s` the sample standard deviation (ddof = 1).

    Returns
    -------
    dict
        ``{"mean": m, "ci95": [lo, hi]}``; ``None`` entries for no values, a zero-width
        interval for one value.
    """
    x = np.asarray(list(values), dtype=float)
    if x.size == 0:
        return {"mean": None, "ci95": [None, None]}
    m = float(x.mean())
    if x.size < 2:
        return {"mean": m, "ci95": [m, m]}
    h = float(t_quantile_975(x.size - 1) * x.std(ddof=1) / np.sqrt(x.size))
    return {"mean": m, "ci95": [m - h, m + h]}


def prediction_interval95(values: Iterable[float], runs: int = 1) -> dict[str, Any]:
    r"""Mean over seeds and the 95% prediction interval for one new run, or for a mean of ``runs`` new runs.

    .. math:: \bar x \pm t_{0.975,\,k-1}\, s \sqrt{1/n + 1/k},

    with :math:`k` seeds, :math:`s` their sample standard deviation (ddof = 1) and :math:`n` =
    ``runs``. Where :func:`mean_ci95`'s interval holds the *mean* of the process, this one holds a
    single run of it (``runs=1``) with probability 0.95, under normal runs: the interval to judge
    a number that the thesis printed from one run.

    Returns
    -------
    dict
        ``{"mean": m, "pi95": [lo, hi], "seeds": k, "runs": n}``; ``None`` ends for fewer than two
        values (no spread to predict from).

    Raises
    ------
    ValueError
        If ``runs`` is not a positive integer.
    """
    if int(runs) != runs or runs < 1:
        raise ValueError(f"runs must be a positive integer, got {runs!r}")
    x = np.asarray(list(values), dtype=float)
    if x.size < 2:
        return {"mean": float(x.mean()) if x.size else None, "pi95": [None, None], "seeds": int(x.size),
                "runs": int(runs)}
    m = float(x.mean())
    h = float(t_quantile_975(x.size - 1) * x.std(ddof=1) * np.sqrt(1 / runs + 1 / x.size))
    return {"mean": m, "pi95": [m - h, m + h], "seeds": int(x.size), "runs": int(runs)}


def seed_summary95(values: Iterable[float]) -> dict[str, Any]:
    """:func:`mean_ci95` with the prediction interval for one run beside it: ``{"mean", "ci95", "pi95"}``
    (the interval of the mean, to judge a printed mean; the prediction interval, to judge one printed run)."""
    x = list(values)
    return {**mean_ci95(x), "pi95": prediction_interval95(x)["pi95"]}


def prediction_band95(values: np.ndarray, runs: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r""":func:`prediction_interval95` at every point of a curve: the 95% prediction band over seeds.

    At each column (point) with :math:`k \ge 2` seeds present (non-NaN entries of axis 0),

    .. math:: \bar x \pm t_{0.975,\,k-1}\, s \sqrt{1/n + 1/k},

    :math:`s` the seeds' sample standard deviation (ddof = 1) and :math:`n` = ``runs``: the band
    that holds one new run of the process (``runs=1``), or the mean of ``runs`` new runs, with
    probability 0.95 at that point, under normal runs. Elementwise arithmetic over seeds in their
    order and mpmath's quantile: the same bits on every CPU.

    Parameters
    ----------
    values : array_like, shape (seeds, points)
        One curve per seed; NaN where a seed has no value (a run that ended earlier).
    runs : int
        How many runs the predicted curve averages (n).

    Returns
    -------
    mean, half, seeds : ndarray, shape (points,)
        Seed mean (NaN without seeds), the band's half-width (NaN where fewer than two seeds)
        and the number of seeds k at each point.

    Raises
    ------
    ValueError
        If ``runs`` is not a positive integer or ``values`` is not 2-D.
    """
    if int(runs) != runs or runs < 1:
        raise ValueError(f"runs must be a positive integer, got {runs!r}")
    v = np.asarray(values, dtype=float)
    if v.ndim != 2:
        raise ValueError(f"values must be 2-D (seeds, points), got shape {v.shape}")
    present = ~np.isnan(v)
    k = present.sum(axis=0)
    filled = np.where(present, v, 0.0)
    total = np.zeros(v.shape[1])
    for row in filled:  # seeds in order: a fixed summation order
        total = total + row
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / k
        squares = np.zeros(v.shape[1])
        for row, ok in zip(filled, present):
            squares = squares + np.where(ok, (row - mean) ** 2, 0.0)
        sd = np.sqrt(squares / (k - 1))
    # One quantile per distinct seed count, not per point: a curve has thousands of points.
    counts, where = np.unique(k, return_inverse=True)
    t = np.array([t_quantile_975(int(n) - 1) if n > 1 else np.nan for n in counts])[where.reshape(k.shape)]
    half = np.where(k > 1, t * sd * np.sqrt(1 / runs + 1 / np.maximum(k, 1)), np.nan)
    return mean, half, k


@cache
def t_quantile_975(df: int) -> float:
    """0.975 quantile of Student's t with ``df`` degrees of freedom (:func:`t_quantile` with both
    tails holding 0.05, the 95% interval)."""
    return t_quantile(df, "0.05")


@cache
def t_quantile(df: int, tails: str) -> float:
    """Upper quantile of Student's t with ``df`` degrees of freedom leaving ``tails`` in the two tails.

    ``tails="0.05"`` gives the 0.975 quantile (a 95% two-sided interval), ``"0.1"`` the 0.95
    quantile (90%). ``tails`` is a decimal string, read exactly by mpmath.

    Computed with mpmath (software arithmetic), not ``scipy.stats.t.ppf``, whose special
    functions call libm and can differ across CPUs in the last bit of a reported interval.
    Solves :math:`I_x(df/2, 1/2) = tails` for :math:`x = df / (df + t^2)`.
    """
    import mpmath

    if int(df) != df or df < 1:
        raise ValueError(f"df must be a positive integer, got {df}")
    with mpmath.workdps(40):
        target = mpmath.mpf(tails)
        if not 0 < target < 1:
            raise ValueError(f"tails must be in (0, 1), got {tails!r}")
        a = mpmath.mpf(df) / 2
        lo, hi = mpmath.mpf(0), mpmath.mpf(1)
        for _ in range(80):  # bisection: I_x increases in x; x > 0.006 for df >= 1, so 2^-80 is below its ulp
            mid = (lo + hi) / 2
            if mpmath.betainc(a, 0.5, 0, mid, regularized=True) < target:
                lo = mid
            else:
                hi = mid
        return float(mpmath.sqrt(df * (1 - lo) / lo))


__all__ = ["mean_ci95", "prediction_band95", "prediction_interval95", "seed_summary95", "t_quantile", "t_quantile_975"]
