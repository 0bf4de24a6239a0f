"""Our runs drawn over the authors' raw outputs (``safepg.thesis.authors``): one function per figure.

Each function draws our curve (mean over seeds and the 95% prediction band for a curve of the kind
they plotted, :func:`seed_band95`) over the authors' own run(s)
of the same setting, from the stored records and the data files, and returns the figure.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any, Literal, TypedDict

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from safepg.envs.lqg import LQG
from safepg.record import LearningRecord, on_trajectories
from safepg.stats import prediction_band95
from safepg.thesis import authors, plotting
from safepg.thesis.authors import LQG2D_BOUND, TABLE_5_4_BUDGET, AuthorsRun, cartpole_runs, lqg2d_runs

# ---------------------------------------------------------------- Section 5.1: 1-D fixed-step runs
#: Table 5.1's cells drawn by default, (sigma, N, alpha): both sigmas at N = 1000, where the
#: printed ratios are the furthest from 100% and the slip cell (sigma = 1, alpha = 1e-3) lies.
T51_OVERLAY_CELLS = ((0.5, 1000, 1e-3), (0.5, 1000, 1e-4), (1.0, 1000, 1e-3), (1.0, 1000, 1e-4))


#: Runs each curve of Figures 5.1-5.2 averages by the caption ("averaged over 5 runs"). Their plotted
#: curves are one run each (:func:`safepg.thesis.authors.grid_curve`), hence the two processings.
FIGURES_51_52_RUNS = 5
#: How a run becomes a curve of Figures 5.1-5.2: as the thesis's text has it (the J of the policy
#: collecting trajectory T, a five-run mean), or as the authors' plot script did (their one run
#: through :func:`safepg.thesis.authors.grid_curve`).
Processing = Literal["text", "authors"]
PROCESSINGS: tuple[Processing, ...] = ("text", "authors")


def seed_band95(values: np.ndarray, runs: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Mean over seeds (axis 0) and the 95% prediction band for a curve of ``runs`` runs, point by point.

    .. math:: \bar x \pm t_{0.975,\,k-1}\, s \sqrt{1/n + 1/k}

    over the :math:`k` seeds present at each point, :math:`n` = ``runs``
    (:func:`safepg.stats.prediction_band95`): the band that holds, with probability 0.95 at each
    point, one new run (``runs=1``) or the mean of ``runs`` new runs. It is drawn for the kind of
    curve the authors plotted beside it (a single run, or their 5-run mean of Figures 5.1-5.2), and it
    is the band the scorecard holds their curve against (:mod:`safepg.thesis.curve_bands`). NaN
    entries (a run that ended earlier) are left out; a point with fewer than two seeds has no band (NaN).

    Parameters
    ----------
    values : ndarray, shape (seeds, points)
    runs : int
        How many runs the predicted curve averages.

    Returns
    -------
    mean, lo, hi : ndarray, shape (points,)
    """
    mean, half, _ = prediction_band95(values, runs)
    return mean, mean - half, mean + half


def _t51_name(sigma: float, n: int, alpha: float) -> str:
    return f"sigma={sigma}-N={n}-alpha={alpha:.0e}"


