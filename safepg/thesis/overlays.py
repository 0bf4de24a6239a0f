"""Our runs drawn over the authors' raw outputs (``safepg.thesis.authors``): one function per figure.

Each function draws our curve (mean and 95% band over seeds) over the authors' own run(s)
of the same setting, from the stored records and the data files, and returns the figure.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from safepg.learning import LearningRecord
from safepg.stats import t_quantile_975
from safepg.thesis.authors import LQG2D_BOUND, AuthorsRun, lqg2d_runs

# ---------------------------------------------------------------- Section 5.1: 1-D fixed-step runs


# ---------------------------------------------------------------- Section 5.2: 2-D runs
#: The authors' 2-D J (``authors.lqg2d_performance``, the J column of their outputs) over the
#: expectation over the initial state: their code integrates over the box [-b, b]^2 instead of
#: averaging, which multiplies by its area (2b)^2 = 16.
LQG2D_AUTHORS_SCALE = (2 * LQG2D_BOUND) ** 2
#: One colour per 2-D method; the authors' run of a method is drawn dashed in its colour.
_LQG2D_COLORS = {"adaptive": "#7d4fb0", "adaptive-authors": "#c0392b", "N=1000": "#3b6fb6", "N=100": "#d98c2b",
                 "scalar": "#3b6fb6", "coordinate": "#7d4fb0"}


#: Our mean is drawn broad and light, their run dashed and dark on top of it, so both stay visible
#: where they coincide.
_LQG2D_OURS = {"linewidth": 2.6, "alpha": 0.6}
_LQG2D_THEIRS = {"linestyle": (0, (4, 3)), "linewidth": 1.3, "zorder": 3}


def _lqg2d_dark(key: str) -> tuple[float, float, float]:
    return tuple(0.55 * c for c in to_rgb(_LQG2D_COLORS.get(key, "#444444")))


def lqg2d_band(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seed mean and 95% Student-t band of ``values`` (seeds, points), point by point.

    NaN entries (past a run's end) are left out; where fewer than two seeds remain the band
    is the mean itself.
    """
    v = np.asarray(values, dtype=float)
    n = np.sum(np.isfinite(v), axis=0)
    with warnings.catch_warnings():  # all-NaN columns and single seeds: NaN, handled below
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(v, axis=0)
        sd = np.nanstd(v, axis=0, ddof=1)
    half = np.zeros_like(mean)
    for k in np.unique(n[n >= 2]):
        half[n == k] = t_quantile_975(int(k) - 1) * sd[n == k] / np.sqrt(k)
    return mean, mean - half, mean + half


