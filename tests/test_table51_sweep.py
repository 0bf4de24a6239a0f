"""The Table 5.1 sweep: its estimator kernel, runs, counting rules and the J-formula invariance."""

import json

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.estimators import trajectory_scores
from safepg.policies import LinearGaussianPolicy
from safepg.thesis import table51_sweep as ts
from safepg.thesis.experiments import T51_PRINTED

ENV = LQG.thesis_1d()


@pytest.mark.parametrize("baseline,flag", [("optimal", True), ("none", False)])
@pytest.mark.parametrize("score", ["clipped", "raw"])
@pytest.mark.parametrize("theta,std", [(-0.55, 1.0), (-0.7, 0.5)])
def test_batch_gradient_is_the_library_estimator(baseline, flag, score, theta, std):
    g, ret = ts.batch_gradient(ENV, theta, std, 3000, np.random.default_rng(5), baseline, score)
    samples, returns = ENV.gradient_batch(LinearGaussianPolicy([[theta]], std), 3000, np.random.default_rng(5),
                                          "gpomdp", flag, score)
    assert g == pytest.approx(samples.mean(), rel=1e-10, abs=1e-12)
    assert ret == pytest.approx(returns.mean(), rel=1e-12)


@pytest.mark.parametrize("score", ["clipped", "raw"])
def test_average_baseline_against_numpy(score):
    pol = LinearGaussianPolicy([[-0.6]], 1.0)
    batch = ENV.simulate(pol, 2000, np.random.default_rng(9))
    cum = np.cumsum(trajectory_scores(pol, batch, score), axis=1)[:, :, 0]
    disc = batch.rewards * ENV.gamma ** np.arange(ENV.horizon)
    expected = (cum * (disc - disc.mean(axis=0))).sum(axis=1).mean()
    g, _ = ts.batch_gradient(ENV, -0.6, 1.0, 2000, np.random.default_rng(9), "average", score)
    assert g == pytest.approx(expected, rel=1e-10)


def test_clipped_score_makes_the_baseline_change_the_expected_gradient():
    # With the clipped-action score E[score] != 0, so b shifts the mean: at sigma = 1 the
    # estimate without baseline is several times the one with the average baseline.
    g = {b: ts.batch_gradient(ENV, -0.55, 1.0, 200_000, 0, b, "clipped")[0] for b in ("none", "average")}
    assert g["none"] < 2 * g["average"] < 0
    raw = {b: ts.batch_gradient(ENV, -0.55, 1.0, 200_000, 0, b, "raw")[0] for b in ("none", "average")}
    assert raw["none"] == pytest.approx(raw["average"], rel=0.1)  # unbiased either way


def test_fixed_step_run_is_seeded_and_counts_batches():
    a = ts.fixed_step_run(ENV, -0.55, 1.0, 100, 1e-3, 1000, 3)
    b = ts.fixed_step_run(ENV, -0.55, 1.0, 100, 1e-3, 1000, 3)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (11,) and a[0] == -0.55 and np.all(np.diff(a) != 0)
    np.testing.assert_array_equal(ts.fixed_step_run(ENV, -0.55, 1.0, 100, 0.0, 1000, 3), np.full(11, -0.55))


@pytest.mark.parametrize("baseline,score,alpha", [("none", "raw", 1e-3), ("optimal", "clipped", 1e-3),
                                                  ("average", "clipped", 1e-3), ("optimal", "clipped", 1e6)])
def test_fixed_step_run_is_the_loop_of_batch_gradients(baseline, score, alpha):
    # The compiled run against batch_gradient called batch by batch, bit for bit; alpha = 1e6
    # diverges, and both stop before the first non-finite parameter.
    rng, theta, path = np.random.default_rng(11), -0.55, [-0.55]
    for _ in range(300):
        g, _ = ts.batch_gradient(ENV, theta, 1.0, 20, rng, baseline, score)
        if not (np.isfinite(g) and np.isfinite(theta + alpha * g)):
            break
        theta = theta + alpha * g
        path.append(theta)
    assert ts.fixed_step_run(ENV, -0.55, 1.0, 20, alpha, 6000, 11, baseline, score).tolist() == path
    assert (len(path) < 301) == (alpha == 1e6)


