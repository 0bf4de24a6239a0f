"""Summaries over seeds, computed the same on every CPU: the mean and its 95% Student-t interval,
and the aggregate statistics of Agarwal et al. (2021) as their library rliable defines them (the
interquartile mean, stratified-bootstrap percentile intervals, the probability of improvement)."""

from __future__ import annotations

import math
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


# ------------------------------------------------------------------ rliable's statistics
# Agarwal, Schwarzer, Castro, Courville, Bellemare, "Deep reinforcement learning at the edge of the
# statistical precipice", NeurIPS 2021, and their library rliable (metrics.py, library.py): with one
# task, the scores of a method are its runs' final scores. Written here with sums in a fixed order
# (math.fsum, or columns added one after another), so that every number is the same on every CPU.

#: rliable's default number of bootstrap replications.
BOOTSTRAP_REPS = 50_000


def _scores(values: Iterable[float], name: str = "scores") -> np.ndarray:
    x = np.asarray(list(values), dtype=float).ravel()
    if x.size == 0 or not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be one or more finite numbers, got {x.size} values")
    return x


def _trim(n: int) -> tuple[int, int]:
    """The rows kept by the 25% trimmed mean of n values: [int(n / 4), n - int(n / 4)) of the sorted ones,
    ``scipy.stats.trim_mean(x, 0.25)``'s cut."""
    low = int(0.25 * n)
    return low, n - low


def interquartile_mean(values: Iterable[float]) -> float:
    r"""The interquartile mean (IQM): the mean of the middle half of the sorted scores.

    rliable's ``aggregate_iqm``, ``scipy.stats.trim_mean(scores, proportiontocut=0.25)``: of n
    scores sorted, :math:`\lfloor n/4 \rfloor` are cut at each end and the rest averaged (exactly
    rounded: :func:`!math.fsum`).
    """
    x = np.sort(_scores(values))
    low, high = _trim(x.size)
    return math.fsum(x[low:high].tolist()) / (high - low)


def probability_of_improvement(x: Iterable[float], y: Iterable[float]) -> float:
    r""":math:`P(X > Y)`, the probability that a run of X scores above a run of Y, ties counting half.

    rliable's ``probability_of_improvement`` on one task: the Mann-Whitney statistic
    :math:`U = \sum_{i,j} [x_i > y_j] + \tfrac12 [x_i = y_j]` over :math:`n_x n_y` (0.5 when the
    two score arrays are equal).
    """
    a, b = _scores(x, "x"), _scores(y, "y")
    if a.shape == b.shape and np.array_equal(a, b):
        return 0.5
    greater = int(np.count_nonzero(a[:, None] > b[None, :]))
    ties = int(np.count_nonzero(a[:, None] == b[None, :]))
    return (greater + 0.5 * ties) / (a.size * b.size)


def _row_means(a: np.ndarray, low: int, high: int) -> np.ndarray:
    """Mean of columns low..high-1 of each row, the columns added one after another."""
    out = a[:, low].copy()
    for j in range(low + 1, high):
        out = out + a[:, j]
    return np.asarray(out / (high - low))


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def bootstrap_interval(values: Iterable[float], statistic: str = "mean", reps: int = BOOTSTRAP_REPS,
                       level: float = 0.95, rng: np.random.Generator | int | None = 0,
                       chunk: int = 5_000) -> list[float]:
    r"""The stratified-bootstrap percentile interval of the mean or the IQM of one method's scores.

    rliable's ``get_interval_estimates(..., method="percentile")`` on one task: ``reps`` resamples of
    the n runs, drawn with replacement; the statistic of each; the interval between the
    :math:`(1 - \text{level})/2` and :math:`(1 + \text{level})/2` quantiles of those
    (``np.percentile``, linear interpolation, as arch's ``conf_int`` takes them).

    Parameters
    ----------
    values
        The runs' scores.
    statistic : {"mean", "iqm"}
        The mean or :func:`interquartile_mean`.
    reps : int
        Bootstrap replications (rliable's default 50 000).
    level : float
        Coverage of the interval.
    rng : Generator, int or None
        Seed of the resamples (rliable draws them from NumPy's global state).
    chunk : int
        Resamples formed at once (memory only: the numbers do not depend on it).

    Returns
    -------
    list of float
        ``[lower, upper]``.
    """
    x = _scores(values)
    if statistic not in ("mean", "iqm"):
        raise ValueError(f"statistic must be 'mean' or 'iqm', got {statistic!r}")
    _check_bootstrap(reps, level)
    gen = _rng(rng)
    idx = gen.integers(0, x.size, size=(int(reps), x.size))
    low, high = (0, x.size) if statistic == "mean" else _trim(x.size)
    stats = np.concatenate([_row_means(np.sort(x[idx[i:i + chunk]], axis=1) if statistic == "iqm"
                                       else x[idx[i:i + chunk]], low, high) for i in range(0, int(reps), chunk)])
    return _percentile_interval(stats, level)


