r"""Learning runs defined as data, run for several seeds in parallel, kept in the store.

A :class:`RunConfig` is one learning configuration: the task (a name or a factory), the
algorithm and its arguments. Its :meth:`~RunConfig.key` hashes everything that determines
the run's numbers; seed ``k`` draws from a stream derived from that key, so the same
configuration and seed give the same numbers on any machine and in any order.

:func:`run_configs` executes the missing (config, seed) runs of a group of configurations
through joblib (all cores by default; a user with a cluster wraps the call in
``joblib.parallel_config(backend="dask")`` or ``"ray"`` without code changes), shows tqdm
progress, and writes each finished run atomically to ``<folder>/<config>/<key>/seed-<k>.npz``
(:func:`run_path`, :mod:`safepg.store`). An interrupted campaign resumes where it stopped; a
run whose settings or library version changed is computed into its own key's folder, beside
the old runs, which :func:`prune` removes when no configuration asks for them. A damaged run file
(truncated, overwritten) is set aside, named in a warning, and its run computed again
(:mod:`safepg.store`).

Workers only compute: each returns its :class:`~safepg.learning.LearningRecord` to the
calling process, which writes it to the store as it arrives. Workers on other machines
therefore need no shared filesystem. A run that starts where another ended (a *warm
start*) receives its starting parameters as data, one per seed, from the caller.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import KW_ONLY, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from tqdm.auto import tqdm

from safepg.definition import from_dict, run_definition
from safepg.learning import learn
from safepg.options import Adaptive, Method, Vanilla
from safepg.record import LearningRecord, RecordFileError
from safepg.store import DamagedRunsError, OnDamaged, load_stored, remove_stale_temp_files, save_atomic

#: Bump when a change to the library alters the numbers a run produces; stored runs with
#: another version are recomputed. 2: every output computed in a CPU-independent order
#: (safepg.portable): products instead of libm's pow, software log, sine and cosine.
#: 3: the kernels draw their own random numbers from counter-based streams (safepg.streams).
#: 4: the key hashes the run's whole definition (the task's fields, every option), so each run's
#: seed stream (RunConfig.seed) changed.
RESULTS_VERSION = "4"

#: The version whose keys seed the runs, frozen at 4: seed k of a configuration draws from the stream
#: of its definition's key at version 4 (:meth:`RunConfig.seed_key`), whatever RESULTS_VERSION becomes.
#: A version bump therefore recomputes every run from the random numbers it had, and its numbers move
#: only where the library's computation changed. (Up to version 4 a run's key and its seed key were one.)
SEED_VERSION = "4"


def make_env(name: str) -> Any:
    """Environment by name.

    ``lqg1d`` and ``lqg2d`` (:meth:`LQG.thesis_1d <safepg.envs.lqg.LQG.thesis_1d>`,
    :meth:`~safepg.envs.lqg.LQG.thesis_2d`), ``cartpole`` and ``cartpole-doubled`` (1 m
    pole, then 2 m), optionally with settings in brackets,
    ``cartpole-doubled[gamma=0.995]`` (:meth:`CartPole.from_name
    <safepg.envs.cartpole.CartPole.from_name>`). Other tasks are given to a
    :class:`RunConfig` as a factory.
    """
    from safepg.envs.cartpole import CartPole
    from safepg.envs.lqg import LQG

    if name.startswith(("cartpole[", "cartpole-doubled[")):
        return CartPole.from_name(name)
    envs = {"lqg1d": LQG.thesis_1d, "lqg2d": LQG.thesis_2d,
            "cartpole": CartPole.thesis, "cartpole-doubled": CartPole.thesis_doubled}
    if name not in envs:
        raise ValueError(f"env must be one of {sorted(envs)} or given as env_factory, got {name!r}")
    return envs[name]()


@dataclass(frozen=True)
class RunConfig:
    """One learning run's definition: a method and the task it learns, from a start, for a budget.

    ``method`` is an :class:`~safepg.options.Adaptive` (Algorithm 4.1,
    :func:`~safepg.learning.adaptive_pg`) or a :class:`~safepg.options.Vanilla` (fixed batch
    size, :func:`~safepg.learning.vanilla_pg`) with all its options. ``task`` is a task
    (:class:`~safepg.envs.lqg.LQG`, :class:`~safepg.envs.cartpole.CartPole`,
    :class:`~safepg.envs.gym_task.GymTask`, or any frozen dataclass task) or the name of one
    of :func:`make_env`'s. ``stop_on_divergence`` ends a run whose gradient estimate is not
    finite and records it (``diverged``), instead of raising: a stored run is a result.
    ``warm_start`` names the run whose final parameters, seed by seed, start this one, and
    ``warm_start_key`` is that run's :meth:`seed_key`, so that a changed starting run changes
    this run's key too. ``name`` only labels the run in its group's folder.

    :meth:`definition` writes all of it as one canonical dictionary (:mod:`safepg.definition`),
    :meth:`from_definition` reads it back, :meth:`key` hashes it with :data:`RESULTS_VERSION`
    (where the store keeps the run) and :meth:`seed_key` with :data:`SEED_VERSION` (the run's
    random numbers).
    """

    name: str
    _: KW_ONLY
    method: Method = field(default_factory=Adaptive)
    task: Any = "lqg1d"
    theta0: tuple[float, ...] = (0.0,)
    sigma: float = 1.0
    budget: int = 30_000_000
    stop_on_divergence: bool = True
    warm_start: str | None = None
    warm_start_key: str | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.method, Adaptive | Vanilla):
            raise TypeError(f"method must be an Adaptive or a Vanilla, got {self.method!r}")
        if isinstance(self.task, str):
            make_env(self.task)  # an unknown name fails here, not in a worker
        if isinstance(self.budget, bool) or not isinstance(self.budget, int | float | np.integer | np.floating) \
                or not float(self.budget).is_integer() or self.budget < 1:
            raise ValueError(f"budget must be a whole number of trajectories >= 1, got {self.budget!r}")
        object.__setattr__(self, "budget", int(self.budget))
        object.__setattr__(self, "theta0", tuple(float(t) for t in np.ravel(self.theta0)))

    @property
    def algorithm(self) -> Literal["adaptive", "vanilla"]:
        """``"adaptive"`` or ``"vanilla"``: which loop runs the method."""
        return "adaptive" if isinstance(self.method, Adaptive) else "vanilla"

    def make_task(self) -> Any:
        """The task this configuration learns on."""
        return make_env(self.task) if isinstance(self.task, str) else self.task

    def definition(self, exact: bool = True) -> dict[str, Any]:
        """Everything that decides the run's numbers, as canonical data (:func:`safepg.definition.to_dict`).

        ``{"task", "method", "theta0", "sigma", "budget", "stop_on_divergence", "warm_start"}``:
        the task and the method with every field, and for a warm start the key of the run it
        starts from (else None).

        Raises
        ------
        safepg.definition.UnnamedError
            With ``exact``, a task or function that has no exact definition (a lambda feature map).
        ValueError
            ``warm_start`` without ``warm_start_key``.
        """
        if self.warm_start is not None and self.warm_start_key is None:
            raise ValueError(f"warm_start_key must be given with warm_start={self.warm_start!r} "
                             f"(config {self.name!r}): the key of the run it starts from")
        return run_definition(self.make_task(), self.method, self.theta0, self.sigma, self.budget,
                              self.stop_on_divergence, self.warm_start_key, exact)

    @classmethod
    def from_definition(cls, name: str, definition: Mapping[str, Any], warm_start: str | None = None) -> RunConfig:
        """The configuration :meth:`definition` wrote (``warm_start``: the name of the run it starts from)."""
        d = dict(definition)
        return cls(name, method=from_dict(d["method"]), task=from_dict(d["task"]), theta0=tuple(d["theta0"] or (0.0,)),
                   sigma=d["sigma"], budget=d["budget"], stop_on_divergence=d["stop_on_divergence"],
                   warm_start=warm_start, warm_start_key=d["warm_start"])

    def key(self) -> str:
        """Hash of the :meth:`definition` (not of the name) and of :data:`RESULTS_VERSION`: the run's
        place in the store, which a change of the library's numbers moves."""
        return _definition_hash(self.definition(), RESULTS_VERSION)

    def seed_key(self) -> str:
        """Hash of the :meth:`definition` and of :data:`SEED_VERSION`: what seeds the run's streams
        (:meth:`seed`), the same across versions of the results."""
        return _definition_hash(self.definition(), SEED_VERSION)

    def seed(self, index: int) -> np.random.SeedSequence:
        """Independent stream for seed ``index`` of this configuration, from its :meth:`seed_key`."""
        return np.random.SeedSequence([index, int(self.seed_key(), 16) % 2**63])

    def run(self, seed: int, progress: bool = False, theta0: np.ndarray | None = None) -> LearningRecord:
        """Run seed ``seed``.

        A warm-started configuration starts from ``theta0``, the final parameters of that
        seed of the run it names; any other starts from its own ``theta0`` field.
        """
        task = self.make_task()
        if self.warm_start is not None:
            if theta0 is None:
                raise ValueError(f"theta0 must be given for the warm-started config {self.name!r}: "
                                 f"the final theta of seed {seed} of {self.warm_start!r}")
            theta0 = np.asarray(theta0, dtype=float)
        elif theta0 is not None:
            raise ValueError(f"theta0 is only for warm-started configs, {self.name!r} starts from {self.theta0}")
        else:
            theta0 = np.asarray(self.theta0, dtype=float)
        rec = learn(task, self.method, theta0, self.sigma, budget=self.budget,
                    rng=np.random.default_rng(self.seed(seed)), progress=progress,
                    stop_on_divergence=self.stop_on_divergence)
        rec.config.update(self.definition(exact=False))  # a warm start's theta0 is its start run's key
        return rec


