r"""Which unstated setting produced Table 5.1? A sweep over the plausible readings.

Table 5.1 prints the improvement ratio of vanilla G(PO)MDP with a fixed step size
:math:`\alpha` and batch size N on the 1-D LQG (:math:`10^6` trajectories,
:math:`\sigma \in \{0.5, 1\}`, printed start :math:`\theta_0 = -0.55`). The thesis leaves
open several settings that change the numbers; this module reruns the table under each:

* ``baseline``: none (b = 0), the variance-minimising G(PO)MDP baseline of Section
  2.3.10 (one per time step), or the *average* baseline :math:`b_l = \langle\gamma^{l-1}
  r_l\rangle_N` (the batch mean of each discounted reward, equivalently the mean
  reward-to-go), the baseline most policy-gradient code of the time used;
* ``score_action``: the authors' score of the clipped action, or the unbiased score of
  the sampled one (with the clipped score the baseline changes the *expected* gradient,
  since :math:`\mathbb E[\nabla\log\pi(\mathrm{clip}(a))] \ne 0`);
* ``sigma_reading``: :math:`\sigma` is the policy's standard deviation, or it is passed
  where the code expects a covariance (``cov = sigma``), so the standard deviation is
  :math:`\sqrt\sigma` (only :math:`\sigma = 0.5` changes);
* the starting point :math:`\theta_0` (:data:`THETA0_SCAN`);

and counts the improving updates two ways: ``count="all"`` scores every update
(:math:`10^6/N` of them); ``count="evaluated"`` evaluates J at the parameters of each batch,
so the last update is never scored (:math:`10^6/N - 1` updates: the printed values are
multiples of 1/99 and 1/999 for N = 10^4 and 10^3, e.g. 95.96% = 95/99, 52.85% = 528/999).
The last batch is never partial here (N divides 10^6).

Which closed form? None of the readings of the J formula matters for the ratio: every
reading (:math:`\sigma` or :math:`\sigma^2` where the authors pass ``cov``, state range
2 or the lab library's 10, reward weights 0.5 or 0.9) has the form
:math:`J = -c_1 P(\theta) - c_0` with :math:`c_1 > 0` and the same
:math:`P(\theta) \propto (1+\theta^2)/(1-\gamma(1+\theta)^2)`, so J rises exactly when
P falls (:func:`closed_form_j`, :func:`j_formula_readings`; tested).

What the sweep finds: from the printed :math:`\theta_0 = -0.55` no combination reproduces
the table (at best 17 of 24 cells within 5 points); from :math:`\theta_0 = -0.575` the
library's default estimator (variance-minimising baseline, clipped-action score) puts all
24 cells within about 2 points, and :math:`-0.57` or :math:`-0.58` are already clearly worse.

The learning runs here use their own small numba kernel (:func:`batch_gradient`) because
the core estimators have no average baseline; with the variance-minimising baseline or
none it gives the library's gradient to rounding (tested), and every run takes a seed.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numba import njit

from safepg.envs.lqg import LQG
from safepg.rng import RNGLike, as_generator
from safepg.streams import batch_key, batch_keys, next_normal, next_uniform, stream_start

Baseline = Literal["none", "optimal", "average"]
SigmaReading = Literal["std", "variance"]
Count = Literal["all", "evaluated"]
Objective = Literal["J", "simulated"]

_BASELINE_CODES = {"none": 0, "optimal": 1, "average": 2}
#: Bump when a change here alters the numbers a sweep run produces (stored sweeps are recomputed).
#: 2: the counter-based streams of safepg.streams instead of NumPy's draws.
SWEEP_VERSION = "2"
#: The version whose hash seeds a sweep run, frozen at 2: a bump of SWEEP_VERSION recomputes the
#: sweep from the same random numbers (as :data:`safepg.runner.SEED_VERSION` for the runs).
SWEEP_SEED_VERSION = "2"


@dataclass(frozen=True)
class Variant:
    """One reading of Table 5.1's unstated learning settings."""

    baseline: Baseline = "optimal"
    score_action: Literal["clipped", "raw"] = "clipped"
    sigma_reading: SigmaReading = "std"

    def __post_init__(self) -> None:
        if self.baseline not in _BASELINE_CODES:
            raise ValueError(f"baseline must be one of {sorted(_BASELINE_CODES)}, got {self.baseline!r}")
        if self.score_action not in ("clipped", "raw"):
            raise ValueError(f"score_action must be 'clipped' or 'raw', got {self.score_action!r}")
        if self.sigma_reading not in ("std", "variance"):
            raise ValueError(f"sigma_reading must be 'std' or 'variance', got {self.sigma_reading!r}")

    @property
    def label(self) -> str:
        """Short name, e.g. ``average baseline, clipped score, sigma = std``."""
        b = {"none": "b = 0", "optimal": "variance-min. b", "average": "average b"}[self.baseline]
        return f"{b}, {self.score_action} score, sigma = {self.sigma_reading}"

    def policy_std(self, sigma: float) -> float:
        """Standard deviation the policy samples with for a printed ``sigma``."""
        _check_positive("sigma", sigma)
        return float(sigma) if self.sigma_reading == "std" else float(np.sqrt(sigma))


