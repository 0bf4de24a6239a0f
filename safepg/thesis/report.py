"""Our numbers beside the thesis's: one JSON-ready summary per configuration of an experiment.

:func:`report` reads an experiment's stored runs (:mod:`safepg.thesis.experiment_store`) and
counts them by the experiment's ``rules``; ``python -m safepg report NAME --json`` prints it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from safepg.definition import to_dict
from safepg.options import FixedStep, Vanilla
from safepg.record import CHECKPOINTS, LearningRecord
from safepg.runner import RunConfig
from safepg.stats import seed_summary95
from safepg.thesis import authors
from safepg.thesis.authors import budget_average, strict_improvement_ratio
from safepg.thesis.experiment_store import load_experiment
from safepg.thesis.experiments import Experiment, get_experiment


def _summary(exp: Experiment, cfg: RunConfig, rec: LearningRecord) -> tuple[float, float]:
    """(Upsilon-bar, improvement ratio) of one run, counted by the experiment's ``rules``."""
    if exp.rules == "ours":
        return rec.upsilon_bar(), rec.improvement_ratio(exp.performance)
    if exp.performance == "J_hat":  # plot_cartpole.m: the batches that end before the budget
        window = budget_average(rec.batch_size, rec.J_hat, cfg.budget)
        return window["upsilon_bar"], window["improvement_ratio"]
    return rec.upsilon_bar(), strict_improvement_ratio(rec.J[:-1])  # J at the batch starts


def _authors_output(exp: Experiment, cfg: RunConfig) -> dict[str, Any] | None:
    """The authors' own output for ``cfg`` of an authors-settings experiment (their files, recomputed)."""
    if exp.rules != "authors":
        return None
    base = authors.cartpole_runs()["baseline"]
    m = cfg.method
    cell = ((cfg.sigma, m.batch_size, m.step.alpha) if isinstance(m, Vanilla) and isinstance(m.step, FixedStep)
            else None)
    out = {"table-5.1-authors": lambda: None if cell is None else authors.table_5_1().get(cell),
           "table-5.3-authors": lambda: authors.table_5_3().get(cfg.name),
           "cartpole-baseline-authors": lambda: {"iterations": base.iterations, "J_hat_final": base["J_hat"][-1]},
           "table-5.4-authors": lambda: authors.table_5_4()["adaptive" if cfg.algorithm == "adaptive" else "fixed"]}
    got = out.get(exp.name.removesuffix("-theta-star"), lambda: None)()
    return None if got is None else {k: np.asarray(v).tolist() for k, v in got.items()}


def report(exp: Experiment | str, records: dict[str, list[LearningRecord]] | None = None,
           root: Path | None = None) -> dict[str, Any]:
    """One JSON-ready object per configuration, with the thesis's printed values beside ours (and,
    for the authors' settings, ``authors_output``: their own raw output recomputed)."""
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    records = load_experiment(exp, root) if records is None else records
    rows = []
    closed_form = exp.performance == "J"
    for c in exp.configs:
        recs = records.get(c.name, [])
        j_at: dict[str, float] = {}
        for T in CHECKPOINTS if closed_form else ():
            vals = [r.J_at((T,)).get(str(T)) for r in recs]
            known = [v for v in vals if v is not None]
            if vals and len(known) == len(vals):
                j_at[str(T)] = float(np.mean(known))
        # Components of theta that any seed's run changed (the thesis's remarks on which
        # entries the coordinate step leaves alone).
        updated = sorted({int(i) for r in recs for i in np.flatnonzero(r.theta[-1] != r.theta[0])})
        upsilon, ratio = ([float(_summary(exp, c, r)[i]) for r in recs] for i in (0, 1))
        rows.append({
            "name": c.name, "method": to_dict(c.method), "sigma": c.sigma, "budget": c.budget, "seeds": len(recs),
            # Each seed's value beside the summary: the scorecard's tests take the runs themselves.
            "upsilon_bar": {**seed_summary95(upsilon), "values": upsilon},
            "improvement_ratio": {**seed_summary95(ratio), "values": ratio},
            "updates": [int(r.iterations) - 1 for r in recs],
            "theta_moved": max((float(np.max(np.abs(r.theta_final - r.theta[0]))) for r in recs), default=None),
            "improvement_ratio_on": exp.performance,
            "rules": exp.rules,
            "J_at": j_at,
            "J_final": float(np.mean([r.J[-1] for r in recs])) if recs and closed_form else None,
            "J_hat_final": float(np.mean([r.J_hat[-1] for r in recs])) if recs else None,
            "iterations": float(np.mean([r.iterations for r in recs])) if recs else None,
            "theta_final": np.mean([r.theta_final for r in recs], axis=0).tolist() if recs else None,
            "components_updated": updated,
            "diverged": sum(r.diverged for r in recs),
            "thesis": exp.thesis.get(c.name),
            "authors_output": _authors_output(exp, c),
        })
    return {"experiment": exp.name, "configs": rows}
