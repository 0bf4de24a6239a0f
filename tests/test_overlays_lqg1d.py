"""Section 5.1's overlays: our 1-D runs drawn over the authors' raw outputs carry the data they were given."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.learning import vanilla_pg
from safepg.options import FixedStep
from safepg.record import on_trajectories
from safepg.stats import prediction_interval95
from safepg.thesis import authors
from safepg.thesis import overlays as O
from safepg.thesis.experiments import get_experiment


@pytest.fixture(scope="module")
def short_runs():
    """Two short fixed-step runs per cell of the default overlay (5 batches each)."""
    out = {}
    for sigma, n, alpha in O.T51_OVERLAY_CELLS:
        out[f"sigma={sigma}-N={n}-alpha={alpha:.0e}"] = [
            vanilla_pg(LQG.thesis_1d(), np.array([-0.575853]), sigma, batch_size=n, step=FixedStep(alpha), budget=5 * n,
                       rng=s)
            for s in (1, 2)]
    return out


def test_seed_band_is_the_prediction_interval_column_by_column():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(5, 7))
    v[4, 6] = np.nan  # a run that ended earlier
    for runs in (1, 5):  # one run of theirs, or their five-run mean (Figures 5.1-5.2)
        mean, lo, hi = O.seed_band95(v, runs=runs)
        for j in range(7):
            ref = prediction_interval95(v[~np.isnan(v[:, j]), j], runs=runs)
            assert mean[j] == pytest.approx(ref["mean"], rel=1e-12)
            assert [lo[j], hi[j]] == pytest.approx(ref["pi95"], rel=1e-12)
    m1, lo1, hi1 = O.seed_band95(v[:1])
    assert np.array_equal(m1, v[0]) and np.all(np.isnan(lo1)) and np.all(np.isnan(hi1))  # one seed: no band


@pytest.mark.parametrize("quantity", ["J", "theta"])
def test_table51_overlay_draws_our_runs_and_the_authors_run(short_runs, quantity):
    fig = O.figure_table51_overlay(short_runs, quantity=quantity)
    try:
        axes = [ax for ax in fig.axes if ax.get_visible()]
        assert len(axes) == len(O.T51_OVERLAY_CELLS)
        for ax, (sigma, n, alpha) in zip(axes, O.T51_OVERLAY_CELLS):
            recs = short_runs[f"sigma={sigma}-N={n}-alpha={alpha:.0e}"]
            run = authors.table51_runs()[(sigma, n, alpha)]
            theirs_line, ours_line = (ln for ln in ax.get_lines() if ln.get_label() in ("authors' run", "ours"))
            # Ours: the seed mean of J (or theta) at each batch start, trajectory k N.
            per_seed = np.array([r.J if quantity == "J" else r.theta[:, 0] for r in recs])
            assert np.array_equal(ours_line.get_xdata(), n * np.arange(6))
            assert np.allclose(ours_line.get_ydata(), per_seed.mean(axis=0), rtol=0, atol=1e-13)
            # The band is the prediction interval for one run (theirs is one run) at each point.
            band = ax.collections[0].get_paths()[0].vertices[:, 1]
            for k in range(per_seed.shape[1]):
                for end in prediction_interval95(per_seed[:, k])["pi95"]:
                    assert np.min(np.abs(band - end)) < 1e-12
            # Theirs: every row of their file, theta as written, J at standard deviation sigma.
            assert np.array_equal(theirs_line.get_xdata(), n * np.arange(run.iterations))
            if quantity == "theta":
                assert np.array_equal(theirs_line.get_ydata(), run["theta"])
            elif sigma == 1.0:  # their J column reads sigma as the variance: the same thing at sigma = 1
                assert np.allclose(theirs_line.get_ydata(), run["J"], rtol=0, atol=1e-8)
            else:
                assert not np.allclose(theirs_line.get_ydata(), run["J"], rtol=0, atol=1e-3)
                assert theirs_line.get_ydata()[0] == pytest.approx(
                    LQG.thesis_1d().performance(run["theta"][0], sigma), abs=1e-12)
    finally:
        plt.close(fig)


def test_table51_overlay_refuses_missing_runs(short_runs):
    with pytest.raises(KeyError):
        O.figure_table51_overlay(short_runs, cells=[(1.0, 100, 1e-6)])


@pytest.mark.parametrize("figure", ["5.1", "5.2"])
def test_figures_5_1_5_2_overlay_carry_ours_and_the_authors_curves(figure):
    exp = get_experiment("table-5.2")
    if figure == "5.1":
        configs = [c for c in exp.configs if (c.method.error.bound, c.method.error.delta) in (
            ("chebyshev", 0.95), ("chebyshev", 0.5))]
    else:
        configs = [c for c in exp.configs
                   if c.method.gradient.estimator == "gpomdp" and c.method.error.delta == 0.95][:2]
    # Short stand-in runs under the configs' names: only their J over trajectories is drawn.
    records = {c.name: [vanilla_pg(LQG.thesis_1d(), np.array([-0.2 - 0.1 * i]), 1.0, batch_size=1000,
                                   step=FixedStep(1e-4), budget=8000, rng=i) for i in range(3)] for c in configs}
    draw = O.figure_5_1_overlay if figure == "5.1" else O.figure_5_2_overlay
    fig = draw(records, configs)
    try:
        lines = [ln for ax in fig.axes for ln in ax.get_lines()]
        colours = [ln for ln in lines if ln.get_color() != "black"]
        theirs = [ln for ln in lines if ln.get_color() == "black"]
        assert len(colours) == len(theirs) == len(configs)
        by_estimator = sorted(configs, key=lambda c: c.method.gradient.estimator != "gpomdp")
        for c, ours_line, their_line in zip(by_estimator, colours, theirs):
            e = c.method.error
            curve = authors.figure51_52_curves()[(c.method.gradient.estimator, e.bound, e.empirical_range, e.delta)]
            assert np.array_equal(their_line.get_ydata(), curve["J"])
            grid = curve["trajectories"].astype(np.int64)
            assert np.array_equal(ours_line.get_xdata(), grid)
            expected = np.nanmean(on_trajectories(records[c.name], grid[:8]), axis=0)
            assert np.allclose(ours_line.get_ydata()[:8], expected, rtol=0, atol=1e-13)
            assert np.all(np.isnan(ours_line.get_ydata()[8:]))  # past our short runs' end
    finally:
        plt.close(fig)
