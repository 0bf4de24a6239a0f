"""One function per figure of the thesis, redrawn from stored results.

Each function takes the records (or the quantities) it draws and returns the matplotlib
Figure; the numbers behind every curve come from :mod:`safepg.thesis.analysis`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Literal

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from safepg.bounds import ErrorBound
from safepg.meta import n_star_search, n_zero, upsilon
from safepg.record import LearningRecord, on_trajectories
from safepg.thesis import plotting
from safepg.thesis.analysis import by_iteration, mean_band

Records = Mapping[str, Sequence[LearningRecord]]


def _grid(records: Records, points: int = 600) -> np.ndarray:
    total = max(r.trajectories for recs in records.values() for r in recs)
    return np.unique(np.linspace(1, total, points).astype(np.int64))


def _performance_panel(ax: Axes, records: Records, labels: Mapping[str, str],
                       styles: Mapping[str, dict], measured: bool = False) -> None:
    grid = _grid({k: records[k] for k in labels})
    field: Literal["J", "J_hat"] = "J_hat" if measured else "J"
    for name, label in labels.items():
        mean, lo, hi = mean_band(on_trajectories(records[name], grid, field))
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
    ax.plot([n_star], [float(upsilon(n_star, g, bound, c))], "D", color=plotting.ACCENT, label=f"$N^*$ = {n_star}")
    ax.set_xscale("log")
    # Upsilon >= 0 and vanishes at N_0: a symmetric-log axis shows the zero and the decades
    # above it. Only the non-negative half is drawn and only decades are labelled, so no two
    # tick labels crowd around 0.
    linthresh = float(upsilon(n_star, g, bound, c)) / 10
    ax.set_yscale("symlog", linthresh=linthresh)
    top = float(np.nanmax(upsilon(ns, g, bound, c, saturate=False)))
    ax.set_ylim(0, top * 3)
    decades = 10.0 ** np.arange(np.ceil(np.log10(linthresh)), np.floor(np.log10(top * 3)) + 1)
    ax.yaxis.set_major_locator(mpl.ticker.FixedLocator([0.0, *decades]))
    ax.yaxis.set_major_formatter(mpl.ticker.FuncFormatter(
        lambda v, _: "0" if v == 0 else f"$10^{{{int(round(np.log10(v)))}}}$"))
    ax.yaxis.set_minor_locator(mpl.ticker.NullLocator())
    ax.set_xlabel("batch size $N$")
    ax.set_ylabel(r"$\Upsilon_\delta(N)$")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def figure_5_1(records: Records, configs: Sequence) -> Figure:
    """Figure 5.1: expected performance over trajectories, Chebyshev's bound, several delta;
    G(PO)MDP solid, REINFORCE dashed; seed mean with the min-max band."""
    fig, ax = plt.subplots(figsize=(7, 4))
    deltas = sorted({c.method.error.delta for c in configs})
    labels, styles = {}, {}
    for c in configs:
        estimator, delta = c.method.gradient.estimator, c.method.error.delta
        labels[c.name] = f"{plotting.ESTIMATOR_LABELS[estimator]}, $\\delta$ = {delta}"
        styles[c.name] = {**plotting.estimator_style(estimator), "color": plotting.delta_color(delta, deltas)}
    _performance_panel(ax, records, labels, styles)
    fig.tight_layout()
    return fig


def figure_5_2(records: Records, configs: Sequence) -> Figure:
    """Figure 5.2: expected performance over trajectories for the concentration bounds
    (G(PO)MDP, delta = 0.95)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    errors = {c.name: c.method.error for c in configs}
    labels = {name: plotting.bound_label(e.bound, e.empirical_range) for name, e in errors.items()}
    styles = {name: {"color": plotting.bound_color(e.bound, e.empirical_range)} for name, e in errors.items()}
    _performance_panel(ax, records, labels, styles)
    fig.tight_layout()
    return fig


