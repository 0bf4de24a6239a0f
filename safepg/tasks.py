"""What a task offers the learning loops: the required interface and the optional fast paths.

A task must simulate batches and state the bounds of Assumption 4.2.1 (:class:`Task`). It
may also offer fast paths, each a Protocol of one method that the task's class declares by
inheriting it:

* :class:`GradientBatch`: a batch's gradient samples and returns in one fused call;
* :class:`GradientBatchConstants`: the same and the batch's measured R and M_phi;
* :class:`FixedStepBatches`: whole runs of vanilla policy gradient with a fixed step;
* :class:`MeasuredReturns`: the per-trajectory performance the loops record as J_hat;
* :class:`Performance` / :class:`PerformanceBatch`: the closed-form J;
* :class:`ActionDimension`: the number of action dimensions (else 1);
* :class:`ConstantsSettings`: how the bound constants are written, ``horizon_term`` and
  ``constants_gamma`` (else :data:`DEFAULT_CONSTANTS_SETTINGS`, Theorem 4.2.3 as printed in the
  task's own discount).

:func:`task_hooks` checks a task once, when a learning loop starts: a declared hook that is
missing or has other parameters, or a method or setting with a hook's name that is not declared,
is a ``TypeError`` (a misspelt hook would otherwise be skipped in silence, and a misspelt setting
would silently change a bound). :func:`constants_settings` is the one reader of the settings
(:meth:`safepg.constants.TaskConstants.from_task` and :mod:`safepg.safety` read them through it),
with the same check.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol, cast

import numpy as np

from safepg.policies import LinearGaussianPolicy
from safepg.rng import RNGLike
from safepg.trajectories import Trajectories


class BoundedTask(Protocol):
    """A task's bounds of Assumption 4.2.1 and its horizon: read-only, as attributes or properties."""

    @property
    def reward_bound(self) -> float: ...

    @property
    def feature_bound(self) -> float: ...

    @property
    def action_volume(self) -> float: ...

    @property
    def action_bound(self) -> float: ...

    @property
    def gamma(self) -> float: ...

    @property
    def horizon(self) -> int: ...


class Task(BoundedTask, Protocol):
    """The required interface: ``simulate`` and the bounds (``reward_bound``, ``feature_bound``,
    ``action_volume``, ``action_bound``, ``gamma``, ``horizon``)."""

    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories:
        """``n`` trajectories of ``policy``."""
        ...


class ActionDimension(Protocol):
    """A task whose actions have ``action_dim`` components (the gain has that many rows)."""

    @property
    def action_dim(self) -> int: ...


class ConstantsSettings(Protocol):
    """How the bound constants of Chapter 4 are written for this task (the simulation is unchanged).

    A task that declares it defines both, as class attributes, dataclass fields with a default
    or properties (the Protocol's are read-only properties, so ``self.horizon_term = ...`` in an
    ``__init__`` is refused: store it under another name behind a property); one that does not
    gets :data:`DEFAULT_CONSTANTS_SETTINGS`.
    """

    @property
    def horizon_term(self) -> str:
        """The horizon factor h of the penalty constant: ``"effective"``, ``"truncated"`` or
        ``"horizon"`` (:class:`~safepg.constants.TaskConstants`)."""
        ...

    @property
    def constants_gamma(self) -> float | None:
        """The discount the constants are written in; None: the task's ``gamma``."""
        ...


class ConstantsSettingValues(NamedTuple):
    """A task's :class:`ConstantsSettings`, as :func:`constants_settings` reads them."""

    horizon_term: str
    constants_gamma: float | None


#: The settings of a task that does not declare :class:`ConstantsSettings`: Theorem 4.2.3 as
#: printed (h = 1 / (1 - gamma)), in the task's own discount.
DEFAULT_CONSTANTS_SETTINGS = ConstantsSettingValues(horizon_term="effective", constants_gamma=None)


class GradientBatch(Protocol):
    """Gradient samples (n, m) and measured returns (n,) of a fresh batch in one call."""

    def gradient_batch(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None, estimator: str = "gpomdp",
                       baseline: bool = True, score_action: str = "clipped") -> tuple[np.ndarray, np.ndarray]:
        """The same numbers as ``gradient_samples`` on ``simulate``'s batch."""
        ...


