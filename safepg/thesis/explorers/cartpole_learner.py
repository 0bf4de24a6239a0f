r"""Section 5.3 live: the doubled-pole cart-pole explorer, computed in the reader's browser (see :mod:`.ch5_live`).

:func:`cartpole_explorer` starts Algorithm 4.1 (G(PO)MDP, Bernstein with the empirical range, as
``table-5.4``) and the fixed-step method of ``table-5.4`` (vanilla, N = 4000, alpha = 0.01) from a
baseline policy on the doubled pole: our stored baseline (``cartpole-baseline``, seed 0) or the
authors' theta* (:func:`~safepg.thesis.authors.cartpole_theta_star`), both embedded. Each of the
authors' settings (``table-5.4-authors``) is a checkbox (:data:`SETTINGS`): gamma = 0.9 in c on an
undiscounted return, R and M_phi measured per batch, the maxima over components, the unguarded
step, a first batch of 1000 (N_min 10), 12 degrees instead of 41.8, m l kept at 0.05. Unticked,
the run is the thesis's text: the penalty constant is about 6*10^7, the steps are zero or under
10^-8 and theta does not move, which the summary says in words; the button "the authors' settings"
ticks every box (and starts from their theta*), and theta_xdot moves.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from safepg.envs.cartpole import CartPole
from safepg.learning import learn
from safepg.options import Adaptive, ErrorModel, Vanilla
from safepg.thesis.authors import cartpole_theta_star
from safepg.thesis.experiments import AUTHORS_DOUBLED, get_experiment, method_of
from safepg.thesis.explorers.ch5_live import (
    CURVE_POINTS,
    Ch5LiveExplorer,
    Reporter,
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

#: Trajectories per run offered; small, so that a run takes seconds in a browser.
BUDGETS = (10_000, 20_000, 50_000, 100_000, 200_000)
#: A component of theta that changed by less than this did not move (the scorecard's rule).
FROZEN = 1e-6
THETA_NAMES = ("theta_x", "theta_xdot", "theta_beta", "theta_betadot")
THETA_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd")
ADAPTIVE_COLOR, VANILLA_COLOR = "#9467bd", "#444444"


def _depart(name: str, method: Adaptive) -> Adaptive:
    """``method`` with the departure ``name`` taken."""
    return replace(method, departures=replace(method.departures, **{name: True}))


def _first_batch_1000(method: Adaptive) -> Adaptive:
    """The authors' cart-pole batches: a first batch of 1000, N_min 10."""
    return replace(method, batches=replace(method.batches, n_min=10, first=1000))


def _same(method: Adaptive) -> Adaptive:
    return method


#: The authors' settings, one checkbox each: (name, label, task fields, the change to Algorithm 4.1).
SETTINGS: tuple[tuple[str, str, dict[str, Any], Callable[[Adaptive], Adaptive]], ...] = (
    ("gamma09", "gamma = 0.9 in c (undiscounted return)",
     {"gamma": AUTHORS_DOUBLED["gamma"], "constants_gamma": AUTHORS_DOUBLED["constants_gamma"]}, _same),
    ("batch_constants", "R and M_phi measured per batch", {}, partial(_depart, "batch_constants")),
    ("max_stats", "maxima over components", {}, partial(_depart, "maxima")),
    ("unguarded", "step even when eps >= |g_k|", {}, partial(_depart, "unguarded_step")),
    ("first1000", "first batch 1000 (N_min 10)", {}, _first_batch_1000),
    ("deg12", "12 deg (not 41.8 deg)", {"angle_threshold_deg": AUTHORS_DOUBLED["angle_threshold_deg"]}, _same),
    ("ml005", "m l kept at 0.05", {"polemass_length": AUTHORS_DOUBLED["polemass_length"]}, _same),
)
TASK_BOXES = tuple(name for name, _, fields, _ in SETTINGS if fields)


def task_key(p: Mapping[str, Any]) -> str:
    """Which embedded task the boxes select: one "0"/"1" per box of :data:`TASK_BOXES`."""
    return "".join("1" if p[name] else "0" for name in TASK_BOXES)


