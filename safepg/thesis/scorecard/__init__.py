r"""The reproduction scorecard: every quantitative result the thesis prints, ours beside it.

One :class:`Row` per printed result, built from the same sources the chapters use:

* the stored runs of the Chapter 5 experiments, summarised by
  :func:`safepg.thesis.report.report` (every cell of Tables 5.1-5.4, the improvement ratios,
  the final parameters of Section 5.2.1, the cart-pole baseline's iteration count), with
  the printed values taken from each :class:`~safepg.thesis.experiments.Experiment`'s ``thesis``;
* the closed forms of :class:`safepg.envs.lqg.LQG` (:math:`\theta^*`, :math:`J(\theta^*)`)
  with the printed values of :mod:`safepg.thesis.lqg_settings` and :data:`PRINTED`;
* the printed statements of Chapters 3-4 and the appendices against their sympy
  derivations, as recorded by :func:`safepg.thesis.errata.verified` and
  :func:`safepg.thesis.errata.errata`.

No number is typed here except the printed values no other module records yet
(:data:`PRINTED`). Each row gets a status by a stated rule (:data:`RULES`, :data:`STATUS_RULE`):
``"reproduced"`` when the rule holds on ours (the thesis's text); otherwise
:data:`AUTHORS_STATUS` when it holds on ours under the authors' settings (the ``*-authors``
experiments, :data:`AUTHORS_VARIANTS`, and their 2-D J); otherwise ``"differs (explained)"``
when the chapter explains the gap (the sentence is kept with the row, :data:`NOTES`), else
``"open"`` with what evidence is missing. Beside them, the authors' own raw output recomputed
(:mod:`~safepg.thesis.scorecard.outputs`), and a named slip where the print is not their output.

:func:`scorecard` builds the rows (``run=True`` computes missing runs first),
:func:`write_scorecard` exports them and each thesis table to CSV and JSON, and
:func:`summary_html` / :func:`group_html` render them for the book's scorecard page.

Modules (their public names used outside the package are available here):

- :mod:`~safepg.thesis.scorecard.rules`: statuses, groups, :data:`PRINTED`, :data:`RULES`,
  :data:`NOTES` (each with the measured values it quotes, a NamedTuple), :class:`Row` and the
  tolerance functions that apply the rules;
- :mod:`~safepg.thesis.scorecard.links`: the book's folder :data:`BOOK` and :func:`book_link`;
- :mod:`~safepg.thesis.scorecard.text`: the cells' texts (percentages, intervals, closed forms);
- :mod:`~safepg.thesis.scorecard.builder`: :class:`~safepg.thesis.scorecard.builder.RowSpec`, what a
  row says before it is judged, and the row builder, which applies the rules and the notes;
- :mod:`~safepg.thesis.scorecard.closed_forms`: the rows of the printed statements and the LQG's
  closed forms;
- :mod:`~safepg.thesis.scorecard.runs`: the rows of the Chapter 5 runs;
- :mod:`~safepg.thesis.scorecard.outputs`: the authors' raw outputs beside the rows;
- :mod:`~safepg.thesis.scorecard.rows`: :func:`scorecard`, every row;
- :mod:`~safepg.thesis.scorecard.stored`: the rows built once per state of their inputs, and stored;
- :mod:`~safepg.thesis.scorecard.export`: :func:`counts`, the CSV and JSON files;
- :mod:`~safepg.thesis.scorecard.page`: the scorecard page's HTML.
"""

from __future__ import annotations

from safepg.thesis.curve_bands import CURVE_SHARE
from safepg.thesis.scorecard.export import (
    CSV_COLUMNS,
    TABLES,
    counts,
    counts_text,
    family_numbers,
    headline_numbers,
    read_csv,
    read_scorecard_json,
    row_id_of,
    status_key,
    statuses,
    write_scorecard,
)
from safepg.thesis.scorecard.links import BOOK, book_link
from safepg.thesis.scorecard.page import group_html, row_anchor, summary_html
from safepg.thesis.scorecard.rows import (
    AUTHORS_VARIANTS,
    NEEDED,
    RANGE_VARIANTS,
    RUN_PAGES,
    build_rows,
    scorecard,
)
from safepg.thesis.scorecard.rules import (
    AUTHORS_ERROR_STATUS,
    AUTHORS_STATUS,
    FROZEN_THETA,
    GROUPS,
    INCONCLUSIVE_STATUS,
    JUDGED_ON,
    KIND_RULE,
    KINDS,
    NOTES,
    PRINTED,
    RATIO_POINTS,
    RELEVANCE,
    RULES,
    STATUS_RULE,
    STATUSES,
    TABLE_DECIMALS,
    VACUOUS_STATUS,
    Note,
    Row,
    Status,
)
from safepg.thesis.scorecard.tolerances import (
    half_unit,
    in_prediction,
    intervals_overlap,
    is_slip,
    order_of_magnitude,
    within_points,
    within_rounding,
)
from safepg.thesis.scorecard.verdicts import CORRECTION, FDR_LEVEL, FLOOR_MARGIN

__all__ = [
    "AUTHORS_ERROR_STATUS", "AUTHORS_STATUS", "AUTHORS_VARIANTS", "BOOK", "CORRECTION", "CSV_COLUMNS",
    "CURVE_SHARE", "FDR_LEVEL", "FLOOR_MARGIN", "FROZEN_THETA", "GROUPS", "INCONCLUSIVE_STATUS", "JUDGED_ON",
    "KINDS", "KIND_RULE", "NEEDED", "NOTES", "PRINTED", "RANGE_VARIANTS", "RATIO_POINTS", "RELEVANCE", "RULES",
    "RUN_PAGES", "STATUSES", "STATUS_RULE", "TABLES", "TABLE_DECIMALS", "THEORY_LABELS", "VACUOUS_STATUS", "Note",
    "Row", "Status", "book_link", "build_rows", "counts", "counts_text", "family_numbers", "group_html",
    "half_unit", "headline_numbers", "in_prediction", "intervals_overlap", "is_slip", "order_of_magnitude",
    "read_csv", "read_scorecard_json", "row_anchor", "row_id_of", "scorecard", "status_key", "statuses",
    "summary_html", "within_points", "within_rounding", "write_scorecard",
]
