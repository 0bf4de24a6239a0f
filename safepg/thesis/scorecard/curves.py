"""Rows of the authors' whole curves (Figures 5.1-5.9): the share of each that lies in our pointwise 95%
prediction band (:mod:`safepg.thesis.curve_bands`), on our runs of the thesis's text and on our runs under
the authors' settings (for Figures 5.1, 5.2 and 5.5 under their plot script's processing), as two columns
of one row.

An authors' figure of several runs of theirs (Figures 5.3-5.4: each of their committed runs drawn as one
run) is one row: it holds when every run's curve does, and shows the range of their shares."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from safepg.record import LearningRecord
from safepg.thesis.curve_bands import (
    CurveScore,
    curve_holds,
    curve_scores,
    outside_sentence,
)
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.outputs import Output
from safepg.thesis.scorecard.verdicts import relevance_text

#: Experiments under the authors' settings: a curve scored on one of them fills the row's authors' column.
AUTHORS_SETTINGS = ("table-5.3-authors", "table-5.4-authors-theta-star", "figures-5.1-5.2-authors",
                    "table-5.2-authors")
#: Where each figure is discussed: its group on the scorecard, the book's page and heading.
FIGURE_PLACES = {"5.1": ("Section 5.1", "lqg1d", "Figures 5.1 and 5.2"),
                 "5.2": ("Section 5.1", "lqg1d", "Figures 5.1 and 5.2"),
                 "5.3": ("Section 5.1", "lqg1d", "Figures 5.3 and 5.4"),
                 "5.4": ("Section 5.1", "lqg1d", "Figures 5.3 and 5.4"),
                 "5.5": ("Section 5.2", "lqg2d", "Figures 5.5 and 5.6"),
                 "5.6": ("Section 5.2", "lqg2d", "Figures 5.5 and 5.6"),
                 "5.7": ("Section 5.2", "lqg2d", "Figures 5.7, 5.8"),
                 "5.8": ("Section 5.2", "lqg2d", "Figures 5.7, 5.8"),
                 "5.9": ("Section 5.3", "cartpole", "Figure 5.9 and Table 5.4")}
#: Why ours under the authors' settings reproduces a curve that ours under the text does not.
AUTHORS_NOTES = {
    "5.7": "Reproduced with the authors' adaptive run: Bernstein on the largest variance and range over the "
           "components, N_max = 100000 (lqgnd/lqgnd_adabatch.py@92ac378:256-257), the step taken even when "
           "ε ≥ abs(g_k).",
    "5.9": "Reproduced on the authors' task and method, from their own baseline policy (theta_star.npy@a82576f): "
           "12° termination, their doubled pole, γ = 0.9 and per-batch R, M_φ in c, the maxima over components, "
           "unguarded steps, their coordinate 'vanilla'.",
}
AUTHORS_NOTES["5.8"] = AUTHORS_NOTES["5.7"]
AUTHORS_NOTES["5.3"] = AUTHORS_NOTES["5.4"] = (
    "Reproduced with the authors' settings: N_min and N_max from each run's header and their step taken after "
    "the first batch whatever ε is (lqg/lqg_adabatch.py@eb78917:212-222), as figures-5.1-5.2-authors runs, and for "
    "the theoretical-range rows their range 1280 with that step (table-5.2-authors).")
AUTHORS_NOTES["5.5"] = (
    "Reproduced as the authors' plot script made it: their run through plots/scaleData.m@4ff60e7:1-11 (at x, the J "
    "of the policy of the last batch ended before x − 1000), and each of our runs likewise.")
AUTHORS_NOTES["5.1"] = AUTHORS_NOTES["5.2"] = (
    "Reproduced with the authors' processing and settings, the same for every curve: each of their curves is "
    "one run (their run 1, not a mean of 5) mapped by plots/scaleData.m@e4cdc9e:1-11 (at x, the J of the policy "
    "of the last batch ended before x − 1000), and their script updates after the first batch whatever ε is "
    "(lqg/lqg_adabatch.py@eb78917:212-222) with N_min and N_max from each run's header.")


def _side(s: CurveScore) -> str:
    """Which column a score fills: the authors' (their settings or their processing) or ours."""
    return "authors" if s.processing == "authors" or s.experiment in AUTHORS_SETTINGS else "ours"


