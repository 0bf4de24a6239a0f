"""The cart-pole sweep over the settings the thesis leaves unstated: the settings as CartPole /
TaskConstants parameters, the generalised penalty constant, the analytic grid, the sweep's
experiments and its summaries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from safepg.constants import TaskConstants
from safepg.envs.cartpole import NORMALISED_SCALE, CartPole
from safepg.estimators import gradient_samples
from safepg.learning import LearningRecord
from safepg.meta import penalty_constant
from safepg.options import ErrorModel, FixedStep
from safepg.policies import LinearGaussianPolicy
from safepg.thesis.cartpole_sweep import (
    CAN_MOVE_SHARE,
    LEARNS_MARGIN,
    THESIS,
    VANILLA_ALPHA,
    drawdown,
    late_minus_early,
    max_safe_step,
    penalty_grid,
    relative_move,
    smallest_c_by_gamma,
    sweep_summary,
    sweep_table,
)
from safepg.thesis.experiments import EXPERIMENTS, get_experiment, make_env
from safepg.thesis.sweep_settings import CARTPOLE_SWEEP, SWEEP_BUDGET

#: c of our default doubled-pole setting (R 1, M_phi 10, |A| 20, gamma 0.99, sigma 1), as the chapter prints it.
DEFAULT_C = 57478845.60802851


def printed_c(R: float, M: float, A: float, gamma: float, sigma: float = 1.0) -> float:
    """Theorem 4.2.3's constant exactly as printed (infinite horizon)."""
    return R * M**2 / ((1 - gamma) ** 2 * sigma**2) * (A / (math.sqrt(2 * math.pi) * sigma) + gamma / (2 * (1 - gamma)))


# ------------------------------------------------------------------ penalty constant
def test_default_penalty_constant_is_unchanged() -> None:
    c = penalty_constant(TaskConstants.from_task(CartPole.thesis_doubled(), 1.0))
    assert c == DEFAULT_C == printed_c(1, 10, 20, 0.99)
    assert TaskConstants.from_task(CartPole.thesis_doubled(), 1.0).horizon_term == "effective"


@pytest.mark.parametrize("gamma", [0.9, 0.99, 0.999])
def test_horizon_terms(gamma: float) -> None:
    k = dict(R=1.0, M_phi=2.0, action_volume=20.0, A_bar=10.0, gamma=gamma, H=200, sigma=1.0)
    eff = TaskConstants(**k)
    trunc = TaskConstants(**k, horizon_term="truncated")
    hor = TaskConstants(**k, horizon_term="horizon")
    assert eff.horizon_factor == pytest.approx(1 / (1 - gamma))
    assert trunc.horizon_factor == pytest.approx((1 - gamma**200) / (1 - gamma))
    assert hor.horizon_factor == 200
    # The generalised formula with h = 1 / (1 - gamma) is the printed one.
    h = eff.horizon_factor
    general = 4 * h**2 * (20 / math.sqrt(2 * math.pi) + gamma * h / 2)
    assert penalty_constant(eff) == pytest.approx(general, rel=1e-12)
    h = trunc.horizon_factor
    assert penalty_constant(trunc) == pytest.approx(4 * h**2 * (20 / math.sqrt(2 * math.pi) + gamma * h / 2))
    # Cutting the sums at H can only shrink c; the undiscounted H = 200 bound is larger.
    assert penalty_constant(trunc) <= penalty_constant(eff) * (1 + 1e-12)
    assert penalty_constant(hor) >= penalty_constant(trunc)


def test_long_horizon_truncated_tends_to_effective() -> None:
    k = dict(R=1.0, M_phi=1.0, action_volume=2.0, A_bar=1.0, gamma=0.9, sigma=1.0)
    assert penalty_constant(TaskConstants(**k, H=10_000, horizon_term="truncated")) == pytest.approx(
        penalty_constant(TaskConstants(**k, H=10_000)), rel=1e-12)