def improvement_interval(x: Iterable[float], y: Iterable[float], reps: int = BOOTSTRAP_REPS, level: float = 0.95,
                         rng: np.random.Generator | int | None = 0, chunk: int = 2_000) -> list[float]:
    """The percentile interval of :func:`probability_of_improvement`, X and Y resampled independently
    (rliable's ``StratifiedIndependentBootstrap``): ``[lower, upper]``."""
    a, b = _scores(x, "x"), _scores(y, "y")
    _check_bootstrap(reps, level)
    gen = _rng(rng)
    ia = gen.integers(0, a.size, size=(int(reps), a.size))
    ib = gen.integers(0, b.size, size=(int(reps), b.size))
    out = []
    for i in range(0, int(reps), chunk):
        ra, rb = a[ia[i:i + chunk]][:, :, None], b[ib[i:i + chunk]][:, None, :]
        counts = 2 * np.count_nonzero(ra > rb, axis=(1, 2)) + np.count_nonzero(ra == rb, axis=(1, 2))
        p = counts / (2 * a.size * b.size)
        # rliable's 0.5 where the two resamples are the same array
        same = np.all(a[ia[i:i + chunk]] == b[ib[i:i + chunk]], axis=1) if a.size == b.size else np.zeros(len(p), bool)
        out.append(np.where(same, 0.5, p))
    return _percentile_interval(np.concatenate(out), level)


def _check_bootstrap(reps: int, level: float) -> None:
    if isinstance(reps, bool) or int(reps) != reps or reps < 1:
        raise ValueError(f"reps must be a positive integer, got {reps!r}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")


def _percentile_interval(stats: np.ndarray, level: float) -> list[float]:
    tail = (1.0 - level) / 2
    lo, hi = np.percentile(stats, [100 * tail, 100 * (1.0 - tail)])
    return [float(lo), float(hi)]


def aggregate_scores(values: Iterable[float], reps: int = BOOTSTRAP_REPS,
                     rng: np.random.Generator | int | None = 0) -> dict[str, Any]:
    """The mean and the IQM of one method's scores with their 95% bootstrap intervals.

    Returns
    -------
    dict
        ``{"runs", "mean", "mean_ci95", "iqm", "iqm_ci95"}``; both intervals from one seed ``rng``
        (the mean's resamples first, then the IQM's).
    """
    x = _scores(values)
    gen = _rng(rng)
    return {"runs": int(x.size), "mean": math.fsum(x.tolist()) / x.size,
            "mean_ci95": bootstrap_interval(x, "mean", reps, rng=gen), "iqm": interquartile_mean(x),
            "iqm_ci95": bootstrap_interval(x, "iqm", reps, rng=gen)}


__all__ = ["BOOTSTRAP_REPS", "aggregate_scores", "bootstrap_interval", "improvement_interval", "interquartile_mean",
           "mean_ci95", "prediction_band95", "prediction_interval95", "probability_of_improvement", "seed_summary95",
           "t_quantile", "t_quantile_975"]
