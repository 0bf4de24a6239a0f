"""Rows of the stored runs of Chapter 5: Tables 5.1-5.4, Figures 5.5-5.7, the step sizes and the
cart-pole's baseline, from the experiments' reports (:func:`safepg.thesis.report.report`).

Each row holds ours (the thesis's text), ours under the authors' settings where a variant runs
them (the ``*-authors`` experiments; for Table 5.2's theoretical range, the authors' formula) and
the authors' own output (:mod:`safepg.thesis.scorecard.outputs`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import replace
from typing import Any, NamedTuple

import numpy as np

from safepg import portable
from safepg.learning import LearningRecord
from safepg.options import Adaptive, FixedStep, Vanilla
from safepg.runner import RunConfig
from safepg.significance import Test, WelchTest
from safepg.stats import prediction_interval95
from safepg.thesis import authors as authors_tables
from safepg.thesis.experiments import AUTHORS_T51_THETA0, T51_PRINTED_THETA0, Experiment, method_of
from safepg.thesis.scorecard import outputs
from safepg.thesis.scorecard.builder import AuthorsColumn, Builder, RowSpec
from safepg.thesis.scorecard.judged import (
    ci_judged,
    frozen,
    never_moved_test,
    order_test,
    pi_text,
    prediction,
    ratio_interval,
    ratio_test,
    ratio_text,
    slip_sentence,
    tail_placement,
    value_relevance,
    value_test,
)
from safepg.thesis.scorecard.rules import (
    FROZEN_THETA,
    PRINTED,
    TABLE_DECIMALS,
    AuthorsBaseline,
    BatchSizes,
    CertifiedSteps,
    FinalTheta,
    MovedComponents,
    RangeRuns,
    TailRuns,
    Theta0s,
    half_unit,
    in_prediction,
    order_of_magnitude,
    within_points,
)
from safepg.thesis.scorecard.text import ci_text, num, pct, signed
from safepg.thesis.scorecard.verdicts import RELEVANT_SHARE, relevance_text


def _points(v: float) -> str:
    """A difference of two ratios, in percentage points."""
    return f"{100 * v:.2g} points"


#: Table 5.2's means are over this many runs of the authors ("All results are averaged over 5 runs").
T52_PRINTED_RUNS = 5
#: The level of Table 5.2's printed intervals as the authors computed them: their plot script's
#: ``tinv([0.05, 0.95], n - 1)``, a 90% interval the thesis prints as 95%
#: (:func:`safepg.thesis.authors.truncated_average`); it gives their runs' spread.
T52_PRINTED_LEVEL = 0.90
#: The relevance of an improvement ratio, and its words.
RATIO_RELEVANCE = RELEVANT_SHARE
RATIO_RELEVANCE_TEXT = relevance_text("ratio", RATIO_RELEVANCE, _points)


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


def _mean_ci(d: Mapping[str, Any]) -> tuple[float | None, list[float] | None]:
    m = d.get("mean")
    if m is None:
        return None, None
    ci = d["ci95"]  # a summary with a mean has its interval (safepg.stats.mean_ci95)
    return float(m), [float(ci[0]), float(ci[1])]


def _authors(exp: Experiment | None, seeds: int, mean: float | None, ci: list[float] | None, text: str,
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


def _said(column: AuthorsColumn) -> str:
    """Ours under the authors' settings as a note quotes it."""
    return "(not stored yet)" if not column.experiment or column.text == "-" else column.text


