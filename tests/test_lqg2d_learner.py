"""The 2-D LQG live explorers (safepg/thesis/explorers/lqg2d_learner.py): the page they render, the
settings each control maps to (against the experiments' registry), and the page objects
(static/lqg2d_page.js, run under Node) against their Python twins. The page in Chromium:
tests/test_browser_live_ch5.py."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from ch5_node import NODE, run_page

from safepg.learning import adaptive_pg, vanilla_pg
from safepg.thesis.experiments import get_experiment
from safepg.thesis.explorers.ch5_live import learner_source, record_c, record_trace
from safepg.thesis.explorers.lqg2d_learner import (
    AUTHORS_2D,
    adaptive_configs,
    adaptive_result,
    lqg2d_adaptive_explorer,
    lqg2d_env,
    lqg2d_steps_explorer,
    steps_configs,
    steps_result,
)

needs_node = pytest.mark.skipif(NODE is None, reason="node is not installed")
#: What the page asks of the engine, in its names, for safepg's keyword arguments.
CAMEL = {"batch_size": "batchSize", "empirical_range": "empiricalRange", "stop_on_divergence": "stopOnDivergence",
         "n_min": "nMin", "n_max": "nMax", "n_first": "nFirst", "step_when_unsafe": "stepWhenUnsafe"}


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
    """The defaults are figures-5.5-5.6's settings; each run is vanilla_pg with alpha=None and its step."""
    exp = get_experiment("figures-5.5-5.6")
    p = steps.defaults()
    runs = steps_configs(p)
    for name, kw in runs.items():
        cfg = exp.config(name)
        assert kw["step"] == cfg.step == name and kw["alpha"] is None and cfg.alpha is None
        assert (kw["batch_size"], kw["bound"], kw["empirical_range"], kw["delta"]) == \
            (cfg.batch_size, cfg.bound, cfg.empirical_range, cfg.delta)
        assert tuple(steps.data["theta0"]) == cfg.theta0 and p["sigma"] == cfg.sigma
    moved = steps_configs({**p, "bound": "bernstein-er", "n": "500", "delta": 0.5, "budget": "30000"})["scalar"]
    assert (moved["bound"], moved["empirical_range"], moved["batch_size"], moved["delta"], moved["budget"]) == \
        ("bernstein", True, 500, 0.5, 30_000)


def test_adaptive_defaults_and_the_authors_switch(adaptive):
    """Unticked: table-5.3's runs; ticked (with the N_max it selects): table-5.3-authors' adaptive run."""
    t53, authors = get_experiment("table-5.3"), get_experiment("table-5.3-authors").config("adaptive")
    p = adaptive.defaults()
    assert p["authors"] is False
    runs = adaptive_configs(p)
    a = t53.config("adaptive")
    assert (runs["adaptive"]["bound"], runs["adaptive"]["empirical_range"], runs["adaptive"]["delta"],
            runs["adaptive"]["n_min"], runs["adaptive"]["n_max"]) == (a.bound, a.empirical_range, a.delta, a.n_min,
                                                                      a.n_max)
    assert not {"statistics", "step_when_unsafe", "n_first"} & set(runs["adaptive"])  # safepg's defaults
    for name in ("N=1000", "N=100"):
        c = t53.config(name)
        assert (runs[name]["batch_size"], runs[name]["alpha"]) == (c.batch_size, c.alpha)
    on = adaptive_configs({**p, "authors": True, "n_max": str(AUTHORS_2D["n_max"])})["adaptive"]
    assert (on["statistics"], on["step_when_unsafe"], on["n_max"]) == \
        (authors.statistics, authors.step_when_unsafe, authors.n_max)
    assert on["n_first"] == AUTHORS_2D["n_first"] == 100  # their 2-D script's hard-coded first batch


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
                     + [{"p": base_a, "data": adaptive.data, "linked": ["authors", v]} for v in (True, False)])
    for (fn, base, moves, out) in ((steps_configs, base_s, moves_s, out_s), (adaptive_configs, base_a, moves_a, out_a)):
        for m, got in zip(moves, out):
            p = {**base, **m}
            py = fn(p)
            js = {r["name"]: r["cfg"] for r in got["configs"]["runs"]}
            assert list(js) == list(py)
            for name, kw in py.items():
                cfg = js[name]
                assert cfg["sigma"] == p["sigma"] and cfg["seed"] == round(p["seed"])
                assert cfg["theta0"] == [0.0] * 4
                for k, v in kw.items():
                    assert cfg[CAMEL.get(k, k)] == v, (m, name, k)
    assert out_a[-2]["linked"] == {"n_max": "100000"} and out_a[-1]["linked"] == {"n_max": "500000"}


def small_traces(p, budget=3000):
    env, theta0 = lqg2d_env(), np.zeros(4)
    traces = {}
    for k, (name, kw) in enumerate(adaptive_configs({**p, "budget": str(budget)}).items()):
        kw = {**kw, "rng": np.random.default_rng([0, k])}
        if name == "adaptive":
            rec = adaptive_pg(env, theta0, float(p["sigma"]), **kw)
            traces[name] = record_trace(rec, record_c(rec))
        else:
            traces[name] = record_trace(vanilla_pg(env, theta0, float(p["sigma"]), **kw))
    return traces


@needs_node
def test_page_draws_what_the_twin_draws_from_the_same_runs(steps, adaptive):
    """Given the same traces, the page objects' result (plots, values, text) is the Python twin's, exactly."""
    p = {**adaptive.defaults(), "authors": True}
    traces = small_traces(p)
    env = lqg2d_env()
    ts = {}
    for k, (name, kw) in enumerate(steps_configs({**steps.defaults(), "budget": "6000"}).items()):
        ts[name] = record_trace(vanilla_pg(env, np.zeros(4), 1.0, rng=np.random.default_rng([0, k]), **kw))
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
        "scalar step [24]: theta_11", "scalar step [24]: theta_22", "coordinate step: theta_11",
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