def _definition_hash(definition: dict[str, Any], version: str) -> str:
    blob = json.dumps([definition, version], sort_keys=True, allow_nan=False)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def run_path(folder: str | os.PathLike[str], cfg: RunConfig, seed: int) -> Path:
    """Where seed ``seed`` of ``cfg`` is stored in a group's folder: ``folder/<name>/<key>/seed-<seed>.npz``.

    The definition's :meth:`~RunConfig.key` is part of the path, so a run of a changed
    definition is stored beside the runs of the old one, never over them (:func:`prune` removes
    the runs no configuration asks for any longer). Folders written before the key was part of
    the path hold ``folder/<name>/seed-<seed>.npz`` (:func:`legacy_run_path`): such files are
    still read when their key matches, and never written.
    """
    return Path(folder) / cfg.name / cfg.key() / f"seed-{seed}.npz"


def legacy_run_path(folder: str | os.PathLike[str], cfg: RunConfig, seed: int) -> Path:
    """Where seed ``seed`` of ``cfg`` was stored before the key was part of the path (read, never written)."""
    return Path(folder) / cfg.name / f"seed-{seed}.npz"


def stored_run(folder: str | os.PathLike[str], cfg: RunConfig, seed: int,
               on_damaged: OnDamaged = "warn") -> LearningRecord | None:
    """Seed ``seed`` of ``cfg`` from the store, or ``None`` if it is not there (or was made otherwise).

    Looks at :func:`run_path`, then at :func:`legacy_run_path` (a folder written before the key
    was part of the path), where only a run of this very definition is accepted. A damaged file
    is handled as ``on_damaged`` says (:data:`safepg.store.OnDamaged`).
    """
    path = run_path(folder, cfg, seed)
    key = path.parent.name  # the definition's hash, computed once
    rec = load_stored(path, key, on_damaged)
    if rec is None and not path.exists():
        rec = load_stored(legacy_run_path(folder, cfg, seed), key, on_damaged)
    return rec


