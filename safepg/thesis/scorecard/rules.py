"""What the scorecard compares and how it judges: statuses, groups, printed values, rules, notes, rows.

:data:`PRINTED` holds the printed values no other module records; :data:`KIND_RULE` states how
each kind of printed number is judged and :data:`RULES` each status rule; the checks of
:mod:`~safepg.thesis.scorecard.tolerances` apply them; :data:`NOTES` keeps the chapters' explanations of the
rows that differ; :class:`Row` is one row of the scorecard.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields
from typing import Any, Final, Literal, NamedTuple, Protocol

from safepg.thesis.scorecard.text import MissingValueError, fill, template_fields

#: The status of a row that fails its rule on our runs of the thesis's text and passes it, by the
#: same rule, on our runs under the authors' settings: what their code ran where the text says
#: something else or nothing.
AUTHORS_STATUS: Final = "reproduced only with the authors' unprinted settings"
#: The status of a row whose printed number is reproduced only by an error in the authors' code (their
#: 2-D J, 16 times the expectation): their number explained, not the thesis's claim confirmed.
AUTHORS_ERROR_STATUS: Final = "reproduced only through an error in the authors' code"
#: The status of a row whose rule holds on a run that could not have done otherwise: an improvement
#: ratio of a run whose theta does not move (consecutive batch means then differ by noise alone, so any
#: such run scores about 50%, or 100% when no update is taken). The agreement carries no information.
VACUOUS_STATUS: Final = "agrees, but carries no information"
#: The status of a row whose tests reject on no column but could not have detected a difference that
#: matters on any: not rejecting is not reproducing.
INCONCLUSIVE_STATUS: Final = "inconclusive"
Status = Literal["reproduced", "reproduced only with the authors' unprinted settings",
                 "reproduced only through an error in the authors' code", "agrees, but carries no information",
                 "inconclusive", "differs (explained)", "open"]
#: The statuses, in the order the page lists them: the two that reproduce the printed number, the two
#: counted apart (agreement through an error of the authors' code, agreement without information),
#: the rows whose tests could not decide, then the two that do not reproduce it.
STATUSES: tuple[Status, ...] = ("reproduced", AUTHORS_STATUS, AUTHORS_ERROR_STATUS, VACUOUS_STATUS,
                                INCONCLUSIVE_STATUS, "differs (explained)", "open")
#: The columns a status can be judged on (:attr:`Row.judged_on`).
JUDGED_ON = ("ours", "authors' settings")
#: A run whose every component of theta moves by less than this over the whole run is frozen: its
#: improvement ratio carries no information (:data:`VACUOUS_STATUS`). Where it falls: the text's
#: adaptive cart-pole runs (table-5.4, theta of order 1 to 7) moved theta by 4e-7 to 1.8e-6 over
#: two draws of five seeds each, and every other run the scorecard counts moved it by 1.4e-5 or
#: more (table-5.1-authors, sigma = 0.5, N = 10000, alpha = 1e-6). 1e-6 lay inside the first
#: spread, so the flag depended on the seeds; 5e-6 sits about three times from both groups.
FROZEN_THETA = 5e-6

#: What kind of number a row compares, which decides the interval it is judged on (:data:`KIND_RULE`).
Kind = Literal["closed form", "one run", "mean of runs", "read off a figure", "whole curve", "statement"]
KINDS: tuple[Kind, ...] = ("closed form", "one run", "mean of runs", "read off a figure", "whole curve", "statement")
#: How each kind of printed number is judged, as stated on the page.
KIND_RULE: dict[str, str] = {
    "closed form": "A formula or a number that follows from the task alone: judged exactly, or at the rounding "
                   "of its last printed digit.",
    "one run": "A number printed from one run of the authors (Table 5.1's cells, Tables 5.3 and 5.4, the 2-D runs' "
               "final parameters and ratios, the baseline's iteration count): a prediction t-test of that one run "
               "against our k runs, T = d / (s·√(1 + 1/k)) with k - 1 degrees of freedom. The interval of our mean "
               "would reject single runs that our own seeds produce routinely.",
    "mean of runs": "A number printed as a mean over runs with its interval (Table 5.2): Welch's t-test of two "
                    "estimates of the same mean, the printed interval giving the spread of their runs.",
    "read off a figure": "A number the text reads off a figure (\"N ≈ 500\", \"of the order of 1e-6\"): the "
                         "prediction t-test against the printed value give or take the reading precision the row "
                         "states.",
    "whole curve": "An authors' curve from their raw output, as its means over three equal blocks of the plotted "
                   "range: their runs against ours by the two-sample Hotelling T² and its exact permutation p-value "
                   "where their history holds several runs (Figures 5.1-5.4), else their one run by Hotelling's T² for "
                   "one new curve. The share of their curve inside our pointwise 95% band stays beside it, to say "
                   "where the curves part.",
    "statement": "A claim about every configuration or every update (\"an improvement ratio of 1 ... also with "
                 "large values of delta\", \"never updates beta\"): judged by its own rule on all our runs.",
}

#: What difference matters, by quantity: a column that is not rejected reproduces the printed number only
#: when its test would have detected that much (with 80% power, at the level it faced).
RELEVANCE: dict[str, str] = {
    "improvement ratio": "5 points: a twentieth of a ratio's range, the scorecard's tolerance for a ratio "
                         "claimed of every configuration.",
    "a performance, an iteration count, a batch size, a step": "5% of the printed value, and never less than the "
                                                               "printed precision or reading.",
    "a final parameter": "5% of the largest printed entry of its matrix: the off-diagonal entries near 0 are "
                         "judged on the matrix's scale.",
    "an order of magnitude": "one decade.",
    "a parameter that never moves, a printed 0": "none: every run must give it exactly.",
    "a whole curve": "5% of the range of the authors' values over the plotted range, the same shift in every "
                     "block.",
}

#: Groups of rows, in the order of the thesis (and of the page).
GROUPS = ("Chapters 3-4 and Appendix A", "Appendix B", "Section 5.1", "Section 5.2", "Section 5.3")

#: Printed values that no other module records (the others come from the experiments'
#: ``thesis`` dicts, :mod:`safepg.thesis.lqg_settings` and :mod:`safepg.thesis.errata`). Strings keep the
#: printed digits, which set the rounding tolerance.
PRINTED: dict[str, Any] = {
    # Section 5.1: "theta* ~ -0.59, corresponding to expected performance J(theta*) ~ -13.21".
    "lqg1d_theta_star": "-0.59",
    "lqg1d_J_star": "-13.21",
    # Section 5.1: "step sizes ... of the order of 10^-5" (also "In all the experiments").
    "lqg1d_step_order": -5,
    # Section 5.2.1: "The adaptive batch size goes from N ~ 500 in the first learning
    # iterations, to N ~ 2500 in the end. The step size takes values of the order of 1e-6".
    "lqg2d_batch_first": "500",
    "lqg2d_batch_last": "2500",
    "lqg2d_step_order": -6,
    # Theorem 4.3.2: "... >= 0.16 ||g||^2", the decimal value of (393 - 95 sqrt 17) / 8.
    "thm_4_3_2_decimal": "0.16",
    # Section 5.3: the adaptive method "never updates the components of theta corresponding
    # to beta and beta-dot" (state [x, x_dot, beta, beta_dot]: components 2 and 3).
    "cartpole_components_never_updated": (2, 3),
}

#: Decimals of the printed tables whose values are stored as floats (-20.50 is printed
#: with two decimals, the float keeps one).
TABLE_DECIMALS = {"table-5.2": 4, "table-5.3": 2, "table-5.4": 2}

#: Improvement-ratio tolerance, in points of percentage.
RATIO_POINTS = 5.0

#: The status rules, as stated on the page.
RULES: dict[str, str] = {
    "closed-form": "Closed forms (Chapters 3-4, appendices): reproduced when our sympy derivation equals the "
                   "printed expression (their difference simplifies to 0), is proportional to it by a "
                   "constant where that is all the text claims, or proves the printed claim, as recorded by "
                   "safepg.thesis.errata.verified(); a printed statement that differs from its derivation is "
                   "recorded, with its explanation, by safepg.thesis.errata.errata().",
    "rounded": "A printed number: reproduced when |ours - thesis| is at most half a unit of its last printed "
               "digit (-0.59 covers -0.595 to -0.585; a printed 0 must be exactly 0).",
    "welch": "Table 5.2 (a mean over 5 runs with its 95% interval): Welch's t-test of the printed mean against "
             "our k runs, the printed interval ȳ ± h giving their standard deviation s = h·√5 / t(0.975, 4), "
             "the printed mean widened by half a unit of its last digit; Welch-Satterthwaite degrees of freedom.",
    "prediction": "A number from one run: the prediction t-test. The printed value, widened by half a unit of its "
                  "last digit, lies at distance d from the mean of our k runs; T = d / (s·√(1 + 1/k)), with s our "
                  "runs' standard deviation, is Student-t with k - 1 degrees of freedom for normal runs. An "
                  "improvement ratio takes the values i/n of its run's n updates: it is also widened by one "
                  "update's share, so that seeds that all agree (100% on a run that improves at each update) do not "
                  "reject a run that differs from them by one update; where all our seeds give the same ratio, s "
                  "is the binomial spread of n updates at our rate of worsening ones. A printed 0 that every run of "
                  "ours gives exactly is reproduced exactly.",
    "reading": "A number read off a figure of one run (\"≈ 500\"): the prediction t-test against the printed "
               "value give or take the reading precision the row states (half a unit of its last significant "
               "digit).",
    "ratio-points": f"An improvement ratio claimed of every configuration: reproduced when |ours - thesis| <= "
                    f"{RATIO_POINTS:g} percentage points for the lowest of them.",
    "order": "\"Of the order of 10^k\" in every configuration: the prediction t-test of each configuration's "
             "median step, on a log10 scale, against the decade [k, k + 1), Bonferroni over the configurations.",
    "set": "Components that never move: the prediction t-test of each printed component's largest move over a "
           "run against exactly 0, Bonferroni over the components; only runs that all leave them exactly where "
           "they started reproduce the print.",
    "curve": "A whole curve as its means over three equal blocks of the plotted range: their runs against ours "
             "by the two-sample Hotelling T² (pooled covariance) and its exact permutation distribution where "
             "their history holds several runs; their one run by Hotelling's T² for one new curve, "
             "(k - B)/(B(k - 1))·T² ~ F(B, k - B) for normal runs, where it holds one (the exact rank of their "
             "curve among ours is beside it).",
}

#: Which column a status is judged on, and what a row that fails its rule means.
STATUS_RULE = ("A row of closed forms is judged by its rule. A row measured on runs has a test on each column: "
               "\"ours\", our runs as the thesis's text describes them (the settings it leaves unstated filled in "
               "by the library's defaults), and, where the row has it, \"ours, authors' settings\" (our runs with "
               "what the authors' code ran where the text says something else or nothing: their starting point, "
               "discount, constants, counting or task). Every such test is corrected together with all the others "
               "(the false discovery rate, below). A column is rejected when its test is among those the "
               "correction rejects; a column that is not rejected is conclusive when its test would have detected "
               "the difference that matters with 80% power at the level it faced, and inconclusive otherwise. The "
               "row is \"reproduced\" when ours is conclusive; otherwise \"" + AUTHORS_STATUS + "\" when the "
               "authors' column is, and the row names the setting that did it; where that column holds only "
               "through an error of their code (their 2-D J, 16 times the expectation), \"" + AUTHORS_ERROR_STATUS +
               "\". Where a cell was run again under the authors' settings with more seeds (Table 5.1's σ = 1, N "
               "= 1000, α = 1e-4: 50), that column is tested on the larger sample. A column that agrees on a run "
               "that could not have done otherwise (an improvement ratio of a run whose θ moves by less than " +
               f"{FROZEN_THETA:g}" + " in every component: its consecutive batch means differ by noise alone) does "
               "not count: it is \"" + VACUOUS_STATUS + "\" unless the other column is conclusive on a run that "
               "moved. A row whose columns are not all rejected, none conclusive, is \"" + INCONCLUSIVE_STATUS +
               "\", with the seeds that would decide it. A row rejected on every column is \"differs "
               "(explained)\" when the chapter that discusses it explains the gap (the one-sentence explanation "
               "is in the row, with a link), and \"open\" otherwise, with a sentence saying what evidence is "
               "missing. \"Authors' output\" is the authors' own raw output recomputed with their plot scripts' "
               "rules (safepg.thesis.authors): it is shown, never judged; where the printed value is more than "
               "one unit of its last digit away from it (neither its rounding nor its truncation), the row names "
               "the slip between their output and the print, with both numbers.")


# ------------------------------------------------------------------ the notes' measured values
# Each note that quotes measured values declares them as one of these: a row gives its note an
# instance, so that a value left out fails where the row is built, not on the page.
class Theta0s(NamedTuple):
    """Table 5.1's two starting points, as the notes quote them."""

    printed_theta0: str
    authors_theta0: str


