"""Any folder of stored runs, read back, summarised and drawn, from the runs' own definitions.

:func:`safepg.runner.run_configs` stores seed k of a configuration at
``<folder>/<name>/<key>/seed-<k>.npz`` (:func:`safepg.runner.run_path`), and each record holds
the run's whole definition as data (``record.config``: the task, the method, theta_0, sigma,
the budget). So a folder is read without the configurations that made it:

>>> runs = load("results/my-task")                      # doctest: +SKIP
>>> summarise(runs)["adaptive"]["final"]                  # doctest: +SKIP
>>> plot_runs(runs)                                       # doctest: +SKIP

No task is rebuilt, so a task whose feature map has only a label (``features_name=``) loads
as well as any. The performance read by default is the closed-form ``J`` where the task has
one and the measured ``J_hat`` otherwise (:attr:`~safepg.record.LearningRecord.performance_field`).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from safepg.record import LearningRecord, Performance, RecordFileError, on_trajectories, performance_field_of
from safepg.runner import run_file_seed, run_files
from safepg.store import DamagedRunWarning

#: A folder's runs: the records of each configuration, by name, in the order of their seeds.
Runs = Mapping[str, Sequence[LearningRecord]]


def load(folder: str | os.PathLike[str]) -> dict[str, list[LearningRecord]]:
    """The finished runs stored in a group's folder, by configuration name, seeds in order.

    A name whose runs were made by more than one definition (the runs of a changed
    configuration beside the old ones) gives one entry per definition, named
    ``<name>/<key>``; a name with one definition keeps its name. Interrupted runs are left
    out, and damaged files with a :class:`~safepg.store.DamagedRunWarning` (as every reader of
    the store does). Each record's ``config`` holds its definition as data.

    Raises
    ------
    NotADirectoryError
        ``folder`` is not a folder.
    """
    root = Path(folder)
    if not root.is_dir():
        raise NotADirectoryError(f"folder must be a folder of stored runs, got {str(root)!r}")
    out: dict[str, list[LearningRecord]] = {}
    for name_dir in sorted(p for p in root.iterdir() if p.is_dir()):
        by_key: dict[str, dict[int, LearningRecord]] = {}
        for folder_key, path in run_files(name_dir):
            try:
                rec = LearningRecord.load(path)
            except RecordFileError as err:
                warnings.warn(f"damaged run file {path} left out: {err.reason}", DamagedRunWarning, stacklevel=2)
                continue
            key = str(rec.config.get("run_key", folder_key))
            if rec.interrupted or (folder_key is not None and key != folder_key):
                continue
            # A run in its key's folder wins over the same seed of the old layout (listed after it).
            by_key.setdefault(key, {}).setdefault(int(rec.config.get("seed", run_file_seed(path))), rec)
        for key, seeds in by_key.items():
            out[name_dir.name if len(by_key) == 1 else f"{name_dir.name}/{key}"] = [seeds[k] for k in sorted(seeds)]
    return out


def _field(runs: Runs, field: Performance | None) -> Performance:
    """``field``, or the performance all the runs share (:func:`~safepg.record.performance_field_of`)."""
    return field or performance_field_of([r for recs in runs.values() for r in recs])


def _mean_sd(values: Sequence[float]) -> dict[str, float]:
    """The mean and the sample standard deviation (n - 1; NaN for one value), in exact sums."""
    v = [float(x) for x in values]
    mean = math.fsum(v) / len(v) if v else float("nan")
    sd = math.sqrt(math.fsum((x - mean) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else float("nan")
    return {"mean": mean, "sd": sd}


def summarise(runs: Runs, field: Performance | None = None,
              checkpoints: Sequence[int] | None = None) -> dict[str, dict[str, Any]]:
    """Each configuration's runs in numbers: the mean and sample standard deviation over seeds.

    Per name: ``seeds``, ``trajectories`` (the mean), the ``field`` read (default: ``"J"`` if
    every run has a closed form, else ``"J_hat"``), its ``initial`` and ``final`` value,
    :math:`\\overline\\Upsilon` (``upsilon_bar``), the ``improvement_ratio`` on that field and
    the value ``at`` each checkpoint that every seed reached (default: the first run's own,
    :meth:`~safepg.record.LearningRecord.checkpoints`).
    """
    field = _field(runs, field)
    out: dict[str, dict[str, Any]] = {}
    for name, recs in runs.items():
        if not recs:
            continue
        points = recs[0].checkpoints() if checkpoints is None else tuple(checkpoints)
        at = [r.at(points, field) for r in recs]
        reached = [T for T in map(str, points) if all(T in a for a in at)]
        out[name] = {
            "seeds": len(recs),
            "trajectories": _mean_sd([r.trajectories for r in recs])["mean"],
            "field": field,
            "initial": _mean_sd([getattr(r, field)[0] for r in recs]),
            "final": _mean_sd([getattr(r, field)[-1] for r in recs]),
            "upsilon_bar": _mean_sd([r.upsilon_bar() for r in recs]),
            "improvement_ratio": _mean_sd([r.improvement_ratio(field) for r in recs]),
            "at": {T: _mean_sd([a[T] for a in at]) for T in reached},
        }
    return out


def plot_runs(runs: Runs, field: Performance | None = None, ax: Any = None, points: int = 200,
              band: str = "sd") -> Any:
    """Each configuration's seeds on one axis of trajectories: thin lines, their mean and a band.

    Like stable-baselines3's ``results_plotter``: every seed's curve
    (:func:`~safepg.record.on_trajectories`, on ``points`` trajectory counts up to the longest
    run), the mean over the seeds that reached each count, and a band of one standard
    deviation around it (``band="sd"``) or of the seeds' range (``band="range"``).

    Returns the matplotlib ``Axes`` (a new figure's unless ``ax`` is given). matplotlib is
    imported here only, so the library needs it only for figures.

    Raises
    ------
    ValueError
        ``band`` is neither ``"sd"`` nor ``"range"``, or ``runs`` holds no run.
    """
    import matplotlib.pyplot as plt

    if band not in ("sd", "range"):
        raise ValueError(f"band must be 'sd' or 'range', got {band!r}")
    field = _field(runs, field)
    longest = max((r.trajectories for recs in runs.values() for r in recs), default=0)
    if longest == 0:
        raise ValueError("runs must hold at least one run")
    grid = np.unique(np.linspace(1, longest, points).round().astype(np.int64))
    if ax is None:
        _, ax = plt.subplots()
    for name, recs in runs.items():
        if not recs:
            continue
        values = on_trajectories(recs, grid, field)
        with warnings.catch_warnings():  # a count no seed reached is NaN, and stays out of the line
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(values, axis=0)
            low, high = ((mean - np.nanstd(values, axis=0), mean + np.nanstd(values, axis=0)) if band == "sd"
                         else (np.nanmin(values, axis=0), np.nanmax(values, axis=0)))
        (line,) = ax.plot(grid, mean, label=f"{name} ({len(recs)} seeds)")
        for row in values:
            ax.plot(grid, row, color=line.get_color(), alpha=0.25, linewidth=0.6)
        ax.fill_between(grid, low, high, color=line.get_color(), alpha=0.15, linewidth=0)
    ax.set_xlabel("trajectories")
    ax.set_ylabel("J (closed form)" if field == "J" else "measured return J_hat")
    ax.legend()
    return ax


__all__ = ["Runs", "load", "plot_runs", "summarise"]
