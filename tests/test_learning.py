"""Learning loops: determinism, record invariants, metrics, bad input."""

import argparse
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest

from safepg.cli import main
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.learning import adaptive_pg, learn, vanilla_pg
from safepg.meta import coordinate_step, penalty_constant
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.record import LearningRecord
from safepg.tasks import MeasuredReturns

ENV = LQG.thesis_1d()
ARRAYS = ("batch_size", "alpha", "coordinate", "theta", "J", "J_hat", "grad", "eps", "safe")


def _equal(a: LearningRecord, b: LearningRecord) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ARRAYS)


@pytest.mark.parametrize("bound,er", [("chebyshev", False), ("hoeffding", True), ("bernstein", True)])
def test_same_seed_same_record(bound, er):
    kw = dict(error=ErrorModel(bound, range="empirical" if er else "lemma"), budget=20_000)
    a, b = adaptive_pg(ENV, rng=5, **kw), adaptive_pg(ENV, rng=5, **kw)
    assert _equal(a, b)
    assert not _equal(a, adaptive_pg(ENV, rng=6, **kw))


def test_adaptive_record_invariants():
    rec = adaptive_pg(ENV, 0.0, 1.0, error=ErrorModel("bernstein", range="empirical"), budget=50_000, rng=1)
    I = rec.iterations
    assert rec.trajectories == 50_000 and rec.batch_size[0] == 100
    assert rec.theta.shape == (I + 1, 1) and rec.J.shape == (I + 1,)
    assert np.all(rec.batch_size[:-1] >= 100) and np.all(rec.batch_size <= 500_000)
    np.testing.assert_allclose(rec.J, [ENV.performance(t, 1.0) for t in rec.theta])
    # theta moves by alpha * g_k on the chosen coordinate, with Corollary 4.2.8's alpha.
    np.testing.assert_allclose(np.diff(rec.theta[:, 0]), rec.alpha * rec.grad[:, 0])
    c = penalty_constant(TaskConstants.from_task(ENV, 1.0))
    np.testing.assert_allclose(rec.alpha, [coordinate_step(abs(g), e, c) for g, e in zip(rec.grad[:, 0], rec.eps)])
    assert np.array_equal(rec.safe, rec.eps < np.abs(rec.grad[:, 0]))
    assert rec.improvement_ratio() == 1.0 and rec.J[-1] > rec.J[0]


def test_two_dimensional_coordinate_descent_moves_one_entry():
    env = LQG.thesis_2d()
    rec = adaptive_pg(env, np.zeros(4), 1.0, error=ErrorModel("bernstein", range="empirical"), budget=20_000, rng=0)
    moved = np.count_nonzero(np.diff(rec.theta, axis=0), axis=1)
    assert np.all(moved <= 1)
    assert set(rec.coordinate.tolist()) <= {0, 3}  # the diagonal gains dominate from theta = 0


def test_metrics():
    rec = adaptive_pg(ENV, 0.0, 1.0, error=ErrorModel("bernstein", range="empirical"), budget=30_000, rng=2)
    assert rec.upsilon_bar() == pytest.approx(np.sum(rec.batch_size * rec.J_hat) / rec.batch_size.sum())
    J = np.array([-3.0, -2.0, -2.5, -2.5, -1.0])
    fake = LearningRecord(np.array([10, 20, 30, 40]), *(np.zeros(4),) * 2, np.zeros((5, 1)), J,
                          np.zeros(4), np.zeros((4, 1)), np.zeros(4), np.ones(4, bool))
    assert fake.improvement_ratio() == 0.75
    ends = {"10": J[0], "11": J[1], "30": J[1], "31": J[2], "100": J[3]}
    assert fake.J_at(tuple(int(k) for k in ends)) == ends


def test_vanilla_fixed_step():
    rec = vanilla_pg(ENV, -0.55, 0.5, batch_size=100, step=FixedStep(1e-4), budget=5_000, rng=3)
    assert rec.iterations == 50 and np.all(rec.batch_size == 100)
    np.testing.assert_allclose(np.diff(rec.theta[:, 0]), 1e-4 * rec.grad[:, 0])


