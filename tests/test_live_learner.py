"""The live batch-size explorer's Python side (safepg/thesis/explorers/live_learner.py): the page it renders,
the stored runs it embeds and its Python twin. The JavaScript learner itself is tested
against safepg in tests/test_learner_js.py, the page in tests/test_browser_learner.py."""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest

from conftest import import_or_fail
from safepg.envs.lqg import LQG
from safepg.learning import LearningRecord
from safepg.thesis.experiments import get_experiment, t52_name
from safepg.thesis.explorers.js_tasks import lqg_task_data
from safepg.thesis.explorers.live_learner import (
    BUDGETS,
    STILL,
    learner_js,
    live_batch_size_explorer,
    task_data,
    theta_moved,
)

VACUOUS = "the improvement ratio carries no information"


def fake_record(batch_sizes: list[int], seed: int) -> LearningRecord:
    """A record with the given batch sizes and made-up numbers (the overlay only reads them)."""
    rng = np.random.default_rng(seed)
    n = np.asarray(batch_sizes, dtype=np.int64)
    I = n.size
    theta = np.cumsum(np.concatenate([[0.0], -rng.uniform(0, 1e-3, I)]))[:, None]
    return LearningRecord(batch_size=n, alpha=rng.uniform(1e-6, 1e-4, I), coordinate=np.zeros(I, np.int64),
                          theta=theta, J=-50 + np.arange(I + 1) / I, J_hat=rng.uniform(-20, -10, I),
                          grad=rng.standard_normal((I, 1)), eps=np.ones(I), safe=np.ones(I, bool))


@pytest.fixture(scope="module")
def stored():
    exp = get_experiment("table-5.2")
    good = exp.config(t52_name("gpomdp", "bernstein", True, 0.95))
    hoeffding = exp.config(t52_name("gpomdp", "hoeffding", False, 0.95))
    other = replace(hoeffding, name="range",
                    method=replace(hoeffding.method, error=replace(hoeffding.method.error, range=1280.0)))
    sizes = [100] + [50_000] * 100  # 5.0001e6 trajectories: past the largest budget
    records = {good.name: [fake_record(sizes, 0), fake_record([100] + [70_000] * 60, 1)],
               other.name: [fake_record(sizes, 2)]}
    return records, [good, other]


def test_page_is_self_contained():
    html = live_batch_size_explorer().to_html()
    urls = set(re.findall(r"https?://[^\s\"'`)]+", html)) - {"http://www.w3.org/2000/svg"}
    assert not urls, urls  # no CDN, no request: only the SVG namespace name
    assert "<script src" not in html and "import(" not in html
    assert "new Worker(url)" in html and "new Blob(" in html
    assert json.dumps(learner_js()) in html  # the learner travels inside the page


def test_task_is_the_thesis_1d_lqg():
    t = task_data()
    assert t == lqg_task_data(LQG.thesis_1d())  # the task every page learner reads, with m = 1
    assert (t["kind"], t["dim"], t["gamma"], t["H"], t["stateBound"], t["actionBound"], t["clip"]) == (
        "lqg", 1, 0.9, 20, 2.0, 2.0, True)
    assert (t["rewardBound"], t["featureBound"], t["actionVolume"]) == (4.0, 2.0, 4.0)
    with pytest.raises(ValueError, match="one-dimensional"):
        task_data(LQG.thesis_2d())


def test_overlay_embeds_matching_stored_runs(stored):
    records, configs = stored
    ex = live_batch_size_explorer(records, configs)
    runs = ex.data["runs"]
    assert list(runs) == ["gpomdp-bernstein-er-delta=0.95-clipped"]  # the reconstructed-range run is not rerunnable
    run = runs["gpomdp-bernstein-er-delta=0.95-clipped"]
    # Seed means per iteration, cut where the mean batch start reaches the largest budget.
    assert run["iteration"][0] == 1 and run["batch_size"][0] == 100
    assert run["batch_size"][1] == 60_000.0 and max(run["start"]) < BUDGETS[-1]
    # Upsilon-bar of the first B trajectories: each batch weighs by its part inside them.
    B = 100_000
    expected = []
    for r in records[configs[0].name]:
        start = np.concatenate([[0], np.cumsum(r.batch_size)[:-1]])
        w = np.clip(B - start, 0, r.batch_size)
        expected.append(w @ r.J_hat / B)
    assert run["budgets"][str(B)]["upsilon_bar"] == pytest.approx(np.mean(expected), rel=5e-6)  # 6 digits
    assert run["budgets"][str(B)]["iterations"] == 3.0  # 100 + 50000 + (part of) 50000, and 100 + 70000
    # Embedded floats carry 6 significant digits at most.
    for v in run["J"] + run["alpha"]:
        assert v is None or float(f"{v:.6g}") == v


def test_python_twin(stored):
    records, configs = stored
    ex = live_batch_size_explorer(records, configs)
    p = {**ex.defaults(), "budget": "10000"}
    res = ex.compute_py(p)
    v = res["values"]
    assert v["adaptive"]["trajectories"] == 10_000 and v["adaptive"]["first_batches"][0] == 100
    assert v["vanilla"]["first_batches"] == [1000, 1000, 1000] and v["vanilla"]["iterations"] == 10
    assert v["thesis"]["found"] and v["thesis"]["key"] == "gpomdp-bernstein-er-delta=0.95-clipped"
    assert [len(res["plots"][k]["series"]) for k in ("N", "J", "alpha")] == [3, 3, 3]
    assert res["plots"]["J"]["series"][0]["x"][-1] <= 10_000
    assert not ex.compute_py({**p, "sigma": 0.5, "vanilla_n": "off"})["values"]["thesis"]["found"]
    assert ex.compute_py({**p, "vanilla_n": "off"})["values"]["vanilla"] is None
    # The same seed gives the same run; another seed another one.
    again = ex.compute_py(p)["values"]["adaptive"]
    assert again == v["adaptive"] and ex.compute_py({**p, "seed": 1.0})["values"]["adaptive"] != v["adaptive"]


