"""safepg: adaptive step size and batch size for safe policy gradients (Papini, 2017).

Environments live in :mod:`safepg.envs`, the policy in :mod:`safepg.policies`, the
gradient estimators in :mod:`safepg.estimators`, the concentration bounds in
:mod:`safepg.bounds`, the step/batch-size rules of Chapter 4 in :mod:`safepg.meta`
and the learning loops of Chapter 5 in :mod:`safepg.learning`.
"""

from safepg.bounds import ErrorBound, error_bound
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.estimators import gpomdp, gradient_samples, reinforce
from safepg.learning import LearningRecord, adaptive_pg, vanilla_pg
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    n_star_closed_form,
    n_star_search,
    n_zero,
    optimal_batch_size,
    penalty_constant,
    scalar_step,
    upsilon,
)
from safepg.policies import LinearGaussianPolicy
from safepg.trajectories import Trajectories

__version__ = "0.1.0"

__all__ = [
    "LQG",
    "ErrorBound",
    "LearningRecord",
    "LinearGaussianPolicy",
    "TaskConstants",
    "Trajectories",
    "__version__",
    "adaptive_pg",
    "coordinate_step",
    "error_bound",
    "gpomdp",
    "gradient_samples",
    "guaranteed_improvement",
    "n_star_closed_form",
    "n_star_search",
    "n_zero",
    "optimal_batch_size",
    "penalty_constant",
    "reinforce",
    "scalar_step",
    "upsilon",
    "vanilla_pg",
]