def lqg2d_held(batch_size: np.ndarray, values: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """The value of the batch that holds trajectory T, for T in ``grid`` (1-based); NaN past the end.

    The thesis's "performance over sample trajectories": each batch's J is held over its batch.
    """
    ends = np.cumsum(np.asarray(batch_size, dtype=float))
    idx = np.searchsorted(ends, np.asarray(grid))
    out = np.full(np.asarray(grid).shape, np.nan)
    ok = idx < ends.size
    out[ok] = np.asarray(values, dtype=float)[idx[ok]]
    return out


def _lqg2d_grid(records: Mapping[str, Sequence[LearningRecord]], runs: Mapping[str, AuthorsRun],
                points: int = 600) -> np.ndarray:
    total = max([r.trajectories for recs in records.values() for r in recs]
                + [float(run["N"].sum()) for run in runs.values()])
    return np.unique(np.linspace(1, total, points).astype(np.int64))


def _lqg2d_authors_axis(ax: plt.Axes) -> None:
    """A right-hand axis in the authors' units (16 times ours), for reading the printed figures."""
    sec = ax.secondary_yaxis("right", functions=(lambda y: y * LQG2D_AUTHORS_SCALE,
                                                 lambda y: y / LQG2D_AUTHORS_SCALE))
    sec.set_ylabel(f"authors' units ({LQG2D_AUTHORS_SCALE:g}× J)")


def _lqg2d_performance_figure(ours: Mapping[str, tuple[str, Sequence[LearningRecord]]],
                              theirs: Mapping[str, tuple[str, AuthorsRun]]) -> Figure:
    grid = _lqg2d_grid({k: recs for k, (_, recs) in ours.items()}, {k: run for k, (_, run) in theirs.items()})
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for key, (label, recs) in ours.items():
        mean, lo, hi = lqg2d_band(np.array([lqg2d_held(r.batch_size, r.J, grid) for r in recs]))
        color = _LQG2D_COLORS.get(key)
        ax.plot(grid, mean, color=color, label=label, gid=f"ours:{key}", **_LQG2D_OURS)
        ax.fill_between(grid, lo, hi, color=color, alpha=0.25, linewidth=0)
    for key, (label, run) in theirs.items():
        ax.plot(grid, lqg2d_held(run["N"], run["J"], grid) / LQG2D_AUTHORS_SCALE, color=_lqg2d_dark(key),
                label=label, gid=f"authors:{key}", **_LQG2D_THEIRS)
    ax.set_xlabel("trajectories")
    ax.set_ylabel(r"expected performance $J(\theta)$")
    _lqg2d_authors_axis(ax)
    ax.legend(fontsize="small", loc="lower right")
    fig.tight_layout()
    return fig


def lqg2d_binned(values: np.ndarray, width: int) -> np.ndarray:
    """Means of consecutive blocks of ``width`` iterations along the last axis (NaN-aware; a
    block with no value is NaN), so that per-iteration noise does not hide the trend."""
    v = np.atleast_2d(np.asarray(values, dtype=float))
    blocks = -(-v.shape[1] // width)
    padded = np.full((v.shape[0], blocks * width), np.nan)
    padded[:, : v.shape[1]] = v
    with warnings.catch_warnings():  # empty blocks past a run's end: NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(padded.reshape(v.shape[0], blocks, width), axis=2)


def _lqg2d_iteration_figure(field: str, ours: Mapping[str, tuple[str, Sequence[LearningRecord]]],
                            theirs: Mapping[str, tuple[str, AuthorsRun]], ylabel: str, log: bool,
                            points: int = 150) -> Figure:
    column = {"batch_size": "N", "alpha": "alpha"}[field]
    length = max([r.iterations for _, recs in ours.values() for r in recs]
                 + [run.iterations for _, run in theirs.values()])
    width = max(1, length // points)
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, (label, recs) in ours.items():
        values = np.full((len(recs), length), np.nan)
        for i, r in enumerate(recs):
            values[i, : r.iterations] = getattr(r, field)
        binned = lqg2d_binned(values, width)
        mean, lo, hi = lqg2d_band(binned)
        # Only where most seeds still run: with one or two seeds left the band is meaningless.
        few = np.sum(np.isfinite(binned), axis=0) < min(3, len(recs))
        mean[few] = lo[few] = hi[few] = np.nan
        it = width * np.arange(mean.size) + (width + 1) / 2
        color = _LQG2D_COLORS.get(key)
        ax.plot(it, mean, color=color, label=label, gid=f"ours:{key}", **_LQG2D_OURS)
        ax.fill_between(it, lo, hi, color=color, alpha=0.25, linewidth=0)
    for key, (label, run) in theirs.items():
        binned = lqg2d_binned(run[column], width)[0]
        ax.plot(width * np.arange(binned.size) + (width + 1) / 2, binned, color=_lqg2d_dark(key), label=label,
                gid=f"authors:{key}", **_LQG2D_THEIRS)
    ax.set_xlabel("iteration" if width == 1 else f"iteration (means over blocks of {width})")
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def figure_5_5_overlay(records: Mapping[str, Sequence[LearningRecord]],
                       runs: Mapping[str, AuthorsRun] | None = None) -> Figure:
    """Figure 5.5 over the authors' runs: the scalar and the coordinate step, N = 2000.

    ``records``: the ``figures-5.5-5.6`` runs (``"scalar"``, ``"coordinate"``); ``runs``: the
    authors' 2-D runs (default :func:`safepg.thesis.authors.lqg2d_runs`). Their J is divided by
    :data:`LQG2D_AUTHORS_SCALE` to be on our scale; the right axis reads in theirs.
    """
    runs = lqg2d_runs() if runs is None else runs
    names = {"scalar": r"scalar step $\hat\alpha^*$", "coordinate": r"coordinate step $\Lambda^*$"}
    return _lqg2d_performance_figure({k: (f"{v}, ours", records[k]) for k, v in names.items()},
                                     {k: (f"{v}, authors' run", runs[k]) for k, v in names.items() if k in runs})


def figure_5_6_overlay(records: Mapping[str, Sequence[LearningRecord]],
                       runs: Mapping[str, AuthorsRun] | None = None) -> Figure:
    r"""Figure 5.6 over the authors' runs: the recorded step size per iteration (the scalar
    :math:`\hat\alpha^*`; :math:`\|\Lambda^*\|_\infty` for the coordinate step)."""
    runs = lqg2d_runs() if runs is None else runs
    names = {"scalar": r"$\hat\alpha^*$ (scalar)", "coordinate": r"$\|\Lambda^*\|_\infty$ (coordinate)"}
    return _lqg2d_iteration_figure("alpha", {k: (f"{v}, ours", records[k]) for k, v in names.items()},
                                   {k: (f"{v}, authors' run", runs[k]) for k, v in names.items() if k in runs},
                                   "step size", log=True)


def figure_5_7_overlay(records: Mapping[str, Sequence[LearningRecord]],
                       authors_settings: Sequence[LearningRecord] | None = None,
                       runs: Mapping[str, AuthorsRun] | None = None) -> Figure:
    """Figure 5.7 over the authors' run: the adaptive batch size per iteration.

    ``records``: the ``table-5.3`` runs; ``authors_settings``: the adaptive runs of
    ``table-5.3-authors`` (drawn when given); ``runs`` as in :func:`figure_5_5_overlay`.
    """
    runs = lqg2d_runs() if runs is None else runs
    ours = {"adaptive": ("adaptive, ours (thesis's text)", records["adaptive"])}
    if authors_settings is not None:
        ours["adaptive-authors"] = ("adaptive, ours (authors' settings)", authors_settings)
    return _lqg2d_iteration_figure("batch_size", ours, {"adaptive": ("adaptive, authors' run", runs["adaptive"])},
                                   "batch size $N$", log=False)


def figure_5_8_overlay(records: Mapping[str, Sequence[LearningRecord]],
                       authors_settings: Sequence[LearningRecord] | None = None,
                       runs: Mapping[str, AuthorsRun] | None = None) -> Figure:
    """Figure 5.8 over the authors' runs: adaptive batch size against N = 1000 and N = 100.

    ``records``: the ``table-5.3`` runs; ``authors_settings``: the adaptive runs of
    ``table-5.3-authors`` (drawn when given); ``runs`` as in :func:`figure_5_5_overlay`. The
    authors' N = 100 run is not in their repository.
    """
    runs = lqg2d_runs() if runs is None else runs
    ours = {"adaptive": ("adaptive, ours (thesis's text)", records["adaptive"])}
    if authors_settings is not None:
        ours["adaptive-authors"] = ("adaptive, ours (authors' settings)", authors_settings)
    ours.update({k: (f"{k}, ours", records[k]) for k in ("N=1000", "N=100") if k in records})
    theirs = {k: (f"{k}, authors' run", runs[k]) for k in ("adaptive", "N=1000") if k in runs}
    return _lqg2d_performance_figure(ours, theirs)


# ---------------------------------------------------------------- Section 5.3: cart-pole runs