def test_vanilla_adaptive_steps_in_two_dimensions():
    env = LQG.thesis_2d()
    kw = dict(batch_size=2000, budget=20_000, rng=4)
    error = ErrorModel("chebyshev", 0.95)
    scal = vanilla_pg(env, np.zeros(4), 1.0, step=SafeStep("scalar", error), **kw)
    coord = vanilla_pg(env, np.zeros(4), 1.0, step=SafeStep("coordinate", error), **kw)
    assert np.all(np.count_nonzero(np.diff(coord.theta, axis=0), axis=1) <= 1)
    assert np.all(scal.coordinate == -1)
    # Same seed, same first batch: Corollary 4.2.5's ordering of the two steps.
    np.testing.assert_array_equal(scal.grad[0], coord.grad[0])
    assert coord.alpha[0] > scal.alpha[0] > 0
    assert coord.J[-1] > coord.J[0] and scal.J[-1] > scal.J[0]


def test_save_load_roundtrip(tmp_path):
    rec = adaptive_pg(ENV, budget=5_000, rng=1)
    rec.save(tmp_path / "r.npz")
    back = LearningRecord.load(tmp_path / "r.npz")
    assert _equal(rec, back) and back.config == json.loads(json.dumps(rec.config))


def test_interrupt_keeps_what_was_computed():
    calls = {"n": 0}

    class Flaky(LQG):
        def gradient_batch(self, policy, n, rng=None, estimator="gpomdp", baseline=True, score_action="clipped"):
            calls["n"] += 1
            if calls["n"] == 4:
                raise KeyboardInterrupt
            return super().gradient_batch(policy, n, rng, estimator, baseline, score_action)

    with pytest.warns(UserWarning, match="interrupted"):
        rec = adaptive_pg(Flaky(), budget=100_000, rng=0)
    assert rec.interrupted and rec.iterations == 3 and rec.theta.shape == (4, 1)


def test_progress_callable_reports_each_batch_and_can_cancel(capsys):
    seen = []
    rec = adaptive_pg(ENV, budget=20_000, rng=3, progress=lambda used, budget: seen.append((used, budget)))
    # One call per batch, with the trajectories used so far; no tqdm bar beside it.
    assert [u for u, _ in seen] == np.cumsum(rec.batch_size).tolist() and seen[-1] == (20_000, 20_000)
    assert capsys.readouterr().err == ""
    assert _equal(rec, adaptive_pg(ENV, budget=20_000, rng=3))  # reporting changes nothing

    class Cancelled(Exception):
        pass

    def cancel_at_third(used: int, budget: int) -> None:
        seen.append(used)
        if len(seen) == 3:
            raise Cancelled

    seen = []
    with pytest.raises(Cancelled):
        vanilla_pg(ENV, batch_size=100, budget=100_000, rng=0, progress=cancel_at_third)
    assert seen == [100, 200, 300]  # stopped at once: no fourth batch was drawn


@pytest.mark.parametrize(
    "kwargs,name",
    [(lambda: {"error": ErrorModel(delta=1.2)}, "delta"), (lambda: {"error": ErrorModel(delta=0.0)}, "delta"),
     (lambda: {"sigma": 0.0}, "sigma"), (lambda: {"sigma": -1.0}, "sigma"),
     (lambda: {"batches": Batches(n_min=600_000)}, "n_min"), (lambda: {"budget": 50}, "budget"),
     (lambda: {"theta0": np.nan}, "theta"), (lambda: {"theta0": [0.0, 0.0]}, "theta")],
)
def test_bad_input_names_the_parameter(kwargs, name):
    # The options check themselves when built, the loop checks the rest: either way, by name.
    with pytest.raises(ValueError, match=f"^{name}"):
        adaptive_pg(ENV, **{"budget": 1000, **kwargs()})