def test_interactive_builds_widgets():
    import_or_fail("ipywidgets")
    ex = live_batch_size_explorer()
    calls = []
    # The view computes the defaults at once, in its worker thread: a stub stands in for the learning run.
    ex.compute_py = lambda p, progress=None: calls.append(p) or {"plots": {k: {"series": [{"x": [1, 2], "y": [1, 2]}]}
                                                                           for k in ("N", "J", "alpha")}, "text": ""}
    view = ex.interactive()
    try:
        assert view.wait(60)
        assert calls and calls[0]["bound"] == "bernstein-er" and view.drawn == calls[0]
        assert {"delta", "sigma", "bound", "estimator", "baseline", "score", "budget", "seed"} <= set(view.controls)
        sliders = [c for c in view.controls.values() if hasattr(c, "continuous_update") and hasattr(c, "step")]
        assert sliders and not any(c.continuous_update for c in sliders)  # each move is a learning run: on release
    finally:
        view.close()


def test_python_twin_reports_progress_and_stops_when_told():
    ex = live_batch_size_explorer()
    seen = []
    res = ex.compute_py({**ex.defaults(), "budget": "10000"}, progress=lambda f, m: seen.append((f, m)))
    # Two runs of 10^4 trajectories: Algorithm 4.1 fills the first half, vanilla PG the second.
    assert seen[0][1].startswith("Algorithm 4.1: 100 / 10,000") and seen[-1] == (1.0, "vanilla PG: 10,000 / 10,000 "
                                                                                     "trajectories")
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))
    assert res["values"] == ex.compute_py({**ex.defaults(), "budget": "10000"})["values"]  # reporting changes nothing

    class Stop(Exception):
        pass

    def stop(fraction: float, message: str) -> None:
        raise Stop

    with pytest.raises(Stop):
        ex.compute_py({**ex.defaults(), "budget": "3000000"}, progress=stop)


def test_theta_moved_is_the_furthest_theta_got_from_theta_0():
    assert theta_moved(np.array([[0.0], [-0.2], [-0.5], [-0.4]])) == 0.5
    assert theta_moved(np.array([[0.1], [0.3], [0.1]])) == pytest.approx(0.2)  # out and back: it moved
    assert theta_moved(np.array([[0.0]])) == 0.0  # no iteration
    assert theta_moved(np.array([[0.0, 1.0], [0.5, 0.0]])) == 1.0  # the largest component


def test_frozen_run_says_its_ratio_carries_no_information():
    """Hoeffding with its theoretical range: eps(N) >= |g| at N = 100, so the first update is
    no step; at 10^4 trajectories the run stops before a second one could move theta."""
    ex = live_batch_size_explorer()
    res = ex.compute_py({**ex.defaults(), "bound": "hoeffding", "budget": "10000", "vanilla_n": "off"})
    a = res["values"]["adaptive"]
    assert a["theta_moved"] == 0.0 and a["ratio_vacuous"] and a["improvement_ratio"] == 1.0  # 100% of no-ops
    first = res["text"].splitlines()[0]
    assert first.startswith("Algorithm 4.1: 2 iterations, 10000 trajectories, Upsilon-bar ")
    assert first.endswith("; theta moved by 0, less than 0.1% of the way to theta* = -0.59: " + VACUOUS + ".")
    assert "improvement ratio 100" not in res["text"]


def test_run_moving_too_little_is_flagged_with_its_movement():
    """The reviewer's run (Hoeffding, theoretical range, 10^6 trajectories, seed 0): two steps of
    alpha ~ 3.7e-6 move theta by 7e-5, 0.01% of the way to theta*; J moves by 0.07 of its 43."""
    ex = live_batch_size_explorer()
    res = ex.compute_py({**ex.defaults(), "bound": "hoeffding", "budget": "1000000", "vanilla_n": "off"})
    a = res["values"]["adaptive"]
    assert a["iterations"] == 3 and 0 < a["theta_moved"] < STILL * 0.588 and a["ratio_vacuous"]
    assert f"theta moved by {a['theta_moved']:.1e}".replace("e-05", "e-5") in res["text"]
    assert VACUOUS in res["text"].splitlines()[0]


def test_moving_run_states_its_ratio_and_every_objective():
    ex = live_batch_size_explorer()
    res = ex.compute_py({**ex.defaults(), "budget": "10000"})  # Bernstein (e.r.): theta moves from the first batch
    lines = res["text"].splitlines()
    v = res["values"]
    for name, line in (("adaptive", lines[0]), ("vanilla", lines[1])):
        assert not v[name]["ratio_vacuous"] and v[name]["theta_moved"] > STILL * 0.588
        assert v[name]["theta_moved"] == pytest.approx(abs(v[name]["theta_final"]))  # from theta_0 = 0, one way
        assert VACUOUS not in line
        assert line.endswith(f"; theta moved by {v[name]['theta_moved']:.4f}, improvement ratio "
                             f"{100 * v[name]['improvement_ratio']:.2f}%."), line
    assert lines[1].startswith("vanilla PG: 10 iterations, 10000 trajectories")
    assert lines[-1] == ("Upsilon-bar: the simulated return (clipped states and actions, 20 steps, discounted by "
                         "gamma = 0.9), averaged over all trajectories. J and the improvement ratio (share of updates "
                         "after which J did not fall): the closed-form J(theta) of the J plot (infinite horizon, "
                         "no clipping).")
