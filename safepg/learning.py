r"""Learning loops of Chapter 5: Algorithm 4.1 (adaptive step and batch size) and
vanilla policy gradient with a fixed batch size.

:func:`learn` runs either method (an :class:`~safepg.options.Adaptive` or a
:class:`~safepg.options.Vanilla`); :func:`adaptive_pg` and :func:`vanilla_pg` build the method
from their options and call it. Each returns a :class:`~safepg.record.LearningRecord` of
per-iteration arrays. Iteration i collects ``batch_size[i]`` trajectories with the policy
``theta[i]`` and moves to ``theta[i+1]``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from safepg.bounds import ErrorBound, error_bound
from safepg.constants import TaskConstants
from safepg.definition import run_definition
from safepg.estimators import gradient_samples
from safepg.meta import coordinate_step, optimal_batch_size, penalty_constant, scalar_step
from safepg.numpy_order import all_finite, column_means, pairwise_sum, sample_range, sample_variance
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.record import CHECKPOINTS, LearningRecord, RecordFileError
from safepg.rng import RNGLike, as_generator
from safepg.streams import batch_keys
from safepg.tasks import Hooks, Task, task_hooks
from safepg.trajectories import Trajectories


@dataclass(frozen=True)
class _Update:
    delta_theta: np.ndarray
    alpha: float
    coordinate: int
    eps: float
    safe: bool
    next_n: int


#: (samples (n, m), their mean, n, the batch's measured (R, M_phi) or None) -> the update.
#: The loop computes the mean once.
_UpdateRule = Callable[[np.ndarray, np.ndarray, int, "tuple[float, float] | None"], _Update]
#: ``progress`` of the learning loops: True for a tqdm bar, or a callable ``report(used, budget)``.
Progress = bool | Callable[[int, int], object]


def _closed_form(hooks: Hooks, thetas: np.ndarray, sigma: float) -> np.ndarray:
    """J(theta_i) for every row of ``thetas``; NaN for a task without a closed form."""
    if hooks.performance_batch is not None:
        return np.asarray(hooks.performance_batch(thetas, sigma), dtype=float)
    if hooks.performance is None:
        return np.full(len(thetas), np.nan)
    return np.array([hooks.performance(theta, sigma) for theta in thetas], dtype=float)


def _collect(
    task: Task, hooks: Hooks, policy: LinearGaussianPolicy, n: int, rng: np.random.Generator, gradient: Gradient,
    batch_constants: bool = False,
) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None]:
    """Gradient samples (n, m), measured returns (n,) and, with ``batch_constants``, the batch's
    measured (R, M_phi) (else None) of a fresh batch.

    Uses the task's fused ``gradient_batch`` when it has one (the LQG and the cart-pole
    do), else simulates the batch and applies :func:`safepg.estimators.gradient_samples`.
    The measured return is the task's ``measured_returns(batch)`` if it defines one (the
    cart-pole: the undiscounted episode length the thesis reports), else the discounted
    return. With ``batch_constants``: the task's ``gradient_batch_constants`` if it has one (the
    cart-pole), else the largest |reward| and |feature| of the simulated batch's live steps.
    """
    how = (gradient.estimator, gradient.baseline, gradient.score_action)
    if batch_constants:
        if hooks.gradient_batch_constants is not None:
            return hooks.gradient_batch_constants(policy, n, rng, *how)
    elif hooks.gradient_batch is not None:
        return (*hooks.gradient_batch(policy, n, rng, *how), None)
    batch = task.simulate(policy, n, rng)
    measured = hooks.measured_returns or Trajectories.discounted_returns
    found = None
    if batch_constants:
        live = np.ones(batch.rewards.shape, dtype=bool) if batch.mask is None else batch.mask.astype(bool)
        found = (float(np.abs(batch.rewards[live]).max()), float(np.abs(batch.features[live]).max()))
    return gradient_samples(policy, batch, *how), measured(batch), found


def _check_budget(budget: int, n_first: int) -> None:
    if int(budget) != budget or budget < n_first:
        raise ValueError(f"budget must be an integer >= the first batch size {n_first}, got {budget}")


def _batch_means(samples: np.ndarray, returns: np.ndarray, n: int) -> tuple[np.ndarray, float]:
    """``samples.sum(axis=0) / n`` and ``returns.sum() / n``, NumPy's bits (:mod:`safepg.numpy_order`):
    compiled for the kernels' C-ordered float arrays, NumPy itself for any other layout, whose order
    it would change. A run with N = 100 has 3*10^5 iterations; NumPy's call costs 30 us at N = 2000."""
    if samples.dtype == np.float64 and samples.ndim == 2 and samples.flags.c_contiguous:
        grad = column_means(samples, n)
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # a non-finite mean is handled by the caller
            grad = samples.sum(axis=0) / n
    if returns.dtype == np.float64 and returns.ndim == 1 and returns.flags.c_contiguous:
        return grad, float(pairwise_sum(returns) / n)
    return grad, float(returns.sum() / n)


