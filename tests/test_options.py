"""The option objects of the learning loops (safepg.options): each checks its own values by name
and is frozen; the loops refuse an option of the wrong type; the same settings give the same run
through the loops and through RunConfig; a RunConfig's flat fields and key do not depend on how
its method is spelt."""

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
              env="lqg2d", theta0=(0.0,) * 4, budget=5000),
    RunConfig("fixed", method=Vanilla(200, FixedStep(1e-3), Gradient(baseline=False), Target(-3.75, True)),
              theta0=(-0.3,), sigma=0.5, budget=20_000),
]


@pytest.mark.parametrize("cfg", CONFIGS, ids=lambda c: c.name)
def test_the_loops_and_run_config_give_the_same_record(cfg):
    env, theta0, m = cfg.make_env(), np.asarray(cfg.theta0), cfg.method
    rng = lambda: np.random.default_rng(cfg.seed(3))  # noqa: E731
    if isinstance(m, Adaptive):
        direct = adaptive_pg(env, theta0, cfg.sigma, gradient=m.gradient, error=m.error, batches=m.batches,
                             departures=m.departures, budget=cfg.budget, rng=rng())
    else:
        direct = vanilla_pg(env, theta0, cfg.sigma, batch_size=m.batch_size, step=m.step, gradient=m.gradient,
                            target=m.target, budget=cfg.budget, rng=rng(), stop_on_divergence=True)
    stored = cfg.run(3)
    assert stored.iterations > 3 and stored.reached_target == (isinstance(m, Vanilla) and m.target is not None)
    assert same_record(direct, stored)
    assert same_record(learn(env, m, theta0, cfg.sigma, budget=cfg.budget, rng=rng()), stored)
    assert same_record(cfg.run(3), stored)  # and again: nothing depends on state left behind
    assert not np.array_equal(cfg.run(4).J_hat, stored.J_hat)  # another seed, another run
    # The record's settings are the config's flat fields (plus the task and c).
    flat = cfg.fields()
    assert {k: v for k, v in stored.config.items() if k in flat} == {
        k: v for k, v in flat.items() if k in stored.config}


# ------------------------------------------------------------------ fields() and key()
def test_a_method_spelt_two_ways_has_one_key():
    scalar = dict(env="lqg2d-gamma0.9", theta0=(0.0,) * 4)
    short = RunConfig("scalar", method=Vanilla(2000, SafeStep("scalar", ErrorModel())), **scalar)
    spelt = RunConfig("x", method=Vanilla(2000, SafeStep("scalar", ErrorModel("chebyshev", 0.95, "lemma")),
                                          Gradient("gpomdp", True, "clipped"), None), sigma=1.0, budget=30_000_000,
                      **scalar)
    assert short.fields() == spelt.fields() and short.key() == spelt.key()
    assert short.key() == RECORDED["figures-5.5-5.6"]["scalar"]  # the stored runs' key
    plain, spelt = RunConfig("a"), RunConfig("b", method=Adaptive(Gradient(), ErrorModel(), Batches(100, 500_000, None),
                                                                  Departures(False, False, False)))
    assert plain.key() == spelt.key() and plain.fields() == spelt.fields()
    assert RunConfig("a", method=Adaptive(error=ErrorModel("bernstein", 0.95, "empirical")),
                     env="lqg2d-gamma0.9", theta0=(0.0,) * 4).key() == RECORDED["table-5.3"]["adaptive"]


def test_every_setting_of_a_method_is_in_the_key():
    """One run per key: changing any one option of either method changes the key."""
    adaptive = [Adaptive(), Adaptive(Gradient("reinforce")), Adaptive(Gradient(baseline=False)),
                Adaptive(Gradient(score_action="raw")), Adaptive(error=ErrorModel("hoeffding")),
                Adaptive(error=ErrorModel(delta=0.5)), Adaptive(error=ErrorModel("hoeffding", range="empirical")),
                Adaptive(error=ErrorModel("hoeffding", range=1280.0)), Adaptive(batches=Batches(n_min=10)),
                Adaptive(batches=Batches(n_max=1000)), Adaptive(batches=Batches(first=1000)),
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


#: Each option away from the algorithm: the method with it at its default and set, its flat
#: name and value in fields().
LEGACY = [
    (Adaptive(), Adaptive(batches=Batches(first=1000)), "n_first", 1000),
    (Adaptive(), Adaptive(batches=Batches(first=100)), "n_first", 100),  # set, even to N_min, is set
    (Adaptive(), Adaptive(departures=Departures(batch_constants=True)), "constants", "batch"),
    (Adaptive(), Adaptive(departures=Departures(maxima=True)), "statistics", "max"),
    (Adaptive(), Adaptive(departures=Departures(unguarded_step=True)), "step_when_unsafe", True),
    (Vanilla(4000, FixedStep(0.01), target=Target(195.0)),
     Vanilla(4000, FixedStep(0.01), target=Target(195.0, update=True)), "update_at_target", True),
    (Adaptive(error=ErrorModel("hoeffding")), Adaptive(error=ErrorModel("hoeffding", range=1280.0)),
     "theoretical_range", 1280.0),
]
OPTIONAL = ("n_first", "constants", "statistics", "step_when_unsafe", "update_at_target", "theoretical_range")


@pytest.mark.parametrize("unset,method,name,value", LEGACY, ids=[n for *_, n, _ in LEGACY])
def test_an_option_is_in_fields_under_its_legacy_name_only_when_set(unset, method, name, value):
    cfg, default = RunConfig("a", method=method), RunConfig("a", method=unset)
    assert not set(OPTIONAL) & set(default.fields())
    f = cfg.fields()
    assert f[name] == value and set(OPTIONAL) & set(f) == {name}
    assert {k: v for k, v in f.items() if k != name} == default.fields()
    assert cfg.key() != default.key()


def test_fields_of_each_method_hold_the_flat_names():
    van = RunConfig("v", method=Vanilla(500, FixedStep(1e-4, "coordinate"), Gradient("reinforce", False, "raw"),
                                        Target(-20.0)), budget=1000)
    assert van.fields() == {
        "algorithm": "vanilla", "env": "lqg1d", "theta0": [0.0], "sigma": 1.0, "estimator": "reinforce",
        "baseline": False, "score_action": "raw", "bound": "chebyshev", "delta": 0.95, "empirical_range": False,
        "budget": 1000, "n_min": 100, "n_max": 500_000, "batch_size": 500, "step": "coordinate", "alpha": 1e-4,
        "target_return": -20.0}
    assert van.algorithm == "vanilla" and RunConfig("a").algorithm == "adaptive"
    safe = RunConfig("s", method=Vanilla(500, SafeStep("scalar", ErrorModel("bernstein", 0.5, "empirical"))))
    f = safe.fields()
    assert (f["bound"], f["delta"], f["empirical_range"]) == ("bernstein", 0.5, True)
    assert "alpha" not in safe.fields()  # a safe step has no alpha
    warm = RunConfig("w", warm_start="cartpole-baseline", warm_start_key="0123456789abcdef")
    assert warm.fields()["warm_start"] == "cartpole-baseline" and "warm_start_key" not in warm.fields()


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