def _curve_key(s: CurveScore) -> str:
    """The authors' curve a score belongs to: their runs of one Figure 5.3-5.4 curve count as one."""
    return s.curve.split("/run-")[0]


def _column(scores: Sequence[CurveScore]) -> dict[str, Any]:
    """One column of a row from the scores of one experiment (several: the authors' runs of one curve)."""
    shares = [s.share_inside for s in scores]
    worst = min(scores, key=lambda s: s.share_inside)
    if len(scores) == 1:
        text = f"{worst.share_inside:.1%} of {worst.points} points inside"
    else:
        text = f"{min(shares):.1%} to {max(shares):.1%} inside, each of their {len(scores)} runs"
    kind = worst.kind if worst.kind == "one run" else f"a {worst.kind}"
    return {"text": text, "share": min(shares), "holds": all(curve_holds(s) for s in scores), "seeds": worst.seeds,
            "band": f"our pointwise 95% prediction band for {kind}, {worst.seeds} seeds (a description: the test "
                    "decides)", "worst": worst, "test": scores[0].test, "relevance": scores[0].relevance}


def curve_rows(b: Builder, records: Mapping[str, Mapping[str, Sequence[LearningRecord]]]) -> None:
    """Add one row per authors' curve to ``b``: ours (the thesis's text) and ours under the authors'
    settings, each the share of their curve in our band (:func:`~safepg.thesis.curve_bands.curve_scores`).

    Parameters
    ----------
    b : Builder
        The rows so far.
    records : mapping
        Loaded runs by experiment name (those of :data:`~safepg.thesis.curve_bands.CURVE_EXPERIMENTS`
        that are stored; a curve without runs gets no row).
    """
    grouped: dict[tuple[str, str], dict[str, list[CurveScore]]] = {}
    for s in curve_scores(records):
        grouped.setdefault((s.figure, _curve_key(s)), {}).setdefault(_side(s), []).append(s)
    for (figure, curve), sides in grouped.items():
        group, page, heading = FIGURE_PLACES[figure]
        ours, theirs = (_column(sides[k]) if k in sides else None for k in ("ours", "authors"))
        shown = ours or theirs
        if shown is None:  # not reached: a curve is grouped under the side whose score it has
            raise TypeError(f"figure {figure}, {curve}: no column to show")
        first = shown["worst"]
        authors = AuthorsColumn() if theirs is None else AuthorsColumn(
            text=theirs["text"], value=theirs["share"], test=theirs["test"], seeds=theirs["seeds"],
            sources=(f"{theirs['worst'].experiment}/{curve}",),
            experiment=theirs["worst"].experiment, interval_text=theirs["band"], note=AUTHORS_NOTES.get(figure, ""))
        processed = theirs is not None and theirs["worst"].processing == "authors"
        label = "Under the authors' processing and settings, ours" if processed else "Under the authors' settings, ours"
        # Where the curves part, described by our band (the test decides).
        remark = " ".join(f"{lab}: their curve {outside_sentence(c['worst'])}"
                          for lab, c in (("Ours", ours), (label, theirs))
                          if c is not None and not c["holds"])
        relevance = (ours or theirs or {}).get("relevance")
        runs = len(next(iter(sides.values())))  # their runs behind the curve (Figures 5.3-5.4: several)
        # What their curve is: under their processing, one run whatever the caption says.
        kind = (f"{theirs['worst'].kind}, which the caption calls averaged over 5 runs"
                if theirs is not None and processed and figure in ("5.1", "5.2") else first.kind)
        b.add(RowSpec(id=f"figure-{figure}/{curve}", group=group, quantity=f"{curve}: {first.quantity}",
              where=first.where, thesis=f"the authors' curve ({kind})",
              ours="-" if ours is None else ours["text"], difference="-", ok=None,
              test=None if ours is None else ours["test"], relevance=relevance,
              sources=() if ours is None else (f"{first.experiment}/{curve}",),
              relevance_text=relevance_text("scale", relevance or 0.0), rule="curve", kind="whole curve", page=page,
              heading=heading,
              ours_value=None if ours is None else ours["share"],
              seeds=None if ours is None else ours["seeds"], interval_text="" if ours is None else ours["band"],
              output=Output(value=None, text=f"their {runs} runs" if runs > 1 else "their curve", source=first.source),
              fields={"figure": figure, "curve": curve, "experiment": None if ours is None else first.experiment},
              remark=remark, authors=authors))