class TailRuns(NamedTuple):
    """Table 5.1's cell outside our interval, against many more of our runs under the authors' settings."""

    runs: int
    mean: str
    interval: str
    at_least: int
    z: float
    theta_star: float
    crossing_theirs: int
    crossing_ours: str


class RangeRuns(NamedTuple):
    """Table 5.2's theoretical-range row under Lemma 4.3.3's range and under the authors' settings."""

    range_rows: str


class PrintedDiscount(NamedTuple):
    """The 2-D LQG's theta* at the printed discount (0.95)."""

    theta_printed_setting: float


class ClosedFormJ(NamedTuple):
    """The 2-D LQG's J(theta*): at the discount the runs use (0.9) and at the printed one (0.95)."""

    J_used: float
    J_printed_setting: float


class FinalTheta(NamedTuple):
    """One entry of the 2-D runs' final theta: the authors' run and the range of our seeds."""

    authors_output: str
    seeds: str


class BatchSizes(NamedTuple):
    """The adaptive batch size of the 2-D runs: ours, the authors' run, ours under their settings."""

    ours: float
    authors_output: str
    authors_settings: str


class AuthorsBaseline(NamedTuple):
    """The cart-pole baseline's iteration count on the authors' task."""

    authors_baseline: str


class CertifiedSteps(NamedTuple):
    """The range of the steps Theorem 4.2.3 certifies on the cart-pole task."""

    adaptive_steps: str


