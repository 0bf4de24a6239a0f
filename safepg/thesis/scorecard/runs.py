"""Rows of the stored runs of Chapter 5: Section 5.1's Tables 5.1 and 5.2 and its step sizes here,
Sections 5.2-5.3 in :mod:`~safepg.thesis.scorecard.later_runs`, from the experiments' reports
(:func:`safepg.thesis.report.report`).

Each row holds ours (the thesis's text), ours under the authors' settings where a variant runs
them (the ``*-authors`` experiments; for Table 5.2's theoretical range, the authors' formula) and
the authors' own output (:mod:`safepg.thesis.scorecard.outputs`); the column of the authors'
settings is built by :mod:`~safepg.thesis.scorecard.run_columns`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from safepg import portable
from safepg.options import Adaptive, FixedStep, Vanilla
from safepg.record import LearningRecord
from safepg.runner import RunConfig
from safepg.significance import Test, WelchTest
from safepg.thesis import authors as authors_tables
from safepg.thesis.experiments import AUTHORS_T51_THETA0, T51_PRINTED_THETA0, Experiment, method_of
from safepg.thesis.scorecard import outputs
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.judged import (
    ci_judged,
    frozen,
    prediction,
    ratio_interval,
    ratio_test,
    ratio_text,
    slip_sentence,
    tail_placement,
    value_relevance,
)
from safepg.thesis.scorecard.later_runs import cartpole_rows, lqg2d_rows
from safepg.thesis.scorecard.rules import FROZEN_THETA, PRINTED, TABLE_DECIMALS, RangeRuns, TailRuns, Theta0s
from safepg.thesis.scorecard.run_columns import (
    RATIO_RELEVANCE,
    RATIO_RELEVANCE_TEXT,
    authors_column,
    mean_ci,
    points,
    report_row,
    step_rows,
)
from safepg.thesis.scorecard.text import ci_text, num, pct, signed
from safepg.thesis.scorecard.tolerances import half_unit, within_points
from safepg.thesis.scorecard.verdicts import relevance_text

#: Table 5.2's means are over this many runs of the authors ("All results are averaged over 5 runs").
T52_PRINTED_RUNS = 5
#: The level of Table 5.2's printed intervals as the authors computed them: their plot script's
#: ``tinv([0.05, 0.95], n - 1)``, a 90% interval the thesis prints as 95%
#: (:func:`safepg.thesis.authors.truncated_average`); it gives their runs' spread.
T52_PRINTED_LEVEL = 0.90


def _cell(c: RunConfig) -> tuple[float, int, float]:
    """(sigma, N, alpha) of a Table 5.1 run (fixed batch size and step)."""
    m = c.method
    assert isinstance(m, Vanilla) and isinstance(m.step, FixedStep)
    return c.sigma, m.batch_size, m.step.alpha


def _row_key(c: RunConfig) -> tuple[str, str, bool, float]:
    """(estimator, bound, empirical range, delta) of a Table 5.2 run, the key of its row everywhere."""
    m = c.method
    assert isinstance(m, Adaptive)
    return m.gradient.estimator, m.error.bound, m.error.empirical_range, m.error.delta


def _table_5_1_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any], printed: Experiment,
                    printed_rep: Mapping[str, Any], authors: Experiment | None,
                    authors_rep: Mapping[str, Any] | None,
                    tail: Mapping[tuple[float, int, float], TailRuns] | None = None,
                    tail_exp: Experiment | None = None, tail_rep: Mapping[str, Any] | None = None) -> None:
    """Table 5.1, cell by cell: ours from the printed theta_0 (``printed``), ours under the authors'
    settings (their theta_0 and counting; a cell ``tail_exp`` ran again with more seeds, on those once
    all are stored: five seeds' verdict there followed the seeds) and their output; ``exp`` (our
    reconstructed theta_0) is quoted in the explanation; ``tail`` places a print among ours."""
    recon = {_cell(c): r for c, r in zip(exp.configs, rep["configs"])}
    theirs = {_cell(c): (e, r) for e, er in ((authors, authors_rep), (tail_exp, tail_rep)) if e is not None
              for c, r in zip(e.configs, (er or {}).get("configs", [])) if e is authors or r["seeds"] >= e.seeds}
    starts = Theta0s(printed_theta0=f"{T51_PRINTED_THETA0:g}", authors_theta0=f"{AUTHORS_T51_THETA0:g}")
    for c, r in zip(printed.configs, printed_rep["configs"]):
        thesis = (r["thesis"] or {}).get("improvement_ratio")
        if thesis is None:
            continue
        key = sigma, n, alpha = _cell(c)
        mean, ci = mean_ci(r["improvement_ratio"])
        a_exp, ar = theirs.get(key, (authors, None))
        a_mean, a_ci = mean_ci(ar["improvement_ratio"]) if ar else (None, None)
        a_col = authors_column(a_exp, ar["seeds"] if ar else 0, a_mean, a_ci,
                               pct(a_mean) + ci_text(prediction(ar and ar["improvement_ratio"], True),
                                                     lambda x: pct(x, 1)),
                               test=ratio_test(thesis, ar), interval=ratio_interval(ar), interval_text=ratio_text(ar),
                               vacuous=frozen(ar and ar.get("theta_moved")),
                               sources=(f"{a_exp.name}/{ar['name']}",) if a_exp is not None and ar else ())
        rc = recon.get(key)
        rc_mean = None if rc is None else rc["improvement_ratio"]["mean"]
        recon_text = "" if rc_mean is None else \
            (f" Our reconstruction θ0 = {exp.configs[0].theta0[0]:g}, found before their outputs were read, "
             f"gives {pct(rc_mean)}.")
        out = outputs.table_5_1(*key)
        printed_text = f"{100 * thesis:.6g}"
        b.add(RowSpec(id=f"table-5.1/sigma={sigma:g}/N={n}/alpha={alpha:.0e}", group="Section 5.1",
              quantity=f"improvement ratio, σ = {sigma:g}, N = {n}, α = {alpha:.0e}", where="Table 5.1",
              thesis=pct(thesis),
              ours=pct(mean) + ci_text(prediction(r["improvement_ratio"], True), lambda x: pct(x, 1)),
              difference="-" if mean is None else f"{100 * (mean - thesis):+.2f} points", ok=None,
              test=ratio_test(thesis, r), relevance=RATIO_RELEVANCE, relevance_text=RATIO_RELEVANCE_TEXT, show=points,
              sources=(f"{printed.name}/{c.name}",),
              rule="prediction", kind="one run", page="lqg1d", heading="Table 5.1", thesis_value=thesis,
              ours_value=mean, ours_ci95=ci, seeds=r["seeds"], expected_seeds=printed.seeds,
              interval=ratio_interval(r), interval_text=ratio_text(r), vacuous=frozen(r.get("theta_moved")),
              authors=replace(a_col, note="Reproduced from the authors' θ0 = "
                              f"{AUTHORS_T51_THETA0:g} (where all 24 of their output files start), counted as they "
                              "counted (strict increases over 10^6/N - 1 updates); from the printed θ0 = "
                              f"{T51_PRINTED_THETA0:g} the test rejects the printed value." + recon_text),
              slip_note=slip_sentence(out, printed_text, lambda v: f"{v:.4g}%", scale=100),
              fields={"sigma": sigma, "N": n, "alpha": alpha, "theta0": c.theta0[0]}, output=out,
              note_id="table-5.1/tail" if key in (tail or {}) else None, note_values=(tail or {}).get(key, starts)))


def _table_5_2_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any],
                    variant: Experiment | None, variant_rep: Mapping[str, Any] | None,
                    authors: Experiment | None = None, authors_rep: Mapping[str, Any] | None = None,
                    settings: Experiment | None = None, settings_rep: Mapping[str, Any] | None = None,
                    records: Mapping[str, Mapping[str, Sequence[LearningRecord]]] | None = None) -> None:
    """Table 5.2 row by row. The two theoretical-range rows (Hoeffding and Bernstein without the
    empirical range) are judged on Lemma 4.3.3's range as printed (``variant``), then on the
    authors' settings: their formula for the range, 2 M_phi A_bar abs(A) R / (sigma^2 (1 - gamma))
    = 1280, which ``exp`` runs, and their step taken even when eps >= abs(g) (``authors``,
    ``table-5.2-authors``; without it, ``exp`` stands for the authors' settings). The other rows'
    authors' settings are ``settings`` (``figures-5.1-5.2-authors``: N_min and N_max from their run
    files, the step taken even when eps >= abs(g)). A printed interval is read as the 90% interval it is
    (:data:`T52_PRINTED_LEVEL`); under the authors' settings our runs (``records``) are averaged over their
    script's window too."""
    dec = TABLE_DECIMALS["table-5.2"]
    fmt = lambda x: num(x, dec)  # noqa: E731
    authors_t52 = authors_tables.table_5_2()
    lemma = {}
    for vc, vr in zip(variant.configs if variant else (), (variant_rep or {}).get("configs", [])):
        if method_of(vc, Adaptive).error.theoretical_range is None:
            lemma[_row_key(vc)] = (vc, vr)
    ratios, still = [], []
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        if "upsilon_bar" not in th:
            continue
        key = estimator, bound, empirical_range, delta = _row_key(c)
        mean, ci = mean_ci(r["upsilon_bar"])
        if frozen(r.get("theta_moved")):  # its ratio, whatever it is, says nothing
            still.append(c.name)
        else:
            ratios.append(r["improvement_ratio"]["mean"])
        out = outputs.table_5_2(key)
        printed_text = f"{th['upsilon_bar']:.{dec}f}"

        def welch(row: Mapping[str, Any] | None, th: Mapping[str, Any] = th, text: str = printed_text,
                  values: Sequence[float] | None = None) -> Test | None:
            values = values if values is not None else (row or {}).get("upsilon_bar", {}).get("values") or []
            return None if len(values) < 2 else WelchTest(th["upsilon_bar"], tuple(th["ci95"]), T52_PRINTED_RUNS,
                                                           tuple(values), half_unit(text), T52_PRINTED_LEVEL)

        def truncated(exp_name: str, key: tuple[str, str, bool, float] = key, name: str = c.name) -> list[float]:
            """Ours under the authors' settings averaged as their script averaged theirs: over the first T
            iterations of each run, T the shortest of their runs (plots/lqg.m)."""
            window = authors_t52.get(key, {}).get("T")
            return [portable.fsum_mean(r.J_hat[:window], weights=r.batch_size[:window])
                    for r in (records or {}).get(exp_name, {}).get(name, [])] if window else []

        test, source = welch(r), f"{exp.name}/{c.name}"
        seeds, a_col, note_id, guarded, range_runs = r["seeds"], AuthorsColumn(), None, "", None
        theoretical = bound != "chebyshev" and not empirical_range and key in lemma
        if theoretical:
            vc, vr = lemma[key]
            guarded = f"{fmt(mean)}{ci_text(ci, fmt)}"  # the authors' range, our guarded step (table-5.2)
            ar = report_row(authors_rep, c.name) if authors is not None else None
            if authors is not None:
                a_mean, a_ci = mean_ci(ar["upsilon_bar"]) if ar else (None, None)
                a_col = authors_column(authors, ar["seeds"] if ar else 0, a_mean, a_ci,
                                       f"{fmt(a_mean)}{ci_text(a_ci, fmt)}",
                                       test=welch(ar, values=truncated(authors.name)),
                                       interval=a_ci, interval_text=ci_judged(a_ci, fmt, ar["seeds"] if ar else None),
                                       sources=(f"{authors.name}/{c.name}",))
            else:
                a_col = authors_column(exp, seeds, mean, ci, guarded, test=test, interval=ci,
                                       interval_text=ci_judged(ci, fmt, seeds), sources=(f"{exp.name}/{c.name}",))
            mean, ci = mean_ci(vr["upsilon_bar"])
            seeds, test, source = vr["seeds"], welch(vr), f"{variant.name}/{vc.name}" if variant else ""
            range_runs = RangeRuns(f"with Lemma 4.3.3's range ours is {fmt(mean)}{ci_text(ci, fmt)}, with the "
                                   f"authors' settings {a_col.text or '-'} over "
                                   f"{r['iterations'] or 0:.0f} iterations, theirs over {out.iterations}")
            note_id = "table-5.2/theoretical-range"
        elif settings is not None and (sr := report_row(settings_rep, c.name)) is not None:
            s_mean, s_ci = mean_ci(sr["upsilon_bar"])
            a_col = replace(authors_column(settings, sr["seeds"], s_mean, s_ci, f"{fmt(s_mean)}{ci_text(s_ci, fmt)}",
                                           test=welch(sr, values=truncated(settings.name)), interval=s_ci,
                                           interval_text=ci_judged(s_ci, fmt, sr["seeds"]),
                                           sources=(f"{settings.name}/{c.name}",)),
                            note="Reproduced with the authors' settings: N_min and N_max from their run files' "
                                 "headers (lqg/lqg_adabatch.py@eb78917:161) and the step taken even when ε ≥ "
                                 "abs(g) (lqg/lqg_adabatch.py@eb78917:212-222), as figures-5.1-5.2-authors runs.")
        er = " (e.r.)" if empirical_range else ""
        label = f"{estimator}-{bound}{'-er' if empirical_range else ''}-delta={delta:g}"
        b.add(RowSpec(id=f"table-5.2/{label}", group="Section 5.1",
              quantity=f"average performance, {'REINFORCE' if estimator == 'reinforce' else 'G(PO)MDP'}, "
              f"{bound.capitalize()}{er}, δ = {delta:g}", where="Table 5.2",
              thesis=f"{fmt(th['upsilon_bar'])}{ci_text(th['ci95'], fmt)}", ours=f"{fmt(mean)}{ci_text(ci, fmt)}",
              difference="-" if mean is None else signed(mean - th["upsilon_bar"], dec), ok=None, rule="welch",
              test=test, relevance=value_relevance(printed_text), show=fmt, sources=(source,),
              relevance_text=relevance_text("value", value_relevance(printed_text), fmt),
              kind="mean of runs", page="lqg1d", heading="Table 5.2", note_id=note_id, thesis_value=th["upsilon_bar"],
              ours_value=mean, ours_ci95=ci, seeds=seeds,
              expected_seeds=variant.seeds if theoretical and variant is not None else exp.seeds, interval=ci,
              interval_text=ci_judged(ci, fmt, seeds),
              authors=a_col if not guarded else replace(a_col, note=(
                  "With Lemma 4.3.3's range (6400 here) the test rejects the printed mean; the authors' "
                  "settings reproduce it: their formula for the range, 2 M_φ Ā |A| R / (σ² (1 - γ)) = 1280 "
                  "(lqg/lqg_adabatch.py@af36577:50-52), and their step taken even when ε ≥ abs(g) "
                  f"(lqg/lqg_adabatch.py@af36577:247-257), which this range meets on the first batch. With "
                  f"their range and our guarded step (table-5.2): {guarded}.")),
              slip_note=slip_sentence(out, printed_text, fmt),
              fields={"estimator": estimator, "bound": bound, "empirical_range": empirical_range, "delta": delta,
                      "theoretical_range": None if theoretical else method_of(c, Adaptive).error.theoretical_range,
                      "thesis_ci95": list(th["ci95"])}, output=out, note_values=range_runs))
    # "Notice that an improvement ratio of 1 is achieved also with large values of delta."
    complete = all(r["seeds"] >= exp.seeds for r in rep["configs"])
    got = [x for x in ratios if x is not None] if complete else []
    low = min(got) if got else None
    b.add(RowSpec(id="section-5.1/improvement-ratio-adaptive", group="Section 5.1",
          quantity="improvement ratio of Algorithm 4.1, every Table 5.2 configuration whose θ moves (lowest)",
          where="Section 5.1, after Table 5.2", thesis="100%", ours=pct(low),
          difference="-" if low is None else f"{100 * (low - 1):+.2f} points",
          ok=None if low is None or len(got) < len(ratios) else within_points(low, 1.0), rule="ratio-points",
          kind="statement", page="lqg1d", heading="Table 5.2", thesis_value=1.0, ours_value=low,
          remark=f"Left out, θ frozen (moving by less than {FROZEN_THETA:g}): {', '.join(still)}." if still else ""))


