"""What a scorecard row is judged on: the prediction interval for one run of a report's entry, the texts
that name an interval, why a run's improvement ratio carries no information, and where a printed run
lies among many of ours."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from safepg.envs.lqg import LQG
from safepg.options import FixedStep, Vanilla
from safepg.record import LearningRecord
from safepg.significance import AllOf, PredictionTest
from safepg.stats import prediction_interval95
from safepg.thesis import authors
from safepg.thesis.analysis import one_cell_spread
from safepg.thesis.experiments import Experiment, method_of
from safepg.thesis.scorecard import outputs
from safepg.thesis.scorecard.rules import FROZEN_THETA, TailRuns
from safepg.thesis.scorecard.text import pct
from safepg.thesis.scorecard.tolerances import half_unit, in_prediction, intervals_overlap, is_slip
from safepg.thesis.scorecard.verdicts import RELEVANT_SHARE


def prediction(d: Mapping[str, Any] | None, ratio: bool = False) -> list[float] | None:
    """The 95% prediction interval for one run of a report's entry (None without two seeds); a
    ratio's is cut to [0, 1], where every ratio lies (which changes no verdict on a printed ratio)."""
    pi = (d or {}).get("pi95")
    if not pi or pi[0] is None:
        return None
    return [max(pi[0], 0.0), min(pi[1], 1.0)] if ratio else [float(pi[0]), float(pi[1])]


def pi_text(pi: Sequence[float] | None, fmt: Callable[[float], str], seeds: int | None, then: str = "") -> str:
    """A prediction interval as the page shows it, with what it is (and ``then``, after a semicolon)."""
    if not pi or pi[0] is None:
        return ""
    return f"[{fmt(pi[0])}; {fmt(pi[1])}]: 95% prediction interval for one run, {seeds} seeds" + \
        (f"; {then}" if then else "")


def ci_judged(ci: Sequence[float] | None, fmt: Callable[[float], str], seeds: int | None) -> str:
    """The interval of our mean as the page shows it, with what it is."""
    if not ci or ci[0] is None:
        return ""
    return f"[{fmt(ci[0])}; {fmt(ci[1])}]: 95% interval of our mean, {seeds} seeds"


def frozen(moved: float | None) -> str:
    """Why a run's improvement ratio carries no information ("" when theta moved)."""
    if moved is None or moved >= FROZEN_THETA:
        return ""
    return (f"θ moved by at most {moved:.1e} over the run (below {FROZEN_THETA:g}): consecutive batch means differ "
            "by noise alone, so the ratio carries no information.")


def ratio_interval(row: Mapping[str, Any] | None) -> list[float] | None:
    """The interval an improvement ratio of one run is judged on, in percentage points: the prediction
    interval for one run of the report's ``row``, widened by one update's share (:func:`_update_share`).

    A ratio takes the values k/n of its run's n updates; where every seed of ours gives the same ratio
    (100% on a run that improves at each update) the seeds' spread is 0, and a run that differs from
    them by a single update would be rejected by the spread alone.
    """
    pi = prediction(row and row["improvement_ratio"], ratio=True)
    if pi is None:
        return None
    step = _update_share(row)
    return [max(100 * pi[0] - step, 0.0), min(100 * pi[1] + step, 100.0)]


def _update_share(row: Mapping[str, Any] | None) -> float:
    """One update's share of a run's ratio, in points: 100 / (iterations - 1), the smaller of the two
    denominators in use (ours counts every iteration's change of J, the authors' scripts one fewer)."""
    its = (row or {}).get("iterations")
    return 100 / (its - 1) if its and its > 2 else 0.0


def ratio_text(row: Mapping[str, Any] | None) -> str:
    """:func:`ratio_interval` as the page shows it, with what it is."""
    interval = ratio_interval(row)
    if interval is None or row is None:
        return ""
    widened = f"widened by one update, {_update_share(row):.2g} points" if _update_share(row) else ""
    return pi_text(interval, lambda x: f"{x:.1f}%", row["seeds"], widened)


def overlaps_printed(printed: Sequence[float]) -> Callable[[float, list[float] | None], bool | None]:
    """Rule ``"ci-overlap"`` as a column under the authors' settings applies it: ``check(mean, ci)``, our
    interval ``ci`` against the ``printed`` one."""

    def check(_: float, ci: list[float] | None) -> bool:
        if ci is None:  # intervals_overlap cannot sort None either
            raise TypeError("rule 'ci-overlap' needs our interval, got None")
        return intervals_overlap(ci, printed)

    return check


def one_run_ratio(printed: float, row: Mapping[str, Any] | None) -> bool | None:
    """Rule ``"prediction"`` on an improvement ratio: the printed percentage in :func:`ratio_interval`."""
    return in_prediction(f"{100 * printed:.6g}", ratio_interval(row))