def test_nan_gradient_raises():
    class Broken(LQG):
        def gradient_batch(self, policy, n, rng=None, estimator="gpomdp", baseline=True, score_action="clipped"):
            samples, returns = super().gradient_batch(policy, n, rng, estimator, baseline, score_action)
            samples[0, 0] = np.nan
            return samples, returns

    with pytest.raises(ValueError, match="^gradient estimate is not finite"):
        adaptive_pg(Broken(), budget=1000, rng=0)


# ------------------------------------------------------------------ learn is the loop, the others build its method
def _same_run(a: LearningRecord, b: LearningRecord) -> bool:
    """Equal arrays, bit for bit, the same ending and the same ``config``."""
    ends = ("interrupted", "diverged", "reached_target")
    return _equal(a, b) and all(getattr(a, k) == getattr(b, k) for k in ends) and a.config == b.config


@pytest.mark.parametrize("options", [
    dict(error=ErrorModel("bernstein", range="empirical")),
    # Every option set, the authors' departures included (batch_constants measures each batch).
    dict(gradient=Gradient("reinforce"), error=ErrorModel("hoeffding", 0.95, 1280.0), batches=Batches(10, 5000, 300),
         departures=Departures(True, True, True)),
], ids=["bernstein", "authors"])
def test_adaptive_pg_is_learn_with_an_adaptive(options):
    wrapped = adaptive_pg(ENV, -0.1, 0.8, **options, budget=10_000, rng=np.random.default_rng(2))
    direct = learn(ENV, Adaptive(**options), -0.1, 0.8, budget=10_000, rng=np.random.default_rng(2))
    assert wrapped.iterations >= 3 and _same_run(wrapped, direct)


@pytest.mark.parametrize("method", [
    Vanilla(100, FixedStep(1e-3)),  # the task's compiled loop
    Vanilla(200, SafeStep("coordinate", ErrorModel("chebyshev")), Gradient(baseline=False), Target(-1.5)),
], ids=["fixed", "safe-target"])
def test_vanilla_pg_is_learn_with_a_vanilla(method):
    m = method
    wrapped = vanilla_pg(ENV, -0.2, 0.8, batch_size=m.batch_size, step=m.step, gradient=m.gradient, target=m.target,
                         budget=5_000, rng=np.random.default_rng(2))
    direct = learn(ENV, method, -0.2, 0.8, budget=5_000, rng=np.random.default_rng(2))
    assert wrapped.iterations >= 3 and _same_run(wrapped, direct)


@pytest.mark.parametrize("bad", [ErrorModel(), FixedStep(1e-3), "adaptive", None], ids=repr)
def test_learn_refuses_a_method_that_is_neither_adaptive_nor_vanilla(bad):
    # Refused by name before anything else is checked: this budget is bad too.
    with pytest.raises(TypeError, match=r"^method must be an Adaptive or a Vanilla, got "):
        learn(ENV, bad, budget=1)


