"""``python -m safepg run-book`` (``make book``): what the chapters need, computed first, with progress."""

from __future__ import annotations

import ast
import io
import json
from pathlib import Path

import numpy as np
import pytest

from safepg import safety_store
from safepg.cli import main
from safepg.envs.lqg import LQG
from safepg.thesis import prefetch, table51_sweep
from safepg.thesis.budget import CHAPTER_EXPERIMENTS, compile_seconds
from safepg.thesis.cartpole_sweep import baseline_experiments
from safepg.thesis.experiments import EXPERIMENTS, get_experiment
from safepg.thesis.scorecard.rows import NEEDED, RANGE_VARIANTS
from safepg.thesis.sweep_settings import SWEEP_SEEDS

BOOK = Path(__file__).resolve().parents[1] / "book"


def _requested_by_cells() -> dict[str, set[str]]:
    """Independently of the prefetch: the experiment names in the list literals of the cells
    that call ``run_experiment`` (``names = [...]``) or pass them to it directly."""
    out: dict[str, set[str]] = {}
    for nb in sorted(BOOK.glob("*.ipynb")):
        for cell in json.loads(nb.read_text())["cells"]:
            src = "".join(cell["source"])
            if cell["cell_type"] != "code" or "run_experiment(" not in src:
                continue
            for node in ast.walk(ast.parse(src)):
                if isinstance(node, ast.List | ast.Tuple):
                    out.setdefault(nb.stem, set()).update(e.value for e in node.elts if isinstance(e, ast.Constant)
                                                          and e.value in EXPERIMENTS)
                if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "run_experiment" and node.args \
                        and isinstance(node.args[0], ast.Constant):
                    out.setdefault(nb.stem, set()).add(node.args[0].value)
    return out


def test_the_list_covers_every_experiment_a_chapter_requests():
    tasks = prefetch.book_tasks(BOOK)
    seeds = {}
    for t in tasks:
        if t.kind == "experiment":
            seeds[t.name] = max(seeds.get(t.name, 0), t.seeds or get_experiment(t.name).seeds)
    requested = _requested_by_cells()
    assert set(requested) >= {"lqg1d", "lqg2d", "cartpole"}
    for chapter, names in requested.items():
        for name in names:
            assert seeds.get(name, 0) >= get_experiment(name).seeds, f"{chapter} runs {name}, not in the list"
    # The chapters' lists as the time budget knows them, the scorecard's (run=True) and the sweep's.
    for names in CHAPTER_EXPERIMENTS.values():
        assert set(names) <= set(seeds)
    for name in (*NEEDED, *RANGE_VARIANTS):
        assert seeds[name] >= get_experiment(name).seeds
    for name in baseline_experiments():
        assert seeds[name] >= SWEEP_SEEDS
    kinds = {t.kind: t for t in tasks}
    assert kinds["table-5.1-sweep"].chapter == "lqg1d" and dict(kinds["table-5.1-sweep"].options) == {"jobs": 2}
    assert kinds["safety-mc"].chapter == "cartpole"
    # Each once, and each warm-started experiment after the one it starts from (as many seeds).
    names = [(t.kind, t.name, t.seeds) for t in tasks]
    assert len(names) == len(set(names))
    order = [t.name for t in tasks]
    warm = 0
    for t in tasks:
        if t.kind == "experiment":
            for c in get_experiment(t.name).configs:
                if c.warm_start:
                    assert order.index(c.warm_start) < order.index(t.name)
                    warm += 1
    assert warm >= 3  # table-5.4, table-5.4-authors and the cart-pole sweep start from a baseline
    # Nothing that no chapter needs: every experiment is requested by a cell or a function the cells call.
    needed = set().union(*requested.values(), NEEDED, RANGE_VARIANTS, baseline_experiments(), {"cartpole-sweep"})
    assert set(seeds) <= needed


def _small(seeds: int = 1) -> prefetch.Task:
    return prefetch.Task("lqg1d", "table-5.1", seeds=seeds, budget=20_000)


