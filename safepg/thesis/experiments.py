r"""The experiments of Chapter 5, defined once as data, with the values the thesis prints.

An :class:`Experiment` is a named group of :class:`~safepg.runner.RunConfig` (one row of
a table or one curve of a figure) run for several seeds, with the thesis's printed values
beside them; :data:`EXPERIMENTS` holds them all by name. Which run starts where another ended
(the cart-pole adaptation of Section 5.3 starts from each seed's baseline policy) is known
here: the runner only receives the starting points.

:func:`safepg.thesis.experiment_store.run_experiment` runs what is missing into the results
folder and :func:`safepg.thesis.report.report` puts ours beside the printed values.
"""

from __future__ import annotations

from dataclasses import KW_ONLY, dataclass, field, replace
from functools import partial
from typing import Any, Literal, TypeVar

import numpy as np

from safepg.bounds import Bound, Range
from safepg.envs.lqg import LQG
from safepg.estimators import Estimator
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.runner import RunConfig
from safepg.runner import make_env as make_core_env
from safepg.thesis.authors import TABLE_5_4_BUDGET, cartpole_theta_star, table52_settings
from safepg.thesis.sweep_settings import CARTPOLE_SWEEP, SWEEP_BASELINE_CAP, SWEEP_BUDGET, SWEEP_SEEDS

#: The 2-D LQG the Section 5.2 experiments run on: the printed task with gamma = 0.9 instead
#: of the printed 0.95, the discount that reproduces the printed theta*, final parameters and
#: Table 5.3 (see :mod:`safepg.thesis.lqg_settings` and the chapter).
LQG2D_GAMMA = 0.9
#: Tasks of the reproduction beyond the core's named ones, by the name their runs are keyed on.
THESIS_ENVS = {"lqg2d-gamma0.9": partial(LQG.thesis_2d, gamma=LQG2D_GAMMA)}
#: That task, as the Section 5.2 configurations hold it.
LQG2D_TASK = THESIS_ENVS["lqg2d-gamma0.9"]()


def make_env(name: str) -> Any:
    """Environment by name: :func:`safepg.runner.make_env`'s tasks and ``lqg2d-gamma0.9``.

    ``lqg1d`` (Section 5.1), ``lqg2d`` (Section 5.2 as printed, gamma = 0.95),
    ``lqg2d-gamma0.9`` (the discount the Section 5.2 experiments run with),
    ``cartpole`` and ``cartpole-doubled`` (Section 5.3: 1 m pole, then 2 m), optionally
    with settings in brackets, ``cartpole-doubled[gamma=0.995]``.
    """
    return THESIS_ENVS[name]() if name in THESIS_ENVS else make_core_env(name)


@dataclass(frozen=True)
class Experiment:
    """A named set of configurations run for ``seeds`` seeds each.

    ``thesis`` maps a config name to the values the thesis prints for it. ``performance``
    is what the improvement ratio is computed on: the closed-form ``"J"`` (the LQG) or the
    batch-average return ``"J_hat"`` (the cart-pole, which has no closed form). ``rules``
    is how :func:`report` counts: ``"ours"`` (the share of updates after which performance
    did not decrease; Upsilon-bar over all trajectories) or ``"authors"`` (their plot
    scripts, :mod:`safepg.thesis.authors`: strict increases between the performances at the
    batch starts; on the cart-pole only the batches that end before the run's budget).
    """

    name: str
    description: str
    configs: tuple[RunConfig, ...]
    _: KW_ONLY
    seeds: int = 5
    thesis: dict[str, dict[str, Any]] = field(default_factory=dict)
    performance: Literal["J", "J_hat"] = "J"
    rules: Literal["ours", "authors"] = "ours"

    def config(self, name: str) -> RunConfig:
        """The configuration named ``name``."""
        for c in self.configs:
            if c.name == name:
                return c
        raise KeyError(f"{self.name} has no config {name!r}")

    def single_config(self) -> RunConfig:
        """The one configuration of an experiment another warm-starts from."""
        if len(self.configs) != 1:
            raise ValueError(f"warm_start must name an experiment with one config, {self.name!r} has "
                             f"{len(self.configs)}")
        return self.configs[0]


_M = TypeVar("_M", Adaptive, Vanilla)


