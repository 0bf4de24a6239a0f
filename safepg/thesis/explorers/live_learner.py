r"""The live batch-size explorer: Algorithm 4.1 reruns in the reader's browser.

:func:`live_batch_size_explorer` returns an :class:`~safepg.explorers.component.Explorer` whose page
half (``static/live_page.js``, with the component's ``static/runtime.js``) runs the JavaScript
learner ``safepg/thesis/explorers/static/learner.js`` (Algorithm 4.1 and vanilla
policy gradient on ``LQG.thesis_1d()``, the same algorithm as :mod:`safepg.learning`) in
a Web Worker created from an inline Blob, so it needs no kernel, no network and no file
beside the page (it works from ``file://``). Every control move cancels the running
worker and starts a new one; long runs are drawn as they progress.

The Python twin ``compute_py`` runs :func:`safepg.learning.adaptive_pg` and
:func:`~safepg.learning.vanilla_pg` with the same settings and returns the same structure
(:meth:`LiveLearnerExplorer.interactive` draws it with ipywidgets, in a worker thread that
shows each run's progress and stops a run when a control moves). The two use different
random-number generators (safepg's counter-based streams here, xoshiro128** in the page), so for one seed
their curves differ as two seeds do; tests/test_learner_js.py shows that they agree in
distribution.

Where the controls match one of the stored Table 5.2 runs (sigma = 1, baseline on and the
estimator, bound, delta and score of a stored configuration) the seed mean of that run,
computed by safepg when the book was built, is drawn beside the live curve.

Each run's summary line says how far theta moved (the furthest theta got from theta_0) and,
when that is under ``STILL`` of the way from theta_0 to theta* (the run barely moved: the
updates it counts are no-ops or steps too small to show on J), that the improvement ratio
carries no information: an update that leaves theta where it was counts as one after
which J did not decrease. A last line says which objective each number is on:
Upsilon-bar on the simulated (clipped, H-step, discounted) return, J and the improvement
ratio on the closed-form J(theta) that the J plot draws.
"""

from __future__ import annotations

import hashlib
import html
import json
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from safepg import portable
from safepg.definition import to_dict
from safepg.envs.lqg import LQG
from safepg.learning import learn
from safepg.options import Adaptive, Batches, Departures, FixedStep, Gradient, Vanilla
from safepg.record import CHECKPOINTS, LearningRecord, on_trajectories
from safepg.thesis import plotting
from safepg.thesis.analysis import by_iteration, mean_band
from safepg.thesis.explorers.ch5_live import bound_control_error, fixed, thin
from safepg.thesis.explorers.component import Explorer, Plot, Select, Slider, static_text

#: Budgets offered (trajectories); the stored runs are embedded up to the largest.
BUDGETS = (10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000)
#: Points of each drawn curve (iterations or trajectory counts): enough for a 640 px plot.
CURVE_POINTS = 600
#: Significant digits of the embedded stored curves: what the page can show, and few
#: enough that the embedded JSON does not depend on the machine's floating-point library.
DIGITS = 6
BOUND_CHOICES = (("chebyshev", "Chebyshev"), ("hoeffding", "Hoeffding"), ("hoeffding-er", "Hoeffding (e.r.)"),
                 ("bernstein", "Bernstein"), ("bernstein-er", "Bernstein (e.r.)"))
#: A run whose theta stays within this share of |theta* - theta_0| of theta_0 did not move:
#: its improvement ratio carries no information. On the 1-D LQG from theta_0 = 0 that is
#: 5.9e-4 (theta* = -0.588), over which J rises by 0.54 of the 43.5 from J(0) to J(theta*):
#: a J curve flat at the plot's scale.
STILL = 1e-3
#: ``progress`` of the Python twin: ``report(fraction, message)`` (see ``Explorer.compute_reports_progress``).
Reporter = Callable[[float, str], object]
TITLE = "Algorithm 4.1 live: adaptive batch size on the 1-D LQG, computed in your browser"


def learner_js() -> str:
    """The JavaScript learner shipped in the package: ``static/learner.js`` and the files that extend
    it to the vector tasks, concatenated (:func:`safepg.thesis.explorers.js_tasks.learner_sources`)."""
    from safepg.thesis.explorers.js_tasks import learner_sources

    return learner_sources()


def _round(values: Any, digits: int = DIGITS) -> list[float | None]:
    """Floats rounded to ``digits`` significant digits (None for NaN), for embedding."""
    out: list[float | None] = []
    for v in np.asarray(values, dtype=float).ravel():
        out.append(float(f"{v:.{digits}g}") if np.isfinite(v) else None)
    return out