def is_stored(folder: str | os.PathLike[str], cfg: RunConfig, seed: int) -> bool:
    """Whether a file for seed ``seed`` of ``cfg`` is in the store (not read: it may still be damaged)."""
    return run_path(folder, cfg, seed).exists() or legacy_run_path(folder, cfg, seed).exists()


def store_run(rec: LearningRecord, folder: str | os.PathLike[str], cfg: RunConfig, seed: int) -> None:
    """Stamp ``rec`` with the key :func:`stored_run` checks and save it (in the calling process,
    so the stamp is this process's key whatever the worker's copy of the definitions)."""
    rec.config["run_key"] = cfg.key()
    rec.config["config_name"] = cfg.name
    rec.config["seed"] = seed
    save_atomic(rec, run_path(folder, cfg, seed))


def check_names(configs: Sequence[RunConfig]) -> None:
    """Refuse two configurations of one name but different definitions (one folder, one name, one run).

    Raises
    ------
    ValueError
        Naming the name and both keys.
    """
    seen: dict[str, str] = {}
    for c in configs:
        key = c.key()
        if seen.setdefault(c.name, key) != key:
            raise ValueError(f"two configs are named {c.name!r} with different definitions (keys {seen[c.name]} "
                             f"and {key}): give each its own name")


def _compute(cfg: RunConfig, seed: int, theta0: np.ndarray | None, single_thread: bool) -> LearningRecord:
    """Run seed ``seed`` of ``cfg`` on a worker and return the record (the caller stores it)."""
    if single_thread:  # joblib already uses every core; numba threads would oversubscribe
        import numba

        numba.set_num_threads(1)
    return cfg.run(seed, theta0=theta0)


