"""Rows of the authors' whole curves (Figures 5.1-5.9): the share of each that lies in our pointwise 95%
prediction band (:mod:`safepg.thesis.curve_bands`), on our runs of the thesis's text and on our runs under
the authors' settings, as two columns of one row.

An authors' figure of several runs of theirs (Figures 5.3-5.4: each of their committed runs drawn as one
run) is one row: it holds when every run's curve does, and shows the range of their shares."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from safepg.learning import LearningRecord
from safepg.thesis.curve_bands import CURVE_SHARE, CurveScore, curve_holds, curve_scores, outside_sentence
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.outputs import Output

#: Experiments under the authors' settings: a curve scored on one of them fills the row's authors' column.
AUTHORS_SETTINGS = ("table-5.3-authors", "table-5.4-authors-theta-star")
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
            "band": f"our pointwise 95% prediction band for {kind}, {worst.seeds} seeds; the rule: at least "
                    f"{CURVE_SHARE:.0%} of the curve inside", "worst": worst}


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
        side = "authors" if s.experiment in AUTHORS_SETTINGS else "ours"
        grouped.setdefault((s.figure, _curve_key(s)), {}).setdefault(side, []).append(s)
    for (figure, curve), sides in grouped.items():
        group, page, heading = FIGURE_PLACES[figure]
        ours, theirs = (_column(sides[k]) if k in sides else None for k in ("ours", "authors"))
        first = (ours or theirs)["worst"]  # type: ignore[index]
        authors = AuthorsColumn() if theirs is None else AuthorsColumn(
            text=theirs["text"], value=theirs["share"], ok=theirs["holds"], seeds=theirs["seeds"],
            experiment=theirs["worst"].experiment, interval_text=theirs["band"], note=AUTHORS_NOTES.get(figure, ""))
        remark = " ".join(f"{label}: their curve {outside_sentence(c['worst'])}"
                          for label, c in (("Ours", ours), ("Under the authors' settings, ours", theirs))
                          if c is not None and not c["holds"])
        runs = len(next(iter(sides.values())))  # their runs behind the curve (Figures 5.3-5.4: several)
        b.add(RowSpec(id=f"figure-{figure}/{curve}", group=group, quantity=f"{curve}: {first.quantity}",
              where=first.where, thesis=f"the authors' curve ({first.kind})",
              ours="-" if ours is None else ours["text"], difference="-", ok=None if ours is None else ours["holds"],
              rule="curve-band", kind="whole curve", page=page, heading=heading,
              ours_value=None if ours is None else ours["share"],
              seeds=None if ours is None else ours["seeds"], interval_text="" if ours is None else ours["band"],
              output=Output(value=None, text=f"their {runs} runs" if runs > 1 else "their curve", source=first.source),
              fields={"figure": figure, "curve": curve, "experiment": None if ours is None else first.experiment},
              remark=remark, authors=authors))