def run_rows(b: Builder, exps: Mapping[str, Experiment], reps: Mapping[str, Mapping[str, Any]],
             recs: Mapping[str, Mapping[str, Sequence[LearningRecord]]], range_variant: str | None) -> None:
    """Add the rows of the Chapter 5 runs to ``b``, in the thesis's order.

    Parameters
    ----------
    b : Builder
        The rows so far.
    exps, reps, recs : mapping
        By experiment name (:data:`~safepg.thesis.scorecard.rows.NEEDED`, the range variant and
        the authors' variants that are defined): the experiment, its report, its records by
        configuration.
    range_variant : str or None
        Name of the Table 5.2 variant with Lemma 4.3.3's range, when the library defines it.
    """
    _table_5_1_rows(b, exps["table-5.1"], reps["table-5.1"], exps["table-5.1-printed-theta0"],
                    reps["table-5.1-printed-theta0"], exps.get("table-5.1-authors"), reps.get("table-5.1-authors"),
                    tail_placement(exps.get("table-5.1-authors-tail"), recs.get("table-5.1-authors-tail", {})),
                    exps.get("table-5.1-authors-tail"), reps.get("table-5.1-authors-tail"))
    _table_5_2_rows(b, exps["table-5.2"], reps["table-5.2"], exps.get(range_variant or ""),
                    reps.get(range_variant or ""), exps.get("table-5.2-authors"), reps.get("table-5.2-authors"),
                    exps.get("figures-5.1-5.2-authors"), reps.get("figures-5.1-5.2-authors"), recs)
    step_rows(b, rid="section-5.1/step-order", group="Section 5.1", where="Section 5.1 (Figures 5.1-5.4)",
              quantity="step size of Algorithm 4.1, every Table 5.2 configuration", recs=recs["table-5.2"],
              names=[c.name for c in exps["table-5.2"].configs], exponent=PRINTED["lqg1d_step_order"], page="lqg1d",
              heading="Figures 5.3 and 5.4", seeds=exps["table-5.2"].seeds, experiment="table-5.2")
    lqg2d_rows(b, exps, reps, recs)
    cartpole_rows(b, exps, reps, recs)
