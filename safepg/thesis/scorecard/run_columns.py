"""What the rows of several sections of Chapter 5 share: the column of ours under the authors'
settings (:func:`authors_column`), the sentences that quote another run or a missing output, the
relevance of an improvement ratio, and the rows of a step size's order of magnitude
(:func:`step_rows`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from safepg.significance import Test
from safepg.thesis.experiments import Experiment
from safepg.thesis.scorecard import outputs
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.judged import (
    order_test,
    prediction,
)
from safepg.thesis.scorecard.tolerances import in_prediction, order_of_magnitude
from safepg.thesis.scorecard.verdicts import RELEVANT_SHARE, relevance_text


def points(v: float) -> str:
    """A difference of two ratios, in percentage points."""
    return f"{100 * v:.2g} points"


#: The relevance of an improvement ratio, and its words.
RATIO_RELEVANCE = RELEVANT_SHARE
RATIO_RELEVANCE_TEXT = relevance_text("ratio", RATIO_RELEVANCE, points)


def mean_ci(d: Mapping[str, Any]) -> tuple[float | None, list[float] | None]:
    m = d.get("mean")
    if m is None:
        return None, None
    ci = d["ci95"]  # a summary with a mean has its interval (safepg.stats.mean_ci95)
    return float(m), [float(ci[0]), float(ci[1])]


def authors_column(exp: Experiment | None, seeds: int, mean: float | None, ci: list[float] | None, text: str,
                   check: Callable[[float, list[float] | None], bool | None] | None = None, *, test: Test | None = None,
                   interval: list[float] | None = None, interval_text: str = "", vacuous: str = "",
                   sources: Sequence[str] = ()) -> AuthorsColumn:
    """Ours under the authors' settings: the cell, and, when every seed of ``exp`` is stored, the row's
    ``test`` (a row judged on runs) or its rule ``check(mean, ci)``, with the ``interval``, ``interval_text``
    and ``vacuous`` of that judgement."""
    if exp is None:
        return AuthorsColumn()
    column = AuthorsColumn(experiment=exp.name, seeds=seeds, text="-", sources=tuple(sources))
    if mean is None or seeds == 0:
        return column
    column = replace(column, value=mean, ci95=ci, text=text)
    if seeds < exp.seeds:  # a partly computed campaign is shown, not judged
        return replace(column, text=f"{text} ({seeds} of {exp.seeds} seeds: not judged)")
    return replace(column, ok=None if check is None else check(mean, ci), test=test, interval=interval,
                   interval_text=interval_text, vacuous=vacuous)


def said(column: AuthorsColumn) -> str:
    """Ours under the authors' settings as a note quotes it."""
    return "(not stored yet)" if not column.experiment or column.text == "-" else column.text


def report_row(rep: Mapping[str, Any] | None, name: str) -> Mapping[str, Any] | None:
    for r in (rep or {}).get("configs", []):
        if r["name"] == name:
            return r
    return None


def also_sentence(also: tuple[Experiment, Mapping[str, Any]] | None, row: Mapping[str, Any] | None, key: str,
                  fmt: Callable[[float], str], printed: str, scale: float = 1.0) -> str:
    """The sentence quoting another run of the authors' settings (``also``) for this row: its mean, its
    prediction interval for one run, and whether that holds the ``printed`` value (in units of ``scale``
    times the row's)."""
    if also is None:
        return ""
    exp = also[0]
    what = (f"The row is judged on the authors' whole protocol, each seed searching its own baseline as they did; "
            f"from their own baseline policy, theta_star.npy@a82576f ({exp.name}, one start for all seeds)")
    if row is None or not row["seeds"] or row[key]["mean"] is None:
        return f"{what}: not stored yet."
    m, pi = row[key]["mean"], prediction(row[key], ratio=key == "improvement_ratio")
    if pi is None:
        return f"{what}: {fmt(m)} ({row['seeds']} of {exp.seeds} seeds)."
    holds = in_prediction(printed, [scale * pi[0], scale * pi[1]])
    return (f"{what}: {fmt(m)}, prediction interval for one run [{fmt(pi[0])}; {fmt(pi[1])}] over {row['seeds']} "
            f"seeds, which {'holds' if holds else 'excludes'} the printed value.")


def missing_sentence(out: outputs.Output | None) -> str:
    if out is None or out.value is not None:
        return ""
    return (f"The authors' output for this run is not in their repository ({out.source} is absent), so the "
            "printed value cannot be checked against it.")


def _seed_medians(recs: Mapping[str, Sequence], names: list[str], seeds: int) -> list[list[float]] | None:
    """Each configuration's runs' median positive steps, or None unless every seed of each is stored and has
    a step."""
    if any(len(recs.get(n, [])) < seeds for n in names):  # judged on the whole campaign only
        return None
    out = []
    for n in names:
        medians = [float(np.median(r.alpha[r.alpha > 0])) for r in recs.get(n, []) if np.any(r.alpha > 0)]
        if len(medians) < len(recs.get(n, [])) or not medians:
            return None
        out.append(medians)
    return out


def step_rows(b: Builder, *, rid: str, group: str, where: str, quantity: str, recs: Mapping[str, Sequence],
              names: Iterable[str], exponent: int, page: str, heading: str, seeds: int, experiment: str,
              authors: Experiment | None = None, authors_recs: Mapping[str, Sequence] | None = None,
              output: outputs.Output | None = None, authors_note: str = "") -> None:
    """A step size "of the order of 10^exponent" in every configuration ``names`` of ``recs`` (and of
    ``authors``): each configuration's median step, judged by :func:`~safepg.thesis.scorecard.judged.order_test`
    on each seed's median."""
    names = list(names)
    per_seed = _seed_medians(recs, names, seeds)
    if per_seed:  # "in all the experiments": every configuration run
        medians = [float(np.median(m)) for m in per_seed]
        ours = f"median {np.median(medians):.1e}" + \
               (f" (per configuration {min(medians):.1e} to {max(medians):.1e})" if len(medians) > 1 else "")
        value = float(np.median(medians))
        diff = f"order 10^{order_of_magnitude(value)}"
    else:
        ours, value, diff = "-", None, "-"
    a_col = AuthorsColumn()
    if authors is not None:
        a_names = [c.name for c in authors.configs]
        got = dict(authors_recs or {})
        n_seeds = min((len(got.get(n, [])) for n in a_names), default=0)
        a_seed = _seed_medians(got, a_names, max(n_seeds, 1)) or []
        a_med = [float(np.median(m)) for m in a_seed]
        a_col = authors_column(authors, n_seeds, float(np.median(a_med)) if a_med else None, None,
                               f"median {np.median(a_med):.1e}" if a_med else "-", test=order_test(exponent, a_seed),
                               sources=tuple(f"{authors.name}/{n}" for n in a_names))
    b.add(RowSpec(id=rid, group=group, quantity=quantity, where=where, thesis=f"of the order of 1e{exponent}",
          ours=ours, difference=diff, ok=None, test=order_test(exponent, per_seed or []), relevance=1.0,
          sources=tuple(f"{experiment}/{n}" for n in names),
          relevance_text=relevance_text("decade", 1.0), show=lambda v: f"{v:.2g} decades", rule="order",
          kind="read off a figure", page=page, heading=heading, thesis_value=10.0**exponent, ours_value=value,
          interval_text="reading precision: an order of magnitude", seeds=min((len(m) for m in per_seed or []),
                                                                               default=None),
          authors=replace(a_col, note=authors_note), output=output))