def method_of(config: RunConfig, kind: type[_M]) -> _M:
    """``config``'s method, of the kind the caller knows it to be (to read or change the options only
    that kind has).

    Parameters
    ----------
    config : RunConfig
    kind : {Adaptive, Vanilla}
        The class of the method ``config`` runs.

    Raises
    ------
    TypeError
        If ``config`` runs the other kind of method.
    """
    if not isinstance(config.method, kind):
        raise TypeError(f"config {config.name!r} must run a {kind.__name__} method, got {config.method!r}")
    return config.method


def _with_gradient(method: Adaptive | Vanilla, **changes: Any) -> Adaptive | Vanilla:
    """``method`` with fields of its :class:`~safepg.options.Gradient` changed."""
    return replace(method, gradient=replace(method.gradient, **changes))


def _with_error(method: Adaptive, **changes: Any) -> Adaptive:
    """``method`` with fields of its :class:`~safepg.options.ErrorModel` changed."""
    return replace(method, error=replace(method.error, **changes))


#: The seeds an experiment starts with when its runs feed a whole curve of the scorecard (Figures 5.1-5.9),
#: by the scorecard's seed rule (:mod:`safepg.thesis.seed_rule`); the others start with the default 5, the
#: thesis's count. A curve is tested against their five runs by a permutation test, whose smallest p-value
#: is 2/252 against five of ours and 1/3003 against ten (a tenth of the level the scorecard's correction
#: reaches, about 0.01, needs at least 8), or against their one run by Hotelling's test of three block
#: means, with k - 3 degrees of freedom.
CURVE_SEEDS = 10

#: The bound of Table 5.3 and Table 5.4's adaptive runs: empirical Bernstein with the batch's range.
BERNSTEIN_ER = ErrorModel("bernstein", 0.95, "empirical")


# ------------------------------------------------------------------ Section 5.1
T51_ALPHAS = (1e-3, 1e-4, 1e-5, 1e-6)
T51_NS = (10_000, 1_000, 100)
#: Table 5.1 as printed: improvement ratio (%) by sigma, N, alpha.
T51_PRINTED: dict[float, dict[int, tuple[float, ...]]] = {
    0.5: {10_000: (95.96, 100, 98.99, 100), 1_000: (52.85, 73.27, 81.88, 83.88), 100: (49.79, 51.41, 55.69, 58.44)},
    1.0: {10_000: (24.24, 100, 100, 100), 1_000: (37.4, 27.03, 99.9, 100), 100: (50.4, 46.08, 39.04, 86.04)},
}


#: Starting point the thesis prints for Table 5.1.
T51_PRINTED_THETA0 = -0.55
#: Starting point Table 5.1 is run from: our reconstruction, not printed. With it all 24 cells
#: come within 2 points of the printed ratios at once (from the printed -0.55, 9 cells are
#: 5-40 points off); the sweep of safepg.thesis.table51_sweep shows that no other unstated setting
#: (baseline, score, sigma reading, J formula, counting) does this from -0.55, and that
#: -0.57 and -0.58 are already clearly worse.
T51_THETA0 = -0.575


def _table_5_1(theta0: float = T51_THETA0) -> Experiment:
    configs, thesis = [], {}
    for sigma in (0.5, 1.0):
        for n in T51_NS:
            for alpha, printed in zip(T51_ALPHAS, T51_PRINTED[sigma][n]):
                name = f"sigma={sigma}-N={n}-alpha={alpha:.0e}"
                configs.append(RunConfig(name, method=Vanilla(n, FixedStep(alpha)), theta0=(theta0,), sigma=sigma,
                                         budget=1_000_000))
                thesis[name] = {"improvement_ratio": round(printed / 100, 6)}
    return Experiment("table-5.1", "Improvement ratio of vanilla G(PO)MDP with fixed step and batch "
                      f"size, 10^6 trajectories (Table 5.1), from theta_0 = {theta0} (the thesis prints "
                      f"{T51_PRINTED_THETA0}; {T51_THETA0} is our reconstruction).", tuple(configs), thesis=thesis)


def _table_5_1_printed_theta0() -> Experiment:
    return replace(_table_5_1(T51_PRINTED_THETA0), name="table-5.1-printed-theta0",
                   description="Table 5.1 from the printed theta_0 = -0.55 (the variance-minimising baseline, "
                               "as in table-5.1): 9 of the 24 cells are more than 5 points off.")