def _report_row(rep: Mapping[str, Any] | None, name: str) -> Mapping[str, Any] | None:
    for r in (rep or {}).get("configs", []):
        if r["name"] == name:
            return r
    return None


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
        mean, ci = _mean_ci(r["improvement_ratio"])
        a_exp, ar = theirs.get(key, (authors, None))
        a_mean, a_ci = _mean_ci(ar["improvement_ratio"]) if ar else (None, None)
        a_col = _authors(a_exp, ar["seeds"] if ar else 0, a_mean, a_ci,
                         pct(a_mean) + ci_text(prediction(ar and ar["improvement_ratio"], True), lambda x: pct(x, 1)),
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
              test=ratio_test(thesis, r), relevance=RATIO_RELEVANCE, relevance_text=RATIO_RELEVANCE_TEXT, show=_points,
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
        mean, ci = _mean_ci(r["upsilon_bar"])
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
            ar = _report_row(authors_rep, c.name) if authors is not None else None
            if authors is not None:
                a_mean, a_ci = _mean_ci(ar["upsilon_bar"]) if ar else (None, None)
                a_col = _authors(authors, ar["seeds"] if ar else 0, a_mean, a_ci,
                                 f"{fmt(a_mean)}{ci_text(a_ci, fmt)}", test=welch(ar, values=truncated(authors.name)),
                                 interval=a_ci, interval_text=ci_judged(a_ci, fmt, ar["seeds"] if ar else None),
                                 sources=(f"{authors.name}/{c.name}",))
            else:
                a_col = _authors(exp, seeds, mean, ci, guarded, test=test, interval=ci,
                                 interval_text=ci_judged(ci, fmt, seeds), sources=(f"{exp.name}/{c.name}",))
            mean, ci = _mean_ci(vr["upsilon_bar"])
            seeds, test, source = vr["seeds"], welch(vr), f"{variant.name}/{vc.name}" if variant else ""
            range_runs = RangeRuns(f"with Lemma 4.3.3's range ours is {fmt(mean)}{ci_text(ci, fmt)}, with the "
                                   f"authors' settings {a_col.text or '-'} over "
                                   f"{r['iterations'] or 0:.0f} iterations, theirs over {out.iterations}")
            note_id = "table-5.2/theoretical-range"
        elif settings is not None and (sr := _report_row(settings_rep, c.name)) is not None:
            s_mean, s_ci = _mean_ci(sr["upsilon_bar"])
            a_col = replace(_authors(settings, sr["seeds"], s_mean, s_ci, f"{fmt(s_mean)}{ci_text(s_ci, fmt)}",
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


def _step_rows(b: Builder, *, rid: str, group: str, where: str, quantity: str, recs: Mapping[str, Sequence],
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
        a_col = _authors(authors, n_seeds, float(np.median(a_med)) if a_med else None, None,
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


def _figures_5_5_5_6_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any],
                          recs: Mapping[str, Sequence[LearningRecord]]) -> None:
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        label = {"scalar": "scalar step of Pirotta et al. (2013)", "coordinate": "coordinate step Λ*"}[c.name]
        if "improvement_ratio" in th:
            mean, ci = _mean_ci(r["improvement_ratio"])
            out = outputs.lqg2d(c.name, "improvement_ratio")
            b.add(RowSpec(id=f"figures-5.5-5.6/{c.name}/improvement-ratio", group="Section 5.2", output=out,
                  quantity=f"improvement ratio, {label}, N = {method_of(c, Vanilla).batch_size}",
                  where="Section 5.2.1 (Figure 5.5)", thesis=pct(th["improvement_ratio"]),
                  ours=pct(mean) + ci_text(prediction(r["improvement_ratio"], True), lambda x: pct(x, 1)),
                  difference="-" if mean is None else f"{100 * (mean - th['improvement_ratio']):+.2f} points",
                  ok=None, test=ratio_test(th["improvement_ratio"], r), relevance=RATIO_RELEVANCE,
                  relevance_text=RATIO_RELEVANCE_TEXT, show=_points, sources=(f"{exp.name}/{c.name}",),
                  rule="prediction", kind="one run", page="lqg2d", heading="Figures 5.5 and 5.6",
                  thesis_value=th["improvement_ratio"], ours_value=mean, ours_ci95=ci, seeds=r["seeds"],
                  expected_seeds=exp.seeds, interval=ratio_interval(r), interval_text=ratio_text(r),
                  vacuous=frozen(r.get("theta_moved"))))
        if "theta_final" in th:
            printed = np.asarray(th["theta_final"], dtype=float)
            finals = np.array([rec.theta_final.reshape(printed.shape) for rec in recs.get(c.name, [])])
            # The matrix's scale: its off-diagonal entries near 0 are judged on it.
            scale = RELEVANT_SHARE * float(np.max(np.abs(printed)))
            for (i, j), p in np.ndenumerate(printed):
                text = repr(float(p)) if p != 0 else "0"
                text = text[:-2] if text.endswith(".0") and "e" not in text else text
                seeds = finals[:, i, j] if finals.size else np.empty(0)
                mean = float(seeds.mean()) if seeds.size else None
                pi = prediction_interval95(seeds)["pi95"] if seeds.size > 1 else None
                rid = f"section-5.2/theta-final-{c.name}/{i + 1}{j + 1}"
                out = outputs.lqg2d(c.name, "theta_final", (i, j))
                # Without a seed the row is not judged, and its note, which quotes them, not filled.
                final = FinalTheta(out.text, f"{seeds.min():.6g} to {seeds.max():.6g}") if seeds.size else None
                b.add(RowSpec(id=rid, group="Section 5.2", quantity=f"final θ{i + 1}{j + 1}, {label}", output=out,
                      slip_note=slip_sentence(out, text, lambda v: f"{v:.6g}"),
                      where="Section 5.2.1 (after Figure 5.5)", thesis=text,
                      ours="-" if mean is None else
                      f"{mean:.6g} (seeds {seeds.min():.6g} to {seeds.max():.6g})",
                      difference="-" if mean is None else f"{mean - p:+.2g}", ok=None,
                      test=value_test(text, list(seeds)), relevance=0.0 if p == 0 else scale,
                      relevance_text=relevance_text("exact" if p == 0 else "scale", scale, lambda v: f"{v:.2g}")
                      .replace("the authors' values", "the printed matrix's entries"),
                      show=lambda v: f"{v:.2g}", rule="prediction", sources=(f"{exp.name}/{c.name}",),
                      kind="one run", page="lqg2d", heading="Figures 5.5 and 5.6", thesis_value=float(p),
                      ours_value=mean, seeds=int(seeds.size), expected_seeds=exp.seeds, interval=pi,
                      interval_text="every seed exactly 0" if p == 0 else pi_text(pi, lambda v: f"{v:.6g}",
                                                                                   int(seeds.size)),
                      fields={"step": c.name, "entry": f"{i + 1}{j + 1}"}, note_values=final))


def _upsilon_table_rows(b: Builder, table: str, exp: Experiment, rep: Mapping[str, Any], page: str,
                        heading: str, group: str, authors: Experiment | None = None,
                        authors_rep: Mapping[str, Any] | None = None,
                        output: Callable[[str, str], outputs.Output] | None = None, authors_note: str = "",
                        also: tuple[Experiment, Mapping[str, Any]] | None = None,
                        note_values: NamedTuple | None = None) -> None:
    """Average performance and improvement ratio of each method of Table 5.3 or 5.4: ours, ours under
    the authors' settings (``authors``, matched by config name) and ``output(config, quantity)``;
    ``also``: another run of the authors' settings, quoted in the row's explanation; ``note_values``:
    the values the table's note quotes."""
    dec = TABLE_DECIMALS[table]
    fmt = lambda x: num(x, dec)  # noqa: E731
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        method = f"N = {c.method.batch_size}" if isinstance(c.method, Vanilla) else "adaptive N"
        ar = _report_row(authors_rep, c.name)
        other = _report_row(also[1], c.name) if also else None
        if "upsilon_bar" in th:
            text = fmt(th["upsilon_bar"])
            mean, ci = _mean_ci(r["upsilon_bar"])
            pi, a_pi = prediction(r["upsilon_bar"]), prediction(ar and ar["upsilon_bar"])
            a_mean, a_ci = _mean_ci(ar["upsilon_bar"]) if ar else (None, None)
            a_col = _authors(authors, ar["seeds"] if ar else 0, a_mean, a_ci, f"{fmt(a_mean)}{ci_text(a_pi, fmt)}",
                             test=value_test(text, ar["upsilon_bar"].get("values") if ar else None), interval=a_pi,
                             interval_text=pi_text(a_pi, fmt, ar["seeds"] if ar else None),
                             sources=(f"{authors.name}/{c.name}",) if authors is not None and ar else ())
            out = output(c.name, "upsilon_bar") if output else None
            b.add(RowSpec(id=f"{table}/{c.name}/upsilon", group=group, quantity=f"average performance, {method}",
                  where=table.replace("table-", "Table "), thesis=text, ours=f"{fmt(mean)}{ci_text(pi, fmt)}",
                  difference="-" if mean is None else signed(mean - th["upsilon_bar"], dec), ok=None,
                  test=value_test(text, r["upsilon_bar"].get("values")), relevance=value_relevance(text),
                  relevance_text=relevance_text("value", value_relevance(text), fmt), show=fmt,
                  sources=(f"{table}/{c.name}",),
                  rule="prediction", kind="one run",
                  page=page, heading=heading, thesis_value=th["upsilon_bar"], ours_value=mean, ours_ci95=ci,
                  seeds=r["seeds"], expected_seeds=exp.seeds, fields={"method": c.name, "quantity": "upsilon_bar"},
                  interval=pi, interval_text=pi_text(pi, fmt, r["seeds"]),
                  authors=replace(a_col, note=authors_note),
                  slip_note="" if out is None else slip_sentence(out, text, fmt),
                  remark=_missing(out) or _also(also, other, "upsilon_bar", fmt, text),
                  output=out, note_values=note_values))
        if "improvement_ratio" in th:
            mean, ci = _mean_ci(r["improvement_ratio"])
            thesis = th["improvement_ratio"]
            a_mean, a_ci = _mean_ci(ar["improvement_ratio"]) if ar else (None, None)
            a_col = _authors(authors, ar["seeds"] if ar else 0, a_mean, a_ci,
                             pct(a_mean) + ci_text(prediction(ar and ar["improvement_ratio"], True),
                                                   lambda x: pct(x, 1)),
                             test=ratio_test(thesis, ar), interval=ratio_interval(ar), interval_text=ratio_text(ar),
                             vacuous=frozen(ar.get("theta_moved") if ar else None),
                             sources=(f"{authors.name}/{c.name}",) if authors is not None and ar else ())
            out = output(c.name, "improvement_ratio") if output else None
            b.add(RowSpec(id=f"{table}/{c.name}/improvement-ratio", group=group,
                  quantity=f"improvement ratio, {method}",
                  where=table.replace("table-", "Table "), thesis=pct(thesis),
                  ours=pct(mean) + ci_text(prediction(r["improvement_ratio"], True), lambda x: pct(x, 1)),
                  difference="-" if mean is None else f"{100 * (mean - thesis):+.2f} points", ok=None,
                  test=ratio_test(thesis, r), relevance=RATIO_RELEVANCE, relevance_text=RATIO_RELEVANCE_TEXT,
                  show=_points, rule="prediction", sources=(f"{table}/{c.name}",),
                  kind="one run", page=page, heading=heading, thesis_value=thesis, ours_value=mean, ours_ci95=ci,
                  seeds=r["seeds"], expected_seeds=exp.seeds, interval=ratio_interval(r), interval_text=ratio_text(r),
                  vacuous=frozen(r.get("theta_moved")),
                  fields={"method": c.name, "quantity": "improvement_ratio"},
                  authors=replace(a_col, note=authors_note),
                  slip_note="" if out is None else slip_sentence(out, f"{100 * thesis:.6g}", lambda v: f"{v:.4g}%",
                                                                 100),
                  remark=_missing(out) or _also(also, other, "improvement_ratio", pct, f"{100 * thesis:.6g}", 100),
                  output=out, note_values=note_values))


def _also(also: tuple[Experiment, Mapping[str, Any]] | None, row: Mapping[str, Any] | None, key: str,
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


def _missing(out: outputs.Output | None) -> str:
    if out is None or out.value is not None:
        return ""
    return (f"The authors' output for this run is not in their repository ({out.source} is absent), so the "
            "printed value cannot be checked against it.")


def _t53_output(name: str, quantity: str) -> outputs.Output:
    return outputs.lqg2d_missing() if name == "N=100" else outputs.lqg2d(name, quantity)


def _t54_output(name: str, quantity: str) -> outputs.Output:
    return outputs.cartpole("adaptive" if name == "adaptive" else "fixed", quantity)


def _batch_means(recs: Sequence[LearningRecord]) -> tuple[list[float], list[float]]:
    """Mean batch over iterations 2-11 and over the last 10 full ones, per run (as the chapter measures them)."""
    first = [float(r.batch_size[1:11].mean()) for r in recs if r.iterations > 11]
    last = [float(r.batch_size[-11:-1].mean()) for r in recs if r.iterations > 11]
    return first, last


def _table_5_3_extra_rows(b: Builder, recs: Mapping[str, Sequence[LearningRecord]], seeds: int,
                          authors: Experiment | None, authors_recs: Mapping[str, Sequence[LearningRecord]]) -> None:
    first, last = _batch_means(recs.get("adaptive", []))
    a_first, a_last = _batch_means(authors_recs.get("adaptive", []))
    note = ("Reproduced with the authors' adaptive run: Bernstein on the largest variance and range over the "
            "components and N_max = 100000 (lqgnd/lqgnd_adabatch.py@92ac378:256-257), the step taken even when "
            "ε ≥ abs(g_k).")
    for rid, q, key, vals, a_vals in (("section-5.2/batch-first", "adaptive batch size, first iterations (2-11)",
                                       "lqg2d_batch_first", first, a_first),
                                      ("section-5.2/batch-last", "adaptive batch size, last 10 iterations",
                                       "lqg2d_batch_last", last, a_last)):
        printed = PRINTED[key]
        mean = float(np.mean(vals)) if vals else None
        out = outputs.lqg2d("adaptive", key.replace("lqg2d_", ""))
        a_mean = float(np.mean(a_vals)) if a_vals else None
        pi, a_pi = prediction_interval95(vals)["pi95"], prediction_interval95(a_vals)["pi95"]
        reading = f"the print read to ± {half_unit(printed):g}"
        precision = half_unit(printed)
        a_col = _authors(authors, len(a_vals), a_mean, None,
                         "-" if a_mean is None else f"{a_mean:.0f} (seeds {min(a_vals):.0f} to {max(a_vals):.0f})",
                         test=value_test(printed, a_vals, precision), interval=a_pi,
                         interval_text=pi_text(a_pi, lambda v: f"{v:.0f}", len(a_vals), reading),
                         sources=(f"{authors.name}/adaptive",) if authors is not None else ())
        relevance = value_relevance(printed, precision)
        sizes = None if mean is None else BatchSizes(mean, out.text, _said(a_col))
        b.add(RowSpec(id=rid, group="Section 5.2", quantity=q, where="Section 5.2.1 (Figure 5.7)",
              thesis=f"≈ {printed}",
              ours="-" if mean is None else f"{mean:.0f} (seeds {min(vals):.0f} to {max(vals):.0f})",
              difference="-" if mean is None else f"{mean - float(printed):+.0f}",
              ok=None, test=value_test(printed, vals, precision), relevance=relevance, sources=("table-5.3/adaptive",),
              relevance_text=relevance_text("reading" if relevance == precision else "value", relevance,
                                            lambda v: f"{v:.0f}"), show=lambda v: f"{v:.0f}",
              rule="reading", kind="read off a figure",
              page="lqg2d", heading="Table 5.3", thesis_value=float(printed), ours_value=mean, seeds=len(vals),
              interval=pi, interval_text=pi_text(pi, lambda v: f"{v:.0f}", len(vals), reading),
              expected_seeds=seeds, authors=replace(a_col, note=note),
              slip_note=slip_sentence(out, printed, lambda v: f"≈ {v:.0f}"), output=out, note_values=sizes))
    _step_rows(b, rid="section-5.2/step-order", group="Section 5.2", where="Section 5.2.1 (Figure 5.7)",
               quantity="step size of the adaptive batch-size runs", recs=recs, names=["adaptive"],
               exponent=PRINTED["lqg2d_step_order"], page="lqg2d", heading="Table 5.3", seeds=seeds,
               experiment="table-5.3", authors=authors,
               authors_recs=authors_recs, output=outputs.lqg2d("adaptive", "step"), authors_note=note)


#: Table 5.4 under the authors' settings: the variant judged, their whole protocol (each seed runs
#: their baseline search, then adapts; the printed values are one run of it, so our interval must
#: hold the spread of the starting policies too), and the one from their own baseline policy
#: (theta_star.npy: one start for every seed), quoted beside it.
T54_AUTHORS, T54_AUTHORS_THETA_STAR = "table-5.4-authors", "table-5.4-authors-theta-star"
_STATE = ("x", "dx/dt", "β", "dβ/dt")  # the cart-pole's state [x, x_dot, beta, beta_dot]


def _moves(recs: Sequence[LearningRecord], components: Sequence[int]) -> list[list[float]]:
    """Per component, each run's largest move of it from where it started, max_t |theta_t - theta_0|."""
    return [[float(np.max(np.abs(r.theta[:, c] - r.theta[0, c]))) for r in recs] for c in components]


def _cartpole_rows(b: Builder, exps: Mapping[str, Experiment], reps: Mapping[str, Mapping[str, Any]],
                   recs: Mapping[str, Mapping[str, Sequence[LearningRecord]]]) -> None:
    base_exp, base_recs = exps["cartpole-baseline"], recs["cartpole-baseline"]
    exp54, rep54, recs54 = exps["table-5.4"], reps["table-5.4"], recs["table-5.4"]
    a_base = exps.get("cartpole-baseline-authors")
    for c in base_exp.configs:
        th = base_exp.thesis.get(c.name, {})
        if "iterations" not in th:
            continue
        its = [float(r.iterations) for r in base_recs.get(c.name, [])]
        a_its = [float(r.iterations) for r in recs.get("cartpole-baseline-authors", {}).get(c.name, [])]
        text = str(th["iterations"])
        mean = float(np.mean(its)) if its else None
        a_mean = float(np.mean(a_its)) if a_its else None
        pi, a_pi = prediction_interval95(its)["pi95"], prediction_interval95(a_its)["pi95"]
        a_col = _authors(a_base, len(a_its), a_mean, None,
                         "-" if a_mean is None else f"{a_mean:.1f} (seeds {min(a_its):.0f} to {max(a_its):.0f})",
                         test=value_test(text, a_its), interval=a_pi,
                         interval_text=pi_text(a_pi, lambda v: f"{v:.1f}", len(a_its)),
                         sources=(f"{a_base.name}/{c.name}",) if a_base is not None else ())
        search = c.method
        assert isinstance(search, Vanilla) and isinstance(search.step, FixedStep) and search.target is not None
        b.add(RowSpec(id="section-5.3/baseline-iterations", group="Section 5.3",
              quantity=f"iterations of the baseline (N = {search.batch_size}, α = {search.step.alpha:g}) to reach "
              f"{search.target.value:g}", where="Section 5.3", thesis=text,
              ours="-" if mean is None else f"{mean:.1f} (seeds {min(its):.0f} to {max(its):.0f})",
              difference="-" if mean is None else f"{mean - th['iterations']:+.1f}",
              ok=None, test=value_test(text, its), relevance=value_relevance(text),
              relevance_text=relevance_text("value", value_relevance(text), lambda v: f"{v:.2g}"),
              show=lambda v: f"{v:.2g}", rule="prediction", kind="one run", sources=(f"{base_exp.name}/{c.name}",),
              page="cartpole", heading="baseline policy", thesis_value=float(th["iterations"]), ours_value=mean,
              seeds=len(its), interval=pi, interval_text=pi_text(pi, lambda v: f"{v:.1f}", len(its)),
              expected_seeds=base_exp.seeds, output=outputs.cartpole("baseline", "iterations"),
              authors=replace(a_col, note="Reproduced on the authors' task: gym's 12° termination "
                              "(cartpole/cartpole.py@b9588b7:42; the thesis prints 41.8°), the undiscounted return "
                              "(cartpole/polgrad.py@aadbf5b:178), and the update of the batch that reaches 195 kept."),
              note_values=AuthorsBaseline(_said(a_col))))
    adaptive = recs54.get("adaptive", [])
    steps = np.concatenate([r.alpha[r.alpha > 0] for r in adaptive] or [np.empty(0)])
    certified = CertifiedSteps(f"{steps.min():.1e} to {steps.max():.1e}" if steps.size else "none")
    never = PRINTED["cartpole_components_never_updated"]
    updated = None
    for r in rep54["configs"]:
        if r["name"] == "adaptive" and r["seeds"] >= exp54.seeds:  # the whole campaign only
            updated = r["components_updated"]
    extra_text, extra_move = "", 0.0
    if updated is not None:
        extra = [i for i in updated if i in never]
        extra_text = ", ".join(_STATE[i] for i in extra) or "nothing else"
        moves = [np.abs(r.theta_final - r.theta[0])[extra] for r in adaptive]
        extra_move = float(np.max(moves)) if extra and moves else 0.0
    a54 = exps.get(T54_AUTHORS)
    a_row = _report_row(reps.get(T54_AUTHORS), "adaptive")
    a_updated = a_row["components_updated"] if a_row and a_row["seeds"] else None
    a_col = _authors(a54, a_row["seeds"] if a_row else 0, None if a_updated is None else 0.0, None,
                     "-" if a_updated is None else ", ".join(_STATE[i] for i in range(4) if i not in a_updated),
                     test=never_moved_test(_moves(recs.get(T54_AUTHORS, {}).get("adaptive", []), never)),
                     sources=(f"{T54_AUTHORS}/adaptive",))
    theirs = outputs.cartpole_components_updated()
    # Without the whole campaign the row is not judged, and its note, which quotes what ours moves, not filled.
    moved = None if updated is None else MovedComponents(extra_text, extra_move, _said(a_col))
    b.add(RowSpec(id="section-5.3/components", group="Section 5.3",
          quantity="components of θ the adaptive method never updates", where="Section 5.3, after Table 5.4",
          thesis=", ".join(_STATE[i] for i in never),
          ours="-" if updated is None else ", ".join(_STATE[i] for i in range(4) if i not in updated) or "none",
          difference="-" if updated is None else
          ("none" if not set(updated) & set(never) else "also updates " + extra_text),
          ok=None, test=never_moved_test(_moves(adaptive, never)) if updated is not None else None, relevance=0.0,
          relevance_text=relevance_text("exact", 0.0), show=lambda v: f"{v:.1e}", rule="set", kind="one run",
          sources=("table-5.4/adaptive",),
          page="cartpole", heading="Table 5.4",
          vacuous=frozen((_report_row(rep54, "adaptive") or {}).get("theta_moved")),
          # A set has no value: the 0.0 given to _authors only marks the column as measured.
          authors=replace(a_col, value=None, note="Reproduced with the authors' adaptive run (their doubled pole at "
                          "12°, undiscounted, γ = 0.9 and R, M_φ measured per batch in c, the maxima over components, "
                          "unguarded steps): only x and dx/dt move, as in their own run."),
          output=outputs.Output(value=None, text=", ".join(_STATE[i] for i in range(4) if i not in theirs),
                                source=outputs.cartpole("adaptive", "upsilon_bar").source),
          note_values=moved))
    _upsilon_table_rows(b, "table-5.4", exp54, rep54, "cartpole", "Table 5.4", "Section 5.3", a54,
                        reps.get(T54_AUTHORS), _t54_output,
                        authors_note="Reproduced on the authors' task and methods, from our runs of their "
                                     "baseline search: 12° termination, their doubled pole (m l kept at 0.05), "
                                     "undiscounted return, γ = 0.9 and per-batch R, M_φ in c, first N = 1000, the "
                                     "maxima over components, unguarded steps; their 'vanilla' moves only the "
                                     "largest component; both averaged over 1151669 trajectories as "
                                     "plot_cartpole.m@54d92b0 does.",
                        also=(exps[T54_AUTHORS_THETA_STAR], reps[T54_AUTHORS_THETA_STAR])
                        if T54_AUTHORS_THETA_STAR in exps else None, note_values=certified)


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
    _step_rows(b, rid="section-5.1/step-order", group="Section 5.1", where="Section 5.1 (Figures 5.1-5.4)",
               quantity="step size of Algorithm 4.1, every Table 5.2 configuration", recs=recs["table-5.2"],
               names=[c.name for c in exps["table-5.2"].configs], exponent=PRINTED["lqg1d_step_order"], page="lqg1d",
               heading="Figures 5.3 and 5.4", seeds=exps["table-5.2"].seeds, experiment="table-5.2")
    _figures_5_5_5_6_rows(b, exps["figures-5.5-5.6"], reps["figures-5.5-5.6"], recs["figures-5.5-5.6"])
    _upsilon_table_rows(b, "table-5.3", exps["table-5.3"], reps["table-5.3"], "lqg2d", "Table 5.3", "Section 5.2",
                        exps.get("table-5.3-authors"), reps.get("table-5.3-authors"), _t53_output,
                        authors_note="Reproduced with the authors' adaptive run: Bernstein on the largest variance "
                                     "and range over the components, N_max = 100000 (lqgnd/lqgnd_adabatch.py@92ac378:"
                                     "256-257), the step taken even when ε ≥ abs(g_k), the ratio counting strict "
                                     "increases.")
    _table_5_3_extra_rows(b, recs["table-5.3"], exps["table-5.3"].seeds, exps.get("table-5.3-authors"),
                          recs.get("table-5.3-authors", {}))
    _cartpole_rows(b, exps, reps, recs)
