r"""Methods compared on one trajectory budget, judged as rliable judges them: the pendulum's campaign.

A :class:`Comparison` runs Algorithm 4.1 in several variants (its adaptive :class:`RunConfig`\ s)
against policy gradient with fixed batch sizes, each with the safe coordinate step and with a
fixed step, every method on the same budget of trajectories and the same seeds:

1. **The fixed step, chosen by a stated rule on other seeds** (:class:`StepSearch`): for each
   batch size, every step of a grid is run on seeds that the comparison does not use
   (``first_seed`` onwards); each run's final parameters are judged on episodes of their own
   (``eval_seed``); the step with the highest mean return wins, a step with a diverged run
   is out, and ties go to the smaller step.
2. **The runs**: each method for ``seeds`` seeds (0, 1, ...), stored, seeded and resumable
   (:func:`safepg.runner.run_groups`).
3. **The judgement**: each run's final parameters on the same ``episodes`` evaluation episodes
   (common random numbers: the same starts and the same normals for every run), the
   undiscounted return, gymnasium's score; :mod:`safepg.stats` gives the mean and the IQM with
   their bootstrap intervals and the probability of improvement of each adaptive variant over
   each fixed one.
4. **Safety** on every update of the adaptive runs that moved theta: paired rollouts with their
   intervals, the Clopper-Pearson bound and the detection floor (:mod:`safepg.safety`).

:func:`pendulum_comparison` is the pendulum chapter's comparison; :func:`run_comparison` computes
what is missing and reads the rest (``python -m safepg run-book`` computes it before the pages).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from safepg import portable
from safepg.bounds import (
    ErrorBound,
    bernstein,
    chebyshev,
    gpomdp_variance_factor,
    gradient_range_bound,
    hoeffding,
)
from safepg.constants import TaskConstants
from safepg.envs.pendulum import Pendulum
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    n_star_closed_form,
    n_star_search,
    n_zero,
    penalty_constant,
)
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.record import LearningRecord
from safepg.runner import OnComputed, RunConfig, RunGroup, run_groups
from safepg.safety import MC_LOOKS_OUR_RUNS, MonteCarloOutcomes
from safepg.safety_store import is_measured, measure_runs
from safepg.stats import BOOTSTRAP_REPS, aggregate_scores, improvement_interval, probability_of_improvement


@dataclass(frozen=True)
class StepSearch:
    """The rule that chooses a fixed step, on seeds the comparison does not use.

    Parameters
    ----------
    alphas : tuple of float
        The steps tried, for each batch size.
    seeds : int
        Runs per step, seeds ``first_seed`` onwards.
    first_seed : int
        The first seed of the search (the comparison's are 0, 1, ...: far below it).
    episodes : int
        Evaluation episodes of each search run's final parameters.
    eval_seed : int
        The seed of those episodes (not the comparison's evaluation seed).
    """

    alphas: tuple[float, ...]
    seeds: int = 5
    first_seed: int = 1000
    episodes: int = 500
    eval_seed: int = 2

    def __post_init__(self) -> None:
        if not self.alphas or any(not (math.isfinite(a) and a > 0) for a in self.alphas):
            raise ValueError(f"alphas must be finite steps > 0, got {self.alphas!r}")
        for name in ("seeds", "episodes"):
            if int(getattr(self, name)) != getattr(self, name) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class Comparison:
    """Adaptive variants against fixed batch sizes on one budget (module docstring).

    Parameters
    ----------
    name : str
        The folder of the store the comparison's runs go to.
    task
        The fixed-batch methods' task, on which every final policy is judged.
    theta0 : tuple of float
        The start of every run.
    sigma : float
        The policy's standard deviation.
    budget : int
        Trajectories of every run.
    gradient : Gradient
        The estimator of the fixed-batch methods.
    adaptive : tuple of RunConfig
        The adaptive variants (each with its own task and options, the same start and budget).
    batch_sizes : tuple of int
        The fixed batch sizes.
    safe_step : SafeStep
        The fixed-batch methods' safe step.
    search : StepSearch
        The rule choosing their fixed step.
    seeds : int
        Runs per method.
    episodes : int
        M, the evaluation episodes every final policy is judged on.
    eval_seed : int
        Their seed.
    looks : tuple of int
        Rollouts per policy of the safety measurement's looks.
    """

    name: str
    task: Any
    theta0: tuple[float, ...]
    sigma: float
    budget: int
    gradient: Gradient
    adaptive: tuple[RunConfig, ...]
    batch_sizes: tuple[int, ...] = (100, 1000)
    safe_step: SafeStep = field(default_factory=SafeStep)
    search: StepSearch = field(default_factory=lambda: StepSearch((1e-4,)))
    seeds: int = 20
    episodes: int = 1000
    eval_seed: int = 1
    looks: tuple[int, ...] = MC_LOOKS_OUR_RUNS

    def _fixed(self, name: str, batch_size: int, step: FixedStep | SafeStep) -> RunConfig:
        return RunConfig(name, method=Vanilla(batch_size, step, self.gradient), task=self.task, theta0=self.theta0,
                         sigma=self.sigma, budget=self.budget)

    def search_configs(self) -> tuple[RunConfig, ...]:
        """Every (batch size, step) of the step search."""
        return tuple(self._fixed(f"search-N={n}-alpha={a:g}", n, FixedStep(a))
                     for n in self.batch_sizes for a in self.search.alphas)

    def fixed_configs(self, steps: Mapping[int, float]) -> tuple[RunConfig, ...]:
        """The fixed-batch methods: each batch size with the safe step and with its chosen fixed step."""
        return tuple(c for n in self.batch_sizes
                     for c in (self._fixed(f"N={n}-safe-step", n, self.safe_step),
                               self._fixed(f"N={n}-fixed-step", n, FixedStep(steps[n]))))

    def configs(self, steps: Mapping[int, float]) -> tuple[RunConfig, ...]:
        """Every method of the comparison, the adaptive variants first."""
        return self.adaptive + self.fixed_configs(steps)

    def folder(self, root: Path) -> Path:
        """The comparison's folder of the store."""
        return Path(root) / self.name


def final_returns(task: Any, thetas: np.ndarray, sigma: float, episodes: int, seed: int) -> np.ndarray:
    """Each parameter vector's mean undiscounted return over the same ``episodes`` episodes.

    Every row of ``thetas`` is judged on the episodes that ``seed`` draws: the same starts and the
    same standard normals (common random numbers), so that two policies differ by their own merit
    and not by their luck. The pendulum's kernel gives the returns; another task simulates. The
    mean is exactly rounded (:func:`!safepg.portable.fsum_mean`).
    """
    T = np.atleast_2d(np.asarray(thetas, dtype=float))
    out = np.empty(T.shape[0])
    for i, th in enumerate(T):
        policy = LinearGaussianPolicy(th.reshape(1, -1), sigma)
        if isinstance(task, Pendulum):
            returns = task.episode_returns(policy, episodes, seed)[1]
        else:
            returns = task.simulate(policy, episodes, seed).rewards.sum(axis=1)
        out[i] = portable.fsum_mean(returns)
    return out


@dataclass(frozen=True)
class ComparisonResult:
    """What :func:`run_comparison` returns.

    Attributes
    ----------
    comparison : Comparison
    steps : dict
        The chosen fixed step of each batch size.
    search_scores : dict
        For each batch size, each step's mean evaluated return over the search's runs (NaN: a run diverged).
    records : dict
        Each method's runs by config name, seed 0 first.
    scores : dict
        Each method's runs' evaluated returns (final parameters on the M evaluation episodes).
    start_score : float
        The start's evaluated return on the same episodes.
    start_standard_error : float
        The standard error of that mean over the M episodes: how far from J a policy's evaluated
        return may lie (the runs' differences are paired: measured on the same episodes).
    safety : dict
        Each adaptive variant's measurement of every update that moved theta, one per run.
    """

    comparison: Comparison
    steps: dict[int, float]
    search_scores: dict[int, dict[float, float]]
    records: dict[str, list[LearningRecord]]
    scores: dict[str, np.ndarray]
    start_score: float
    start_standard_error: float
    safety: dict[str, list[MonteCarloOutcomes]]

    def summary(self, reps: int = BOOTSTRAP_REPS, seed: int = 0) -> list[dict[str, Any]]:
        """Per method: :func:`safepg.stats.aggregate_scores` of its evaluated returns (mean and IQM with
        their 95% bootstrap intervals), the share of its runs that end above the start, and its name."""
        rows = []
        for k, (name, x) in enumerate(self.scores.items()):
            rows.append({"method": name, **aggregate_scores(x, reps, np.random.default_rng([seed, k])),
                         "improved": float(np.mean(x > self.start_score))})
        return rows

    def improvement(self, reps: int = BOOTSTRAP_REPS, seed: int = 1) -> list[dict[str, Any]]:
        """P(X > Y) of each adaptive variant X over each fixed-batch method Y, with its 95% bootstrap interval."""
        fixed = [c.name for c in self.comparison.fixed_configs(self.steps)]
        rows = []
        for i, a in enumerate(c.name for c in self.comparison.adaptive):
            for j, f in enumerate(fixed):
                x, y = self.scores[a], self.scores[f]
                rows.append({"adaptive": a, "fixed": f, "p": probability_of_improvement(x, y),
                             "ci95": improvement_interval(x, y, reps, rng=np.random.default_rng([seed, i, j]))})
        return rows

    def safety_counts(self) -> dict[str, dict[str, Any]]:
        """Each adaptive variant's updates over all its runs (:meth:`MonteCarloOutcomes.counts` of the
        runs joined), with the largest detection floor and bound of a single run."""
        out = {}
        for name, parts in self.safety.items():
            measured = [p for p in parts if p.updates.size]
            counts = MonteCarloOutcomes.join(measured).counts() if measured else {
                "updates": 0, "lowered": 0, "raised": 0, "undetermined": 0, "share_lowered_upper95": None,
                "detection_floor": 0.0, "rollouts": 0}
            per_run = [p.counts() for p in measured]
            out[name] = {**counts, "runs": len(parts), "runs_with_updates": len(measured),
                         "largest_run_floor": max((c["detection_floor"] for c in per_run), default=0.0),
                         "largest_run_upper95": max((c["share_lowered_upper95"] for c in per_run), default=None)}
        return out


def _search_scores(cmp: Comparison, records: Mapping[str, list[LearningRecord]]) -> dict[int, dict[float, float]]:
    out: dict[int, dict[float, float]] = {}
    for cfg in cmp.search_configs():
        assert isinstance(cfg.method, Vanilla) and isinstance(cfg.method.step, FixedStep)
        recs = records[cfg.name]
        if any(r.diverged for r in recs) or len(recs) < cmp.search.seeds:
            score = math.nan
        else:
            finals = np.array([r.theta_final for r in recs])
            score = portable.fsum_mean(final_returns(cmp.task, finals, cmp.sigma, cmp.search.episodes,
                                                     cmp.search.eval_seed))
        out.setdefault(cfg.method.batch_size, {})[cfg.method.step.alpha] = score
    return out


def choose_steps(scores: Mapping[int, Mapping[float, float]]) -> dict[int, float]:
    """The rule of :class:`StepSearch`: for each batch size the step with the highest mean evaluated
    return, a step with a diverged run (NaN) left out, ties to the smaller step."""
    out = {}
    for n, by_alpha in scores.items():
        finite = {a: s for a, s in by_alpha.items() if math.isfinite(s)}
        if not finite:
            raise ValueError(f"scores must hold a step without divergence for N = {n}")
        out[n] = min(finite, key=lambda a: (-finite[a], a))
    return out


def run_comparison(cmp: Comparison, root: Path, jobs: int = -1, progress: bool = False,
                   report: Callable[[str], object] | None = None,
                   on_computed: OnComputed | None = None) -> ComparisonResult:
    """Compute what is missing of ``cmp`` into ``root`` and return it all (:class:`ComparisonResult`).

    The step search and the adaptive variants are dispatched together; then the fixed-batch
    methods (their fixed step comes from the search); then the safety measurements of the
    adaptive runs, each stored once (:func:`!safepg.safety_store.measure_runs`). Everything is seeded:
    the same call gives the same numbers, and a stored run or measurement is read, not recomputed.

    Parameters
    ----------
    cmp : Comparison
    root : Path
        The store; the comparison's folder is ``root / cmp.name``.
    jobs : int
        joblib's workers (-1: every core).
    progress : bool
        tqdm bars of the runs.
    report : callable, optional
        Called with one line as each stage ends.
    on_computed : callable, optional
        Passed to :func:`safepg.runner.run_groups`: called for each folder runs were computed in, with
        how long they took (nothing is written for it otherwise).
    """
    say = report or (lambda _line: None)
    folder = cmp.folder(root)
    search = RunGroup(cmp.search_configs(), cmp.search.seeds, folder / "search", first_seed=cmp.search.first_seed)
    adaptive = RunGroup(cmp.adaptive, cmp.seeds, folder)
    search_records, adaptive_records = run_groups([search, adaptive], jobs, progress, f"{cmp.name}: search, adaptive",
                                                  on_computed)
    scores_by_step = _search_scores(cmp, search_records)
    steps = choose_steps(scores_by_step)
    say(f"fixed steps chosen on seeds {cmp.search.first_seed}-{cmp.search.first_seed + cmp.search.seeds - 1}: "
        + ", ".join(f"N = {n}: {a:g}" for n, a in steps.items()))
    fixed_records = run_groups([RunGroup(cmp.fixed_configs(steps), cmp.seeds, folder)], jobs, progress,
                               f"{cmp.name}: fixed batches", on_computed)[0]
    records = {**adaptive_records, **fixed_records}
    say(f"runs: {sum(len(v) for v in records.values())} of {cmp.seeds * len(records)}")
    safety = {}
    for cfg in cmp.adaptive:
        safety[cfg.name] = measure_runs(cfg.make_task(), [r.theta for r in records[cfg.name]], cmp.sigma,
                                        folder / "safety-mc", looks=cmp.looks, jobs=_workers(jobs))
    say("safety measured on every update of the adaptive runs")
    order = [c.name for c in cmp.configs(steps)]
    scores = {name: final_returns(cmp.task, np.array([r.theta_final for r in records[name]]), cmp.sigma,
                                  cmp.episodes, cmp.eval_seed) for name in order}
    start = float(final_returns(cmp.task, np.asarray(cmp.theta0), cmp.sigma, cmp.episodes, cmp.eval_seed)[0])
    return ComparisonResult(cmp, steps, scores_by_step, {n: records[n] for n in order}, scores, start,
                            _standard_error(cmp), safety)


def _standard_error(cmp: Comparison) -> float:
    """The sample standard deviation of the start's M evaluation returns over sqrt(M) (exact sums)."""
    policy = LinearGaussianPolicy(np.asarray(cmp.theta0, dtype=float).reshape(1, -1), cmp.sigma)
    if isinstance(cmp.task, Pendulum):
        x = cmp.task.episode_returns(policy, cmp.episodes, cmp.eval_seed)[1]
    else:
        x = cmp.task.simulate(policy, cmp.episodes, cmp.eval_seed).rewards.sum(axis=1)
    m = portable.fsum_mean(x)
    return math.sqrt(math.fsum(((x - m) * (x - m)).tolist()) / (x.size - 1)) / math.sqrt(x.size)


def is_computed(cmp: Comparison, root: Path) -> bool:
    """Whether :func:`run_comparison` would compute nothing (every run and measurement stored)."""
    from safepg.runner import load_configs

    folder = cmp.folder(root)
    search = load_configs(cmp.search_configs(), cmp.search.seeds, folder / "search", first_seed=cmp.search.first_seed)
    if any(len(v) < cmp.search.seeds for v in search.values()):
        return False
    steps = choose_steps(_search_scores(cmp, search))
    stored = load_configs(cmp.configs(steps), cmp.seeds, folder)
    if any(len(v) < cmp.seeds for v in stored.values()):
        return False
    return all(is_measured(folder / "safety-mc", cfg.make_task(), r.theta, cmp.sigma, cmp.looks)
               for cfg in cmp.adaptive for r in stored[cfg.name])


def _workers(jobs: int) -> int:
    from joblib import effective_n_jobs

    return int(effective_n_jobs(jobs))


# ------------------------------------------------------------------ what a guarantee costs
def guarantee_costs(task: Any, sigma: float, g: float, sample_variance: float, sample_range: float,
                    deltas: Sequence[float]) -> list[dict[str, Any]]:
    r"""N*, the step and the improvement each bound guarantees at a gradient ``g`` (Section 4.3).

    For each bound (Chebyshev with the G(PO)MDP variance bound; Hoeffding and empirical Bernstein,
    each with Lemma 4.3.3's range and with the batch's range ``sample_range``) and each
    :math:`\delta`: :math:`d_\delta`, :math:`f_\delta`, :math:`N_0` (the smallest batch whose
    :math:`\epsilon` is below g), :math:`N^*` (the maximiser of :math:`\Upsilon_\delta`), the step
    :math:`\alpha^*` and the improvement guaranteed at :math:`N^*`, with the task's penalty
    constant c. ``sample_variance`` is the G(PO)MDP samples' variance of Bernstein's bound.
    """
    constants = TaskConstants.from_task(task, sigma)
    c = penalty_constant(constants)
    lemma = gradient_range_bound(constants)
    rows = []
    for delta in deltas:
        bounds: list[tuple[str, bool, ErrorBound]] = [
            ("chebyshev", False, chebyshev(delta, gpomdp_variance_factor(constants))),
            ("hoeffding", False, hoeffding(delta, lemma)), ("hoeffding", True, hoeffding(delta, sample_range)),
            ("bernstein", False, bernstein(delta, sample_variance, lemma)),
            ("bernstein", True, bernstein(delta, sample_variance, sample_range))]
        for bound, empirical, bd in bounds:
            n_star = n_star_closed_form(g, bd) if bd.f == 0 else n_star_search(g, bd, c)
            eps = float(bd.eps(n_star))
            rows.append({"bound": bound, "empirical_range": empirical, "delta": float(delta), "d": bd.d, "f": bd.f,
                         "N0": n_zero(g, bd), "Nstar": n_star, "eps": eps, "alpha": coordinate_step(g, eps, c),
                         "improvement": guaranteed_improvement(g, eps, c), "c": c})
    return rows


def updated_gradients(records: Sequence[LearningRecord]) -> np.ndarray:
    r""":math:`|\hat g_k|` of every update of ``records``, run after run: the gradient component each
    update was about (the largest one of the batch's estimate)."""
    return np.concatenate([np.abs(r.grad[np.arange(r.iterations), np.maximum(r.coordinate, 0)]) for r in records])


def update_terms(records: Sequence[LearningRecord]) -> dict[str, Any]:
    r"""Why an adaptive method moves theta or not, in numbers, over the updates of ``records``.

    The penalty constant c of the runs (``config["c"]``, from the task's bounds: the per-batch
    constants of ``Departures(batch_constants=True)`` are not recorded), and over every update:
    :math:`|\hat g_k|`, :math:`\epsilon` and their ratio, the step :math:`\alpha`, the share of
    updates with :math:`\epsilon < |\hat g_k|` (the guarded step moves only there), and the largest
    distance the runs' theta moved from its start (the infinity norm).
    """
    g = updated_gradients(records)
    eps = np.concatenate([r.eps for r in records])
    alpha = np.concatenate([r.alpha for r in records])
    return {"c": float(records[0].config["c"]), "updates": int(g.size),
            "g_median": float(np.median(g)), "eps_median": float(np.median(eps)),
            "eps_over_g_median": float(np.median(eps / g)), "share_eps_below_g": float(np.mean(eps < g)),
            "alpha_max": float(alpha.max()), "alpha_median": float(np.median(alpha)),
            "batch_median": float(np.median(np.concatenate([r.batch_size for r in records]))),
            "moved_max": float(max(np.abs(r.theta - r.theta[0]).max() for r in records))}


# ------------------------------------------------------------------ the pendulum's comparison
#: The steps the pendulum's search tries for each batch size.
PENDULUM_ALPHAS = (1e-5, 3e-5, 1e-4, 3e-4, 1e-3)
#: Trajectories of every run of the pendulum's comparison.
PENDULUM_BUDGET = 20_000


def pendulum_comparison(seeds: int = 20, budget: int = PENDULUM_BUDGET, episodes: int = 1000) -> Comparison:
    r"""The pendulum chapter's comparison: :class:`~safepg.envs.pendulum.Pendulum` (gamma = 0.99), from
    theta = 0 with sigma = 1, G(PO)MDP with its baseline and the score of the sampled action, on
    ``budget`` trajectories a run, ``seeds`` seeds, every final policy judged on ``episodes`` episodes.

    The adaptive variants, each Algorithm 4.1 with delta = 0.95:

    - ``algorithm-4.1-chebyshev``: as the thesis states it, Chebyshev's bound with the G(PO)MDP
      variance bound, N_min = 100, N_max = 100 000;
    - ``algorithm-4.1-bernstein-er``: empirical Bernstein with the batch's own range (the empirical
      range), the same limits;
    - ``authors-relaxations``: the empirical range and everything the authors' cart-pole code did
      otherwise (``table-5.4-authors``): the undiscounted return (gamma = 1) with gamma = 0.9 in the
      penalty constant, R and M_phi measured on each batch, the largest variance and range over the
      components, the step taken even where eps >= |g_k|, a first batch of 1000 and N_min = 10.

    The fixed batches N = 100 and N = 1000 with the safe coordinate step (the same empirical
    Bernstein bound) and with a fixed step chosen on 5 other seeds from :data:`PENDULUM_ALPHAS`.
    """
    gradient = Gradient(score_action="raw")
    task = Pendulum()
    er = ErrorModel("bernstein", 0.95, "empirical")
    start = (0.0, 0.0, 0.0)

    def run(name: str, method: Adaptive, on: Pendulum = task) -> RunConfig:
        return RunConfig(name, method=method, task=on, theta0=start, sigma=1.0, budget=budget)

    adaptive = (
        run("algorithm-4.1-chebyshev", Adaptive(gradient, ErrorModel("chebyshev", 0.95), Batches(100, 100_000))),
        run("algorithm-4.1-bernstein-er", Adaptive(gradient, er, Batches(100, 100_000))),
        run("authors-relaxations", Adaptive(gradient, er, Batches(10, 100_000, first=1000),
                                            Departures(True, True, True)),
            replace(task, gamma=1.0, constants_gamma=0.9)),
    )
    return Comparison("pendulum", task, start, 1.0, budget, gradient, adaptive, (100, 1000),
                      SafeStep("coordinate", er), StepSearch(PENDULUM_ALPHAS), seeds, episodes)


__all__ = ["Comparison", "ComparisonResult", "PENDULUM_ALPHAS", "PENDULUM_BUDGET", "StepSearch", "choose_steps",
           "final_returns", "guarantee_costs", "is_computed", "pendulum_comparison", "run_comparison",
           "update_terms", "updated_gradients"]
