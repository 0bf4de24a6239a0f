"""The Monte Carlo safety measurement: paired rollouts, intervals and outcomes against a closed form;
the per-run summary (counts, Clopper-Pearson bound, detection floor)."""

import json

import numpy as np
import pytest

from safepg import safety, safety_store
from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.envs.pendulum import Pendulum
from safepg.policies import LinearGaussianPolicy

# The unclipped 1-D LQG over a long horizon: its simulated J is the closed form up to 0.9^150 ~ 1e-7.
ENV = LQG.thesis_1d(clip=False, horizon=150)
# Towards theta* ~ -0.59 and past it, with a step that does not move theta at all (update 6).
THETAS = np.array([-0.3, -0.4, -0.5, -0.56, -0.585, -0.62, -0.75, -0.75, -0.7, -0.9])[:, None]
LOOKS = (500, 2000, 8000)


@pytest.fixture(scope="module")
def outcomes():
    return safety.monte_carlo_changes(ENV, THETAS, 1.0, looks=LOOKS, seed=3)


def test_classification_agrees_with_the_closed_form(outcomes):
    truth = np.diff([ENV.performance(t, 1.0) for t in THETAS[:, 0]])
    decided = outcomes.outcome != "undetermined"
    assert decided.sum() >= 7, outcomes.outcome
    expected = np.where(truth < 0, "lowered", "raised")
    assert np.array_equal(outcomes.outcome[decided], expected[decided])
    assert outcomes.outcome[6] == "undetermined" and outcomes.change[6] == 0  # theta did not move
    # Every interval holds the closed-form change.
    assert np.all((outcomes.lower <= truth) & (truth <= outcomes.upper)), (outcomes.lower, truth, outcomes.upper)
    c = outcomes.counts()
    assert c["lowered"] == int(np.sum(outcomes.outcome == "lowered"))
    assert c["lowered"] + c["raised"] + c["undetermined"] == c["updates"] == THETAS.shape[0] - 1
    assert c["rollouts"] == 2 * outcomes.rollouts.sum()


def test_rollouts_grow_only_where_the_interval_contains_zero(outcomes):
    half = (outcomes.upper - outcomes.lower) / 2
    for k in range(outcomes.updates.size):
        n = outcomes.rollouts[k]
        assert n in LOOKS
        if n < LOOKS[-1]:  # stopped early: the interval is narrower than the change
            assert half[k] < abs(outcomes.change[k])
    assert outcomes.rollouts[6] == LOOKS[-1]  # a zero change is never decided
    # Big steps far from the optimum are decided at the first look.
    assert outcomes.rollouts[0] == LOOKS[0]


def test_paired_rollouts_cut_the_variance():
    a, b = safety.paired_returns(ENV, THETAS[3], THETAS[4], 1.0, 2000, 11)
    a2, b2 = safety.paired_returns(ENV, THETAS[3], THETAS[4], 1.0, 2000, 11)
    assert np.array_equal(a, a2) and np.array_equal(b, b2)  # seeded
    assert np.std(b - a) < 0.2 * np.std(a)  # common random numbers


def test_cart_pole_pairs_use_the_kernel_with_the_same_random_numbers():
    env = CartPole.thesis_doubled(gamma=1.0, angle_threshold_deg=12.0)
    theta = np.array([-0.9, 2.1, 3.5, 7.25])
    a, _ = safety.paired_returns(env, theta, theta, 1.0, 300, 5)
    sim = env.simulate(LinearGaussianPolicy(theta[None, :], 1.0), 300, 5)
    assert np.array_equal(a, sim.rewards.sum(axis=1))


def test_discounted_cart_pole_returns_come_from_the_episode_lengths():
    # The thesis's task (gamma = 0.99): the kernel's episode lengths L give sum_{t < L} gamma^t.
    env = CartPole.thesis_doubled()
    theta = np.array([-0.9, 2.1, 3.5, 7.25])
    a, b = safety.paired_returns(env, theta, theta + [0.0, 0.0, 0.3, 0.0], 1.0, 300, 5)
    for th, got in ((theta, a), (theta + [0.0, 0.0, 0.3, 0.0], b)):
        sim = env.simulate(LinearGaussianPolicy(th[None, :], 1.0), 300, 5)
        np.testing.assert_allclose(got, sim.discounted_returns(), rtol=0, atol=1e-11)
    assert env.gamma == 0.99 and a.max() <= (1 - 0.99 ** env.horizon) / 0.01 + 1e-9