#: Table 5.2 as printed: (estimator, bound, empirical range, delta, Upsilon-bar, CI).
_T52_PRINTED: list[tuple[Estimator, Bound, bool, float, float, tuple[float, float]]] = [
    ("reinforce", "chebyshev", False, 0.95, -11.3266, (-11.3277, -11.3256)),
    ("reinforce", "chebyshev", False, 0.75, -11.4303, (-11.4308, -11.4297)),
    ("reinforce", "chebyshev", False, 0.5, -11.5947, (-11.5958, -11.5937)),
    ("gpomdp", "chebyshev", False, 0.95, -10.6085, (-10.6087, -10.6083)),
    ("gpomdp", "chebyshev", False, 0.75, -10.7141, (-10.7145, -10.7136)),
    ("gpomdp", "chebyshev", False, 0.5, -10.9036, (-10.9040, -10.9031)),
    ("gpomdp", "chebyshev", False, 0.25, -11.2355, (-11.2363, -11.2346)),
    ("gpomdp", "chebyshev", False, 0.05, -11.836, (-11.8368, -11.8352)),
    ("gpomdp", "hoeffding", False, 0.95, -11.914, (-11.9143, -11.9136)),
    ("gpomdp", "bernstein", False, 0.95, -10.2159, (-10.2162, -10.2155)),
    ("gpomdp", "hoeffding", True, 0.95, -9.8582, (-9.8589, -9.8574)),
    # Printed as [-9.6619; -9.6627]: the interval's ends are swapped in the thesis.
    ("gpomdp", "bernstein", True, 0.95, -9.6623, (-9.6627, -9.6619)),
]


def t52_name(estimator: str, bound: str, empirical_range: bool, delta: float) -> str:
    return f"{estimator}-{bound}{'-er' if empirical_range else ''}-delta={delta}"


#: Gradient range of the theoretical-range rows of Table 5.2 (Hoeffding and Bernstein without
#: the empirical range): 1280 = 4 H M_phi A_bar R / sigma^2, a fifth of Lemma 4.3.3's
#: 2 H M_phi A_bar R / (sigma^2 (1 - gamma)) = 6400. Not printed anywhere: it is our
#: reconstruction, the default because it reproduces both printed rows to 4 digits at once
#: (-11.914 and -10.216), while 6400 reproduces neither (experiment table-5.2-lemma-range).
RECONSTRUCTED_RANGE = 1280.0


def _table_5_2() -> Experiment:
    configs, thesis = [], {}
    for est, bound, er, delta, ups, ci in _T52_PRINTED:
        name = t52_name(est, bound, er, delta)
        # Only Hoeffding/Bernstein without the empirical range use a range other than the batch's.
        grad_range: Range = "empirical" if er else RECONSTRUCTED_RANGE if bound != "chebyshev" else "lemma"
        configs.append(RunConfig(name, method=Adaptive(Gradient(est), ErrorModel(bound, delta, grad_range))))
        thesis[name] = {"upsilon_bar": ups, "ci95": list(ci)}
    return Experiment("table-5.2", "Adaptive batch size on the 1-D LQG: the twelve estimator x bound x "
                      "delta rows of Table 5.2 (theta_0 = 0, sigma = 1, 3*10^7 trajectories), "
                      "also Figures 5.1-5.4; the theoretical range is our reconstruction 1280.",
                      tuple(configs), seeds=CURVE_SEEDS, thesis=thesis)


def _theoretical_range_rows(t52: Experiment) -> list[RunConfig]:
    """The rows of Table 5.2 run with a given range (Hoeffding and Bernstein without the empirical range)."""
    return [c for c in t52.configs if isinstance(c.method, Adaptive) and c.method.error.theoretical_range is not None]


def _table_5_2_lemma_range() -> Experiment:
    t52 = _table_5_2()
    configs, thesis = [], {}
    for c in _theoretical_range_rows(t52):
        name = f"{c.name}-lemma-range"
        configs.append(replace(c, name=name, method=_with_error(method_of(c, Adaptive), range="lemma")))
        thesis[name] = t52.thesis[c.name]
    return Experiment("table-5.2-lemma-range", "The two theoretical-range rows of Table 5.2 with Lemma "
                      "4.3.3's range 6400 instead of the reconstructed 1280 (the printed lemma, which "
                      "reproduces neither row).", tuple(configs), thesis=thesis)