class GradientBatchConstants(Protocol):
    """:class:`GradientBatch` plus the batch's measured (R, M_phi): its largest |reward| and |feature|."""

    def gradient_batch_constants(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None,
                              estimator: str = "gpomdp", baseline: bool = True, score_action: str = "clipped",
                              ) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
        """Samples, returns and (R, M_phi) of one batch."""
        ...


class FixedStepBatches(Protocol):
    """Consecutive batches of vanilla policy gradient with a fixed step, in one call."""

    def fixed_step_batches(self, policy: LinearGaussianPolicy, sizes: np.ndarray, keys: np.ndarray, alpha: float,
                           kind: str = "scalar", estimator: str = "gpomdp", baseline: bool = True,
                           score_action: str = "clipped") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Parameters (b + 1, m), gradients (b, m) and mean measured returns (b,) of batches of
        ``sizes[i]`` trajectories drawn with ``keys[i]``: the numbers of ``gradient_batch`` and of
        the step, batch after batch, up to the first non-finite gradient or parameters."""
        ...


class MeasuredReturns(Protocol):
    """The per-trajectory performance recorded as J_hat (default: the discounted return)."""

    def measured_returns(self, batch: Trajectories) -> np.ndarray:
        """Shape (N,)."""
        ...


class Performance(Protocol):
    """The closed-form J of one parameter."""

    def performance(self, theta: np.ndarray | float, sigma: float | np.ndarray) -> float:
        """J(theta)."""
        ...


class PerformanceBatch(Protocol):
    """The closed-form J of many parameters at once."""

    def performance_batch(self, thetas: np.ndarray, sigma: float | np.ndarray) -> np.ndarray:
        """J of each row of ``thetas``."""
        ...


class Definition(Protocol):
    """A task written into its run's definition by the keywords ``definition()`` returns, instead of
    by its dataclass fields (:func:`safepg.definition.to_dict`): a matrix written out, a factory by name."""

    def definition(self) -> dict[str, Any]:
        """The keyword arguments that make this task."""
        ...


class FromDefinition(Protocol):
    """A task built again from the keywords of its definition by ``from_definition`` instead of by its
    constructor (:func:`safepg.definition.from_dict`)."""

    @classmethod
    def from_definition(cls, **kwargs: Any) -> Any:
        """The task the keywords of :meth:`Definition.definition` describe."""
        ...


#: The optional methods, by the Protocol that declares each.
METHOD_HOOKS: dict[type, str] = {GradientBatch: "gradient_batch", GradientBatchConstants: "gradient_batch_constants",
                                 FixedStepBatches: "fixed_step_batches", MeasuredReturns: "measured_returns",
                                 Performance: "performance", PerformanceBatch: "performance_batch"}
#: The optional values (attributes or properties), by the Protocol that declares them.
VALUE_HOOKS: dict[type, tuple[str, ...]] = {ActionDimension: ("action_dim",),
                                            ConstantsSettings: ("horizon_term", "constants_gamma")}


@dataclass(frozen=True)
class Hooks:
    """A task's fast paths, bound to the task (None where it has none)."""

    gradient_batch: Callable[..., tuple[np.ndarray, np.ndarray]] | None
    gradient_batch_constants: Callable[..., tuple[np.ndarray, np.ndarray, tuple[float, float]]] | None
    fixed_step_batches: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]] | None
    measured_returns: Callable[[Trajectories], np.ndarray] | None
    performance: Callable[[Any, Any], float] | None
    performance_batch: Callable[[np.ndarray, Any], np.ndarray] | None
    action_dim: int


def _parameters(func: Callable[..., Any]) -> list[tuple[str, bool]]:
    """(name, has a default) of each parameter after ``self``."""
    params = list(inspect.signature(func).parameters.values())
    if params and params[0].name == "self":
        params = params[1:]
    return [(p.name, p.default is not inspect.Parameter.empty) for p in params
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]


def _check_signature(cls: type, proto: type, name: str) -> None:
    expected = _parameters(getattr(proto, name))
    got = _parameters(getattr(cls, name))
    names = [n for n, _ in got]
    # The loops call hooks positionally: the Protocol's parameters first, any further ones optional.
    if names[:len(expected)] != [n for n, _ in expected] or not all(d for _, d in got[len(expected):]):
        raise TypeError(f"{cls.__name__}.{name} must take ({', '.join(n for n, _ in expected)}) as "
                        f"{proto.__name__} declares, got ({', '.join(names)})")


_MISSING = object()


