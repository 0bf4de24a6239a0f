"""Experiment runner: definitions, resume, invalidation, report, CLI."""

import json
from dataclasses import replace

import numpy as np
import pytest

from safepg import runner, stats, store
from safepg.cli import main
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep
from safepg.thesis import experiment_store as es
from safepg.thesis import experiments as ex
from safepg.thesis import report as rp


@pytest.fixture()
def root(tmp_path, monkeypatch):
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    return tmp_path


def fixed(c):
    """(batch size, step size) of a fixed-step config."""
    return c.method.batch_size, c.method.step.alpha


def small(name="table-5.2", configs=3, budget=3000, seeds=2):
    e = ex.get_experiment(name)
    return ex.scaled(replace(e, configs=e.configs[:configs]), seeds, budget)


def test_definitions_match_the_thesis():
    t51, t52 = ex.get_experiment("table-5.1"), ex.get_experiment("table-5.2")
    assert len(t51.configs) == 24 and {c.budget for c in t51.configs} == {1_000_000}
    assert {(c.sigma, c.method.batch_size, c.method.step.alpha) for c in t51.configs} == {
        (s, n, a) for s in (0.5, 1.0) for n in (10_000, 1_000, 100) for a in (1e-3, 1e-4, 1e-5, 1e-6)}
    # Run from the reconstructed theta_0 = -0.575 (the thesis prints -0.55: table-5.1-printed-theta0).
    assert all(c.theta0 == (-0.575,) and c.method.gradient.estimator == "gpomdp" and c.method.gradient.baseline
               for c in t51.configs)
    printed = ex.get_experiment("table-5.1-printed-theta0")
    assert [replace(c, theta0=(-0.575,)) for c in printed.configs] == list(t51.configs)
    assert len(t52.configs) == 12 and t52.seeds == ex.CURVE_SEEDS  # it feeds the curves of Figures 5.1-5.4
    assert all(c.budget == 30_000_000 and c.theta0 == (0.0,) and c.sigma == 1.0 for c in t52.configs)
    assert sum(c.method.gradient.estimator == "reinforce" for c in t52.configs) == 3
    assert len({c.key() for c in t52.configs}) == 12
    for c in t52.configs:
        lo, hi = t52.thesis[c.name]["ci95"]
        assert lo <= t52.thesis[c.name]["upsilon_bar"] <= hi


def test_run_resume_and_invalidation(root, monkeypatch):
    exp = small()
    recs = es.run_experiment(exp, jobs=1, progress=False)
    assert all(len(v) == 2 for v in recs.values())
    files = sorted(root.rglob("*.npz"))
    assert len(files) == 6
    stamp = {f: f.stat().st_mtime_ns for f in files}
    calls = []
    monkeypatch.setattr(ex.RunConfig, "run", lambda self, k, progress=False, theta0=None: calls.append((self.name, k)))
    again = es.run_experiment(exp, jobs=1, progress=False)
    assert calls == [] and all(f.stat().st_mtime_ns == stamp[f] for f in files)
    for name in recs:
        assert all(np.array_equal(a.theta, b.theta) for a, b in zip(recs[name], again[name]))
    # Changing one config's settings invalidates only its runs.
    c0 = exp.configs[0]
    c0 = replace(c0, method=replace(c0.method, error=replace(c0.method.error, delta=0.9)))
    changed = replace(exp, configs=(c0,) + exp.configs[1:])
    assert runner.stored_run(es.experiment_folder(changed), changed.configs[0], 0) is None
    assert runner.stored_run(es.experiment_folder(changed), changed.configs[1], 0) is not None


def test_same_results_in_parallel_and_serial(root, tmp_path_factory):
    exp = small(configs=2, seeds=2)
    serial = es.run_experiment(exp, jobs=1, progress=False)
    par = es.run_experiment(exp, jobs=2, progress=False, root=tmp_path_factory.mktemp("par"))
    for name in serial:
        assert all(np.array_equal(a.theta, b.theta) for a, b in zip(serial[name], par[name]))


def test_interrupted_or_partial_files_are_recomputed(root):
    exp = small(configs=1, seeds=1)
    cfg = exp.configs[0]
    path = runner.run_path(es.experiment_folder(exp), cfg, 0)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"half a file")
    with pytest.warns(store.DamagedRunWarning, match="left out"):
        assert store.load_stored(path, cfg.key()) is None
    with pytest.warns(store.DamagedRunWarning, match="set aside"):  # kept: tests/test_damaged_store.py
        es.run_experiment(exp, jobs=1, progress=False)
    assert store.load_stored(path, cfg.key()) is not None
    assert not list(path.parent.glob("*.tmp.npz"))