class MovedComponents(NamedTuple):
    """The cart-pole components that ours moves although the thesis says they never move."""

    extra: str
    extra_move: float
    authors_components: str


class _Measured(Protocol):
    """What a note's ``measured`` is: a NamedTuple class, whose fields name the values it quotes."""

    def _asdict(self) -> dict[str, Any]: ...


@dataclass(frozen=True)
class Note:
    """Why a row differs (``explains=True``) or what is known about an open row.

    ``measured``: the NamedTuple of the values its ``{...}`` fields name (None: it names none).

    Raises
    ------
    MissingValueError
        If ``text`` names a field that ``measured`` does not declare.
    """

    text: str
    page: str
    heading: str
    explains: bool = True
    measured: type[_Measured] | None = None

    def __post_init__(self) -> None:
        declared = set(getattr(self.measured, "_fields", ()))
        missing = template_fields(self.text) - declared
        if missing:
            raise MissingValueError(f"the note {self.text[:60]!r}... names {sorted(missing)}, which its measured "
                                    f"values {sorted(declared)} do not declare")

    def fill(self, values: _Measured | None) -> str:
        """The note's text filled from ``values``, an instance of :attr:`measured`.

        Raises
        ------
        MissingValueError
            If the note names values and ``values`` is not its :attr:`measured` (None: none given).
        """
        if self.measured is None:
            if values is not None:
                raise TypeError(f"the note {self.text[:60]!r}... quotes no values, got {values!r}")
            return self.text
        if not isinstance(values, self.measured):
            raise MissingValueError(f"the note {self.text[:60]!r}... needs a {self.measured.__name__}, got {values!r}")
        return fill(self.text, values._asdict())