def test_plain_lines_then_stored(tmp_path):
    out = io.StringIO()
    assert prefetch.prefetch_experiment(_small(), tmp_path, jobs=1, stream=out, tty=False) == "computed"
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue() and all(line.startswith("run-book: table-5.1: ") for line in lines)
    # Fast runs: the start and the end, no progress line (at most one every 30 s).
    assert len(lines) == 2, lines
    assert lines[0] == "run-book: table-5.1: computing 24 of 24 runs (0 stored)"
    assert lines[1].startswith("run-book: table-5.1: done, 24/24 runs, ") and " trajectories in " in lines[1]
    assert len(list((tmp_path / "table-5.1").glob("*/*/seed-0.npz"))) == 24

    again = io.StringIO()
    assert prefetch.prefetch_experiment(_small(), tmp_path, jobs=1, stream=again, tty=False) == "stored"
    assert again.getvalue() == "run-book: table-5.1: stored (24 runs)\n"

    # One more seed: only the missing runs are computed, the stored ones counted as done.
    more = io.StringIO()
    prefetch.prefetch_experiment(_small(seeds=2), tmp_path, jobs=1, stream=more, tty=False)
    assert more.getvalue().splitlines()[0] == "run-book: table-5.1: computing 24 of 48 runs (24 stored)"


def test_progress_lines_are_rate_limited():
    now = [0.0]
    out = io.StringIO()
    p = prefetch.Progress("exp", 30, 0, 30.0, stream=out, tty=False, interval=30.0, clock=lambda: now[0],
                          ticker=False)
    for _ in range(29):
        now[0] += 4.0
        p.advance(1000, 1.0)
        p.tick()
    now[0] += 4.0
    p.advance(1000, 1.0)
    p.close()
    lines = out.getvalue().splitlines()
    assert lines[0] == "run-book: exp: computing 30 of 30 runs (0 stored)"
    progress = lines[1:-1]
    assert len(progress) == 3  # 120 s of runs: one line at 32 s, 64 s and 96 s
    assert progress[0] == "run-book: exp: 8/30 runs, 8e+03 trajectories, 32s elapsed, about 1m28s left"
    assert lines[-1] == "run-book: exp: done, 30/30 runs, 3e+04 trajectories in 2m00s"
    # Without a unit done, the time left comes from the last build, else is unknown.
    q = prefetch.Progress("exp", 2, 0, 2.0, stream=io.StringIO(), tty=False, previous_s=100.0,
                          clock=lambda: now[0], ticker=False)
    assert q.left() == pytest.approx(100.0)


def test_tty_bar_shows_runs_trajectories_and_time_left():
    out = io.StringIO()
    p = prefetch.Progress("exp", 4, 1, 3.0, stream=out, tty=True, ticker=False)
    p.advance(5000, 1.0)
    p.close()
    text = out.getvalue()
    assert "run-book: exp: 2/4 runs" in text and "5e+03 trajectories" in text and "left" in text
    assert text.rstrip().splitlines()[-1].startswith("run-book: exp: done, 2/4 runs")


def test_stored_checks_agree_with_the_caches(tmp_path, monkeypatch):
    thetas = np.array([-0.3, -0.4, -0.4, -0.5])[:, None]
    env = LQG.thesis_1d(clip=False, horizon=150)
    assert not safety_store.is_measured(tmp_path, env, thetas, 1.0, (300, 600))
    safety_store.measure_runs(env, [thetas], 1.0, tmp_path, looks=(300, 600))
    assert safety_store.is_measured(tmp_path, env, thetas, 1.0, (300, 600))
    assert not safety_store.is_measured(tmp_path, env, thetas, 1.0, (300, 1200))

    plan = ((table51_sweep.DEFAULT, -0.575),)
    monkeypatch.setattr(table51_sweep, "CHAPTER_PLAN", plan)
    assert not prefetch._sweep_path(tmp_path, 1, 10_000).exists()
    table51_sweep.sweep_paths(plan, seeds=1, budget=10_000, root=tmp_path)
    assert prefetch._sweep_path(tmp_path, 1, 10_000).exists()


