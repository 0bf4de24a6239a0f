"""The campaign's budget: counts from the store, recorded times, floor and ratio."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from safepg.runner import run_configs
from safepg.thesis import budget
from safepg.thesis.campaign import TIMING_FILE
from safepg.thesis.experiment_store import experiment_folder, run_experiment
from safepg.thesis.experiments import get_experiment, scaled

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    root = tmp_path_factory.mktemp("store")
    lqg = scaled(get_experiment("table-5.3"), seeds=2, budget=3000)
    cart = scaled(get_experiment("cartpole-baseline"), seeds=1, budget=8000)
    for exp in (lqg, cart):
        run_experiment(exp, root=root, jobs=1, progress=False, timing=True)  # as run-book computes them
    return root, lqg, cart


def test_lqg_counts_follow_from_the_configs(store, monkeypatch):
    root, lqg, _ = store
    monkeypatch.setattr(budget, "get_experiment", lambda name: lqg)
    w = budget.experiment_work("table-5.3", "lqg2d", root)
    traj = len(lqg.configs) * lqg.seeds * 3000  # every run uses its whole budget
    assert (w.trajectories, w.steps, w.normals, w.uniforms) == (traj, 20 * traj, 2 * 20 * traj, 2 * traj)
    lines = (experiment_folder(lqg, root) / TIMING_FILE).read_text().splitlines()
    assert len(lines) == 1 and json.loads(lines[0])["runs"] == len(lqg.configs) * lqg.seeds
    assert w.seconds == pytest.approx(json.loads(lines[0])["seconds"]) and w.seconds > 0
    run_experiment(lqg, root=root, jobs=1, progress=False, timing=True)  # nothing left to compute: no new line
    assert len((experiment_folder(lqg, root) / TIMING_FILE).read_text().splitlines()) == 1


def test_timing_is_written_only_when_asked(tmp_path, monkeypatch):
    """The runner and the library write no timing file; run-book's ``timing=True`` does, once per
    folder that computed runs (and none where the runs were stored)."""
    exp = scaled(get_experiment("table-5.3"), seeds=1, budget=2000)
    run_configs(exp.configs, 1, tmp_path / "runner", jobs=1, progress=False)
    run_experiment(exp, root=tmp_path / "library", jobs=1, progress=False)
    for folder in ("runner", "library"):
        assert len(list((tmp_path / folder).rglob("*.npz"))) == len(exp.configs)
        assert not list((tmp_path / folder).rglob(TIMING_FILE)), folder
    monkeypatch.setattr(budget, "get_experiment", lambda name: exp)
    assert budget.experiment_work(exp.name, "lqg2d", tmp_path / "library").seconds is None
    run_experiment(exp, root=tmp_path / "library", jobs=1, progress=False, timing=True)  # all stored: no time
    assert not list((tmp_path / "library").rglob(TIMING_FILE))

    run_experiment(exp, root=tmp_path / "book", jobs=1, progress=False, timing=True)
    assert [p.relative_to(tmp_path) for p in tmp_path.rglob(TIMING_FILE)] == [Path("book", exp.name, TIMING_FILE)]
    line = json.loads((experiment_folder(exp, tmp_path / "book") / TIMING_FILE).read_text())
    assert line["runs"] == len(exp.configs) and line["seconds"] > 0
    assert budget.experiment_work(exp.name, "lqg2d", tmp_path / "book").seconds == pytest.approx(line["seconds"])


def test_cartpole_counts_one_normal_per_lived_step(store, monkeypatch):
    root, _, cart = store
    monkeypatch.setattr(budget, "get_experiment", lambda name: cart)
    w = budget.experiment_work("cartpole-baseline", "cartpole", root)
    rec = run_experiment(cart, root=root, jobs=1, progress=False)[cart.configs[0].name][0]
    traj = int(rec.batch_size.sum())
    assert w.trajectories == traj and w.uniforms == 4 * traj
    assert traj <= w.steps <= 1000 * traj and w.normals == w.steps


def test_safety_measurements_count_the_steps_they_stored(tmp_path) -> None:
    folder = tmp_path / budget.SAFETY_MC
    folder.mkdir()

    def store(name: str, task: str, rollouts: list[int], steps: int | None, seconds: float) -> None:
        outcomes = {"rollouts": rollouts, **({} if steps is None else {"steps": steps})}
        (folder / name).write_text(json.dumps({"key": json.dumps([task]), "outcomes": outcomes, "seconds": seconds}))

    store("a.json", "CartPole(pole_length=2.0)", [100, 300], 70_000, 1.5)
    store("b.json", "CartPole(pole_length=2.0)", [100], 19_000, 0.5)
    store("c.json", "LQG(dim=2)", [200], 8_000, 0.25)
    (cart, lqg) = sorted(budget.safety_work(tmp_path), key=lambda w: w.chapter)
    assert (cart.trajectories, cart.steps, cart.normals, cart.uniforms, cart.seconds) == (
        1000, 89_000, 89_000, 4000, 2.0)
    assert lqg.normals is None and lqg.seconds == 0.25  # the LQG's random numbers are not counted
    store("d.json", "CartPole(pole_length=2.0)", [100], None, 0.5)  # stored before steps were counted
    cart = next(w for w in budget.safety_work(tmp_path) if w.chapter == "cartpole")
    assert cart.steps is None and cart.normals is None and cart.trajectories == 1200


def test_rows_floor_and_ratio() -> None:
    works = [budget.Work("a", "lqg1d", 10, 200, 200, 10, 4.0), budget.Work("b", "lqg1d", 5, 100, 100, 5, None),
             budget.Work("safety-mc", "cartpole", 8, None, None, None, 3.0)]
    out = budget.budget_rows(works, normal_rate=100.0, uniform_rate=10.0, chapter_seconds={"lqg1d": 9.0})
    a, b, mc = out["experiments"]
    assert a["floor_s"] == pytest.approx(200 / 100 + 10 / 10) and a["ratio"] == pytest.approx(4.0 / 3.0, abs=0.01)
    assert b["ratio"] is None and mc["floor_s"] is None and mc["ratio"] is None
    lqg1d, cartpole = out["chapters"]
    assert lqg1d["floor_s"] == pytest.approx(3.0 + 1.5) and lqg1d["campaign_s"] == 4.0 and lqg1d["notebook_s"] == 9.0
    assert cartpole["ratio"] is None  # nothing with known random numbers: no floor
    table = budget.markdown(out)
    assert "| lqg1d | 15 |" in table and "| safety-mc | cartpole |" in table


def test_a_chapter_s_floor_by_its_bare_step() -> None:
    """With a bare step's rate, a chapter's floor is its steps at that rate (plus its uniforms); the
    other chapters keep their normals' floor."""
    works = [budget.Work("c", "cartpole", 10, 300, 300, 40, 6.0), budget.Work("a", "lqg1d", 10, 200, 200, 10, 4.0)]
    out = budget.budget_rows(works, normal_rate=100.0, uniform_rate=10.0, step_rates={"cartpole": 50.0})
    c, a = out["experiments"]
    assert c["floor_s"] == pytest.approx(300 / 50 + 40 / 10) and c["ratio"] == pytest.approx(0.6)
    assert a["floor_s"] == pytest.approx(200 / 100 + 10 / 10)


def _notebook_names(chapter: str) -> list[str]:
    """The experiment names of the chapter's ``names = [...]`` cell."""
    cells = json.loads((ROOT / "book" / f"{chapter}.ipynb").read_text())["cells"]
    for c in cells:
        for node in ast.walk(ast.parse("".join(c["source"]))) if c["cell_type"] == "code" else ():
            if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", None) == "names":
                return list(ast.literal_eval(node.value))
    raise AssertionError(f"no names = [...] cell in {chapter}")


@pytest.mark.parametrize("chapter", list(budget.CHAPTER_EXPERIMENTS))
def test_chapters_list_what_their_notebooks_run(chapter: str) -> None:
    names = _notebook_names(chapter)
    assert set(names) <= set(budget.CHAPTER_EXPERIMENTS[chapter])
    for name in budget.CHAPTER_EXPERIMENTS[chapter]:
        get_experiment(name)  # every listed name is an experiment