def task_fields(p: Mapping[str, Any]) -> dict[str, Any]:
    """The :class:`~safepg.envs.cartpole.CartPole` fields the ticked boxes set (on the doubled pole)."""
    out: dict[str, Any] = {}
    for name, _, fields, _ in SETTINGS:
        if fields and p[name]:
            out.update(fields)
    return out


def cartpole_task(p: Mapping[str, Any]) -> CartPole:
    """The doubled-pole task of the boxes ``p``."""
    return CartPole.thesis_doubled(**task_fields(p))


def adaptive_method(p: Mapping[str, Any]) -> Adaptive:
    """Algorithm 4.1 as the controls ``p`` set it: ``table-5.4``'s adaptive run (Bernstein with
    the empirical range) at the control's delta, with the ticked boxes' changes."""
    method = replace(method_of(get_experiment("table-5.4").config("adaptive"), Adaptive),
                     error=ErrorModel("bernstein", float(p["delta"]), "empirical"))
    for name, _, _, change in SETTINGS:
        if p[name]:
            method = change(method)
    return method


def vanilla_method() -> Vanilla:
    """``table-5.4``'s fixed-step method (N = 4000, alpha = 0.01), whatever the boxes."""
    method = get_experiment("table-5.4").config("N=4000").method
    assert isinstance(method, Vanilla)
    return method


def stored_baseline() -> np.ndarray | None:
    """Seed 0's final theta of the stored ``cartpole-baseline`` run, or None if it is not stored."""
    try:
        from safepg.thesis.experiment_store import load_experiment

        recs = load_experiment("cartpole-baseline").get("baseline") or []
    except Exception:  # noqa: BLE001 (no store, or a damaged one: the explorer offers theta* alone)
        return None
    return np.asarray(recs[0].theta_final, dtype=float) if recs else None


def _moved_text(v: float | None) -> str:
    """A movement as the page writes it (``safepgCartpoleMoved``): 1.3e-9 under 10^-3, else 4 decimals."""
    if v is None:
        return "-"
    if v == 0:
        return "0"
    if v < 1e-3:
        mantissa, exponent = f"{v:.1e}".split("e")
        return f"{mantissa}e{int(exponent):+d}"
    return f"{v:.4f}"


def _exp(v: float | None) -> str:
    if v is None:
        return "-"
    mantissa, exponent = f"{v:.2e}".split("e")
    return f"{mantissa}e{int(exponent):+d}"


def settings_line(p: Mapping[str, Any]) -> str:
    """The settings a run used, in words (the page's ``safepgCartpoleSettings``)."""
    return ("Settings: " + ("gamma = 1 in the return, 0.9 in c" if p["gamma09"] else "gamma = 0.99")
            + "; R and M_phi " + ("measured per batch" if p["batch_constants"] else "the task's bounds")
            + "; " + ("largest variance and range over components" if p["max_stats"] else "statistics of component k")
            + "; " + ("unguarded step" if p["unguarded"] else "no step when eps >= |g_k|")
            + "; first batch " + ("1000, N_min 10" if p["first1000"] else "100, N_min 100")
            + "; " + ("12" if p["deg12"] else "41.8") + " deg; m l "
            + ("0.05 (the 1 m pole's)" if p["ml005"] else "0.1 (a consistent 2 m pole)") + ".")