def table51_overlay_series(records: Mapping[str, Sequence[LearningRecord]], cell: tuple[float, int, float],
                           quantity: Literal["J", "theta"] = "J") -> dict[str, np.ndarray]:
    """The curves of one Table 5.1 cell: ours (seed mean and 95% prediction band for one run) and the
    authors' run.

    Both are read at the batch starts, trajectory k N for k = 0, 1, ... The authors' J column
    reads sigma as a variance (their sigma = 0.5 files start at -7.134), so their J is
    recomputed from their theta with our closed form at standard deviation sigma, which is
    their column itself at sigma = 1; theta is theirs as written.

    Parameters
    ----------
    records : mapping of config name to records
        Our runs of a Table 5.1 experiment (``table-5.1`` or ``table-5.1-authors``).
    cell : (sigma, N, alpha)
    quantity : "J" or "theta"

    Returns
    -------
    dict
        ``x`` and ``ours_mean``, ``ours_lo``, ``ours_hi`` (ours), ``x_authors`` and ``authors``.
    """
    sigma, n, alpha = cell
    recs = records[_t51_name(sigma, n, alpha)]
    if not recs:
        raise ValueError(f"records must hold runs of {_t51_name(sigma, n, alpha)}, got none")
    length = max(r.iterations + 1 for r in recs)
    ours = np.full((len(recs), length), np.nan)
    for i, r in enumerate(recs):
        ours[i, : r.iterations + 1] = r.J if quantity == "J" else r.theta[:, 0]
    run = authors.table51_runs()[(sigma, n, alpha)]
    theirs = run["theta"]
    if quantity == "J":
        theirs = LQG.thesis_1d().performance_batch(theirs.reshape(-1, 1), sigma)
    mean, lo, hi = seed_band95(ours)
    return {"x": n * np.arange(length), "ours_mean": mean, "ours_lo": lo, "ours_hi": hi,
            "x_authors": n * np.arange(run.iterations), "authors": np.asarray(theirs, dtype=float)}


