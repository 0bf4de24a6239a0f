"""Where an experiment's runs are stored, and running what is missing.

Seed k of config ``c`` of experiment ``e`` is ``<results>/<e>/<c>/seed-<k>.npz``; the
results folder is ``$SAFEPG_RESULTS`` or ``results/`` under the current directory.
:func:`run_experiment` runs what is missing through :func:`safepg.runner.run_configs`,
after the experiments it warm-starts from.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from safepg.learning import LearningRecord
from safepg.runner import load_configs, run_configs, stored_run
from safepg.store import OnDamaged, results_dir
from safepg.thesis.experiments import Experiment, get_experiment, scaled


def experiment_folder(exp: Experiment | str, root: Path | None = None) -> Path:
    """The folder of ``exp``'s runs in the store."""
    return (root or results_dir()) / (exp if isinstance(exp, str) else exp.name)


def run_experiment(exp: Experiment | str, seeds: int | None = None, budget: int | None = None, jobs: int = -1,
                   root: Path | None = None, progress: bool = True) -> dict[str, list[LearningRecord]]:
    """Run every missing (config, seed) of ``exp`` and return all records by config name.

    Finished runs are loaded, never recomputed (:func:`safepg.runner.run_configs`, which
    also says how to run on a Dask cluster); a damaged run file is set aside with a
    warning and its run computed again. A warm-started experiment first runs the
    experiment it starts from, with the same seeds, and hands each seed's final parameters
    to the runner. ``jobs`` follows joblib: a positive count, or -1 for every core (-2 all
    but one, ...).
    """
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    exp = scaled(exp, seeds, budget)
    # Starting policies first (in parallel), so no two workers compute the same one.
    starts: dict[str, list[np.ndarray]] = {}
    for dep in sorted({c.warm_start for c in exp.configs if c.warm_start is not None}):
        dep_exp = scaled(get_experiment(dep), seeds=exp.seeds)
        run_experiment(dep_exp, jobs=jobs, root=root, progress=progress)
        # Seed by seed from its own file, so a missing seed can never shift the others.
        dep_folder, dep_cfg = experiment_folder(dep_exp, root), dep_exp.single_config()
        dep_recs = [stored_run(dep_folder, dep_cfg, seed) for seed in range(exp.seeds)]
        missing = [seed for seed, r in enumerate(dep_recs) if r is None]
        if missing:
            raise RuntimeError(f"warm_start {dep!r}: seeds {missing} are not stored; rerun to compute them")
        starts[dep] = [r.theta_final for r in dep_recs if r is not None]
    by_config = {c.name: starts[c.warm_start] for c in exp.configs if c.warm_start is not None}
    return run_configs(exp.configs, exp.seeds, experiment_folder(exp, root), starts=by_config, jobs=jobs,
                       progress=progress, desc=exp.name)


def load_experiment(exp: Experiment | str, root: Path | None = None,
                    on_damaged: OnDamaged = "warn") -> dict[str, list[LearningRecord]]:
    """Finished runs of ``exp`` by config name (missing seeds are left out).

    Damaged run files are left out with a warning, or with ``on_damaged="raise"`` named
    all at once in a :class:`~safepg.store.DamagedRunsError`; :func:`run_experiment`
    sets them aside and computes their runs again.
    """
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    return load_configs(exp.configs, exp.seeds, experiment_folder(exp, root), on_damaged)