def cartpole_result(p: Mapping[str, Any], traces: Mapping[str, Any], data: Mapping[str, Any]) -> dict[str, Any]:
    """Plots, values and text from the traces (the page's ``safepgCartpolePage.result``)."""
    plots: dict[str, Any] = {k: {"series": []} for k in ("theta", "ret", "N", "alpha", "c")}
    values: dict[str, Any] = {}
    lines = []
    pts = data["points"]
    for name in ("adaptive", "vanilla"):
        r = traces.get(name)
        if r is None:
            values[name] = None
            continue
        label = "Algorithm 4.1" if name == "adaptive" else data["vanilla_label"]
        style = {"label": label, "color": ADAPTIVE_COLOR if name == "adaptive" else VANILLA_COLOR, "dash": False}
        x, y = trajectory_series(r, "Jhat", pts)
        plots["ret"]["series"].append({**style, "x": x, "y": y})
        x, y = iteration_series(r, "batchSize", pts)
        plots["N"]["series"].append({**style, "x": x, "y": y})
        x, y = iteration_series(r, "alpha", pts)
        plots["alpha"]["series"].append({**style, "x": x, "y": y})
        s = trace_summary(r)
        moved = s["theta_moved"]
        big = max((m for m in moved if m is not None), default=0.0)
        s["frozen"] = bool(big < data["frozen"])
        s["alpha_max"] = max((a for a in r["alpha"] if a is not None), default=None)
        cs = [c for c in r["c"] if c is not None]
        s["c_min"], s["c_max"] = (min(cs), max(cs)) if cs else (None, None)
        values[name] = s
        head = (f"{label}: {s['iterations']} iterations, {s['trajectories']} trajectories, mean batch return "
                f"{fixed(s['upsilon_bar'], 2)}")
        if name == "adaptive":
            theta0 = r["theta"][0]
            for j, nm in enumerate(data["theta_names"]):
                x, y = iteration_series(r, "theta", pts, j, True)
                plots["theta"]["series"].append({"label": f"{nm} - {nm}_0", "x": x, "color": data["theta_colors"][j],
                                                 "dash": False, "y": [None if v is None else v - theta0[j] for v in y]})
            # The band |change| < FROZEN: a frozen theta stays inside it, at a scale that shows it.
            band = {"x": [0, s["iterations"]], "color": "#999999", "dash": True}
            plots["theta"]["series"] += [{**band, "label": f"+/-{_moved_text(data['frozen'])}: did not move",
                                          "y": [data["frozen"]] * 2},
                                         {**band, "label": "", "y": [-data["frozen"]] * 2}]
            x, y = iteration_series(r, "c", pts)
            plots["c"]["series"].append({**style, "x": x, "y": y})
            cs_text = (_exp(s["c_min"]) if s["c_min"] == s["c_max"]
                       else f"from {_exp(s['c_min'])} to {_exp(s['c_max'])}")
            if s["frozen"]:
                tail = (f"theta did not move: no component changed by {_moved_text(data['frozen'])} or more (largest "
                        f"change {_moved_text(big)}, largest step alpha {_exp(s['alpha_max'])}, penalty constant c "
                        f"{cs_text}).")
            else:
                each = ", ".join(f"{nm} by {_moved_text(m)}" for nm, m in zip(data["theta_names"], moved))
                tail = f"theta moved: {each} (penalty constant c {cs_text})."
        else:
            tail = f"theta moved by up to {_moved_text(big)}{' (diverged)' if s['diverged'] else ''}."
        lines.append(f"{head}; {tail}")
    lines.append(settings_line(p))
    return {"plots": plots, "values": values, "text": "<br>".join(lines)}


