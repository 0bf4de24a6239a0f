"""The record of a learning run: per-iteration arrays, their summaries, and their file.

:class:`LearningRecord` is what :func:`safepg.learning.adaptive_pg` and
:func:`safepg.learning.vanilla_pg` return; :meth:`LearningRecord.save` and
:meth:`LearningRecord.load` keep it as ``.npz`` (a file that does not hold one raises
:class:`RecordFileError`).
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from safepg import portable

#: Trajectory counts at which Figures 5.1-5.2 are read off (``LearningRecord.J_at``).
CHECKPOINTS = (100_000, 1_000_000, 3_000_000, 10_000_000, 30_000_000)
#: A run's performance: the closed-form ``"J"`` or the measured ``"J_hat"``.
Performance = Literal["J", "J_hat"]


class RecordFileError(ValueError):
    """A file that exists but does not hold a readable :class:`LearningRecord`.

    ``path`` is the file and ``reason`` says, in words, what is wrong with it.
    """

    def __init__(self, path: str | Path, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path, self.reason = Path(path), reason


def _damage(err: Exception) -> str:
    """What is wrong with a run file, in words, from the error that reading it raised."""
    detail = f"{type(err).__name__}: {err}"
    if isinstance(err, zipfile.BadZipFile):
        what = "not a whole .npz archive (truncated or overwritten)"
    elif isinstance(err, EOFError):
        what = "empty"
    elif isinstance(err, ValueError) and "pickle" in str(err):
        # np.load's message here advises allow_pickle=True, which a damaged file must not get.
        what, detail = "not an .npz archive (overwritten with other data)", type(err).__name__
    elif isinstance(err, KeyError | TypeError | AttributeError):
        what = "not a saved run (an array or the metadata is missing or extra)"
    elif isinstance(err, json.JSONDecodeError | UnicodeDecodeError):
        what = "unreadable metadata"
    else:
        what = "not a saved run"
    return f"{what} ({detail})"


@dataclass
class LearningRecord:
    """Per-iteration record of a learning run (arrays of length I = iterations).

    Attributes
    ----------
    batch_size : int array (I,)
        Trajectories collected at iteration i.
    alpha : float array (I,)
        Step size applied (to ``coordinate[i]``, or to every component if -1).
    coordinate : int array (I,)
        Updated component k, or -1 for a full (scalar-step) update.
    theta : float array (I + 1, m)
        Parameters before each iteration; the last row is the final theta.
    J : float array (I + 1,)
        Closed-form expected performance J(theta[i]) (NaN if the task has none).
    J_hat : float array (I,)
        Measured performance: mean return of batch i (discounted; for a task with
        ``measured_returns``, such as the cart-pole, the return that defines).
    grad : float array (I, m)
        Gradient estimate of batch i.
    eps : float array (I,)
        Estimation error bound used for the step (0 for a fixed step).
    safe : bool array (I,)
        Whether the update came with the high-probability improvement guarantee
        (Assumption 4.2.7 held: eps < |g_k|).
    config : dict
        The settings of the run (JSON-serialisable).
    interrupted : bool
        The run was stopped early (KeyboardInterrupt); the arrays hold what was done.
    diverged : bool
        The run stopped because the gradient estimate overflowed (theta diverged under a
        fixed step); only with ``stop_on_divergence=True``.
    reached_target : bool
        The run stopped because a batch's mean return reached its ``Target``; that
        last batch made no update, so ``theta_final`` is the policy that reached it.
    """

    batch_size: np.ndarray
    alpha: np.ndarray
    coordinate: np.ndarray
    theta: np.ndarray
    J: np.ndarray
    J_hat: np.ndarray
    grad: np.ndarray
    eps: np.ndarray
    safe: np.ndarray
    config: dict[str, Any] = field(default_factory=dict)
    interrupted: bool = False
    diverged: bool = False
    reached_target: bool = False

    @property
    def iterations(self) -> int:
        return int(self.batch_size.size)

    @property
    def trajectories(self) -> int:
        return int(self.batch_size.sum())

    @property
    def theta_final(self) -> np.ndarray:
        last: np.ndarray = self.theta[-1]
        return last

    def upsilon_bar(self) -> float:
        r"""Average performance :math:`\overline\Upsilon` (Tables 5.2-5.4): the measured
        performance averaged over all trajectories (iterations weighted by batch size)."""
        # Exact sums (math.fsum), not ``@``: BLAS's dot product differs across CPUs in the last bit.
        return portable.fsum_mean(self.J_hat, weights=self.batch_size)

    @property
    def performance_field(self) -> Performance:
        """The performance this run is judged on by default: ``"J"`` where the task has a closed
        form (J is not NaN), else ``"J_hat"``, the measured returns (every task has them)."""
        return "J" if not np.isnan(self.J).all() else "J_hat"

    def improvement_ratio(self, on: Performance | None = None) -> float:
        """Share of policy updates after which performance did not decrease.

        ``on="J"``: the closed-form J (Section 5.1); ``on="J_hat"``: the batch-average
        return of consecutive batches (Section 5.3, no closed form); None:
        :attr:`performance_field`. NaN where the performance is unknown (``J`` of a task
        without a closed form, which is NaN) or nothing was updated.
        """
        perf = getattr(self, on or self.performance_field)
        if np.isnan(perf).any():
            return float("nan")
        with np.errstate(invalid="ignore"):  # -inf to -inf (a diverged run) counts as no improvement
            steps = np.diff(perf)
        if steps.size == 0:
            return float("nan")
        return float(np.mean(steps >= 0))

    def checkpoints(self, count: int = 4) -> tuple[int, ...]:
        """The run's own checkpoints: ``count`` trajectory counts evenly spread up to its last
        trajectory (by default a quarter, half, three quarters and all of it)."""
        return tuple(sorted({max(1, self.trajectories * (i + 1) // count) for i in range(count)}))

    def at(self, checkpoints: Sequence[int] | None = None, field: Performance | None = None) -> dict[str, float]:
        """``field`` (default :attr:`performance_field`) at each reached checkpoint T (1-based):
        J of the policy that generated trajectory T, or the measured return of the batch that
        holds it. ``checkpoints`` default to the run's own (:meth:`checkpoints`)."""
        field = field or self.performance_field
        values = getattr(self, field)
        ends = np.cumsum(self.batch_size)
        out = {}
        for T in self.checkpoints() if checkpoints is None else checkpoints:
            if T <= self.trajectories:
                out[str(T)] = float(values[int(np.searchsorted(ends, T))])
        return out

    def J_at(self, checkpoints: Sequence[int] | None = None) -> dict[str, float]:
        """J of the policy that generated trajectory number T (1-based), for each reached
        checkpoint T: Figures 5.1-5.2 read at T (the thesis's are ``CHECKPOINTS``; by
        default the run's own, :meth:`checkpoints`)."""
        return self.at(checkpoints, "J")

    def performance_curve(self, field: Performance | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(trajectories used before each value, the value) as a step curve, Figures 5.1-5.2.

        ``"J"`` (the default where there is a closed form) is J before each batch and after the
        last, at 0, N_1, N_1 + N_2, ...; ``"J_hat"`` is each batch's measured return, at its start.
        """
        field = field or self.performance_field
        ends = np.concatenate([[0], np.cumsum(self.batch_size)])
        return (ends, self.J) if field == "J" else (ends[:-1], self.J_hat)

    def summary(self, checkpoints: Sequence[int] | None = None) -> dict[str, Any]:
        """JSON-ready summary of the run (``checkpoints``: as :meth:`at`, the run's own by default).

        ``J_*`` read the closed form (NaN without one); ``performance`` reads
        :attr:`performance_field`, which every task has.
        """
        field = self.performance_field
        values = getattr(self, field)
        return {
            "iterations": self.iterations,
            "trajectories": self.trajectories,
            "theta": self.theta_final.tolist(),
            "J_initial": float(self.J[0]),
            "J_final": float(self.J[-1]),
            "J_at": self.J_at(checkpoints),
            "performance": {"field": field, "initial": float(values[0]), "final": float(values[-1]),
                            "at": self.at(checkpoints, field)},
            "upsilon_bar": self.upsilon_bar(),
            "improvement_ratio": self.improvement_ratio(),
            "batch_sizes": self.batch_size.tolist(),
            "interrupted": self.interrupted,
            "diverged": self.diverged,
            "reached_target": self.reached_target,
        }

    def save(self, path: str | Path) -> None:
        """Write the record to a compressed ``.npz`` (config as JSON metadata)."""
        # Any: numpy types **kwargs as if one of them could be allow_pickle.
        arrays: dict[str, Any] = {k: v for k, v in asdict(self).items() if isinstance(v, np.ndarray)}
        meta = json.dumps({"config": self.config, "interrupted": self.interrupted, "diverged": self.diverged,
                           "reached_target": self.reached_target})
        np.savez_compressed(path, meta=np.array(meta), **arrays)

    def check(self) -> None:
        """Raise ``ValueError`` unless the arrays have the kinds and lengths of one run.

        With I iterations and m parameters: ``batch_size``, ``alpha``, ``coordinate``,
        ``J_hat``, ``eps`` and ``safe`` of shape (I,), ``theta`` (I + 1, m), ``J`` (I + 1,)
        and ``grad`` (I, m); the counts integer, ``safe`` boolean, the rest floating point.
        The record of every finished run passes; a file that holds anything else is
        not a run, whatever its archive says.
        """
        kinds = {"batch_size": "iu", "alpha": "f", "coordinate": "iu", "theta": "f", "J": "f",
                 "J_hat": "f", "grad": "f", "eps": "f", "safe": "b"}
        for name, kind in kinds.items():
            a = getattr(self, name)
            if not isinstance(a, np.ndarray) or a.dtype.kind not in kind:
                raise ValueError(f"{name} must be an array of kind {kind!r}, got {getattr(a, 'dtype', type(a))}")
        if self.theta.ndim != 2 or self.theta.shape[1] == 0:
            raise ValueError(f"theta must have shape (iterations + 1, m), got {self.theta.shape}")
        it, m = self.theta.shape[0] - 1, self.theta.shape[1]
        shapes = {"batch_size": (it,), "alpha": (it,), "coordinate": (it,), "J": (it + 1,), "J_hat": (it,),
                  "grad": (it, m), "eps": (it,), "safe": (it,)}
        for name, shape in shapes.items():
            if getattr(self, name).shape != shape:
                raise ValueError(f"{name} must have shape {shape} to match theta {self.theta.shape}, "
                                 f"got {getattr(self, name).shape}")
        if not isinstance(self.config, dict):
            raise ValueError(f"config must be a dict, got {type(self.config).__name__}")

    @classmethod
    def load(cls, path: str | Path) -> LearningRecord:
        """Read a record written by :meth:`save`.

        Raises
        ------
        RecordFileError
            The file exists but is not a whole record: empty, truncated, overwritten with
            something else, missing an array or its metadata, or holding arrays whose
            lengths do not fit together (:meth:`check`).
        OSError
            The file cannot be opened (missing, no permission, a folder): nothing is known
            about its contents.
        """
        try:
            # Opened here, not by np.load, which leaves its file open when the archive is broken.
            # allow_pickle=False: a file can only hold plain arrays.
            with open(path, "rb") as f, np.load(f) as z:
                meta = json.loads(str(z["meta"]))
                arrays = {k: z[k] for k in z.files if k != "meta"}
            rec = cls(**arrays, config=meta["config"], interrupted=bool(meta["interrupted"]),
                      diverged=bool(meta.get("diverged", False)),
                      reached_target=bool(meta.get("reached_target", False)))
        except (FileNotFoundError, PermissionError, IsADirectoryError, MemoryError):
            raise  # says nothing about the contents
        except Exception as err:
            # np.load and zipfile report a damaged file through many types: BadZipFile
            # (truncated, bad CRC), EOFError (empty), ValueError (pickled or text data),
            # zlib.error, TypeError (a bare .npy, or an array too many), KeyError and JSON
            # errors (a missing array or metadata).
            raise RecordFileError(path, _damage(err)) from err
        try:
            rec.check()
        except ValueError as err:
            raise RecordFileError(path, f"arrays that do not form one run ({err})") from err
        return rec
def performance_field_of(records: Sequence[LearningRecord]) -> Performance:
    """The performance several runs are read on together: ``"J"`` if every one has a closed form
    (:attr:`LearningRecord.performance_field`), else the measured ``"J_hat"``, which every run has."""
    return "J" if records and all(r.performance_field == "J" for r in records) else "J_hat"


def on_trajectories(records: Sequence[LearningRecord], grid: np.ndarray | Sequence[int],
                    field: Performance | None = None) -> np.ndarray:
    """Several seeds' runs on one axis of trajectories: per run, ``field`` of the iteration whose
    batch holds trajectory T, for each T of ``grid`` (1-based).

    ``"J"`` is the thesis's "expected performance over sample trajectories" (Figures 5.1-5.2:
    each iteration's J held for all the trajectories of its batch); ``"J_hat"`` the batch's
    measured average return (Figure 5.9). Runs of different batch sizes thus line up, and
    their mean or band over seeds can be taken column by column. None: the records' common
    performance (:func:`safepg.record.performance_field_of`).

    Returns
    -------
    ndarray, shape (len(records), len(grid))
        NaN past a run's last trajectory.
    """
    grid = np.asarray(grid)
    field = field or performance_field_of(records)
    out = np.full((len(records), grid.size), np.nan)
    for i, r in enumerate(records):
        idx = np.searchsorted(np.cumsum(r.batch_size), grid)
        ok = idx < r.iterations
        out[i, ok] = getattr(r, field)[idx[ok]]
    return out


__all__ = ["CHECKPOINTS", "LearningRecord", "Performance", "RecordFileError", "on_trajectories", "performance_field_of"]