def _table_5_1_no_baseline() -> Experiment:
    t51 = _table_5_1(T51_PRINTED_THETA0)
    return replace(t51, name="table-5.1-no-baseline",
                   description="Table 5.1 from the printed theta_0 = -0.55 with G(PO)MDP without baseline "
                               "(b = 0): the thesis does not say which baseline it used.",
                   configs=tuple(replace(c, method=_with_gradient(c.method, baseline=False)) for c in t51.configs))


def _table_5_2_raw_score() -> Experiment:
    t52 = _table_5_2()
    keep = [t52_name("gpomdp", "chebyshev", False, 0.95), t52_name("gpomdp", "bernstein", True, 0.95)]
    configs = tuple(replace(t52.config(n), name=f"{n}-raw-score",
                            method=_with_gradient(t52.config(n).method, score_action="raw")) for n in keep)
    return Experiment("table-5.2-raw-score", "Two rows of Table 5.2 with the unbiased score of the sampled "
                      "(unclipped) action instead of the authors' clipped-action score.", configs,
                      thesis={f"{n}-raw-score": t52.thesis[n] for n in keep})


# ------------------------------------------------------------------ Section 5.2
#: Final parameters printed in Section 5.2.1 after 3*10^7 trajectories (row-major 2 x 2).
_PRINTED_THETA_SCALAR = [[-0.014676, 1.4e-06], [1.7e-06, -0.013678]]
_PRINTED_THETA_COORDINATE = [[-0.0275, 0.0], [0.0, -0.0274]]


def _figures_5_5_5_6() -> Experiment:
    error = ErrorModel("chebyshev", 0.95)
    configs = tuple(RunConfig(kind, method=Vanilla(2000, SafeStep(kind, error)), task=LQG2D_TASK,
                              theta0=(0.0,) * 4) for kind in ("scalar", "coordinate"))
    thesis = {"scalar": {"improvement_ratio": 1.0, "theta_final": _PRINTED_THETA_SCALAR},
              "coordinate": {"improvement_ratio": 1.0, "theta_final": _PRINTED_THETA_COORDINATE}}
    return Experiment("figures-5.5-5.6", "2-D LQG: the scalar adaptive step of Pirotta et al. (2013) against the "
                      "coordinate step Lambda* (G(PO)MDP, Chebyshev, delta = 0.95, N = 2000, 3*10^7 trajectories), "
                      "Figures 5.5-5.6.", configs, seeds=CURVE_SEEDS, thesis=thesis)


def _table_5_3() -> Experiment:
    task = partial(RunConfig, task=LQG2D_TASK, theta0=(0.0,) * 4)
    configs = (task("adaptive", method=Adaptive(error=BERNSTEIN_ER)),
               task("N=1000", method=Vanilla(1000, FixedStep(1e-6))),
               task("N=100", method=Vanilla(100, FixedStep(1e-6))))
    thesis = {"adaptive": {"upsilon_bar": -20.50, "improvement_ratio": 1.0},
              "N=1000": {"upsilon_bar": -22.39, "improvement_ratio": 1.0},
              "N=100": {"upsilon_bar": -19.77, "improvement_ratio": 0.89}}
    return Experiment("table-5.3", "2-D LQG: adaptive batch size (G(PO)MDP, Bernstein with empirical range, "
                      "delta = 0.95) against fixed N = 1000 and N = 100 with alpha = 1e-6, 3*10^7 "
                      "trajectories (Table 5.3, Figures 5.7-5.8).", configs, seeds=CURVE_SEEDS, thesis=thesis)


# ------------------------------------------------------------------ Section 5.3
#: Trajectories per run after the pole is doubled, the same for both methods (the thesis
#: does not state its budget): 500 iterations of the vanilla method's N = 4000.
CARTPOLE_BUDGET = 2_000_000
#: Cap on the baseline search (the thesis reached 195 in 72 iterations of N = 4000).
_BASELINE_CAP = 4000 * 400


def _cartpole_baseline() -> Experiment:
    cfg = RunConfig("baseline", method=Vanilla(4000, FixedStep(0.01), target=Target(195.0)), task="cartpole",
                    theta0=(0.0,) * 4, budget=_BASELINE_CAP)
    return Experiment("cartpole-baseline", "Cart-pole, 1 m pole: vanilla G(PO)MDP with alpha = 0.01 and "
                      "N = 4000 from theta = 0 until a batch's average return reaches 195 (Section 5.3).",
                      (cfg,), thesis={"baseline": {"iterations": 72, "J_hat_final": 195.0}}, performance="J_hat")