def test_report_structure(root):
    exp = small(configs=2, seeds=3, budget=120_000)
    records = es.run_experiment(exp, jobs=1, progress=False)
    rep = rp.report(exp, records)
    assert rep["experiment"] == "table-5.2" and len(rep["configs"]) == 2
    row = rep["configs"][0]
    for key in ("name", "method", "sigma", "budget", "seeds", "upsilon_bar", "improvement_ratio", "J_at", "J_final",
                "thesis"):
        assert key in row
    assert row["seeds"] == 3 and row["method"]["gradient"]["estimator"] == "reinforce"
    assert row["method"]["error"]["bound"] == "chebyshev"
    # The row's Upsilon-bar: the mean of the three seeds' runs, its 95% interval and the 95% prediction interval
    # for one more run, recomputed here with scipy's t quantile.
    from scipy import stats as scipy_stats

    ups = np.array([r.upsilon_bar() for r in records[exp.configs[0].name]])
    assert ups.size == 3 and np.ptp(ups) > 0
    t, m, sd = scipy_stats.t.ppf(0.975, 2), ups.mean(), ups.std(ddof=1)
    got = row["upsilon_bar"]
    assert got["mean"] == pytest.approx(m, rel=1e-12)
    assert got["ci95"] == pytest.approx([m - t * sd / np.sqrt(3), m + t * sd / np.sqrt(3)], rel=1e-9)
    assert got["pi95"] == pytest.approx([m - t * sd * np.sqrt(1 + 1 / 3), m + t * sd * np.sqrt(1 + 1 / 3)], rel=1e-9)
    assert list(row["J_at"]) == ["100000"]
    assert row["thesis"]["upsilon_bar"] == -11.3266


def test_mean_ci95_matches_scipy():
    from scipy import stats as scipy_stats

    x = [1.0, 2.0, 4.0, 3.5, 2.2]
    lo, hi = scipy_stats.t.interval(0.95, len(x) - 1, loc=np.mean(x), scale=scipy_stats.sem(x))
    assert stats.mean_ci95(x)["ci95"] == pytest.approx([lo, hi])


