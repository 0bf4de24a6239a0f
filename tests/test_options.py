"""The option objects of the learning loops (safepg.options): each checks its own values by name
and is frozen; the loops refuse an option of the wrong type; the same settings give the same run
through the loops and through RunConfig; a RunConfig's definition and key do not depend on how
its method is spelt, and every field of the definition is in the key."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from safepg.envs.lqg import LQG
from safepg.learning import adaptive_pg, learn, vanilla_pg
from safepg.options import (
    Adaptive,
    Batches,
    Departures,
    ErrorModel,
    FixedStep,
    Gradient,
    SafeStep,
    Target,
    Vanilla,
)
from safepg.runner import RunConfig
from safepg.thesis.experiments import LQG2D_TASK

ENV = LQG.thesis_1d()
ARRAYS = ("batch_size", "alpha", "coordinate", "theta", "J", "J_hat", "grad", "eps", "safe")
NAN, INF = float("nan"), float("inf")
RECORDED = json.loads((Path(__file__).parent / "data" / "run_keys.json").read_text())


def same_record(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ARRAYS) and a.config == b.config


# ------------------------------------------------------------------ each object checks its values
BAD = [
    (lambda: Gradient("natural"), "estimator"),
    (lambda: Gradient(baseline="yes"), "baseline"),
    (lambda: Gradient(baseline=1), "baseline"),
    (lambda: Gradient(score_action="sampled"), "score_action"),
    (lambda: ErrorModel("markov"), "bound"),
    *((lambda d=d: ErrorModel(delta=d), "delta") for d in (0.0, 1.0, -0.1, 1.5, NAN)),
    *((lambda r=r: ErrorModel("hoeffding", range=r), "range") for r in ("foo", "Lemma", -1, 0, NAN, INF, True)),
    (lambda: Batches(n_min=1), "n_min"),
    (lambda: Batches(n_min=100.5), "n_min"),
    (lambda: Batches(n_max=True), "n_max"),
    (lambda: Batches(n_min=600_000), "n_min must be <= n_max"),
    (lambda: Batches(n_min=1000, n_max=999), "n_min must be <= n_max"),
    (lambda: Batches(first=1), "first"),
    (lambda: Batches(first=0), "first"),
    (lambda: Departures(batch_constants="batch"), "batch_constants"),
    (lambda: Departures(maxima="max"), "maxima"),
    (lambda: Departures(unguarded_step=1), "unguarded_step"),
    *((lambda a=a: FixedStep(a), "alpha") for a in (NAN, -1e-3, INF, True, "0.01", None)),
    (lambda: FixedStep(1e-3, "x"), "kind"),
    (lambda: SafeStep("x"), "kind"),
    *((lambda v=v: Target(v), "target value") for v in (NAN, INF, -INF, "195", True, None)),
    (lambda: Target(195.0, update="yes"), "update"),
    (lambda: Vanilla(1), "batch_size"),
    (lambda: Vanilla(100.5), "batch_size"),
    (lambda: Vanilla(None), "batch_size"),
]
#: An option of the wrong type inside another (a misplaced string or number): a TypeError, by name.
WRONG_TYPE = [
    (lambda: SafeStep("scalar", "bernstein"), "error"),
    (lambda: SafeStep("scalar", Gradient()), "error"),
    (lambda: Vanilla(100, 0.01), "step"),
    (lambda: Vanilla(100, ErrorModel()), "step"),
    (lambda: Vanilla(100, gradient="gpomdp"), "gradient"),
    (lambda: Vanilla(100, target=195.0), "target"),
    (lambda: Adaptive(error="bernstein"), "error"),
    (lambda: Adaptive(gradient=ErrorModel()), "gradient"),
    (lambda: Adaptive(batches=(100, 1000)), "batches"),
    (lambda: Adaptive(departures={"maxima": True}), "departures"),
]


@pytest.mark.parametrize("make,field", BAD, ids=[f"{i}-{f}" for i, (_, f) in enumerate(BAD)])
def test_bad_values_are_refused_by_name(make, field):
    with pytest.raises(ValueError, match=f"^{field}"):
        make()


@pytest.mark.parametrize("make,field", WRONG_TYPE, ids=[f"{i}-{f}" for i, (_, f) in enumerate(WRONG_TYPE)])
def test_options_of_the_wrong_type_are_refused_by_name(make, field):
    with pytest.raises(TypeError, match=f"^{field} must be a"):
        make()


def test_run_config_refuses_what_is_not_a_method():
    with pytest.raises(TypeError, match="^method must be"):
        RunConfig("a", method="adaptive")
    with pytest.raises(TypeError, match="^method must be"):
        RunConfig("a", method=ErrorModel())


def test_good_values_are_kept():
    assert ErrorModel("hoeffding", 0.5, 1280).range == 1280
    e = ErrorModel("bernstein", 0.2, "empirical")
    assert (e.empirical_range, e.theoretical_range) == (True, None)
    assert (ErrorModel().empirical_range, ErrorModel().theoretical_range) == (False, None)  # "lemma"
    assert ErrorModel(range=1280).theoretical_range == 1280.0
    assert Batches().first_size == 100 and Batches(10, 1000, 1000).first_size == 1000
    assert Batches(2, 2).n_min == 2 and FixedStep(0.0).alpha == 0.0 and FixedStep(1).alpha == 1
    assert Target(-1e9).update is False and Target(195, True).update is True


OBJECTS = [Gradient(), ErrorModel(), Batches(), Departures(), FixedStep(1e-3), SafeStep(), Target(195.0),
           Adaptive(), Vanilla(100), RunConfig("a")]


@pytest.mark.parametrize("obj", OBJECTS, ids=lambda o: type(o).__name__)
def test_objects_are_frozen(obj):
    name = dataclasses.fields(obj)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(obj, name, getattr(obj, name))
    hash(obj)  # frozen, so hashable: usable as a key


# ------------------------------------------------------------------ the loops check the types
@pytest.mark.parametrize("name,value", [("error", "bernstein"), ("gradient", "gpomdp"), ("batches", (100, 1000)),
                                        ("departures", {"maxima": True}), ("error", Gradient()),
                                        ("batches", Departures())])
def test_adaptive_pg_refuses_an_option_of_the_wrong_type(name, value):
    with pytest.raises(TypeError, match=f"^{name} must be a"):
        adaptive_pg(ENV, budget=1000, **{name: value})


@pytest.mark.parametrize("name,value", [("step", 0.01), ("step", ErrorModel()), ("gradient", "reinforce"),
                                        ("target", 195.0), ("target", FixedStep(1.0))])
def test_vanilla_pg_refuses_an_option_of_the_wrong_type(name, value):
    with pytest.raises(TypeError, match=f"^{name} must be a"):
        vanilla_pg(ENV, batch_size=100, budget=1000, **{name: value})


def test_learn_refuses_what_is_not_a_method():
    with pytest.raises(TypeError, match="^method"):
        learn(ENV, ErrorModel(), budget=1000)


# ------------------------------------------------------------------ the same run, however it is asked for
CONFIGS = [
    RunConfig("adaptive", method=Adaptive(Gradient("reinforce"), ErrorModel("bernstein", 0.5, "empirical")),
              budget=20_000),
    RunConfig("authors", method=Adaptive(error=ErrorModel("hoeffding", 0.95, 1280.0), batches=Batches(10, 5000, 300),
                                         departures=Departures(True, True, True)), budget=20_000),
    RunConfig("safe", method=Vanilla(500, SafeStep("coordinate", ErrorModel("chebyshev", 0.9))),
              task="lqg2d", theta0=(0.0,) * 4, budget=5000),
    RunConfig("fixed", method=Vanilla(200, FixedStep(1e-3), Gradient(baseline=False), Target(-3.75, True)),
              theta0=(-0.3,), sigma=0.5, budget=20_000),
]


@pytest.mark.parametrize("cfg", CONFIGS, ids=lambda c: c.name)
def test_the_loops_and_run_config_give_the_same_record(cfg):
    env, theta0, m = cfg.make_task(), np.asarray(cfg.theta0), cfg.method
    rng = lambda: np.random.default_rng(cfg.seed(3))  # noqa: E731
    if isinstance(m, Adaptive):
        direct = adaptive_pg(env, theta0, cfg.sigma, gradient=m.gradient, error=m.error, batches=m.batches,
                             departures=m.departures, budget=cfg.budget, rng=rng(), stop_on_divergence=True)
    else:
        direct = vanilla_pg(env, theta0, cfg.sigma, batch_size=m.batch_size, step=m.step, gradient=m.gradient,
                            target=m.target, budget=cfg.budget, rng=rng(), stop_on_divergence=True)
    stored = cfg.run(3)
    assert stored.iterations > 3 and stored.reached_target == (isinstance(m, Vanilla) and m.target is not None)
    assert same_record(direct, stored)
    assert same_record(learn(env, m, theta0, cfg.sigma, budget=cfg.budget, rng=rng(), stop_on_divergence=True),
                       stored)
    assert same_record(cfg.run(3), stored)  # and again: nothing depends on state left behind
    assert not np.array_equal(cfg.run(4).J_hat, stored.J_hat)  # another seed, another run
    # The record's settings are the config's definition, and the penalty constant c.
    assert stored.config == {**cfg.definition(), "c": stored.config["c"]}


# ------------------------------------------------------------------ definition() and key()
def test_a_method_spelt_two_ways_has_one_key():
    scalar = dict(task=LQG2D_TASK, theta0=(0.0,) * 4)
    short = RunConfig("scalar", method=Vanilla(2000, SafeStep("scalar", ErrorModel())), **scalar)
    spelt = RunConfig("x", method=Vanilla(2000, SafeStep("scalar", ErrorModel("chebyshev", 0.95, "lemma")),
                                          Gradient("gpomdp", True, "clipped"), None), sigma=1.0, budget=30_000_000,
                      **scalar)
    assert short.definition() == spelt.definition() and short.key() == spelt.key()
    assert short.key() == RECORDED["figures-5.5-5.6"]["scalar"]  # the stored runs' key
    plain, spelt = RunConfig("a"), RunConfig("b", method=Adaptive(Gradient(), ErrorModel(), Batches(100, 500_000, None),
                                                                  Departures(False, False, False)))
    assert plain.key() == spelt.key() and plain.definition() == spelt.definition()
    assert RunConfig("a", method=Adaptive(error=ErrorModel("bernstein", 0.95, "empirical")),
                     task=LQG2D_TASK, theta0=(0.0,) * 4).key() == RECORDED["table-5.3"]["adaptive"]
    # A task by its preset's name or as the object: one task, one key.
    assert RunConfig("a", task="lqg2d").key() == RunConfig("a", task=LQG.thesis_2d()).key()
    assert RunConfig("a", task=LQG.thesis_1d(A=1.0)).key() == RunConfig("a", task=LQG.thesis_1d(A=[[1.0]])).key()


def test_every_setting_of_a_method_is_in_the_key():
    """One run per key: changing any one option of either method changes the key."""
    adaptive = [Adaptive(), Adaptive(Gradient("reinforce")), Adaptive(Gradient(baseline=False)),
                Adaptive(Gradient(score_action="raw")), Adaptive(error=ErrorModel("hoeffding")),
                Adaptive(error=ErrorModel(delta=0.5)), Adaptive(error=ErrorModel("hoeffding", range="empirical")),
                Adaptive(error=ErrorModel("hoeffding", range=1280.0)), Adaptive(batches=Batches(n_min=10)),
                Adaptive(batches=Batches(n_max=1000)), Adaptive(batches=Batches(first=1000)),
                Adaptive(batches=Batches(first=100)),  # set, even to N_min, is set
                *(Adaptive(departures=Departures(**{d: True})) for d in DEPARTURES)]
    vanilla = [Vanilla(100), Vanilla(200), Vanilla(100, FixedStep(1e-2)), Vanilla(100, FixedStep(1e-3, "coordinate")),
               Vanilla(100, gradient=Gradient("reinforce")), Vanilla(100, target=Target(195.0)),
               Vanilla(100, target=Target(195.0, update=True)), Vanilla(100, SafeStep("scalar")),
               Vanilla(100, SafeStep("coordinate")), Vanilla(100, SafeStep("scalar", ErrorModel("bernstein"))),
               Vanilla(100, SafeStep("scalar", ErrorModel(delta=0.5))),
               Vanilla(100, SafeStep("scalar", ErrorModel("hoeffding", range="empirical")))]
    methods = adaptive + vanilla
    keys = [RunConfig("a", method=m).key() for m in methods]
    same = [(methods[i], methods[j]) for i in range(len(keys)) for j in range(i) if keys[i] == keys[j]]
    assert not same


#: Values a leaf of a definition may take, tried in turn for a changed one that is still valid.
ALTERNATIVES = ("reinforce", "gpomdp", "raw", "clipped", "hoeffding", "bernstein", "chebyshev", "empirical",
                "lemma", "scalar", "coordinate", "semi-implicit", "euler", "truncated", "effective", 3.5, 0.5, 7,
                1000, (1.0, 2.0, 3.0, 4.0), None, True, False, {"type": "Target", "value": 195.0, "update": False})


def _leaves(d, path=()):
    """(path, value) of every field of a definition, a task's matrix as one value."""
    if isinstance(d, dict):
        for k, v in d.items():
            if k != "type":
                yield from _leaves(v, (*path, k))
    else:
        yield path, d


