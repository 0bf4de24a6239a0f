"""The book's campaign machinery around :func:`safepg.runner.run_groups`: compile the kernels once, time each folder.

:func:`compile_once` compiles the numba kernels a campaign needs, one task family per worker,
before the campaign's workers all compile the same kernels at once. :func:`record_timing`
appends one line per folder that a call computed runs in to its ``timing.jsonl``; ``run-book``
passes it to the runner as ``on_computed`` (:func:`safepg.runner.run_groups`: through
``run_experiment(..., timing=True)`` and ``run_experiments`` of :mod:`safepg.thesis.experiment_store`,
and ``run_comparison(..., on_computed=record_timing)`` of :mod:`safepg.comparison`), and
:mod:`safepg.thesis.budget` and ``benchmarks/bench_book.py`` read it. A notebook, the command line's
``run`` or a researcher's own campaign writes no timing file unless it asks for one the same way.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from safepg.options import Vanilla
from safepg.runner import RESULTS_VERSION, RunConfig


def _shape(d: Any) -> Any:
    """A definition's structure: its keys, strings and flags, and the length of its lists, not its numbers."""
    if isinstance(d, Mapping):
        return tuple((k, _shape(v)) for k, v in sorted(d.items()))
    if isinstance(d, list | tuple):
        return tuple(_shape(v) for v in d)
    return d if d is None or isinstance(d, bool | str) else type(d).__name__


def _first_batch(cfg: RunConfig) -> int:
    return cfg.method.batch_size if isinstance(cfg.method, Vanilla) else cfg.method.batches.first_size


def _short_runs(configs: Sequence[RunConfig]) -> int:
    """Two batches of each config, on one thread, nothing kept: what compiles their kernels."""
    import numba

    numba.set_num_threads(1)
    for c in configs:
        replace(c, budget=2 * _first_batch(c)).run(0)
    return len(configs)


def compile_once(configs: Sequence[RunConfig], jobs: int = -1) -> int:
    """Compile the numba kernels that ``configs`` run, each in one worker, before a campaign runs them.

    Numba compiles a kernel in every process that calls it before it is in numba's cache
    (``safepg/__pycache__``); on a cold cache, the workers of :func:`safepg.runner.run_configs` all compile
    the same kernels at once, and one core's work is wasted per extra worker. Here the configs
    are grouped by task family (task type and dimension: the same kernels), and each family
    compiles in one joblib worker, the families side by side: two batches of one config of
    each distinct kind (the structure of its definition: its keys, strings and flags, not its
    numbers). The kernels go to numba's cache; the campaign's workers then load them. Nothing
    is stored, and no number of a campaign depends on it. Warm-started configs are left out
    (they run their start run's kernels).

    Returns the number of short runs made.
    """
    from joblib import Parallel, delayed, effective_n_jobs

    families: dict[Any, dict[Any, RunConfig]] = {}
    for c in configs:
        if c.warm_start is not None:
            continue
        d = c.definition(exact=False)
        family = (d["task"].get("type"), d["task"].get("dim"))
        families.setdefault(family, {}).setdefault(_shape([d["task"], d["method"]]), c)
    groups = sorted((list(f.values()) for f in families.values()), key=len, reverse=True)
    n_jobs = min(effective_n_jobs(jobs), len(groups))
    if n_jobs < 2:  # one family, or one worker: each kernel is compiled once anyway
        return 0
    return sum(Parallel(n_jobs=n_jobs)(delayed(_short_runs)(g) for g in groups))


#: One line per call of :func:`safepg.runner.run_configs` (or :func:`run_groups`) that computed runs in a folder:
#: how long it took (its share of the call's wall time).
TIMING_FILE = "timing.jsonl"


def record_timing(folder: Path, seconds: float, runs: int, jobs: int) -> None:
    """Append {seconds, runs, jobs, cores, version} to ``folder/timing.jsonl``
    (benchmarks/bench_book.py sets these against the random-number floor)."""
    line = json.dumps({"seconds": round(seconds, 3), "runs": runs, "jobs": jobs, "cores": os.cpu_count(),
                       "results_version": RESULTS_VERSION})
    with open(folder / TIMING_FILE, "a") as f:
        f.write(line + "\n")


__all__ = ["TIMING_FILE", "compile_once", "record_timing"]
