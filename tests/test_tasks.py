"""What a task offers the learning loops (safepg.tasks): the fast paths a task declares by
inheriting their Protocols are checked when a loop starts (task_hooks) and then used; a hook that
is declared but missing, has other parameters, or is defined without being declared is a
TypeError naming it."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import import_or_fail
from safepg.constants import TaskConstants
from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.envs.pendulum import Pendulum
from safepg.learning import adaptive_pg, vanilla_pg
from safepg.options import Batches, Departures, ErrorModel, FixedStep
from safepg.tasks import (
    DEFAULT_CONSTANTS_SETTINGS,
    ActionDimension,
    ConstantsSettings,
    GradientBatch,
    GradientBatchConstants,
    MeasuredReturns,
    Performance,
    PerformanceBatch,
    constants_settings,
    task_hooks,
)

HOOKS = ("gradient_batch", "gradient_batch_constants", "measured_returns", "performance", "performance_batch")
ARRAYS = ("batch_size", "alpha", "coordinate", "theta", "J_hat", "grad", "eps", "safe")


class Minimal:
    """The required interface only: simulate and the bounds (of the 1-D LQG it runs)."""

    def __init__(self) -> None:
        self.lqg = LQG.thesis_1d()
        self.simulated = 0
        for name in ("reward_bound", "feature_bound", "action_volume", "action_bound", "gamma", "horizon"):
            setattr(self, name, getattr(self.lqg, name))

    def simulate(self, policy, n, rng=None):
        self.simulated += 1
        return self.lqg.simulate(policy, n, rng)


class Fused(Minimal, GradientBatch):
    """Minimal plus the fused batch, counted."""

    def __init__(self) -> None:
        super().__init__()
        self.fused = 0

    def gradient_batch(self, policy, n, rng=None, estimator="gpomdp", baseline=True, score_action="clipped"):
        self.fused += 1
        return self.lqg.gradient_batch(policy, n, rng, estimator, baseline, score_action)


def hooks_of(task) -> set[str]:
    h = task_hooks(task)
    return {name for name in HOOKS if getattr(h, name) is not None}


# ------------------------------------------------------------------ mistakes are TypeErrors, by name
def test_a_declared_hook_that_is_missing_is_refused():
    class Declares(Minimal, GradientBatch):
        pass

    with pytest.raises(TypeError, match="declares GradientBatch but does not define gradient_batch"):
        task_hooks(Declares())
    for loop in (lambda t: adaptive_pg(t, budget=1000, rng=0), lambda t: vanilla_pg(t, budget=1000, rng=0)):
        with pytest.raises(TypeError, match="gradient_batch"):  # the loops check when they start
            loop(Declares())


@pytest.mark.parametrize("signature", [
    "self, policy, n",  # too few
    "self, pol, n, rng=None, estimator='gpomdp', baseline=True, score_action='clipped'",  # a renamed parameter
    "self, n, policy, rng=None, estimator='gpomdp', baseline=True, score_action='clipped'",  # reordered
    "self, policy, n, rng, estimator, baseline, score_action, extra",  # a further parameter without a default
    "self, *args",
])
def test_a_hook_with_other_parameters_is_refused_naming_the_method(signature):
    namespace: dict = {}
    exec(f"def gradient_batch({signature}):\n    raise AssertionError('never called')", namespace)
    Wrong = type("Wrong", (Minimal, GradientBatch), {"gradient_batch": namespace["gradient_batch"]})
    with pytest.raises(TypeError, match=r"^Wrong\.gradient_batch must take \(policy, n, rng, estimator"):
        task_hooks(Wrong())
    with pytest.raises(TypeError, match=r"Wrong\.gradient_batch"):
        adaptive_pg(Wrong(), budget=1000, rng=0)


def test_a_further_optional_parameter_is_allowed():
    class Extra(Fused):
        def gradient_batch(self, policy, n, rng=None, estimator="gpomdp", baseline=True, score_action="clipped",
                           check=False):
            return super().gradient_batch(policy, n, rng, estimator, baseline, score_action)

    assert hooks_of(Extra()) == {"gradient_batch"}


@pytest.mark.parametrize("name,proto", [("measured_returns", "MeasuredReturns"), ("performance", "Performance"),
                                        ("gradient_batch", "GradientBatch"),
                                        ("performance_batch", "PerformanceBatch"),
                                        ("gradient_batch_constants", "GradientBatchConstants"),
                                        ("fixed_step_batches", "FixedStepBatches")])
def test_a_hook_defined_without_being_declared_is_refused(name, proto):
    Undeclared = type("Undeclared", (Minimal,), {name: lambda self, *a: None})
    with pytest.raises(TypeError, match=f"defines {name} but does not declare safepg.tasks.{proto}"):
        task_hooks(Undeclared())
    with pytest.raises(TypeError, match=name):
        vanilla_pg(Undeclared(), budget=1000, rng=0)


def test_a_task_without_the_required_interface_is_refused():
    class NoSimulate:
        reward_bound = feature_bound = action_volume = action_bound = 1.0
        gamma, horizon = 0.9, 20

    with pytest.raises(TypeError, match="'simulate'"):
        task_hooks(NoSimulate())


@pytest.mark.parametrize("dim", [0, -1, 1.0, "1", True])
def test_a_declared_action_dimension_must_be_a_positive_integer(dim):
    Wide = type("Wide", (Minimal, ActionDimension), {"action_dim": dim})
    with pytest.raises(TypeError, match="action_dim"):
        task_hooks(Wide())


def test_an_action_dimension_defined_without_being_declared_is_refused():
    Undeclared = type("Undeclared", (Minimal,), {"action_dim": 2})  # would silently learn a 1-row gain
    with pytest.raises(TypeError, match="defines action_dim but does not declare safepg.tasks.ActionDimension"):
        task_hooks(Undeclared())
    with pytest.raises(TypeError, match="declares ActionDimension but does not define action_dim"):
        task_hooks(type("Declares", (Minimal, ActionDimension), {})())


# ------------------------------------------------------------------ the settings of the bound constants
def read_everywhere(task) -> list:
    """Every reader of the settings: the check of the loops, the reader, the constants, a loop."""
    return [lambda: task_hooks(task), lambda: constants_settings(task), lambda: TaskConstants.from_task(task, 1.0),
            lambda: adaptive_pg(task, budget=1000, rng=0)]


@pytest.mark.parametrize("name,value", [("horizon_term", "horizon"), ("constants_gamma", 0.5)])
@pytest.mark.parametrize("where", ["class", "instance"])
def test_a_setting_defined_without_being_declared_is_refused(name, value, where):
    Undeclared = type("Undeclared", (Minimal,), {name: value} if where == "class" else {})
    task = Undeclared()
    if where == "instance":
        setattr(task, name, value)
    for read in read_everywhere(task):
        with pytest.raises(TypeError, match=f"^Undeclared defines {name} but does not declare "
                                            f"safepg.tasks.ConstantsSettings"):
            read()


@pytest.mark.parametrize("defined,missing", [
    ({"horizon_terms": "horizon", "constants_gamma": None}, "horizon_term"),  # misspelt
    ({"horizon_term": "horizon", "constant_gamma": 0.9}, "constants_gamma"),  # misspelt
    ({"horizon_term": "truncated"}, "constants_gamma"),  # declared half
    ({}, "horizon_term"),
])
def test_a_misspelt_or_half_declaration_is_refused(defined, missing):
    task = type("Declares", (Minimal, ConstantsSettings), defined)()
    for read in read_everywhere(task):
        with pytest.raises(TypeError, match=f"^Declares declares ConstantsSettings but does not define {missing}$"):
            read()


def test_a_task_without_settings_gets_the_defaults():
    task = Minimal()
    assert DEFAULT_CONSTANTS_SETTINGS == ("effective", None)
    assert constants_settings(task) == DEFAULT_CONSTANTS_SETTINGS
    k = TaskConstants.from_task(task, 1.0)
    assert (k.horizon_term, k.gamma) == ("effective", task.gamma)
    assert constants_settings(LQG.thesis_2d()) == DEFAULT_CONSTANTS_SETTINGS  # the LQG declares none


def test_declared_settings_are_read():
    class Settled(Minimal, ConstantsSettings):
        horizon_term = "truncated"
        constants_gamma = 0.8

    class InTheTasksGamma(Minimal, ConstantsSettings):  # None is a value: the task's own gamma
        horizon_term = "horizon"
        constants_gamma = None

    assert constants_settings(Settled()) == ("truncated", 0.8)
    k = TaskConstants.from_task(Settled(), 1.0)
    assert (k.horizon_term, k.gamma, k.H) == ("truncated", 0.8, 20)
    assert hooks_of(Settled()) == set()
    k = TaskConstants.from_task(InTheTasksGamma(), 1.0)
    assert (k.horizon_term, k.gamma) == ("horizon", 0.9)


def test_the_librarys_tasks_declare_their_settings():
    for task in (CartPole(horizon_term="truncated", constants_gamma=0.9), Pendulum(horizon_term="horizon")):
        assert ConstantsSettings in type(task).__mro__
        task_hooks(task)
    assert constants_settings(CartPole(horizon_term="truncated", constants_gamma=0.9)) == ("truncated", 0.9)
    assert constants_settings(Pendulum(horizon_term="horizon")) == ("horizon", None)
    assert constants_settings(CartPole()) == constants_settings(Pendulum()) == DEFAULT_CONSTANTS_SETTINGS
    assert ConstantsSettings not in LQG.__mro__


# ------------------------------------------------------------------ declared hooks are used
def test_a_minimal_task_learns_through_simulate():
    task = Minimal()
    assert hooks_of(task) == set() and task_hooks(task).action_dim == 1
    rec = adaptive_pg(task, 0.0, 1.0, budget=3000, rng=1)
    assert task.simulated == rec.iterations > 1
    assert np.all(np.isnan(rec.J)) and np.all(np.isfinite(rec.J_hat))  # no closed form declared


def test_a_declared_fused_batch_is_used_and_gives_the_lqgs_run():
    task = Fused()
    assert hooks_of(task) == {"gradient_batch"}
    kw = dict(error=ErrorModel("bernstein", range="empirical"), budget=20_000, rng=3)
    rec = adaptive_pg(task, 0.0, 1.0, **kw)
    assert task.fused == rec.iterations > 1 and task.simulated == 0
    lqg = adaptive_pg(LQG.thesis_1d(), 0.0, 1.0, **kw)  # the LQG's own fused path: the same numbers
    assert all(np.array_equal(getattr(rec, k), getattr(lqg, k)) for k in ARRAYS)
    assert np.all(np.isnan(rec.J)) and np.all(np.isfinite(lqg.J))  # the LQG also declares Performance
    van = vanilla_pg(task, 0.0, 1.0, batch_size=100, step=FixedStep(1e-3), budget=500, rng=0)
    assert task.fused == rec.iterations + van.iterations


def test_the_maxima_hook_is_used_with_batch_constants_only():
    calls = []

    class WithConstants(Fused, GradientBatchConstants):
        def gradient_batch_constants(self, policy, n, rng=None, estimator="gpomdp", baseline=True,
                                  score_action="clipped"):
            calls.append(n)
            samples, returns = self.lqg.gradient_batch(policy, n, rng, estimator, baseline, score_action)
            return samples, returns, (self.reward_bound, self.feature_bound)

    task = WithConstants()
    assert hooks_of(task) == {"gradient_batch", "gradient_batch_constants"}
    batch = adaptive_pg(task, 0.0, 1.0, departures=Departures(batch_constants=True), budget=2000, rng=0)
    assert calls == batch.batch_size.tolist() and task.fused == 0
    plain = adaptive_pg(task, 0.0, 1.0, budget=2000, rng=0)
    assert len(calls) == batch.iterations and task.fused == plain.iterations
    # The hook reported the bounds themselves, so the penalty and the run are the algorithm's.
    assert np.array_equal(batch.theta, plain.theta) and np.array_equal(batch.eps, plain.eps)


def test_declared_returns_and_closed_forms_are_used():
    class Described(Fused, MeasuredReturns, Performance, PerformanceBatch):
        def __init__(self) -> None:
            super().__init__()
            self.calls = {"measured_returns": 0, "performance": 0, "performance_batch": 0}

        def measured_returns(self, batch):
            self.calls["measured_returns"] += 1
            return batch.rewards.sum(axis=1)  # undiscounted

        def performance(self, theta, sigma):
            self.calls["performance"] += 1
            return self.lqg.performance(theta, sigma)

        def performance_batch(self, thetas, sigma):
            self.calls["performance_batch"] += 1
            return self.lqg.performance_batch(thetas, sigma)

    class Simulated(Minimal, MeasuredReturns, Performance):
        measured_returns = Described.measured_returns
        performance = Described.performance

        def __init__(self) -> None:
            super().__init__()
            self.calls = {"measured_returns": 0, "performance": 0}

    task = Described()
    assert hooks_of(task) == {"gradient_batch", "measured_returns", "performance", "performance_batch"}
    rec = adaptive_pg(task, 0.0, 1.0, budget=1000, rng=0)
    # The fused batch brings its own returns; the batch form of J is preferred.
    assert task.calls == {"measured_returns": 0, "performance": 0, "performance_batch": 1}
    np.testing.assert_array_equal(rec.J, LQG.thesis_1d().performance_batch(rec.theta, 1.0))
    task = Simulated()
    rec = vanilla_pg(task, -0.3, 1.0, batch_size=100, step=FixedStep(1e-3), budget=300, rng=1)
    assert task.calls == {"measured_returns": 3, "performance": 4}  # each batch; each theta of the record
    batch = task.lqg.simulate(rec_policy(-0.3), 100, np.random.default_rng(1))
    assert rec.J_hat[0] == pytest.approx(batch.rewards.sum(axis=1).mean(), rel=1e-12)
    np.testing.assert_allclose(rec.J, [task.lqg.performance(t, 1.0) for t in rec.theta], rtol=1e-12)


def rec_policy(theta):
    from safepg.policies import LinearGaussianPolicy

    return LinearGaussianPolicy(np.array([[theta]]), 1.0)


def test_a_declared_action_dimension_shapes_theta():
    class Two(Minimal, ActionDimension):
        action_dim = 2

    assert task_hooks(Two()).action_dim == 2
    with pytest.raises(ValueError, match="^theta0 must have a multiple of 2"):
        adaptive_pg(Two(), np.zeros(3), 1.0, budget=1000, rng=0)


# ------------------------------------------------------------------ the library's tasks
def test_the_lqg_declares_its_fused_batch_and_closed_forms():
    for env in (LQG.thesis_1d(), LQG.thesis_2d()):
        assert hooks_of(env) == {"gradient_batch", "performance", "performance_batch"}
        assert task_hooks(env).action_dim == env.dim
        h = task_hooks(env)
        assert h.gradient_batch.__self__ is env and h.performance_batch.__func__ is type(env).performance_batch


def test_the_cartpole_declares_its_batches_and_measured_returns():
    for env in (CartPole.thesis(), CartPole.thesis_doubled()):
        assert hooks_of(env) == {"gradient_batch", "gradient_batch_constants", "measured_returns"}
        assert task_hooks(env).action_dim == 1
    rec = adaptive_pg(CartPole.thesis(), np.zeros(4), 1.0, batches=Batches(10, 100), budget=40, rng=0)
    assert np.all(np.isnan(rec.J)) and np.all(rec.J_hat >= 1)  # undiscounted episode lengths


def test_a_gym_task_declares_its_measured_returns():
    import_or_fail("gymnasium")
    from safepg.envs.gym_task import GymTask

    task = GymTask("Pendulum-v1", horizon=5, gamma=0.9, reward_bound=17.0, feature_bound=8.0)
    try:
        assert hooks_of(task) == {"measured_returns"}
        assert task_hooks(task).action_dim == 1
        assert ConstantsSettings in type(task).__mro__ and constants_settings(task) == DEFAULT_CONSTANTS_SETTINGS
    finally:
        task.close()
    task = GymTask("Pendulum-v1", horizon=5, gamma=0.9, reward_bound=17.0, feature_bound=8.0, horizon_term="horizon")
    try:
        assert constants_settings(task) == ("horizon", None)
        assert TaskConstants.from_task(task, 1.0).horizon_term == "horizon"
    finally:
        task.close()


def test_a_definition_hook_is_used_only_where_declared():
    """``definition()`` writes a task into its run's key only where the class declares it: a method of
    that name left undeclared would silently decide (or not) what the key hashes."""
    import dataclasses

    from safepg.definition import from_dict, to_dict
    from safepg.tasks import Definition

    @dataclasses.dataclass(frozen=True)
    class Undeclared:
        gain: float = 1.0

        def definition(self) -> dict[str, float]:
            return {"gain": 2 * self.gain}

    @dataclasses.dataclass(frozen=True)
    class Declared(Definition):
        gain: float = 1.0

        def definition(self) -> dict[str, float]:
            return {"gain": self.gain, "written": True}

    with pytest.raises(TypeError, match="defines definition but does not declare safepg.tasks.Definition"):
        to_dict(Undeclared())
    assert to_dict(Declared(2))["gain"] == 2.0 and to_dict(Declared(2))["written"] is True
    with pytest.raises(TypeError, match="declares Definition but does not define definition"):
        to_dict(type("Half", (Definition,), {})())
    assert to_dict(from_dict(to_dict(LQG(gamma=0.5)))) == to_dict(LQG(gamma=0.5))