def _changed(d, path, value):
    if not path:
        return value
    return {**d, path[0]: _changed(d[path[0]], path[1:], value)}


def _alternatives(value):
    if isinstance(value, list):  # theta0 or a matrix: change its first entry
        flat = np.asarray(value, dtype=float)
        yield (flat + np.eye(*flat.shape) if flat.ndim == 2 else flat + 0.5).tolist()
        return
    if isinstance(value, bool):
        yield not value
    elif isinstance(value, int | float) and value:
        yield type(value)(value * 2) if isinstance(value, int) else value / 2
    yield from (a for a in ALTERNATIVES if a != value and not (isinstance(a, bool) and not isinstance(value, bool)))


#: One configuration of each method, on each core task, warm-started or not.
DEFINED = [
    RunConfig("adaptive", method=Adaptive(batches=Batches(first=300)), task="lqg1d"),
    RunConfig("safe", method=Vanilla(500, SafeStep("scalar", ErrorModel("hoeffding", 0.9, 1280.0)),
                                     target=Target(-3.0)), task="lqg2d", theta0=(0.0,) * 4),
    RunConfig("cartpole", method=Vanilla(4000, FixedStep(0.01, "coordinate")), task="cartpole-doubled",
              warm_start="cartpole-baseline", warm_start_key="0123456789abcdef"),
]


