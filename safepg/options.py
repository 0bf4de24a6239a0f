r"""The options of the learning loops, one frozen object per concept.

Algorithm 4.1 (:func:`safepg.learning.adaptive_pg`) is set by four objects:

* :class:`Gradient`: how each trajectory's gradient sample is computed (REINFORCE or
  G(PO)MDP, the baseline, which action the score is taken at);
* :class:`ErrorModel`: the bound on the estimation error, :math:`\epsilon = d_\delta/\sqrt N +
  f_\delta/N` (Chebyshev, Hoeffding or Bernstein), its :math:`\delta` and the gradient's range;
* :class:`Batches`: :math:`N_{min}`, :math:`N_{max}` and the first batch size;
* :class:`Departures`: the authors' departures from Algorithm 4.1 (their scripts did what the
  theorems do not allow), each off by default.

The fixed-batch loop (:func:`safepg.learning.vanilla_pg`) takes its step as a
:class:`FixedStep` or a :class:`SafeStep`, and an optional :class:`Target`. :class:`Adaptive`
and :class:`Vanilla` hold a whole method, as a :class:`~safepg.runner.RunConfig` stores it.

Every object checks its own values when it is built, with a message naming the field.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

from safepg.bounds import BOUNDS, Bound, Range, check_delta, check_range
from safepg.estimators import Estimator, ScoreAction, check_estimator, check_score_action

#: A step applied to all components (``"scalar"``) or to the largest one only (``"coordinate"``).
StepKind = Literal["scalar", "coordinate"]


def _check_choice(name: str, value: object, choices: tuple[object, ...]) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in choices)}, got {value!r}")


def _check_flag(name: str, value: object) -> None:
    if not isinstance(value, bool):
        raise ValueError(f"{name} must be True or False, got {value!r}")


def _check_size(name: str, value: object, low: int = 2) -> None:
    # numbers.Real: NumPy's integers too (a size read off an array), which int | float does not admit.
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not float(value).is_integer() or value < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")


@dataclass(frozen=True)
class Gradient:
    """How a batch's gradient samples are computed (Section 3.3).

    Parameters
    ----------
    estimator : {"gpomdp", "reinforce"}
        G(PO)MDP or REINFORCE.
    baseline : bool
        Subtract the variance-minimising baseline (else b = 0).
    score_action : {"clipped", "raw"}
        The score at the action the task applied after clipping (the authors' code) or at the
        sampled action (the unbiased score).
    """

    estimator: Estimator = "gpomdp"
    baseline: bool = True
    score_action: ScoreAction = "clipped"

    def __post_init__(self) -> None:
        check_estimator(self.estimator)
        _check_flag("baseline", self.baseline)
        check_score_action(self.score_action)


@dataclass(frozen=True)
class ErrorModel:
    r"""The bound :math:`\epsilon` on the gradient estimate's error (Section 4.3).

    With probability at least :math:`1 - \delta`, :math:`|\hat\nabla_k J - \nabla_k J| \le
    \epsilon = d_\delta/\sqrt N + f_\delta/N`.

    Parameters
    ----------
    bound : {"chebyshev", "hoeffding", "bernstein"}
        The concentration inequality.
    delta : float
        The probability of a worsening update, in (0, 1).
    range : "lemma", "empirical" or float
        The gradient's range in Hoeffding's and Bernstein's bounds: Lemma 4.3.3's bound, the
        batch's own max - min (the thesis's "empirical range"), or a given number. Chebyshev
        uses no range.
    """

    bound: Bound = "chebyshev"
    delta: float = 0.95
    range: Range = "lemma"

    def __post_init__(self) -> None:
        _check_choice("bound", self.bound, BOUNDS)
        check_delta(self.delta)
        check_range(self.range)

    @property
    def empirical_range(self) -> bool:
        """Whether the range is the batch's own max - min."""
        return self.range == "empirical"

    @property
    def theoretical_range(self) -> float | None:
        """The given range, or None for Lemma 4.3.3's (and for the empirical range)."""
        return None if isinstance(self.range, str) else float(self.range)