def tail_placement(tail: Experiment | None, recs: Mapping[str, Sequence[LearningRecord]]
                   ) -> dict[tuple[float, int, float], TailRuns]:
    """Where the printed cell of ``tail`` (one Table 5.1 cell, many seeds under the authors' settings)
    lies among our runs of it (``recs``: its runs by config): the note's values by cell (sigma, N,
    alpha); empty without two runs that differ."""
    if tail is None:
        return {}
    cfg = tail.single_config()
    if len(recs.get(cfg.name, ())) < 2:
        return {}
    method = method_of(cfg, Vanilla)
    if not isinstance(method.step, FixedStep):
        raise TypeError(f"the tail cell {cfg.name!r} must run a fixed step, got {method.step!r}")
    cell = (cfg.sigma, method.batch_size, method.step.alpha)
    theta_star = float(LQG.thesis_1d().optimal_gain().ravel()[0])
    s = one_cell_spread(recs[cfg.name], tail.thesis[cfg.name]["improvement_ratio"],
                        authors.table51_runs()[cell]["theta"], theta_star)
    if not np.isfinite(s["z"]):  # our runs all agree: no spread to place the print in
        return {}
    pi = prediction_interval95(s["ratios"])["pi95"]
    c = s["crossing"]
    return {cell: TailRuns(runs=len(recs[cfg.name]), mean=pct(s["mean"]), interval=f"[{pct(pi[0])}; {pct(pi[1])}]",
                           at_least=s["at_least"], z=s["z"], theta_star=theta_star,
                           crossing_theirs=s["crossing_theirs"],
                           crossing_ours=f"{c.min()} to {c.max()} (mean {c.mean():.0f})")}


def slip_sentence(out: outputs.Output, printed: str, show: Callable[[float], str], scale: float = 1.0) -> str:
    """The sentence naming a slip between the authors' output and the print ("" when none).
    ``printed`` as printed (a percentage for a ratio: ``scale`` 100 brings the output there)."""
    if out.value is None or not out.complete or not is_slip(scale * out.value, printed):
        return ""
    return (f"Slip between the authors' output and the print: their run gives {show(scale * out.value)} "
            f"({out.source}), the thesis prints {show(float(printed))}.")


# ------------------------------------------------------------------ the tests of the rows judged on runs
def printed_interval(printed: str, scale: float = 1.0, integer_unit: bool = False) -> tuple[float, float]:
    """A printed number as the interval its digits cover, value ± half a unit of the last one (times
    ``scale``: 0.01 brings a printed percentage to a ratio); a printed 0 is exactly 0. ``integer_unit``: an
    integer's last digit is its units digit ("100%" is 99.5% to 100.5%), not its last non-zero one."""
    v = float(printed) * scale
    if v == 0:
        return 0.0, 0.0
    h = (0.5 if integer_unit and "." not in printed and "e" not in printed.lower() else half_unit(printed)) * scale
    return v - h, v + h


def value_test(printed: str, values: Sequence[float] | None, reading: float | None = None) -> PredictionTest | None:
    """The prediction t-test of a number printed from one run against our runs' ``values`` (None without two):
    the printed interval is its digits' (:func:`printed_interval`), or ± ``reading`` for a number read off a
    figure."""
    if values is None or len(values) < 2:
        return None
    v = float(printed)
    interval = printed_interval(printed) if reading is None else (v - reading, v + reading)
    return PredictionTest(interval, tuple(float(x) for x in values))


def ratio_test(printed: float, row: Mapping[str, Any] | None, text: str | None = None) -> PredictionTest | None:
    r"""The prediction t-test of a printed improvement ratio (a fraction) against a report's ``row``: the
    printed percentage's digits, widened by half an update's share :math:`1/(2n)` (:math:`n`: the smaller of
    the two update counts in use, ours and the authors': the ratio's own last digit); where every run of ours
    gives the same ratio, the spread is the binomial spread of :math:`n` updates at our rate of worsening ones,
    :math:`\sqrt{\hat q (1 - \hat q)/n}`, :math:`\hat q = (\text{worsening} + 1/2)/(\text{updates} + 1)`.
    ``text``: the percentage as printed (default: the shortest that gives ``printed``; "100" for 100%).
    None without two runs."""
    if row is None:
        return None
    values = row["improvement_ratio"].get("values") or []
    if len(values) < 2:
        return None
    n = float(np.mean(row["updates"])) - 1
    if n < 1:
        return None
    worse = float(np.sum([(1 - v) * n for v in values]))
    q = (worse + 0.5) / (n * len(values) + 1)
    return PredictionTest(printed_interval(text or f"{100 * printed:.6g}", 0.01, integer_unit=True),
                          tuple(float(v) for v in values),
                          resolution=0.5 / n, sd_floor=math.sqrt(q * (1 - q) / n))


def order_test(exponent: int, medians: Sequence[Sequence[float]]) -> AllOf | None:
    """The test of "of the order of 10^exponent" in every configuration: per configuration, the prediction
    t-test of its runs' median steps, on a log10 scale, against [exponent, exponent + 1]; Bonferroni over the
    configurations. ``medians``: each configuration's runs' median steps (None without two runs in each)."""
    if not medians or any(len(m) < 2 for m in medians):
        return None
    return AllOf(tuple(PredictionTest((float(exponent), float(exponent + 1)),
                                      tuple(math.log10(v) for v in m)) for m in medians))


def never_moved_test(moves: Sequence[Sequence[float]]) -> AllOf | None:
    """The test of "never updates these components": per printed component, the prediction t-test of each
    run's largest move of it against exactly 0; Bonferroni over the components. ``moves``: per component, each
    run's largest |theta - theta_0| (None without two runs)."""
    if not moves or any(len(m) < 2 for m in moves):
        return None
    return AllOf(tuple(PredictionTest((0.0, 0.0), tuple(float(v) for v in m)) for m in moves))


def value_relevance(printed: str, reading: float = 0.0) -> float:
    """The difference that matters for a printed number: :data:`RELEVANT_SHARE` of it, never less than half a
    unit of its last digit or its reading precision."""
    return max(RELEVANT_SHARE * abs(float(printed)), half_unit(printed), reading)
