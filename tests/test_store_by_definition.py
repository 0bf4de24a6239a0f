"""The store is addressed by the definition: a changed run never overwrites another; any folder loads.

Before the key was part of a run's path (``<folder>/<name>/seed-<k>.npz``), the run of a
changed definition overwrote the old one under the same name: in
:func:`test_a_changed_definition_is_stored_beside_the_old_one`, ``stored_run(folder, a, 0)``
was None after ``b`` ran, and the folder held one file.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import replace

import matplotlib
import numpy as np
import pytest

from safepg import runner
from safepg.cli import main
from safepg.envs.cartpole import CartPole
from safepg.options import FixedStep, Vanilla
from safepg.record import LearningRecord
from safepg.results import load, plot_runs, summarise
from safepg.store import DAMAGED_SUFFIX, save_atomic

matplotlib.use("Agg")

A = runner.RunConfig("x", method=Vanilla(10, FixedStep(1e-3)), theta0=(-0.5,), sigma=1.0, budget=40)
B = replace(A, sigma=0.5)


def run_files(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("seed-*.npz"))


def test_a_changed_definition_is_stored_beside_the_old_one(tmp_path):
    runner.run_configs([A], 1, tmp_path, jobs=1, progress=False)
    runner.run_configs([B], 1, tmp_path, jobs=1, progress=False)
    assert runner.stored_run(tmp_path, A, 0) is not None
    assert runner.stored_run(tmp_path, B, 0) is not None
    assert run_files(tmp_path) == sorted([f"x/{A.key()}/seed-0.npz", f"x/{B.key()}/seed-0.npz"])
    assert runner.run_path(tmp_path, A, 0) == tmp_path / "x" / A.key() / "seed-0.npz"


def test_two_definitions_under_one_name_are_refused(tmp_path):
    with pytest.raises(ValueError, match="two configs are named 'x' with different definitions"):
        runner.run_configs([A, B], 1, tmp_path, jobs=1, progress=False)
    with pytest.raises(ValueError, match="named 'x'"):
        runner.load_configs([A, B], 1, tmp_path)
    assert not tmp_path.exists() or run_files(tmp_path) == []
    runner.check_names([A, replace(A)])  # the same definition twice is one run


def test_a_folder_of_the_old_layout_keeps_loading(tmp_path):
    rec = A.run(0)
    rec.config.update(run_key=A.key(), config_name="x", seed=0)
    save_atomic(rec, runner.legacy_run_path(tmp_path, A, 0))
    assert runner.stored_run(tmp_path, A, 0) is not None and runner.is_stored(tmp_path, A, 0)
    assert runner.stored_run(tmp_path, B, 0) is None  # another definition's file is not its run
    again = runner.run_configs([A], 1, tmp_path, jobs=1, progress=False)["x"]
    assert run_files(tmp_path) == ["x/seed-0.npz"]  # found, not computed again
    np.testing.assert_array_equal(again[0].theta, rec.theta)
    assert list(load(tmp_path)) == ["x"]


def test_prune_removes_the_runs_no_config_asks_for(tmp_path):
    runner.run_configs([A], 2, tmp_path, jobs=1, progress=False)
    runner.run_configs([B], 1, tmp_path, jobs=1, progress=False)
    runner.run_configs([replace(A, name="gone")], 1, tmp_path, jobs=1, progress=False)
    old = B.run(0)
    old.config.update(run_key=B.key(), config_name="x", seed=5)
    save_atomic(old, runner.legacy_run_path(tmp_path, B, 5))  # the old layout, another definition
    damaged = tmp_path / "x" / A.key() / f"seed-1.npz{DAMAGED_SUFFIX}20260101T000000Z"
    damaged.write_bytes(b"kept for inspection")
    (tmp_path / "x" / "notes.txt").write_text("not a run")
    before = run_files(tmp_path)
    listed = runner.prune(tmp_path, [A], dry_run=True)
    assert run_files(tmp_path) == before
    assert sorted(p.relative_to(tmp_path).as_posix() for p in listed) == sorted(
        [f"x/{B.key()}/seed-0.npz", "x/seed-5.npz", f"gone/{A.key()}/seed-0.npz"])
    assert runner.prune(tmp_path, [A]) == listed
    assert run_files(tmp_path) == [f"x/{A.key()}/seed-0.npz", f"x/{A.key()}/seed-1.npz"]
    assert damaged.exists() and (tmp_path / "x" / "notes.txt").exists()
    assert not (tmp_path / "x" / B.key()).exists()
    assert runner.prune(tmp_path, [A]) == []


def test_load_reads_a_folder_by_its_stored_definitions(tmp_path):
    runner.run_configs([A, replace(A, name="y", sigma=2.0)], 2, tmp_path, jobs=1, progress=False)
    runs = load(tmp_path)
    assert list(runs) == ["x", "y"] and [r.config["seed"] for r in runs["x"]] == [0, 1]
    assert runs["y"][0].config["sigma"] == 2.0 and runs["y"][0].config["run_key"] == replace(A, sigma=2.0).key()
    runner.run_configs([B], 1, tmp_path, jobs=1, progress=False)
    runs = load(tmp_path)
    assert sorted(runs) == sorted([f"x/{A.key()}", f"x/{B.key()}", "y"])
    (tmp_path / "y" / replace(A, sigma=2.0).key() / "seed-1.npz").write_bytes(b"truncated")
    with pytest.warns(UserWarning, match="damaged run file"):
        assert len(load(tmp_path)["y"]) == 1
    with pytest.raises(NotADirectoryError, match="folder"):
        load(tmp_path / "missing")


def test_summaries_and_the_figure_read_the_measured_return_without_a_closed_form(tmp_path):
    cart = runner.RunConfig("cart", task=CartPole(), method=Vanilla(20, FixedStep(1e-3)), theta0=(0.0,) * 4,
                            budget=100)
    runs = runner.run_configs([cart, A], 3, tmp_path, jobs=1, progress=False)
    assert runs["cart"][0].performance_field == "J_hat" and runs["x"][0].performance_field == "J"
    table = summarise({"cart": runs["cart"]})
    finals = [r.J_hat[-1] for r in runs["cart"]]
    assert table["cart"]["field"] == "J_hat" and table["cart"]["seeds"] == 3
    assert table["cart"]["final"]["mean"] == pytest.approx(np.mean(finals), rel=1e-12)
    assert table["cart"]["final"]["sd"] == pytest.approx(np.std(finals, ddof=1), rel=1e-12)
    assert list(table["cart"]["at"]) == ["25", "50", "75", "100"]  # the run's own checkpoints
    assert summarise({"x": runs["x"]})["x"]["field"] == "J"
    assert np.isfinite(runs["cart"][0].improvement_ratio()) and np.isnan(runs["cart"][0].improvement_ratio("J"))
    ax = plot_runs(runs, band="range")
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["cart (3 seeds)", "x (3 seeds)"]
    assert len(ax.get_lines()) == 2 * (1 + 3) and len(ax.collections) == 2
    assert ax.get_ylabel() == "measured return J_hat"  # one field for all: J_hat, which both have
    with pytest.raises(ValueError, match="band"):
        plot_runs(runs, band="iqr")


def test_the_performance_curve_and_checkpoints_follow_the_field():
    rec = LearningRecord(batch_size=np.array([10, 10, 20]), alpha=np.zeros(3), coordinate=np.zeros(3, int),
                         theta=np.zeros((4, 1)), J=np.full(4, np.nan), J_hat=np.array([1.0, 3.0, 2.0]),
                         grad=np.zeros((3, 1)), eps=np.zeros(3), safe=np.zeros(3, bool))
    x, y = rec.performance_curve()
    np.testing.assert_array_equal(x, [0, 10, 20]) and np.testing.assert_array_equal(y, [1.0, 3.0, 2.0])
    assert rec.checkpoints() == (10, 20, 30, 40)
    assert rec.at() == {"10": 1.0, "20": 3.0, "30": 2.0, "40": 2.0}
    assert rec.improvement_ratio() == 0.5
    assert rec.summary()["performance"]["final"] == 2.0


def test_the_prune_command(tmp_path, capsys, monkeypatch):
    """``safepg prune`` on the book's store: the runs of the experiments' old definitions go."""
    from safepg.thesis import experiment_store as es
    from safepg.thesis.experiments import get_experiment, scaled

    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    exp = scaled(get_experiment("table-5.3"), seeds=1, budget=4000)
    folder = es.experiment_folder(exp, tmp_path)
    stale = replace(exp.configs[0], sigma=0.25)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        runner.run_configs([stale], 1, folder, jobs=1, progress=False)
    assert main(["prune", "table-5.3", "--budget", "4000", "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert stale.key() in out and runner.stored_run(folder, stale, 0) is not None
    assert main(["prune", "table-5.3", "--budget", "4000", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {"removed": [str(runner.run_path(folder, stale, 0))]}
    assert runner.stored_run(folder, stale, 0) is None


def test_the_library_imports_matplotlib_only_to_draw():
    import subprocess
    import sys

    code = "import sys, safepg, safepg.results; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
