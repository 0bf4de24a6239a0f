"""Where an experiment's runs are stored, and running what is missing.

Seed k of config ``c`` of experiment ``e`` is ``<results>/<e>/<c>/<key>/seed-<k>.npz``
(:func:`safepg.runner.run_path`, ``<key>`` the config's :meth:`~safepg.runner.RunConfig.key`); the
results folder is ``$SAFEPG_RESULTS`` or ``results/`` under the current directory.
:func:`run_experiment` runs what is missing through :func:`safepg.runner.run_configs`,
after the experiments it warm-starts from; with ``timing=True`` (``run-book``'s campaign) each folder
that runs were computed in gets a line of how long they took (:func:`safepg.thesis.campaign.record_timing`),
otherwise nothing but the runs is written.

A results folder holds one campaign (:class:`Campaign`, in its ``campaign.json``): the index of its
first seed (another draw of the same experiments starts elsewhere, so that its seeds are disjoint)
and, by config key, the seeds a configuration runs beyond its experiment's count (the scorecard's
seed rule, :mod:`safepg.thesis.seed_rule`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from safepg.record import LearningRecord
from safepg.runner import OnComputed, RunGroup, load_configs, run_configs, run_groups, stored_run
from safepg.store import OnDamaged, results_dir
from safepg.thesis.campaign import record_timing
from safepg.thesis.experiments import Experiment, get_experiment, scaled


def experiment_folder(exp: Experiment | str, root: Path | None = None) -> Path:
    """The folder of ``exp``'s runs in the store."""
    return (root or results_dir()) / (exp if isinstance(exp, str) else exp.name)


#: The file of a results folder that holds its :class:`Campaign`.
CAMPAIGN_FILE = "campaign.json"


@dataclass(frozen=True)
class Campaign:
    """The seeds of one results folder's runs.

    Attributes
    ----------
    first_seed : int
        The index of every configuration's first seed (0; another draw: far from 0).
    seeds : mapping of str to int
        By config key (:meth:`safepg.runner.RunConfig.key`), how many seeds that configuration runs when
        that is more than its experiment's count.

    Raises
    ------
    ValueError
        If ``first_seed`` is negative or a count is below 1.
    """

    first_seed: int = 0
    seeds: Mapping[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if int(self.first_seed) != self.first_seed or self.first_seed < 0:
            raise ValueError(f"first_seed must be a non-negative integer, got {self.first_seed!r}")
        bad = {k: v for k, v in self.seeds.items() if int(v) != v or v < 1}
        if bad:
            raise ValueError(f"seeds must be positive integers, got {bad}")

    def counts(self, exp: Experiment) -> dict[str, int]:
        """Each config of ``exp`` by name: its experiment's seeds, or more where the campaign says so."""
        return {c.name: max(exp.seeds, int(self.seeds.get(c.key(), 0))) for c in exp.configs}


def read_campaign(root: Path | None = None) -> Campaign:
    """The :class:`Campaign` of a results folder (the default one where it has none)."""
    path = (root or results_dir()) / CAMPAIGN_FILE
    if not path.exists():
        return Campaign()
    data = json.loads(path.read_text(encoding="utf-8"))
    return Campaign(int(data.get("first_seed", 0)), {str(k): int(v) for k, v in data.get("seeds", {}).items()})


def write_campaign(campaign: Campaign, root: Path | None = None) -> Path:
    """Write ``campaign`` as the results folder's :data:`CAMPAIGN_FILE` (atomically)."""
    folder = root or results_dir()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / CAMPAIGN_FILE
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps({"first_seed": campaign.first_seed, "seeds": dict(sorted(campaign.seeds.items()))},
                              indent=1) + "\n", encoding="utf-8")
    tmp.replace(path)
    return path


def _counts(exp: Experiment, root: Path | None, seeds: int | None) -> dict[str, int]:
    """Each config's seeds: ``seeds`` for all when given, else the campaign's."""
    return {c.name: seeds for c in exp.configs} if seeds is not None else read_campaign(root).counts(exp)


def _on_computed(timing: bool) -> OnComputed | None:
    """What the runner is given to report computed runs: the campaign's timing file, or nothing."""
    return record_timing if timing else None


