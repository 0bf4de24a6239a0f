"""Our runs drawn over the authors' raw outputs (``safepg.thesis.authors``): one function per figure.

Each function draws our curve (mean and 95% band over seeds) over the authors' own run(s)
of the same setting, from the stored records and the data files, and returns the figure.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from safepg.learning import LearningRecord
from safepg.stats import t_quantile_975
from safepg.thesis.analysis import measured_on_grid
from safepg.thesis.authors import TABLE_5_4_BUDGET, cartpole_runs

# ---------------------------------------------------------------- Section 5.1: 1-D fixed-step runs


# ---------------------------------------------------------------- Section 5.2: 2-D runs


# ---------------------------------------------------------------- Section 5.3: cart-pole runs
# Figure 5.9 redrawn: the batch-average return over trajectories, each batch's mean held over its
# trajectories as the authors' plot_cartpole.m draws it, over the window Table 5.4 averages.

#: Colours of the cart-pole overlay: ours (adaptive, fixed step) and the authors' runs beside them.
_CARTPOLE_COLORS = {"adaptive": "#7d4fb0", "N=4000": "#d98c2b"}


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
        ``ours[name]``: ``mean``, ``lo``, ``hi`` (the seed mean of the batch-average return and its
        95% Student-t band, :math:`\bar x \pm t_{0.975,n-1} s/\sqrt n`) and ``seeds``;
        ``authors[name]``: ``trajectories`` (each batch's last trajectory) and ``J_hat``, from
        :func:`safepg.thesis.authors.cartpole_runs` (``"adaptive"`` and ``"N=4000"``, their fixed run).
    """
    grid = np.asarray(grid)
    ours = {}
    for name, recs in records.items():
        values = measured_on_grid(recs, grid)
        n = np.sum(np.isfinite(values), axis=0)
        with warnings.catch_warnings():  # past every run's end a column is all NaN, and stays NaN
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(values, axis=0)
            sd = np.nanstd(values, axis=0, ddof=1)
        half = np.array([t_quantile_975(int(k) - 1) if k > 1 else np.nan for k in n]) * sd / np.sqrt(n)
        ours[name] = {"mean": mean, "lo": mean - half, "hi": mean + half, "seeds": len(recs)}
    runs = cartpole_runs()
    authors = {mine: {"trajectories": np.cumsum(runs[theirs]["N"]), "J_hat": np.asarray(runs[theirs]["J_hat"])}
               for mine, theirs in (("adaptive", "adaptive"), ("N=4000", "fixed"))}
    return {"grid": grid, "ours": ours, "authors": authors}


def figure_cartpole_overlay(records: Mapping[str, Sequence[LearningRecord]], labels: Mapping[str, str],
                            budget: int = TABLE_5_4_BUDGET, points: int = 800) -> Figure:
    """Figure 5.9 under the authors' settings: our runs (seed mean, 95% band) over the authors' two runs.

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
        ax.plot(grid, c["mean"], color=col, label=f"ours: {label} ({c['seeds']} seeds, 95% band)")
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
    """Each measured update's change of J with its interval (:func:`safepg.thesis.safety.measure_runs`).

    ``measured`` maps a run's label to its :class:`~safepg.thesis.safety.MonteCarloOutcomes`; labels
    with "adaptive" go to the left panel, the others (the fixed-step runs) to the right one, each on
    its own scale. Within a panel the runs follow each other, updates in their order.
    """
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.6))
    colours = ("#7d4fb0", "#2e9e5b")
    for ax, adaptive in zip(axes, (True, False)):
        x0 = 0
        names = [n for n in measured if ("adaptive" in n) == adaptive]
        for name, col in zip(names, colours):
            out = measured[name]
            x = x0 + np.arange(out.change.size)
            ax.errorbar(x, out.change, yerr=[out.change - out.lower, out.upper - out.change], fmt="o", markersize=3,
                        color=col, elinewidth=1, capsize=0, label=name)
            x0 += out.change.size + 2
        ax.axhline(0, color="black", linewidth=0.8)
        ax.set_xticks([])
        ax.set_xlabel("measured updates, in order")
        ax.set_title("adaptive" if adaptive else "fixed step", fontsize="medium")
        ax.legend(fontsize="x-small")
    axes[0].set_ylabel(r"$J(\theta_{k+1}) - J(\theta_k)$ (steps)")
    fig.tight_layout()
    return fig