def task_data(env: LQG | None = None) -> dict[str, Any]:
    """The 1-D LQG the page's learner runs (:func:`~safepg.thesis.explorers.js_tasks.lqg_task_data`)."""
    from safepg.thesis.explorers.js_tasks import lqg_task_data

    env = LQG.thesis_1d() if env is None else env
    if env.dim != 1:
        raise ValueError(f"env must be a one-dimensional LQG, got dim={env.dim}")
    return lqg_task_data(env)


def _stored_run(cfg: Any, recs: Sequence[LearningRecord], grid: np.ndarray) -> dict[str, Any]:
    """The embedded curves of one stored configuration: seed means up to the largest budget."""
    top = BUDGETS[-1]
    starts = [np.concatenate([[0], np.cumsum(r.batch_size)[:-1]]) for r in recs]
    cut = [int(np.searchsorted(s, top)) for s in starts]  # iterations that start before the largest budget
    n = mean_band(by_iteration(recs, "batch_size"))[0]
    a = mean_band(by_iteration(recs, "alpha"))[0]
    start = np.full((len(recs), max(cut)), np.nan)
    for i, (s, k) in enumerate(zip(starts, cut)):
        start[i, :k] = s[:k]
    start_mean = np.nanmean(start, axis=0)
    keep = np.asarray(thin(max(cut)))
    per_budget = {}
    for B in BUDGETS:
        ups, its = [], []
        for r, s in zip(recs, starts):
            # Trajectories 1..B: each batch weighs by its part inside the first B.
            w = np.clip(B - s, 0, r.batch_size)
            ups.append(portable.fsum_mean(r.J_hat, weights=w))  # exact sums, not BLAS (safepg.portable)
            its.append(int(np.count_nonzero(s < B)))
        per_budget[str(B)] = {"upsilon_bar": _round([np.mean(ups)])[0], "iterations": float(np.mean(its))}
    m = cfg.method
    return {"estimator": m.gradient.estimator, "bound": m.error.bound + ("-er" if m.error.empirical_range else ""),
            "delta": m.error.delta, "score": m.gradient.score_action, "seeds": len(recs), "name": cfg.name,
            "iteration": (keep + 1).tolist(), "start": _round(start_mean[keep]),
            "batch_size": _round(n[keep]), "alpha": _round(a[keep]),
            "J": _round(mean_band(on_trajectories(recs, grid, "J"))[0]), "budgets": per_budget}


def _matches_1d_table(cfg: Any) -> bool:
    """A stored configuration the live learner can rerun: Algorithm 4.1 on the 1-D LQG from
    theta_0 = 0, sigma = 1, with the default batch limits, range and a long enough budget."""
    m = cfg.method
    return (isinstance(m, Adaptive) and to_dict(cfg.make_task()) == to_dict(LQG.thesis_1d())
            and tuple(cfg.theta0) == (0.0,) and cfg.sigma == 1.0 and m.gradient.baseline and m.batches == Batches()
            and m.departures == Departures() and m.error.theoretical_range is None and cfg.budget >= BUDGETS[-1]
            and cfg.warm_start is None)


def overlay_key(p: Mapping[str, Any]) -> str:
    """Key of the stored run matching the controls ``p`` (also built by the page)."""
    return f"{p['estimator']}-{p['bound']}-delta={float(p['delta']):g}-{p['score']}"


class LiveLearnerExplorer(Explorer):
    """An :class:`~safepg.explorers.component.Explorer` whose page runs the JavaScript learner in a
    Web Worker (see the module docstring); ``compute_js`` is unused."""

    continuous_update = False  # interactive(): each change is a whole learning run, so sliders act on release
    compute_reports_progress = True  # compute_py(p, progress=report): after each batch of either run
    kernel_title = "Algorithm 4.1 live: adaptive batch size on the 1-D LQG, rerun by safepg in this kernel"
    plot_width = 5.0

    def to_html(self) -> str:
        """The self-contained HTML + JavaScript block (learner, worker and plots inline)."""
        spec = json.dumps(self._spec(), separators=(",", ":"), allow_nan=False)
        learner = json.dumps(learner_js())
        # "safepg-" + 10 hex digits, as Explorer's ids: tests/nbval_sanitize.cfg masks them.
        uid = "safepg-" + hashlib.sha1((self.title + spec + learner).encode()).hexdigest()[:10]
        return (
            f'<div class="safepg-explorer safepg-live" id="{uid}" style="border:1px solid rgba(127,127,127,.4);'
            f'border-radius:6px;padding:0.8em;margin:1em 0">'
            f'<div style="font-weight:600;margin-bottom:0.4em">{html.escape(self.title)}</div>'
            f'{self._controls_html()}'
            '<div class="safepg-status" style="font-size:0.85em;opacity:0.8;margin:0.2em 0"></div>'
            f'{self._plots_html()}<div class="safepg-text" style="font-family:monospace;font-size:0.9em"></div>'
            '<pre class="safepg-values" hidden></pre>'
            # The page half (static/live_page.js) draws with the runtime's safepgPlot; the learner
            # travels as a string so the worker can be built from a Blob (no file, no network:
            # static/live_jobs.js).
            f'<script>(function(){{\n{static_text("runtime.js")}\n{static_text("live_jobs.js")}\n'
            f'{static_text("live_page.js")}'
            f"const spec={spec};const learnerSrc={learner};"
            f'safepgLiveLearner(document.getElementById("{uid}"),spec,learnerSrc);}})();</script></div>'
        )

    def __repr__(self) -> str:
        return f"LiveLearnerExplorer({self.title!r})"


