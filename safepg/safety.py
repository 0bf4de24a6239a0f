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
form (the cart-pole, the pendulum), with common random numbers and a 99% interval per update
(:mod:`safepg.safety_store` keeps the results in the results folder and measures every update of
each run). Both summaries give, per run, the updates that lowered, raised or
left undetermined :math:`J`, the one-sided 95% Clopper-Pearson bound on the share of updates that
lower it (:func:`clopper_pearson_upper`) and the detection floor of the Monte Carlo measurement.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from safepg import portable
from safepg.envs.cartpole import CartPole
from safepg.envs.pendulum import Pendulum
from safepg.options import Adaptive
from safepg.policies import LinearGaussianPolicy
from safepg.record import LearningRecord
from safepg.runner import RunConfig
from safepg.tasks import constants_settings, task_hooks


def theorem_assumptions(cfg: RunConfig) -> list[dict[str, Any]]:
    """The assumptions of Theorem 4.2.3 / Corollary 4.2.8 for an adaptive run ``cfg``.

    Returns one row per assumption: ``assumption`` (its words), ``holds`` (bool) and
    ``why`` (the setting that decides it).
    """
    method = cfg.method
    if not isinstance(method, Adaptive):
        raise ValueError(f"cfg must be an adaptive run, got algorithm={cfg.algorithm!r}")
    task = cfg.make_task()
    simulated, written = task.gamma, constants_settings(task).constants_gamma
    one_discount = written is None or written == simulated
    from_bounds, guarded, per_component = method.departures.assumptions()
    empirical = method.error.bound in ("bernstein", "hoeffding") and method.error.empirical_range
    first = method.batches.first
    rows = [
        from_bounds._asdict(),
        {"assumption": "c written for the discount the simulator optimises",
         "holds": one_discount,
         "why": f"gamma = {simulated:g} in both" if one_discount
         else f"the return is simulated with gamma = {simulated:g}, c is written with {written:g}"},
        guarded._asdict(),
        per_component._asdict(),
        {"assumption": "eps from a range bound, not the batch's own range",
         "holds": not empirical,
         "why": "theoretical range" if not method.error.empirical_range else "the empirical range of the batch"},
        {"assumption": "batch sizes as Algorithm 4.1 sets them (N_min, then N* of the bound)",
         "holds": first is None,
         "why": "the first batch is the algorithm's N_min, every later one the bound's N*" if first is None
         else f"the first batch is fixed at {first}, outside the algorithm"},
    ]
    return rows


@cache
def clopper_pearson_upper(k: int, n: int, level: str = "0.95") -> float:
    r"""The one-sided Clopper-Pearson upper bound on a binomial share, ``k`` of ``n``.

    The largest share :math:`p` under which ``k`` or fewer of ``n`` independent trials succeed
    with probability at least :math:`1 - \text{level}`:

    .. math::

        p_U = \sup\{p : P(X \le k \mid n, p) \ge 1 - \text{level}\}, \qquad
        X \sim \mathrm{Binomial}(n, p),

    that is the ``level`` quantile of :math:`\mathrm{Beta}(k + 1, n - k)`,
    :math:`I_{p_U}(k + 1, n - k) = \text{level}` with :math:`I` the regularised incomplete beta
    function, and :math:`p_U = 1` for :math:`k = n`. For :math:`k = 0` it is
    :math:`1 - (1 - \text{level})^{1/n}` (about :math:`3/n` at level 0.95). Whatever the true
    share, the bound lies above it with probability at least ``level``.

    Computed with mpmath (software arithmetic, 40 digits: the binomial sum :math:`P(X \le k)`
    and a bisection on it, to 2^-120 or until both ends round to one float), so the same to
    the last bit on every CPU.

    Parameters
    ----------
    k : int
        Successes (here: updates that lowered J, or may have), ``0 <= k <= n``.
    n : int
        Trials (updates), ``n >= 1``.
    level : str
        The confidence level, a decimal string in (0, 1).
    """
    import mpmath

    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k <= n:
        raise ValueError(f"k must be an integer in [0, n = {n}], got {k!r}")
    with mpmath.workdps(40):
        q = mpmath.mpf(level)
        if not 0 < q < 1:
            raise ValueError(f"level must be in (0, 1), got {level!r}")
        if k == n:
            return 1.0
        if k == 0:
            return float(1 - mpmath.power(1 - q, mpmath.mpf(1) / n))
        lo, hi = mpmath.mpf(0), mpmath.mpf(1)
        for _ in range(120):  # P(X <= k) falls as p grows: halve [lo, hi] to 2^-120
            if float(lo) == float(hi):
                # Rounding is monotone: every later hi, inside [lo, hi], rounds to this float too.
                break
            mid = (lo + hi) / 2
            if _binomial_cdf(k, n, mid) > 1 - q:
                lo = mid
            else:
                hi = mid
        return float(hi)


