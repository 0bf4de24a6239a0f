r"""Learning loops of Chapter 5: Algorithm 4.1 (adaptive step and batch size) and
vanilla policy gradient with a fixed batch size.

Both return a :class:`LearningRecord` of per-iteration arrays. Iteration i collects
``batch_size[i]`` trajectories with the policy ``theta[i]`` and moves to ``theta[i+1]``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Literal, Protocol

import numpy as np
from tqdm.auto import tqdm

from safepg.bounds import Bound, ErrorBound, check_delta, error_bound
from safepg.constants import BoundedTask, TaskConstants
from safepg.estimators import Estimator, ScoreAction, gradient_samples
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    optimal_batch_size,
    penalty_constant,
    scalar_step,
)
from safepg.policies import LinearGaussianPolicy
from safepg.record import CHECKPOINTS, LearningRecord, RecordFileError
from safepg.rng import RNGLike, as_generator
from safepg.trajectories import Trajectories


class Task(BoundedTask, Protocol):
    def simulate(self, policy: LinearGaussianPolicy, n: int, rng: RNGLike = None) -> Trajectories: ...


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
UpdateRule = Callable[[np.ndarray, np.ndarray, int, "tuple[float, float] | None"], _Update]
#: ``progress`` of the learning loops: True for a tqdm bar, or a callable ``report(used, budget)``.
Progress = bool | Callable[[int, int], object]


def _closed_form(task: Task, thetas: np.ndarray, sigma: float) -> np.ndarray:
    """J(theta_i) for every row of ``thetas``; NaN for a task without a closed form."""
    batched = getattr(task, "performance_batch", None)
    if batched is not None:
        return np.asarray(batched(thetas, sigma), dtype=float)
    perf = getattr(task, "performance", None)
    if perf is None:
        return np.full(len(thetas), np.nan)
    return np.array([perf(theta, sigma) for theta in thetas], dtype=float)


def _collect(
    task: Task, policy: LinearGaussianPolicy, n: int, rng: np.random.Generator,
    estimator: Estimator, baseline: bool, score_action: ScoreAction, maxima: bool = False,
) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None]:
    """Gradient samples (n, m), measured returns (n,) and, with ``maxima``, the batch's
    measured (R, M_phi) (else None) of a fresh batch.

    Uses the task's fused ``gradient_batch`` when it has one (the LQG and the cart-pole
    do), else simulates the batch and applies :func:`safepg.estimators.gradient_samples`.
    The measured return is the task's ``measured_returns(batch)`` if it defines one (the
    cart-pole: the undiscounted episode length the thesis reports), else the discounted
    return. With ``maxima``: the task's ``gradient_batch_maxima`` if it has one (the
    cart-pole), else the largest |reward| and |feature| of the simulated batch's live steps.
    """
    if maxima:
        fused_maxima = getattr(task, "gradient_batch_maxima", None)
        if fused_maxima is not None:
            return fused_maxima(policy, n, rng, estimator, baseline, score_action)
    else:
        fused = getattr(task, "gradient_batch", None)
        if fused is not None:
            return (*fused(policy, n, rng, estimator, baseline, score_action), None)
    batch = task.simulate(policy, n, rng)
    measured = getattr(task, "measured_returns", Trajectories.discounted_returns)
    found = None
    if maxima:
        live = np.ones(batch.rewards.shape, dtype=bool) if batch.mask is None else batch.mask.astype(bool)
        found = (float(np.abs(batch.rewards[live]).max()), float(np.abs(batch.features[live]).max()))
    return gradient_samples(policy, batch, estimator, baseline, score_action), measured(batch), found


def _check_budget(budget: int, n_first: int) -> None:
    if int(budget) != budget or budget < n_first:
        raise ValueError(f"budget must be an integer >= the first batch size {n_first}, got {budget}")


def _learn(
    task: Task,
    policy: LinearGaussianPolicy,
    rule: UpdateRule,
    n_first: int,
    budget: int,
    rng: RNGLike,
    estimator: Estimator,
    baseline: bool,
    score_action: ScoreAction,
    config: dict[str, Any],
    progress: Progress,
    stop_on_divergence: bool = False,
    target_return: float | None = None,
    update_at_target: bool = False,
    maxima: bool = False,
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
            samples, returns, found = _collect(task, policy, n, rng, estimator, baseline, score_action, maxima)
            with np.errstate(over="ignore", invalid="ignore"):  # a non-finite mean is handled just below
                # sum / n is what ndarray.mean computes (same bits), without its Python overhead:
                # a run with N = 100 has 3*10^5 iterations.
                grad = samples.sum(axis=0) / n
            if not np.all(np.isfinite(grad)):
                if stop_on_divergence:
                    diverged = True
                    break
                raise ValueError(f"gradient estimate is not finite at theta={theta.tolist()}: {grad}")
            J_hat = float(returns.sum() / n)
            reached = target_return is not None and J_hat >= target_return
            if reached and not update_at_target:
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
    m = theta.size
    theta_rows = np.asarray(thetas, dtype=float).reshape(-1, m)
    return LearningRecord(
        batch_size=np.asarray(rows["batch_size"], dtype=np.int64),
        alpha=np.asarray(rows["alpha"], dtype=float),
        coordinate=np.asarray(rows["coordinate"], dtype=np.int64),
        theta=theta_rows,
        J=_closed_form(task, theta_rows, policy.sigma),
        J_hat=np.asarray(rows["J_hat"], dtype=float),
        grad=np.asarray(rows["grad"], dtype=float).reshape(-1, m),
        eps=np.asarray(rows["eps"], dtype=float),
        safe=np.asarray(rows["safe"], dtype=bool),
        config=config,
        interrupted=interrupted,
        diverged=diverged,
        reached_target=reached,
    )


def _initial_policy(task: Task, theta0: np.ndarray | float, sigma: float | np.ndarray) -> LinearGaussianPolicy:
    theta0 = np.asarray(theta0, dtype=float)
    shape = (getattr(task, "action_dim", None) or getattr(task, "dim", 1), None)
    d_a = shape[0]
    if theta0.ndim <= 1:
        theta0 = np.broadcast_to(theta0, (theta0.size,)) if theta0.ndim == 1 else theta0.reshape(1)
        m = theta0.size
        if m % d_a:
            raise ValueError(f"theta0 must have a multiple of {d_a} entries, got {m}")
        theta0 = theta0.reshape(d_a, m // d_a)
    return LinearGaussianPolicy(theta0, sigma)


def adaptive_pg(
    task: Task,
    theta0: np.ndarray | float = 0.0,
    sigma: float = 1.0,
    *,
    estimator: Estimator = "gpomdp",
    baseline: bool = True,
    bound: Bound = "chebyshev",
    delta: float = 0.95,
    empirical_range: bool = False,
    theoretical_range: float | None = None,
    n_min: int = 100,
    n_max: int = 500_000,
    budget: int = 30_000_000,
    score_action: ScoreAction = "clipped",
    rng: RNGLike = None,
    progress: Progress = False,
    n_first: int | None = None,
    constants: Literal["bounds", "batch"] = "bounds",
    statistics: Literal["component", "max"] = "component",
    step_when_unsafe: bool = False,
) -> LearningRecord:
    r"""Adaptive policy gradient, Algorithm 4.1 (as corrected in the book's errata).

    Each iteration collects N trajectories, estimates the gradient, picks
    :math:`k = \arg\max_i|\hat\nabla_{\theta_i}J|`, computes
    :math:`\epsilon = d_\delta/\sqrt N + f_\delta/N` from the chosen bound on component k,
    moves :math:`\theta_k` by the step of Corollary 4.2.8, and sets the next batch size to
    N* (Theorem 4.3.2, or the search of Section 4.3.3 for Bernstein) clipped to
    [n_min, n_max]. The first batch has n_min trajectories (``n_first`` to change it).

    The last four parameters default to the algorithm as the theorems need it; the other
    values are what the authors' 2-D and cart-pole scripts did, to reproduce their runs.

    Parameters
    ----------
    task : environment with ``simulate`` and the bound constants (e.g. :class:`~safepg.envs.LQG`)
    theta0 : initial parameters (flat vector or gain matrix)
    sigma : policy standard deviation
    estimator : "reinforce" or "gpomdp"
    baseline : use the variance-minimising baseline (else b = 0)
    bound : "chebyshev", "hoeffding" or "bernstein"
    delta : probability of a worsening update, in (0, 1)
    empirical_range : Hoeffding/Bernstein with the batch's max - min instead of Lemma 4.3.3
    theoretical_range : replaces Lemma 4.3.3's range when ``empirical_range`` is False
    n_min, n_max : batch-size limits
    budget : total number of trajectories
    score_action : "clipped" (the authors' code) or "raw" (unbiased score)
    rng : seed or Generator
    progress : True shows a tqdm bar; a callable ``progress(used, budget)`` is called instead
        after each batch with the trajectories used so far. An exception it raises stops
        the run and propagates to the caller, with no record: how a caller running the loop
        in a thread cancels it (one call per batch, so cancelling waits for one batch).
    n_first : size of the first batch (None: n_min), which no bound chooses (the authors
        hard-coded 100 in 2-D and 1000 on the cart-pole)
    constants : "bounds" (default): R and M_phi are the task's bounds (Assumption 4.2.1), as
        Theorem 4.2.3 needs; "batch": the largest |reward| and |feature| measured on each batch
        (the authors' cart-pole script), so the penalty constant and the bounds change from
        batch to batch; the record's ``config["c"]`` is then the bound-based constant
    statistics : "component" (default): the sample variance and range of component k, as in
        Section 4.3.3; "max": the largest sample variance and range over all components (the
        authors' 2-D and cart-pole scripts)
    step_when_unsafe : take the step of Corollary 4.2.8's formula even when eps >= |g_k|
        (the authors' scripts); by default the algorithm does not move then
    """
    check_delta(delta)
    if int(n_min) != n_min or n_min < 2:
        raise ValueError(f"n_min must be an integer >= 2, got {n_min}")
    if n_min > n_max:
        raise ValueError(f"n_min must be <= n_max, got n_min={n_min} > n_max={n_max}")
    if n_first is not None and (int(n_first) != n_first or n_first < 2):
        raise ValueError(f"n_first must be an integer >= 2 or None, got {n_first}")
    if constants not in ("bounds", "batch"):
        raise ValueError(f"constants must be 'bounds' or 'batch', got {constants!r}")
    if statistics not in ("component", "max"):
        raise ValueError(f"statistics must be 'component' or 'max', got {statistics!r}")
    first = n_min if n_first is None else int(n_first)
    _check_budget(budget, first)
    policy = _initial_policy(task, theta0, sigma)
    bounds = TaskConstants.from_task(task, policy.sigma)
    c_bounds = penalty_constant(bounds)

    def rule(samples: np.ndarray, grad: np.ndarray, n: int, found: tuple[float, float] | None) -> _Update:
        k = int(np.argmax(np.abs(grad)))
        g = float(abs(grad[k]))
        batch_k, c = bounds, c_bounds
        if found is not None:  # constants="batch": this batch's R and M_phi
            batch_k = replace(bounds, R=found[0], M_phi=found[1])
            c = penalty_constant(batch_k)
        spread = {}
        if statistics == "max":
            spread = dict(variance=float(np.var(samples, axis=0, ddof=1).max()),
                          sample_range=float(np.ptp(samples, axis=0).max()))
        eb: ErrorBound = error_bound(bound, samples[:, k], delta, batch_k, estimator, empirical_range,
                                     theoretical_range, **spread)
        eps = float(eb.eps(n))
        alpha = coordinate_step(g, eps, c, guarded=not step_when_unsafe)
        step = np.zeros_like(grad)
        step[k] = alpha * grad[k]
        return _Update(step, alpha, k, eps, eps < g, optimal_batch_size(g, eb, c, n_min, n_max))

    config = dict(
        algorithm="adaptive", task=repr(task), theta0=np.asarray(theta0, float).tolist(),
        sigma=sigma, estimator=estimator, baseline=baseline, bound=bound, delta=delta,
        empirical_range=empirical_range, theoretical_range=theoretical_range, n_min=n_min, n_max=n_max,
        budget=budget, score_action=score_action, c=c_bounds,
    )
    # The options only when set, so a default run's record is what it always was.
    config.update({k: v for k, v in (("n_first", n_first), ("constants", constants), ("statistics", statistics),
                                     ("step_when_unsafe", step_when_unsafe))
                   if v not in (None, "bounds", "component", False)})
    return _learn(task, policy, rule, first, budget, rng, estimator, baseline, score_action, config, progress,
                  maxima=constants == "batch")


def vanilla_pg(
    task: Task,
    theta0: np.ndarray | float = 0.0,
    sigma: float = 1.0,
    *,
    batch_size: int = 100,
    alpha: float | None = 1e-3,
    step: Literal["scalar", "coordinate"] = "scalar",
    estimator: Estimator = "gpomdp",
    baseline: bool = True,
    bound: Bound = "chebyshev",
    delta: float = 0.95,
    empirical_range: bool = False,
    budget: int = 1_000_000,
    score_action: ScoreAction = "clipped",
    rng: RNGLike = None,
    progress: Progress = False,
    stop_on_divergence: bool = False,
    target_return: float | None = None,
    update_at_target: bool = False,
) -> LearningRecord:
    r"""Policy gradient with a fixed batch size.

    With a fixed ``alpha``: :math:`\theta \leftarrow \theta + \alpha\hat\nabla J` (``step="scalar"``)
    or only the largest component moves (``step="coordinate"``). With ``alpha=None`` the
    step is adaptive, using the bound's eps at the fixed N: the scalar step of [24]
    (``"scalar"``) or the coordinate step Lambda* of Corollary 4.2.8 (``"coordinate"``),
    as compared in Section 5.2.1 (Figures 5.5-5.6). A fixed step can make theta diverge
    until the gradient overflows: with ``stop_on_divergence=True`` the run then ends and
    the record says so (``diverged``), instead of raising.

    ``target_return`` stops the run at the first batch whose mean measured return reaches
    it, without updating (``reached_target``): the protocol that learns the cart-pole
    baseline policy of Section 5.3 ("we stop once an average performance of 195 over the
    batch is achieved"). ``budget`` then caps the search. With ``update_at_target=True``
    the batch that reaches the target still updates theta before the run stops, as in the
    authors' baseline script (its saved policy is one update past the batch that reached 195).

    ``progress`` is as in :func:`adaptive_pg`: True for a tqdm bar, or a callable
    ``progress(used, budget)`` called after each batch, whose exceptions stop the run.
    """
    if int(batch_size) != batch_size or batch_size < 2:
        raise ValueError(f"batch_size must be an integer >= 2, got {batch_size}")
    if alpha is not None and not (np.isfinite(alpha) and alpha >= 0):
        raise ValueError(f"alpha must be finite and >= 0, got {alpha}")
    if step not in ("scalar", "coordinate"):
        raise ValueError(f"step must be 'scalar' or 'coordinate', got {step!r}")
    if alpha is None:
        check_delta(delta)
    if target_return is not None and not np.isfinite(target_return):
        raise ValueError(f"target_return must be finite or None, got {target_return}")
    _check_budget(budget, batch_size)
    policy = _initial_policy(task, theta0, sigma)
    constants = TaskConstants.from_task(task, policy.sigma)
    c = penalty_constant(constants)

    def rule(samples: np.ndarray, grad: np.ndarray, n: int, found: tuple[float, float] | None) -> _Update:
        k = int(np.argmax(np.abs(grad)))
        eps, safe, a = 0.0, True, alpha
        if alpha is None:
            # One common eps for all components: the largest per-component bound.
            eps = max(float(error_bound(bound, samples[:, i], delta, constants, estimator,
                                        empirical_range).eps(n)) for i in range(grad.size))
            safe = eps < abs(grad[k])
            a = scalar_step(grad, eps, c) if step == "scalar" else coordinate_step(abs(grad[k]), eps, c)
        assert a is not None
        if step == "scalar":
            return _Update(a * grad, a, -1, eps, safe, batch_size)
        d = np.zeros_like(grad)
        d[k] = a * grad[k]
        return _Update(d, a, k, eps, safe, batch_size)

    config = dict(
        algorithm="vanilla", task=repr(task), theta0=np.asarray(theta0, float).tolist(),
        sigma=sigma, batch_size=batch_size, alpha=alpha, step=step, estimator=estimator,
        baseline=baseline, bound=bound, delta=delta, empirical_range=empirical_range,
        budget=budget, score_action=score_action, c=c, target_return=target_return,
    )
    if update_at_target:  # only when set, so a default run's record is what it always was
        config["update_at_target"] = True
    return _learn(task, policy, rule, batch_size, budget, rng, estimator, baseline, score_action, config, progress,
                  stop_on_divergence, target_return, update_at_target)


__all__ = ["CHECKPOINTS", "LearningRecord", "RecordFileError", "adaptive_pg", "guaranteed_improvement", "vanilla_pg"]