#: Every combination the sweep runs (3 baselines x 2 scores x 2 sigma readings).
VARIANTS: tuple[Variant, ...] = tuple(
    Variant(b, s, r) for b in ("none", "optimal", "average") for s in ("clipped", "raw")
    for r in ("std", "variance")
)


def _check_positive(name: str, value: float) -> None:
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value}")


# ----------------------------------------------------------------------------- gradient
@njit(cache=True)
def _batch_gradient(theta: float, std: float, key: np.uint64, N: int, H: int, gamma: float, bound: float,
                    score_clipped: bool, baseline: int) -> tuple[float, float]:  # pragma: no cover - numba
    s1 = np.zeros(H)    # sum_n cum * gamma^t r_t
    scum = np.zeros(H)  # sum_n cum
    num = np.zeros(H)   # sum_n cum^2 gamma^t r_t  (variance-minimising baseline)
    den = np.zeros(H)   # sum_n cum^2
    rsum = np.zeros(H)  # sum_n gamma^t r_t          (average baseline)
    inv_var = 1.0 / (std * std)
    ret = 0.0
    for n in range(N):
        state = stream_start(key, n)
        v, state = next_uniform(state)
        s = -bound + (bound + bound) * v  # the library's initial state (safepg.envs.lqg)
        cum = 0.0
        disc = 1.0
        for t in range(H):
            mean = theta * s
            zt, state = next_normal(state)
            a = mean + std * zt
            u = min(max(a, -bound), bound)
            dr = -0.5 * (s * s + u * u) * disc
            cum += ((u if score_clipped else a) - mean) * s * inv_var
            s1[t] += cum * dr
            scum[t] += cum
            num[t] += cum * cum * dr
            den[t] += cum * cum
            rsum[t] += dr
            ret += dr
            disc *= gamma
            s = min(max(s + u, -bound), bound)
    g = 0.0
    for t in range(H):
        b = 0.0
        if baseline == 1 and den[t] != 0.0:
            b = num[t] / den[t]
        elif baseline == 2:
            b = rsum[t] / N
        g += s1[t] - b * scum[t]
    return g / N, ret / N


def batch_gradient(env: LQG, theta: float, std: float, n: int, rng: RNGLike, baseline: Baseline = "optimal",
                   score_action: str = "clipped") -> tuple[float, float]:
    """G(PO)MDP batch estimate of dJ/dtheta and the batch's mean discounted return (1-D LQG).

    Draws the library's random numbers (one batch key from ``rng``, trajectory i on its
    stream i, see :mod:`safepg.streams`), so with the same generator state and the
    ``"optimal"`` or ``"none"`` baseline it matches
    ``env.gradient_batch(..., "gpomdp", baseline, score_action)[0].mean()`` to rounding.

    Parameters
    ----------
    env : LQG
        A one-dimensional, clipped LQG (A = B = Q = R = 1, state and action bounds equal).
    theta, std : float
        Policy gain and standard deviation.
    n : int
        Batch size.
    rng : seed or Generator
    baseline : "none", "optimal" or "average"
    score_action : "clipped" or "raw"
    """
    _check_env(env)
    _check_options(baseline, score_action)
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n}")
    rng = as_generator(rng)
    g, ret = _batch_gradient(float(theta), float(std), batch_key(rng), int(n), int(env.horizon), float(env.gamma),
                             float(env.state_bound), score_action == "clipped", _BASELINE_CODES[baseline])
    return float(g), float(ret)


