"""The page learner's vocabulary (safepg.thesis.explorers.option_names and static/options.js).

The committed table is what the module writes; every field of every option object has one
name in it; a method flattened through it comes back whole; and the JavaScript learner, filling
in what a configuration leaves out from that table, holds safepg's own defaults.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess

import pytest

from conftest import require_node
from safepg.definition import OPTION_TYPES, from_dict, to_dict
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.thesis.explorers.js_tasks import learner_sources
from safepg.thesis.explorers.option_names import (
    TABLE_FILE,
    camel,
    learner_options,
    option_table,
    table_js,
)

needs_node = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)

METHODS = [Adaptive(), Vanilla(100), Vanilla(100, SafeStep()),
           Adaptive(Gradient("reinforce", False, "raw"), ErrorModel("bernstein", 0.5, "empirical"),
                    Batches(10, 1000, 77), Departures(True, True, True)),
           Vanilla(7, SafeStep("scalar", ErrorModel("hoeffding", 0.2, 123.0)), Gradient("reinforce")),
           Vanilla(1000, FixedStep(0.01, "coordinate"), target=Target(195.0, True))]


def test_the_committed_table_is_what_the_module_writes():
    assert TABLE_FILE.read_text() == table_js(), (
        "static/options.js is stale: run python -m safepg.thesis.explorers.option_names")


def test_every_field_of_every_option_has_one_name():
    table = option_table()["types"]
    assert set(table) == set(OPTION_TYPES)
    for name, cls in OPTION_TYPES.items():
        fields = [f.name for f in dataclasses.fields(cls) if f.init]
        assert [e["field"] for e in table[name].values()] == fields, name
        assert list(table[name]) == [camel(f) for f in fields], name


def test_camel():
    assert [camel(n) for n in ("n_min", "score_action", "stop_on_divergence", "theta0", "delta")] == [
        "nMin", "scoreAction", "stopOnDivergence", "theta0", "delta"]


@pytest.mark.parametrize("method", METHODS, ids=repr)
def test_a_flattened_method_comes_back_whole(method):
    """learner_options loses nothing: rebuilt through the table, the flat options give the method again."""
    flat = learner_options(method)
    table = option_table()["types"]

    def rebuild(type_name: str) -> dict:
        out = {"type": type_name}
        for name, e in table[type_name].items():
            if e.get("nested"):
                out[e["field"]] = rebuild(e["types"][0])
            elif "types" in e:
                out[e["field"]] = None if flat[name] is None else rebuild(flat[name])
            else:
                out[e["field"]] = flat[name]
        return out

    data = rebuild(flat["method"])
    assert data == to_dict(method)
    assert from_dict(data) == method


def test_repeated_flat_names_are_refused(monkeypatch):
    """Two options of one method under one name would be one option to the page."""
    import safepg.thesis.explorers.option_names as on

    monkeypatch.setitem(on.RUN_FIELDS, "delta", {"field": "delta", "number": True, "default": 0.5})
    with pytest.raises(ValueError, match=r"repeated names \['delta'\]"):
        on.option_table()


def _node(script: str, payload: object) -> object:
    proc = subprocess.run([require_node(), "-e", learner_sources() + "\n" + script], input=json.dumps(payload),
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@needs_node
def test_the_page_learner_fills_in_safepgs_defaults():
    """A configuration that names only its method (and what has no default) is completed to the
    defaults of safepg's own option objects."""
    given = [{}, {"method": "Vanilla", "batchSize": 100, "alpha": 0.001},
             {"method": "Vanilla", "batchSize": 100, "step": "SafeStep"}]
    expected = [Adaptive(), Vanilla(100, FixedStep(0.001)), Vanilla(100, SafeStep())]
    got = _node("const cfgs = JSON.parse(require('fs').readFileSync(0, 'utf8'));"
                "process.stdout.write(JSON.stringify(cfgs.map(c => safepgLearner.runOptions(c))));", given)
    for cfg, method in zip(got, expected):
        options = learner_options(method)
        assert {k: cfg[k] for k in options} == options


@needs_node
@pytest.mark.parametrize("cfg,message", [
    ({"empiricalRange": True}, "empiricalRange is not an option of this Adaptive run"),
    ({"method": "Vanilla", "batchSize": 100, "alpha": 0.1, "bound": "chebyshev"},
     "bound is not an option of this Vanilla run"),
    ({"bound": "cheb"}, 'bound must be "chebyshev" or "hoeffding" or "bernstein", got "cheb"'),
    ({"method": "Vanilla"}, "batchSize is required for a Vanilla run"),
    ({"method": "Vanilla", "batchSize": 100}, "alpha is required for a Vanilla run"),
    ({"method": "Reinforce"}, "method must be one of Adaptive, Vanilla"),
    ({"first": 1.5}, "first must be an integer or null, got 1.5"),
])
def test_the_page_learner_refuses_what_safepg_refuses(cfg, message):
    got = _node("const cfg = JSON.parse(require('fs').readFileSync(0, 'utf8'));"
                "try { safepgLearner.runOptions(cfg); process.stdout.write(JSON.stringify(null)); }"
                "catch (e) { process.stdout.write(JSON.stringify(e.message)); }", cfg)
    assert got is not None and message in got, got
