"""The authors' raw outputs (safepg/thesis/data/authors): the files against their manifest, the
printed tables recomputed from them with the authors' rules, and the 2-D closed form of their code."""

from __future__ import annotations

import hashlib
import json
import math
import re

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.stats import t_quantile, t_quantile_975
from safepg.thesis import authors as A
from safepg.thesis.experiments import T51_ALPHAS, T51_PRINTED, get_experiment, t52_name

HEX40 = re.compile(r"^[0-9a-f]{40}$")


# ------------------------------------------------------------------ files and provenance
def test_manifest_matches_the_files() -> None:
    assert A.verify_data() == []
    m = json.loads((A.DATA_DIR / "MANIFEST.json").read_text())
    assert m["repository"] == A.REPOSITORY and HEX40.match(m["read_at"])
    total = 0
    for name, entry in m["files"].items():
        data = (A.DATA_DIR / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == entry["sha256"] and len(data) == entry["bytes"]
        total += len(data)
        for src in entry["sources"]:
            assert HEX40.match(src["commit"]) and HEX40.match(src["blob"]), src
            assert src["bytes"] > 0 and src["header"] and src["columns"] and src["path"]
    assert total + len((A.DATA_DIR / "MANIFEST.json").read_bytes()) < 5_000_000
    # Every row is there: the manifest's row counts against the loaded runs.
    loaded = {"table51.csv.xz": A.table51_runs().values(), "lqg2d.csv.xz": A.lqg2d_runs().values(),
              "cartpole.csv.xz": A.cartpole_runs().values(), "figures51_52.csv.xz": A.figure51_52_curves().values(),
              "table52.csv.xz": [r for runs in A.table52_runs().values() for r in runs],
              "figure55.csv.xz": A.figure55_curves().values()}
    for name, runs in loaded.items():
        assert sum(r.iterations for r in runs) == m["files"][name]["rows"], name


def test_verify_data_reports_an_altered_file(tmp_path) -> None:
    for p in A.DATA_DIR.iterdir():
        (tmp_path / p.name).write_bytes(p.read_bytes())
    assert A.verify_data(tmp_path) == []
    (tmp_path / "cartpole_theta_star.csv").write_text("tampered\n")
    (tmp_path / "stray.csv").write_text("x\n")
    assert A.verify_data(tmp_path) == ["cartpole_theta_star.csv: bytes or sha256 differ from MANIFEST.json",
                                       "stray.csv: not in MANIFEST.json"]


def test_runs_are_what_the_manifest_says() -> None:
    t51 = A.table51_runs()
    assert len(t51) == 24
    for (sigma, n, alpha), run in t51.items():
        assert run.iterations == 1_000_000 // n and run["theta"][0] == -0.575853  # every file starts there
        assert run.source["header"] == f"{n} {alpha:g} {sigma} gpomdp 1000000"
    t52 = A.table52_runs()
    assert len(t52) == 12 and sorted(len(v) for v in t52.values()) == [1] + [5] * 11
    assert all(r.source["header"].endswith("30000000") for runs in t52.values() for r in runs)
    assert set(A.lqg2d_runs()) == {"adaptive", "N=1000", "coordinate", "scalar"}
    cp = A.cartpole_runs()
    assert set(cp) == {"adaptive", "fixed", "fixed-short", "baseline"} and cp["adaptive"]["theta"].shape == (251, 4)
    curves = A.figure51_52_curves()
    assert len(curves) == 12 and all(c["J"][0] == -56.666667 for c in curves.values())


def test_each_runs_rows_are_its_source_rows_in_file_order() -> None:
    """The one-pass split by source gives each run the rows a mask on its source number selects."""
    files = [name for name, entry in A.manifest()["files"].items() if "source" in A._read(name)[0]]
    assert len(files) >= 5
    for name in files:
        header, table = A._read(name)
        which = table[:, header.index("source")].astype(int)
        sources = len(A.manifest()["files"][name]["sources"])
        for n in (sources, sources - 1):  # a source number beyond the manifest's is dropped
            parts = A._rows_by_source(name, n)
            assert len(parts) == n and all(np.array_equal(p, table[which == i]) for i, p in enumerate(parts)), name
            assert not any(p.flags.writeable for p in parts), "shared between lookups: read-only"


# ------------------------------------------------------------------ the rules
def test_rules_on_small_examples() -> None:
    assert A.strict_improvement_ratio([1.0, 2.0, 2.0, 1.0, 3.0]) == 0.5  # a tie is no increase
    assert math.isnan(A.strict_improvement_ratio([1.0]))
    w = A.budget_average([10, 20, 30, 40], [1.0, 2.0, 3.0, 4.0], 60)
    # Only the batches that end before the budget: 10 + 20 < 60, the third ends at 60.
    assert (w["batches"], w["trajectories"], w["increases"]) == (2, 30, 1)
    assert w["upsilon_bar"] == pytest.approx(5 / 3) and w["improvement_ratio"] == 1.0
    with pytest.raises(ValueError, match="^budget "):
        A.budget_average([10], [1.0], 10)
    t = A.truncated_average([(np.array([1, 1, 1]), np.array([1.0, 2.0, 9.0])),
                             (np.array([2, 2]), np.array([3.0, 5.0]))])
    assert t["T"] == 2 and t["per_run"] == [1.5, 4.0] and t["mean"] == 2.75
    assert t["ci90"][1] - 2.75 == pytest.approx(t_quantile(1, "0.1") * np.std([1.5, 4.0], ddof=1) / math.sqrt(2))


def test_t_quantiles() -> None:
    # Matlab's tinv(0.95, 4), the authors' "95%" interval, and the 0.975 quantile kept as it was.
    assert t_quantile(4, "0.1") == pytest.approx(2.131846786326649, rel=1e-15)
    assert t_quantile_975(4) == t_quantile(4, "0.05") == pytest.approx(2.7764451051977987, rel=1e-15)
    with pytest.raises(ValueError, match="^tails "):
        t_quantile(4, "1.5")


# ------------------------------------------------------------------ the printed tables
def test_table_5_1_cells_but_one_are_the_print() -> None:
    recomputed = A.table_5_1()
    off = {}
    for (sigma, n, alpha), row in recomputed.items():
        printed = T51_PRINTED[sigma][n][T51_ALPHAS.index(alpha)]
        if round(100 * row["improvement_ratio"], 2) != printed:
            off[(sigma, n, alpha)] = (row["increases"], row["updates"], printed)
        assert row["updates"] == 1_000_000 // n - 1
    # The one slip: 376 of 999 updates is 37.64%, printed 37.4% (so already in their spreadsheet).
    assert off == {(1.0, 1000, 1e-3): (376, 999, 37.4)}


def test_table_5_1_J_column_reads_sigma_as_the_variance() -> None:
    run = A.table51_runs()[(0.5, 100, 1e-3)]
    env = LQG.thesis_1d()
    assert run["J"][0] == pytest.approx(env.performance(-0.575853, math.sqrt(0.5)), abs=1e-10)
    assert run["J"][0] != pytest.approx(env.performance(-0.575853, 0.5), abs=1e-3)


def test_table_5_2_with_the_shortest_run_and_90_percent_intervals() -> None:
    printed = get_experiment("table-5.2").thesis
    recomputed = A.table_5_2()
    five = one = 0
    for (est, bound, er, delta), row in recomputed.items():
        p = printed[t52_name(est, bound, er, delta)]
        if row["runs"] == 5:
            assert round(row["mean"], 4) == p["upsilon_bar"]
            assert [round(v, 4) for v in row["ci90"]] == p["ci95"]  # printed as "95%"
            five += 1
        else:  # Bernstein e.r.: one of the five runs is committed
            assert (bound, er, round(row["mean"], 4), p["upsilon_bar"]) == ("bernstein", True, -9.6625, -9.6623)
            one += 1
    assert (five, one) == (11, 1)  # every row of Table 5.2 checked
    assert recomputed[("reinforce", "chebyshev", False, 0.95)]["T"] == 1275
    # A 95% interval would not be the print.
    row = recomputed[("reinforce", "chebyshev", False, 0.95)]
    half95 = (row["ci90"][1] - row["mean"]) * t_quantile_975(4) / t_quantile(4, "0.1")
    assert round(row["mean"] - half95, 4) != printed[t52_name("reinforce", "chebyshev", False, 0.95)]["ci95"][0]


def test_table_5_3_and_figures_5_5_5_6() -> None:
    t53 = A.table_5_3()
    printed = get_experiment("table-5.3").thesis
    for name in ("adaptive", "N=1000"):
        assert round(t53[name]["upsilon_bar"], 2) == printed[name]["upsilon_bar"]
        assert t53[name]["improvement_ratio"] == printed[name]["improvement_ratio"] == 1.0
    assert round(t53["adaptive"]["upsilon_bar"], 4) == -20.4973 and round(t53["N=1000"]["upsilon_bar"], 4) == -22.3926
    assert t53["adaptive"]["trajectories"] == 29_998_496 and t53["N=1000"]["trajectories"] == 30_000_000
    fig = get_experiment("figures-5.5-5.6").thesis
    assert t53["coordinate"]["improvement_ratio"] == t53["scalar"]["improvement_ratio"] == 1.0
    np.testing.assert_allclose(t53["coordinate"]["theta_final"], fig["coordinate"]["theta_final"], atol=1e-4)
    # The printed scalar theta_11 = -0.014676 is a typo of the run's -0.013677 (theta_22 is printed right).
    scalar = t53["scalar"]["theta_final"]
    assert round(scalar[0, 0], 6) == -0.013677 and round(scalar[1, 1], 6) == fig["scalar"]["theta_final"][1][1]


def test_table_5_4_over_the_adaptive_runs_length() -> None:
    t54 = A.table_5_4()
    runs = A.cartpole_runs()
    assert A.TABLE_5_4_BUDGET == int(runs["adaptive"]["N"].sum()) == 1_151_669
    ad, fx = t54["adaptive"], t54["fixed"]
    assert (ad["batches"], ad["trajectories"], ad["increases"]) == (250, 1_142_872, 132)
    assert (fx["batches"], fx["trajectories"], fx["increases"]) == (287, 1_148_000, 128)
    printed = get_experiment("table-5.4").thesis
    assert round(ad["upsilon_bar"], 2) == printed["adaptive"]["upsilon_bar"] == 193.12
    assert round(fx["upsilon_bar"], 2) == printed["N=4000"]["upsilon_bar"] == 192.86
    assert round(ad["improvement_ratio"], 4) == printed["adaptive"]["improvement_ratio"] == 0.5301
    assert round(fx["improvement_ratio"], 4) == printed["N=4000"]["improvement_ratio"] == 0.4476
    # Their "vanilla" moves one component per update (coordinate step), the adaptive one too.
    moved = np.count_nonzero(np.diff(runs["fixed"]["theta"], axis=0), axis=1)
    assert moved.max() == 1 and np.count_nonzero(np.diff(runs["adaptive"]["theta"], axis=0)[:, 2:]) == 0


def test_cartpole_baseline_policy() -> None:
    theta = A.cartpole_theta_star()
    runs = A.cartpole_runs()
    np.testing.assert_allclose(theta, [-0.89869951, 2.09873833, 3.48744313, 7.25175622], atol=5e-9)
    for name in ("adaptive", "fixed", "fixed-short"):  # every doubled-pole run starts there
        np.testing.assert_allclose(runs[name]["theta"][0], theta, atol=5e-9)
    base = runs["baseline"]
    assert base.iterations == 72 and base["J_hat"][0] == 40.1595 and base["J_hat"][-1] == 197.0655
    # theta_star is one update past the last logged (pre-update) parameter of the batch that reached 195.
    assert np.abs(base["theta"][-1] - theta).max() > 0.1


# ------------------------------------------------------------------ the 2-D closed form of their code
def _by_hand(k: float, gamma: float = 0.9) -> tuple[float, float]:
    """(their J, the consistent J) at theta = diag(k, k), sigma = 1, written out per diagonal entry:
    p = (1 + k^2) / 2 / (1 - gamma (1 + k)^2); tr P = 2p; W = 2 (1/2 + gamma p) / (1 - gamma)."""
    p = 0.5 * (1 + k * k) / (1 - gamma * (1 + k) ** 2)
    W = 2 * (0.5 + gamma * p) / (1 - gamma)
    consistent = -(4 / 3) * 2 * p - W
    return -16 * ((4 / 3) * 2 * p + W), consistent


def test_lqg2d_performance_is_16_times_the_expectation() -> None:
    env = LQG.thesis_2d(gamma=0.9)
    zero, star = np.zeros(4), np.diag([-0.588403, -0.588403])
    theirs0, consistent0 = _by_hand(0.0)
    assert (theirs0, consistent0) == (pytest.approx(-1813.3333333333), pytest.approx(-113.3333333333))
    assert A.lqg2d_performance(zero) == pytest.approx(theirs0, rel=1e-14)
    assert env.performance(zero, 1.0) == pytest.approx(consistent0, rel=1e-14)
    theirs, consistent = _by_hand(-0.588403)
    assert round(theirs, 5) == -422.61602 and round(consistent, 4) == -26.4135  # printed: -422.616
    assert A.lqg2d_performance(star) == pytest.approx(theirs, rel=1e-13)
    assert env.performance(star, 1.0) == pytest.approx(consistent, rel=1e-13)
    # At the optimum the code finds (gamma = 0.9, theta* = diag(-0.588403)):
    assert env.optimal_gain()[0, 0] == pytest.approx(-0.588403, abs=1e-6)
    assert A.lqg2d_performance(env.optimal_gain()) == pytest.approx(-422.61602, abs=5e-6)
    rng = np.random.default_rng(0)
    for k in rng.uniform(-0.9, -0.05, size=(5, 2)):  # any diagonal gain: exactly 16 times
        K = np.diag(k)
        assert A.lqg2d_performance(K) == pytest.approx(16 * env.performance(K, 1.0), rel=1e-12)


def test_lqg2d_performance_gives_their_J_column() -> None:
    for name, ends in A.lqg2d_theta_ends().items():
        for theta, J in zip(ends["theta"], ends["J"]):
            # Their theta is logged to 8 significant digits, J to 12.
            assert A.lqg2d_performance(theta) == pytest.approx(J, rel=1e-6), name
    run = A.lqg2d_runs()["adaptive"]
    assert run["J"][0] == -1813.33333333