@dataclass(frozen=True)
class Batches:
    """The batch sizes Algorithm 4.1 may choose.

    Parameters
    ----------
    n_min, n_max : int
        The limits :math:`N_{min} \\le N \\le N_{max}` the bound's :math:`N^*` is clipped to.
    first : int or None
        The first batch's size, which no bound chooses: None for :math:`N_{min}` (the
        algorithm); the authors hard-coded 100 in 2-D and 1000 on the cart-pole.
    """

    n_min: int = 100
    n_max: int = 500_000
    first: int | None = None

    def __post_init__(self) -> None:
        _check_size("n_min", self.n_min)
        _check_size("n_max", self.n_max)
        if self.n_min > self.n_max:
            raise ValueError(f"n_min must be <= n_max, got n_min={self.n_min} > n_max={self.n_max}")
        if self.first is not None:
            _check_size("first", self.first)

    @property
    def first_size(self) -> int:
        """The first batch's size (:math:`N_{min}` unless ``first`` is given)."""
        return self.n_min if self.first is None else int(self.first)


class Assumption(NamedTuple):
    """One assumption of Theorem 4.2.3 / Corollary 4.2.8 and whether a setting keeps it."""

    assumption: str
    holds: bool
    why: str


@dataclass(frozen=True)
class Departures:
    r"""The authors' departures from Algorithm 4.1, each False by default (the algorithm).

    Their 2-D and cart-pole scripts ran the adaptive method otherwise than the theorems
    allow; each departure is a switch, to reproduce their runs.

    Parameters
    ----------
    batch_constants : bool
        R and :math:`M_\phi` measured on each batch (the largest |reward| and |feature|)
        instead of the task's bounds (Assumption 4.2.1), so the penalty constant c changes
        from batch to batch (the authors' cart-pole script).
    maxima : bool
        The largest sample variance and range over all components instead of those of the
        component k that moves (the authors' 2-D and cart-pole scripts).
    unguarded_step : bool
        Take the step of Corollary 4.2.8's formula even when :math:`\epsilon \ge |\hat g_k|`
        (the authors' scripts); the algorithm does not move then.
    """

    batch_constants: bool = False
    maxima: bool = False
    unguarded_step: bool = False

    def __post_init__(self) -> None:
        for name in ("batch_constants", "maxima", "unguarded_step"):
            _check_flag(name, getattr(self, name))

    def changed(self) -> tuple[str, ...]:
        """The names of the departures taken, in the order of the fields."""
        return tuple(name for name in ("batch_constants", "maxima", "unguarded_step") if getattr(self, name))

    def assumptions(self) -> tuple[Assumption, Assumption, Assumption]:
        """The three assumptions the departures decide: c from the task's bounds, the step only
        where :math:`\\epsilon < |\\hat g_k|`, and a per-component :math:`\\epsilon`."""
        return (
            Assumption("c from bounds of |r| and |phi| (Assumption 4.2.1)", not self.batch_constants,
                       "R and M_phi are measured on each batch, so c changes with the batch" if self.batch_constants
                       else "R and M_phi are the task's bounds"),
            Assumption("step only where eps < |g_k| (Assumption 4.2.7)", not self.unguarded_step,
                       "the step formula is applied even when eps >= |g_k|" if self.unguarded_step
                       else "no step when eps >= |g_k|"),
            Assumption("eps a per-component error bound", not self.maxima,
                       "the largest variance and range over the components" if self.maxima
                       else "variance and range of component k"),
        )


@dataclass(frozen=True)
class FixedStep:
    r"""A fixed step size :math:`\alpha`.

    Parameters
    ----------
    alpha : float
        The step size, finite and >= 0.
    kind : {"scalar", "coordinate"}
        :math:`\theta \leftarrow \theta + \alpha\hat\nabla J` (``"scalar"``), or only the
        largest component moves, by :math:`\alpha \hat g_k` (``"coordinate"``, the authors'
        cart-pole "vanilla" method).
    """

    alpha: float
    kind: StepKind = "scalar"

    def __post_init__(self) -> None:
        if isinstance(self.alpha, bool) or not isinstance(self.alpha, int | float) or not (
                math.isfinite(self.alpha) and self.alpha >= 0):
            raise ValueError(f"alpha must be finite and >= 0, got {self.alpha!r}")
        _check_choice("kind", self.kind, ("scalar", "coordinate"))