def _compute_task(i: int, cfg: RunConfig, seed: int, theta0: np.ndarray | None,
                  single_thread: bool) -> tuple[int, LearningRecord, float]:
    """:func:`_compute` tagged with the task's index (results arrive in any order), and the
    seconds the run took on its worker."""
    started = time.perf_counter()
    rec = _compute(cfg, seed, theta0, single_thread)
    return i, rec, time.perf_counter() - started


#: Seeds per configuration: one count for all, or a count by config name.
Seeds = int | Mapping[str, int]


def seeds_of(seeds: Seeds, name: str) -> int:
    """How many seeds config ``name`` runs under ``seeds`` (one count for all, or by config name).

    Raises
    ------
    KeyError
        If ``seeds`` is a mapping without ``name``.
    """
    return int(seeds) if isinstance(seeds, int | np.integer) else int(seeds[name])


def load_configs(configs: Sequence[RunConfig], seeds: Seeds, folder: str | os.PathLike[str],
                 on_damaged: OnDamaged = "warn", first_seed: int = 0) -> dict[str, list[LearningRecord]]:
    """Finished runs of ``configs`` by config name, n seeds each from ``first_seed`` on (n its count in
    ``seeds``); missing seeds are left out.

    Damaged files are left out with a warning; with ``on_damaged="raise"``, every file is
    read first and one :class:`~safepg.store.DamagedRunsError` names all the damaged ones.
    """
    check_names(configs)
    out: dict[str, list[LearningRecord]] = {}
    damaged = []
    for c in configs:
        recs = []
        for seed in range(first_seed, first_seed + seeds_of(seeds, c.name)):
            try:
                recs.append(stored_run(folder, c, seed, on_damaged))
            except DamagedRunsError as err:
                damaged.extend(err.damaged)
        out[c.name] = [r for r in recs if r is not None]
    if damaged:
        raise DamagedRunsError(damaged)
    return out


_RUN_FILE = re.compile(r"^seed-(\d+)\.npz$")
_KEY_DIR = re.compile(r"^[0-9a-f]{16}$")


def run_files(name_dir: Path) -> list[tuple[str | None, Path]]:
    """Each run file stored under one configuration name's folder, with the key its folder names.

    ``(key, <name_dir>/<key>/seed-<k>.npz)`` in the layout :func:`run_path` writes, and
    ``(None, <name_dir>/seed-<k>.npz)`` in the old one (:func:`legacy_run_path`), whose key is
    in the file. Only run files: damaged files set aside and temporary files are not listed.
    """
    files: list[tuple[str | None, Path]] = []
    for path in sorted(name_dir.iterdir()):
        if path.is_dir() and _KEY_DIR.match(path.name):
            files += [(path.name, p) for p in sorted(path.iterdir()) if _RUN_FILE.match(p.name)]
        elif path.is_file() and _RUN_FILE.match(path.name):
            files.append((None, path))
    return files


def run_file_seed(path: Path) -> int:
    """The seed a run file's name gives (``seed-<k>.npz``)."""
    m = _RUN_FILE.match(path.name)
    if m is None:
        raise ValueError(f"path must name a run file seed-<k>.npz, got {path.name!r}")
    return int(m.group(1))


def _legacy_key(path: Path) -> str | None:
    """The key a run file of the old layout was stamped with, or None if it cannot be read (kept: damaged)."""
    try:
        return str(LearningRecord.load(path).config.get("run_key"))
    except (RecordFileError, OSError):
        return None