def _check_options(baseline: str, score_action: str) -> None:
    if baseline not in _BASELINE_CODES:
        raise ValueError(f"baseline must be one of {sorted(_BASELINE_CODES)}, got {baseline!r}")
    if score_action not in ("clipped", "raw"):
        raise ValueError(f"score_action must be 'clipped' or 'raw', got {score_action!r}")


def _check_env(env: LQG) -> None:
    A, B, Q, R = (float(m[0, 0]) for m in env._mats)
    if env.dim != 1 or not env.clip or (A, B, Q, R) != (1.0, 1.0, 1.0, 1.0) or env.state_bound != env.action_bound:
        raise ValueError("env must be the 1-D clipped LQG of Section 5.1 (A = B = Q = R = 1, equal bounds)")


# ----------------------------------------------------------------------------- learning
def fixed_step_run(env: LQG, theta0: float, std: float, batch_size: int, alpha: float, budget: int,
                   rng: RNGLike, baseline: Baseline = "optimal", score_action: str = "clipped") -> np.ndarray:
    r"""Vanilla G(PO)MDP, :math:`\theta \leftarrow \theta + \alpha\hat\nabla J`, with a fixed batch size.

    Returns the parameters before each batch followed by the final one, shape
    (budget // batch_size + 1,), or fewer if the gradient estimate overflowed (a
    diverged run stops there, as in :func:`safepg.learning.vanilla_pg`).
    """
    if int(batch_size) != batch_size or batch_size < 2:
        raise ValueError(f"batch_size must be an integer >= 2, got {batch_size}")
    if not (np.isfinite(alpha) and alpha >= 0):
        raise ValueError(f"alpha must be finite and >= 0, got {alpha}")
    if int(budget) != budget or budget < batch_size:
        raise ValueError(f"budget must be an integer >= batch_size, got {budget}")
    _check_env(env)
    _check_options(baseline, score_action)
    keys = batch_keys(as_generator(rng), int(budget) // int(batch_size))  # batch_gradient's, drawn at once
    path: np.ndarray = _fixed_step_path(float(theta0), float(std), keys, int(batch_size), int(env.horizon),
                                        float(env.gamma), float(env.state_bound), score_action == "clipped",
                                        _BASELINE_CODES[baseline], float(alpha))
    return path


@njit(cache=True)
def _fixed_step_path(theta: float, std: float, keys: np.ndarray, N: int, H: int, gamma: float, bound: float,
                     score_clipped: bool, baseline: int, alpha: float) -> np.ndarray:  # pragma: no cover - numba
    # The whole run in one compiled loop: 10^4 batches of N = 100 were as many Python calls.
    path = np.empty(keys.size + 1)
    path[0] = theta
    b = 0
    for i in range(keys.size):
        g, _ = _batch_gradient(theta, std, keys[i], N, H, gamma, bound, score_clipped, baseline)
        step = theta + alpha * g
        if not (np.isfinite(g) and np.isfinite(step)):
            break
        theta = step
        b += 1
        path[b] = theta
    return path[:b + 1]


def improvement_ratio(values: np.ndarray, count: Count = "all") -> float:
    """Share of updates after which ``values`` (the objective at each theta) did not decrease.

    ``count="all"`` scores every update; ``"evaluated"`` leaves out the last one (whose
    result is never evaluated when J is computed at the start of each batch).
    """
    v = np.asarray(values, dtype=float)
    if count == "evaluated":
        v = v[:-1]
    elif count != "all":
        raise ValueError(f"count must be 'all' or 'evaluated', got {count!r}")
    with np.errstate(invalid="ignore"):
        steps = np.diff(v)
    return float(np.mean(steps >= 0)) if steps.size else float("nan")


# ----------------------------------------------------------------------------- closed forms
def closed_form_j(theta: np.ndarray | float, noise: float, gamma: float = 0.9, q: float = 0.5, r: float = 0.5,
                  state_bound: float = 2.0) -> np.ndarray:
    r"""1-D closed-form J under one reading of the authors' formula.

    .. math:: P = \frac{q + r\theta^2}{1 - \gamma(1+\theta)^2}, \qquad
              J = -\frac{b^2}{3}P - \frac{\mathrm{noise}\,(r + \gamma P)}{1-\gamma}

    ``noise`` is what multiplies the trace term: :math:`\sigma^2` (SETTINGS.md) or
    :math:`\sigma` (``cov = sigma``); q = r = 0.5 is the thesis's reward, 0.9 the lab
    library's (which has no 0.5); b = 2 the thesis's state range, 10 the library's.
    -inf where the closed loop is unstable.
    """
    t = np.asarray(theta, dtype=float)
    with np.errstate(over="ignore"):
        den = 1 - gamma * (1 + t) ** 2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a diverged run's parameters
        P = (q + r * t**2) / den
        J = -(state_bound**2 / 3) * P - noise * (r + gamma * P) / (1 - gamma)
    return np.where(den > 0, J, -np.inf)


def j_formula_readings(sigma: float) -> dict[str, Callable[[np.ndarray], np.ndarray]]:
    """The readings of the J formula considered: name -> J(theta array)."""
    return {
        "SETTINGS.md (sigma^2, b = 2, 0.5)": lambda t: closed_form_j(t, sigma**2),
        "cov = sigma (sigma, b = 2, 0.5)": lambda t: closed_form_j(t, sigma),
        "lab library (sigma^2, b = 10, 0.9)": lambda t: closed_form_j(t, sigma**2, q=0.9, r=0.9, state_bound=10.0),
        "lab library, cov = sigma": lambda t: closed_form_j(t, sigma, q=0.9, r=0.9, state_bound=10.0),
    }


# ----------------------------------------------------------------------------- the sweep
#: The starting point the thesis prints, and the one that reproduces the table (our reconstruction).
PRINTED_THETA0 = -0.55
RECONSTRUCTED_THETA0 = -0.575
#: Starting points scanned with the default estimator (variance-minimising baseline, clipped score).
THETA0_SCAN = (-0.55, -0.56, -0.565, -0.57, -0.5725, -0.575, -0.5775, -0.58, -0.585, -0.59)
DEFAULT = Variant("optimal", "clipped", "std")


def _plan_default() -> tuple[tuple[Variant, float], ...]:
    at_printed = [(v, PRINTED_THETA0) for v in VARIANTS]
    scan = [(DEFAULT, t) for t in THETA0_SCAN if t != PRINTED_THETA0]
    # The other estimators from the reconstructed start: is the match specific to the default one?
    others = [(v, RECONSTRUCTED_THETA0) for v in VARIANTS if v.sigma_reading == "std" and v != DEFAULT]
    return tuple(at_printed + scan + others)


#: What the chapter runs (1 seed per run; about 550 runs of 10^6 trajectories, ~4 core-minutes):
#: every variant from the printed theta_0, the default estimator over THETA0_SCAN, and the
#: other estimators from the reconstructed theta_0.
CHAPTER_PLAN: tuple[tuple[Variant, float], ...] = _plan_default()


def _printed() -> dict[float, dict[int, tuple[float, ...]]]:
    from safepg.thesis.experiments import T51_PRINTED

    return T51_PRINTED


def table_cells() -> list[tuple[float, int, float, float]]:
    """(sigma, N, alpha, printed ratio in [0, 1]) for the 24 cells of Table 5.1."""
    from safepg.thesis.experiments import T51_ALPHAS, T51_NS

    return [(s, n, a, round(p / 100, 6)) for s in (0.5, 1.0) for n in T51_NS
            for a, p in zip(T51_ALPHAS, _printed()[s][n])]


def cell_name(sigma: float, n: int, alpha: float) -> str:
    """The name :mod:`safepg.thesis.experiments` gives a Table 5.1 cell."""
    return f"sigma={sigma}-N={n}-alpha={alpha:.0e}"


def _seed(variant: Variant, theta0: float, sigma: float, n: int, alpha: float, k: int) -> np.random.SeedSequence:
    blob = json.dumps([asdict(variant), theta0, sigma, n, alpha, SWEEP_SEED_VERSION], sort_keys=True)
    return np.random.SeedSequence([k, int(hashlib.sha256(blob.encode()).hexdigest()[:15], 16)])


def run_cell(variant: Variant, sigma: float, batch_size: int, alpha: float, k: int, budget: int = 1_000_000,
             theta0: float = PRINTED_THETA0) -> list[float]:
    """Seed k of one Table 5.1 cell under ``variant`` from ``theta0``: the parameter path
    (see :func:`fixed_step_run`)."""
    env = LQG.thesis_1d()
    path = fixed_step_run(env, theta0, variant.policy_std(sigma), batch_size, alpha, budget,
                          np.random.default_rng(_seed(variant, theta0, sigma, batch_size, alpha, k)),
                          variant.baseline, variant.score_action)
    return path.tolist()


def _theta0_key(theta0: float) -> str:
    return f"{theta0:g}"


def sweep_file(plan: Sequence[tuple[Variant, float]], seeds: int, budget: int, root: Path) -> Path:
    """The file that stores :func:`sweep_paths` of ``(plan, seeds, budget)`` under the results folder ``root``."""
    spec = [[asdict(v), t] for v, t in plan]
    key = hashlib.sha256(json.dumps([spec, seeds, budget, SWEEP_VERSION], sort_keys=True).encode()).hexdigest()[:16]
    return root / "table-5.1-sweep" / f"{key}.json"


def sweep_paths(plan: Sequence[tuple[Variant, float]] = CHAPTER_PLAN, seeds: int = 1, budget: int = 1_000_000,
                jobs: int = 1, root: Path | None = None) -> dict[str, Any]:
    """Parameter paths of every (variant, theta_0) of ``plan``, cell and seed, computed once and stored.

    Stored as one JSON file per (plan, seeds, budget) under ``<results>/table-5.1-sweep/``
    (written atomically), so a rebuild recomputes nothing. Cells the sigma reading does
    not change (sigma = 1 with ``sigma_reading="variance"``) are not run twice.

    Returns
    -------
    dict
        ``{"plan": [...], "seeds", "budget", "paths": {variant label: {theta_0: {cell: [path per seed]}}}}``.
    """
    from joblib import Parallel, delayed

    from safepg.store import results_dir

    if int(seeds) != seeds or seeds < 1:
        raise ValueError(f"seeds must be a positive integer, got {seeds}")
    if int(budget) != budget or budget < max(n for _, n, _, _ in table_cells()):
        raise ValueError(f"budget must be an integer >= the largest batch size 10000, got {budget}")
    spec = [[asdict(v), t] for v, t in plan]
    path = sweep_file(plan, seeds, budget, root or results_dir())
    if path.exists():
        return json.loads(path.read_text())
    tasks = [(v, t, s, n, a, k) for v, t in plan for s, n, a, _ in table_cells() for k in range(seeds)
             if not (s == 1.0 and v.sigma_reading == "variance")]
    # Longest runs (N = 100: 10^4 updates) first keeps the workers busy to the end.
    tasks.sort(key=lambda task: task[3])
    started = time.perf_counter()
    out = Parallel(n_jobs=jobs)(delayed(run_cell)(v, s, n, a, k, budget, t) for v, t, s, n, a, k in tasks)
    seconds = time.perf_counter() - started
    paths: dict[str, dict[str, dict[str, list[list[float]]]]] = {}
    for (v, t, s, n, a, _k), pth in sorted(zip(tasks, out), key=lambda x: x[0][-1]):
        paths.setdefault(v.label, {}).setdefault(_theta0_key(t), {}).setdefault(cell_name(s, n, a), []).append(pth)
    # What it cost (benchmarks/bench_book.py): every batch before the last parameter is n trajectories.
    trajectories = sum(n * (len(pth) - 1) for (_v, _t, _s, n, _a, _k), pth in zip(tasks, out))
    result = {"plan": spec, "seeds": seeds, "budget": budget, "paths": paths, "seconds": round(seconds, 3),
              "jobs": jobs, "trajectories": trajectories}
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(result, f)
    os.replace(tmp, path)
    return result


def sweep_table(sweep: dict[str, Any], counts: Iterable[Count] = ("all", "evaluated")) -> list[dict[str, Any]]:
    """One row per (variant, theta_0, count, cell): the seed-mean ratio on the closed-form J
    beside the printed one (any reading of the J formula gives the same ratio)."""
    rows = []
    for vd, theta0 in sweep["plan"]:
        v = Variant(**vd)
        by_cell = sweep["paths"][v.label][_theta0_key(theta0)]
        for s, n, a, printed in table_cells():
            std = v.policy_std(s)
            paths = by_cell.get(cell_name(s, n, a))
            if paths is None:  # sigma = 1 under the variance reading: the std reading's runs
                same = Variant(v.baseline, v.score_action, "std").label
                paths = sweep["paths"].get(same, {}).get(_theta0_key(theta0), {}).get(cell_name(s, n, a))
                if paths is None:
                    paths = [run_cell(Variant(v.baseline, v.score_action, "std"), s, n, a, k, sweep["budget"], theta0)
                             for k in range(sweep["seeds"])]
            for count in counts:
                ratios = [improvement_ratio(closed_form_j(np.asarray(p), std**2), count) for p in paths]
                rows.append({"variant": v.label, **vd, "theta0": theta0, "count": count, "sigma": s, "N": n,
                             "alpha": a, "thesis": printed, "ours": float(np.mean(ratios)), "single_runs": ratios,
                             "difference": float(np.mean(ratios)) - printed})
    return rows


def summarise(rows: Sequence[dict[str, Any]], tol: float = 0.05) -> list[dict[str, Any]]:
    """Per (variant, theta_0, count): how many of the 24 cells are within ``tol`` of the printed
    value (all, and by sigma half), the mean and largest absolute difference; best first."""
    groups: dict[tuple[str, float, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["variant"], r["theta0"], r["count"]), []).append(r)
    out = []
    for (variant, theta0, count), rs in groups.items():
        d = np.array([r["difference"] for r in rs])
        half = np.array([r["sigma"] for r in rs])
        out.append({"variant": variant, "theta0": theta0, "count": count, "within_all": int(np.sum(np.abs(d) <= tol)),
                    "within_sigma_0.5": int(np.sum(np.abs(d[half == 0.5]) <= tol)),
                    "within_sigma_1": int(np.sum(np.abs(d[half == 1.0]) <= tol)),
                    "mean_abs_difference": float(np.abs(d).mean()), "max_abs_difference": float(np.abs(d).max())})
    return sorted(out, key=lambda r: (-r["within_all"], r["mean_abs_difference"]))


def figure_theta0_scan(summary: Sequence[dict[str, Any]], count: Count = "all") -> Any:
    """Mean |ours - printed| over the 24 cells against theta_0: the default estimator as a
    line, every other estimator as a marker at the theta_0 values it was run from."""
    import matplotlib.pyplot as plt

    rows = [r for r in summary if r["count"] == count]
    fig, axes = plt.subplots(1, 2, figsize=(10, 5.2), sharex=True)
    default = sorted((r for r in rows if r["variant"] == DEFAULT.label), key=lambda r: r["theta0"])
    others = [r for r in rows if r["variant"] != DEFAULT.label]
    markers = "osD^v<>phX*"
    labels = sorted({r["variant"] for r in others})
    for ax, key, ylabel in ((axes[0], "mean_abs_difference", "mean |ours - thesis| (points)"),
                            (axes[1], "within_all", "cells within 5 points (of 24)")):
        scale = 100 if key == "mean_abs_difference" else 1
        ax.plot([r["theta0"] for r in default], [scale * r[key] for r in default], "k-o", lw=2, ms=4,
                label=DEFAULT.label + " (the default)")
        for j, lab in enumerate(labels):
            pts = [r for r in others if r["variant"] == lab]
            ax.plot([r["theta0"] for r in pts], [scale * r[key] for r in pts], markers[j % len(markers)],
                    ms=6, alpha=0.8, label=lab)
        ax.axvline(PRINTED_THETA0, color="0.6", ls=":", lw=1)
        ax.axvline(RECONSTRUCTED_THETA0, color="C3", ls="--", lw=1)
        ax.set_xticks(np.round(np.arange(-0.59, -0.549, 0.01), 2))
        ax.set_xlabel(r"starting point $\theta_0$")
        ax.set_ylabel(ylabel)
    axes[1].axhline(24, color="0.6", lw=0.8)
    axes[0].set_yscale("log")
    handles, labels_ = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels_, loc="lower center", ncol=3, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.2, 1, 1))
    return fig


__all__ = [
    "CHAPTER_PLAN",
    "DEFAULT",
    "PRINTED_THETA0",
    "RECONSTRUCTED_THETA0",
    "THETA0_SCAN",
    "VARIANTS",
    "Variant",
    "batch_gradient",
    "cell_name",
    "closed_form_j",
    "figure_theta0_scan",
    "fixed_step_run",
    "improvement_ratio",
    "j_formula_readings",
    "run_cell",
    "summarise",
    "sweep_paths",
    "sweep_table",
    "table_cells",
]