#: The authors' curves of Figures 5.1 and 5.2, where their runs differ from ours under both settings.
_FIGURES_5_1_5_2 = Note(
    "Open: their five runs differ from ours both as the thesis's text has them (the J of the policy in use) and "
    "as the authors made them (through plots/scaleData.m, one update behind, under their settings). What is "
    "missing: a setting the audit has not found.", "lqg1d", "Figures 5.1 and 5.2", explains=False)

#: Figure 5.5's coordinate curve, where their run differs from ours under both processings.
_FIGURE_5_5_COORDINATE = Note(
    "Open: their coordinate run differs from ours, read as the thesis's text reads it (each batch's J held at "
    "their batch ends) and as their plot script made it (plots/scaleData.m, one update behind), which differ by "
    "about a hundredth of J at most. What is missing: their other runs (one run per step rule is committed), to "
    "tell a run ahead of ours from a difference of the method.", "lqg2d", "Figures 5.5 and 5.6", explains=False)

#: Explanations and notes, by row id or id prefix (``"table-5.1/"`` covers every cell).
#: ``{...}`` fields are filled from the note's measured values, which the row gives (:meth:`Note.fill`).
NOTES: dict[str, Note] = {
    "table-5.1/": Note(
        "Open: the test rejects the printed value both from the printed θ0 = {printed_theta0} and from the "
        "authors' θ0 = {authors_theta0}; what is missing: the authors' other runs (one run per cell is committed) "
        "to tell a setting from one run's noise.", "lqg1d", "Table 5.1", explains=False,
        measured=Theta0s),
    "table-5.1/tail": Note(
        "The print is the authors' own run, and a rare one of the process ours follows: of our {runs} runs under "
        "their settings (table-5.1-authors-tail) {at_least} reach it; it lies {z:.1f} standard deviations of one "
        "run above our mean {mean} (our 95% prediction interval for one run from those runs: {interval}). An "
        "update improves J while θ moves towards θ* = {theta_star:.4f}, so the ratio is set mostly by when θ "
        "crosses it: theirs after {crossing_theirs} updates, ours after {crossing_ours}.", "lqg1d", "Table 5.1",
        measured=TailRuns),
    "table-5.2/theoretical-range": Note(
        "Open: {range_rows}, and the authors' own five runs give the printed value (beside). What is missing is "
        "a setting of theirs that accounts for the rest.", "lqg1d", "Table 5.2", explains=False,
        measured=RangeRuns),
    "section-5.2/theta-star": Note(
        "Reproduced with γ = 0.9, the discount the Section 5.2 runs use and the only one in the authors' code "
        "(lqgnd/lqgnd.py@92ac378:41); the printed γ = 0.95 gives {theta_printed_setting:.4f}.", "lqg2d",
        "setting as printed", measured=PrintedDiscount),
    "section-5.2/J-star": Note(
        "Not reproducible by the consistent closed form: it gives {J_used:.3f} at θ* (γ = 0.9) and "
        "{J_printed_setting:.3f} for the printed γ = 0.95.", "lqg2d", "lab library", measured=ClosedFormJ),
    "section-5.2/theta-final-scalar/11": Note(
        "Ours end near the authors' own run ({authors_output}; our seeds {seeds}), one digit away from the print: "
        "the print slipped.", "lqg2d", "Figures 5.5 and 5.6", measured=FinalTheta),
    "section-5.2/theta-final-scalar/22": Note(
        "Open: the authors' one committed run ends at {authors_output}, as printed; our five seeds end at "
        "{seeds}, about 2e-5 nearer 0 (θ11 likewise). What is missing: their other runs, to tell a setting from "
        "one run's noise.", "lqg2d", "Figures 5.5 and 5.6", explains=False, measured=FinalTheta),
    "section-5.2/batch-first": Note(
        "Open: our adaptive batch size starts at {ours:.0f} on average over iterations 2-11, the authors' "
        "own run at {authors_output}, near the printed ≈ 500; under their settings ours is "
        "{authors_settings}. What is missing: the setting that makes their early batches larger than ours.",
        "lqg2d", "Table 5.3", explains=False, measured=BatchSizes),
    "section-5.2/batch-last": Note(
        "The printed ≈ 2500 is not in the authors' own run either: it averages {authors_output} over "
        "its last 10 iterations, ours {ours:.0f}; the thesis reads its number off Figure 5.7.", "lqg2d",
        "Table 5.3", measured=BatchSizes),
    "table-5.3/adaptive/upsilon": Note(
        "The thesis gives no N_min, nor what happens when Assumption 4.2.7 fails, for this section; ours "
        "(N_min = 100, no update) set the first iterations, which weigh on the average.", "lqg2d", "Table 5.3"),
    "section-5.3/baseline-iterations": Note(
        "The count depends strongly on settings the thesis does not state: with the same protocol, 72 lies "
        "between our counts at γ = 0.99 and γ = 0.995, and the chapter's sweep also reaches it with a 0.01 s "
        "time step; on the authors' task ours is {authors_baseline}.", "cartpole", "baseline policy",
        measured=AuthorsBaseline),
    # The chapter's sweep found the printed result not reproducible under any plausible setting:
    # an explained difference, not an open one.
    "table-5.4/": Note(
        "Not reproducible as the thesis describes the task: the steps Theorem 4.2.3 certifies on it "
        "({adaptive_steps}) leave θ where the baseline left it, and the chapter's sweep over every unstated setting "
        "finds none where it learns or where vanilla PG oscillates as reported.", "cartpole", "What the sweep says",
        measured=CertifiedSteps),
    "section-5.3/components": Note(
        "Open: ours also moves {extra} (by at most {extra_move:.0e}); the thesis's constants, which decide "
        "which component is updated, are not given; under the authors' settings (their per-batch constants) the "
        "components never updated are {authors_components}.", "cartpole", "Table 5.4", explains=False,
        measured=MovedComponents),
    "figure-5.5/coordinate": _FIGURE_5_5_COORDINATE,
    "figure-5.1/": _FIGURES_5_1_5_2,
    "figure-5.2/": _FIGURES_5_1_5_2,
    # Errata rows carry their own sentence (safepg.thesis.errata.errata()); this gives their link.
    "theory/erratum": Note("", "errata", "Errata"),
}