def _spread(bound: str, range_: Any, x: np.ndarray) -> dict[str, float]:
    """The sample statistics :func:`~safepg.bounds.error_bound` would compute from component ``x``,
    computed here in NumPy's order (the same bits, without NumPy's call overhead): Bernstein's sample
    variance, the empirical range."""
    out = {}
    if bound == "bernstein":
        out["variance"] = float(sample_variance(x))
    if bound != "chebyshev" and range_ == "empirical":
        out["sample_range"] = float(sample_range(x))
    return out


def _not_finite(theta: np.ndarray, grad: np.ndarray) -> ValueError:
    return ValueError(f"gradient estimate is not finite at theta={theta.tolist()}: {grad}")


def _learn(
    task: Task,
    hooks: Hooks,
    policy: LinearGaussianPolicy,
    rule: _UpdateRule,
    n_first: int,
    budget: int,
    rng: RNGLike,
    gradient: Gradient,
    config: dict[str, Any],
    progress: Progress,
    stop_on_divergence: bool = False,
    target: Target | None = None,
    batch_constants: bool = False,
) -> LearningRecord:
    rng = as_generator(rng)
    theta = policy.theta
    thetas = [theta.copy()]
    rows: dict[str, list[Any]] = {k: [] for k in ("batch_size", "alpha", "coordinate", "J_hat", "grad", "eps", "safe")}
    used, n = 0, n_first
    interrupted = diverged = reached = False
    # A callable replaces the bar (a caller that draws its own progress wants no tqdm output).
    report = progress if callable(progress) else None
    bar = tqdm(total=budget, unit="traj", disable=report is not None or not progress, leave=False,
               dynamic_ncols=True)
    try:
        while True:
            # The last batch is cut to the remaining budget, so a run uses exactly `budget`.
            n = min(n, budget - used)
            if n < 2:
                break
            samples, returns, found = _collect(task, hooks, policy, n, rng, gradient, batch_constants)
            # sum / n is what ndarray.mean computes (same bits), without its Python overhead.
            grad, J_hat = _batch_means(samples, returns, n)
            if not all_finite(grad):
                if stop_on_divergence:
                    diverged = True
                    break
                raise _not_finite(theta, grad)
            reached = target is not None and J_hat >= target.value
            if reached and not (target is not None and target.update):
                # The policy that produced this batch is the result: record the batch, keep theta.
                up = _Update(np.zeros_like(grad), 0.0, -1, 0.0, True, n)
            else:
                up = rule(samples, grad, n, found)
            theta = theta + up.delta_theta
            policy = policy.with_theta(theta)
            used += n
            for k, v in (("batch_size", n), ("alpha", up.alpha), ("coordinate", up.coordinate),
                         ("J_hat", J_hat), ("grad", grad),
                         ("eps", up.eps), ("safe", up.safe)):
                rows[k].append(v)
            thetas.append(theta.copy())
            bar.update(n)
            if report is not None:
                # Once per batch, after the batch is recorded: whatever it raises (a caller's
                # cancellation) leaves this loop through the `finally` below and propagates.
                report(used, budget)
            if reached:
                break
            n = up.next_n
    except KeyboardInterrupt:
        interrupted = True
        warnings.warn(f"interrupted after {used} trajectories; returning the partial record", stacklevel=2)
    finally:
        bar.close()
    return _record(hooks, policy.sigma, np.asarray(thetas, dtype=float).reshape(-1, theta.size), rows, config,
                   interrupted=interrupted, diverged=diverged, reached_target=reached)