def live_batch_size_explorer(records: Mapping[str, Sequence[LearningRecord]] | None = None,
                             configs: Sequence[Any] = (), points: int = 300) -> LiveLearnerExplorer:
    """Algorithm 4.1 (and vanilla PG beside it) rerun live on the 1-D LQG for any delta,
    sigma, bound, estimator, baseline, score, budget and seed.

    Parameters
    ----------
    records : stored runs by configuration name (e.g. ``run_experiment("table-5.2")``), or None
    configs : the :class:`~safepg.thesis.experiments.RunConfig` of those runs; those that the
        learner can rerun (Algorithm 4.1, 1-D LQG, theta_0 = 0, sigma = 1, baseline on)
        are embedded as overlays, their seed means rounded to 6 significant digits
    points : trajectory counts at which the stored J curves are embedded (log-spaced up
        to the largest budget, plus a linear part so every budget's plot has points)

    Returns
    -------
    LiveLearnerExplorer
        Renders in the page (no kernel); ``.interactive()`` and ``compute_py`` run safepg.
    """
    env = LQG.thesis_1d()
    task = task_data(env)
    top = BUDGETS[-1]
    grid = np.unique(np.concatenate([np.geomspace(1, top, points // 2), np.linspace(1, top, points - points // 2)])
                     .round().astype(np.int64))
    runs: dict[str, Any] = {}
    for c in configs:
        recs = (records or {}).get(c.name) or []
        if not recs or not _matches_1d_table(c):
            continue
        run = _stored_run(c, recs, grid)
        runs[overlay_key(run)] = run
    style = plotting.style_table()
    data = {"task": task, "grid": grid.tolist(), "runs": runs, "points": CURVE_POINTS, "still": STILL,
            "theta_star": float(np.asarray(env.optimal_gain(), dtype=float).reshape(-1)[0]),
            "muted": plotting.MUTED, "vanilla_color": "#444444",
            "colors": {k: v["color"] for k, v in style["bounds"].items()}}

    def compute_py(p: Mapping[str, Any], progress: Reporter | None = None) -> dict[str, Any]:
        return _compute_py(p, env, data, progress)

    controls: list[Slider | Select] = [
        Slider("delta", "delta", 0.01, 0.99, 0.01, 0.95),
        Slider("sigma", "sigma", 0.25, 2.0, 0.05, 1.0),
        Select("bound", "bound", BOUND_CHOICES, "bernstein-er"),
        Select("estimator", "estimator", (("gpomdp", "G(PO)MDP"), ("reinforce", "REINFORCE")), "gpomdp"),
        Select("baseline", "baseline", (("on", "on"), ("off", "off")), "on"),
        Select("score", "score", (("clipped", "clipped action (authors)"), ("raw", "raw action (unbiased)")),
               "clipped"),
        Select("budget", "trajectories", tuple((str(b), f"{b:,}") for b in BUDGETS), "1000000"),
        Slider("seed", "seed", 0, 99, 1, 0),
        Select("vanilla_n", "vanilla PG: N", (("off", "off"), ("100", "100"), ("1000", "1000"), ("10000", "10000")),
               "1000"),
        Select("vanilla_alpha", "alpha", tuple((a, a) for a in ("1e-3", "1e-4", "1e-5", "1e-6")), "1e-4"),
    ]
    plots = [Plot("N", "iteration", "batch size N", ylog=True),
             Plot("J", "trajectories", "expected performance J(theta)"),
             Plot("alpha", "iteration", "step size alpha", ylog=True)]
    return LiveLearnerExplorer(TITLE, controls, plots, "", compute_py, data)


def theta_moved(theta: Any) -> float:
    """How far theta moved over a run: the largest |theta_i - theta_0| over its iterations
    and components (|theta_final - theta_0| for a run that moves one way)."""
    t = np.asarray(theta, dtype=float)
    t = t.reshape(t.shape[0], -1)
    return float(np.max(np.abs(t - t[0])))


def still_tolerance(data: Mapping[str, Any], theta0: float = 0.0) -> float:
    """The movement under which a run counts as still: ``STILL`` of |theta* - theta_0|."""
    return float(data["still"]) * abs(float(data["theta_star"]) - theta0)


def run_summary(rec: LearningRecord, tol: float) -> dict[str, Any]:
    """The page's summary of one run (``safepgLiveSummary``): safepg's, plus ``theta_moved``
    (:func:`theta_moved`) and ``ratio_vacuous`` (no iteration, or theta moved less than ``tol``)."""
    s = rec.summary(CHECKPOINTS)  # the thesis's checkpoints, not the run's own
    moved = theta_moved(rec.theta)
    return {"iterations": s["iterations"], "trajectories": s["trajectories"], "upsilon_bar": s["upsilon_bar"],
            "improvement_ratio": s["improvement_ratio"], "J_final": s["J_final"], "theta_final": s["theta"][0],
            "theta_moved": moved, "ratio_vacuous": bool(s["iterations"] == 0 or moved < tol),
            "J_at": {k: v for k, v in s["J_at"].items() if int(k) <= BUDGETS[-1]},
            "first_batches": rec.batch_size[:3].tolist(), "done": True, "diverged": rec.diverged}


def _moved_text(v: float) -> str:
    """A movement as the page writes it: 0, 7.0e-5 under 10^-3, else 4 decimals."""
    if not np.isfinite(v):
        return "-"
    if v == 0:
        return "0"
    if v < 1e-3:
        mantissa, exponent = f"{v:.1e}".split("e")
        return f"{mantissa}e{int(exponent):+d}"  # JavaScript's toExponential(1): 7.0e-5
    return f"{v:.4f}"


def run_line(name: str, v: Mapping[str, Any], data: Mapping[str, Any]) -> str:
    """One run's summary line (the page's ``safepgLiveLine``, word for word)."""
    moved = _moved_text(v["theta_moved"])
    if v["ratio_vacuous"]:
        ratio = (f"theta moved by {moved}, less than {100 * data['still']:g}% of the way to theta* = "
                 f"{fixed(data['theta_star'], 2)}: the improvement ratio carries no information")
    else:
        ratio = f"theta moved by {moved}, improvement ratio {fixed(100 * v['improvement_ratio'], 2)}%"
    return (f"{name}: {v['iterations']} iterations, {v['trajectories']} trajectories, "
            f"Upsilon-bar {fixed(v['upsilon_bar'], 4)}, J {fixed(v['J_final'], 3)} at theta "
            f"{fixed(v['theta_final'], 4)}{' (diverged)' if v['diverged'] else ''}; {ratio}.")


def objectives_line(data: Mapping[str, Any]) -> str:
    """Which objective each number is on (the page's ``safepgLiveObjectives``)."""
    t = data["task"]
    return (f"Upsilon-bar: the simulated return (clipped states and actions, {t['H']} steps, discounted by "
            f"gamma = {t['gamma']:g}), averaged over all trajectories. J and the improvement ratio (share of "
            "updates after which J did not fall): the closed-form J(theta) of the J plot (infinite horizon, "
            "no clipping).")


def summary_text(values: Mapping[str, Any], data: Mapping[str, Any], budget: int) -> str:
    """The text under the plots, one line per run, the stored run, the objectives (the page's
    ``safepgLiveText``; the page joins the lines with <br>, this with newlines)."""
    lines = [run_line("Algorithm 4.1", values["adaptive"], data)]
    if values.get("vanilla"):
        lines.append(run_line("vanilla PG", values["vanilla"], data))
    th = values["thesis"]
    if th["found"]:  # toFixed(0) rounds halves up
        lines.append(f"stored safepg run {th['name']} (seed mean, first {budget} trajectories): "
                     f"{math.floor(th['iterations'] + 0.5)} iterations, Upsilon-bar {fixed(th['upsilon_bar'], 4)}.")
    else:
        lines.append("no stored run for these settings (Table 5.2 ran sigma = 1, baseline on, "
                     "delta in {0.05, 0.25, 0.5, 0.75, 0.95}).")
    lines.append(objectives_line(data))
    return "\n".join(lines)


def _compute_py(p: Mapping[str, Any], env: LQG, data: Mapping[str, Any],
                progress: Reporter | None = None) -> dict[str, Any]:
    """The Python twin of the page: the same runs with safepg (numpy seeds: adaptive
    ``seed``, vanilla ``[seed, 1]``), the same plotted structure and values.

    ``progress(fraction, message)``, if given, is called after each batch of either run
    (the two runs are one budget each); what it raises stops the runs and propagates.
    """
    budget, seed = int(p["budget"]), int(round(float(p["seed"])))
    bound = str(p["bound"])
    gradient = Gradient(p["estimator"], p["baseline"] == "on", p["score"])
    runs = 1 if p["vanilla_n"] == "off" else 2

    def report(k: int, label: str) -> Callable[[int, int], object] | bool:
        """safepg's per-batch report for run k, as a fraction of all runs (False: no report)."""
        if progress is None:
            return False
        return lambda used, total: progress((k * budget + used) / (runs * budget),
                                            f"{label}: {used:,} / {total:,} trajectories")

    error = bound_control_error(bound, float(p["delta"]))
    recs = {"adaptive": learn(env, Adaptive(gradient, error), 0.0, float(p["sigma"]), budget=budget,
                              rng=np.random.default_rng(seed), progress=report(0, "Algorithm 4.1"))}
    if p["vanilla_n"] != "off":
        recs["vanilla"] = learn(env, Vanilla(int(p["vanilla_n"]), FixedStep(float(p["vanilla_alpha"])), gradient),
                                0.0, float(p["sigma"]), budget=budget, rng=np.random.default_rng([seed, 1]),
                                progress=report(1, "vanilla PG"))
    plots: dict[str, Any] = {"N": {"series": []}, "J": {"series": []}, "alpha": {"series": []}}
    values: dict[str, Any] = {"done": True}
    key = overlay_key(p)
    run = data["runs"].get(key) if float(p["sigma"]) == 1.0 and p["baseline"] == "on" else None
    if run is not None:
        k = next((i for i, s in enumerate(run["start"]) if s is None or s >= budget), len(run["start"]))
        g = int(np.searchsorted(data["grid"], budget, side="right"))
        seeds = f"{run['seeds']} seed{'' if run['seeds'] == 1 else 's'}"
        muted = {"color": data["muted"], "dash": True, "label": f"stored safepg run ({seeds})"}
        plots["N"]["series"].append({"x": run["iteration"][:k], "y": run["batch_size"][:k], **muted})
        plots["J"]["series"].append({"x": data["grid"][:g], "y": run["J"][:g], **muted})
        plots["alpha"]["series"].append({"x": run["iteration"][:k], "y": run["alpha"][:k], **muted})
        values["thesis"] = {"found": True, "key": key, "name": run["name"], **run["budgets"][str(budget)]}
    else:
        values["thesis"] = {"found": False, "key": key}
    values["vanilla"] = None
    for name, rec in recs.items():
        keep = np.asarray(thin(rec.iterations, data["points"]))
        style = ({"color": data["colors"][bound], "dash": p["estimator"] == "reinforce"} if name == "adaptive"
                 else {"color": data["vanilla_color"], "dash": False})
        style["label"] = ("Algorithm 4.1 (safepg)" if name == "adaptive"
                          else f"vanilla, N = {p['vanilla_n']}, alpha = {p['vanilla_alpha']}")
        plots["N"]["series"].append({"x": (keep + 1).tolist(), "y": rec.batch_size[keep].tolist(), **style})
        plots["alpha"]["series"].append({"x": (keep + 1).tolist(), "y": rec.alpha[keep].tolist(), **style})
        T = np.unique(np.maximum(1, np.round(1 + np.arange(data["points"]) * (budget - 1) / (data["points"] - 1))))
        T = T[T <= rec.trajectories].astype(np.int64)
        plots["J"]["series"].append({"x": T.tolist(), "y": on_trajectories([rec], T, "J")[0].tolist(), **style})
        values[name] = run_summary(rec, still_tolerance(data, float(rec.theta[0, 0])))
    return {"plots": plots, "values": values, "text": summary_text(values, data, budget)}


__all__ = ["BUDGETS", "STILL", "LiveLearnerExplorer", "learner_js", "live_batch_size_explorer", "objectives_line",
           "run_line", "run_summary", "still_tolerance", "summary_text", "task_data", "theta_moved"]
