"""Curves and tables from stored learning records (what the figures and tables show).

Kept apart from plotting so the numbers behind every figure can be tested and printed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from safepg.record import LearningRecord
from safepg.tables import Markdown, Table, markdown_table  # noqa: F401 (the chapters read them here too)
from safepg.thesis.authors import strict_improvement_ratio


def by_iteration(records: Sequence[LearningRecord], field: str = "batch_size") -> np.ndarray:
    """A per-iteration field (e.g. batch size, step size) per seed, NaN-padded: (seeds, max I)."""
    length = max(r.iterations for r in records)
    out = np.full((len(records), length), np.nan)
    for i, r in enumerate(records):
        out[i, : r.iterations] = getattr(r, field)
    return out


def mean_band(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seed mean and the min-max band, ignoring missing (NaN) entries."""
    with np.errstate(all="ignore"):
        return np.nanmean(values, axis=0), np.nanmin(values, axis=0), np.nanmax(values, axis=0)


def compare(ours: float | None, thesis: float | None) -> dict[str, Any]:
    """Our value, the thesis's and the difference (ours - thesis)."""
    diff = None if ours is None or thesis is None else ours - thesis
    return {"ours": ours, "thesis": thesis, "difference": diff}


def method_columns(method: dict[str, Any]) -> dict[str, Any]:
    """The thesis's table columns of a method written as data (:func:`safepg.definition.to_dict`):
    ``estimator``, ``bound``, ``empirical_range`` (its "e.r."), ``delta``, and the fixed
    ``batch_size`` and ``alpha`` (None for Algorithm 4.1 or a safe step)."""
    step = method.get("step") or {}
    error = method.get("error") or step.get("error") or {}
    return {"estimator": method["gradient"]["estimator"], "bound": error.get("bound"),
            "empirical_range": error.get("range") == "empirical", "delta": error.get("delta"),
            "batch_size": method.get("batch_size"), "alpha": step.get("alpha")}