def figure_table51_overlay(records: Mapping[str, Sequence[LearningRecord]],
                           cells: Sequence[tuple[float, int, float]] = T51_OVERLAY_CELLS,
                           quantity: Literal["J", "theta"] = "J", label: str = "ours") -> Figure:
    """Table 5.1's fixed-step runs: ours (mean and 95% prediction band for one run) over the authors'
    run.

    One panel per cell (sigma, N, alpha), two columns; J (or theta) against the trajectories
    at each batch start. The dotted line is the optimum of the closed form.

    Parameters
    ----------
    records : mapping of config name to records
        Our runs of ``table-5.1`` or ``table-5.1-authors``.
    cells : sequence of (sigma, N, alpha)
    quantity : "J" or "theta"
    label : str
        Legend label of our runs.
    """
    rows = math.ceil(len(cells) / 2)
    fig, axes = plt.subplots(rows, 2, figsize=(7, 2.6 * rows), squeeze=False, sharex=True)
    env = LQG.thesis_1d()
    theta_star = float(env.optimal_gain()[0, 0])  # the closed form's optimum, whatever sigma
    for ax, cell in zip(axes.flat, cells):
        s = table51_overlay_series(records, cell, quantity)
        ax.plot(s["x_authors"], s["authors"], color="black", linewidth=0.9, label="authors' run")
        ax.plot(s["x"], s["ours_mean"], color=plotting.ACCENT, linewidth=1.1, label=label)
        ax.fill_between(s["x"], s["ours_lo"], s["ours_hi"], color=plotting.ACCENT, alpha=0.25, linewidth=0)
        best = env.performance(theta_star, cell[0]) if quantity == "J" else theta_star
        ax.axhline(best, color=plotting.MUTED, linestyle=":", linewidth=0.8)
        ax.set_title(f"σ = {cell[0]}, N = {cell[1]}, α = {cell[2]:.0e}", fontsize="small")
        ax.set_ylabel(r"$J(\theta)$" if quantity == "J" else r"$\theta$")
        ax.ticklabel_format(axis="y", useOffset=False)  # J varies in its 4th decimal at sigma = 0.5
    for ax in axes.flat[len(cells):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("trajectories")
    axes.flat[0].legend(fontsize="small")
    fig.tight_layout()
    return fig


class OverlaySeries(TypedDict):
    """One curve of Figures 5.1-5.2 on the authors' grid (:func:`figure51_52_overlay_series`)."""

    x: np.ndarray
    ours_mean: np.ndarray
    ours_lo: np.ndarray
    ours_hi: np.ndarray
    authors: np.ndarray
    values: np.ndarray
    runs: int


def figure51_52_overlay_series(records: Mapping[str, Sequence[LearningRecord]], config,
                               processing: Processing = "text", runs: int | None = None) -> OverlaySeries:
    """One curve of Figures 5.1-5.2 on the authors' grid of T: ours (``values``, each seed's curve; their
    mean and 95% prediction band) and the authors' plotted curve.

    ``processing="text"``: each seed's closed-form J of the policy that generated trajectory T
    (:func:`~safepg.record.on_trajectories`), the band for a five-run mean (the caption).
    ``processing="authors"``: each seed through the authors' :func:`~safepg.thesis.authors.grid_curve`
    (their ``scaleData.m``), the band for one run, as their curve is. ``runs`` sets the band's number
    of runs otherwise (to test one choice at a time).
    """
    if processing not in PROCESSINGS:
        raise ValueError(f"processing must be one of {PROCESSINGS}, got {processing!r}")
    error = config.method.error
    curve = authors.figure51_52_curves()[(config.method.gradient.estimator, error.bound, error.empirical_range,
                                          error.delta)]
    grid = curve["trajectories"].astype(np.int64)
    if processing == "text":
        values, n = on_trajectories(records[config.name], grid, "J"), FIGURES_51_52_RUNS
    else:
        mapped = [authors.grid_curve(r.batch_size, r.J[:-1]) for r in records[config.name]]
        if any(not np.array_equal(x, grid) for x, _ in mapped):
            raise ValueError(f"{config.name}: the authors' grid is not grid_curve's")
        values, n = np.array([z for _, z in mapped]), 1
    runs = n if runs is None else runs
    mean, lo, hi = seed_band95(values, runs=runs)
    return {"x": grid, "ours_mean": mean, "ours_lo": lo, "ours_hi": hi, "authors": curve["J"], "values": values,
            "runs": runs}


def _figure51_52_panel(ax: Axes, records: Mapping[str, Sequence[LearningRecord]], configs: Sequence,
                       colors: Mapping[str, str], labels: Mapping[str, str], processing: Processing) -> None:
    for c in configs:
        s = figure51_52_overlay_series(records, c, processing)
        ax.plot(s["x"], s["ours_mean"], color=colors[c.name], linewidth=1.6, label=labels[c.name])
        ax.fill_between(s["x"], s["ours_lo"], s["ours_hi"], color=colors[c.name], alpha=0.25, linewidth=0)
        # Theirs on top, thin: the two curves mostly coincide.
        ax.plot(s["x"], s["authors"], color="black", linestyle=(0, (3, 3)), linewidth=0.7)
    ax.set_xlabel("trajectories")
    ax.set_ylabel(r"expected performance $J(\theta)$")
    ax.legend(fontsize="small", title="ours (colour), authors' (black dashed)", title_fontsize="small")


def figure_5_1_overlay(records: Mapping[str, Sequence[LearningRecord]], configs: Sequence,
                       ylim: tuple[float, float] | None = None, processing: Processing = "text") -> Figure:
    """Figure 5.1 (Chebyshev, each delta): our runs (mean and 95% prediction band over seeds, in colour)
    under the authors' curves (black, dashed); one panel per estimator.

    ``processing`` (:func:`figure51_52_overlay_series`): ``"text"`` draws the band for a five-run mean of
    the J of the policy in use, ``"authors"`` the band for one run through their ``scaleData.m``.
    """
    estimators = [e for e in ("gpomdp", "reinforce") if any(c.method.gradient.estimator == e for c in configs)]
    fig, axes = plt.subplots(1, len(estimators), figsize=(7, 3.6), squeeze=False, sharey=True)
    deltas = sorted({c.method.error.delta for c in configs})
    for ax, est in zip(axes[0], estimators):
        mine = [c for c in configs if c.method.gradient.estimator == est]
        delta = {c.name: c.method.error.delta for c in mine}
        _figure51_52_panel(ax, records, mine, {n: plotting.delta_color(d, deltas) for n, d in delta.items()},
                           {n: f"δ = {d}" for n, d in delta.items()}, processing)
        ax.set_title(plotting.ESTIMATOR_LABELS[est], fontsize="small")
        if ylim is not None:
            ax.set_ylim(*ylim)
    fig.tight_layout()
    return fig


def figure_5_2_overlay(records: Mapping[str, Sequence[LearningRecord]], configs: Sequence,
                       ylim: tuple[float, float] | None = None, processing: Processing = "text") -> Figure:
    """Figure 5.2 (G(PO)MDP, delta = 0.95, each bound): our runs (mean and 95% prediction band, in colour)
    under the authors' curves (black, dashed); ``processing`` as in :func:`figure_5_1_overlay`."""
    fig, ax = plt.subplots(figsize=(7, 3.8))
    errors = {c.name: c.method.error for c in configs}
    _figure51_52_panel(ax, records, configs,
                       {n: plotting.bound_color(e.bound, e.empirical_range) for n, e in errors.items()},
                       {n: plotting.bound_label(e.bound, e.empirical_range) for n, e in errors.items()}, processing)
    if ylim is not None:
        ax.set_ylim(*ylim)
    fig.tight_layout()
    return fig


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
_LQG2D_OURS: dict[str, Any] = {"linewidth": 2.6, "alpha": 0.6}
_LQG2D_THEIRS: dict[str, Any] = {"linestyle": (0, (4, 3)), "linewidth": 1.3, "zorder": 3}


def _lqg2d_dark(key: str) -> tuple[float, float, float]:
    red, green, blue = to_rgb(_LQG2D_COLORS.get(key, "#444444"))
    return 0.55 * red, 0.55 * green, 0.55 * blue


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


def _lqg2d_authors_axis(ax: Axes) -> None:
    """A right-hand axis in the authors' units (16 times ours), for reading the printed figures."""
    sec = ax.secondary_yaxis("right", functions=(lambda y: np.multiply(y, LQG2D_AUTHORS_SCALE),
                                                 lambda y: np.divide(y, LQG2D_AUTHORS_SCALE)))
    sec.set_ylabel(f"authors' units ({LQG2D_AUTHORS_SCALE:g}× J)")


def _lqg2d_performance_figure(ours: Mapping[str, tuple[str, Sequence[LearningRecord]]],
                              theirs: Mapping[str, tuple[str, AuthorsRun]]) -> Figure:
    grid = _lqg2d_grid({k: recs for k, (_, recs) in ours.items()}, {k: run for k, (_, run) in theirs.items()})
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for key, (label, recs) in ours.items():
        mean, lo, hi = seed_band95(np.array([lqg2d_held(r.batch_size, r.J, grid) for r in recs]))
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


def lqg2d_iteration_series(field: str, ours: Mapping[str, Sequence[LearningRecord]],
                           theirs: Mapping[str, AuthorsRun], points: int = 150) -> dict[str, Any]:
    """The curves of Figures 5.6-5.7's overlays: a per-iteration field in blocks of ``width`` iterations.

    ``width`` = max(1, L // ``points``), L the longest of all the runs drawn, so it depends on
    every curve of the figure. Returns ``width``, ``ours[key]`` (per-seed block means, (seeds,
    blocks)), ``theirs[key]`` (the authors' run's block means) and ``x_ours[key]``, ``x_theirs[key]``,
    each curve's block centres in iterations (1-based).
    """
    column = {"batch_size": "N", "alpha": "alpha"}[field]
    length = max([r.iterations for recs in ours.values() for r in recs] + [run.iterations for run in theirs.values()])
    width = max(1, length // points)
    binned_ours = {}
    for key, recs in ours.items():
        values = np.full((len(recs), length), np.nan)
        for i, r in enumerate(recs):
            values[i, : r.iterations] = getattr(r, field)
        binned_ours[key] = lqg2d_binned(values, width)
    binned_theirs = {key: lqg2d_binned(run[column], width)[0] for key, run in theirs.items()}
    def centres(b: np.ndarray) -> np.ndarray:
        return width * np.arange(b.shape[-1]) + (width + 1) / 2

    return {"width": width, "ours": binned_ours, "theirs": binned_theirs,
            "x_ours": {k: centres(b) for k, b in binned_ours.items()},
            "x_theirs": {k: centres(b) for k, b in binned_theirs.items()}}


def _lqg2d_iteration_figure(field: str, ours: Mapping[str, tuple[str, Sequence[LearningRecord]]],
                            theirs: Mapping[str, tuple[str, AuthorsRun]], ylabel: str, log: bool,
                            points: int = 150) -> Figure:
    series = lqg2d_iteration_series(field, {k: recs for k, (_, recs) in ours.items()},
                                    {k: run for k, (_, run) in theirs.items()}, points)
    width = series["width"]
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, (label, recs) in ours.items():
        binned = series["ours"][key]
        mean, lo, hi = seed_band95(binned)
        # Only where most seeds still run: with one or two seeds left the band is meaningless.
        few = np.sum(np.isfinite(binned), axis=0) < min(3, len(recs))
        mean[few] = lo[few] = hi[few] = np.nan
        it = series["x_ours"][key]
        color = _LQG2D_COLORS.get(key)
        ax.plot(it, mean, color=color, label=label, gid=f"ours:{key}", **_LQG2D_OURS)
        ax.fill_between(it, lo, hi, color=color, alpha=0.25, linewidth=0)
    for key, (label, _) in theirs.items():
        ax.plot(series["x_theirs"][key], series["theirs"][key], color=_lqg2d_dark(key), label=label,
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
# Figure 5.9 redrawn: the batch-average return over trajectories, each batch's mean held over its
# trajectories as the authors' plot_cartpole.m draws it, over the window Table 5.4 averages.

#: Colours of the cart-pole overlay: ours (adaptive, fixed step) and the authors' runs beside them.
_CARTPOLE_COLORS = {"adaptive": "#7d4fb0", "N=4000": "#d98c2b"}
#: The authors' cart-pole run (:func:`safepg.thesis.authors.cartpole_runs`) each of our configs is drawn over.
CARTPOLE_AUTHORS_RUN = {"adaptive": "adaptive", "N=4000": "fixed"}


def cartpole_overlay_curves(records: Mapping[str, Sequence[LearningRecord]], grid: np.ndarray) -> dict[str, Any]:
    r"""The numbers behind :func:`figure_cartpole_overlay`.

    Parameters
    ----------
    records : mapping of config name to records
        Our runs (``"adaptive"`` and ``"N=4000"`` of ``table-5.4-authors``), one per seed.
    grid : array_like of int
        Trajectory counts (1-based) at which the curves are read.

    Returns
    -------
    dict
        ``ours[name]``: ``mean``, ``lo``, ``hi`` (the seed mean of the batch-average return and the
        95% prediction band for one run, :math:`\bar x \pm t_{0.975,n-1} s \sqrt{1 + 1/n}`), ``seeds`` and ``values``
        (each seed's curve, (seeds, len(grid)));
        ``authors[name]``: ``trajectories`` (each batch's last trajectory) and ``J_hat``, from
        :func:`safepg.thesis.authors.cartpole_runs` (``"adaptive"`` and ``"N=4000"``, their fixed run).
    """
    grid = np.asarray(grid)
    ours = {}
    for name, recs in records.items():
        values = on_trajectories(recs, grid, "J_hat")
        mean, lo, hi = seed_band95(values)
        one = np.sum(~np.isnan(values), axis=0) < 2  # no band drawn where fewer than two seeds remain
        lo[one] = hi[one] = np.nan
        ours[name] = {"mean": mean, "lo": lo, "hi": hi, "seeds": len(recs), "values": values}
    runs = cartpole_runs()
    authors = {mine: {"trajectories": np.cumsum(runs[theirs]["N"]), "J_hat": np.asarray(runs[theirs]["J_hat"])}
               for mine, theirs in CARTPOLE_AUTHORS_RUN.items()}
    return {"grid": grid, "ours": ours, "authors": authors}


def figure_cartpole_overlay(records: Mapping[str, Sequence[LearningRecord]], labels: Mapping[str, str],
                            budget: int = TABLE_5_4_BUDGET, points: int = 800) -> Figure:
    """Figure 5.9 under the authors' settings: our runs (seed mean, 95% prediction band for one run) over
    the authors' two runs.

    ``labels`` maps our config names (``"adaptive"``, ``"N=4000"``) to legend labels. The authors'
    runs (thin, dark) are their output files' batch means, each held over its batch; the x-axis
    ends at ``budget``, the window Table 5.4 averages over (their fixed run goes on beyond it).
    """
    grid = np.unique(np.linspace(1, budget, points).astype(np.int64))
    curves = cartpole_overlay_curves({k: records[k] for k in labels}, grid)
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, label in labels.items():
        col = _CARTPOLE_COLORS.get(name, "#3b6fb6")
        c = curves["ours"][name]
        ax.plot(grid, c["mean"], color=col, label=f"ours: {label} ({c['seeds']} seeds, 95% band for one run)")
        ax.fill_between(grid, c["lo"], c["hi"], color=col, alpha=0.25, linewidth=0)
        a = curves["authors"][name]
        # Each batch's mean held over the batch's trajectories (a step that ends at the batch's end).
        ax.step(np.concatenate([[0], a["trajectories"]]), np.concatenate([a["J_hat"][:1], a["J_hat"]]),
                where="pre", color=col, linewidth=0.8, linestyle="--", label=f"authors' run: {label}")
    ax.set_xlim(0, budget)
    ax.set_xlabel("trajectories")
    ax.set_ylabel("average return over the batch")
    ax.legend(fontsize="small", loc="lower right")
    fig.tight_layout()
    return fig


def figure_cartpole_safety(measured: Mapping[str, Any]) -> Figure:
    """Each measured update's change of J with its interval (:func:`safepg.safety_store.measure_runs`).

    ``measured`` maps a label to a :class:`~safepg.safety.MonteCarloOutcomes` (one run, or
    several joined by :meth:`~safepg.safety.MonteCarloOutcomes.join`); labels with
    "adaptive" go to the left panel, the others (the fixed-step runs) to the right one, each on
    its own scale. Within a panel the labels follow each other, updates in their order; labels
    without updates are left out.
    """
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.6))
    colours = ("#7d4fb0", "#2e9e5b", "#d98c2b", "#3b6fb6", "#c0392b", "#555555")
    for ax, adaptive in zip(axes, (True, False)):
        x0 = 0
        names = [n for n in measured if ("adaptive" in n) == adaptive and measured[n].change.size]
        for name, col in zip(names, colours):
            out = measured[name]
            x = x0 + np.arange(out.change.size)
            ax.errorbar(x, out.change, yerr=[out.change - out.lower, out.upper - out.change], fmt="o",
                        markersize=3 if out.change.size <= 50 else 1.5, color=col,
                        elinewidth=1 if out.change.size <= 50 else 0.4, capsize=0, label=name)
            x0 += out.change.size + max(2, out.change.size // 50)
        ax.axhline(0, color="black", linewidth=0.8)
        ax.set_xticks([])
        ax.set_xlabel("measured updates, in order")
        ax.set_title("adaptive" if adaptive else "fixed step", fontsize="medium")
        ax.legend(fontsize="x-small")
    axes[0].set_ylabel(r"$J(\theta_{k+1}) - J(\theta_k)$ (steps)")
    fig.tight_layout()
    return fig