def test_cli_learn_json(capsys):
    assert main(["learn", "--budget", "120000", "--bound", "bernstein", "--range", "empirical",
                 "--quiet", "--seed", "3"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("iterations", "trajectories", "theta", "J_initial", "J_star", "J_final", "J_at",
                "upsilon_bar", "improvement_ratio", "batch_sizes"):
        assert key in out
    # The run's own checkpoints: its quarters.
    assert out["trajectories"] == 120_000 and list(out["J_at"]) == ["30000", "60000", "90000", "120000"]
    assert out["J_initial"] == pytest.approx(-56.667, abs=1e-3)
    assert out["J_star"] == pytest.approx(-13.207, abs=1e-3)
    assert len(out["batch_sizes"]) == out["iterations"]
    # The run's definition, in the option objects' names.
    assert out["config"]["method"]["error"] == {"type": "ErrorModel", "bound": "bernstein", "delta": 0.95,
                                                "range": "empirical"}


def test_cli_vanilla(capsys):
    assert main(["learn", "--alpha", "1e-4", "--batch-size", "100", "--budget", "2000",
                 "--theta0", "-0.55", "--sigma", "0.5", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["batch_sizes"] == [100] * 20
    assert out["config"]["method"]["step"] == {"type": "FixedStep", "alpha": 1e-4, "kind": "scalar"}


@pytest.mark.parametrize("args,method", [
    (["--first", "300", "--maxima", "--unguarded-step", "--no-baseline"],
     Adaptive(Gradient(baseline=False), batches=Batches(first=300), departures=Departures(maxima=True,
                                                                                          unguarded_step=True))),
    (["--batch-size", "200", "--safe-step", "coordinate", "--bound", "hoeffding", "--range", "1280"],
     Vanilla(200, SafeStep("coordinate", ErrorModel("hoeffding", 0.95, 1280.0)))),
    (["--batch-size", "200", "--alpha", "0.01", "--kind", "coordinate", "--target", "-20", "--update"],
     Vanilla(200, FixedStep(0.01, "coordinate"), target=Target(-20.0, True))),
])
def test_cli_flags_are_the_option_objects_fields(args, method):
    from safepg.cli import _learn_parser, _method

    parser = argparse.ArgumentParser()
    _learn_parser(parser.add_subparsers())
    assert _method(parser.parse_args(["learn", *args])) == method


@pytest.mark.parametrize("args,word", [(["--delta", "1.5"], "delta"), (["--sigma", "0"], "sigma"),
                                       (["--n-min", "10", "--n-max", "5"], "n_min"),
                                       (["--alpha", "0.1"], "--batch-size"),
                                       (["--batch-size", "100"], "--alpha")])
def test_cli_bad_input_one_line_no_traceback(args, word):
    p = subprocess.run([sys.executable, "-m", "safepg", "learn", "--quiet", "--budget", "1000", *args],
                       capture_output=True, text=True)
    assert p.returncode != 0
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0] and "Traceback" not in p.stderr


def test_divergence_stops_only_when_asked():
    # b = 0 and a large fixed step: theta runs away until the gradient overflows.
    kw = dict(batch_size=100, step=FixedStep(1e-2), gradient=Gradient(baseline=False), budget=2_000_000, rng=0)
    with pytest.raises(ValueError, match="^gradient estimate is not finite"):
        vanilla_pg(ENV, -0.55, 1.0, **kw)
    rec = vanilla_pg(ENV, -0.55, 1.0, stop_on_divergence=True, **kw)
    assert rec.diverged and rec.trajectories < 2_000_000 and np.all(np.isfinite(rec.grad))


def test_target_return_stops_at_the_first_batch_that_reaches_it():
    kw = dict(batch_size=200, step=FixedStep(1e-3), budget=200 * 40, rng=4)
    full = vanilla_pg(ENV, -0.1, 1.0, **kw)
    target = float(np.sort(full.J_hat)[-5])  # reached, but not at the first batch
    first = int(np.argmax(full.J_hat >= target))
    rec = vanilla_pg(ENV, -0.1, 1.0, target=Target(target), **kw)
    assert rec.reached_target and not full.reached_target
    assert rec.iterations == first + 1
    np.testing.assert_array_equal(rec.J_hat, full.J_hat[: first + 1])
    # The batch that reached the target makes no update: the result is the policy that reached it.
    assert rec.alpha[-1] == 0 and np.array_equal(rec.theta[-1], rec.theta[-2])
    np.testing.assert_array_equal(rec.theta[:-1], full.theta[: first + 1])
    with pytest.raises(ValueError, match="^target value"):
        vanilla_pg(ENV, batch_size=100, budget=1000, target=Target(float("nan")))


def test_measured_returns_hook_sets_J_hat():
    class Undiscounted(_Simulated, MeasuredReturns):
        """An LQG reporting undiscounted returns, through the hook the cart-pole uses (and
        without the fused path, so that the loop simulates the batch)."""

        def measured_returns(self, batch):
            return batch.rewards.sum(axis=1)

    env = Undiscounted(dim=1, gamma=0.9, horizon=20)
    rec = vanilla_pg(env, -0.3, 1.0, batch_size=300, step=FixedStep(1e-3), budget=600, rng=1)
    batch = env.simulate(LinearGaussianPolicy(np.array([[-0.3]]), 1.0), 300, np.random.default_rng(1))
    assert rec.J_hat[0] == pytest.approx(batch.rewards.sum(axis=1).mean(), rel=1e-12)
    assert rec.J_hat[0] != pytest.approx(batch.discounted_returns().mean(), rel=1e-3)


# ------------------------------------------------------------------ the authors' ways of running
ENV2 = LQG.thesis_2d(gamma=0.9)


class _Simulated:
    """An LQG without its fused path (it declares none of safepg.tasks' hooks): the loops simulate
    the batch and apply gradient_samples to it."""

    def __init__(self, **fields):
        self._lqg = LQG(**fields)

    def __getattr__(self, name):
        # Not the LQG's action_dim: a task that has it without declaring safepg.tasks.ActionDimension
        # is refused, and the 1-D LQG's is the default (1) anyway.
        if name == "action_dim":
            raise AttributeError(name)
        return getattr(self.__dict__["_lqg"], name)


def _first_batch(env, theta0, n, seed):
    """The first batch an adaptive run with ``rng=seed`` draws: samples and returns."""
    pol = LinearGaussianPolicy(np.asarray(theta0, float).reshape(env.dim, env.dim), 1.0)
    return env.gradient_batch(pol, n, np.random.default_rng(seed))


def test_n_first_sets_only_the_first_batch():
    kw = dict(error=ErrorModel("bernstein", range="empirical"), budget=20_000)
    rec = adaptive_pg(ENV, batches=Batches(n_min=10, first=1000), rng=np.random.default_rng(3), **kw)
    assert rec.batch_size[0] == 1000 and rec.config["method"]["batches"]["first"] == 1000
    # The rest follows N* clipped to [n_min, n_max]; without n_first the first batch is n_min.
    assert 1000 not in rec.batch_size[1:-1]
    default = adaptive_pg(ENV, batches=Batches(n_min=10), rng=3, **kw)
    assert default.batch_size[0] == 10 and "n_first" not in default.config
    with pytest.raises(ValueError, match="^first "):
        Batches(first=1)
    with pytest.raises(ValueError, match="^budget "):
        adaptive_pg(ENV, batches=Batches(first=2000), budget=1000)


def test_statistics_max_uses_the_largest_variance_and_range_over_components():
    from safepg.bounds import bernstein

    kw = dict(error=ErrorModel("bernstein", range="empirical"), budget=300, batches=Batches(first=300))
    rec = adaptive_pg(ENV2, np.zeros(4), departures=Departures(maxima=True), rng=np.random.default_rng(8), **kw)
    samples, _ = _first_batch(ENV2, np.zeros(4), 300, 8)
    k = int(rec.coordinate[0])
    var, rng_ = np.var(samples, axis=0, ddof=1), np.ptp(samples, axis=0)
    assert rec.eps[0] == pytest.approx(bernstein(0.95, var.max(), rng_.max()).eps(300), rel=1e-12)
    own = adaptive_pg(ENV2, np.zeros(4), rng=np.random.default_rng(8), **kw)
    assert own.eps[0] == pytest.approx(bernstein(0.95, var[k], rng_[k]).eps(300), rel=1e-12)
    assert rec.eps[0] > own.eps[0]  # the maxima are the more conservative choice here
    with pytest.raises(ValueError, match="^maxima "):
        Departures(maxima="max")


def test_constants_batch_measures_R_and_M_phi_on_each_batch():
    # The 1-D LQG without its fused path: the loop measures the maxima on the simulated batch.
    env = _Simulated(dim=1, gamma=0.9, horizon=20)
    kw = dict(error=ErrorModel("bernstein", range="empirical"), budget=400, batches=Batches(first=400))
    rec = adaptive_pg(env, -0.5, 0.1, departures=Departures(batch_constants=True, unguarded_step=True),
                      rng=np.random.default_rng(2), **kw)
    batch = env.simulate(LinearGaussianPolicy(np.array([[-0.5]]), 0.1), 400, np.random.default_rng(2))
    R, M = np.abs(batch.rewards).max(), np.abs(batch.features).max()
    assert R < env.reward_bound and M < env.feature_bound  # measured values are below the bounds ...
    bounds = TaskConstants.from_task(env, 0.1)
    c = penalty_constant(TaskConstants(R, M, bounds.action_volume, bounds.A_bar, 0.9, 20, 0.1))
    g = abs(rec.grad[0, 0])
    assert rec.alpha[0] == pytest.approx(coordinate_step(g, rec.eps[0], c, guarded=False), rel=1e-12)
    # ... so the penalty is smaller and the step larger than with the bounds (config["c"] keeps the latter).
    assert rec.config["c"] == penalty_constant(bounds) > c
    with pytest.raises(ValueError, match="^batch_constants "):
        Departures(batch_constants="batch")


def test_step_when_unsafe_moves_where_the_algorithm_stops():
    # Chebyshev at N = 100 from theta = 0: eps exceeds |g| on the first batch.
    kw = dict(budget=100, rng=0)
    guarded, unguarded = adaptive_pg(ENV, **kw), adaptive_pg(ENV, departures=Departures(unguarded_step=True), **kw)
    assert not guarded.safe[0] and not unguarded.safe[0]
    assert guarded.alpha[0] == 0.0 and unguarded.alpha[0] > 0.0
    g, eps = abs(unguarded.grad[0, 0]), unguarded.eps[0]
    c = penalty_constant(TaskConstants.from_task(ENV, 1.0))
    assert unguarded.alpha[0] == (g - eps) ** 2 / (2 * c * (g + eps) ** 2)
    assert coordinate_step(1.0, 2.0, 1.0) == 0.0 and coordinate_step(1.0, 2.0, 1.0, guarded=False) == 1 / 18
    assert coordinate_step(0.0, 0.0, 1.0, guarded=False) == 0.0


def test_update_at_target_updates_before_stopping():
    kw = dict(batch_size=200, step=FixedStep(1e-3), budget=200 * 40, rng=4)
    kept = vanilla_pg(ENV, -0.1, 1.0, target=Target(-1e9), **kw)
    updated = vanilla_pg(ENV, -0.1, 1.0, target=Target(-1e9, update=True), **kw)
    assert kept.reached_target and updated.reached_target and kept.iterations == updated.iterations == 1
    assert kept.theta[-1] == kept.theta[0] and updated.theta[-1] != updated.theta[0]
    np.testing.assert_allclose(updated.theta[-1] - updated.theta[0], 1e-3 * updated.grad[0])
    assert updated.config["method"]["target"]["update"] is True and kept.config["method"]["target"]["update"] is False


def test_run_config_passes_the_options_and_hashes_its_definition():
    from safepg.options import Adaptive, Vanilla
    from safepg.runner import RESULTS_VERSION, RunConfig

    plain = RunConfig("a", budget=2000)
    # The key hashes the whole definition and the results version, nothing else.
    blob = json.dumps([plain.definition(), RESULTS_VERSION], sort_keys=True)
    assert plain.key() == hashlib.sha256(blob.encode()).hexdigest()[:16]
    opts = RunConfig("a", budget=2000, method=Adaptive(batches=Batches(first=500), departures=Departures(
        batch_constants=True, maxima=True, unguarded_step=True)))
    first100 = RunConfig("a", budget=2000, method=Adaptive(batches=Batches(first=100)))
    assert len({plain.key(), opts.key(), first100.key()}) == 3
    rec = opts.run(0)
    assert rec.batch_size[0] == 500
    assert rec.config["method"]["batches"]["first"] == 500
    assert rec.config["method"]["departures"] == {"type": "Departures", "batch_constants": True, "maxima": True,
                                                  "unguarded_step": True}
    # An option of the other method cannot be given at all; a method must be one of the two.
    with pytest.raises(TypeError):
        Vanilla(100, FixedStep(1e-3), batches=Batches(first=200))  # type: ignore[call-arg]
    with pytest.raises(TypeError, match="^method "):
        RunConfig("a", budget=1000, method="vanilla")  # type: ignore[arg-type]