def _check_values(task: object) -> None:
    """Refuse a value hook defined without its Protocol, or a Protocol declared without all its values.

    "Defined" is on the instance or its class, looked up statically (no property runs, and
    what a ``__getattr__`` forwards is not the task's own, as for the methods); the
    Protocol's own stub is not a definition.
    """
    cls = type(task)
    for proto, names in VALUE_HOOKS.items():
        declared = proto in cls.__mro__
        for name in names:
            found = inspect.getattr_static(task, name, _MISSING)
            defined = found is not _MISSING and found is not proto.__dict__[name]
            if declared and not defined:
                raise TypeError(f"{cls.__name__} declares {proto.__name__} but does not define {name}")
            if defined and not declared:
                raise TypeError(f"{cls.__name__} defines {name} but does not declare safepg.tasks.{proto.__name__}: "
                                f"inherit it so that it is read")


def constants_settings(task: object) -> ConstantsSettingValues:
    """How the bound constants are written for ``task``: its :class:`ConstantsSettings` if it
    declares them, else :data:`DEFAULT_CONSTANTS_SETTINGS`.

    The one reader of ``horizon_term`` and ``constants_gamma``; the values themselves are
    checked where they are used (:class:`~safepg.constants.TaskConstants`).

    Raises
    ------
    TypeError
        The task defines ``horizon_term`` or ``constants_gamma`` without declaring
        :class:`ConstantsSettings`, or declares it without defining both (a misspelt name).
    """
    _check_values(task)
    if ConstantsSettings not in type(task).__mro__:
        return DEFAULT_CONSTANTS_SETTINGS
    declared = cast(ConstantsSettings, task)  # checked above: the class inherits it and defines both
    return ConstantsSettingValues(declared.horizon_term, declared.constants_gamma)


def declares(cls: type, proto: type, name: str) -> bool:
    """Whether ``cls`` declares the one-method Protocol ``proto`` (inherits it and defines ``name``).

    Raises
    ------
    TypeError
        ``cls`` declares ``proto`` without defining ``name``, defines ``name`` without declaring
        ``proto`` (a hook that would otherwise be used, or skipped, in silence), or defines it
        with other parameters than ``proto``.
    """
    declared = proto in cls.__mro__
    method = getattr(cls, name, None)
    if declared and (method is None or method is getattr(proto, name)):
        raise TypeError(f"{cls.__name__} declares {proto.__name__} but does not define {name}")
    if not declared and method is not None:
        raise TypeError(f"{cls.__name__} defines {name} but does not declare safepg.tasks.{proto.__name__}: "
                        f"inherit it so that it is used")
    if declared:
        _check_signature(cls, proto, name)
    return declared


def task_hooks(task: Task) -> Hooks:
    """Check ``task``'s declared fast paths and settings, and return the fast paths bound.

    Raises
    ------
    TypeError
        A declared hook is missing or takes other parameters than its Protocol, or the task
        has a method or value named like a hook without declaring its Protocol.
    """
    cls = type(task)
    for attr in ("simulate", "reward_bound", "feature_bound", "action_volume", "action_bound", "gamma", "horizon"):
        if not hasattr(task, attr):
            raise TypeError(f"task must have {attr!r} (safepg.tasks.Task), {cls.__name__} has not")
    _check_values(task)
    found: dict[str, Any] = {}
    for proto, name in METHOD_HOOKS.items():
        if declares(cls, proto, name):
            found[name] = getattr(task, name)
    action_dim = 1
    if ActionDimension in cls.__mro__:
        action_dim = cast(ActionDimension, task).action_dim  # declared: the class inherits it
        if isinstance(action_dim, bool) or not isinstance(action_dim, int | np.integer) or action_dim < 1:
            raise TypeError(f"{cls.__name__}.action_dim must be an integer >= 1, got {action_dim!r}")
    return Hooks(**{name: found.get(name) for name in METHOD_HOOKS.values()}, action_dim=int(action_dim))


__all__ = ["DEFAULT_CONSTANTS_SETTINGS", "METHOD_HOOKS", "VALUE_HOOKS", "ActionDimension", "BoundedTask",
           "ConstantsSettingValues", "ConstantsSettings", "Definition", "FixedStepBatches", "FromDefinition",
           "GradientBatch", "GradientBatchConstants", "Hooks", "MeasuredReturns", "Performance", "PerformanceBatch",
           "Task", "constants_settings", "declares", "task_hooks"]