def test_undiscounted_needs_a_finite_horizon_term() -> None:
    k = dict(R=1.0, M_phi=1.0, action_volume=2.0, A_bar=1.0, gamma=1.0, H=200, sigma=1.0)
    with pytest.raises(ValueError, match="^gamma "):
        TaskConstants(**k)
    for term in ("truncated", "horizon"):
        assert TaskConstants(**k, horizon_term=term).horizon_factor == 200
    with pytest.raises(ValueError, match="^horizon_term "):
        TaskConstants(**{**k, "gamma": 0.9}, horizon_term="infinite")
    with pytest.raises(ValueError, match="^gamma "):
        TaskConstants(**{**k, "gamma": 1.5}, horizon_term="horizon")


def test_task_settings_reach_the_constants() -> None:
    task = CartPole.thesis_doubled(gamma=0.995, feature_bound=1.0, action_space_volume=2.0, reward_bound=3.0,
                                   horizon_term="truncated")
    k = TaskConstants.from_task(task, 1.0)
    assert (k.R, k.M_phi, k.action_volume, k.A_bar, k.gamma, k.H, k.horizon_term) == (
        3.0, 1.0, 2.0, 10.0, 0.995, 200, "truncated")
    assert CartPole().action_volume == 20.0


# ------------------------------------------------------------------ analytic grid
def test_penalty_grid() -> None:
    rows = penalty_grid()
    ours = [r for r in rows if (r["gamma"], r["horizon_term"], r["M_phi"], r["A_volume"], r["R"])
            == (0.99, "effective", 10.0, 20.0, 1.0)]
    assert len(ours) == 1 and ours[0]["c"] == DEFAULT_C
    assert ours[0]["max_step"] == pytest.approx(8.7e-9, rel=0.01)
    assert not any(r["gamma"] == 1 and r["horizon_term"] == "effective" for r in rows)
    for r in rows:
        assert r["max_step"] == max_safe_step(r["c"]) == 1 / (2 * r["c"])
        assert r["step_at_n_star"] < r["max_step"]
        assert r["can_move"] == (r["max_step"] >= CAN_MOVE_SHARE * VANILLA_ALPHA)
    # Only discounts below 0.99 bring c under the threshold, whatever the other constants.
    assert {r["gamma"] for r in rows if r["can_move"]} == {0.9, 0.95}
    best = {r["gamma"]: r for r in smallest_c_by_gamma(rows)}
    assert best[0.99]["c"] > 3e5 and best[0.9]["c"] < 1e3
    assert (best[0.99]["M_phi"], best[0.99]["A_volume"], best[0.99]["R"]) == (1.0, 2.0, 1.0)


# ------------------------------------------------------------------ task names and settings
def test_names_round_trip() -> None:
    tasks = [CartPole(), CartPole.thesis_doubled(), CartPole(gamma=0.995, integrator="semi-implicit"),
             CartPole.thesis_doubled(feature_scale=NORMALISED_SCALE, feature_bound=1.0, horizon_term="horizon"),
             CartPole(angle_threshold_deg=12.0, tau=0.01, init_bound=0.1, horizon=150, action_space_volume=2.0)]
    for task in tasks:
        assert CartPole.from_name(task.setting_name()) == task
        assert make_env(task.setting_name()) == task
    assert CartPole().setting_name() == "cartpole"
    assert CartPole.thesis_doubled(gamma=0.9).setting_name() == "cartpole-doubled[gamma=0.9]"


@pytest.mark.parametrize("name", ["cartpole-tripled", "cartpole[gamma=0.9", "cartpole[colour=red]",
                                  "cartpole[pole_length=3]", "cartpole[gamma]", "cartpole[gamma=abc]",
                                  "cartpole[feature_scale=1/2]"])
def test_bad_names(name: str) -> None:
    with pytest.raises(ValueError, match="^(name|gamma|feature_scale) "):
        CartPole.from_name(name)


@pytest.mark.parametrize(("field", "value"), [("integrator", "rk4"), ("horizon_term", "infinite"),
                                              ("feature_scale", (1.0, 2.0, 3.0)), ("feature_scale", [1, 1, 1, 1]),
                                              ("feature_scale", (1.0, 0.0, 1.0, 1.0)),
                                              ("action_space_volume", -2.0), ("reward_bound", 0.0)])