def cartpole_explorer(baseline: Any = None) -> Ch5LiveExplorer:
    """Section 5.3 live: Algorithm 4.1 against the fixed step on the doubled pole, with a checkbox
    for each of the authors' settings and a button for all of them.

    Parameters
    ----------
    baseline : our baseline policy (4 numbers), or None for seed 0 of the stored ``cartpole-baseline``
        (left out when it is not stored: the explorer then starts from the authors' theta* alone)

    Returns
    -------
    Ch5LiveExplorer
        Renders in the page (no kernel); ``.interactive()`` and ``compute_py`` run safepg.
    """
    from safepg.thesis.explorers.js_tasks import cartpole_task_data

    base = stored_baseline() if baseline is None else np.asarray(baseline, dtype=float)
    starts: dict[str, list[float]] = {}
    options = []
    if base is not None:
        starts["baseline"] = [float(v) for v in base]
        options.append(("baseline", "our baseline (cartpole-baseline, seed 0)"))
    starts["theta_star"] = [float(v) for v in cartpole_theta_star()]
    options.append(("theta_star", "the authors' theta* (theta_star.npy)"))
    tasks = {}
    for k in range(2 ** len(TASK_BOXES)):
        p = {name: bool(k >> i & 1) for i, name in enumerate(TASK_BOXES)}
        tasks[task_key(p)] = cartpole_task_data(cartpole_task(p))
    van = learner_options(vanilla_method())
    text = adaptive_method({"delta": 0.95, **{name: False for name, *_ in SETTINGS}})
    text_options = learner_options(text)
    data = {"tasks": tasks, "starts": starts, "points": CURVE_POINTS, "frozen": FROZEN,
            "theta_names": list(THETA_NAMES), "theta_colors": list(THETA_COLORS), "task_boxes": list(TASK_BOXES),
            # Each box's options under the page learner's names, as far as they differ from the text's.
            "settings": {name: {k: v for k, v in learner_options(change(text)).items() if text_options[k] != v}
                         for name, _, _, change in SETTINGS},
            "adaptive": text_options, "vanilla": van,
            "vanilla_label": f"fixed step (N = {van['batchSize']}, alpha = {van['alpha']:g})"}

    def compute_py(p: Mapping[str, Any], progress: Reporter | None = None) -> dict[str, Any]:
        task, theta0, sigma = cartpole_task(p), np.asarray(starts[str(p["start"])]), float(p["sigma"])
        seed, budget = int(round(float(p["seed"]))), int(p["budget"])

        def report(k: int, label: str) -> Any:
            if progress is None:
                return False
            return lambda used, total: progress((k * budget + used) / (2 * budget),
                                                f"{label}: {used:,} / {total:,} trajectories")

        method = adaptive_method(p)
        rec = learn(task, method, theta0, sigma, budget=budget, rng=np.random.default_rng([seed, 0]),
                    progress=report(0, "Algorithm 4.1"))
        traces = {"adaptive": record_trace(rec, record_c(rec, method.departures.batch_constants))}
        traces["vanilla"] = record_trace(learn(task, vanilla_method(), theta0, sigma, budget=budget,
                                               rng=np.random.default_rng([seed, 1]), progress=report(1, "fixed step")))
        out = cartpole_result(p, traces, data)
        return kernel_text(out)

    controls: list[Any] = [Select("start", "start", tuple(options), options[0][0]),
                           *(Checkbox(name, label, False) for name, label, _, _ in SETTINGS),
                           Slider("delta", "delta", 0.05, 0.95, 0.05, 0.95),
                           Slider("sigma", "sigma", 0.25, 2.0, 0.05, 1.0),
                           Select("budget", "trajectories", tuple((str(b), f"{b:,}") for b in BUDGETS), "20000"),
                           Slider("seed", "seed", 0, 99, 1, 0)]
    plots = [Plot("theta", "updates", "theta_i - theta_i,0 (Algorithm 4.1)"),
             Plot("ret", "trajectories", "batch-average return"),
             Plot("N", "iteration", "batch size N", ylog=True),
             Plot("alpha", "iteration", "step size alpha", ylog=True),
             Plot("c", "iteration", "penalty constant c", ylog=True)]
    ex = Ch5LiveExplorer("Section 5.3 live: Algorithm 4.1 on the doubled pole, the thesis's text and the authors' "
                         "settings, computed in your browser", controls, plots, "", compute_py, data)
    ex.page_script, ex.page_object = "cartpole_page.js", "safepgCartpolePage"
    ex.kernel_title = "Section 5.3: Algorithm 4.1 on the doubled pole, rerun by safepg in this kernel"
    thesis = {name: False for name, _, _, _ in SETTINGS}
    ex.presets = {"thesis": ("the thesis's text", {**thesis, "start": options[0][0]}),
                  "authors": ("the authors' settings", {**{k: True for k in thesis}, "start": "theta_star"})}
    return ex


__all__ = ["BUDGETS", "FROZEN", "SETTINGS", "TASK_BOXES", "adaptive_method", "cartpole_explorer", "cartpole_result",
           "cartpole_task", "settings_line", "stored_baseline", "task_fields", "task_key", "vanilla_method"]