@dataclass(frozen=True)
class SafeStep:
    r"""The step that guarantees improvement with probability :math:`1 - \delta` at a fixed N.

    ``kind="scalar"`` is the scalar step of Pirotta et al. (2013); ``"coordinate"`` the coordinate step
    :math:`\Lambda^*` of Corollary 4.2.8 (Section 5.2.1 compares them, Figures 5.5-5.6). One
    :math:`\epsilon` serves all components: the largest per-component bound.

    Parameters
    ----------
    kind : {"scalar", "coordinate"}
        The scalar step of Pirotta et al. (2013) or the coordinate step.
    error : ErrorModel
        The bound :math:`\epsilon` is computed with.
    """

    kind: StepKind = "coordinate"
    error: ErrorModel = field(default_factory=ErrorModel)

    def __post_init__(self) -> None:
        _check_choice("kind", self.kind, ("scalar", "coordinate"))
        if not isinstance(self.error, ErrorModel):
            raise TypeError(f"error must be an ErrorModel, got {self.error!r}")


@dataclass(frozen=True)
class Target:
    """Stop at the first batch whose mean measured return reaches ``value``.

    The protocol that learns the cart-pole's baseline policy (Section 5.3: "we stop once an
    average performance of 195 over the batch is achieved").

    Parameters
    ----------
    value : float
        The target mean return of a batch.
    update : bool
        Whether the batch that reaches it still updates theta (the authors' baseline script:
        its saved policy is one update past that batch); by default theta stays.
    """

    value: float
    update: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.value, bool) or not isinstance(self.value, int | float) or not math.isfinite(self.value):
            raise ValueError(f"target value must be a finite number, got {self.value!r}")
        _check_flag("update", self.update)


@dataclass(frozen=True)
class Adaptive:
    """Algorithm 4.1 (adaptive step and batch size), as :func:`~safepg.learning.adaptive_pg` runs it.

    Parameters
    ----------
    gradient : Gradient
        Estimator, baseline and score.
    error : ErrorModel
        The bound, delta and the gradient's range.
    batches : Batches
        N_min, N_max and the first batch.
    departures : Departures
        The authors' departures from the algorithm (none by default).
    """

    gradient: Gradient = field(default_factory=Gradient)
    error: ErrorModel = field(default_factory=ErrorModel)
    batches: Batches = field(default_factory=Batches)
    departures: Departures = field(default_factory=Departures)

    def __post_init__(self) -> None:
        for name, kind in (("gradient", Gradient), ("error", ErrorModel), ("batches", Batches),
                           ("departures", Departures)):
            if not isinstance(getattr(self, name), kind):
                article = "an" if kind.__name__[0] in "AEIOU" else "a"
                raise TypeError(f"{name} must be {article} {kind.__name__}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class Vanilla:
    """Policy gradient with a fixed batch size, as :func:`~safepg.learning.vanilla_pg` runs it.

    Parameters
    ----------
    batch_size : int
        Trajectories per iteration, >= 2.
    step : FixedStep or SafeStep
        The step (default: a fixed scalar step of 1e-3).
    gradient : Gradient
        Estimator, baseline and score.
    target : Target or None
        Stop once a batch's mean return reaches a target (the cart-pole's baseline search).
    """

    batch_size: int
    step: FixedStep | SafeStep = field(default_factory=lambda: FixedStep(1e-3))
    gradient: Gradient = field(default_factory=Gradient)
    target: Target | None = None

    def __post_init__(self) -> None:
        _check_size("batch_size", self.batch_size)
        if not isinstance(self.step, FixedStep | SafeStep):
            raise TypeError(f"step must be a FixedStep or a SafeStep, got {self.step!r}")
        if not isinstance(self.gradient, Gradient):
            raise TypeError(f"gradient must be a Gradient, got {self.gradient!r}")
        if self.target is not None and not isinstance(self.target, Target):
            raise TypeError(f"target must be a Target or None, got {self.target!r}")


#: A learning method as a run stores it.
Method = Adaptive | Vanilla

__all__ = ["Adaptive", "Assumption", "Batches", "Departures", "ErrorModel", "FixedStep", "Gradient", "Method",
           "SafeStep", "StepKind", "Target", "Vanilla"]