def test_cli_lists_what_the_chapters_need(capsys):
    assert main(["run-book", "--list"]) == 0
    out = capsys.readouterr().out
    assert "lqg1d        table-5.1-sweep" in out and "cartpole     safety-mc" in out
    assert "cartpole-baseline-gamma=0.95 (2 seeds)" in out


def test_whole_book_run_on_a_small_plan(tmp_path, monkeypatch, capsys):
    """prefetch() with the CLI's stream: plain lines when stdout is not a terminal, then stored."""
    tasks = [_small()]
    first = prefetch.prefetch(BOOK, tmp_path, jobs=1, tasks=tasks)
    second = prefetch.prefetch(BOOK, tmp_path, jobs=1, tasks=tasks)
    assert first == {"table-5.1": "computed"} and second == {"table-5.1": "stored"}
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("run-book: 1 computation the chapters need, stored in ")
    assert "run-book: table-5.1: stored (24 runs)" in lines
    assert lines[-1].startswith("run-book: 0 computed, 1 already stored, in ")


def test_kernels_compile_once_for_what_is_left_to_compute(tmp_path, monkeypatch):
    """Before the tasks, campaign.compile_once gets the configs with runs to compute, and only those."""
    calls = []

    def compile_once(configs, jobs=-1):
        calls.append([c.name for c in configs])
        return len(configs)

    monkeypatch.setattr(prefetch.campaign, "compile_once", compile_once)
    tasks = [_small(), prefetch.Task("lqg2d", "table-5.3", seeds=1, budget=20_000)]
    prefetch.prefetch_experiment(tasks[0], tmp_path, jobs=1, stream=io.StringIO(), tty=False)
    out = io.StringIO()
    prefetch.prefetch(BOOK, tmp_path, jobs=1, stream=out, tty=False, tasks=tasks)
    assert calls == [["adaptive", "N=1000", "N=100"]]
    assert out.getvalue().splitlines()[1].startswith("run-book: kernels compiled once, each task family in one worker")
    again = io.StringIO()
    prefetch.prefetch(BOOK, tmp_path, jobs=1, stream=again, tty=False, tasks=tasks)
    assert calls[-1] == [] and "compiled" not in again.getvalue()
    # The time it took, once: bench_book.py reads it.
    timing = (tmp_path / prefetch.COMPILE_ONCE / "timing.jsonl").read_text().splitlines()
    assert len(timing) == 1 and json.loads(timing[0])["runs"] == 3
    assert compile_seconds(tmp_path) == json.loads(timing[0])["seconds"]


def test_experiments_dispatched_together_store_what_each_alone_stores(tmp_path):
    """Several experiments in one dispatch (a later one for an experiment that warm-starts from
    another): the same run files as one experiment at a time, a line as each is done, and each
    experiment's share of the time."""
    tasks = [_small(), prefetch.Task("cartpole", "cartpole-baseline-authors", seeds=1),
             prefetch.Task("cartpole", "table-5.4-authors", seeds=1, budget=20_000)]
    out = io.StringIO()
    got = prefetch.prefetch_experiments(tasks, tmp_path / "together", jobs=2, stream=out, tty=False)
    assert got == dict.fromkeys(["table-5.1", "cartpole-baseline-authors", "table-5.4-authors"], "computed")
    lines = out.getvalue().splitlines()
    assert lines[0] == "run-book: 3 experiments: computing 27 of 27 runs (0 stored)"
    for name, runs in (("table-5.1", 24), ("cartpole-baseline-authors", 1), ("table-5.4-authors", 2)):
        assert sum(line.startswith(f"run-book: {name}: done, {runs}/{runs} runs, ") for line in lines) == 1, lines
    assert lines[-1].startswith("run-book: 3 experiments: done, 27/27 runs, ")
    for t in tasks:
        prefetch.prefetch_experiment(t, tmp_path / "alone", jobs=1, stream=io.StringIO(), tty=False)
    together = sorted((tmp_path / "together").rglob("*.npz"))
    assert len(together) == 27
    for path in together:
        a, b = np.load(path), np.load(tmp_path / "alone" / path.relative_to(tmp_path / "together"))
        assert a.files == b.files and all(a[k].tobytes() == b[k].tobytes() for k in a.files), path
    shares = [json.loads(line)["seconds"] for t in tasks
              for line in (tmp_path / "together" / t.name / "timing.jsonl").read_text().splitlines()]
    assert len(shares) == 3 and all(s > 0 for s in shares)
    again = io.StringIO()
    assert set(prefetch.prefetch_experiments(tasks, tmp_path / "together", jobs=2, stream=again,
                                             tty=False).values()) == {"stored"}
    assert again.getvalue().splitlines() == ["run-book: table-5.1: stored (24 runs)",
                                             "run-book: cartpole-baseline-authors: stored (1 runs)",
                                             "run-book: table-5.4-authors: stored (2 runs)"]


