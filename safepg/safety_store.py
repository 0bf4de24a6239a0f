r"""The safety measurements of :mod:`safepg.safety`, stored in the results folder.

:func:`cached_monte_carlo_changes` keeps one run's Monte Carlo measurement in a file keyed by
all its inputs (:func:`measurement_file`), and :func:`measure_runs` measures every update of each
run that moved theta: a book's build computes each measurement once, before the chapter that
reads it.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from safepg.runner import RESULTS_VERSION
from safepg.safety import MC_ALPHA, MC_LOOKS, MonteCarloOutcomes, monte_carlo_changes, moved_updates


def measurement_file(folder: Path, env: Any, thetas: np.ndarray, sigma: float, updates: np.ndarray,
                     looks: tuple[int, ...], alpha: str, seed: int) -> tuple[str, Path]:
    """The key of all of a measurement's inputs, and the file under ``folder`` that stores it."""
    T = np.ascontiguousarray(np.asarray(thetas, dtype=float))
    blob = json.dumps([repr(env), hashlib.sha256(T.tobytes()).hexdigest(), list(T.shape), float(sigma),
                       np.asarray(updates, dtype=int).tolist(), list(looks), alpha, seed, RESULTS_VERSION])
    return blob, Path(folder) / f"{hashlib.sha256(blob.encode()).hexdigest()[:16]}.json"


def stored_measurement(path: Path, blob: str) -> MonteCarloOutcomes | None:
    """The measurement stored at ``path`` under the key ``blob``; None if absent, unreadable or of other inputs."""
    try:
        stored = json.loads(path.read_text())
        return MonteCarloOutcomes.from_json(stored["outcomes"]) if stored.get("key") == blob else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def is_measured(folder: Path, env: Any, thetas: np.ndarray, sigma: float, looks: tuple[int, ...] = MC_LOOKS,
                alpha: str = MC_ALPHA, seed: int = 0) -> bool:
    """Whether :func:`measure_runs` would read this run's measurement from ``folder`` (a run that
    never moved theta needs none)."""
    T = np.ascontiguousarray(np.asarray(thetas, dtype=float))
    ks = moved_updates(T)
    if ks.size == 0:
        return True
    blob, path = measurement_file(folder, env, T, sigma, ks, looks, alpha, seed)
    return stored_measurement(path, blob) is not None


def cached_monte_carlo_changes(folder: Path, env: Any, thetas: np.ndarray, sigma: float,
                               updates: np.ndarray | None = None, looks: tuple[int, ...] = MC_LOOKS,
                               alpha: str = MC_ALPHA, seed: int = 0, jobs: int = 1) -> MonteCarloOutcomes:
    """:func:`monte_carlo_changes`, stored in ``folder`` under a key of all its inputs.

    The file ``<key>.json`` is written atomically (a temporary file renamed over it, as the run
    store does); a file that cannot be read, or was made by other inputs, is computed again.
    It also records the ``seconds`` the measurement took (wall time; the time budget reads them,
    with the ``steps`` its rollouts lived). Without updates nothing is simulated or stored.

    ``jobs`` > 1 measures the updates in that many joblib processes, update ``i`` of the list in
    process ``i % jobs``. Each update's rollouts are seeded by the update and the look alone, so
    the outcomes are the same for any ``jobs``; it is not part of the key.
    """
    T = np.ascontiguousarray(np.asarray(thetas, dtype=float))
    ks = np.arange(T.shape[0] - 1) if updates is None else np.asarray(updates, dtype=int)
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1, got {jobs!r}")
    if ks.size == 0:
        return monte_carlo_changes(env, T, sigma, ks, looks, alpha, seed)
    blob, path = measurement_file(folder, env, T, sigma, ks, looks, alpha, seed)
    stored = stored_measurement(path, blob)
    if stored is not None:
        return stored
    started = time.perf_counter()
    jobs = int(min(jobs, ks.size))
    if jobs == 1:
        out = monte_carlo_changes(env, T, sigma, ks, looks, alpha, seed)
    else:
        from joblib import Parallel, delayed

        parts = Parallel(n_jobs=jobs)(delayed(_one_thread_changes)(env, T, sigma, ks[j::jobs], looks, alpha, seed)
                                      for j in range(jobs))
        joined = MonteCarloOutcomes.join(parts)
        order = np.argsort(np.concatenate([np.arange(ks.size)[j::jobs] for j in range(jobs)]), kind="stable")
        out = replace(joined, updates=joined.updates[order], change=joined.change[order], lower=joined.lower[order],
                      upper=joined.upper[order], rollouts=joined.rollouts[order], outcome=joined.outcome[order])
    seconds = time.perf_counter() - started  # benchmarks/bench_book.py and safepg.thesis.budget read it
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"{path.stem}~", suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump({"key": blob, "outcomes": out.to_json(), "seconds": round(seconds, 3)}, f)
    os.replace(tmp, path)
    return out


def _one_thread_changes(*args: Any) -> MonteCarloOutcomes:
    """:func:`monte_carlo_changes` in a joblib process, its kernels on one thread (the processes
    share the cores; a batch does not depend on the thread count, ``safepg.streams``)."""
    import numba

    numba.set_num_threads(1)
    return monte_carlo_changes(*args)


def measure_runs(env: Any, runs: Sequence[np.ndarray], sigma: float, folder: Path,
                 looks: tuple[int, ...] = MC_LOOKS, alpha: str = MC_ALPHA, seed: int = 0,
                 jobs: int = 1) -> list[MonteCarloOutcomes]:
    """:func:`cached_monte_carlo_changes` on every update of each run that moved theta, run by run.

    Parameters
    ----------
    env : task
        The task the runs learned on.
    runs : sequence of arrays (I + 1, m)
        Each run's parameters in the order visited (a record's ``theta``, or the authors' logged
        theta column).
    sigma : float
        The policies' standard deviation.
    folder : Path
        Where the measurements are stored (one file per run).
    looks, alpha, seed
        As in :func:`monte_carlo_changes`: the last look sets the detection floor of the updates
        that stay undetermined.
    jobs : int
        Processes per run (:func:`cached_monte_carlo_changes`; the outcomes do not depend on it).

    Returns
    -------
    list of MonteCarloOutcomes
        One per run, every update k with theta[k + 1] != theta[k] (:func:`moved_updates`), in
        order; :meth:`MonteCarloOutcomes.counts` summarises a run, :meth:`MonteCarloOutcomes.join`
        pools several.
    """
    return [cached_monte_carlo_changes(folder, env, T, sigma, moved_updates(T), looks, alpha, seed, jobs)
            for T in runs]


__all__ = ["cached_monte_carlo_changes", "is_measured", "measure_runs", "measurement_file", "stored_measurement"]