def test_fixed_step_run_stops_when_theta_diverges():
    path = ts.fixed_step_run(ENV, -0.55, 1.0, 10, 1e6, 10_000, 0)
    assert path.size < 1001 and np.all(np.isfinite(path))


def test_improvement_ratio_counting():
    v = np.array([0.0, 1.0, 0.5, 0.7, 0.2])
    assert ts.improvement_ratio(v, "all") == pytest.approx(2 / 4)
    assert ts.improvement_ratio(v, "evaluated") == pytest.approx(2 / 3)
    with pytest.raises(ValueError, match="^count"):
        ts.improvement_ratio(v, "some")


def test_closed_form_j_is_the_library_closed_form():
    thetas = np.linspace(-1.2, 0.2, 15)
    for sigma in (0.5, 1.0):
        np.testing.assert_allclose(ts.closed_form_j(thetas, sigma**2),
                                   [ENV.performance(t, sigma) for t in thetas], rtol=1e-12)
    assert ts.closed_form_j(np.array([0.5]), 1.0)[0] == -np.inf


def test_every_reading_of_the_j_formula_gives_the_same_improvement_ratio():
    path = -0.55 + np.cumsum(np.random.default_rng(2).normal(-1e-3, 5e-3, 500))
    for sigma in (0.5, 1.0):
        ratios = {name: ts.improvement_ratio(f(path)) for name, f in ts.j_formula_readings(sigma).items()}
        assert len(set(ratios.values())) == 1, ratios
        assert 0.2 < next(iter(ratios.values())) < 0.8  # a path that really goes both ways


def test_printed_values_are_counts_over_one_update_less_than_batches():
    # N = 10^4: 10^6 / N = 100 batches; the printed ratios are k / 99 (not k / 100).
    for sigma in (0.5, 1.0):
        for p in T51_PRINTED[sigma][10_000]:
            k = round(p / 100 * 99)
            assert abs(100 * k / 99 - p) < 0.006, p
    assert any(abs(round(p) - p) > 0.01 for p in T51_PRINTED[0.5][10_000])  # 95.96% is not k/100


def test_variant_validation_and_policy_std():
    with pytest.raises(ValueError, match="^baseline"):
        ts.Variant(baseline="mean")
    with pytest.raises(ValueError, match="^score_action"):
        ts.Variant(score_action="sampled")
    with pytest.raises(ValueError, match="^sigma_reading"):
        ts.Variant(sigma_reading="var")
    assert ts.Variant(sigma_reading="variance").policy_std(0.5) == pytest.approx(np.sqrt(0.5))
    assert ts.Variant().policy_std(0.5) == 0.5
    with pytest.raises(ValueError, match="^sigma"):
        ts.Variant().policy_std(-1.0)


def test_table_cells_are_the_printed_table():
    cells = ts.table_cells()
    assert len(cells) == 24
    assert (0.5, 10_000, 1e-3, 0.9596) in cells and (1.0, 100, 1e-6, 0.8604) in cells