def table_5_1(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of Table 5.1: improvement ratio by sigma, N, alpha, ours beside the thesis's."""
    rows = []
    for c in report["configs"]:
        ir, m = c["improvement_ratio"], method_columns(c["method"])
        rows.append({"sigma": c["sigma"], "N": m["batch_size"], "alpha": m["alpha"], "seeds": c["seeds"],
                     "diverged": c.get("diverged", 0),
                     "ci95": ir["ci95"], **compare(ir["mean"], (c["thesis"] or {}).get("improvement_ratio"))})
    return rows


def table_5_2(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of Table 5.2: average performance with 95% CI, ours beside the thesis's."""
    rows = []
    for c in report["configs"]:
        ub, th, m = c["upsilon_bar"], c["thesis"] or {}, method_columns(c["method"])
        rows.append({"estimator": m["estimator"], "bound": m["bound"], "empirical_range": m["empirical_range"],
                     "delta": m["delta"], "seeds": c["seeds"], "ci95": ub["ci95"], "thesis_ci95": th.get("ci95"),
                     "improvement_ratio": c["improvement_ratio"]["mean"],
                     **compare(ub["mean"], th.get("upsilon_bar"))})
    return rows


def table_upsilon(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of Tables 5.3 and 5.4: average performance and improvement ratio per method,
    ours (mean and 95% CI over seeds) beside the thesis's, with the differences."""
    rows = []
    for c in report["configs"]:
        ub, ir, th = c["upsilon_bar"], c["improvement_ratio"], c["thesis"] or {}
        m = method_columns(c["method"])
        up = compare(ub["mean"], th.get("upsilon_bar"))
        imp = compare(ir["mean"], th.get("improvement_ratio"))
        rows.append({"name": c["name"], "batch_size": m["batch_size"], "alpha": m["alpha"], "seeds": c["seeds"],
                     "upsilon_bar": up["ours"], "upsilon_ci95": ub["ci95"], "thesis_upsilon_bar": up["thesis"],
                     "upsilon_difference": up["difference"],
                     "improvement_ratio": imp["ours"], "improvement_ci95": ir["ci95"],
                     "thesis_improvement_ratio": imp["thesis"], "improvement_difference": imp["difference"]})
    return rows


def with_labels(rows: Sequence[dict[str, Any]], suffix: str = "") -> list[dict[str, Any]]:
    """Copies of table rows whose ``estimator`` and ``bound`` (with ``empirical_range``)
    hold the labels the figures use, e.g. ``"G(PO)MDP"`` and ``"Hoeffding (e.r.)"``;
    ``suffix`` is appended to the bound label (e.g. ``", range 1280"``)."""
    from safepg.thesis import plotting  # matplotlib only when a table is labelled

    out = []
    for r in rows:
        r = dict(r)
        if "bound" in r:
            r["bound"] = plotting.bound_label(r["bound"], r.get("empirical_range", False)) + suffix
        if "estimator" in r:
            r["estimator"] = plotting.ESTIMATOR_LABELS[r["estimator"]]
        out.append(r)
    return out


def errata_markdown(entries: Sequence[Any]) -> Markdown:
    """The errata as Markdown, one section per entry (``safepg.thesis.errata.errata()``): where,
    why, the printed and the corrected statement, what corrected minus printed simplifies
    to (when both are expressions), and whether the experiments are affected.

    Expressions are display formulas, so a long one scrolls inside its own box in the book
    instead of running past the text column.
    """
    import sympy as sp

    def block(x: Any) -> str:
        # an expression or a LaTeX string as a display formula, a sentence as a quotation
        if isinstance(x, sp.Basic):
            return f"$$\n{sp.latex(x)}\n$$"
        text = str(x)
        return f"$$\n{text}\n$$" if any(ch in text for ch in "\\^_=") else f"> {text}"

    parts = []
    for e in entries:
        text = [f"### {e.location}", e.explanation, "Printed:", block(e.printed), "Corrected:", block(e.corrected)]
        if isinstance(e.printed, sp.Basic) and isinstance(e.corrected, sp.Basic):
            diff = sp.factor(sp.simplify(e.corrected - e.printed))
            text += ["Corrected minus printed simplifies to", block(diff)]
        text.append(f"*Affects the experiments:* {e.affects_experiments}. {e.impact}")
        parts.append("\n\n".join(text))
    return Markdown("\n\n".join(parts))


# ------------------------------------------------------------------ estimators and objectives
def simulated_performance(env: Any, thetas: Sequence[float] | np.ndarray, sigma: float, n: int,
                          seed: int = 0, score_action: str = "clipped") -> np.ndarray:
    """Monte Carlo estimate of the simulator's objective (clipped, H-step discounted return)
    at each theta, with common random numbers: every theta sees the same initial states and
    noise, so differences between thetas are estimated far more precisely than the values."""
    from safepg.policies import LinearGaussianPolicy

    out = []
    for theta in np.atleast_1d(np.asarray(thetas, dtype=float)):
        pol = LinearGaussianPolicy(np.reshape(theta, (env.dim, -1)), sigma)
        out.append(env.gradient_batch(pol, n, np.random.default_rng(seed), "gpomdp", False, score_action)[1].mean())
    return np.asarray(out)


def simulated_gradient(env: Any, theta: float, sigma: float, n: int, seed: int = 0, h: float = 1e-4) -> float:
    """Central finite difference of :func:`simulated_performance` (common random numbers):
    the gradient of the objective the simulator really optimises (1-D)."""
    lo, hi = simulated_performance(env, [theta - h, theta + h], sigma, n, seed)
    return float((hi - lo) / (2 * h))


def gradient_estimates(env: Any, theta: float, sigma: float, batch_sizes: Sequence[int], repeats: int,
                       seed: int = 0, estimators: Sequence[str] = ("reinforce", "gpomdp"),
                       score_action: str = "clipped") -> dict[str, np.ndarray]:
    """Batch gradient estimates (with baseline) for each estimator and batch size N:
    ``{estimator: array (len(batch_sizes), repeats)}``; every repeat is an independent batch,
    and the estimators share each batch's random numbers."""
    from safepg.policies import LinearGaussianPolicy

    pol = LinearGaussianPolicy(np.array([[theta]]), sigma)
    rng = np.random.default_rng(seed)
    out = {e: np.empty((len(batch_sizes), repeats)) for e in estimators}
    for i, n in enumerate(batch_sizes):
        for r in range(repeats):
            state = rng.bit_generator.state
            for e in estimators:
                rng.bit_generator.state = state  # same trajectories for every estimator
                out[e][i, r] = env.gradient_batch(pol, int(n), rng, e, True, score_action)[0].mean()
    return out


def sample_variance(env: Any, theta: float, sigmas: Sequence[float] | np.ndarray, n: int, seed: int = 0,
                    estimators: Sequence[str] = ("reinforce", "gpomdp"),
                    baseline: bool = True) -> dict[str, np.ndarray]:
    """Per-trajectory variance of each estimator's gradient sample as sigma varies (1-D)."""
    from safepg.policies import LinearGaussianPolicy

    out = {e: np.empty(len(sigmas)) for e in estimators}
    for i, s in enumerate(sigmas):
        pol = LinearGaussianPolicy(np.array([[theta]]), s)
        for e in estimators:
            out[e][i] = env.gradient_batch(pol, n, np.random.default_rng(seed), e, baseline)[0].var(ddof=1)
    return out


def improvement_ratio_on(records: Sequence[LearningRecord], objective: Any) -> np.ndarray:
    """Improvement ratio of each run measured with another objective, ``objective(theta_array)``
    (e.g. an interpolant of :func:`simulated_performance`), instead of the closed-form J."""
    out = []
    for r in records:
        vals = objective(r.theta[:, 0] if r.theta.shape[1] == 1 else r.theta)
        out.append(float(np.mean(np.diff(vals) >= 0)))
    return np.asarray(out)


def simulated_objective(env: Any, sigma: float, lo: float, hi: float, points: int = 61, n: int = 200_000,
                        seed: int = 0) -> Any:
    """Cubic-spline interpolant of :func:`simulated_performance` on [lo, hi] (1-D).

    With common random numbers the sampled curve is smooth in theta, so the spline can
    tell whether a step of 1e-5 went up or down the simulator's objective.
    """
    from scipy.interpolate import CubicSpline

    grid = np.linspace(lo, hi, points)
    return CubicSpline(grid, simulated_performance(env, grid, sigma, n, seed))


def one_cell_spread(records: Sequence[LearningRecord], printed: float, theirs_theta: np.ndarray,
                    theta_star: float) -> dict[str, Any]:
    """Where one printed improvement ratio (one run of the authors') lies among many of our runs of a
    Table 5.1 cell, counted as the authors counted (strict increases of J between batch starts), and
    when theta crosses the optimum in their run and in ours (updates improve J while theta moves
    towards theta*, so the crossing sets most of the ratio).

    Parameters
    ----------
    records : sequence of LearningRecord
        Our runs of the cell (at least two).
    printed : float
        The printed ratio.
    theirs_theta : array_like
        Their run's theta before each update.
    theta_star : float
        The optimum the runs start above.

    Returns
    -------
    dict
        ``ratios`` (ours), ``mean``, ``sd`` (one run's), ``at_least`` (our runs reaching the print),
        ``z`` (the print in our standard deviations above our mean; NaN if our runs agree),
        ``crossing`` (the updates after which each of our runs is past theta*) and ``crossing_theirs``.
    """
    if len(records) < 2:
        raise ValueError(f"records must hold at least two runs, got {len(records)}")
    ratios = np.array([strict_improvement_ratio(r.J[:-1]) for r in records])
    mean, sd = float(ratios.mean()), float(ratios.std(ddof=1))
    return {"ratios": ratios, "mean": mean, "sd": sd, "at_least": int(np.sum(ratios >= printed)),
            "z": (printed - mean) / sd if sd > 0 else float("nan"),
            "crossing": np.array([int(np.argmax(r.theta[:, 0] < theta_star)) for r in records]),
            "crossing_theirs": int(np.argmax(np.asarray(theirs_theta) < theta_star))}
