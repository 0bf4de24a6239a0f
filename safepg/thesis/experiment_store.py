"""Where an experiment's runs are stored, and running what is missing.

Seed k of config ``c`` of experiment ``e`` is ``<results>/<e>/<c>/seed-<k>.npz``; the
results folder is ``$SAFEPG_RESULTS`` or ``results/`` under the current directory.
:func:`run_experiment` runs what is missing through :func:`safepg.runner.run_configs`,
after the experiments it warm-starts from.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from safepg.learning import LearningRecord
from safepg.runner import RunGroup, load_configs, run_configs, run_groups, stored_run
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
    for dep in _dependencies(exp):
        run_experiment(scaled(get_experiment(dep), seeds=exp.seeds), jobs=jobs, root=root, progress=progress)
    return run_configs(exp.configs, exp.seeds, experiment_folder(exp, root), starts=_starts(exp, root), jobs=jobs,
                       progress=progress, desc=exp.name)


def run_experiments(exps: Sequence[Experiment | str], jobs: int = -1, root: Path | None = None,
                    progress: bool = True) -> dict[str, dict[str, list[LearningRecord]]]:
    """:func:`run_experiment` for several experiments, their missing runs dispatched together
    (:func:`safepg.runner.run_groups`: no worker waits at the end of one experiment while
    another has runs left). An experiment runs in a later dispatch than the ones it
    warm-starts from; those not in ``exps`` are run first (:func:`run_experiment`). Returns
    each experiment's records by config name, by experiment name.
    """
    pending = [get_experiment(e) if isinstance(e, str) else e for e in exps]
    out: dict[str, dict[str, list[LearningRecord]]] = {}
    while pending:
        names = {e.name for e in pending}
        wave = [e for e in pending if not set(_dependencies(e)) & names]
        for e in wave:  # stored by an earlier dispatch (then only read) or not in exps
            for dep in _dependencies(e):
                run_experiment(scaled(get_experiment(dep), seeds=e.seeds), jobs=jobs, root=root, progress=progress)
        groups = [RunGroup(e.configs, e.seeds, experiment_folder(e, root), _starts(e, root)) for e in wave]
        desc = wave[0].name if len(wave) == 1 else f"{len(wave)} experiments"
        out.update(zip([e.name for e in wave], run_groups(groups, jobs, progress, desc)))
        pending = [e for e in pending if e not in wave]
    return out


def _dependencies(exp: Experiment) -> list[str]:
    """The experiments ``exp``'s configs warm-start from."""
    return sorted({c.warm_start for c in exp.configs if c.warm_start is not None})


def _starts(exp: Experiment, root: Path | None) -> dict[str, list[np.ndarray]]:
    """Each warm-started config's starting parameters, seed by seed: the final parameters of
    the stored runs it starts from."""
    starts: dict[str, list[np.ndarray]] = {}
    for dep in _dependencies(exp):
        dep_exp = scaled(get_experiment(dep), seeds=exp.seeds)
        # Seed by seed from its own file, so a missing seed can never shift the others.
        dep_folder, dep_cfg = experiment_folder(dep_exp, root), dep_exp.single_config()
        dep_recs = [stored_run(dep_folder, dep_cfg, seed) for seed in range(exp.seeds)]
        missing = [seed for seed, r in enumerate(dep_recs) if r is None]
        if missing:
            raise RuntimeError(f"warm_start {dep!r}: seeds {missing} are not stored; rerun to compute them")
        starts[dep] = [r.theta_final for r in dep_recs if r is not None]
    return {c.name: starts[c.warm_start] for c in exp.configs if c.warm_start is not None}


def load_experiment(exp: Experiment | str, root: Path | None = None,
                    on_damaged: OnDamaged = "warn") -> dict[str, list[LearningRecord]]:
    """Finished runs of ``exp`` by config name (missing seeds are left out).

    Damaged run files are left out with a warning, or with ``on_damaged="raise"`` named
    all at once in a :class:`~safepg.store.DamagedRunsError`; :func:`run_experiment`
    sets them aside and computes their runs again.
    """
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    return load_configs(exp.configs, exp.seeds, experiment_folder(exp, root), on_damaged)
