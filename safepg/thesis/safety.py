r"""Is an adaptive run *safe*? The theorem's assumptions, and how often an update lowered J.

Theorem 4.2.3 and Corollary 4.2.8 certify that, with probability at least :math:`1 - \delta`,
the step :math:`\Lambda^*` does not lower the performance :math:`J`, provided that

* the penalty constant :math:`c` is built from bounds :math:`R \ge |r|` and
  :math:`M_\phi \ge |\phi|` of the task (Assumption 4.2.1), for the discounted :math:`J`
  that the simulator optimises;
* the step is taken only where the estimate is accurate enough, :math:`\epsilon < |\hat g_k|`
  (Assumption 4.2.7);
* :math:`\epsilon` bounds the gradient's estimation error with probability :math:`1 - \delta`
  (a valid error bound on the batch actually drawn).

:func:`theorem_assumptions` checks these on a run's settings; :func:`closed_form_outcomes`
counts, from a learning record, how many updates lowered the closed-form :math:`J`;
:func:`monte_carlo_changes` measures the same with a Monte Carlo :math:`J` on tasks without a closed
form (the cart-pole), with common random numbers and a 99% interval per update
(:func:`cached_monte_carlo_changes` keeps the result in the results folder).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from safepg import portable
from safepg.learning import LearningRecord
from safepg.policies import LinearGaussianPolicy
from safepg.runner import RESULTS_VERSION, RunConfig


def theorem_assumptions(cfg: RunConfig) -> list[dict[str, Any]]:
    """The assumptions of Theorem 4.2.3 / Corollary 4.2.8 for an adaptive run ``cfg``.

    Returns one row per assumption: ``assumption`` (its words), ``holds`` (bool) and
    ``why`` (the setting that decides it).
    """
    if cfg.algorithm != "adaptive":
        raise ValueError(f"cfg must be an adaptive run, got algorithm={cfg.algorithm!r}")
    constants = cfg.constants or "bounds"
    statistics = cfg.statistics or "component"
    task = cfg.make_env()
    simulated, written = task.gamma, getattr(task, "constants_gamma", None)
    one_discount = written is None or written == simulated
    rows = [
        {"assumption": "c from bounds of |r| and |phi| (Assumption 4.2.1)",
         "holds": constants == "bounds",
         "why": "R and M_phi are the task's bounds" if constants == "bounds"
         else "R and M_phi are measured on each batch, so c changes with the batch"},
        {"assumption": "c written for the discount the simulator optimises",
         "holds": one_discount,
         "why": f"gamma = {simulated:g} in both" if one_discount
         else f"the return is simulated with gamma = {simulated:g}, c is written with {written:g}"},
        {"assumption": "step only where eps < |g_k| (Assumption 4.2.7)",
         "holds": not cfg.step_when_unsafe,
         "why": "no step when eps >= |g_k|" if not cfg.step_when_unsafe
         else "the step formula is applied even when eps >= |g_k|"},
        {"assumption": "eps a per-component error bound",
         "holds": statistics == "component",
         "why": "variance and range of component k" if statistics == "component"
         else "the largest variance and range over the components"},
        {"assumption": "eps from a range bound, not the batch's own range",
         "holds": not (cfg.bound in ("bernstein", "hoeffding") and cfg.empirical_range),
         "why": "theoretical range" if not cfg.empirical_range else "the empirical range of the batch"},
        {"assumption": "batch sizes as Algorithm 4.1 sets them (N_min, then N* of the bound)",
         "holds": cfg.n_first is None,
         "why": "the first batch is the algorithm's N_min, every later one the bound's N*" if cfg.n_first is None
         else f"the first batch is fixed at {cfg.n_first}, outside the algorithm"},
    ]
    return rows


def closed_form_outcomes(record: LearningRecord) -> dict[str, Any]:
    """How the updates of ``record`` changed the closed-form J (``record.J``, one per theta row).

    Counts only updates that moved theta. Returns ``updates`` (their number), ``lowered``
    (those with a strictly lower J after than before), ``share_lowered``,
    ``unguarded`` (moves taken where eps >= |g_k|, ``record.safe`` False),
    ``lowered_unguarded`` and ``largest_drop`` (the largest decrease of J, 0 if none).
    """
    J = np.asarray(record.J, dtype=float)
    if J.shape != (record.theta.shape[0],) or not np.all(np.isfinite(J)):
        raise ValueError("record.J must hold a finite closed-form J per theta row")
    moved = np.any(np.diff(record.theta, axis=0) != 0, axis=1)
    dJ = np.diff(J)
    lowered = moved & (dJ < 0)
    unguarded = moved & ~np.asarray(record.safe, dtype=bool)
    n = int(moved.sum())
    return {"updates": n, "lowered": int(lowered.sum()), "share_lowered": lowered.sum() / n if n else 0.0,
            "unguarded": int(unguarded.sum()), "lowered_unguarded": int((lowered & unguarded).sum()),
            "largest_drop": float(-dJ[lowered].min()) if lowered.any() else 0.0}


# ---------------------------------------------------------------- Monte Carlo J (cart-pole)
# Without a closed form, J is estimated by simulation. The change of one update,
# J(theta_{k+1}) - J(theta_k), is estimated on *common random numbers*: both policies are
# simulated with the same seed, i.e. the same initial states and the same action noise, and the
# per-rollout differences are averaged. An update moves theta a little, so most paired rollouts
# come out alike and the difference has a far smaller variance than either return (on the
# authors' cart-pole, a standard deviation of about 0.5 steps against 20 for one return).

#: Rollouts per policy after each look of :func:`monte_carlo_changes` (cumulative): an update
#: whose interval still contains 0 gets fresh rollouts up to the next count.
MC_LOOKS = (4_000, 16_000, 64_000)
#: Probability that an update's interval misses its true change, over all the looks together.
MC_ALPHA = "0.01"


@dataclass(frozen=True)
class MonteCarloOutcomes:
    """How each measured update changed a Monte Carlo J.

    Attributes
    ----------
    updates : int array (U,)
        Which updates were measured: k stands for theta[k] -> theta[k + 1].
    change : float array (U,)
        Estimated J(theta[k + 1]) - J(theta[k]) (mean of the paired differences).
    lower, upper : float array (U,)
        Its interval: all U intervals, at every look, hold their true change together with
        probability at least ``1 - alpha`` each (Bonferroni over the looks).
    rollouts : int array (U,)
        Rollouts per policy used for the update (the look at which it stopped).
    outcome : str array (U,)
        ``"lowered"`` (upper < 0), ``"raised"`` (lower > 0) or ``"undetermined"`` (the
        interval contains 0 at the last look).
    looks : tuple of int
        The rollout counts of the looks.
    alpha : str
        The miss probability of each update's interval over all looks.
    steps : int
        Trajectory-steps simulated, both policies of every update (0 where not recorded).
    """

    updates: np.ndarray
    change: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    rollouts: np.ndarray
    outcome: np.ndarray
    looks: tuple[int, ...]
    alpha: str
    steps: int = 0

    def counts(self) -> dict[str, Any]:
        """``updates``, ``lowered``, ``raised``, ``undetermined``, the total ``rollouts`` (both policies
        of every update) and the median and largest interval ``half_width``."""
        half = (self.upper - self.lower) / 2
        return {"updates": int(self.updates.size),
                **{k: int(np.count_nonzero(self.outcome == k)) for k in ("lowered", "raised", "undetermined")},
                "rollouts": int(2 * self.rollouts.sum()),
                "median_half_width": float(np.median(half)) if half.size else float("nan"),
                "largest_half_width": float(half.max()) if half.size else float("nan")}

    def to_json(self) -> dict[str, Any]:
        """JSON-ready form (:meth:`from_json` reads it back)."""
        return {"updates": self.updates.tolist(), "change": self.change.tolist(), "lower": self.lower.tolist(),
                "upper": self.upper.tolist(), "rollouts": self.rollouts.tolist(), "outcome": self.outcome.tolist(),
                "looks": list(self.looks), "alpha": self.alpha, "steps": self.steps}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> MonteCarloOutcomes:
        return cls(np.array(d["updates"], dtype=int), np.array(d["change"], dtype=float),
                   np.array(d["lower"], dtype=float), np.array(d["upper"], dtype=float),
                   np.array(d["rollouts"], dtype=int), np.array(d["outcome"], dtype=str),
                   tuple(d["looks"]), d["alpha"], int(d.get("steps", 0)))


def paired_returns(env: Any, theta_a: np.ndarray, theta_b: np.ndarray, sigma: float, n: int,
                   seed: int) -> tuple[np.ndarray, np.ndarray]:
    r"""Returns of ``n`` rollouts of two policies on common random numbers.

    Both policies :math:`\mathcal N(\theta^\top\phi(s), \sigma^2)` are simulated by the task with the
    same ``seed``: the same initial states and the same standard-normal action noise. The return is
    the task's objective, :math:`\sum_t \gamma^t r_t` with its ``gamma``; at ``gamma == 1`` a task
    with a fused ``gradient_batch`` (the cart-pole, whose second output is the undiscounted return)
    is run through it, which draws the same random numbers as ``simulate`` and is faster.

    Returns
    -------
    (ndarray, ndarray)
        The (n,) returns under ``theta_a`` and under ``theta_b``.
    """
    out = []
    for theta in (theta_a, theta_b):
        th = np.asarray(theta, dtype=float)
        policy = LinearGaussianPolicy(th.reshape(getattr(env, "action_dim", getattr(env, "dim", 1)), -1), sigma)
        if _fused_returns(env):
            # The returns alone: no baseline to form (the returns are the same either way).
            out.append(np.asarray(env.gradient_batch(policy, n, seed, baseline=False)[1], dtype=float))
        else:
            out.append(env.simulate(policy, n, seed).discounted_returns())
    return out[0], out[1]


@cache
def normal_quantile(tails: str) -> float:
    """The standard normal quantile leaving ``tails`` (a decimal string) in the two tails together.

    mpmath (software arithmetic), so the same on every CPU; for thousands of rollouts it is the
    Student-t quantile to four digits (``safepg.stats.t_quantile``'s series does not converge
    there for small tails).
    """
    import mpmath

    with mpmath.workdps(40):
        p = mpmath.mpf(tails)
        if not 0 < p < 1:
            raise ValueError(f"tails must be in (0, 1), got {tails!r}")
        return float(mpmath.sqrt(2) * mpmath.erfinv(1 - p))


def _interval(d: np.ndarray, tails: str) -> tuple[float, float, float]:
    """Mean of the paired differences and its interval leaving ``tails`` outside (fsum: portable)."""
    m = portable.fsum_mean(d)
    s = math.sqrt(math.fsum(((d - m) * (d - m)).tolist()) / (d.size - 1))
    h = normal_quantile(tails) * s / math.sqrt(d.size)
    return m, m - h, m + h


def _fused_returns(env: Any) -> bool:
    """Whether :func:`paired_returns` reads the returns off a fused ``gradient_batch``: the
    undiscounted returns of the cart-pole, one reward per step lived."""
    return getattr(env, "gamma", None) == 1.0 and hasattr(env, "gradient_batch")


def rollout_steps(env: Any, returns_a: np.ndarray, returns_b: np.ndarray) -> int:
    """Trajectory-steps lived by the rollouts of :func:`paired_returns` (for the time budget):
    the returns themselves on the fused path, the horizon for every rollout otherwise."""
    if _fused_returns(env):
        return int(returns_a.sum() + returns_b.sum())
    return int(env.horizon) * (returns_a.size + returns_b.size)


def monte_carlo_changes(env: Any, thetas: np.ndarray, sigma: float, updates: np.ndarray | None = None,
                        looks: tuple[int, ...] = MC_LOOKS, alpha: str = MC_ALPHA, seed: int = 0) -> MonteCarloOutcomes:
    r"""Did each update lower J? Paired Monte Carlo estimates with a sequential rollout count.

    For each update k (theta[k] -> theta[k + 1]) the change of J is estimated from paired rollouts
    (:func:`paired_returns`). At the first look every update gets ``looks[0]`` rollouts per
    policy; an update whose interval contains 0 gets fresh rollouts (new seeds) up to
    ``looks[1]``, and so on: the rollout count grows until the interval is narrower than the
    change, or the last look is reached. Each look's interval is the normal interval at level
    ``1 - alpha / len(looks)`` (:func:`normal_quantile`), so that the interval at which an update
    stops covers its true change with probability at least ``1 - alpha`` (Bonferroni over the looks;
    asymptotically, with hundreds to thousands of rollouts per look).

    Parameters
    ----------
    env : task
        ``simulate(policy, n, rng)`` and ``gamma`` (optionally a fused ``gradient_batch``).
    thetas : array_like, shape (I + 1, m)
        The parameters in the order visited (a record's ``theta``).
    sigma : float
        The policy's standard deviation.
    updates : int array or None
        The updates to measure (default: all I).
    looks : tuple of int
        Increasing cumulative rollout counts per policy.
    alpha : str
        Miss probability per update, a decimal string.
    seed : int
        Seeds of the rollouts: update k's block j is seeded by SeedSequence([seed, k, j]).
    """
    T = np.asarray(thetas, dtype=float)
    T = T.reshape(T.shape[0], -1)
    ks = np.arange(T.shape[0] - 1) if updates is None else np.asarray(updates, dtype=int)
    if ks.size and (ks.min() < 0 or ks.max() >= T.shape[0] - 1):
        raise ValueError(f"updates must lie in [0, {T.shape[0] - 2}], got {ks.min()}..{ks.max()}")
    if not looks or looks[0] < 100 or any(b <= a for a, b in zip(looks, looks[1:])):
        raise ValueError(f"looks must be increasing counts >= 100 (the interval is asymptotic), got {looks}")
    tails = repr(float(alpha) / len(looks))
    diffs: list[list[np.ndarray]] = [[] for _ in ks]
    result = np.zeros((ks.size, 3))
    done = np.zeros(ks.size, dtype=bool)
    used = np.zeros(ks.size, dtype=int)
    steps = 0
    for j, n in enumerate(looks):
        for i in np.flatnonzero(~done):
            k = int(ks[i])
            block_seed = int(np.random.SeedSequence([seed, k, j]).generate_state(1)[0])
            a, b = paired_returns(env, T[k], T[k + 1], sigma, n - used[i], block_seed)
            steps += rollout_steps(env, a, b)
            diffs[i].append(b - a)
            used[i] = n
            result[i] = _interval(np.concatenate(diffs[i]), tails)
            done[i] = result[i, 1] > 0 or result[i, 2] < 0
    outcome = np.where(result[:, 2] < 0, "lowered", np.where(result[:, 1] > 0, "raised", "undetermined"))
    return MonteCarloOutcomes(ks, result[:, 0], result[:, 1], result[:, 2], used, outcome.astype(str),
                              tuple(int(n) for n in looks), alpha, steps)


def spread_updates(iterations: int, count: int) -> np.ndarray:
    """``count`` updates spread evenly over a run of ``iterations`` updates (the first and last included)."""
    if iterations < 1 or count < 1:
        raise ValueError(f"iterations and count must be >= 1, got {iterations} and {count}")
    return np.unique(np.round(np.linspace(0, iterations - 1, min(count, iterations))).astype(int))


def cached_monte_carlo_changes(folder: Path, env: Any, thetas: np.ndarray, sigma: float,
                               updates: np.ndarray | None = None, looks: tuple[int, ...] = MC_LOOKS,
                               alpha: str = MC_ALPHA, seed: int = 0) -> MonteCarloOutcomes:
    """:func:`monte_carlo_changes`, stored in ``folder`` under a key of all its inputs.

    The file ``<key>.json`` is written atomically (a temporary file renamed over it, as the run
    store does); a file that cannot be read, or was made by other inputs, is computed again.
    """
    T = np.ascontiguousarray(np.asarray(thetas, dtype=float))
    ks = np.arange(T.shape[0] - 1) if updates is None else np.asarray(updates, dtype=int)
    blob = json.dumps([repr(env), hashlib.sha256(T.tobytes()).hexdigest(), list(T.shape), float(sigma),
                       ks.tolist(), list(looks), alpha, seed, RESULTS_VERSION])
    key = hashlib.sha256(blob.encode()).hexdigest()[:16]
    path = Path(folder) / f"{key}.json"
    try:
        stored = json.loads(path.read_text())
        if stored.get("key") == blob:
            return MonteCarloOutcomes.from_json(stored["outcomes"])
    except (OSError, ValueError, KeyError, TypeError):
        pass
    started = time.perf_counter()
    out = monte_carlo_changes(env, T, sigma, ks, looks, alpha, seed)
    seconds = time.perf_counter() - started  # benchmarks/bench_book.py reads it
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"{key}~", suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump({"key": blob, "outcomes": out.to_json(), "seconds": round(seconds, 3)}, f)
    os.replace(tmp, path)
    return out


def measure_runs(env: Any, runs: Sequence[np.ndarray], sigma: float, per_run: int, folder: Path,
                 looks: tuple[int, ...] = MC_LOOKS, alpha: str = MC_ALPHA, seed: int = 0) -> MonteCarloOutcomes:
    """:func:`cached_monte_carlo_changes` on ``per_run`` updates spread over each run, joined.

    Parameters
    ----------
    env : task
        The task the runs learned on.
    runs : sequence of arrays (I + 1, m)
        Each run's parameters in the order visited (a record's ``theta``, or the authors' logged
        theta column).
    sigma : float
        The policies' standard deviation.
    per_run : int
        Updates measured per run (:func:`spread_updates`: the first, the last and evenly between).
    folder : Path
        Where the measurements are stored.

    Returns
    -------
    MonteCarloOutcomes
        All runs' measured updates in one (``updates`` keeps each run's own indices).
    """
    parts = [cached_monte_carlo_changes(folder, env, T, sigma, spread_updates(len(T) - 1, per_run), looks, alpha,
                                        seed) for T in runs]
    return MonteCarloOutcomes(*(np.concatenate([getattr(p, f) for p in parts])
                                for f in ("updates", "change", "lower", "upper", "rollouts", "outcome")),
                              looks=tuple(looks), alpha=alpha, steps=sum(p.steps for p in parts))
