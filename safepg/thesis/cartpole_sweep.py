r"""The cart-pole sweep over the settings the thesis leaves unstated: can the adaptive step
move on the doubled pole at all?

In Section 5.3 the thesis reports that on the doubled pole the adaptive method (Algorithm
4.1, G(PO)MDP, Bernstein with empirical range, delta = 0.95) learns more slowly than vanilla
PG but steadily. With our settings its step is at most :math:`1/(2c) \approx 8.7\cdot10^{-9}`
and it does not learn. The penalty constant of Theorem 4.2.3,

.. math:: c = \frac{R M_\phi^2 h^2}{\sigma^2}\Big(\frac{|\mathcal A|}{\sqrt{2\pi}\,\sigma} + \frac{\gamma h}{2}\Big),
   \qquad h = \frac{1}{1-\gamma}\ \text{(as printed)},

depends on settings the thesis does not state. This module

- computes c and the largest safe step :math:`1/(2c)` over the whole grid of plausible
  settings analytically (:func:`penalty_grid`, free);
- runs the short learning runs of ``cartpole-sweep`` and the baseline searches
  ``cartpole-baseline-*`` (defined in :mod:`safepg.thesis.experiments`, stored like every other
  experiment, :func:`run_sweep`);
- summarises them per setting (:func:`sweep_table`): whether the adaptive method learns,
  Upsilon-bar and improvement ratio of both methods, the baseline's iteration count, and
  whether the thesis's qualitative claim holds.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np

from safepg import portable
from safepg.constants import TaskConstants
from safepg.envs.cartpole import CartPole
from safepg.meta import ALPHA_STAR_FACTOR, penalty_constant
from safepg.record import LearningRecord
from safepg.thesis.experiment_store import load_experiment, run_experiment
from safepg.thesis.experiments import get_experiment, make_env
from safepg.thesis.sweep_settings import CARTPOLE_SWEEP, SWEEP_BUDGET, SWEEP_SEEDS

#: The thesis's printed numbers the sweep is held against (Section 5.3, Table 5.4).
THESIS = {"baseline_iterations": 72, "adaptive_upsilon_bar": 193.12, "adaptive_improvement_ratio": 0.5301,
          "vanilla_upsilon_bar": 192.86, "vanilla_improvement_ratio": 0.4476}
#: The vanilla method's fixed step, the yardstick of "the adaptive step can move".
VANILLA_ALPHA = 0.01
#: A setting's adaptive step "can move" when its largest safe step 1/(2c) is at least this
#: share of the vanilla step: 1/1000 of alpha = 0.01, i.e. c <= 5 * 10^4. Below it, 100
#: iterations at the largest safe step move theta less than a tenth of one vanilla step.
CAN_MOVE_SHARE = 1e-3
#: The penalty constant below which the step can move: 1 / (2 CAN_MOVE_SHARE VANILLA_ALPHA) = 5 * 10^4.
CAN_MOVE_C = 1.0 / (2.0 * CAN_MOVE_SHARE * VANILLA_ALPHA)
#: A run "learns" when its average return over the last quarter of its trajectories exceeds
#: that over the first tenth by more than this many steps (a batch of 4000 episodes of about
#: 185 steps has a standard error near 0.5 steps).
LEARNS_MARGIN = 2.0

#: The analytic grid. M_phi: 10 (our measured bound on raw states), 2.4 (the largest
#: position threshold, i.e. ignoring the unbounded velocities), 1 (normalised features).
#: |A|: 20 (the force interval), 10 (A-bar), 2 (actions normalised to [-1, 1]).
GRID_GAMMAS = (0.9, 0.95, 0.99, 0.995, 0.999, 1.0)
GRID_HORIZON_TERMS = ("effective", "truncated", "horizon")
GRID_M_PHI = (10.0, 2.4, 1.0)
GRID_VOLUMES = (20.0, 10.0, 2.0)
GRID_R = (1.0, 200.0)


def max_safe_step(c: float) -> float:
    """The largest step Corollary 4.2.8 ever allows, 1/(2c) (eps = 0)."""
    return 1.0 / (2.0 * c)


def penalty_grid(gammas: tuple[float, ...] = GRID_GAMMAS, horizon_terms: tuple[str, ...] = GRID_HORIZON_TERMS,
                 m_phis: tuple[float, ...] = GRID_M_PHI, volumes: tuple[float, ...] = GRID_VOLUMES,
                 rewards: tuple[float, ...] = GRID_R, sigma: float = 1.0, horizon: int = 200) -> list[dict[str, Any]]:
    r"""Penalty constant c and largest safe step over a grid of settings (no simulation).

    One row per (gamma, horizon term, M_phi, |A|, R); gamma = 1 only with a finite horizon
    term. ``step_at_n_star`` is the step at the optimal batch size of Theorem 4.3.2
    (:math:`\alpha^* = (13 - 3\sqrt{17})/(4c)`), what the algorithm takes in practice;
    ``can_move``: the largest safe step is at least :data:`CAN_MOVE_SHARE` of the vanilla
    step :data:`VANILLA_ALPHA`.
    """
    rows = []
    for gamma, term, m_phi, vol, r in itertools.product(gammas, horizon_terms, m_phis, volumes, rewards):
        if gamma == 1 and term == "effective":
            continue
        constants = TaskConstants(R=r, M_phi=m_phi, action_volume=vol, A_bar=10.0, gamma=gamma, H=horizon,
                                  sigma=sigma, horizon_term=term)
        c = penalty_constant(constants)
        # "A_volume" is the column the book's table of the grid (book/cartpole.ipynb) reads.
        rows.append({"gamma": gamma, "horizon_term": term, "h": constants.horizon_factor, "M_phi": m_phi,
                     "A_volume": vol, "R": r, "c": c, "max_step": max_safe_step(c),
                     "step_at_n_star": ALPHA_STAR_FACTOR / c,
                     "can_move": max_safe_step(c) >= CAN_MOVE_SHARE * VANILLA_ALPHA})
    return rows


def smallest_c_by_gamma(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """For each gamma, the grid row with the smallest c (the most favourable constants)."""
    out = []
    for gamma in sorted({r["gamma"] for r in rows}):
        out.append(min((r for r in rows if r["gamma"] == gamma), key=lambda r: r["c"]))
    return out


# ------------------------------------------------------------------ learning runs
def baseline_experiments() -> list[str]:
    """Names of the baseline searches of the sweep (the default's ``cartpole-baseline`` first)."""
    names = []
    for st in CARTPOLE_SWEEP.values():
        if st.baseline_experiment not in names:
            names.append(st.baseline_experiment)
    return names


def run_sweep(root: Path | None = None, jobs: int = -1, progress: bool = False) -> dict[str, Any]:
    """Run (or load) every run of the sweep: the baseline searches, then ``cartpole-sweep``.

    Each is an ordinary experiment of :mod:`safepg.thesis.experiments`, stored under ``root``
    (``python -m safepg run cartpole-sweep`` does the same from the shell). The baselines
    run with :data:`~safepg.thesis.experiments.SWEEP_SEEDS` seeds. Returns
    ``{"baselines": {experiment: records}, "sweep": records by config}``.
    """
    baselines = {}
    for name in baseline_experiments():
        exp = get_experiment(name)
        cfg = exp.configs[0]
        baselines[name] = run_experiment(exp, seeds=SWEEP_SEEDS, jobs=jobs, root=root, progress=progress)[cfg.name]
    sweep = run_experiment("cartpole-sweep", jobs=jobs, root=root, progress=progress)
    return {"baselines": baselines, "sweep": sweep}


def load_sweep(root: Path | None = None) -> dict[str, Any]:
    """The stored runs of the sweep, as :func:`run_sweep` returns them (missing runs left out)."""
    baselines = {}
    for name in baseline_experiments():
        exp = get_experiment(name)
        recs = load_experiment(exp, root)[exp.configs[0].name]
        baselines[name] = recs[:SWEEP_SEEDS]
    return {"baselines": baselines, "sweep": load_experiment("cartpole-sweep", root)}


def _average(rec: LearningRecord, sel: np.ndarray) -> float:
    w = rec.batch_size[sel]
    return portable.fsum_mean(rec.J_hat[sel], weights=w)  # exact sums, not BLAS (safepg.portable)


def late_minus_early(rec: LearningRecord, late: float = 0.25, early: float = 0.1) -> float:
    """Average return over the last ``late`` share of the run's trajectories minus that over the
    first ``early`` share (at least the first batch). The adaptive method's first batch has only
    N_min = 100 trajectories, too noisy to compare with on its own."""
    ends = np.cumsum(rec.batch_size)
    starts = ends - rec.batch_size
    first = starts < early * ends[-1]
    return _average(rec, ends > (1 - late) * ends[-1]) - _average(rec, first)


def drawdown(rec: LearningRecord) -> float:
    """Largest fall of the batch-average return below its best value so far (steps): how
    far the method oscillates back down after it has improved."""
    best = np.maximum.accumulate(rec.J_hat)
    return float(np.max(best - rec.J_hat))


def relative_move(rec: LearningRecord, task: CartPole) -> float:
    """Largest change of a component of theta over the run, in raw-state units, relative to the
    largest component of the starting theta (feature scales undone)."""
    scale = np.ones(4) if task.feature_scale is None else np.asarray(task.feature_scale)
    start, end = rec.theta[0] / scale, rec.theta_final / scale
    return float(np.max(np.abs(end - start)) / max(np.max(np.abs(start)), 1e-12))


def _mean(values: list[float]) -> float | None:
    return float(np.mean(values)) if values else None


def _method_summary(recs: list[LearningRecord], task: CartPole) -> dict[str, Any]:
    return {"upsilon_bar": _mean([r.upsilon_bar() for r in recs]),
            "improvement_ratio": _mean([r.improvement_ratio("J_hat") for r in recs]),
            "gain": _mean([late_minus_early(r) for r in recs]),
            "drawdown": _mean([drawdown(r) for r in recs]),
            "move": _mean([relative_move(r, task) for r in recs]),
            "start": _mean([float(r.J_hat[0]) for r in recs]),
            "seeds": len(recs)}


def sweep_table(runs: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per sweep setting, from :func:`run_sweep`'s (or :func:`load_sweep`'s) runs.

    Columns: ``c`` and ``max_step`` of the adaptive run's task; ``baseline_iterations``
    (mean over seeds; ``baseline_reached``: seeds that reached 195); for each method
    (``adaptive_*``, ``vanilla_*``) Upsilon-bar, improvement ratio, ``gain`` (late minus
    early average return, :func:`late_minus_early`), ``drawdown`` and ``move`` (relative change of theta);
    ``adaptive_learns`` (gain > :data:`LEARNS_MARGIN`); ``claim_holds``: the thesis's
    qualitative claim, i.e. the adaptive method learns, improves more steadily than vanilla
    (higher improvement ratio) and keeps at least vanilla's average performance.
    """
    exp = get_experiment("cartpole-sweep")
    names = {c.name for c in exp.configs}
    rows = []
    for st in CARTPOLE_SWEEP.values():
        base = runs["baselines"].get(st.baseline_experiment, [])
        row: dict[str, Any] = {"key": st.key, "label": st.label, "plausible": st.plausible,
                               "baseline_iterations": _mean([r.iterations for r in base]),
                               "baseline_reached": sum(r.reached_target for r in base),
                               "baseline_seeds": len(base)}
        task = make_env(st.env(doubled=True))
        c = penalty_constant(TaskConstants.from_task(task, 1.0))
        row.update(c=c, max_step=max_safe_step(c))
        if st.doubled:
            vkey = f"{st.key}:N=4000" if f"{st.key}:N=4000" in names else "thesis:N=4000"
            for method, name in (("adaptive", f"{st.key}:adaptive"), ("vanilla", vkey)):
                summary = _method_summary(runs["sweep"].get(name, []), exp.config(name).make_task())
                row.update({f"{method}_{k}": v for k, v in summary.items()})
            ok = row["adaptive_seeds"] and row["vanilla_seeds"]
            row["adaptive_learns"] = bool(ok and row["adaptive_gain"] > LEARNS_MARGIN)
            row["claim_holds"] = bool(ok and row["adaptive_learns"]
                                      and row["adaptive_improvement_ratio"] > row["vanilla_improvement_ratio"]
                                      and row["adaptive_upsilon_bar"] >= row["vanilla_upsilon_bar"])
        rows.append(row)
    return rows


def sweep_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The answers the chapter states, computed from :func:`sweep_table`'s rows."""
    doubled = [r for r in rows if "adaptive_learns" in r]
    plausible = [r for r in doubled if r["plausible"]]
    return {
        "learns": [r["key"] for r in doubled if r["adaptive_learns"]],
        "learns_plausible": [r["key"] for r in plausible if r["adaptive_learns"]],
        "claim_holds": [r["key"] for r in doubled if r["claim_holds"]],
        "claim_holds_plausible": [r["key"] for r in plausible if r["claim_holds"]],
        "smallest_c_plausible": min(r["c"] for r in plausible) if plausible else math.nan,
        "budget": SWEEP_BUDGET, "seeds": SWEEP_SEEDS,
    }


__all__ = ["CAN_MOVE_C", "CAN_MOVE_SHARE", "LEARNS_MARGIN", "THESIS", "VANILLA_ALPHA", "baseline_experiments",
           "drawdown", "late_minus_early",
           "load_sweep", "max_safe_step", "penalty_grid", "relative_move", "run_sweep", "smallest_c_by_gamma",
           "sweep_summary", "sweep_table"]
