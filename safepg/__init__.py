"""safepg: adaptive step size and batch size for safe policy gradients (Papini, 2017).

Environments live in :mod:`safepg.envs`, the policy in :mod:`safepg.policies`, the
gradient estimators in :mod:`safepg.estimators`, the concentration bounds in
:mod:`safepg.bounds`, the step/batch-size rules of Chapter 4 in :mod:`safepg.meta`
and the learning loops of Chapter 5 in :mod:`safepg.learning`.
"""

import hashlib
import os
from pathlib import Path


def _kernel_cache_dir() -> None:
    """Keep numba's compiled kernels in a folder named by a hash of every kernel's source.

    Numba's on-disk cache (``cache=True``) checks only the source file of the function it
    caches, not those of the functions it calls or the global tables it froze in: a kernel
    in safepg/envs would keep calling the previous version of safepg/streams.py's generator
    after an update, and draw other numbers than a fresh process. Here the cache folder
    changes whenever any module that defines a kernel changes (NUMBA_CACHE_DIR, when set, is
    the parent folder). Must run before the first ``@njit(cache=True)`` is decorated.
    """
    import numba

    package = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        text = path.read_bytes()
        if b"njit" in text:
            digest.update(path.relative_to(package).as_posix().encode() + b"\0" + text)
    parent = Path(os.environ["NUMBA_CACHE_DIR"]) if os.environ.get("NUMBA_CACHE_DIR") else package / "__pycache__"
    if not os.access(parent if parent.exists() else parent.parent, os.W_OK):
        parent = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "safepg"
    # numba.config sets its names at run time (from the environment), so its stubs do not list them.
    vars(numba.config)["CACHE_DIR"] = str(parent / f"numba-{digest.hexdigest()[:16]}")


_kernel_cache_dir()

from safepg.bounds import ErrorBound, error_bound
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.estimators import gpomdp, gradient_samples, reinforce
from safepg.learning import adaptive_pg, learn, vanilla_pg
from safepg.meta import (
    coordinate_step,
    n_star_closed_form,
    n_star_search,
    n_zero,
    optimal_batch_size,
    penalty_constant,
    scalar_step,
    upsilon,
)
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.record import LearningRecord, on_trajectories
from safepg.results import load, plot_runs, summarise
from safepg.trajectories import Trajectories

#: The package's version.
__version__ = "0.1.0"

__all__ = [
    "LQG",
    "Adaptive",
    "Batches",
    "Departures",
    "ErrorBound",
    "ErrorModel",
    "FixedStep",
    "Gradient",
    "LearningRecord",
    "LinearGaussianPolicy",
    "SafeStep",
    "Target",
    "TaskConstants",
    "Trajectories",
    "Vanilla",
    "__version__",
    "adaptive_pg",
    "coordinate_step",
    "error_bound",
    "gpomdp",
    "gradient_samples",
    "learn",
    "load",
    "n_star_closed_form",
    "n_star_search",
    "n_zero",
    "on_trajectories",
    "optimal_batch_size",
    "penalty_constant",
    "plot_runs",
    "reinforce",
    "scalar_step",
    "summarise",
    "upsilon",
    "vanilla_pg",
]