def test_pendulum_pairs_use_the_kernel_with_common_random_numbers():
    """The pendulum's paired rollouts come from its fused kernel: the discounted returns of
    ``simulate``'s batch for each policy, the same starts and normals for both."""
    env = Pendulum()
    theta = np.array([-1.0, -3.0, 0.5])
    other = theta + [0.0, 0.05, 0.0]
    a, b = safety.paired_returns(env, theta, other, 1.0, 400, 5)
    for th, got in ((theta, a), (other, b)):
        sim = env.simulate(LinearGaussianPolicy(th[None, :], 1.0), 400, 5)
        np.testing.assert_allclose(got, sim.discounted_returns(), rtol=1e-12)
    assert np.std(b - a) < 0.3 * np.std(a)  # the pairs share their randomness
    out = safety.monte_carlo_changes(env, np.array([theta, other]), 1.0, looks=(300,), seed=2)
    assert out.steps == 2 * 300 * env.horizon


def test_steps_lived_are_counted(outcomes):
    # The LQG rollouts run to the horizon; the cart-pole's end when they fall, one reward a step.
    assert outcomes.steps == 2 * ENV.horizon * outcomes.rollouts.sum()
    env = CartPole.thesis_doubled(gamma=1.0, angle_threshold_deg=12.0)
    thetas = np.array([[-0.9, 2.1, 3.5, 7.25], [-0.9, 2.1, 3.6, 7.25]])
    out = safety.monte_carlo_changes(env, thetas, 1.0, looks=(300,), seed=4)
    block_seed = int(np.random.SeedSequence([4, 0, 0]).generate_state(1)[0])
    lengths = [env.simulate(LinearGaussianPolicy(t[None, :], 1.0), 300, block_seed).mask.sum() for t in thetas]
    assert out.steps == sum(lengths) and 0 < out.steps < 2 * 300 * env.horizon


def test_same_inputs_same_outcomes_and_bad_inputs_refused():
    kw = dict(updates=np.array([0, 5]), looks=(300, 600), seed=1)
    one = safety.monte_carlo_changes(ENV, THETAS, 1.0, **kw)
    two = safety.monte_carlo_changes(ENV, THETAS, 1.0, **kw)
    assert one.to_json() == two.to_json()
    assert safety.MonteCarloOutcomes.from_json(one.to_json()).to_json() == one.to_json()
    with pytest.raises(ValueError, match="updates"):
        safety.monte_carlo_changes(ENV, THETAS, 1.0, updates=np.array([9]))
    with pytest.raises(ValueError, match="looks"):
        safety.monte_carlo_changes(ENV, THETAS, 1.0, looks=(600, 300))


def test_cache_returns_the_stored_measurement(tmp_path, monkeypatch):
    kw = dict(updates=np.array([1, 2]), looks=(300, 600), seed=2)
    first = safety_store.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **kw)
    assert len(list(tmp_path.glob("*.json"))) == 1

    def fail(*args, **kwargs):
        raise AssertionError("recomputed a stored measurement")

    monkeypatch.setattr(safety_store, "monte_carlo_changes", fail)
    assert safety_store.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **kw).to_json() == first.to_json()
    with pytest.raises(AssertionError, match="recomputed"):  # other inputs: not the stored one
        safety_store.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **{**kw, "seed": 3})


def test_normal_quantile():
    assert safety.normal_quantile("0.01") == pytest.approx(2.5758293035489004, abs=1e-15)
    assert safety.normal_quantile("0.05") == pytest.approx(1.959963984540054, abs=1e-15)
    with pytest.raises(ValueError, match="tails"):
        safety.normal_quantile("1.5")


