"""The cart-pole live explorer (safepg/thesis/explorers/cartpole_learner.py): each checkbox maps to
the right safepg option or CartPole field, all of them together are table-5.4-authors' adaptive
run, none of them table-5.4's; the page object (static/cartpole_page.js, under Node) sends the
engine the same settings and draws from the same runs what the Python twin draws. The page in
Chromium: tests/test_browser_live_ch5.py."""

from __future__ import annotations

import json

import numpy as np
import pytest
from ch5_node import run_page

from safepg.envs.cartpole import CartPole
from safepg.learning import learn
from safepg.options import FixedStep
from safepg.thesis.authors import cartpole_theta_star
from safepg.thesis.experiments import get_experiment
from safepg.thesis.explorers.cartpole_learner import (
    SETTINGS,
    adaptive_method,
    cartpole_explorer,
    cartpole_result,
    cartpole_task,
    task_fields,
    vanilla_method,
)
from safepg.thesis.explorers.ch5_live import record_c, record_trace
from safepg.thesis.explorers.js_tasks import cartpole_task_data
from safepg.thesis.explorers.option_names import learner_options

needs_node = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)
BOXES = [name for name, *_ in SETTINGS]
#: Each box: the CartPole fields and the options of Algorithm 4.1 it sets (under the page learner's
#: names, option_names.learner_options), and nothing else.
EXPECTED = {"gamma09": ({"gamma": 1.0, "constants_gamma": 0.9}, {}),
            "batch_constants": ({}, {"batchConstants": True}),
            "max_stats": ({}, {"maxima": True}),
            "unguarded": ({}, {"unguardedStep": True}),
            "first1000": ({}, {"first": 1000, "nMin": 10}),
            "deg12": ({"angle_threshold_deg": 12.0}, {}),
            "ml005": ({"polemass_length": 0.05}, {})}


@pytest.fixture(scope="module")
def explorer():
    return cartpole_explorer(baseline=[-0.97, 2.07, 2.42, 5.27])


def test_each_box_sets_its_option_and_only_it(explorer):
    p0 = explorer.defaults()
    assert not any(p0[b] for b in BOXES) and set(EXPECTED) == set(BOXES)
    base_opts, base_task = learner_options(adaptive_method(p0)), CartPole.thesis_doubled()
    assert task_fields(p0) == {} and cartpole_task(p0) == base_task
    for box, (fields, options) in EXPECTED.items():
        p = {**p0, box: True}
        assert task_fields(p) == fields, box
        assert cartpole_task(p) == CartPole.thesis_doubled(**fields)
        changed = {k: v for k, v in learner_options(adaptive_method(p)).items() if base_opts[k] != v}
        assert changed == options, box


def test_no_box_is_table_5_4_and_every_box_is_table_5_4_authors(explorer):
    p0 = explorer.defaults()
    thesis = get_experiment("table-5.4").config("adaptive")
    assert adaptive_method(p0) == thesis.method
    assert cartpole_task(p0).setting_name() == thesis.task == "cartpole-doubled"
    authors = get_experiment("table-5.4-authors-theta-star").config("adaptive")
    p1 = {**p0, **{b: True for b in BOXES}}
    method = adaptive_method(p1)
    assert (method.error, method.batches, method.departures) == (
        authors.method.error, authors.method.batches, authors.method.departures)
    assert cartpole_task(p1).setting_name() == authors.task
    assert explorer.data["starts"]["theta_star"] == list(authors.theta0) == cartpole_theta_star().tolist()
    van = get_experiment("table-5.4").config("N=4000")
    assert vanilla_method() == van.method  # the fixed-step method is table-5.4's, whatever the boxes
    assert (van.method.batch_size, van.method.step) == (4000, FixedStep(0.01))


def test_presets_and_starts(explorer):
    presets = explorer.presets
    assert presets["authors"][1] == {**{b: True for b in BOXES}, "start": "theta_star"}
    assert presets["thesis"][1] == {**{b: False for b in BOXES}, "start": "baseline"}
    assert explorer.defaults()["start"] == "baseline"
    assert explorer.data["starts"]["baseline"] == [-0.97, 2.07, 2.42, 5.27]
    # The embedded tasks: one per combination of the boxes that change the task, as js_tasks builds them.
    assert len(explorer.data["tasks"]) == 8
    p = {**explorer.defaults(), "gamma09": True, "ml005": True}
    key = "".join("1" if p[b] else "0" for b in explorer.data["task_boxes"])
    assert explorer.data["tasks"][key] == cartpole_task_data(cartpole_task(p))