def run_experiment(exp: Experiment | str, seeds: int | None = None, budget: int | None = None, jobs: int = -1,
                   root: Path | None = None, progress: bool = True,
                   timing: bool = False) -> dict[str, list[LearningRecord]]:
    """Run every missing (config, seed) of ``exp`` and return all records by config name.

    Finished runs are loaded, never recomputed (:func:`safepg.runner.run_configs`, which
    also says how to run on a Dask cluster); a damaged run file is set aside with a
    warning and its run computed again. A warm-started experiment first runs the
    experiment it starts from, with the same seeds, and hands each seed's final parameters
    to the runner. ``jobs`` follows joblib: a positive count, or -1 for every core (-2 all
    but one, ...). With ``timing``, the experiment's folder (and that of each experiment it
    starts from) gets a line of ``timing.jsonl`` for the runs computed in it
    (:func:`safepg.thesis.campaign.record_timing`: ``run-book`` asks, for
    :mod:`safepg.thesis.budget`); without, nothing but the runs is written.
    """
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    exp = scaled(exp, seeds, budget)
    counts = _counts(exp, root, seeds)
    # Starting policies first (in parallel), so no two workers compute the same one.
    for dep in _dependencies(exp):
        run_experiment(get_experiment(dep), seeds=_dependency_seeds(exp, dep, counts), jobs=jobs, root=root,
                       progress=progress, timing=timing)
    return run_configs(exp.configs, counts, experiment_folder(exp, root), starts=_starts(exp, root, counts),
                       jobs=jobs, progress=progress, desc=exp.name, first_seed=read_campaign(root).first_seed,
                       on_computed=_on_computed(timing))


def run_experiments(exps: Sequence[Experiment | str], jobs: int = -1, root: Path | None = None,
                    progress: bool = True, timing: bool = False) -> dict[str, dict[str, list[LearningRecord]]]:
    """:func:`run_experiment` for several experiments, their missing runs dispatched together
    (:func:`safepg.runner.run_groups`: no worker waits at the end of one experiment while
    another has runs left). An experiment runs in a later dispatch than the ones it
    warm-starts from; those not in ``exps`` are run first (:func:`run_experiment`). Returns
    each experiment's records by config name, by experiment name. ``timing`` as in
    :func:`run_experiment`: each folder gets its share of a dispatch's wall time.
    """
    pending = [get_experiment(e) if isinstance(e, str) else e for e in exps]
    out: dict[str, dict[str, list[LearningRecord]]] = {}
    while pending:
        names = {e.name for e in pending}
        wave = [e for e in pending if not set(_dependencies(e)) & names]
        counts = {e.name: _counts(e, root, None) for e in wave}
        for e in wave:  # stored by an earlier dispatch (then only read) or not in exps
            for dep in _dependencies(e):
                run_experiment(get_experiment(dep), seeds=_dependency_seeds(e, dep, counts[e.name]), jobs=jobs,
                               root=root, progress=progress, timing=timing)
        first = read_campaign(root).first_seed
        groups = [RunGroup(e.configs, counts[e.name], experiment_folder(e, root), _starts(e, root, counts[e.name]),
                           first) for e in wave]
        desc = wave[0].name if len(wave) == 1 else f"{len(wave)} experiments"
        out.update(zip([e.name for e in wave], run_groups(groups, jobs, progress, desc, _on_computed(timing))))
        pending = [e for e in pending if e not in wave]
    return out


def _dependencies(exp: Experiment) -> list[str]:
    """The experiments ``exp``'s configs warm-start from."""
    return sorted({c.warm_start for c in exp.configs if c.warm_start is not None})


def _dependency_seeds(exp: Experiment, dep: str, counts: Mapping[str, int]) -> int:
    """How many seeds of ``dep`` the configs of ``exp`` that warm-start from it need: the most of them."""
    return max(counts[c.name] for c in exp.configs if c.warm_start == dep)


def _starts(exp: Experiment, root: Path | None, counts: Mapping[str, int]) -> dict[str, list[np.ndarray]]:
    """Each warm-started config's starting parameters, seed by seed: the final parameters of
    the stored runs it starts from (the same seeds)."""
    first = read_campaign(root).first_seed
    out: dict[str, list[np.ndarray]] = {}
    for c in exp.configs:
        if c.warm_start is None:
            continue
        dep_exp = get_experiment(c.warm_start)
        # Seed by seed from its own file, so a missing seed can never shift the others.
        dep_folder, dep_cfg = experiment_folder(dep_exp, root), dep_exp.single_config()
        seeds = range(first, first + counts[c.name])
        dep_recs = [stored_run(dep_folder, dep_cfg, seed) for seed in seeds]
        missing = [seed for seed, r in zip(seeds, dep_recs) if r is None]
        if missing:
            raise RuntimeError(f"warm_start {c.warm_start!r}: seeds {missing} are not stored; rerun to compute them")
        out[c.name] = [r.theta_final for r in dep_recs if r is not None]
    return out


def load_experiment(exp: Experiment | str, root: Path | None = None,
                    on_damaged: OnDamaged = "warn") -> dict[str, list[LearningRecord]]:
    """Finished runs of ``exp`` by config name (missing seeds are left out).

    Damaged run files are left out with a warning, or with ``on_damaged="raise"`` named
    all at once in a :class:`~safepg.store.DamagedRunsError`; :func:`run_experiment`
    sets them aside and computes their runs again.
    """
    exp = get_experiment(exp) if isinstance(exp, str) else exp
    return load_configs(exp.configs, read_campaign(root).counts(exp), experiment_folder(exp, root), on_damaged,
                        read_campaign(root).first_seed)