def _binomial_cdf(k: int, n: int, p: Any) -> Any:
    r""":math:`P(X \le k)` for :math:`X \sim \mathrm{Binomial}(n, p)`, an mpmath number, ``0 < p < 1``.

    The sum of the :math:`\binom{n}{i} p^i (1-p)^{n-i}` over the shorter side (:math:`i \le k`, or
    one minus :math:`i > k`), each term from the previous one by the ratio of consecutive terms.
    """
    import mpmath

    r = p / (1 - p)
    if k <= n // 2:
        term = mpmath.power(1 - p, n)  # i = 0
        total = term
        for i in range(k):
            term = term * (n - i) / (i + 1) * r
            total += term
        return total
    term = mpmath.power(p, n)  # i = n
    total = term
    for i in range(n, k + 1, -1):
        term = term * i / (n - i + 1) / r
        total += term
    return 1 - total


def safety_summary(lowered: int, raised: int, undetermined: int = 0, detection_floor: float = 0.0,
                   level: str = "0.95") -> dict[str, Any]:
    r"""One run's updates: how many lowered, raised or left undetermined J, and the bound on the share.

    An *undetermined* update (a Monte Carlo interval that contains 0) may have lowered J, so the
    upper bound counts it as lowered:

    .. math::

        \text{share\_lowered\_upper95} = p_U(\text{lowered} + \text{undetermined},\ \text{updates})

    (:func:`clopper_pearson_upper`), the largest share of updates that lower J, for updates drawn
    as these were, consistent at ``level`` with the counts; with no update at all it is ``None``.
    ``detection_floor`` says how large a decrease an undetermined update could hide.

    Parameters
    ----------
    lowered, raised, undetermined : int
        The counts (``updates`` is their sum).
    detection_floor : float
        The largest decrease of J an undetermined update could hide (0 when there are none).
    level : str
        The bound's confidence level.

    Returns
    -------
    dict
        ``updates``, ``lowered``, ``raised``, ``undetermined``, ``share_lowered_upper95``,
        ``detection_floor``.
    """
    for name, v in (("lowered", lowered), ("raised", raised), ("undetermined", undetermined)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
            raise ValueError(f"{name} must be an integer >= 0, got {v!r}")
    if not (math.isfinite(detection_floor) and detection_floor >= 0):
        raise ValueError(f"detection_floor must be finite and >= 0, got {detection_floor!r}")
    if undetermined == 0 and detection_floor != 0:
        raise ValueError(f"detection_floor must be 0 without undetermined updates, got {detection_floor!r}")
    n = int(lowered + raised + undetermined)
    bound = clopper_pearson_upper(int(lowered + undetermined), n, level) if n else None
    return {"updates": n, "lowered": int(lowered), "raised": int(raised), "undetermined": int(undetermined),
            "share_lowered_upper95": bound, "detection_floor": float(detection_floor)}


def moved_updates(thetas: np.ndarray) -> np.ndarray:
    """The updates that moved theta: every k with theta[k + 1] != theta[k] in some component.

    ``thetas`` is (I + 1, m) (or (I + 1,)), the parameters in the order visited. A step of size 0
    (no update taken, Assumption 4.2.7 failing) is no update: it cannot change J.
    """
    T = np.asarray(thetas, dtype=float)
    if T.ndim not in (1, 2) or T.shape[0] < 1:
        raise ValueError(f"thetas must be (I + 1, m) parameters, got shape {T.shape}")
    T = T.reshape(T.shape[0], -1)
    return np.flatnonzero(np.any(T[1:] != T[:-1], axis=1))


def closed_form_summary(J: np.ndarray, updates: np.ndarray | None = None) -> dict[str, Any]:
    r"""How the updates changed a closed-form J, exactly: :func:`safety_summary` of its changes.

    Update k changes J by :math:`\Delta J_k = J_{k+1} - J_k`. It *lowered* J when
    :math:`\Delta J_k < 0` and *raised* it otherwise (:math:`\Delta J_k \ge 0`: it did not
    worsen the performance, the thesis's improvement, Section 5.1); none is undetermined and the
    detection floor is 0.

    Parameters
    ----------
    J : array (I + 1,)
        The closed-form J at each visited theta.
    updates : int array or None
        The updates to count (default: all I; :func:`moved_updates` for those that moved theta).

    Returns
    -------
    dict
        :func:`safety_summary`'s fields, plus ``largest_drop`` (the largest decrease, 0 if none).
    """
    J = np.asarray(J, dtype=float)
    if J.ndim != 1 or not np.all(np.isfinite(J)):
        raise ValueError("J must be a finite closed-form J per visited theta")
    dJ = np.diff(J)
    ks = np.arange(dJ.size) if updates is None else np.asarray(updates, dtype=int)
    if ks.size and (ks.min() < 0 or ks.max() >= dJ.size):
        raise ValueError(f"updates must lie in [0, {dJ.size - 1}], got {ks.min()}..{ks.max()}")
    lowered = dJ[ks] < 0
    return {**safety_summary(int(lowered.sum()), int(ks.size - lowered.sum())),
            "largest_drop": float(-dJ[ks][lowered].min()) if lowered.any() else 0.0}


def closed_form_outcomes(record: LearningRecord) -> dict[str, Any]:
    """How the updates of ``record`` changed the closed-form J (``record.J``, one per theta row).

    Counts only updates that moved theta (:func:`moved_updates`). Returns
    :func:`closed_form_summary`'s fields (``updates``, ``lowered``, ``raised``, ``undetermined`` = 0,
    ``share_lowered_upper95``, ``detection_floor`` = 0, ``largest_drop``), plus ``share_lowered``,
    ``unguarded`` (moves taken where eps >= |g_k|, ``record.safe`` False) and ``lowered_unguarded``.
    """
    J = np.asarray(record.J, dtype=float)
    if J.shape != (record.theta.shape[0],) or not np.all(np.isfinite(J)):
        raise ValueError("record.J must hold a finite closed-form J per theta row")
    ks = moved_updates(record.theta)
    out = closed_form_summary(J, ks)
    lowered = np.diff(J)[ks] < 0
    unguarded = ~np.asarray(record.safe, dtype=bool)[ks]
    n = out["updates"]
    return {**out, "share_lowered": out["lowered"] / n if n else 0.0, "unguarded": int(unguarded.sum()),
            "lowered_unguarded": int((lowered & unguarded).sum())}


# ---------------------------------------------------------------- Monte Carlo J (cart-pole, pendulum)
# Without a closed form, J is estimated by simulation. The change of one update,
# J(theta_{k+1}) - J(theta_k), is estimated on *common random numbers*: both policies are
# simulated with the same seed, i.e. the same initial states and the same action noise, and the
# per-rollout differences are averaged. An update moves theta a little, so most paired rollouts
# come out alike and the difference has a far smaller variance than either return (on the
# authors' cart-pole, a standard deviation of about 0.5 steps against 20 for one return).

#: Rollouts per policy after each look of :func:`monte_carlo_changes` (cumulative): an update
#: whose interval still contains 0 gets fresh rollouts up to the next count.
MC_LOOKS = (4_000, 16_000, 64_000)
#: The looks for our own runs (thousands of updates: with the authors' runs at :data:`MC_LOOKS`,
#: 100 s on 2 cores from empty): a smaller last look, hence a larger detection floor.
MC_LOOKS_OUR_RUNS = (1_000, 2_000)
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

    def counts(self, level: str = "0.95") -> dict[str, Any]:
        r"""The run's :func:`safety_summary` (``updates``, ``lowered``, ``raised``, ``undetermined``,
        ``share_lowered_upper95``, ``detection_floor``), the total ``rollouts`` (both policies of
        every update) and the median and largest interval ``half_width``.

        The detection floor is the largest decrease of J an undetermined update could hide,
        :math:`\max_k \max(0, -\text{lower}_k)` over the undetermined updates (0 when none), in
        the units of J (steps of episode length on the cart-pole).
        """
        half = (self.upper - self.lower) / 2
        n = {k: int(np.count_nonzero(self.outcome == k)) for k in ("lowered", "raised", "undetermined")}
        hidden = -self.lower[self.outcome == "undetermined"]
        floor = max(0.0, float(hidden.max())) if hidden.size else 0.0
        return {**safety_summary(n["lowered"], n["raised"], n["undetermined"], floor, level),
                "rollouts": int(2 * self.rollouts.sum()),
                "median_half_width": float(np.median(half)) if half.size else float("nan"),
                "largest_half_width": float(half.max()) if half.size else float("nan")}

    @classmethod
    def join(cls, parts: Sequence[MonteCarloOutcomes]) -> MonteCarloOutcomes:
        """Several measurements in one, in order (``updates`` keeps each part's own indices); the
        parts must share their looks and alpha."""
        if not parts:
            raise ValueError("parts must hold at least one measurement")
        if any((p.looks, p.alpha) != (parts[0].looks, parts[0].alpha) for p in parts):
            raise ValueError("parts must share their looks and alpha")

        def joined(name: str) -> np.ndarray:
            return np.concatenate([getattr(p, name) for p in parts])

        return cls(joined("updates"), joined("change"), joined("lower"), joined("upper"), joined("rollouts"),
                   joined("outcome"), looks=parts[0].looks, alpha=parts[0].alpha, steps=sum(p.steps for p in parts))

    def to_json(self) -> dict[str, Any]:
        """JSON-ready form (:meth:`!from_json` reads it back)."""
        return {"updates": self.updates.tolist(), "change": self.change.tolist(), "lower": self.lower.tolist(),
                "upper": self.upper.tolist(), "rollouts": self.rollouts.tolist(), "outcome": self.outcome.tolist(),
                "looks": list(self.looks), "alpha": self.alpha, "steps": int(self.steps)}

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
    the task's objective, :math:`\sum_t \gamma^t r_t` with its ``gamma``. The cart-pole, rewarded 1
    per step lived, is run through its fused ``gradient_batch`` (the same random numbers as
    ``simulate``, and faster), whose second output is each episode's length :math:`L`; its return
    is then :math:`\sum_{t < L} \gamma^t` (:math:`L` itself at :math:`\gamma = 1`). The pendulum
    is run through its fused ``episode_returns`` (the same random numbers as ``simulate``).

    Returns
    -------
    (ndarray, ndarray)
        The (n,) returns under ``theta_a`` and under ``theta_b``.
    """
    a, b, _ = _paired(env, theta_a, theta_b, sigma, n, seed)
    return a, b


def _paired(env: Any, theta_a: np.ndarray, theta_b: np.ndarray, sigma: float, n: int,
            seed: int) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`paired_returns` and the trajectory-steps its rollouts lived (for the time budget):
    the episode lengths on the cart-pole, the horizon for every rollout otherwise."""
    out, steps = [], 0
    for theta in (theta_a, theta_b):
        th = np.asarray(theta, dtype=float)
        policy = LinearGaussianPolicy(th.reshape(task_hooks(env).action_dim, -1), sigma)
        if isinstance(env, CartPole):
            # The episode lengths alone: no baseline to form (the returns are the same either way).
            lengths = np.asarray(env.gradient_batch(policy, n, seed, baseline=False)[1])
            steps += int(lengths.sum())
            out.append(_discounted_sums(float(env.gamma), int(env.horizon))[lengths.astype(np.int64)])
        elif isinstance(env, Pendulum):
            out.append(env.episode_returns(policy, n, seed)[0])
            steps += int(env.horizon) * int(n)
        else:
            out.append(env.simulate(policy, n, seed).discounted_returns())
            steps += int(env.horizon) * int(n)
    return out[0], out[1], steps


@cache
def _discounted_sums(gamma: float, horizon: int) -> np.ndarray:
    r""":math:`\sum_{t < L} \gamma^t` for :math:`L = 0, \dots, H`, summed in order (exact integers at
    :math:`\gamma = 1`)."""
    table = np.zeros(horizon + 1)
    for t, p in enumerate(portable.powers(gamma, horizon)):
        table[t + 1] = table[t] + p
    table.flags.writeable = False
    return table


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
        ``simulate(policy, n, rng)`` and ``gamma`` (the cart-pole through its fused ``gradient_batch``).
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
            a, b, lived = _paired(env, T[k], T[k + 1], sigma, n - used[i], block_seed)
            steps += lived
            diffs[i].append(b - a)
            used[i] = n
            result[i] = _interval(np.concatenate(diffs[i]), tails)
            done[i] = result[i, 1] > 0 or result[i, 2] < 0
    outcome = np.where(result[:, 2] < 0, "lowered", np.where(result[:, 1] > 0, "raised", "undetermined"))
    return MonteCarloOutcomes(ks, result[:, 0], result[:, 1], result[:, 2], used, outcome.astype(str),
                              tuple(int(n) for n in looks), alpha, steps)


__all__ = ["MC_ALPHA", "MC_LOOKS", "MC_LOOKS_OUR_RUNS", "MonteCarloOutcomes", "closed_form_outcomes",
           "closed_form_summary", "clopper_pearson_upper", "monte_carlo_changes", "moved_updates", "normal_quantile",
           "paired_returns", "safety_summary", "theorem_assumptions"]
