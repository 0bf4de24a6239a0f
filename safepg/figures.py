"""One function per figure of the thesis, redrawn from stored results.

Each function takes the records (or the quantities) it draws and returns the matplotlib
Figure; the numbers behind every curve come from :mod:`safepg.analysis`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from safepg import plotting
from safepg.analysis import by_iteration, mean_band, measured_on_grid, performance_on_grid
from safepg.bounds import ErrorBound
from safepg.learning import LearningRecord
from safepg.meta import n_star_search, n_zero, upsilon

Records = Mapping[str, Sequence[LearningRecord]]


def _grid(records: Records, points: int = 600) -> np.ndarray:
    total = max(r.trajectories for recs in records.values() for r in recs)
    return np.unique(np.linspace(1, total, points).astype(np.int64))


def _performance_panel(ax: plt.Axes, records: Records, labels: Mapping[str, str],
                       styles: Mapping[str, dict], measured: bool = False) -> None:
    grid = _grid({k: records[k] for k in labels})
    curve = measured_on_grid if measured else performance_on_grid
    for name, label in labels.items():
        mean, lo, hi = mean_band(curve(records[name], grid))
        st = styles[name]
        ax.plot(grid, mean, label=label, **st)
        ax.fill_between(grid, lo, hi, color=st.get("color"), alpha=0.2, linewidth=0)
    ax.set_xlabel("trajectories")
    ax.set_ylabel("average return over the batch" if measured else r"expected performance $J(\theta)$")
    ax.legend(fontsize="small")


def figure_4_1(g: float, bound: ErrorBound, c: float, n_max: float | None = None) -> Figure:
    """Figure 4.1: Upsilon_delta over the batch size N, with N_0 (minimum) and N* (diamond).

    The unsaturated formula is drawn (as in the thesis) with the infeasible region
    N < N_0 shaded: there no improvement can be guaranteed.
    """
    n0 = n_zero(g, bound)
    n_star = n_star_search(g, bound, c)
    hi = n_max or 4 * n_star
    ns = np.geomspace(max(n0 / 20, 1.0), hi, 800)
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(ns, upsilon(ns, g, bound, c, saturate=False), color=plotting.ACCENT)
    ax.axvspan(ns[0], n0, color="grey", alpha=0.15, label=r"$N < N_0$: no guarantee")
    ax.plot([n0], [0], "o", color="grey", label=f"$N_0$ = {n0:.0f}")
    ax.plot([n_star], [upsilon(n_star, g, bound, c)], "D", color=plotting.ACCENT, label=f"$N^*$ = {n_star}")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=upsilon(n_star, g, bound, c) / 10)
    ax.set_xlabel("batch size $N$")
    ax.set_ylabel(r"$\Upsilon_\delta(N)$")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def figure_5_1(records: Records, configs: Sequence) -> Figure:
    """Figure 5.1: expected performance over trajectories, Chebyshev's bound, several delta;
    G(PO)MDP solid, REINFORCE dashed; seed mean with the min-max band."""
    fig, ax = plt.subplots(figsize=(7, 4))
    deltas = sorted({c.delta for c in configs})
    labels = {c.name: f"{plotting.ESTIMATOR_LABELS[c.estimator]}, $\\delta$ = {c.delta}" for c in configs}
    styles = {c.name: {**plotting.estimator_style(c.estimator), "color": plotting.delta_color(c.delta, deltas)}
              for c in configs}
    _performance_panel(ax, records, labels, styles)
    fig.tight_layout()
    return fig


def figure_5_2(records: Records, configs: Sequence) -> Figure:
    """Figure 5.2: expected performance over trajectories for the concentration bounds
    (G(PO)MDP, delta = 0.95)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    labels = {c.name: plotting.bound_label(c.bound, c.empirical_range) for c in configs}
    styles = {c.name: {"color": plotting.bound_color(c.bound, c.empirical_range)} for c in configs}
    _performance_panel(ax, records, labels, styles)
    fig.tight_layout()
    return fig


def figure_batch_sizes(records: Records, configs: Sequence, log: bool = True) -> Figure:
    """Figures 5.3 and 5.4: adaptive batch size over learning iterations (seed mean and band)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for c in configs:
        mean, lo, hi = mean_band(by_iteration(records[c.name], "batch_size"))
        it = np.arange(1, mean.size + 1)
        color = plotting.bound_color(c.bound, c.empirical_range)
        ax.plot(it, mean, color=color, label=plotting.bound_label(c.bound, c.empirical_range))
        ax.fill_between(it, lo, hi, color=color, alpha=0.2, linewidth=0)
    ax.set_xlabel("iteration")
    ax.set_ylabel("batch size $N$")
    if log:
        ax.set_yscale("log")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


#: Colours of the curves of Sections 5.2-5.3 (adaptive method, and the methods it is compared to).
_COMPARISON_COLORS = ("#7d4fb0", "#3b6fb6", "#d98c2b", "#2e9e5b")


def figure_comparison(records: Records, labels: Mapping[str, str], measured: bool = False) -> Figure:
    """Figures 5.5, 5.8 and 5.9: performance over trajectories of a few methods.

    ``labels`` maps a config name to its legend label. The closed-form J is held over
    each batch (Figures 5.5, 5.8); with ``measured=True`` the curve is the batch-average
    return, "used as representative for all the trajectories in the batch" (Figure 5.9).
    Seed mean with the min-max band.
    """
    fig, ax = plt.subplots(figsize=(7, 4))
    styles = {name: {"color": col} for name, col in zip(labels, _COMPARISON_COLORS)}
    _performance_panel(ax, records, labels, styles, measured)
    fig.tight_layout()
    return fig


def figure_5_6(records: Records, labels: Mapping[str, str]) -> Figure:
    r"""Figure 5.6: magnitude of the step size over iterations, the scalar
    :math:`\hat\alpha^*` of [24] against :math:`\|\Lambda^*\|_\infty` (the coordinate
    step moves one component, so its infinity norm is the recorded alpha)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for (name, label), col in zip(labels.items(), _COMPARISON_COLORS):
        mean, lo, hi = mean_band(by_iteration(records[name], "alpha"))
        it = np.arange(1, mean.size + 1)
        ax.plot(it, mean, color=col, label=label)
        ax.fill_between(it, lo, hi, color=col, alpha=0.2, linewidth=0)
    ax.set_xlabel("iteration")
    ax.set_ylabel("step size")
    ax.set_yscale("log")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig
