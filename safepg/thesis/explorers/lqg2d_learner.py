r"""Section 5.2 live: the 2-D LQG explorers, computed in the reader's browser (see :mod:`.ch5_live`).

:func:`lqg2d_steps_explorer` (Figures 5.5-5.6): the scalar adaptive step of Pirotta et al. (2013) against the
coordinate step Lambda* (``vanilla_pg`` with ``SafeStep("scalar")``/``SafeStep("coordinate")``,
a fixed N as ``figures-5.5-5.6`` configures it: G(PO)MDP, Chebyshev, delta = 0.95, N = 2000),
drawing the diagonal gains theta_11 and theta_22 and J over the updates.

:func:`lqg2d_adaptive_explorer` (Figures 5.7-5.8): Algorithm 4.1 (as ``table-5.3``: Bernstein
with the empirical range, delta = 0.95, N in [100, 500000]) against fixed N = 1000 and N = 100
with alpha = 1e-6, drawing J over trajectories and the batch sizes. A switch gives the authors'
2-D settings (``table-5.3-authors``): the largest sample variance and range over the components,
the step taken even when eps >= |g_k|, a first batch of 100 and N_max = 100000 (ticking it moves
the N_max control to 100000).

Both run on ``lqg2d-gamma0.9``, the discount the Section 5.2 experiments use, from theta_0 = 0.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from safepg.envs.lqg import LQG
from safepg.learning import learn
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Method, SafeStep, Vanilla
from safepg.thesis.experiments import LQG2D_GAMMA, get_experiment
from safepg.thesis.explorers.ch5_live import (
    BOUND_CHOICES,
    CURVE_POINTS,
    Ch5LiveExplorer,
    Reporter,
    bound_control_error,
    fixed,
    iteration_series,
    kernel_text,
    record_c,
    record_trace,
    trace_summary,
    trajectory_series,
)
from safepg.thesis.explorers.component import Checkbox, Plot, Select, Slider
from safepg.thesis.explorers.option_names import learner_options

#: Budgets offered (trajectories per run); the experiments ran 3*10^7.
BUDGETS = (30_000, 100_000, 300_000, 1_000_000, 3_000_000, 10_000_000, 30_000_000)
#: Entries of the flattened 2 x 2 gain drawn: the diagonal (the off-diagonal gains stay near 0).
THETA_INDEX = (0, 3)
THETA_NAMES = ("theta_11", "theta_22")
STEP_LABELS = {"scalar": "scalar step (Pirotta et al. 2013)", "coordinate": "coordinate step"}
STEP_COLORS = {"scalar": "#1f77b4", "coordinate": "#d62728"}
FIXED_RUNS = (("N=1000", 1000, "#444444"), ("N=100", 100, "#2ca02c"))
ADAPTIVE_COLOR = "#9467bd"


def authors_2d() -> Adaptive:
    """The authors' 2-D adaptive run (``table-5.3-authors``): the maxima over components, the
    unguarded step, N_max = 100000, and the first batch of 100 their script hard-codes (the same
    size as N_min here, so ``table-5.3-authors`` leaves it to the algorithm)."""
    method = get_experiment("table-5.3-authors").config("adaptive").method
    assert isinstance(method, Adaptive)
    return replace(method, batches=replace(method.batches, first=100))


def lqg2d_env() -> LQG:
    """The 2-D LQG the Section 5.2 experiments run on (``lqg2d-gamma0.9``)."""
    return LQG.thesis_2d(gamma=LQG2D_GAMMA)


def lqg_task(env: LQG) -> dict[str, Any]:
    """The task as the JavaScript learner takes it (the engine's ``js_tasks.lqg_task_data``)."""
    from safepg.thesis.explorers import js_tasks

    return js_tasks.lqg_task_data(env)


def _task_or_none(env: LQG) -> dict[str, Any] | None:
    try:
        return lqg_task(env)
    except ImportError:  # the engine for vector tasks is not installed: the page says so when it runs
        return {"kind": "lqg", "missing": "safepg.thesis.explorers.js_tasks"}


def _error(p: Mapping[str, Any]) -> ErrorModel:
    """The bound control at the delta control."""
    return bound_control_error(str(p["bound"]), float(p["delta"]))


def _seed(p: Mapping[str, Any]) -> int:
    return int(round(float(p["seed"])))


def _reporter(progress: Reporter | None, k: int, runs: int, budget: int, label: str) -> Any:
    if progress is None:
        return False
    return lambda used, total: progress((k * budget + used) / (runs * budget),
                                        f"{label}: {used:,} / {total:,} trajectories")


# ---------------------------------------------------------------- Figures 5.5-5.6
def steps_configs(p: Mapping[str, Any]) -> dict[str, Vanilla]:
    """The method of each run of the steps explorer (the page's ``configs``): the scalar and the
    coordinate safe step at the fixed N of the controls."""
    return {kind: Vanilla(int(p["n"]), SafeStep(kind, _error(p))) for kind in ("scalar", "coordinate")}


def steps_result(p: Mapping[str, Any], traces: Mapping[str, Any], data: Mapping[str, Any]) -> dict[str, Any]:
    """Plots, values and text from the traces (the page's ``safepgLqg2dSteps.result``)."""
    plots: dict[str, Any] = {"theta": {"series": []}, "J": {"series": []}}
    values: dict[str, Any] = {}
    lines = []
    for step in ("scalar", "coordinate"):
        r = traces.get(step)
        if r is None:
            values[step] = None
            continue
        label = STEP_LABELS[step]
        for j, (idx, name) in enumerate(zip(data["theta_index"], data["theta_names"])):
            x, y = iteration_series(r, "theta", data["points"], idx, True)
            plots["theta"]["series"].append({"label": f"{label}: {name}", "x": x, "y": y,
                                             "color": data["colors"][step], "dash": j == 1})
        x, y = iteration_series(r, "J", data["points"], None, True)
        plots["J"]["series"].append({"label": label, "x": x, "y": y, "color": data["colors"][step], "dash": False})
        s = values[step] = trace_summary(r)
        th = s["theta_final"]
        lines.append(f"{label}: {s['iterations']} iterations, {s['trajectories']} trajectories, J "
                     f"{fixed(s['J_final'], 3)} at theta_11 {fixed(th[data['theta_index'][0]], 6)}, theta_22 "
                     f"{fixed(th[data['theta_index'][1]], 6)}{' (diverged)' if s['diverged'] else ''}; improvement "
                     f"ratio {fixed(None if s['improvement_ratio'] is None else 100 * s['improvement_ratio'], 2)}%.")
    lines.append(data["printed"])
    return {"plots": plots, "values": values, "text": "<br>".join(lines)}


def lqg2d_steps_explorer() -> Ch5LiveExplorer:
    """Figures 5.5-5.6 live: the scalar step of Pirotta et al. (2013) against the coordinate step on the 2-D LQG.

    Returns
    -------
    Ch5LiveExplorer
        Renders in the page (no kernel); ``.interactive()`` and ``compute_py`` run safepg.
    """
    env = lqg2d_env()
    exp = get_experiment("figures-5.5-5.6")
    cfg = exp.config("scalar")
    th = {k: np.asarray(v["theta_final"]).ravel() for k, v in exp.thesis.items()}
    data = {"task": _task_or_none(env), "theta0": list(cfg.theta0), "points": CURVE_POINTS,
            "theta_index": list(THETA_INDEX), "theta_names": list(THETA_NAMES), "colors": STEP_COLORS,
            "printed": (f"Section 5.2.1 prints after 3*10^7 trajectories: scalar step theta_11 = {th['scalar'][0]:g}, "
                        f"theta_22 = {th['scalar'][3]:g}; coordinate step theta_11 = {th['coordinate'][0]:g}, "
                        f"theta_22 = {th['coordinate'][3]:g}.")}

    def compute_py(p: Mapping[str, Any], progress: Reporter | None = None) -> dict[str, Any]:
        traces = {}
        for k, (step, method) in enumerate(steps_configs(p).items()):
            rec = learn(env, method, np.asarray(cfg.theta0, float), float(p["sigma"]), budget=int(p["budget"]),
                        rng=np.random.default_rng([_seed(p), k]),
                        progress=_reporter(progress, k, 2, int(p["budget"]), STEP_LABELS[step]))
            traces[step] = record_trace(rec)
        out = steps_result(p, traces, data)
        return kernel_text(out)

    method = cfg.method
    assert isinstance(method, Vanilla) and isinstance(method.step, SafeStep)
    controls: list[Slider | Select | Checkbox] = [
        Slider("delta", "delta", 0.05, 0.95, 0.05, method.step.error.delta),
        Slider("sigma", "sigma", 0.25, 2.0, 0.05, cfg.sigma),
        Select("bound", "bound", BOUND_CHOICES, method.step.error.bound),
        Select("n", "N", tuple((str(n), f"{n:,}") for n in (100, 500, 1000, 2000, 5000, 10_000)),
               str(method.batch_size)),
        Select("budget", "trajectories", tuple((str(b), f"{b:,}") for b in BUDGETS), "100000"),
        Slider("seed", "seed", 0, 99, 1, 0)]
    plots = [Plot("theta", "updates", "gain theta_11, theta_22"), Plot("J", "updates", "expected performance J")]
    ex = Ch5LiveExplorer("Figures 5.5-5.6 live: the scalar step against the coordinate step on the 2-D LQG, "
                         "computed in your browser", controls, plots, "", compute_py, data)
    ex.page_script, ex.page_object = "lqg2d_page.js", "safepgLqg2dSteps"
    ex.kernel_title = "Figures 5.5-5.6: scalar against coordinate step on the 2-D LQG, rerun by safepg here"
    return ex


# ---------------------------------------------------------------- Figures 5.7-5.8
def adaptive_configs(p: Mapping[str, Any]) -> dict[str, Method]:
    """The method of each run of the adaptive explorer (the page's ``configs``): with ``authors``
    on, Algorithm 4.1 takes the authors' departures and first batch (their N_max is the N_max
    control's 100000, which ticking the switch selects)."""
    authors = authors_2d()
    batches = Batches(100, int(p["n_max"]), authors.batches.first if p["authors"] else None)
    adaptive = Adaptive(error=_error(p), batches=batches,
                        departures=authors.departures if p["authors"] else Departures())
    runs: dict[str, Method] = {"adaptive": adaptive}
    for name, n, _ in FIXED_RUNS:
        runs[name] = Vanilla(n, FixedStep(1e-6))
    return runs


def adaptive_result(p: Mapping[str, Any], traces: Mapping[str, Any], data: Mapping[str, Any]) -> dict[str, Any]:
    """Plots, values and text from the traces (the page's ``safepgLqg2dAdaptive.result``)."""
    plots: dict[str, Any] = {"J": {"series": []}, "N": {"series": []}}
    values: dict[str, Any] = {}
    lines = []
    for name, color in data["runs"]:
        r = traces.get(name)
        if r is None:
            values[name] = None
            continue
        label = "Algorithm 4.1" + (" (authors' settings)" if p["authors"] else "") if name == "adaptive" \
            else f"fixed {name}, alpha = 1e-6"
        style = {"label": label, "color": color, "dash": False}
        x, y = trajectory_series(r, "J", data["points"], 1)
        plots["J"]["series"].append({**style, "x": [0, *x], "y": [r["J"][0], *y]})
        x, y = iteration_series(r, "batchSize", data["points"])
        plots["N"]["series"].append({**style, "x": x, "y": y})
        s = values[name] = trace_summary(r)
        ratio = None if s["improvement_ratio"] is None else 100 * s["improvement_ratio"]
        lines.append(f"{label}: {s['iterations']} iterations, {s['trajectories']} trajectories, Upsilon-bar "
                     f"{fixed(s['upsilon_bar'], 2)}, J {fixed(s['J_final'], 3)}"
                     f"{' (diverged)' if s['diverged'] else ''}; improvement ratio {fixed(ratio, 2)}%.")
    lines.append(data["printed"])
    return {"plots": plots, "values": values, "text": "<br>".join(lines)}


def lqg2d_adaptive_explorer() -> Ch5LiveExplorer:
    """Figures 5.7-5.8 live: Algorithm 4.1 against fixed batch sizes on the 2-D LQG.

    Returns
    -------
    Ch5LiveExplorer
        Renders in the page (no kernel); ``.interactive()`` and ``compute_py`` run safepg.
    """
    env = lqg2d_env()
    exp = get_experiment("table-5.3")
    cfg = exp.config("adaptive")
    t = exp.thesis
    data = {"task": _task_or_none(env), "theta0": list(cfg.theta0), "points": CURVE_POINTS,
            "runs": [["adaptive", ADAPTIVE_COLOR], *[[n, c] for n, _, c in FIXED_RUNS]],
            "authors": {k: v for k, v in learner_options(authors_2d()).items()
                        if k in ("maxima", "unguardedStep", "first")},
            "printed": (f"Table 5.3 prints after 3*10^7 trajectories: Upsilon-bar {t['adaptive']['upsilon_bar']} "
                        f"(adaptive), {t['N=1000']['upsilon_bar']} (N = 1000), {t['N=100']['upsilon_bar']} "
                        "(N = 100).")}

    def compute_py(p: Mapping[str, Any], progress: Reporter | None = None) -> dict[str, Any]:
        traces = {}
        budget = int(p["budget"])
        for k, (name, method) in enumerate(adaptive_configs(p).items()):
            rec = learn(env, method, np.asarray(cfg.theta0, float), float(p["sigma"]), budget=budget,
                        rng=np.random.default_rng([_seed(p), k]), progress=_reporter(progress, k, 3, budget, name))
            traces[name] = record_trace(rec, record_c(rec)) if name == "adaptive" else record_trace(rec)
        out = adaptive_result(p, traces, data)
        return kernel_text(out)

    method = cfg.method
    assert isinstance(method, Adaptive)
    controls: list[Slider | Select | Checkbox] = [
        Slider("delta", "delta", 0.05, 0.95, 0.05, method.error.delta),
        Slider("sigma", "sigma", 0.25, 2.0, 0.05, cfg.sigma),
        Select("bound", "bound", BOUND_CHOICES, "bernstein-er"),
        Select("budget", "trajectories", tuple((str(b), f"{b:,}") for b in BUDGETS), "100000"),
        Slider("seed", "seed", 0, 99, 1, 0),
        Select("n_max", "N_max", tuple((str(n), f"{n:,}") for n in (10_000, 100_000, 500_000)),
               str(method.batches.n_max)),
        Checkbox("authors", "the authors' adaptive settings (max statistics, unguarded step, "
                            "first N 100, N_max 100,000)", False)]
    plots = [Plot("J", "trajectories", "expected performance J"),
             Plot("N", "iteration", "batch size N", ylog=True)]
    ex = Ch5LiveExplorer("Figures 5.7-5.8 live: adaptive batch size against fixed N on the 2-D LQG, computed in "
                         "your browser", controls, plots, "", compute_py, data)
    ex.page_script, ex.page_object = "lqg2d_page.js", "safepgLqg2dAdaptive"
    # The authors' switch selects their N_max; off, the thesis's.
    ex.links = {"authors": ((True, {"n_max": str(authors_2d().batches.n_max)}),
                            (False, {"n_max": str(method.batches.n_max)}))}
    ex.kernel_title = "Figures 5.7-5.8: adaptive against fixed batch sizes on the 2-D LQG, rerun by safepg here"
    return ex


__all__ = ["BUDGETS", "adaptive_configs", "authors_2d", "adaptive_result", "lqg2d_adaptive_explorer", "lqg2d_env",
           "lqg2d_steps_explorer", "steps_configs", "steps_result"]