def test_measure_runs_takes_every_update_that_moved_theta(tmp_path):
    runs = [THETAS[:5], THETAS[4:]]  # the second run holds the update that does not move theta (its k = 2)
    out = safety_store.measure_runs(ENV, runs, 1.0, tmp_path, looks=(300, 600), seed=4)
    assert [o.updates.tolist() for o in out] == [[0, 1, 2, 3], [0, 1, 3, 4]]
    one = safety_store.cached_monte_carlo_changes(tmp_path, ENV, runs[1], 1.0, np.array([0, 1, 3, 4]), (300, 600),
                                                  seed=4)
    assert out[1].to_json() == one.to_json()
    assert len(list(tmp_path.glob("*.json"))) == 2  # one file per run, read back above
    for o, T in zip(out, runs):  # the counts add up to the run's updates
        c = o.counts()
        assert c["lowered"] + c["raised"] + c["undetermined"] == c["updates"] == safety.moved_updates(T).size
    pooled = safety.MonteCarloOutcomes.join(out)
    assert pooled.updates.tolist() == [0, 1, 2, 3, 0, 1, 3, 4] and pooled.steps == out[0].steps + out[1].steps
    # A run that never moved: nothing measured, nothing stored (the time budget reads every stored file).
    still = safety_store.measure_runs(ENV, [np.repeat(THETAS[:1], 4, axis=0)], 1.0, tmp_path, looks=(300, 600))
    assert still[0].updates.size == 0 and still[0].counts()["share_lowered_upper95"] is None
    assert len(list(tmp_path.glob("*.json"))) == 2
    with pytest.raises(ValueError, match="looks"):
        safety.MonteCarloOutcomes.join([out[0], safety.monte_carlo_changes(ENV, THETAS, 1.0, [0], looks=(300,))])


def test_parallel_measurement_is_the_serial_one(tmp_path):
    ks = np.array([0, 2, 3, 5, 6, 8])
    serial = safety.monte_carlo_changes(ENV, THETAS, 1.0, ks, looks=(300, 1200), seed=5)
    par = safety_store.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, ks, (300, 1200), seed=5, jobs=2)
    assert par.to_json() == serial.to_json()
    stored = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert stored["seconds"] > 0 and stored["outcomes"]["steps"] == serial.steps > 0  # what the budget reads
    with pytest.raises(ValueError, match="jobs"):
        safety_store.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, ks, (300,), jobs=0)


def test_counts_add_up_on_a_cart_pole_measurement():
    """A small real measurement: an authors' adaptive update and a fixed-step one, on their doubled pole."""
    from safepg.thesis import authors

    env = CartPole.thesis_doubled(gamma=1.0, angle_threshold_deg=12.0)
    runs = authors.cartpole_runs()
    thetas = np.concatenate([runs["adaptive"]["theta"][:3], runs["fixed"]["theta"][:3]])
    out = safety.monte_carlo_changes(env, thetas, 1.0, looks=(300, 600), seed=1)
    c = out.counts()
    assert c["lowered"] + c["raised"] + c["undetermined"] == c["updates"] == 5
    assert c["share_lowered_upper95"] == safety.clopper_pearson_upper(c["lowered"] + c["undetermined"], 5)
    hidden = [-lo for lo, o in zip(out.lower, out.outcome) if o == "undetermined"]
    assert c["detection_floor"] == max([0.0, *hidden])


def _synthetic(lower, upper):
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    outcome = np.where(upper < 0, "lowered", np.where(lower > 0, "raised", "undetermined"))
    return safety.MonteCarloOutcomes(np.arange(lower.size), (lower + upper) / 2, lower, upper,
                                     np.full(lower.size, 64_000), outcome, (4000, 16_000, 64_000), "0.01", 1)


def test_summary_of_synthetic_outcomes():
    out = _synthetic([0.1, -0.5, -0.003, -0.02, 0.2, -0.001], [0.3, -0.1, 0.004, 0.01, 0.5, 0.0005])
    c = out.counts()
    assert (c["updates"], c["lowered"], c["raised"], c["undetermined"]) == (6, 1, 2, 3)
    # The largest decrease an undetermined interval leaves room for: -lower of the third, 0.02 steps.
    assert c["detection_floor"] == 0.02
    assert c["share_lowered_upper95"] == safety.clopper_pearson_upper(4, 6)
    # Only raised updates: no floor, and the bound is the k = 0 one, 1 - 0.05^(1/n).
    clean = _synthetic([0.1, 0.2, 0.01], [0.3, 0.4, 0.02]).counts()
    assert clean["detection_floor"] == 0.0 and clean["undetermined"] == 0
    assert clean["share_lowered_upper95"] == pytest.approx(1 - 0.05 ** (1 / 3), abs=1e-15)
    # An undetermined interval entirely above -0: hides no decrease.
    assert _synthetic([0.0, 0.1], [0.2, 0.3]).counts()["detection_floor"] == 0.0


