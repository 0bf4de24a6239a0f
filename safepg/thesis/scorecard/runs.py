"""Rows of the stored runs of Chapter 5: Tables 5.1-5.4, Figures 5.5-5.7, the step sizes and the
cart-pole's baseline, from the experiments' reports (:func:`safepg.thesis.experiments.report`)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from safepg.learning import LearningRecord
from safepg.thesis.experiments import T51_PRINTED_THETA0, Experiment
from safepg.thesis.scorecard.builder import Builder
from safepg.thesis.scorecard.rules import (
    PRINTED,
    TABLE_DECIMALS,
    in_seed_range,
    in_widened_interval,
    intervals_overlap,
    order_of_magnitude,
    within_points,
)
from safepg.thesis.scorecard.text import ci_text, num, pct, signed


def _mean_ci(d: Mapping[str, Any]) -> tuple[float | None, list[float] | None]:
    m, ci = d.get("mean"), d.get("ci95")
    if m is None:
        return None, None
    return float(m), [float(ci[0]), float(ci[1])]


def _table_5_1_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any], variant: Experiment | None,
                    variant_rep: Mapping[str, Any] | None) -> None:
    """Table 5.1, cell by cell. ``variant``: the table from the other starting point (the printed
    theta_0 when the table runs from a reconstructed one), quoted beside each cell."""
    others = {}
    for vc, vr in zip(variant.configs if variant else (), (variant_rep or {}).get("configs", [])):
        others[(vc.sigma, vc.batch_size, vc.alpha)] = (vc, vr)
    printed_theta0 = repr(T51_PRINTED_THETA0)
    for c, r in zip(exp.configs, rep["configs"]):
        thesis = (r["thesis"] or {}).get("improvement_ratio")
        if thesis is None:
            continue
        mean, ci = _mean_ci(r["improvement_ratio"])
        ok = None if mean is None else within_points(mean, thesis)
        rid = f"table-5.1/sigma={c.sigma:g}/N={c.batch_size}/alpha={c.alpha:.0e}"
        explanation = None
        theta0 = c.theta0[0]
        vc, vr = others.get((c.sigma, c.batch_size, c.alpha), (None, None))
        v_mean = None if vr is None else vr["improvement_ratio"]["mean"]
        if ok and theta0 != float(printed_theta0):
            explanation = f"Run from θ0 = {theta0:g}, our reconstruction: the thesis prints θ0 = {printed_theta0}" + \
                (f", from which ours is {pct(v_mean)}." if v_mean is not None and vc.theta0[0] == float(printed_theta0)
                 else ".")
        b.values["t51_theta0"] = f"{theta0:g}"
        b.add(id=rid, group="Section 5.1", quantity=f"improvement ratio, σ = {c.sigma:g}, N = {c.batch_size}, "
              f"α = {c.alpha:.0e}", where="Table 5.1", thesis=pct(thesis),
              ours=pct(mean) + ci_text(ci, lambda x: pct(x, 1)),
              difference="-" if mean is None else f"{100 * (mean - thesis):+.2f} points", ok=ok,
              rule="ratio-points", page="lqg1d", heading="Table 5.1", explanation=explanation, thesis_value=thesis,
              ours_value=mean, ours_ci95=ci, seeds=r["seeds"], expected_seeds=exp.seeds,
              fields={"sigma": c.sigma, "N": c.batch_size, "alpha": c.alpha, "theta0": theta0})


def _range_label(r: Mapping[str, Any] | None, cfg: Any) -> str:
    rng = getattr(cfg, "theoretical_range", None)
    return f"the range {rng:g} (our reconstruction, not printed)" if rng is not None else "Lemma 4.3.3's range"


def _table_5_2_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any],
                    variant: Experiment | None, variant_rep: Mapping[str, Any] | None) -> None:
    dec = TABLE_DECIMALS["table-5.2"]
    fmt = lambda x: num(x, dec)  # noqa: E731
    # The variant reruns the theoretical-range rows with the other range (Lemma 4.3.3's or
    # the reconstructed one): matched to the table's rows by estimator, bound and delta.
    variants = {}
    for vc, vr in zip(variant.configs if variant else (), (variant_rep or {}).get("configs", [])):
        variants[(vc.estimator, vc.bound, vc.empirical_range, vc.delta)] = (vc, vr)
    ratios = []
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        if "upsilon_bar" not in th:
            continue
        mean, ci = _mean_ci(r["upsilon_bar"])
        ok = None if mean is None else intervals_overlap(ci, th["ci95"])
        ratios.append(r["improvement_ratio"]["mean"])
        theoretical = c.bound != "chebyshev" and not c.empirical_range
        note_id, explanation = None, None
        if theoretical:
            vc, vr = variants.get((c.estimator, c.bound, c.empirical_range, c.delta), (None, None))
            v_text, v_ok = "not computed", None
            if vr is not None and vr["upsilon_bar"]["mean"] is not None:
                vm, vci = _mean_ci(vr["upsilon_bar"])
                v_ok = intervals_overlap(vci, th["ci95"])
                v_text = f"{fmt(vm)}{ci_text(vci, fmt)}"
            if ok:
                explanation = f"Reproduced with {_range_label(r, c)}; with {_range_label(vr, vc)} " \
                              f"ours is {v_text}." if vc is not None else f"Reproduced with {_range_label(r, c)}."
            elif ok is not None and c.theoretical_range is not None:
                # The row runs with a reconstructed range: the gap is the unknown constant's.
                b.values["range_gap"] = (f"with our reconstruction {c.theoretical_range:g} ours is "
                                         f"{100 * abs(mean - th['upsilon_bar']) / abs(th['upsilon_bar']):.2f}% "
                                         f"from the printed value; with {_range_label(vr, vc)} it is {v_text}")
                note_id = "table-5.2/reconstructed-range"
            else:
                b.values["variant"] = f"{v_text} with {_range_label(vr, vc)}"
                note_id = "table-5.2/theoretical-range" if v_ok else "table-5.2/theoretical-range-unexplained"
        er = " (e.r.)" if c.empirical_range else ""
        label = f"{c.estimator}-{c.bound}{'-er' if c.empirical_range else ''}-delta={c.delta:g}"
        b.add(id=f"table-5.2/{label}", group="Section 5.1",
              quantity=f"average performance, {'REINFORCE' if c.estimator == 'reinforce' else 'G(PO)MDP'}, "
              f"{c.bound.capitalize()}{er}, δ = {c.delta:g}", where="Table 5.2",
              thesis=f"{fmt(th['upsilon_bar'])}{ci_text(th['ci95'], fmt)}", ours=f"{fmt(mean)}{ci_text(ci, fmt)}",
              difference="-" if mean is None else signed(mean - th["upsilon_bar"], dec), ok=ok, rule="ci-overlap",
              page="lqg1d", heading="Table 5.2", note_id=note_id, explanation=explanation,
              thesis_value=th["upsilon_bar"], ours_value=mean, ours_ci95=ci, seeds=r["seeds"],
              expected_seeds=exp.seeds,
              fields={"estimator": c.estimator, "bound": c.bound, "empirical_range": c.empirical_range,
                      "delta": c.delta, "theoretical_range": c.theoretical_range,
                      "thesis_ci95": list(th["ci95"])})
    # "Notice that an improvement ratio of 1 is achieved also with large values of delta."
    complete = all(r["seeds"] == exp.seeds for r in rep["configs"])
    got = [x for x in ratios if x is not None] if complete else []
    low = min(got) if got else None
    b.add(id="section-5.1/improvement-ratio-adaptive", group="Section 5.1",
          quantity="improvement ratio of Algorithm 4.1, every Table 5.2 configuration (lowest)",
          where="Section 5.1, after Table 5.2", thesis="100%", ours=pct(low),
          difference="-" if low is None else f"{100 * (low - 1):+.2f} points",
          ok=None if low is None or len(got) < len(ratios) else within_points(low, 1.0), rule="ratio-points",
          page="lqg1d", heading="Table 5.2", thesis_value=1.0, ours_value=low)


def _step_rows(b: Builder, *, rid: str, group: str, where: str, quantity: str, recs: Mapping[str, Sequence],
               names: Iterable[str], k: int, page: str, heading: str, seeds: int) -> None:
    medians, names = [], list(names)
    if any(len(recs.get(n, [])) < seeds for n in names):  # judged on the whole campaign only
        names = names + ["(missing seeds)"]
    for n in names:
        steps = np.concatenate([r.alpha[r.alpha > 0] for r in recs.get(n, [])] or [np.empty(0)])
        if steps.size:
            medians.append(float(np.median(steps)))
    if medians and len(medians) == len(names):  # "in all the experiments": every configuration run
        ours = f"median {np.median(medians):.1e}" + \
               (f" (per configuration {min(medians):.1e} to {max(medians):.1e})" if len(medians) > 1 else "")
        ok = all(order_of_magnitude(m) == k for m in medians)
        value = float(np.median(medians))
        diff = f"order 10^{order_of_magnitude(value)}"
    else:
        ours, ok, value, diff = "-", None, None, "-"
    b.add(id=rid, group=group, quantity=quantity, where=where, thesis=f"of the order of 1e{k}", ours=ours,
          difference=diff, ok=ok, rule="order", page=page, heading=heading, thesis_value=10.0**k, ours_value=value)


def _figures_5_5_5_6_rows(b: Builder, exp: Experiment, rep: Mapping[str, Any],
                          recs: Mapping[str, Sequence[LearningRecord]]) -> None:
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        label = {"scalar": "scalar step of [24]", "coordinate": "coordinate step Λ*"}.get(c.name, c.name)
        if "improvement_ratio" in th:
            mean, ci = _mean_ci(r["improvement_ratio"])
            b.add(id=f"figures-5.5-5.6/{c.name}/improvement-ratio", group="Section 5.2",
                  quantity=f"improvement ratio, {label}, N = {c.batch_size}", where="Section 5.2.1 (Figure 5.5)",
                  thesis=pct(th["improvement_ratio"]), ours=pct(mean),
                  difference="-" if mean is None else f"{100 * (mean - th['improvement_ratio']):+.2f} points",
                  ok=None if mean is None else within_points(mean, th["improvement_ratio"]), rule="ratio-points",
                  page="lqg2d", heading="Figures 5.5 and 5.6", thesis_value=th["improvement_ratio"],
                  ours_value=mean, ours_ci95=ci, seeds=r["seeds"], expected_seeds=exp.seeds)
        if "theta_final" in th:
            printed = np.asarray(th["theta_final"], dtype=float)
            finals = np.array([rec.theta_final.reshape(printed.shape) for rec in recs.get(c.name, [])])
            for (i, j), p in np.ndenumerate(printed):
                text = repr(float(p)) if p != 0 else "0"
                text = text[:-2] if text.endswith(".0") and "e" not in text else text
                seeds = finals[:, i, j] if finals.size else np.empty(0)
                mean = float(seeds.mean()) if seeds.size else None
                rid = f"section-5.2/theta-final-{c.name}/{i + 1}{j + 1}"
                b.add(id=rid, group="Section 5.2", quantity=f"final θ{i + 1}{j + 1}, {label}",
                      where="Section 5.2.1 (after Figure 5.5)", thesis=text,
                      ours="-" if mean is None else
                      f"{mean:.6g} (seeds {seeds.min():.6g} to {seeds.max():.6g})",
                      difference="-" if mean is None else f"{mean - p:+.2g}",
                      ok=None if mean is None else in_seed_range(list(seeds), text), rule="seed-range",
                      page="lqg2d", heading="Figures 5.5 and 5.6", thesis_value=float(p), ours_value=mean,
                      seeds=int(seeds.size), expected_seeds=exp.seeds,
                      fields={"step": c.name, "entry": f"{i + 1}{j + 1}"})


def _upsilon_table_rows(b: Builder, table: str, exp: Experiment, rep: Mapping[str, Any], page: str,
                        heading: str, group: str) -> None:
    dec = TABLE_DECIMALS[table]
    fmt = lambda x: num(x, dec)  # noqa: E731
    for c, r in zip(exp.configs, rep["configs"]):
        th = r["thesis"] or {}
        method = "adaptive N" if c.batch_size is None else f"N = {c.batch_size}"
        if "upsilon_bar" in th:
            text = fmt(th["upsilon_bar"])
            mean, ci = _mean_ci(r["upsilon_bar"])
            b.add(id=f"{table}/{c.name}/upsilon", group=group, quantity=f"average performance, {method}",
                  where=table.replace("table-", "Table "), thesis=text, ours=f"{fmt(mean)}{ci_text(ci, fmt)}",
                  difference="-" if mean is None else signed(mean - th["upsilon_bar"], dec),
                  ok=None if mean is None else in_widened_interval(text, ci), rule="ci-contains", page=page,
                  heading=heading, thesis_value=th["upsilon_bar"], ours_value=mean, ours_ci95=ci, seeds=r["seeds"],
                  expected_seeds=exp.seeds, fields={"method": c.name, "quantity": "upsilon_bar"})
        if "improvement_ratio" in th:
            mean, ci = _mean_ci(r["improvement_ratio"])
            b.add(id=f"{table}/{c.name}/improvement-ratio", group=group, quantity=f"improvement ratio, {method}",
                  where=table.replace("table-", "Table "), thesis=pct(th["improvement_ratio"]),
                  ours=pct(mean) + ci_text(ci, lambda x: pct(x, 1)),
                  difference="-" if mean is None else f"{100 * (mean - th['improvement_ratio']):+.2f} points",
                  ok=None if mean is None else within_points(mean, th["improvement_ratio"]), rule="ratio-points",
                  page=page, heading=heading, thesis_value=th["improvement_ratio"], ours_value=mean, ours_ci95=ci,
                  seeds=r["seeds"], expected_seeds=exp.seeds,
                  fields={"method": c.name, "quantity": "improvement_ratio"})


def _table_5_3_extra_rows(b: Builder, recs: Mapping[str, Sequence[LearningRecord]], seeds: int) -> None:
    adaptive = recs.get("adaptive", [])
    # As the chapter measures them: mean batch over iterations 2-11, and over the last 10 full ones.
    first = [float(r.batch_size[1:11].mean()) for r in adaptive if r.iterations > 11]
    last = [float(r.batch_size[-11:-1].mean()) for r in adaptive if r.iterations > 11]
    b.values.update(batch_first=float(np.mean(first)) if first else float("nan"),
                    batch_last=float(np.mean(last)) if last else float("nan"))
    for rid, q, key, vals in (("section-5.2/batch-first", "adaptive batch size, first iterations (2-11)",
                               "lqg2d_batch_first", first),
                              ("section-5.2/batch-last", "adaptive batch size, last 10 iterations",
                               "lqg2d_batch_last", last)):
        printed = PRINTED[key]
        mean = float(np.mean(vals)) if vals else None
        b.add(id=rid, group="Section 5.2", quantity=q, where="Section 5.2.1 (Figure 5.7)", thesis=f"≈ {printed}",
              ours="-" if mean is None else f"{mean:.0f} (seeds {min(vals):.0f} to {max(vals):.0f})",
              difference="-" if mean is None else f"{mean - float(printed):+.0f}",
              ok=None if mean is None else in_seed_range(vals, printed), rule="seed-range", page="lqg2d",
              heading="Table 5.3", thesis_value=float(printed), ours_value=mean, seeds=len(vals),
              expected_seeds=seeds)
    _step_rows(b, rid="section-5.2/step-order", group="Section 5.2", where="Section 5.2.1 (Figure 5.7)",
               quantity="step size of the adaptive batch-size runs", recs=recs, names=["adaptive"],
               k=PRINTED["lqg2d_step_order"], page="lqg2d", heading="Table 5.3", seeds=seeds)


def _cartpole_rows(b: Builder, base_exp: Experiment, base_recs: Mapping[str, Sequence[LearningRecord]],
                   exp54: Experiment, rep54: Mapping[str, Any], recs54: Mapping[str, Sequence[LearningRecord]]) -> None:
    for c in base_exp.configs:
        th = base_exp.thesis.get(c.name, {})
        if "iterations" not in th:
            continue
        its = [float(r.iterations) for r in base_recs.get(c.name, [])]
        text = str(th["iterations"])
        mean = float(np.mean(its)) if its else None
        b.add(id="section-5.3/baseline-iterations", group="Section 5.3",
              quantity=f"iterations of the baseline (N = {c.batch_size}, α = {c.alpha:g}) to reach "
              f"{c.target_return:g}", where="Section 5.3", thesis=text,
              ours="-" if mean is None else f"{mean:.1f} (seeds {min(its):.0f} to {max(its):.0f})",
              difference="-" if mean is None else f"{mean - th['iterations']:+.1f}",
              ok=None if mean is None else in_seed_range(its, text), rule="seed-range", page="cartpole",
              heading="baseline policy", thesis_value=float(th["iterations"]), ours_value=mean, seeds=len(its),
              expected_seeds=base_exp.seeds)
    adaptive = recs54.get("adaptive", [])
    steps = np.concatenate([r.alpha[r.alpha > 0] for r in adaptive] or [np.empty(0)])
    b.values["adaptive_steps"] = f"{steps.min():.1e} to {steps.max():.1e}" if steps.size else "none"
    names = ["x", "dx/dt", "β", "dβ/dt"]  # the state [x, x_dot, beta, beta_dot]
    never = PRINTED["cartpole_components_never_updated"]
    updated = None
    for r in rep54["configs"]:
        if r["name"] == "adaptive" and r["seeds"] == exp54.seeds:  # the whole campaign only
            updated = r["components_updated"]
    if updated is not None:
        extra = [i for i in updated if i in never]
        b.values["extra"] = ", ".join(names[i] for i in extra) or "nothing else"
        moves = [np.abs(r.theta_final - r.theta[0])[extra] for r in adaptive]
        b.values["extra_move"] = float(np.max(moves)) if extra and moves else 0.0
    b.add(id="section-5.3/components", group="Section 5.3",
          quantity="components of θ the adaptive method never updates", where="Section 5.3, after Table 5.4",
          thesis=", ".join(names[i] for i in never),
          ours="-" if updated is None else ", ".join(names[i] for i in range(4) if i not in updated) or "none",
          difference="-" if updated is None else
          ("none" if not set(updated) & set(never) else "also updates " + b.values["extra"]),
          ok=None if updated is None else not set(updated) & set(never), rule="set", page="cartpole",
          heading="Table 5.4")
    _upsilon_table_rows(b, "table-5.4", exp54, rep54, "cartpole", "Table 5.4", "Section 5.3")


def run_rows(b: Builder, exps: Mapping[str, Experiment], reps: Mapping[str, Mapping[str, Any]],
             recs: Mapping[str, Mapping[str, Sequence[LearningRecord]]], range_variant: str | None,
             theta0_variant: str | None) -> None:
    """Add the rows of the Chapter 5 runs to ``b``, in the thesis's order.

    Parameters
    ----------
    b : Builder
        The rows so far.
    exps, reps, recs : mapping
        By experiment name (:data:`~safepg.thesis.scorecard.rows.NEEDED` and the variants): the
        experiment, its report, its records by configuration.
    range_variant, theta0_variant : str or None
        Names of the Table 5.2 variant with the other theoretical range and of the Table 5.1
        variant from the other theta_0, when the library defines them.
    """
    _table_5_1_rows(b, exps["table-5.1"], reps["table-5.1"], exps.get(theta0_variant or ""),
                    reps.get(theta0_variant or ""))
    _table_5_2_rows(b, exps["table-5.2"], reps["table-5.2"], exps.get(range_variant or ""),
                    reps.get(range_variant or ""))
    _step_rows(b, rid="section-5.1/step-order", group="Section 5.1", where="Section 5.1 (Figures 5.1-5.4)",
               quantity="step size of Algorithm 4.1, every Table 5.2 configuration", recs=recs["table-5.2"],
               names=[c.name for c in exps["table-5.2"].configs], k=PRINTED["lqg1d_step_order"], page="lqg1d",
               heading="Figures 5.3 and 5.4", seeds=exps["table-5.2"].seeds)
    _figures_5_5_5_6_rows(b, exps["figures-5.5-5.6"], reps["figures-5.5-5.6"], recs["figures-5.5-5.6"])
    _upsilon_table_rows(b, "table-5.3", exps["table-5.3"], reps["table-5.3"], "lqg2d", "Table 5.3", "Section 5.2")
    _table_5_3_extra_rows(b, recs["table-5.3"], exps["table-5.3"].seeds)
    _cartpole_rows(b, exps["cartpole-baseline"], recs["cartpole-baseline"], exps["table-5.4"], reps["table-5.4"],
                   recs["table-5.4"])