def _record(hooks: Hooks, sigma: float, thetas: np.ndarray, rows: dict[str, Any], config: dict[str, Any],
            **ended: bool) -> LearningRecord:
    """The record of a run from its parameters (b + 1, m) and its per-batch ``rows``."""
    return LearningRecord(
        batch_size=np.asarray(rows["batch_size"], dtype=np.int64),
        alpha=np.asarray(rows["alpha"], dtype=float),
        coordinate=np.asarray(rows["coordinate"], dtype=np.int64),
        theta=thetas,
        J=_closed_form(hooks, thetas, sigma),
        J_hat=np.asarray(rows["J_hat"], dtype=float),
        grad=np.asarray(rows["grad"], dtype=float).reshape(-1, thetas.shape[1]),
        eps=np.asarray(rows["eps"], dtype=float),
        safe=np.asarray(rows["safe"], dtype=bool),
        config=config,
        **ended,
    )


#: Trajectories per call of a task's ``fixed_step_batches``: between calls the progress bar moves
#: and an interruption is taken (a call takes about 0.05 s on the LQG).
FUSED_TRAJECTORIES = 2**18


def _learn_fixed_step(
    hooks: Hooks,
    policy: LinearGaussianPolicy,
    method: Vanilla,
    budget: int,
    rng: RNGLike,
    config: dict[str, Any],
    progress: bool,
    stop_on_divergence: bool,
) -> LearningRecord:
    """:func:`_learn` for a fixed step and no target, through the task's ``fixed_step_batches``:
    the same batches (one key each from ``rng``, drawn a group at a time), steps and record."""
    assert hooks.fixed_step_batches is not None and isinstance(method.step, FixedStep)
    rng = as_generator(rng)
    n, step, gradient = method.batch_size, method.step, method.gradient
    how = (gradient.estimator, gradient.baseline, gradient.score_action)
    # As in _learn: batches of n, the last one cut to what remains of the budget if that is >= 2.
    sizes = np.full(budget // n, n, dtype=np.int64)
    if budget % n >= 2:
        sizes = np.append(sizes, budget % n)
    thetas, grads, j_hats = [policy.theta[None, :]], [], []
    used = 0
    interrupted = diverged = False
    bar = tqdm(total=budget, unit="traj", disable=not progress, leave=False, dynamic_ncols=True)
    per_call = max(1, FUSED_TRAJECTORIES // n)
    try:
        for lo in range(0, sizes.size, per_call):
            group = sizes[lo:lo + per_call]
            th, g, j_hat = hooks.fixed_step_batches(policy, group, batch_keys(rng, group.size), step.alpha, step.kind,
                                                    *how)
            if not np.all(np.isfinite(g[-1])):
                if not stop_on_divergence:
                    raise _not_finite(th[-1], g[-1])
                diverged = True
                g, j_hat = g[:-1], j_hat[:-1]
            else:  # refuses non-finite parameters, as in the Python loop
                policy = policy.with_theta(th[-1])
            thetas.append(th[1:])
            grads.append(g)
            j_hats.append(j_hat)
            done = int(group[:j_hat.size].sum())
            used += done
            bar.update(done)
            if diverged:
                break
    except KeyboardInterrupt:
        interrupted = True
        warnings.warn(f"interrupted after {used} trajectories; returning the partial record", stacklevel=2)
    finally:
        bar.close()
    grad = np.concatenate([np.empty((0, policy.theta.size)), *grads])
    b = grad.shape[0]
    # The rule's k: the first largest |component| moves ("coordinate"); -1 when all of them do.
    coordinate = np.argmax(np.abs(grad), axis=1) if step.kind == "coordinate" else np.full(b, -1)
    rows = {"batch_size": sizes[:b], "alpha": np.full(b, float(step.alpha)), "coordinate": coordinate,
            "J_hat": np.concatenate([[], *j_hats]), "grad": grad, "eps": np.zeros(b), "safe": np.ones(b, dtype=bool)}
    return _record(hooks, policy.sigma, np.concatenate(thetas), rows, config, interrupted=interrupted,
                   diverged=diverged, reached_target=False)


def _initial_policy(hooks: Hooks, theta0: np.ndarray | float, sigma: float | np.ndarray) -> LinearGaussianPolicy:
    theta0 = np.asarray(theta0, dtype=float)
    d_a = hooks.action_dim
    if theta0.ndim <= 1:
        theta0 = np.broadcast_to(theta0, (theta0.size,)) if theta0.ndim == 1 else theta0.reshape(1)
        m = theta0.size
        if m % d_a:
            raise ValueError(f"theta0 must have a multiple of {d_a} entries, got {m}")
        theta0 = theta0.reshape(d_a, m // d_a)
    return LinearGaussianPolicy(theta0, sigma)


def _adaptive_rule(method: Adaptive, constants: TaskConstants, c_bounds: float) -> _UpdateRule:
    """Algorithm 4.1's update with ``method``'s options.

    Parameters
    ----------
    method : Adaptive
        The bound, the batch-size limits and the departures the update follows.
    constants : TaskConstants
        The task's bound constants at the policy's sigma.
    c_bounds : float
        The penalty constant of ``constants``.

    Returns
    -------
    callable
        The rule :func:`_learn` applies to each batch: Corollary 4.2.8's step on the largest
        gradient component and the next batch size N* (Theorem 4.3.2) in [n_min, n_max].
    """
    gradient, error, batches, departures = method.gradient, method.error, method.batches, method.departures

    def rule(samples: np.ndarray, grad: np.ndarray, n: int, found: tuple[float, float] | None) -> _Update:
        k = int(np.argmax(np.abs(grad)))
        g = float(abs(grad[k]))
        batch_constants, c = constants, c_bounds
        if found is not None:  # departures.batch_constants: this batch's R and M_phi
            batch_constants = replace(constants, R=found[0], M_phi=found[1])
            c = penalty_constant(batch_constants)
        if departures.maxima:
            spread = dict(variance=float(np.var(samples, axis=0, ddof=1).max()),
                          sample_range=float(np.ptp(samples, axis=0).max()))
        else:
            spread = _spread(error.bound, error.range, samples[:, k])
        eb: ErrorBound = error_bound(error.bound, samples[:, k], error.delta, batch_constants, gradient.estimator,
                                     error.range, **spread)
        eps = float(eb.eps(n))
        alpha = coordinate_step(g, eps, c, guarded=not departures.unguarded_step)
        step = np.zeros_like(grad)
        step[k] = alpha * grad[k]
        return _Update(step, alpha, k, eps, eps < g, optimal_batch_size(g, eb, c, batches.n_min, batches.n_max))

    return rule


def _vanilla_rule(method: Vanilla, constants: TaskConstants, c: float) -> _UpdateRule:
    """The update of policy gradient with ``method``'s fixed batch size and step.

    Parameters
    ----------
    method : Vanilla
        The batch size, the step and the estimator.
    constants : TaskConstants
        The task's bound constants at the policy's sigma (a :class:`~safepg.options.SafeStep`'s bound).
    c : float
        The penalty constant of ``constants``.

    Returns
    -------
    callable
        The rule :func:`_learn` applies to each batch: a fixed step, or the safe step of
        Pirotta et al. (2013) / Corollary 4.2.8 with one eps for all components.
    """
    batch_size, step, gradient = method.batch_size, method.step, method.gradient

    def rule(samples: np.ndarray, grad: np.ndarray, n: int, found: tuple[float, float] | None) -> _Update:
        k = int(np.argmax(np.abs(grad)))
        if isinstance(step, FixedStep):
            eps, safe, a = 0.0, True, step.alpha
        else:
            e = step.error
            # One common eps for all components: the largest per-component bound.
            eps = max(float(error_bound(e.bound, samples[:, i], e.delta, constants, gradient.estimator,
                                        e.range, **_spread(e.bound, e.range, samples[:, i])).eps(n))
                      for i in range(grad.size))
            safe = eps < abs(grad[k])
            a = scalar_step(grad, eps, c) if step.kind == "scalar" else coordinate_step(abs(grad[k]), eps, c)
        if step.kind == "scalar":
            return _Update(a * grad, a, -1, eps, safe, batch_size)
        d = np.zeros_like(grad)
        d[k] = a * grad[k]
        return _Update(d, a, k, eps, safe, batch_size)

    return rule


def learn(task: Task, method: Adaptive | Vanilla, theta0: np.ndarray | float = 0.0, sigma: float = 1.0, *,
          budget: int, rng: RNGLike = None, progress: Progress = False,
          stop_on_divergence: bool = False) -> LearningRecord:
    """Run ``method`` on ``task``: Algorithm 4.1 for an :class:`~safepg.options.Adaptive`
    (:func:`adaptive_pg`), policy gradient with a fixed batch size for a
    :class:`~safepg.options.Vanilla` (:func:`vanilla_pg`).

    Both loops are this function: :func:`adaptive_pg` and :func:`vanilla_pg` build the method
    from their options and call it, so a method gives the same record however it is run. Both
    have the same divergence behaviour: raise ``ValueError``, or with ``stop_on_divergence``
    end the run with ``diverged`` set (a campaign's runs do: :class:`safepg.runner.RunConfig`).

    Parameters
    ----------
    task : Task
        As in :func:`adaptive_pg`.
    method : Adaptive or Vanilla
        The method with all its options.
    theta0, sigma, budget, rng, progress, stop_on_divergence
        As in :func:`adaptive_pg`.

    Returns
    -------
    LearningRecord
        The per-iteration arrays; ``config`` holds the run's definition
        (:func:`safepg.definition.run_definition`) and ``config["c"]``, the penalty constant
        from the task's bounds.

    Raises
    ------
    TypeError
        ``method`` is neither an Adaptive nor a Vanilla, or the task's declared fast paths
        are malformed (:func:`safepg.tasks.task_hooks`).
    ValueError
        A bad ``budget``, ``theta0`` or ``sigma``, or (without ``stop_on_divergence``) a
        gradient estimate that is not finite.
    """
    # The method's type first: the budget is checked against its first batch.
    if isinstance(method, Adaptive):
        first = method.batches.first_size
    elif isinstance(method, Vanilla):
        first = method.batch_size
    else:
        raise TypeError(f"method must be an Adaptive or a Vanilla, got {method!r}")
    _check_budget(budget, first)
    hooks = task_hooks(task)
    policy = _initial_policy(hooks, theta0, sigma)
    constants = TaskConstants.from_task(task, policy.sigma)
    c = penalty_constant(constants)
    config = {**run_definition(task, method, theta0, sigma, budget, stop_on_divergence, exact=False), "c": c}
    if isinstance(method, Adaptive):
        return _learn(task, hooks, policy, _adaptive_rule(method, constants, c), first, budget, rng, method.gradient,
                      config, progress, stop_on_divergence, batch_constants=method.departures.batch_constants)
    # A callable progress is called after each batch: only the Python loop stops there.
    fused = isinstance(method.step, FixedStep) and method.target is None and not callable(progress)
    if fused and hooks.fixed_step_batches is not None:
        return _learn_fixed_step(hooks, policy, method, budget, rng, config, bool(progress), stop_on_divergence)
    return _learn(task, hooks, policy, _vanilla_rule(method, constants, c), first, budget, rng, method.gradient,
                  config, progress, stop_on_divergence, method.target)


def adaptive_pg(
    task: Task,
    theta0: np.ndarray | float = 0.0,
    sigma: float = 1.0,
    *,
    gradient: Gradient = Gradient(),
    error: ErrorModel = ErrorModel(),
    batches: Batches = Batches(),
    departures: Departures = Departures(),
    budget: int = 30_000_000,
    rng: RNGLike = None,
    progress: Progress = False,
    stop_on_divergence: bool = False,
) -> LearningRecord:
    r"""Adaptive policy gradient, Algorithm 4.1 (as corrected in the book's errata).

    Each iteration collects N trajectories, estimates the gradient, picks
    :math:`k = \arg\max_i|\hat\nabla_{\theta_i}J|`, computes
    :math:`\epsilon = d_\delta/\sqrt N + f_\delta/N` from the chosen bound on component k,
    moves :math:`\theta_k` by the step of Corollary 4.2.8, and sets the next batch size to
    N* (Theorem 4.3.2, or the search of Section 4.3.3 for Bernstein) clipped to
    [n_min, n_max]. The first batch has n_min trajectories (``batches.first`` to change it).

    The same run as ``learn(task, Adaptive(gradient, error, batches, departures), theta0, sigma,
    ...)``, which this function calls (:func:`learn`).

    Parameters
    ----------
    task : Task
        An environment with ``simulate`` and the bound constants (e.g. :class:`~safepg.envs.LQG`);
        its fast paths (:mod:`safepg.tasks`) are checked when the loop starts.
    theta0 : ndarray or float
        Initial parameters (flat vector or gain matrix).
    sigma : float
        Policy standard deviation.
    gradient : Gradient
        Estimator, baseline and score (:class:`~safepg.options.Gradient`).
    error : ErrorModel
        The bound, delta and gradient range (:class:`~safepg.options.ErrorModel`).
    batches : Batches
        N_min, N_max and the first batch (:class:`~safepg.options.Batches`).
    departures : Departures
        The authors' departures from the algorithm, none by default
        (:class:`~safepg.options.Departures`).
    budget : int
        Total number of trajectories.
    rng : int, Generator or None
        Seed or Generator.
    progress : bool or callable
        True shows a tqdm bar; a callable ``progress(used, budget)`` is called instead
        after each batch with the trajectories used so far. An exception it raises stops
        the run and propagates to the caller, with no record: how a caller running the loop
        in a thread cancels it (one call per batch, so cancelling waits for one batch).
    stop_on_divergence : bool
        When a gradient estimate is not finite, end the run and return its record with
        ``diverged`` set, instead of raising ``ValueError``.

    Returns
    -------
    LearningRecord
        As :func:`learn` returns it.
    """
    # Building the method checks each option's type, before anything else is looked at.
    return learn(task, Adaptive(gradient, error, batches, departures), theta0, sigma, budget=budget, rng=rng,
                 progress=progress, stop_on_divergence=stop_on_divergence)


def vanilla_pg(
    task: Task,
    theta0: np.ndarray | float = 0.0,
    sigma: float = 1.0,
    *,
    batch_size: int = 100,
    step: FixedStep | SafeStep = FixedStep(1e-3),
    gradient: Gradient = Gradient(),
    target: Target | None = None,
    budget: int = 1_000_000,
    rng: RNGLike = None,
    progress: Progress = False,
    stop_on_divergence: bool = False,
) -> LearningRecord:
    r"""Policy gradient with a fixed batch size.

    With a :class:`~safepg.options.FixedStep`: :math:`\theta \leftarrow \theta +
    \alpha\hat\nabla J` (``kind="scalar"``) or only the largest component moves
    (``kind="coordinate"``). With a :class:`~safepg.options.SafeStep` the step is adaptive,
    using the bound's eps at the fixed N: the scalar step of Pirotta et al. (2013) (``"scalar"``) or the
    coordinate step Lambda* of Corollary 4.2.8 (``"coordinate"``), as compared in Section
    5.2.1 (Figures 5.5-5.6). A fixed step can make theta diverge until the gradient
    overflows: with ``stop_on_divergence=True`` the run then ends and the record says so
    (``diverged``), instead of raising.

    A fixed step without a target runs in the task's compiled loop when it has one
    (:class:`~safepg.tasks.FixedStepBatches`, as the LQG does), with the same numbers; a
    callable ``progress``, which is called after every batch, keeps the loop in Python.

    The same run as ``learn(task, Vanilla(batch_size, step, gradient, target), theta0, sigma,
    ...)``, which this function calls (:func:`learn`).

    Parameters
    ----------
    task : Task
        As in :func:`adaptive_pg`.
    theta0 : ndarray or float
        Initial parameters (flat vector or gain matrix).
    sigma : float
        Policy standard deviation.
    batch_size : int
        Trajectories per iteration.
    step : FixedStep or SafeStep
        The step (:class:`~safepg.options.FixedStep`, :class:`~safepg.options.SafeStep`).
    gradient : Gradient
        Estimator, baseline and score (:class:`~safepg.options.Gradient`).
    target : Target or None
        Stop at the first batch whose mean measured return reaches ``target.value``
        (``reached_target``), the protocol that learns the cart-pole baseline policy of
        Section 5.3; ``budget`` then caps the search (:class:`~safepg.options.Target`).
    budget : int
        Total number of trajectories.
    rng : int, Generator or None
        Seed or Generator.
    progress : bool or callable
        As in :func:`adaptive_pg`.
    stop_on_divergence : bool
        End the run (``diverged``) instead of raising when the gradient estimate is not finite.

    Returns
    -------
    LearningRecord
        The per-iteration arrays and the settings in ``config``.
    """
    # Building the method checks batch_size and each option's type, before anything else is looked at.
    return learn(task, Vanilla(batch_size, step, gradient, target), theta0, sigma, budget=budget, rng=rng,
                 progress=progress, stop_on_divergence=stop_on_divergence)


# CHECKPOINTS, LearningRecord and RecordFileError live in safepg.record, where the library imports
# them from; they stay exported here too because the API page documents them under safepg.learning,
# and code written against that page imports them from this module.
__all__ = ["CHECKPOINTS", "FUSED_TRAJECTORIES", "LearningRecord", "Progress", "RecordFileError", "adaptive_pg",
           "learn", "vanilla_pg"]
