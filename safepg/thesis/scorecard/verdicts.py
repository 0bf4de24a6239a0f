r"""Verdicts on the rows measured on runs: one family of tests, corrected together, and what each
test could have detected.

Every row judged on runs (:data:`RANDOM_KINDS`) carries a test per column (ours, ours under the
authors' settings; :mod:`safepg.significance`). All of them form one family, and the
Benjamini-Hochberg procedure keeps its false discovery rate at :data:`FDR_LEVEL`: a column
"differs" only when its test is among those rejected. A column that is not rejected reproduces the
printed number only when its test would have detected a difference that matters: the row's
*relevance* (:func:`relevance_text`), at the level a test not rejected faces, :math:`(R + 1)q/m`,
with probability 0.8; otherwise the column is inconclusive, and :func:`column_verdict` says how many
runs of ours would make it conclusive.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from safepg.significance import POWER, Test, benjamini_hochberg, seeds_for

#: The false discovery rate the scorecard controls over its random rows' tests.
FDR_LEVEL = 0.05
#: The kinds of rows judged on runs: their verdicts are tests, corrected together.
RANDOM_KINDS = ("one run", "mean of runs", "read off a figure", "whole curve")
#: The share of a quantity's scale that matters (:func:`relevance_text`): a twentieth, the scorecard's
#: 5 points of an improvement ratio.
RELEVANT_SHARE = 0.05
#: A printed number carries its own noise (one run of theirs, or a mean of five), which no number of runs of
#: ours removes: a test's detectable difference never falls below what it is with unlimited runs of ours. The
#: difference that matters is never less than this many times that floor, so that enough seeds can always
#: make a row conclusive.
FLOOR_MARGIN = 1.5
#: Runs are added in blocks of this many, and "the seeds it would need" counts in them.
SEED_BLOCK = 5
#: The most runs "the seeds it would need" looks at.
SEEDS_LIMIT = 400

#: Why the false discovery rate, as the page states it.
CORRECTION = (
    f"The random rows' tests (every column of every row judged on runs) are one family, corrected together by "
    f"the Benjamini-Hochberg procedure at a false discovery rate of {FDR_LEVEL:.0%}: of the columns the scorecard "
    "calls different, at most 5% are expected to be false alarms, whatever the number of rows. A row's 'open' or "
    "'differs' is a finding the reader acts on; the false discovery rate is the error of that list. Holm's "
    "family-wise control would hold each test to 0.05/m at the first step, so every row added to the scorecard "
    "would weaken the test of every other, and the rows' detectable differences would grow with the size of the "
    "scorecard. The procedure assumes the tests independent or positively dependent; rows that share runs (one "
    "configuration feeds several rows) are positively dependent through them.")


@dataclass(frozen=True)
class ColumnVerdict:
    """One column's test, judged within the family.

    Attributes
    ----------
    p_value : float
    rejected : bool
        Among the tests the correction rejects.
    level : float
        The threshold the test faced: for a test not rejected, the one it would have had to meet to join
        the rejected, :math:`(R + 1)q/m`; for a rejected one, its own rank's :math:`iq/m`.
    detectable : float
        The smallest difference its test detects with probability 0.8 at the level a test not rejected faces,
        :math:`(R + 1)q/m` (for every column: the seed rule asks for runs by it, whatever the p-value).
    conclusive : bool
        Not rejected and ``detectable`` within the row's relevance.
    seeds_needed : int or None
        Where ``detectable`` is above the relevance: the runs of ours at which it would not be (None: it is
        not, or no number up to :data:`SEEDS_LIMIT` would do).
    seeds : int
    floor : float
        The test's detectable difference with unlimited runs of ours (NaN for a rejected test).
    relevance : float
        The difference it was held to: the row's, or :data:`FLOOR_MARGIN` times ``floor`` if more.
    """

    p_value: float
    rejected: bool
    level: float
    detectable: float
    conclusive: bool
    seeds_needed: int | None
    seeds: int
    floor: float = math.nan
    relevance: float = math.nan


def correct(p_values: Sequence[float], q: float = FDR_LEVEL) -> tuple[np.ndarray, float, np.ndarray]:
    """The family's decisions: which tests are rejected, the level a test not rejected faces, and each
    rejected test's own threshold (its rank's ``i q / m``; NaN for the others)."""
    rejected, level = benjamini_hochberg(p_values, q)
    p = np.asarray(p_values, dtype=float)
    order = np.argsort(p, kind="stable")
    own = np.full(p.size, np.nan)
    own[order] = q * np.arange(1, p.size + 1) / max(p.size, 1)
    return rejected, level, np.where(rejected, own, np.nan)


def column_verdict(test: Test, rejected: bool, level: float, relevance: float, own_level: float = math.nan,
                   block: int = SEED_BLOCK) -> ColumnVerdict:
    """A column's test judged: rejected, or not rejected and conclusive when its detectable difference at
    ``level`` is within ``relevance``, else inconclusive with the runs it would need."""
    p = test.p_value
    if not math.isfinite(p):  # too few runs for the statistic: it detects nothing yet
        return ColumnVerdict(p, False, level, math.inf, False, seeds_for(test, level, relevance, block, SEEDS_LIMIT)
                             if relevance > 0 else None, test.seeds)
    detectable = test.detectable_difference(level)
    floor = test.detectable_difference(level, math.inf)
    # An exact claim (relevance 0: a parameter that never moves) is held to exactness, whatever the noise.
    held = max(relevance, FLOOR_MARGIN * floor) if relevance > 0 and math.isfinite(floor) else relevance
    enough = bool(detectable <= held * (1 + 1e-12))
    needed = None if enough else seeds_for(test, level, held, block, SEEDS_LIMIT)
    return ColumnVerdict(p, rejected, own_level if rejected else level, detectable, enough and not rejected, needed,
                         test.seeds, floor, held)


def relevance_text(kind: str, value: float, fmt: Any = None) -> str:
    """How a row's relevance was set, in words: ``kind`` is one of ``"ratio"`` (5 points of a ratio),
    ``"value"`` (5% of the printed value), ``"scale"`` (5% of the curve's or the matrix's scale),
    ``"reading"`` (the reading precision), ``"decade"`` (an order of magnitude) or ``"exact"`` (the printed
    value exactly, in every run)."""
    show = fmt or (lambda v: f"{v:.3g}")
    share = f"{RELEVANT_SHARE:.0%}"
    return {"ratio": f"{show(value)}: {share} of a ratio's range",
            "value": f"{show(value)}: {share} of the printed value",
            "scale": f"{show(value)}: {share} of the range of the authors' values over the figure's curves",
            "reading": f"{show(value)}: the printed reading's precision",
            "decade": "one decade: the printed order of magnitude",
            "exact": "none: the printed value exactly, in every run"}[kind]


def p_text(p: float) -> str:
    """A p-value as the page prints it: two significant digits, or a bound below 1e-4."""
    if p != p:  # NaN
        return "-"
    return "p < 0.0001" if p < 1e-4 else f"p = {p:.2g}"


def short_verdict(v: ColumnVerdict, name: str, fmt: Any) -> str:
    """A column's test in a few words, for under the status: its p-value, test and seeds, and what it
    detects (rejected: its threshold)."""
    head = f"{p_text(v.p_value)} ({name}, {v.seeds} seeds)"
    if v.rejected:
        return f"{head}, below {v.level:.2g}: differs"
    if v.conclusive:
        return f"{head}; detects {fmt(v.detectable)}, {fmt(v.relevance)} matter"
    more = f"{v.seeds_needed} seeds would" if v.seeds_needed is not None else "no number of seeds would"
    return f"{head}; detects only {fmt(v.detectable)}, {fmt(v.relevance)} matter: {more}"


def verdict_sentence(v: ColumnVerdict, name: str, fmt: Any, relevance: float, on: str) -> str:
    """What a column's test found, in one sentence for the row's explanation."""
    seeds = f"{v.seeds} seeds"
    if v.rejected:
        return (f"On {on}: {p_text(v.p_value)} ({name}, {seeds}), below its threshold {v.level:.2g} of the "
                f"false discovery rate: differs.")
    found = (f"On {on}: {p_text(v.p_value)} ({name}, {seeds}); at the level {v.level:.2g} the test detects "
             f"{fmt(v.detectable)} with {POWER:.0%} power")
    held = (f"the {fmt(v.relevance)} that matter" if v.relevance <= relevance * (1 + 1e-12) else
            f"{fmt(v.relevance)}, {FLOOR_MARGIN:g} times the {fmt(v.floor)} that no number of our runs would go "
            f"below (the printed number's own noise; {fmt(relevance)} would matter)")
    if v.conclusive:
        return f"{found}, within {held}."
    more = (f"{v.seeds_needed} seeds would" if v.seeds_needed is not None else f"no number up to {SEEDS_LIMIT} would")
    return f"{found}, more than {held}: inconclusive; {more}."


__all__ = ["CORRECTION", "FDR_LEVEL", "FLOOR_MARGIN", "RANDOM_KINDS", "RELEVANT_SHARE", "SEEDS_LIMIT", "SEED_BLOCK",
           "ColumnVerdict", "column_verdict", "correct", "p_text", "relevance_text", "short_verdict",
           "verdict_sentence"]