@dataclass(frozen=True)
class Row:
    """One printed result of the thesis, ours beside it.

    Attributes
    ----------
    id : str
        Stable identifier, e.g. ``"table-5.1/sigma=0.5/N=10000/alpha=1e-03"``.
    group : str
        One of :data:`GROUPS`.
    quantity : str
        What is compared.
    where : str
        Thesis section, table or statement.
    thesis, ours : str
        As printed / as we compute it (with our 95% interval over seeds where there is one).
    difference : str
        ``ours - thesis`` (or the relation of two closed forms).
    status : one of :data:`STATUSES`
    rule : str
        Key of :data:`RULES` that decided the status.
    explanation : str
        One sentence: why it differs, what is known about an open row, or a remark.
    link : str
        URL of the book section that discusses it, relative to the book's pages
        (``"lqg1d.html#table-5-1-fixed-step-size-and-batch-size"``).
    thesis_value, ours_value : float or None
        The numbers behind ``thesis`` and ``ours`` when they are numbers.
    ours_ci95 : list of float or None
        Our 95% interval over seeds.
    seeds : int or None
        Seeds behind ``ours``.
    thesis_tex, ours_tex : str
        LaTeX of closed forms ("" for numbers).
    fields : dict
        The row's coordinates in its thesis table (sigma, N, alpha, estimator, ...).
    judged_on : {"ours", "authors' settings", ""}
        The column the status was judged on ("" when neither could be: missing runs).
    authors : str
        Ours under the authors' settings ("" when the row has no such run; "-" when its runs are
        not stored).
    authors_value, authors_ci95, authors_seeds
        The number, our 95% interval and the seeds behind ``authors``.
    authors_experiment : str
        The experiment behind ``authors`` (e.g. ``"table-5.1-authors"``), or what was computed.
    authors_output : str
        The authors' own raw output, recomputed with their plot scripts' rules ("" when none
        applies).
    authors_output_value : float or None
    authors_output_source : str
        ``path@commit`` of the authors' file(s) behind ``authors_output``.
    slip : bool
        The printed value is neither the rounding nor the truncation of the authors' output.
    kind : one of :data:`KINDS`
        What kind of printed number this is (:data:`KIND_RULE`).
    judged_interval : list of float or None
        The interval the status was judged on (on the column ``judged_on``), in the units of
        ``ours_value``; None for rules without one.
    judged_interval_text : str
        That interval as the page shows it, with what it is ("95% prediction interval for one run,
        5 seeds").
    judged_seeds : int or None
        The seeds behind the judged column.
    no_information : str
        Why one of our columns agrees with the print without information ("" when none does): the
        row is flagged, and counted at the top of the page, whatever its status.
    test : str
        The test of a row judged on runs (:mod:`safepg.significance`), "" for a closed form.
    p_value, authors_p_value : float or None
        Its two-sided p-value on ours and on ours under the authors' settings.
    level : float or None
        The threshold the judged column's test faced within the family (:mod:`~safepg.thesis.scorecard.verdicts`).
    detectable : float or None
        The smallest difference the judged column's test detects with 80% power at ``level``, in the units
        of ``ours_value`` (a column not rejected).
    relevance, relevance_text : float or None, str
        The difference that matters for this row, and how it was set (:data:`RELEVANCE`).
    seeds_needed, authors_seeds_needed : int or None
        For an inconclusive column (ours; ours under the authors' settings): the seeds at which its test
        would be conclusive (None: conclusive, rejected, or no number would).
    test_text : str
        What each column's test found, in words.
    sources, authors_sources : list of str
        The configurations behind each column, ``"experiment/config"``: the seed rule adds runs to them
        (:mod:`safepg.thesis.seed_rule`).
    state, authors_state : {"", "rejected", "conclusive", "inconclusive"}
        Each column's test within the family ("" without a test).
    verdict : str
        The judged column's test in a few words (its p-value, seeds and detectable difference), for the page.
    """

    id: str
    group: str
    quantity: str
    where: str
    thesis: str
    ours: str
    difference: str
    status: Status
    rule: str
    explanation: str
    link: str
    thesis_value: float | None = None
    ours_value: float | None = None
    ours_ci95: list[float] | None = None
    seeds: int | None = None
    thesis_tex: str = ""
    ours_tex: str = ""
    fields: dict[str, Any] = field(default_factory=dict)
    judged_on: str = ""
    authors: str = ""
    authors_value: float | None = None
    authors_ci95: list[float] | None = None
    authors_seeds: int | None = None
    authors_experiment: str = ""
    authors_output: str = ""
    authors_output_value: float | None = None
    authors_output_source: str = ""
    slip: bool = False
    kind: str = "closed form"
    judged_interval: list[float] | None = None
    judged_interval_text: str = ""
    judged_seeds: int | None = None
    no_information: str = ""
    test: str = ""
    p_value: float | None = None
    authors_p_value: float | None = None
    level: float | None = None
    detectable: float | None = None
    relevance: float | None = None
    relevance_text: str = ""
    seeds_needed: int | None = None
    authors_seeds_needed: int | None = None
    test_text: str = ""
    sources: list[str] = field(default_factory=list)
    authors_sources: list[str] = field(default_factory=list)
    state: str = ""
    authors_state: str = ""
    verdict: str = ""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Row:
        names = {f.name for f in fields(cls)}
        unknown = set(d) - names
        if unknown:
            raise ValueError(f"d has unknown keys {sorted(unknown)}")
        return cls(**dict(d))