def _table_5_4() -> Experiment:
    task = partial(RunConfig, task="cartpole-doubled", warm_start="cartpole-baseline", budget=CARTPOLE_BUDGET)
    configs = (task("adaptive", method=Adaptive(error=BERNSTEIN_ER)),
               task("N=4000", method=Vanilla(4000, FixedStep(0.01))))
    thesis = {"adaptive": {"upsilon_bar": 193.12, "improvement_ratio": 0.5301},
              "N=4000": {"upsilon_bar": 192.86, "improvement_ratio": 0.4476}}
    return Experiment("table-5.4", "Cart-pole with the pole doubled (2 m), from each seed's baseline policy: "
                      "adaptive (G(PO)MDP, Bernstein with empirical range, delta = 0.95) against vanilla "
                      f"alpha = 0.01, N = 4000, {CARTPOLE_BUDGET:.0e} trajectories each (Table 5.4, "
                      "Figure 5.9).", configs, seeds=CURVE_SEEDS, thesis=thesis, performance="J_hat")




def _sweep_baselines() -> list[Experiment]:
    base = _cartpole_baseline()
    out = []
    for st in CARTPOLE_SWEEP.values():
        if st.task and st.warm_start is None:
            cfg = replace(base.configs[0], task=st.env(doubled=False, constants=False), budget=SWEEP_BASELINE_CAP)
            out.append(replace(base, name=st.baseline_experiment, configs=(cfg,), seeds=SWEEP_SEEDS,
                               description=f"Cart-pole sweep: the baseline search with {st.label} "
                                           f"(capped at {SWEEP_BASELINE_CAP // 4000} iterations)."))
    return out


def _cartpole_sweep() -> Experiment:
    t54 = _table_5_4()
    adaptive, vanilla = t54.config("adaptive"), t54.config("N=4000")
    configs = []
    for st in CARTPOLE_SWEEP.values():
        if not st.doubled:
            continue
        configs.append(replace(adaptive, name=f"{st.key}:adaptive", task=st.env(doubled=True),
                               warm_start=st.baseline_experiment, budget=SWEEP_BUDGET))
        if not st.constants or st.task:  # a constants-only setting shares the default's vanilla run
            configs.append(replace(vanilla, name=f"{st.key}:N=4000", task=st.env(doubled=True, constants=False),
                                   warm_start=st.baseline_experiment, budget=SWEEP_BUDGET))
    # Every setting is held against Table 5.4 as printed (report --json shows them side by side).
    thesis = {c.name: t54.thesis["adaptive" if c.algorithm == "adaptive" else "N=4000"] for c in configs}
    return Experiment("cartpole-sweep", "Cart-pole sweep over the settings the thesis leaves unstated: adaptive "
                      "(Bernstein with empirical range, delta = 0.95) and vanilla (alpha = 0.01, N = 4000) on "
                      f"the doubled pole from each setting's baseline, {SWEEP_BUDGET:.0e} trajectories, "
                      f"{SWEEP_SEEDS} seeds.", tuple(configs), seeds=SWEEP_SEEDS, thesis=thesis,
                      performance="J_hat")


# ------------------------------------------------------------------ the authors' settings
# What the authors' code ran where the thesis says otherwise or nothing (their repository
# T3p/adaptive-batch-size: scripts and raw outputs, safepg.thesis.authors). Each setting is a
# parameter of the library; these experiments combine them.

#: Table 5.1's starting point in every one of the authors' 24 output files.
AUTHORS_T51_THETA0 = -0.575853
#: The cart-pole their scripts simulated: gym's 12 degrees, the undiscounted return (their
#: gamma ** l was typed sigma ** l, with sigma = 1) and gamma = 0.9 in the penalty constant;
#: doubling the pole kept the 1 m pole's m l = 0.05 (gym caches it before ``length *= 2``).
AUTHORS_CARTPOLE = {"angle_threshold_deg": 12.0, "gamma": 1.0, "constants_gamma": 0.9}
AUTHORS_DOUBLED = {**AUTHORS_CARTPOLE, "polemass_length": 0.05}
#: Their adaptive runs (2-D and cart-pole): the largest sample variance and range over the
#: components, and the step taken even when eps >= |g_k|.
AUTHORS_DEPARTURES = Departures(maxima=True, unguarded_step=True)