def figure_batch_sizes(records: Records, configs: Sequence, log: bool = True) -> Figure:
    """Figures 5.3 and 5.4: adaptive batch size over learning iterations (seed mean and band)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for c in configs:
        mean, lo, hi = mean_band(by_iteration(records[c.name], "batch_size"))
        it = np.arange(1, mean.size + 1)
        e = c.method.error
        color = plotting.bound_color(e.bound, e.empirical_range)
        ax.plot(it, mean, color=color, label=plotting.bound_label(e.bound, e.empirical_range))
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
    :math:`\hat\alpha^*` of Pirotta et al. (2013) against :math:`\|\Lambda^*\|_\infty` (the coordinate
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


# ------------------------------------------------------------------ our figures (preliminaries)
def figure_lqg_performance(env, thetas: np.ndarray, sigmas: Sequence[float] = (0.5, 1.0)) -> Figure:
    """Closed-form expected performance J(theta) of a 1-D LQG for each sigma (dashed for
    all but the last), with theta* (the LQR gain, the same for every sigma) marked."""
    theta_star = float(np.asarray(env.optimal_gain()).item())
    fig, ax = plt.subplots(figsize=(6.5, 3.6))
    dashes = ["--", ":", "-."]
    for i, sigma in enumerate(sigmas):
        ls = "-" if i == len(sigmas) - 1 else dashes[i % len(dashes)]
        ax.plot(thetas, [env.performance(t, sigma) for t in thetas], ls, color=plotting.ACCENT,
                label=f"$\\sigma$ = {sigma}")
        ax.plot([theta_star], [env.performance(theta_star, sigma)], "D", color=plotting.ACCENT)
    ax.set_ylim(-120, 0)
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel(r"$J(\theta)$")
    ax.legend()
    fig.tight_layout()
    return fig


def figure_gradient_estimates(batch_sizes: Sequence[int], estimates: Mapping[str, Mapping[str, np.ndarray]],
                              target: float, theta: float) -> Figure:
    """Gradient estimates against the batch size: one panel per score action (the keys of
    ``estimates``), mean and +- one standard deviation over repeated batches of each
    estimator (arrays (len(batch_sizes), repeats)), and the gradient of the simulated
    return as a horizontal line."""
    fig, axes = plt.subplots(1, len(estimates), figsize=(11, 3.8), sharey=True, squeeze=False)
    axes = axes[0]
    for ax, (score_action, by_estimator) in zip(axes, estimates.items()):
        for name, v in by_estimator.items():
            mean, sd = v.mean(axis=1), v.std(axis=1)
            color = plotting.estimator_color(name)
            ax.plot(batch_sizes, mean, marker="o", color=color, label=plotting.ESTIMATOR_LABELS[name],
                    **plotting.estimator_style(name))
            ax.fill_between(batch_sizes, mean - sd, mean + sd, color=color, alpha=0.15)
        ax.axhline(target, color="k", lw=1, label="gradient of the simulated return")
        ax.set_xscale("log")
        ax.set_ylim(-12, 4)
        ax.set_xlabel(f"batch size $N$ (score of the {score_action} action)")
    axes[0].set_ylabel(rf"$\hat\nabla_\theta J$ at $\theta = {theta}$")
    axes[0].legend(fontsize="small")
    fig.tight_layout()
    return fig


def figure_estimator_variance(sigmas: np.ndarray, variance: Mapping[str, np.ndarray]) -> Figure:
    """Per-trajectory variance of each gradient estimator (log scale) against sigma."""
    fig, ax = plt.subplots(figsize=(6.5, 3.6))
    for name, v in variance.items():
        ax.plot(sigmas, v, color=plotting.estimator_color(name), label=plotting.ESTIMATOR_LABELS[name],
                **plotting.estimator_style(name))
    ax.set_yscale("log")
    ax.set_xlabel(r"$\sigma$")
    ax.set_ylabel("per-trajectory variance")
    ax.legend()
    fig.tight_layout()
    return fig


def figure_cartpole_sweep(rows: Sequence[Mapping], thesis: Mapping[str, float]) -> Figure:
    """Cart-pole sweep (ours): Upsilon-bar and improvement ratio of both methods per setting.

    ``rows`` are :func:`safepg.thesis.cartpole_sweep.sweep_table` rows (settings without a doubled-pole
    run are skipped), one per line from the top, labelled with the setting's penalty constant c;
    ``thesis`` holds its ``THESIS`` values, drawn as dashed lines. Filled adaptive markers: the
    adaptive method learns under that setting; open: it does not. Counterfactual settings (not
    plausible: they only locate how small c must be) have a grey background.
    """
    rows = [r for r in rows if r.get("adaptive_seeds")]
    fig, axes = plt.subplots(1, 2, figsize=(10, 0.42 * len(rows) + 1.8), sharey=True)
    y = np.arange(len(rows))[::-1]
    colours = {"adaptive": _COMPARISON_COLORS[0], "vanilla": _COMPARISON_COLORS[1]}
    labels = {"adaptive": r"adaptive (Bernstein e.r., $\delta$ = 0.95)",
              "vanilla": r"vanilla, N = 4000, $\alpha = 10^{-2}$"}
    for ax, what, scale, xlabel in ((axes[0], "upsilon_bar", 1.0, r"$\overline{\Upsilon}$ (average return)"),
                                    (axes[1], "improvement_ratio", 100.0, "improvement ratio (%)")):
        for yi, r in zip(y, rows):
            if not r["plausible"]:
                ax.axhspan(yi - 0.5, yi + 0.5, color="0.9", zorder=0, linewidth=0)
        for method, dy in (("adaptive", 0.13), ("vanilla", -0.13)):
            v = np.array([r[f"{method}_{what}"] for r in rows], dtype=float) * scale
            if method == "adaptive":
                learns = np.array([bool(r["adaptive_learns"]) for r in rows])
                # Legend entries only for the kinds that occur.
                ax.scatter(v[learns], y[learns] + dy, color=colours[method], zorder=3,
                           label=labels[method] + ", learns" if learns.any() else None)
                ax.scatter(v[~learns], y[~learns] + dy, facecolor="white", edgecolor=colours[method], zorder=3,
                           label=labels[method] + ", does not learn" if (~learns).any() else None)
            else:
                ax.scatter(v, y + dy, color=colours[method], marker="s", label=labels[method], zorder=3)
            ax.axvline(thesis[f"{method}_{what}"] * scale, color=colours[method], linestyle="--", linewidth=1,
                       label=f"thesis, {method}")
        ax.set_xlabel(xlabel)
    axes[0].set_yticks(y)
    axes[0].set_yticklabels([f"{r['label']}  (c = {r['c']:.1e})" for r in rows], fontsize=8)
    axes[0].set_ylim(-0.6, len(rows) - 0.4)
    handles, names = axes[1].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    return fig


def figure_penalty_grid(rows: Sequence[Mapping], threshold_c: float | None = None,
                        ours: tuple[float, float] | None = None) -> Figure:
    """Cart-pole sweep (ours): the penalty constant c against gamma, analytically.

    ``rows`` are :func:`safepg.thesis.cartpole_sweep.penalty_grid` rows. For each horizon term, the
    band spans every (M_phi, |A|) of the grid with R = 1; the line is its most favourable
    corner (smallest c). The right axis is the largest safe step 1/(2c); ``threshold_c``
    (dotted) is where that step becomes able to move theta; ``ours`` = (gamma, c) is starred.
    """
    fig, ax = plt.subplots(figsize=(7, 4.2))
    terms = sorted({r["horizon_term"] for r in rows}, key=["effective", "truncated", "horizon"].index)
    for term, col in zip(terms, _COMPARISON_COLORS):
        sel = [r for r in rows if r["horizon_term"] == term and r["R"] == 1.0]
        gammas = sorted({r["gamma"] for r in sel})
        lo = [min(r["c"] for r in sel if r["gamma"] == g) for g in gammas]
        hi = [max(r["c"] for r in sel if r["gamma"] == g) for g in gammas]
        ax.fill_between(gammas, lo, hi, color=col, alpha=0.15, linewidth=0)
        ax.plot(gammas, lo, marker="o", color=col, label={"effective": r"$h = 1/(1-\gamma)$ (as printed)",
                                                          "truncated": r"$h = (1-\gamma^H)/(1-\gamma)$",
                                                          "horizon": r"$h = H = 200$"}.get(term, term))
    if threshold_c is not None:
        ax.axhline(threshold_c, color="k", linestyle=":", linewidth=1, label="the step can move below this")
    if ours is not None:
        ax.plot(*ours, marker="*", markersize=13, color="k", linestyle="none", label="ours (default)")
    ax.set_yscale("log")
    ax.set_xlabel(r"discount $\gamma$")
    ax.set_ylabel("penalty constant c")
    sec = ax.secondary_yaxis("right", functions=(lambda c: 1 / (2 * np.maximum(c, 1e-300)),
                                                 lambda s: 1 / (2 * np.maximum(s, 1e-300))))
    sec.set_ylabel("largest safe step 1/(2c)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