def test_cli_list_run_report(root, capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "table-5.1" in out and "table-5.2" in out
    assert main(["list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["table-5.3"]["configs"]["adaptive"]
    cfg = ex.get_experiment("table-5.3").config("adaptive")
    assert listed == {"key": cfg.key(), "definition": cfg.definition()}
    assert main(["run", "table-5.1", "--seeds", "1", "--budget", "20000", "--jobs", "2", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["report", "table-5.1", "--seeds", "1", "--budget", "20000", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["experiment"] == "table-5.1" and len(rep["configs"]) == 24
    row = rep["configs"][0]
    assert row["method"]["batch_size"] == 10_000 and row["method"]["step"]["alpha"] == 1e-3 and row["seeds"] == 1
    assert row["thesis"] == {"improvement_ratio": 0.9596}


def test_unknown_experiment():
    with pytest.raises(ValueError, match="^experiment"):
        ex.get_experiment("table-9")


def test_sections_5_2_and_5_3_definitions():
    f55, t53 = ex.get_experiment("figures-5.5-5.6"), ex.get_experiment("table-5.3")
    for c in f55.configs + t53.configs:
        assert c.task == ex.make_env("lqg2d-gamma0.9") and c.theta0 == (0.0,) * 4 and c.budget == 30_000_000
    assert {c.method.step.kind for c in f55.configs} == {"scalar", "coordinate"}
    assert all(c.method.batch_size == 2000 and c.method.step.error == ErrorModel("chebyshev", 0.95)
               for c in f55.configs)
    adaptive, n1000, n100 = t53.configs
    assert adaptive.method == Adaptive(error=ErrorModel("bernstein", 0.95, "empirical"))
    assert (fixed(n1000), fixed(n100)) == ((1000, 1e-6), (100, 1e-6))
    env = ex.make_env("lqg2d-gamma0.9")
    assert env.dim == 2 and env.gamma == 0.9 and ex.make_env("lqg2d").gamma == 0.95
    base, t54 = ex.get_experiment("cartpole-baseline"), ex.get_experiment("table-5.4")
    (b,) = base.configs
    assert (b.task, *fixed(b), b.method.target.value) == ("cartpole", 4000, 0.01, 195.0)
    assert {c.task for c in t54.configs} == {"cartpole-doubled"} and len({c.budget for c in t54.configs}) == 1
    assert all(c.warm_start == "cartpole-baseline" for c in t54.configs)
    assert base.performance == t54.performance == "J_hat" and t53.performance == "J"
    assert ex.make_env("cartpole-doubled").pole_length == 2 * ex.make_env("cartpole").pole_length


def test_warm_start_runs_the_baseline_first_and_starts_from_it(root):
    base = ex.scaled(ex.get_experiment("cartpole-baseline"), seeds=2)
    # A cheap stand-in for the baseline: the same experiment name, two iterations.
    b0 = base.configs[0]
    cheap = replace(base, configs=(replace(b0, budget=8000, method=replace(b0.method, target=None)),))
    t54 = ex.scaled(ex.get_experiment("table-5.4"), seeds=2, budget=12_000)
    import safepg.thesis.experiments as mod

    saved = dict(mod.EXPERIMENTS)
    mod.EXPERIMENTS["cartpole-baseline"] = cheap
    try:
        recs = es.run_experiment(t54, jobs=1, progress=False)
        baselines = es.load_experiment(cheap)["baseline"]
        assert len(baselines) == 2 and all(r.iterations == 2 for r in baselines)
        for name in ("adaptive", "N=4000"):
            for k, r in enumerate(recs[name]):
                np.testing.assert_array_equal(r.theta[0], baselines[k].theta_final)
        assert not np.array_equal(baselines[0].theta_final, baselines[1].theta_final)
        # The starting policy is part of a run's identity: the key of the run it starts from is.
        key = t54.configs[0].key()
        assert t54.configs[0].warm_start_key == saved[
            "cartpole-baseline"].configs[0].key()
        other_start = replace(cheap.configs[0], method=replace(cheap.configs[0].method, step=FixedStep(0.02)))
        assert replace(t54.configs[0], warm_start_key=other_start.key()).key() != key
    finally:
        mod.EXPERIMENTS.clear()
        mod.EXPERIMENTS.update(saved)
    rep = rp.report(t54, recs)
    rows = {r["name"]: r for r in rep["configs"]}
    assert rows["adaptive"]["method"]["type"] == "Adaptive"
    assert (rows["N=4000"]["method"]["batch_size"], rows["N=4000"]["method"]["step"]["alpha"]) == (4000, 0.01)
    for name, row in rows.items():
        assert row["improvement_ratio_on"] == "J_hat" and row["J_final"] is None and row["J_at"] == {}
        expected = np.mean([r.improvement_ratio("J_hat") for r in recs[name]])
        assert row["improvement_ratio"]["mean"] == pytest.approx(expected)
        assert row["upsilon_bar"]["mean"] == pytest.approx(np.mean([r.J_hat @ r.batch_size / r.trajectories
                                                                    for r in recs[name]]))
        assert 1 <= row["J_hat_final"] <= 200  # undiscounted episode lengths
    assert rows["N=4000"]["components_updated"] == [0, 1, 2, 3]


def test_report_lists_the_components_each_method_updated(root):
    exp = ex.scaled(ex.get_experiment("figures-5.5-5.6"), seeds=1, budget=20_000)
    rows = {r["name"]: r for r in rp.report(exp, es.run_experiment(exp, jobs=1, progress=False))["configs"]}
    assert rows["coordinate"]["components_updated"] == [0, 3]  # only the diagonal moves
    assert rows["scalar"]["components_updated"] == [0, 1, 2, 3]
    assert rows["coordinate"]["improvement_ratio_on"] == "J"


# ------------------------------------------------------------------ the authors' settings
def test_authors_experiments_are_the_library_settings_combined():
    from safepg.envs.cartpole import CartPole
    from safepg.thesis.authors import TABLE_5_4_BUDGET, cartpole_theta_star

    t51 = ex.get_experiment("table-5.1-authors")
    assert t51.rules == "authors" and all(c.theta0 == (-0.575853,) for c in t51.configs)
    assert [replace(c, theta0=(-0.575,)) for c in t51.configs] == list(ex.get_experiment("table-5.1").configs)
    base = ex.get_experiment("cartpole-baseline-authors").configs[0]
    assert ex.make_env(base.task) == CartPole(angle_threshold_deg=12.0, gamma=1.0, constants_gamma=0.9)
    assert base.method.target.update and (*fixed(base), base.method.step.kind, base.method.target.value) == (
        4000, 0.01, "scalar", 195.0)
    t54 = ex.get_experiment("table-5.4-authors")
    ad, fx = t54.config("adaptive"), t54.config("N=4000")
    assert ex.make_env(ad.task) == CartPole.thesis_doubled(angle_threshold_deg=12.0, gamma=1.0, constants_gamma=0.9,
                                                           polemass_length=0.05) == ex.make_env(fx.task)
    assert ad.method.batches == Batches(10, 500_000, 1000)
    assert ad.method.departures == Departures(batch_constants=True, maxima=True, unguarded_step=True)
    assert ad.method.error == ErrorModel("bernstein", 0.95, "empirical")
    assert (fx.method.step.kind, *fixed(fx)[::-1]) == ("coordinate", 0.01, 4000)
    assert ad.budget == fx.budget == TABLE_5_4_BUDGET and t54.rules == "authors" and t54.thesis == ex.get_experiment(
        "table-5.4").thesis
    assert ad.warm_start == "cartpole-baseline-authors" and ad.warm_start_key == base.key()
    star = ex.get_experiment("table-5.4-authors-theta-star")
    assert all(c.warm_start is None and c.theta0 == tuple(cartpole_theta_star()) for c in star.configs)
    t53 = ex.get_experiment("table-5.3-authors").configs[0]
    algorithm = replace(t53.method, batches=replace(t53.method.batches, n_max=500_000), departures=Departures())
    assert replace(t53, method=algorithm) == ex.get_experiment("table-5.3").config("adaptive")
    # Table 5.2's theoretical-range rows (the range 1280 already the authors'), their step unguarded.
    t52, t52a = ex.get_experiment("table-5.2"), ex.get_experiment("table-5.2-authors")
    assert [c.name for c in t52a.configs] == ["gpomdp-hoeffding-delta=0.95", "gpomdp-bernstein-delta=0.95"]
    assert [replace(c, method=replace(c.method, departures=Departures())) for c in t52a.configs] == [
        t52.config(c.name) for c in t52a.configs]
    assert all(c.method.departures.unguarded_step and c.method.error.range == 1280.0 for c in t52a.configs)
    assert t52a.rules == "authors" and t52a.thesis == {c.name: t52.thesis[c.name] for c in t52a.configs}


def test_authors_experiment_runs_and_is_counted_their_way(root):
    from safepg.thesis.authors import budget_average, strict_improvement_ratio

    exp = ex.scaled(ex.get_experiment("table-5.4-authors-theta-star"), seeds=1, budget=12_000)
    recs = es.run_experiment(exp, jobs=1, progress=False)
    ad, fx = recs["adaptive"][0], recs["N=4000"][0]
    assert ad.batch_size[0] == 1000 and fx.batch_size[0] == 4000
    assert ad.config["method"]["departures"]["batch_constants"]
    assert np.all(np.count_nonzero(np.diff(fx.theta, axis=0), axis=1) <= 1)  # one component per update
    assert 180 < ad.J_hat[0] < 195  # the authors' first doubled-pole batch: 187.5
    rows = {r["name"]: r for r in rp.report(exp, recs)["configs"]}
    for name, rec in (("adaptive", ad), ("N=4000", fx)):
        window = budget_average(rec.batch_size, rec.J_hat, 12_000)
        assert rows[name]["rules"] == "authors"
        assert rows[name]["upsilon_bar"]["mean"] == window["upsilon_bar"]
        assert rows[name]["improvement_ratio"]["mean"] == window["improvement_ratio"]
    lqg = ex.scaled(replace(ex.get_experiment("table-5.1-authors"), configs=ex.get_experiment(
        "table-5.1-authors").configs[:1]), seeds=1, budget=60_000)
    rec = es.run_experiment(lqg, jobs=1, progress=False)[lqg.configs[0].name][0]
    row = rp.report(lqg, {lqg.configs[0].name: [rec]})["configs"][0]
    assert row["improvement_ratio"]["mean"] == strict_improvement_ratio(rec.J[:-1])  # 5 of 6 batch starts


def test_experiments_start_with_the_seed_rule_s_counts() -> None:
    """An experiment whose runs feed a whole curve of the scorecard starts with the rule's count for curves;
    the others the count for one run (safepg.thesis.seed_rule)."""
    from safepg.thesis.curve_bands import CURVE_EXPERIMENTS
    from safepg.thesis.seed_rule import START_SEEDS

    assert START_SEEDS["whole curve"] == ex.CURVE_SEEDS > START_SEEDS["one run"] == 5
    for name in CURVE_EXPERIMENTS:
        assert ex.get_experiment(name).seeds == ex.CURVE_SEEDS, name
    for name in ("table-5.1", "table-5.1-authors", "table-5.2-lemma-range", "cartpole-baseline", "table-5.4-authors"):
        assert ex.get_experiment(name).seeds == START_SEEDS["one run"], name
