"""The 2-D LQG live explorers (safepg/thesis/explorers/lqg2d_learner.py): the page they render, the
settings each control maps to (against the experiments' registry), and the page objects
(static/lqg2d_page.js, run under Node) against their Python twins. The page in Chromium:
tests/test_browser_live_ch5.py."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from ch5_node import run_page

from safepg.learning import learn
from safepg.options import Departures, ErrorModel, SafeStep, Vanilla
from safepg.thesis.experiments import get_experiment
from safepg.thesis.explorers.ch5_live import learner_source, record_c, record_trace
from safepg.thesis.explorers.lqg2d_learner import (
    adaptive_configs,
    adaptive_result,
    authors_2d,
    lqg2d_adaptive_explorer,
    lqg2d_env,
    lqg2d_steps_explorer,
    steps_configs,
    steps_result,
)
from safepg.thesis.explorers.option_names import learner_options

needs_node = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)


@pytest.fixture(scope="module")
def steps():
    return lqg2d_steps_explorer()


@pytest.fixture(scope="module")
def adaptive():
    return lqg2d_adaptive_explorer()


def test_pages_are_self_contained(steps, adaptive):
    for ex in (steps, adaptive):
        html = ex.to_html()
        urls = set(re.findall(r"https?://[^\s\"'`)]+", html)) - {"http://www.w3.org/2000/svg"}
        assert not urls, urls
        assert "<script src" not in html and "new Blob(" in html and "new Worker(url)" in html
        assert json.dumps(learner_source()) in html  # the engine travels inside the page
        assert ex.data["task"]["kind"] == "lqg" and ex.data["task"]["dim"] == 2
        assert ex.data["task"]["gamma"] == 0.9  # lqg2d-gamma0.9, as the Section 5.2 experiments run


def test_steps_defaults_are_the_registrys(steps):
    """The defaults are figures-5.5-5.6's settings; each run is vanilla_pg with the SafeStep of its kind."""
    exp = get_experiment("figures-5.5-5.6")
    p = steps.defaults()
    runs = steps_configs(p)
    assert list(runs) == ["scalar", "coordinate"]
    for name, method in runs.items():
        cfg = exp.config(name)
        assert isinstance(method.step, SafeStep) and method.step.kind == name
        assert method == cfg.method  # N, bound, delta, range: the registry's
        assert tuple(steps.data["theta0"]) == cfg.theta0 and p["sigma"] == cfg.sigma
    moved = steps_configs({**p, "bound": "bernstein-er", "n": "500", "delta": 0.5, "budget": "30000"})["scalar"]
    assert moved == Vanilla(500, SafeStep("scalar", ErrorModel("bernstein", 0.5, "empirical")))


def test_adaptive_defaults_and_the_authors_switch(adaptive):
    """Unticked: table-5.3's runs; ticked (with the N_max it selects): table-5.3-authors' adaptive run."""
    t53, authors = get_experiment("table-5.3"), get_experiment("table-5.3-authors").config("adaptive")
    p = adaptive.defaults()
    assert p["authors"] is False
    runs = adaptive_configs(p)
    assert runs["adaptive"] == t53.config("adaptive").method  # bound, delta, N_min, N_max
    assert runs["adaptive"].departures == Departures() and runs["adaptive"].batches.first is None  # safepg's defaults
    for name in ("N=1000", "N=100"):
        assert runs[name] == t53.config(name).method
    on = adaptive_configs({**p, "authors": True, "n_max": str(authors_2d().batches.n_max)})["adaptive"]
    assert on == authors_2d()
    a = authors.method
    assert (on.error, on.departures, on.batches.n_min, on.batches.n_max) == (
        a.error, a.departures, a.batches.n_min, a.batches.n_max)
    assert on.departures.changed() == ("maxima", "unguarded_step") and on.batches.n_max == 100_000
    assert on.batches.first == 100  # their 2-D script's hard-coded first batch (= N_min: the same run)


