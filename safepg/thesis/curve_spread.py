"""Why some of the authors' curves leave our band: each choice between the thesis's text and the
authors' processing and settings changed in turn (:data:`FIGURES_51_52_HYPOTHESES`), and how far
the share inside the band scatters for one run (their committed runs, and each of our seeds
against our others: :func:`own_spread`). The scores themselves are :mod:`safepg.thesis.curve_bands`'."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from safepg.options import Adaptive
from safepg.thesis import authors, overlays
from safepg.thesis.curve_bands import (
    CURVE_DECIMALS,
    RUN_DIGITS,
    Records,
    band_share,
    figure55_series,
    figure_of_51_52,
    figures51_52_authors_runs,
    written_rounding,
)
from safepg.thesis.experiments import get_experiment, method_of


class Hypothesis(NamedTuple):
    """One way of holding the authors' curves of Figures 5.1-5.2 against ours, each choice explicit."""

    label: str
    processing: overlays.Processing
    runs: int
    settings: str  # "text" (table-5.2) or "authors" (:func:`figures51_52_authors_runs`)


#: The ways tested, one choice changed at a time from the thesis's text to the authors' processing and
#: settings (the scorecard decides on the first and the last; the others say which choice matters).
FIGURES_51_52_HYPOTHESES = (
    Hypothesis("the thesis's text: J of the policy in use, a five-run mean", "text", 5, "text"),
    Hypothesis("their curve is one run: J of the policy in use", "text", 1, "text"),
    Hypothesis("one run through their scaleData.m, our runs of the text", "authors", 1, "text"),
    Hypothesis("J of the policy in use, one run, our runs under their settings", "text", 1, "authors"),
    Hypothesis("their processing and settings: one run through scaleData.m, our runs under their settings",
               "authors", 1, "authors"),
)


def figures51_52_hypotheses(records: Records) -> list[dict[str, Any]]:
    """Each curve of Figures 5.1-5.2 under each of :data:`FIGURES_51_52_HYPOTHESES`: the share of the
    authors' curve inside our band.

    Returns
    -------
    list of dict
        One per curve: ``curve`` (the config's name) and one share per hypothesis label (NaN where the
        runs it needs are not stored).
    """
    text = records.get("table-5.2", {})
    out = []
    for cfg in get_experiment("table-5.2").configs:
        row: dict[str, Any] = {"curve": cfg.name}
        theirs = figures51_52_authors_runs(records, cfg.name)
        for h in FIGURES_51_52_HYPOTHESES:
            recs, c = (text.get(cfg.name), cfg) if h.settings == "text" else (
                (theirs[1], get_experiment(theirs[0]).config(cfg.name)) if theirs else (None, cfg))
            if not recs:
                row[h.label] = math.nan
                continue
            s = overlays.figure51_52_overlay_series({cfg.name: recs}, c, h.processing, runs=h.runs)
            row[h.label] = band_share(s["x"], s["authors"], s["values"], h.runs,
                                      rounding=written_rounding(s["authors"], decimals=CURVE_DECIMALS))["share_inside"]
        out.append(row)
    return out


def figures51_52_spread(records: Records) -> list[dict[str, Any]]:
    """How far one run's share scatters, under the authors' processing and settings: each of their
    committed runs of a curve of Figures 5.1-5.2 against our band for one run, and each of our seeds
    against the band of our other seeds (one run drawn from our own process, judged by the same rule).

    Returns
    -------
    list of dict
        One per curve with our runs under their settings: ``figure``, ``curve``, ``theirs`` (the share
        of each of their runs, run 1 first: the plotted one) and ``ours`` (each of our seeds' share).
    """
    runs52 = authors.table52_runs()
    out = []
    for cfg in get_experiment("table-5.2").configs:
        found = figures51_52_authors_runs(records, cfg.name)
        if found is None:
            continue
        method = method_of(cfg, Adaptive)
        error = method.error
        key = (method.gradient.estimator, error.bound, error.empirical_range, error.delta)
        s = overlays.figure51_52_overlay_series({cfg.name: found[1]}, cfg, "authors")
        mapped = [authors.grid_curve(r["N"], r["J"])[1] for r in runs52[key]]
        theirs = [band_share(s["x"], z, s["values"], 1, rounding=written_rounding(z, digits=RUN_DIGITS))["share_inside"]
                  for z in mapped]
        out.append({"figure": figure_of_51_52(error), "curve": cfg.name, "theirs": theirs,
                    "ours": own_spread(s["x"], s["values"])})
    return out


def figure55_spread(records: Records) -> list[dict[str, Any]]:
    """:func:`figures51_52_spread` for Figure 5.5 (their one committed run of each step rule)."""
    runs, step = authors.lqg2d_runs(), records.get("figures-5.5-5.6", {})
    out = []
    for key in ("scalar", "coordinate"):
        if step.get(key):
            g = figure55_series(runs[key], step[key])
            theirs = band_share(g["x"], g["theirs"], g["values"], 1, rounding=g["rounding"])["share_inside"]
            out.append({"figure": "5.5", "curve": key, "theirs": [theirs], "ours": own_spread(g["x"], g["values"])})
    return out


def own_spread(x: np.ndarray, ours: np.ndarray) -> list[float]:
    """Each of our seeds held, as one run, against the band for one run of our other seeds: how far the
    share of a curve drawn from our own process scatters under the rule (``ours``: (seeds, points))."""
    return [band_share(x, ours[i], np.delete(ours, i, axis=0), 1)["share_inside"] for i in range(ours.shape[0])]


__all__ = ["FIGURES_51_52_HYPOTHESES", "Hypothesis", "figure55_spread", "figures51_52_hypotheses",
           "figures51_52_spread", "own_spread"]