def test_sweep_is_stored_and_reloaded(tmp_path, monkeypatch):
    plan = ((ts.Variant("none", "raw", "std"), -0.55), (ts.Variant("none", "raw", "variance"), -0.55),
            (ts.DEFAULT, -0.575))
    first = ts.sweep_paths(plan, seeds=1, budget=10_000, root=tmp_path)
    files = list((tmp_path / "table-5.1-sweep").glob("*.json"))
    assert len(files) == 1 and json.loads(files[0].read_text()) == first
    # sigma = 1 is not rerun under the variance reading (same runs as the std reading).
    assert len(first["paths"][plan[1][0].label]["-0.55"]) == 12
    assert len(first["paths"][plan[0][0].label]["-0.55"]) == 24
    assert first["paths"][ts.DEFAULT.label]["-0.575"]["sigma=1.0-N=100-alpha=1e-03"][0][0] == -0.575

    def boom(*args, **kwargs):
        raise AssertionError("recomputed a stored sweep")

    monkeypatch.setattr(ts, "run_cell", boom)
    assert ts.sweep_paths(plan, seeds=1, budget=10_000, root=tmp_path) == first
    rows = ts.sweep_table(first)
    assert len(rows) == 3 * 24 * 2  # (variant, theta0) x cells x counts
    summary = ts.summarise(rows)
    assert {(s["theta0"], s["count"]) for s in summary} == {(-0.55, "all"), (-0.55, "evaluated"),
                                                            (-0.575, "all"), (-0.575, "evaluated")}
    # Each group's count of cells within 5 points of the printed value, recounted from its 24 rows.
    for s in summary:
        group = [r for r in rows if (r["variant"], r["theta0"], r["count"]) == (s["variant"], s["theta0"], s["count"])]
        assert len(group) == 24
        assert s["within_all"] == sum(abs(r["difference"]) <= 0.05 for r in group)
        assert s["within_all"] == s["within_sigma_0.5"] + s["within_sigma_1"]
    assert len(summary) == 6
    fig = ts.figure_theta0_scan(summary)
    assert len(fig.axes) == 2


def test_sweep_rejects_bad_sizes(tmp_path):
    with pytest.raises(ValueError, match="^seeds"):
        ts.sweep_paths(((ts.DEFAULT, -0.55),), seeds=0, root=tmp_path)
    with pytest.raises(ValueError, match="^budget"):
        ts.sweep_paths(((ts.DEFAULT, -0.55),), budget=1000, root=tmp_path)


def test_run_cell_is_seeded_by_variant_start_and_cell():
    a = ts.run_cell(ts.DEFAULT, 1.0, 10_000, 1e-3, 0, budget=30_000, theta0=-0.575)
    assert a == ts.run_cell(ts.DEFAULT, 1.0, 10_000, 1e-3, 0, budget=30_000, theta0=-0.575)
    assert a != ts.run_cell(ts.DEFAULT, 1.0, 10_000, 1e-3, 1, budget=30_000, theta0=-0.575)
    b = ts.run_cell(ts.DEFAULT, 1.0, 10_000, 1e-3, 0, budget=30_000, theta0=-0.55)
    assert b[0] == -0.55 and len(a) == len(b) == 4


@pytest.mark.parametrize("baseline,flag", [("optimal", True), ("none", False)])
def test_fixed_step_run_is_the_library_vanilla_loop(baseline, flag):
    from safepg.learning import vanilla_pg
    from safepg.options import FixedStep, Gradient

    ours = ts.fixed_step_run(ENV, -0.575, 1.0, 500, 1e-3, 10_000, np.random.default_rng(4), baseline)
    lib = vanilla_pg(ENV, -0.575, 1.0, batch_size=500, step=FixedStep(1e-3), budget=10_000,
                     gradient=Gradient(baseline=flag), rng=np.random.default_rng(4))
    np.testing.assert_allclose(ours, lib.theta[:, 0], rtol=0, atol=1e-12)
    assert ts.improvement_ratio(ts.closed_form_j(ours, 1.0)) == lib.improvement_ratio()


def test_sweep_starts_are_the_experiments_starts():
    from safepg.thesis import experiments as ex

    assert ts.PRINTED_THETA0 == ex.T51_PRINTED_THETA0 and ts.RECONSTRUCTED_THETA0 == ex.T51_THETA0
    assert ts.PRINTED_THETA0 in ts.THETA0_SCAN and ts.RECONSTRUCTED_THETA0 in ts.THETA0_SCAN
    assert (ts.DEFAULT, ts.RECONSTRUCTED_THETA0) in ts.CHAPTER_PLAN
    assert {v for v, t in ts.CHAPTER_PLAN if t == ts.PRINTED_THETA0} == set(ts.VARIANTS)