def prune(folder: str | os.PathLike[str], configs: Sequence[RunConfig], dry_run: bool = False) -> list[Path]:
    """Remove the runs in a group's ``folder`` of definitions that none of ``configs`` has; return them.

    A run is kept when its name is one of ``configs``' and it was made by that config's
    definition (its key; a name asked for with several definitions keeps each); every other
    run file is removed: the runs of an older definition of
    a config, and those of names no config has any longer. Only run files are touched
    (``<name>/<key>/seed-<k>.npz``, and ``<name>/seed-<k>.npz`` of the old layout, read for its
    key): damaged files set aside, temporary files and anything else in the folder stay, and so
    does an old-layout file that cannot be read.

    Parameters
    ----------
    folder
        The group's folder (:func:`run_configs`'s ``folder``).
    configs
        The configurations whose runs are kept.
    dry_run
        Only list what would be removed.
    """
    asked: dict[str, set[str]] = {}
    for c in configs:
        asked.setdefault(c.name, set()).add(c.key())
    removed: list[Path] = []
    root = Path(folder)
    for name_dir in sorted(p for p in root.iterdir() if p.is_dir()) if root.is_dir() else ():
        keys = asked.get(name_dir.name, set())
        for key, path in run_files(name_dir):
            # An old-layout file's key is in the file; one that cannot be read stays (damaged, not stale).
            stamped = key if key is not None else _legacy_key(path)
            if stamped is not None and stamped not in keys:
                removed.append(path)
    if not dry_run:
        for path in removed:
            path.unlink()
        for parent in {p.parent for p in removed}:
            if not any(parent.iterdir()):
                parent.rmdir()
    return removed


@dataclass(frozen=True)
class RunGroup:
    """The runs of one folder of the store: each of ``configs`` for its count of ``seeds`` (one count
    for all, or by config name), seeds ``first_seed``, ``first_seed + 1``, ...; the warm-started ones
    from ``starts`` (by config name, one per seed in that order).

    A ``first_seed`` above 0 gives runs that share no seed with seeds 0, 1, ...: another draw of the
    same runs, or runs a step size is chosen on that leaves those seeds unseen (:mod:`safepg.comparison`).
    """

    configs: Sequence[RunConfig]
    seeds: Seeds
    folder: Path
    starts: Mapping[str, Sequence[np.ndarray]] = field(default_factory=dict)
    first_seed: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.first_seed, bool) or int(self.first_seed) != self.first_seed or self.first_seed < 0:
            raise ValueError(f"first_seed must be an integer >= 0, got {self.first_seed!r}")

    def seed_range(self, config: RunConfig) -> range:
        """The seeds of ``config`` in this group."""
        return range(self.first_seed, self.first_seed + seeds_of(self.seeds, config.name))


def run_configs(
    configs: Sequence[RunConfig],
    seeds: Seeds,
    folder: str | os.PathLike[str],
    starts: Mapping[str, Sequence[np.ndarray]] | None = None,
    jobs: int = -1,
    progress: bool = True,
    desc: str | None = None,
    first_seed: int = 0,
    on_computed: OnComputed | None = None,
) -> dict[str, list[LearningRecord]]:
    """Run every missing (config, seed) and return all records by config name.

    Finished runs are loaded, never recomputed; a damaged run file is set aside (kept as
    ``seed-<k>.npz.damaged-<time>``), named in a :class:`~safepg.store.DamagedRunWarning`
    and its run computed again. The runs go to joblib's current backend
    (local processes, or a Dask/Ray cluster inside ``joblib.parallel_config``); each
    worker returns its record and this process saves it as soon as it arrives, so an
    interrupted campaign loses nothing already computed and remote workers need no
    access to ``folder``.

    Parameters
    ----------
    configs
        The configurations, each run for seeds ``first_seed .. first_seed + n - 1``.
    seeds
        Number of seeds n: one for all configs, or a count by config name.
    folder
        The group's folder in the store; seed k of config ``c`` is ``folder/c.name/c.key()/seed-k.npz``
        (:func:`run_path`).
    starts
        For each warm-started config (by name), its starting parameters seed by seed.
    jobs
        joblib's ``n_jobs``: a positive count, or -1 for every core (-2 all but one, ...).
    progress, desc
        tqdm progress bar and its label (default: the folder's name).
    first_seed
        The first seed's index (another draw of the same runs: seeds disjoint from 0, 1, ...).
    on_computed
        Called as ``on_computed(folder, seconds, runs, jobs)`` if runs were computed: how long
        they took (the book's campaign records it in each folder's ``timing.jsonl``).
        Nothing is written for it otherwise.
    """
    group = RunGroup(configs, seeds, Path(folder), starts or {}, first_seed)
    return run_groups([group], jobs, progress, desc or Path(folder).name, on_computed)[0]


