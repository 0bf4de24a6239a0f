"""``python -m safepg run/report NAME --json`` on the authors'-settings variants (small budgets, a
temporary results store): the report carries the thesis's printed values, the authors' counting
rules and the authors' own outputs recomputed from their files."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from safepg.cli import main
from safepg.thesis import authors
from safepg.thesis import experiments as ex
from safepg.thesis import report as rp


@pytest.fixture()
def root(tmp_path, monkeypatch):
    monkeypatch.setenv("SAFEPG_RESULTS", str(tmp_path))
    return tmp_path


def run_and_report(name: str, budget: int, capsys) -> dict:
    assert main(["run", name, "--seeds", "1", "--budget", str(budget), "--jobs", "1", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["report", name, "--seeds", "1", "--budget", str(budget), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_every_authors_variant_is_listed(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in ("table-5.1-authors", "table-5.2-authors", "table-5.3-authors", "cartpole-baseline-authors",
                 "table-5.4-authors", "table-5.4-authors-theta-star"):
        assert name in out


def test_report_of_table_5_1_authors(root, capsys):
    rep = run_and_report("table-5.1-authors", 20_000, capsys)
    assert rep["experiment"] == "table-5.1-authors" and len(rep["configs"]) == 24
    theirs = authors.table_5_1()
    for row, cfg in zip(rep["configs"], ex.get_experiment("table-5.1-authors").configs):
        assert row["rules"] == "authors" and row["seeds"] == 1
        assert row["thesis"] == ex.get_experiment("table-5.1").thesis[cfg.name]  # the printed value
        out = row["authors_output"]
        cell = (cfg.sigma, cfg.method.batch_size, cfg.method.step.alpha)
        assert out["improvement_ratio"] == theirs[cell]["improvement_ratio"]
        assert out["theta0"] == -0.575853
    slip = next(r for r in rep["configs"] if r["name"] == "sigma=1.0-N=1000-alpha=1e-03")
    assert slip["thesis"]["improvement_ratio"] == 0.374 and slip["authors_output"]["increases"] == 376
    assert slip["authors_output"]["updates"] == 999


def test_report_of_table_5_4_authors_theta_star(root, capsys):
    rep = run_and_report("table-5.4-authors-theta-star", 12_000, capsys)
    rows = {r["name"]: r for r in rep["configs"]}
    assert set(rows) == {"adaptive", "N=4000"}
    assert rows["adaptive"]["thesis"] == {"upsilon_bar": 193.12, "improvement_ratio": 0.5301}
    assert rows["adaptive"]["authors_output"]["upsilon_bar"] == pytest.approx(193.1249, abs=1e-4)
    assert rows["adaptive"]["authors_output"]["increases"] == 132
    assert rows["N=4000"]["authors_output"]["upsilon_bar"] == pytest.approx(192.8615, abs=1e-4)
    assert rows["N=4000"]["authors_output"]["budget"] == authors.TABLE_5_4_BUDGET
    # Started from the authors' own baseline policy.
    assert rows["adaptive"]["seeds"] == 1 and rows["adaptive"]["rules"] == "authors"


def test_report_of_other_experiments_has_no_authors_output(root, capsys):
    rep = run_and_report("table-5.3-authors", 3000, capsys)
    assert rep["configs"][0]["authors_output"]["upsilon_bar"] == pytest.approx(-20.4973, abs=1e-4)
    rep = rp.report(ex.scaled(ex.get_experiment("table-5.3"), seeds=1, budget=3000), {})
    assert all(r["authors_output"] is None for r in rep["configs"])


def test_report_json_from_the_command_line(root):
    # The module entry point, as a user runs it, on a variant's stored run.
    cmd = [sys.executable, "-m", "safepg"]
    args = ["cartpole-baseline-authors", "--seeds", "1", "--budget", "8000"]
    subprocess.run([*cmd, "run", *args, "--jobs", "1", "--quiet"], check=True, capture_output=True)
    done = subprocess.run([*cmd, "report", *args, "--json"], check=True, capture_output=True, text=True)
    rep = json.loads(done.stdout)
    (row,) = rep["configs"]
    assert rep["experiment"] == "cartpole-baseline-authors" and row["thesis"]["iterations"] == 72
    assert row["authors_output"] == {"iterations": 72, "J_hat_final": pytest.approx(197.0655)}