#: Short names of the statements of :mod:`safepg.thesis.errata` (display only; a new record falls
#: back to its id).
THEORY_LABELS = {
    "thm_4_2_3_c": "penalty constant c", "cor_4_2_4_alpha": "step size 1/(2c)",
    "cor_4_2_4_improvement": "guaranteed improvement", "cor_4_2_5_scalar_step": "scalar step of Pirotta et al. (2013)",
    "cor_4_2_5_inequality": "coordinate step never worse than scalar", "cor_4_2_8_alpha": "step size with error ε",
    "cor_4_2_8_improvement": "guaranteed improvement with error ε", "sec_4_2_2_selection": "choice of k",
    "cor_4_2_8_actual_update": "guarantee for the update actually made", "thm_4_3_2_N0": "N₀",
    "thm_4_3_2_N_star": "batch size N*", "thm_4_3_2_alpha": "step size α*", "thm_4_3_2_N_star_feasible": "N* ≥ N₀",
    "fig_4_1_shape": "shape of Υ(N) (Figure 4.1)", "chebyshev_d": "Chebyshev d_δ",
    "chebyshev_N_star_reinforce": "Chebyshev N*, REINFORCE", "chebyshev_N_star_gpomdp": "Chebyshev N*, G(PO)MDP",
    "hoeffding_d": "Hoeffding d_δ", "bernstein_d_f": "Bernstein d_δ and f_δ", "bernstein_S_N": "sample variance S_N",
    "bernstein_N0": "Bernstein N₀", "bernstein_factors": "factors of dΥ/dN", "bernstein_descartes": "unique maximum",
    "scalar_step_3_3_2": "scalar step α* of Pirotta et al. (2013)",
    "scalar_improvement_3_3_2": "improvement of Pirotta et al. (2013)",
    "bound_3_7": "bound (3.7)", "lemma_a_0_1_hessian": "Gaussian second derivative",
    "lemma_a_0_1_statement": "Lemma A.0.1", "lemma_a_0_2_statement": "Lemma A.0.2",
    "lemma_b_0_3": "softmax second derivative", "lemma_b_0_5": "softmax policy distance",
    "thm_b_0_6_c": "constant c", "thm_b_0_6_b": "constant b", "cor_b_0_7_alpha": "step size",
    "cor_b_0_7_improvement": "guaranteed improvement", "thm_4_3_2_upsilon_proof": "Υ(Λ*, N) in the proof",
    "thm_4_3_2_upsilon_star": "Υ*", "thm_4_3_2_improvement": "guaranteed improvement N* Υ*",
    "hoeffding_exponent": "Hoeffding's tail", "range_definition": "range R of the gradient samples",
    "lemma_4_3_3_range": "bound on the range R", "algorithm_4_1_step_line": "Algorithm 4.1, step line",
    "algorithm_4_1_stopping": "Algorithm 4.1, stopping test",
    "algorithm_4_1_min_batch": "Algorithm 4.1, smallest batch",
    "lemma_4_2_2_q_sign": "sign of the Q term", "thm_4_2_6_probability": "confidence (1 - δ)^m",
    "scalar_step_5_2_1": "scalar step α̂* as printed in 5.2.1",
}