#: ``on_computed(folder, seconds, runs, jobs)`` of :func:`run_groups`: a folder's share of the wall time.
OnComputed = Callable[[Path, float, int, int], None]


def run_groups(groups: Sequence[RunGroup], jobs: int = -1, progress: bool = True,
               desc: str | None = None, on_computed: OnComputed | None = None) -> list[dict[str, list[LearningRecord]]]:
    """:func:`run_configs` for several folders at once: their missing runs in one dispatch.

    The runs of all the groups are dispatched longest first together, so that no worker waits
    at the end of one group while another group has runs left. With ``on_computed``, each
    group that computed runs is reported with its share of the dispatch's wall time, in
    proportion to its runs' time on the workers (one group: the whole wall time). Returns each
    group's records by config name, in order.
    """
    from joblib import Parallel, delayed, effective_n_jobs

    if isinstance(jobs, bool) or not isinstance(jobs, int | np.integer) or jobs == 0:
        raise ValueError(f"jobs must be a positive number of workers or negative (-1: all cores), got {jobs!r}")
    for g in groups:
        for c in g.configs:
            if c.warm_start is not None and len(g.starts.get(c.name, ())) < len(g.seed_range(c)):
                raise ValueError(f"starts must give {len(g.seed_range(c))} starting points for the warm-started "
                                 f"config {c.name!r}")
    for g in groups:
        check_names(g.configs)
    todo: list[tuple[int, RunConfig, int]] = []
    for k, g in enumerate(groups):
        # Files a killed runner was writing; a live runner's are kept.
        remove_stale_temp_files(g.folder)
        todo += [(k, c, seed) for c in g.configs for seed in g.seed_range(c)
                 if stored_run(g.folder, c, seed, "set_aside") is None]
    # Longest runs first, so that no long run is dispatched last and leaves the other workers
    # idle at the end: the largest budgets; among equal budgets the adaptive runs (a Python
    # iteration each, with the bound and the N* search: one seed of Table 5.3 takes about 12 s
    # adaptive, 9.5 s at N = 100 and 7.5 s at N = 1000), then the smallest fixed batch sizes
    # (more iterations). Stable: ties keep the given order.
    todo.sort(key=lambda kcs: (-kcs[1].budget, isinstance(kcs[1].method, Vanilla),
                               kcs[1].method.batch_size if isinstance(kcs[1].method, Vanilla) else 0))
    if todo:
        started = time.perf_counter()
        n_jobs = effective_n_jobs(jobs)
        tasks = (delayed(_compute_task)(i, c, seed, None if c.warm_start is None else
                                        groups[k].starts[c.name][seed - groups[k].first_seed], n_jobs > 1)
                 for i, (k, c, seed) in enumerate(todo))
        worked = [0.0] * len(groups)
        with tqdm(total=len(todo), desc=desc or groups[0].folder.name, unit="run", disable=not progress) as bar:
            for i, rec, seconds in Parallel(n_jobs=n_jobs, return_as="generator_unordered")(tasks):
                if rec.interrupted:  # Ctrl-C caught by a run in this process: stop the campaign
                    raise KeyboardInterrupt
                k, c, seed = todo[i]
                store_run(rec, groups[k].folder, c, seed)
                worked[k] += seconds
                bar.update()
        wall = time.perf_counter() - started
        for k, g in enumerate(groups):
            runs = sum(1 for kk, _, _ in todo if kk == k)
            if runs and on_computed is not None:
                share = worked[k] / sum(worked) if sum(worked) > 0 else runs / len(todo)
                on_computed(g.folder, wall * share, runs, n_jobs)
    return [load_configs(g.configs, g.seeds, g.folder, first_seed=g.first_seed) for g in groups]


__all__ = ["OnComputed", "RESULTS_VERSION", "RunConfig", "RunGroup", "SEED_VERSION", "Seeds", "check_names",
           "is_stored", "legacy_run_path", "load_configs", "make_env", "prune", "run_configs", "run_file_seed",
           "run_files", "run_groups", "run_path", "seeds_of", "store_run", "stored_run"]