@pytest.mark.parametrize("n", [1, 2, 5, 16, 30, 250, 1000])
def test_clopper_pearson_upper_is_scipy_beta_quantile(n):
    from scipy.stats import beta

    for k in sorted({0, 1, n // 3, n // 2, n - 1, n}):
        expected = 1.0 if k == n else beta.ppf(0.95, k + 1, n - k)
        assert safety.clopper_pearson_upper(k, n) == pytest.approx(expected, abs=1e-10), (k, n)
    expected = beta.ppf(0.99, 2, n - 1) if n > 1 else 1.0
    assert safety.clopper_pearson_upper(1, n, "0.99") == pytest.approx(expected, abs=1e-10)


@pytest.mark.parametrize("level", ["0.95", "0.99"])
def test_clopper_pearson_upper_stops_its_bisection_without_changing_a_bit(level):
    """The bisection ends once both ends round to one float: the bound is the float of the full
    120 halvings, bit for bit (a stored measurement's bound must not move)."""
    import mpmath

    def full_bisection(k, n):
        with mpmath.workdps(40):
            lo, hi = mpmath.mpf(0), mpmath.mpf(1)
            for _ in range(120):
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if safety._binomial_cdf(k, n, mid) > 1 - mpmath.mpf(level) else (lo, mid)
            return float(hi)

    for n in (2, 3, 17, 97, 401):
        for k in sorted({1, n // 3, n // 2, n - 1}):
            assert safety.clopper_pearson_upper(k, n, level) == full_bisection(k, n), (k, n)


def test_clopper_pearson_upper_values_and_refusals():
    assert safety.clopper_pearson_upper(0, 16) == pytest.approx(0.1707497, abs=1e-7)  # 0 of 16: still 17%
    assert safety.clopper_pearson_upper(7, 7) == 1.0
    assert safety.clopper_pearson_upper(0, 1) == pytest.approx(0.95, abs=1e-15)
    with pytest.raises(ValueError, match="^n must"):
        safety.clopper_pearson_upper(0, 0)
    with pytest.raises(ValueError, match="^k must"):
        safety.clopper_pearson_upper(5, 4)
    with pytest.raises(ValueError, match="^level must"):
        safety.clopper_pearson_upper(1, 4, "1.5")


def test_safety_summary_refuses_bad_counts():
    assert safety.safety_summary(0, 0)["share_lowered_upper95"] is None  # no update: no bound
    with pytest.raises(ValueError, match="^lowered"):
        safety.safety_summary(-1, 3)
    with pytest.raises(ValueError, match="^undetermined"):
        safety.safety_summary(0, 3, 1.5)
    with pytest.raises(ValueError, match="^detection_floor"):
        safety.safety_summary(0, 3, 0, 0.1)  # nothing undetermined hides nothing
    with pytest.raises(ValueError, match="^detection_floor"):
        safety.safety_summary(0, 3, 1, float("nan"))


def test_moved_updates():
    assert safety.moved_updates(THETAS).tolist() == [0, 1, 2, 3, 4, 5, 7, 8]
    assert safety.moved_updates(np.array([[1.0, 2.0], [1.0, 2.0], [1.0, 2.5]])).tolist() == [1]
    with pytest.raises(ValueError, match="^thetas"):
        safety.moved_updates(np.zeros((2, 2, 2)))


def test_theorem_assumptions_name_the_two_discounts():
    from safepg.thesis import experiments as ex

    rows = {r["assumption"]: r for r in safety.theorem_assumptions(ex.get_experiment("table-5.4-authors").configs[0])}
    row = rows["c written for the discount the simulator optimises"]
    assert not row["holds"] and "gamma = 1" in row["why"] and "0.9" in row["why"]
    rows = {r["assumption"]: r for r in safety.theorem_assumptions(ex.get_experiment("table-5.4").configs[0])}
    assert rows["c written for the discount the simulator optimises"]["holds"]
