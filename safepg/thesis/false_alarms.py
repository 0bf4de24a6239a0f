r"""How often the scorecard's tests call our own runs different: their false alarms, measured.

The prediction t-test, Welch's t-test and Hotelling's test of one curve (:mod:`safepg.significance`) hold
their level exactly only for normal runs; an improvement ratio is a count of updates, a performance
is a sum of clipped returns. So their level is measured here, on our own runs, where the printed number
comes from the very process ours follow and every rejection is a false alarm. Each rule gets
:data:`TRIALS` disjoint trials; a trial holds one run (or :data:`PRINTED_RUNS` runs, summarised as the
thesis prints a mean: its value and its 95% interval, rounded) as "the print" and runs of ours beside
it, whose number is set by the scorecard's seed rule (:mod:`safepg.thesis.seed_rule`): a start, then
blocks of :data:`~safepg.thesis.scorecard.verdicts.SEED_BLOCK` up to
:data:`~safepg.thesis.seed_rule.SEED_CAP` while the test could not detect what matters (here: within
:data:`~safepg.thesis.scorecard.verdicts.FLOOR_MARGIN` of its floor), the test made once at the end.

The trials run cheap configurations (the check is of the rule, not of an experiment), each where its
quantity varies from run to run as the scorecard's rows do: vanilla G(PO)MDP on the 1-D LQG with
:math:`N = 10` and :data:`TRIAL_BUDGET` trajectories (400 updates). For the improvement ratio, the average
performance :math:`\overline\Upsilon` and a mean of five runs, from Table 5.1's printed
:math:`\theta_0 = -0.55` with :math:`\alpha = 10^{-3}` (:data:`NOISY_CONFIG`: updates near
:math:`\theta^*`, half of them worsening, the ratio varying by several updates between runs); for a curve,
the learning curve of :math:`J` over iterations from :math:`\theta_0 = 0` with :math:`\alpha = 10^{-4}`
(:data:`CURVE_CONFIG`: :math:`J` rising from :math:`-56.7` towards :math:`-17`, as the scorecard's curves
rise; near :math:`\theta^*` a run's :math:`J` is bounded by :math:`J^*` and its block means are skewed, which
this test, like a prediction interval, does not tolerate). The measured rate comes with its
95% Clopper-Pearson interval, which must hold the rule's nominal level; run at 1% or at 10% in place of
5%, the same check must fail (:func:`false_alarm_checks`).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from safepg.curve_tests import CurvePredictionTest, block_means
from safepg.distributions import clopper_pearson
from safepg.options import FixedStep, Vanilla
from safepg.record import LearningRecord
from safepg.runner import RunConfig
from safepg.significance import PredictionTest, WelchTest
from safepg.thesis.curve_bands import CURVE_BLOCKS
from safepg.thesis.scorecard.verdicts import FLOOR_MARGIN, SEED_BLOCK
from safepg.thesis.seed_rule import SEED_CAP, START_SEEDS

#: Disjoint trials per rule.
TRIALS = 400
#: The nominal level every check states, and the levels of the negative controls.
NOMINAL = 0.05
CONTROLS = (0.01, 0.10)
#: Runs summarised as one printed mean (Table 5.2's count).
PRINTED_RUNS = 5
#: The trials' configuration and its budget.
TRIAL_BUDGET = 4_000
NOISY_CONFIG = RunConfig("false-alarms-noisy", task="lqg1d", method=Vanilla(10, FixedStep(1e-3)), theta0=(-0.55,),
                         sigma=1.0, budget=TRIAL_BUDGET)
CURVE_CONFIG = RunConfig("false-alarms-curve", task="lqg1d", method=Vanilla(10, FixedStep(1e-4)), theta0=(0.0,),
                         sigma=1.0, budget=TRIAL_BUDGET)
#: Runs set aside for each trial: the print (up to a mean's runs) and ours up to the cap.
RUNS_PER_TRIAL = PRINTED_RUNS + SEED_CAP


@dataclass(frozen=True)
class AlarmCheck:
    """One rule's false alarms over the trials, at one level.

    Attributes
    ----------
    rule : str
        What was tested, e.g. ``"prediction t, improvement ratio"``.
    level : float
        The level the rule was run at.
    trials, alarms : int
    rate : float
    interval : (float, float)
        The rate's two-sided 95% Clopper-Pearson interval.
    nominal : float
        The level the scorecard states (:data:`NOMINAL`).
    holds : bool
        ``nominal`` lies in ``interval``.
    mean_seeds : float
        Our runs per trial at the test, on average (the seed rule's additions).
    """

    rule: str
    level: float
    trials: int
    alarms: int
    rate: float
    interval: tuple[float, float]
    nominal: float
    holds: bool
    mean_seeds: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def trial_runs(config: RunConfig, trials: int = TRIALS, jobs: int = 1) -> list[list[LearningRecord]]:
    """The runs of every trial of ``config``: trial ``t`` holds seeds ``t * RUNS_PER_TRIAL`` onward
    (disjoint between trials), computed in memory."""
    from joblib import Parallel, delayed

    def block(t: int) -> list[LearningRecord]:
        return [config.run(t * RUNS_PER_TRIAL + i) for i in range(RUNS_PER_TRIAL)]

    return list(Parallel(n_jobs=jobs)(delayed(block)(t) for t in range(trials)))


def _with_seed_rule(make: Callable[[int], Any], start: int, alpha: float) -> Any:
    """The test at the seeds the rule gives it: ``make(k)`` builds the test on k of ours; seeds are added in
    blocks while its detectable difference at ``alpha`` is above :data:`FLOOR_MARGIN` times its floor."""
    k = start
    test = make(k)
    while k + SEED_BLOCK <= SEED_CAP:
        floor = test.detectable_difference(alpha, math.inf)
        if test.detectable_difference(alpha) <= FLOOR_MARGIN * floor * (1 + 1e-12):
            break
        k += SEED_BLOCK
        test = make(k)
    return test


def _ratio_test(printed: LearningRecord, ours: Sequence[LearningRecord]) -> PredictionTest:
    from safepg.thesis.scorecard.judged import ratio_test

    values = [r.improvement_ratio() for r in ours]
    row = {"improvement_ratio": {"values": values}, "updates": [r.iterations - 1 for r in ours]}
    # Printed as Table 5.1 prints most of its cells: a percentage with two decimals.
    text = f"{100 * printed.improvement_ratio():.2f}"
    test = ratio_test(float(text) / 100, row, text)
    if test is None:
        raise ValueError("the trials' runs must have updates")
    return test


def _value_test(printed: LearningRecord, ours: Sequence[LearningRecord]) -> PredictionTest:
    from safepg.thesis.scorecard.judged import value_test

    test = value_test(f"{printed.upsilon_bar():.4f}", [r.upsilon_bar() for r in ours])
    if test is None:
        raise ValueError("need two runs of ours")
    return test


def _welch_test(printed: Sequence[LearningRecord], ours: Sequence[LearningRecord]) -> WelchTest:
    from safepg.stats import mean_ci95

    theirs = mean_ci95(r.upsilon_bar() for r in printed)
    lo, hi = theirs["ci95"]
    # Printed as Table 5.2 prints: four decimals, about a tenth of its interval's half-width here too.
    decimals = max(0, -math.floor(math.log10((hi - lo) / 20)))
    rounded = [round(v, decimals) for v in (theirs["mean"], lo, hi)]
    return WelchTest(rounded[0], (rounded[1], rounded[2]), len(printed), tuple(r.upsilon_bar() for r in ours),
                     0.5 * 10.0**-decimals)


def _curve(rec: LearningRecord) -> np.ndarray:
    return np.asarray(rec.J[:-1], dtype=float)


def _curve_test(printed: LearningRecord, ours: Sequence[LearningRecord]) -> CurvePredictionTest:
    n = min(len(_curve(r)) for r in [printed, *ours])
    x = np.arange(1, n + 1, dtype=float)
    blocks = block_means(x, np.array([_curve(r)[:n] for r in [printed, *ours]]), CURVE_BLOCKS, (1.0, float(n)))
    return CurvePredictionTest(blocks[0], blocks[1:])


#: The rules measured: name, the configuration of its trials, the kind of row (its starting seeds), how
#: many runs make the print, and the test of the print against k of ours.
MEASURED: dict[str, tuple[RunConfig, str, int, Callable[[Any, Sequence[LearningRecord]], Any]]] = {
    "prediction t, improvement ratio": (NOISY_CONFIG, "one run", 1, lambda p, o: _ratio_test(p[0], o)),
    "prediction t, average performance": (NOISY_CONFIG, "one run", 1, lambda p, o: _value_test(p[0], o)),
    "Welch t, a mean of five runs": (NOISY_CONFIG, "mean of runs", PRINTED_RUNS, _welch_test),
    "Hotelling F, one curve": (CURVE_CONFIG, "whole curve", 1, lambda p, o: _curve_test(p[0], o)),
}


def _on_first(make: Callable[[Any, Sequence[LearningRecord]], Any], printed: Sequence[LearningRecord],
              ours: Sequence[LearningRecord], k: int) -> Any:
    """``make``'s test of the print against the first ``k`` of our runs."""
    return make(printed, ours[:k])


def false_alarms(runs: Mapping[str, Sequence[Sequence[LearningRecord]]],
                 levels: Sequence[float] = (NOMINAL, *CONTROLS)) -> list[AlarmCheck]:
    """Every measured rule at every level over the trials ``runs`` (by configuration name, :func:`trial_runs`).

    Returns
    -------
    list of AlarmCheck
        Rule by rule, level by level.
    """
    out = []
    for rule, (config, kind, printed_runs, make) in MEASURED.items():
        for alpha in levels:
            alarms, seeds = 0, 0
            for trial in runs[config.name]:
                printed, ours = trial[:printed_runs], trial[PRINTED_RUNS:]
                test = _with_seed_rule(partial(_on_first, make, printed, ours), START_SEEDS[kind], alpha)
                alarms += bool(test.p_value <= alpha)
                seeds += test.seeds
            n = len(runs[config.name])
            lo, hi = clopper_pearson(alarms, n)
            out.append(AlarmCheck(rule, alpha, n, alarms, alarms / n, (lo, hi), NOMINAL, lo <= NOMINAL <= hi,
                                  seeds / n))
    return out


def false_alarm_checks(trials: int = TRIALS, jobs: int = 1) -> list[AlarmCheck]:
    """:func:`false_alarms` on :func:`trial_runs` of every configuration: at the nominal level every check
    should hold, at the controls none."""
    configs = {c.name: c for c, *_ in MEASURED.values()}
    return false_alarms({name: trial_runs(c, trials, jobs) for name, c in configs.items()})


def checks_from_dicts(data: Sequence[Mapping[str, Any]]) -> list[AlarmCheck]:
    """Checks stored as :meth:`AlarmCheck.to_dict` wrote them."""
    return [AlarmCheck(**{**d, "interval": tuple(d["interval"])}) for d in data]


# ------------------------------------------------------------------ stored with the book's runs
#: The folder of the stored checks, inside the results folder.
FOLDER = "false-alarms"
#: What the checks are computed from: these modules' sources and the trial configurations' keys.
_SOURCES = ("significance.py", "curve_tests.py", "distributions.py", "stats.py", "thesis/false_alarms.py",
            "thesis/seed_rule.py", "thesis/scorecard/judged.py", "thesis/scorecard/tolerances.py",
            "thesis/scorecard/verdicts.py")


def checks_key(trials: int = TRIALS) -> str:
    """SHA-256 (hex, 16 digits) of what the checks depend on: the rules' modules, the trials' configurations
    (their keys hold the kernels' version) and the number of trials."""
    package = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(f"trials {trials}\n".encode())
    for name in _SOURCES:
        h.update(name.encode() + b"\n" + (package / name).read_bytes())
    for config in {c.name: c for c, *_ in MEASURED.values()}.values():
        h.update(f"config {config.name} {config.key()}\n".encode())
    return h.hexdigest()[:16]


def checks_path(root: Path, trials: int = TRIALS) -> Path:
    """Where the checks of the present rules are stored under the results folder ``root``."""
    return root / FOLDER / f"checks-{checks_key(trials)}.json"


def false_alarms_stored(root: Path, trials: int = TRIALS, jobs: int = -1) -> list[AlarmCheck]:
    """The checks of :func:`false_alarm_checks` for the present rules, read from ``root`` or computed and
    stored there (atomically; the files of other rules are removed)."""
    path = checks_path(root, trials)
    if path.exists():
        return checks_from_dicts(json.loads(path.read_text(encoding="utf-8")))
    checks = false_alarm_checks(trials, jobs)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps([c.to_dict() for c in checks], indent=1) + "\n", encoding="utf-8")
    tmp.replace(path)
    for old in path.parent.glob("checks-*.json"):
        if old != path:
            old.unlink(missing_ok=True)
    return checks


def checks_table(checks: Sequence[AlarmCheck]) -> str:
    """The checks as a Markdown table: each rule at each level, its false alarms, their rate with its 95%
    Clopper-Pearson interval, whether the interval holds the nominal level, and our runs per trial."""
    lines = ["| rule | run at | false alarms | rate [95% interval] | holds 5%? | our runs (mean) |",
             "|---|---:|---:|---|:-:|---:|"]
    for c in checks:
        lines.append(f"| {c.rule} | {c.level:.0%} | {c.alarms} of {c.trials} | {c.rate:.1%} "
                     f"[{c.interval[0]:.1%}; {c.interval[1]:.1%}] | {'yes' if c.holds else 'no'} | "
                     f"{c.mean_seeds:.1f} |")
    return "\n".join(lines)


__all__ = ["CONTROLS", "CURVE_CONFIG", "FOLDER", "MEASURED", "NOISY_CONFIG", "NOMINAL", "PRINTED_RUNS",
           "RUNS_PER_TRIAL", "TRIALS", "TRIAL_BUDGET", "AlarmCheck", "checks_from_dicts", "checks_key", "checks_path",
           "checks_table", "false_alarm_checks", "false_alarms", "false_alarms_stored", "trial_runs"]