@needs_node
def test_page_configs_are_the_python_settings(steps, adaptive):
    """Every setting the page sends the engine is the twin's safepg argument, control by control."""
    base_s, base_a = steps.defaults(), adaptive.defaults()
    moves_s = [{}, {"bound": "hoeffding-er"}, {"delta": 0.4}, {"sigma": 0.5}, {"n": "5000"}, {"seed": 7.0},
               {"budget": "30000"}]
    moves_a = [{}, {"authors": True, "n_max": "100000"}, {"bound": "chebyshev"}, {"n_max": "10000"},
               {"delta": 0.25}, {"sigma": 1.5}, {"seed": 3.0}]
    out_s = run_page("lqg2d_page.js", "safepgLqg2dSteps",
                     [{"p": {**base_s, **m}, "data": steps.data, "configs": True} for m in moves_s])
    out_a = run_page("lqg2d_page.js", "safepgLqg2dAdaptive",
                     [{"p": {**base_a, **m}, "data": adaptive.data, "configs": True} for m in moves_a]
                     + [{"p": base_a, "data": adaptive.data, "links": adaptive._spec()["links"],
                         "linked": ["authors", v]} for v in (True, False)])
    for (fn, base, moves, out) in ((steps_configs, base_s, moves_s, out_s), (adaptive_configs, base_a, moves_a, out_a)):
        for m, got in zip(moves, out):
            p = {**base, **m}
            py = fn(p)
            js = {r["name"]: r["cfg"] for r in got["configs"]["runs"]}
            completed = dict(zip(js, got["completed"]))
            assert list(js) == list(py)
            for name, method in py.items():
                cfg = js[name]
                assert cfg["sigma"] == p["sigma"] and cfg["seed"] == round(p["seed"])
                assert cfg["theta0"] == [0.0] * 4 and cfg["budget"] == int(p["budget"])
                if isinstance(method, Vanilla):
                    assert cfg["stopOnDivergence"] is True  # learn() stops a diverging vanilla run
                # The page's configuration, completed with the table's defaults as the learner completes
                # it, is the method's own.
                options = learner_options(method)
                assert {k: completed[name][k] for k in options} == options, (m, name)
                assert set(completed[name]) - set(options) == {"sigma", "seed", "theta0", "budget",
                                                               "stopOnDivergence", "stream"}, (m, name)
    assert out_a[-2]["linked"] == {"n_max": "100000"} and out_a[-1]["linked"] == {"n_max": "500000"}
    assert [adaptive.linked("authors", v) for v in (True, False)] == [out_a[-2]["linked"], out_a[-1]["linked"]]


def small_traces(p, budget=3000):
    env, theta0 = lqg2d_env(), np.zeros(4)
    traces = {}
    for k, (name, method) in enumerate(adaptive_configs({**p, "budget": str(budget)}).items()):
        rec = learn(env, method, theta0, float(p["sigma"]), budget=budget, rng=np.random.default_rng([0, k]))
        traces[name] = record_trace(rec, record_c(rec)) if name == "adaptive" else record_trace(rec)
    return traces


@needs_node
def test_page_draws_what_the_twin_draws_from_the_same_runs(steps, adaptive):
    """Given the same traces, the page objects' result (plots, values, text) is the Python twin's, exactly."""
    p = {**adaptive.defaults(), "authors": True}
    traces = small_traces(p)
    env = lqg2d_env()
    ts = {}
    for k, (name, method) in enumerate(steps_configs({**steps.defaults(), "budget": "6000"}).items()):
        ts[name] = record_trace(learn(env, method, np.zeros(4), 1.0, budget=6000, rng=np.random.default_rng([0, k])))
    js_a, = run_page("lqg2d_page.js", "safepgLqg2dAdaptive", [{"p": p, "data": adaptive.data, "traces": traces}])
    js_s, = run_page("lqg2d_page.js", "safepgLqg2dSteps", [{"p": steps.defaults(), "data": steps.data,
                                                             "traces": ts}])
    assert js_a["result"] == json.loads(json.dumps(adaptive_result(p, traces, adaptive.data)))
    assert js_s["result"] == json.loads(json.dumps(steps_result(steps.defaults(), ts, steps.data)))
    assert "Algorithm 4.1 (authors' settings)" in js_a["result"]["text"]


def test_kernel_twins_return_the_pages_structure(steps, adaptive):
    res = steps.compute_py({**steps.defaults(), "budget": "30000"})
    assert set(res["plots"]) == {"theta", "J"} and set(res["values"]) == {"scalar", "coordinate", "done"}
    assert [s["label"] for s in res["plots"]["theta"]["series"]] == [
        "scalar step (Pirotta et al. 2013): theta_11", "scalar step (Pirotta et al. 2013): theta_22",
        "coordinate step: theta_11",
        "coordinate step: theta_22"]
    v = res["values"]["coordinate"]
    assert v["trajectories"] == 30_000 and v["theta_final"][0] < 0 and v["theta_final"][3] < 0
    seen = []
    res = adaptive.compute_py({**adaptive.defaults(), "budget": "30000"},
                              progress=lambda f, m: seen.append(f))
    assert set(res["values"]) == {"adaptive", "N=1000", "N=100", "done"}
    assert [s["label"] for s in res["plots"]["N"]["series"]] == [
        "Algorithm 4.1", "fixed N=1000, alpha = 1e-6", "fixed N=100, alpha = 1e-6"]
    assert seen and 0 < seen[0] and seen[-1] == pytest.approx(1.0)
    assert res["values"]["adaptive"]["trajectories"] == 30_000