@needs_node
def test_page_sends_the_engine_the_twins_settings(explorer):
    p0 = explorer.defaults()
    moves = [{}, *({b: True} for b in BOXES), {b: True for b in BOXES} | {"start": "theta_star"},
             {"delta": 0.5, "sigma": 0.75, "budget": "50000", "seed": 4.0}]
    out = run_page("cartpole_page.js", "safepgCartpolePage",
                   [{"p": {**p0, **m}, "data": explorer.data, "configs": True} for m in moves])
    for m, got in zip(moves, out):
        p = {**p0, **m}
        runs = {r["name"]: r["cfg"] for r in got["configs"]["runs"]}
        completed = {r["name"]: c for r, c in zip(got["configs"]["runs"], got["completed"])}
        assert got["configs"]["task"] == cartpole_task_data(cartpole_task(p))
        for name, method in (("adaptive", adaptive_method(p)), ("vanilla", vanilla_method())):
            cfg = runs[name]
            assert cfg["sigma"] == p["sigma"] and cfg["seed"] == round(p["seed"])
            assert cfg["theta0"] == explorer.data["starts"][p["start"]] and cfg["budget"] == int(p["budget"])
            # The page's configuration, completed as the learner completes it, is the method's own.
            options = learner_options(method)
            assert {k: completed[name][k] for k in options} == options, (m, name)
            if name == "vanilla":
                assert cfg["stopOnDivergence"] is True  # learn() stops a diverging vanilla run


def traces_of(p, data, budget=3000):
    task, theta0 = cartpole_task(p), np.asarray(data["starts"][p["start"]])
    method = adaptive_method(p)
    rec = learn(task, method, theta0, 1.0, budget=budget, rng=np.random.default_rng(0))
    van = learn(task, vanilla_method(), theta0, 1.0, budget=8000, rng=np.random.default_rng(1))
    return {"adaptive": record_trace(rec, record_c(rec, method.departures.batch_constants)),
            "vanilla": record_trace(van)}


@needs_node
def test_page_draws_what_the_twin_draws_from_the_same_runs(explorer):
    """Given the same runs, the page's result (plots, values, the summary's words) is the twin's, exactly:
    unticked, theta is frozen and the summary says so; all boxes ticked, theta_xdot moves."""
    p0 = explorer.defaults()
    p1 = {**p0, **explorer.presets["authors"][1]}
    cases = [(p, traces_of(p, explorer.data)) for p in (p0, p1)]
    out = run_page("cartpole_page.js", "safepgCartpolePage",
                   [{"p": p, "data": explorer.data, "traces": t} for p, t in cases])
    for (p, t), got in zip(cases, out):
        assert got["result"] == json.loads(json.dumps(cartpole_result(p, t, explorer.data)))
    frozen, moving = out[0]["result"], out[1]["result"]
    assert frozen["values"]["adaptive"]["frozen"] and "theta did not move: " in frozen["text"]
    assert not moving["values"]["adaptive"]["frozen"] and "theta moved: " in moving["text"]
    assert moving["values"]["adaptive"]["theta_moved"][1] > 1e-4  # theta_xdot


def test_kernel_twin_structure(explorer):
    seen = []
    res = explorer.compute_py({**explorer.defaults(), "budget": "10000"}, progress=lambda f, m: seen.append(f))
    assert set(res["plots"]) == {"theta", "ret", "N", "alpha", "c"}
    assert set(res["values"]) == {"adaptive", "vanilla", "done"}
    a = res["values"]["adaptive"]
    assert a["frozen"] and a["trajectories"] == 10_000 and a["c_min"] == a["c_max"] > 1e7
    assert "theta did not move: " in res["text"]
    assert [s["label"] for s in res["plots"]["theta"]["series"]] == [
        "theta_x - theta_x_0", "theta_xdot - theta_xdot_0", "theta_beta - theta_beta_0",
        "theta_betadot - theta_betadot_0", "+/-1.0e-6: did not move", ""]
    assert seen and seen[-1] == pytest.approx(1.0)