def test_bad_settings(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=rf"^{field} "):
        CartPole(**{field: value})


def test_normalised_features_fused_matches_reference() -> None:
    task = CartPole.thesis_doubled(feature_scale=NORMALISED_SCALE, feature_bound=1.0)
    pol = LinearGaussianPolicy(np.array([1.0, 2.0, 40.0, 8.0]) * np.array(NORMALISED_SCALE), 8.0)
    batch = task.simulate(pol, 1500, 4)
    assert np.abs(batch.features).max() <= 1.0  # the normalised features are bounded by M_phi = 1
    for estimator in ("gpomdp", "reinforce"):
        samples, returns = task.gradient_batch(pol, 1500, 4, estimator)
        np.testing.assert_allclose(samples, gradient_samples(pol, batch, estimator), rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(returns, task.undiscounted_returns(batch))


def test_normalised_features_are_a_reparametrisation() -> None:
    """The same policy in normalised units gives the same episodes and the raw gradient / scale."""
    raw_task = CartPole.thesis_doubled()
    norm_task = CartPole.thesis_doubled(feature_scale=NORMALISED_SCALE)
    K = np.array([1.0, 2.0, 40.0, 8.0])
    scale = np.array(NORMALISED_SCALE)
    raw = raw_task.gradient_batch(LinearGaussianPolicy(K, 8.0), 1000, 6)
    norm = norm_task.gradient_batch(LinearGaussianPolicy(K * scale, 8.0), 1000, 6)
    np.testing.assert_array_equal(raw[1], norm[1])
    np.testing.assert_allclose(norm[0], raw[0] / scale, rtol=1e-9, atol=1e-12)


def test_semi_implicit_fused_matches_reference_and_differs_from_euler() -> None:
    task = CartPole(integrator="semi-implicit")
    pol = LinearGaussianPolicy(np.array([-1.0, 0.0, 30.0, 5.0]), 5.0)
    batch = task.simulate(pol, 1200, 2)
    for estimator in ("gpomdp", "reinforce"):
        samples, returns = task.gradient_batch(pol, 1200, 2, estimator)
        np.testing.assert_allclose(samples, gradient_samples(pol, batch, estimator), rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(returns, task.undiscounted_returns(batch))
    euler = CartPole().gradient_batch(pol, 1200, 2)
    assert not np.array_equal(euler[1], task.gradient_batch(pol, 1200, 2)[1])


# ------------------------------------------------------------------ experiments
def test_sweep_experiments_are_well_formed() -> None:
    exp = get_experiment("cartpole-sweep")
    assert exp.performance == "J_hat" and exp.seeds == 2
    names = {c.name for c in exp.configs}
    doubled = 0
    for st in CARTPOLE_SWEEP.values():
        base = get_experiment(st.baseline_experiment)
        assert len(base.configs) == 1 and base.configs[0].method.target.value == 195.0
        if st.task and st.warm_start is None:  # its own baseline, on its own 1 m task
            assert make_env(base.configs[0].task) == CartPole.thesis(**st.task)
        if not st.doubled:
            assert f"{st.key}:adaptive" not in names
            continue
        doubled += 1
        ad = exp.config(f"{st.key}:adaptive")
        assert (ad.algorithm, ad.method.error, ad.budget) == ("adaptive", ErrorModel("bernstein", 0.95, "empirical"),
                                                              SWEEP_BUDGET)
        assert ad.warm_start == st.baseline_experiment
        assert make_env(ad.task) == CartPole.thesis_doubled(**st.task, **st.constants)
        # The bound constants alone do not change the vanilla run: shared with the default's.
        van = f"{st.key}:N=4000"
        assert (van in names) == (not st.constants or bool(st.task))
        if van in names:
            v = exp.config(van)
            assert (v.method.batch_size, v.method.step, v.warm_start) == (4000, FixedStep(0.01), st.baseline_experiment)
            assert make_env(v.task) == CartPole.thesis_doubled(**st.task)
    assert "cartpole-sweep" in EXPERIMENTS and "thesis:N=4000" in names
    assert doubled == sum(c.name.endswith(":adaptive") for c in exp.configs) >= 5  # each adaptive config checked


# ------------------------------------------------------------------ summaries
def record(J_hat: list[float], n: int = 4000, theta_end: float = 1.0) -> LearningRecord:
    it = len(J_hat)
    theta = np.ones((it + 1, 4))
    theta[-1, 0] = theta_end
    return LearningRecord(batch_size=np.full(it, n), alpha=np.zeros(it), coordinate=np.zeros(it, dtype=int),
                          theta=theta, J=np.full(it + 1, np.nan), J_hat=np.asarray(J_hat, dtype=float),
                          grad=np.zeros((it, 4)), eps=np.zeros(it), safe=np.ones(it, dtype=bool),
                          reached_target=True)


def test_run_metrics() -> None:
    rec = record([180, 190, 185, 200, 196, 199, 198, 197], theta_end=1.5)
    assert late_minus_early(rec) == pytest.approx((198 + 197) / 2 - 180)  # early: the first batch only
    assert late_minus_early(rec, early=0.3) == pytest.approx((198 + 197) / 2 - (180 + 190 + 185) / 3)
    uneven = record([180.0, 190, 200, 200])
    uneven.batch_size[:] = (100, 900, 1000, 1000)  # the first tenth is the first two batches, weighted
    assert late_minus_early(uneven) == pytest.approx(200 - (180 * 100 + 190 * 900) / 1000)
    assert drawdown(rec) == 5.0  # 190 -> 185 (200 -> 196 is 4)
    assert relative_move(rec, CartPole()) == pytest.approx(0.5)
    # Normalised units are undone: theta / scale.
    assert relative_move(rec, CartPole(feature_scale=NORMALISED_SCALE)) == pytest.approx(
        0.5 / 2.4 / (1 / min(NORMALISED_SCALE)))


def test_sweep_table_and_summary_on_synthetic_runs() -> None:
    flat, climbing = [185.0] * 8, [185.0, 185.5, 186, 187, 188, 189, 190, 191]
    oscillating = [185.0, 199, 180, 199, 181, 198, 182, 199]
    exp = get_experiment("cartpole-sweep")
    sweep = {c.name: [record(flat)] * 2 for c in exp.configs}
    sweep["thesis:N=4000"] = [record(oscillating)] * 2
    sweep["M_phi=0.01:adaptive"] = [record(climbing)] * 2  # learns, steadier, but below vanilla's average
    sweep["M_phi=0.03:adaptive"] = [record([185.0, 190, 195, 196, 197, 198, 199, 199.5])] * 2  # the claim
    baselines = {name: [record([20.0] * 80), record([20.0] * 90)] for name in
                 {st.baseline_experiment for st in CARTPOLE_SWEEP.values()}}
    rows = sweep_table({"baselines": baselines, "sweep": sweep})
    by = {r["key"]: r for r in rows}
    assert set(by) == set(CARTPOLE_SWEEP)
    assert by["thesis"]["c"] == DEFAULT_C and by["thesis"]["baseline_iterations"] == 85
    assert not by["thesis"]["adaptive_learns"] and not by["thesis"]["claim_holds"]
    assert by["M_phi=0.01"]["adaptive_learns"] and not by["M_phi=0.01"]["claim_holds"]
    assert by["M_phi=0.03"]["claim_holds"]
    assert by["M_phi=0.03"]["vanilla_drawdown"] == 19.0  # the shared default vanilla run
    assert "adaptive_learns" not in by["gamma=0.95"]  # baseline search only
    summary = sweep_summary(rows)
    assert summary["learns"] == ["M_phi=0.03", "M_phi=0.01"] and summary["learns_plausible"] == []
    assert summary["claim_holds"] == ["M_phi=0.03"] and summary["claim_holds_plausible"] == []
    assert LEARNS_MARGIN > 0 and THESIS["baseline_iterations"] == 72