def test_the_comparison_records_its_time_under_run_book_only(tmp_path, monkeypatch):
    """run-book's comparison writes the timing lines budget.comparison_work reads (the comparison's folder and
    its step search's); run_comparison called as the pendulum chapter calls it writes none."""
    from dataclasses import replace

    from safepg.comparison import StepSearch, pendulum_comparison, run_comparison
    from safepg.thesis.budget import comparison_work
    from safepg.thesis.campaign import TIMING_FILE

    full = pendulum_comparison(seeds=2, budget=800, episodes=40)
    small = replace(full, adaptive=full.adaptive[1:2], batch_sizes=(100,),
                    search=StepSearch((1e-4,), seeds=1, episodes=20), looks=(100,))
    run_comparison(small, tmp_path / "library", jobs=1)
    assert list((tmp_path / "library").rglob("*.npz")) and not list((tmp_path / "library").rglob(TIMING_FILE))
    monkeypatch.setattr(prefetch, "_comparison", lambda task: small)
    task = prefetch.Task("pendulum", prefetch.COMPARISON, "comparison")
    prefetch.prefetch_comparison(task, tmp_path / "book", jobs=1, stream=io.StringIO(), tty=False)
    folder = tmp_path / "book" / small.name
    assert sorted(tmp_path.rglob(TIMING_FILE)) == [folder / "search" / TIMING_FILE, folder / TIMING_FILE]
    # The adaptive runs with the search, then the fixed batches: two lines in the comparison's folder.
    assert len((folder / TIMING_FILE).read_text().splitlines()) == 2
    assert comparison_work(tmp_path / "book").seconds > 0


def test_one_experiment_asked_twice_is_computed_and_counted_once(tmp_path, monkeypatch):
    """Two chapters may ask for one experiment at two seed counts (the scorecard's cart-pole baseline at
    5 and 10): the larger count is computed, each seed once, and the line counts each run once."""
    computed = []
    compute = prefetch.runner._compute_task

    def counting(i, cfg, seed, theta0, single_thread):
        computed.append((cfg.name, seed))
        return compute(i, cfg, seed, theta0, single_thread)

    monkeypatch.setattr(prefetch.runner, "_compute_task", counting)
    tasks = [_small(1), _small(2), prefetch.Task("cartpole", "cartpole-baseline-authors", seeds=1)]
    out = io.StringIO()
    got = prefetch.prefetch_experiments(tasks, tmp_path, jobs=1, stream=out, tty=False)
    assert got == dict.fromkeys(["table-5.1", "cartpole-baseline-authors"], "computed")
    lines = out.getvalue().splitlines()
    assert lines[0] == "run-book: 2 experiments: computing 49 of 49 runs (0 stored)"
    assert lines[-1].startswith("run-book: 2 experiments: done, 49/49 runs, ")
    assert len(computed) == len(set(computed)) == 49


def test_an_interrupted_task_says_stopped(tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(prefetch, "run_experiment", interrupted)
    out = io.StringIO()
    with pytest.raises(KeyboardInterrupt):
        prefetch.prefetch_experiment(_small(), tmp_path, jobs=1, stream=out, tty=False)
    assert out.getvalue().splitlines()[-1].startswith("run-book: table-5.1: stopped, 0/24 runs, 0 trajectories in ")