@pytest.mark.parametrize("cfg", DEFINED, ids=lambda c: c.name)
def test_every_field_of_the_definition_is_in_the_key(cfg):
    """Each field changed alone, to any other value its object accepts, gives another key."""
    d = cfg.definition()
    assert RunConfig.from_definition(cfg.name, d, cfg.warm_start).definition() == d  # the round trip
    checked = []
    for path, value in _leaves(d):
        for alt in _alternatives(value):
            try:
                other = RunConfig.from_definition(cfg.name, _changed(d, path, alt), cfg.warm_start)
                key = other.key()
            except (ValueError, TypeError):
                continue  # not a value this field takes
            if other.definition() == d:
                continue  # the same definition spelt otherwise (an int for a float)
            assert key != cfg.key(), (path, value, alt)
            checked.append(path)
            break
    # The LQG's dim changes only with its matrices (each is dim x dim): no value of it alone is valid.
    # A warm-started run starts where its warm_start run ended: it has no theta0 of its own.
    unchangeable = {("task", "dim")} | ({("theta0",)} if cfg.warm_start else set())
    assert {p for p, _ in _leaves(d)} - set(checked) <= unchangeable


def test_the_definition_holds_the_option_objects_field_names():
    van = RunConfig("v", method=Vanilla(500, FixedStep(1e-4, "coordinate"), Gradient("reinforce", False, "raw"),
                                        Target(-20.0)), budget=1000)
    d = van.definition()
    assert d["method"] == {
        "type": "Vanilla", "batch_size": 500, "step": {"type": "FixedStep", "alpha": 1e-4, "kind": "coordinate"},
        "gradient": {"type": "Gradient", "estimator": "reinforce", "baseline": False, "score_action": "raw"},
        "target": {"type": "Target", "value": -20.0, "update": False}}
    assert d["task"]["type"] == "LQG" and d["task"]["A"] == [[1.0]] and d["task"]["gamma"] == 0.9
    assert (d["theta0"], d["sigma"], d["budget"], d["stop_on_divergence"], d["warm_start"]) == ([0.0], 1.0, 1000,
                                                                                                True, None)
    assert van.algorithm == "vanilla" and RunConfig("a").algorithm == "adaptive"
    warm = RunConfig("w", warm_start="cartpole-baseline", warm_start_key="0123456789abcdef")
    assert warm.definition()["warm_start"] == "0123456789abcdef" and warm.definition()["theta0"] is None
    with pytest.raises(ValueError, match="^warm_start_key must be given"):
        RunConfig("w", warm_start="cartpole-baseline").key()


# ------------------------------------------------------------------ the departures and the theorems' assumptions
DEPARTURES = ("batch_constants", "unguarded_step", "maxima")  # in the order of assumptions()


def test_the_algorithm_keeps_every_assumption():
    d = Departures()
    assert d.changed() == () and all(a.holds for a in d.assumptions())
    assert len(d.assumptions()) == 3 and all(a.assumption and a.why for a in d.assumptions())


@pytest.mark.parametrize("i,name", list(enumerate(DEPARTURES)))
def test_each_departure_flips_exactly_its_own_assumption(i, name):
    d = Departures(**{name: True})
    assert d.changed() == (name,)
    holds = [a.holds for a in d.assumptions()]
    assert holds == [j != i for j in range(3)]
    assert d.assumptions()[i].why != Departures().assumptions()[i].why  # the reason says what changed
    assert [a.assumption for a in d.assumptions()] == [a.assumption for a in Departures().assumptions()]


def test_changed_lists_what_is_set_in_field_order():
    assert Departures(True, True, True).changed() == ("batch_constants", "maxima", "unguarded_step")
    assert Departures(unguarded_step=True, batch_constants=True).changed() == ("batch_constants", "unguarded_step")
    assert not any(a.holds for a in Departures(True, True, True).assumptions())