def _authors_cartpole(doubled: bool) -> str:
    from safepg.envs.cartpole import CartPole

    task = CartPole.thesis_doubled(**AUTHORS_DOUBLED) if doubled else CartPole.thesis(**AUTHORS_CARTPOLE)
    return task.setting_name()


def _table_5_1_authors() -> Experiment:
    return replace(_table_5_1(AUTHORS_T51_THETA0), name="table-5.1-authors", rules="authors",
                   description="Table 5.1 as the authors ran and counted it: from theta_0 = -0.575853 (their output "
                               "files), strict increases of J between batch starts over 10^6/N - 1 updates.")


#: Table 5.1's cell whose print, the authors' own run (270 increases in 999 updates), lies outside our
#: prediction interval for one run under their settings: sigma = 1, N = 1000, alpha = 1e-4.
T51_TAIL_CELL = "sigma=1.0-N=1000-alpha=1e-04"
#: Seeds of that cell's rerun. What the verdict needs is the spread of one run's ratio, to place the print
#: in it: n seeds estimate a standard deviation within a relative 1/sqrt(2 (n - 1)), 10% at 50 (a third
#: at the table's 5), so the print's distance in standard deviations is known to about +-0.25.
T51_TAIL_SEEDS = 50


def _table_5_1_authors_tail() -> Experiment:
    t51a = _table_5_1_authors()
    return Experiment("table-5.1-authors-tail", "Table 5.1's cell sigma = 1, N = 1000, alpha = 1e-4 under the authors' "
                      f"settings with {T51_TAIL_SEEDS} seeds: where their run (27.03%) lies in the distribution of one "
                      "run's improvement ratio.", (t51a.config(T51_TAIL_CELL),), seeds=T51_TAIL_SEEDS,
                      thesis={T51_TAIL_CELL: t51a.thesis[T51_TAIL_CELL]}, rules="authors")


def _table_5_3_authors() -> Experiment:
    adaptive = _table_5_3().config("adaptive")
    cfg = replace(adaptive, method=replace(method_of(adaptive, Adaptive), batches=Batches(n_max=100_000),
                                           departures=AUTHORS_DEPARTURES))
    return Experiment("table-5.3-authors", "Table 5.3's adaptive run as the authors' script ran it: N_max = 100000, "
                      "Bernstein on the largest variance and range over the components, the step taken even when "
                      "eps >= |g_k|; strict improvement ratio.", (cfg,), seeds=CURVE_SEEDS,
                      thesis={"adaptive": _table_5_3().thesis["adaptive"]}, rules="authors")


def _table_5_2_authors() -> Experiment:
    t52 = _table_5_2()
    configs = tuple(replace(c, method=replace(method_of(c, Adaptive), departures=Departures(unguarded_step=True)))
                    for c in _theoretical_range_rows(t52))
    return Experiment("table-5.2-authors", "Table 5.2's two theoretical-range rows as the authors' script ran them: "
                      "the range 1280, the step taken even when eps >= |g| (with this range, on the first batch).",
                      configs, seeds=CURVE_SEEDS, thesis={c.name: t52.thesis[c.name] for c in configs}, rules="authors")


def _figures_5_1_5_2_authors() -> Experiment:
    t52 = _table_5_2()
    theoretical = {c.name for c in _theoretical_range_rows(t52)}
    settings = table52_settings()
    configs = []
    for c in t52.configs:
        if c.name in theoretical:  # table-5.2-authors runs them under the authors' settings already
            continue
        method = method_of(c, Adaptive)
        error = method.error
        limits = settings[(method.gradient.estimator, error.bound, error.empirical_range, error.delta)]
        configs.append(replace(c, method=replace(method, batches=Batches(limits["n_min"], limits["n_max"]),
                                                 departures=Departures(unguarded_step=True))))
    return Experiment("figures-5.1-5.2-authors", "The curves of Figures 5.1-5.2 (Table 5.2's rows but the two "
                      "theoretical-range ones, which table-5.2-authors runs) as the authors' script ran them: "
                      "N_min and N_max from each row's run files, the step taken even when eps >= |g| (on the "
                      "first batch: their first update comes after N_min trajectories, ours after two batches).",
                      tuple(configs), seeds=CURVE_SEEDS, thesis={c.name: t52.thesis[c.name] for c in configs},
                      rules="authors")


def _cartpole_baseline_authors() -> Experiment:
    base = _cartpole_baseline()
    search = base.configs[0]
    cfg = replace(search, task=_authors_cartpole(doubled=False),
                  method=replace(method_of(search, Vanilla), target=Target(195.0, update=True)))
    return replace(base, name="cartpole-baseline-authors", configs=(cfg,), rules="authors",
                   description="The cart-pole baseline search on the authors' task (12 deg, undiscounted return): "
                               "vanilla G(PO)MDP, alpha = 0.01, N = 4000 from theta = 0 until a batch averages 195, "
                               "that batch's update included (their theta_star).")


def _table_5_4_authors(theta_star: bool = False) -> Experiment:
    # Both runs as long as the authors' adaptive run, the window their table averages over.
    task = partial(RunConfig, task=_authors_cartpole(doubled=True), budget=TABLE_5_4_BUDGET)
    if theta_star:
        task = partial(task, theta0=tuple(float(v) for v in cartpole_theta_star()))
    else:
        task = partial(task, warm_start="cartpole-baseline-authors")
    configs = (task("adaptive", method=Adaptive(error=BERNSTEIN_ER, batches=Batches(n_min=10, first=1000),
                                                departures=replace(AUTHORS_DEPARTURES, batch_constants=True))),
               task("N=4000", method=Vanilla(4000, FixedStep(0.01, "coordinate"))))
    origin = "their own baseline policy (theta_star.npy)" if theta_star else "each seed's cartpole-baseline-authors"
    return Experiment(f"table-5.4-authors{'-theta-star' if theta_star else ''}",
                      f"Table 5.4 as the authors ran it, from {origin}: their doubled pole (m l kept at 0.05), 12 deg, "
                      "undiscounted return; adaptive with gamma = 0.9 and R, M_phi measured per batch in c, first N = "
                      "1000, N_min = 10, the maxima over components, unguarded steps; 'vanilla' moving only the "
                      f"largest component by 0.01 g_k; {TABLE_5_4_BUDGET} trajectories each, counted as "
                      "plot_cartpole.m.", configs, seeds=CURVE_SEEDS if theta_star else 5, thesis=_table_5_4().thesis,
                      performance="J_hat", rules="authors")


def _bind(exp: Experiment, registry: dict[str, Experiment]) -> Experiment:
    """``exp`` with the key of the run each config warm-starts from."""
    configs = []
    for c in exp.configs:
        if c.warm_start is not None:
            c = replace(c, warm_start_key=registry[c.warm_start].single_config().seed_key())
        configs.append(c)
    return replace(exp, configs=tuple(configs))


def _registry() -> dict[str, Experiment]:
    experiments = (_table_5_1(), _table_5_1_printed_theta0(), _table_5_1_no_baseline(), _table_5_2(),
                   _table_5_2_lemma_range(), _table_5_2_raw_score(), _figures_5_5_5_6(), _table_5_3(),
                   _cartpole_baseline(), _table_5_4(),
                   # The cart-pole sweep's experiments.
                   *_sweep_baselines(), _cartpole_sweep(),
                   # The authors' settings.
                   _table_5_1_authors(), _table_5_1_authors_tail(), _table_5_2_authors(), _figures_5_1_5_2_authors(),
                   _table_5_3_authors(), _cartpole_baseline_authors(), _table_5_4_authors(),
                   _table_5_4_authors(theta_star=True))
    registry = {e.name: e for e in experiments}
    return {name: _bind(e, registry) for name, e in registry.items()}


#: Every experiment, by name.
EXPERIMENTS: dict[str, Experiment] = _registry()


def get_experiment(name: str) -> Experiment:
    if name not in EXPERIMENTS:
        raise ValueError(f"experiment must be one of {sorted(EXPERIMENTS)}, got {name!r}")
    return EXPERIMENTS[name]


def scaled(exp: Experiment, seeds: int | None = None, budget: int | None = None) -> Experiment:
    """The same experiment with fewer seeds or another trajectory budget."""
    for name, value in (("seeds", seeds), ("budget", budget)):
        # bool is an int, numpy integers are not: accept the latter, refuse the former.
        if value is not None and (isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1):
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    configs = exp.configs if budget is None else tuple(replace(c, budget=budget) for c in exp.configs)
    return replace(exp, configs=configs, seeds=exp.seeds if seeds is None else seeds)
