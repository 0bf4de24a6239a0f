"""The Monte Carlo safety measurement: paired rollouts, intervals and outcomes against a closed form."""

import numpy as np
import pytest

from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.policies import LinearGaussianPolicy
from safepg.thesis import safety

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
    first = safety.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **kw)
    assert len(list(tmp_path.glob("*.json"))) == 1

    def fail(*args, **kwargs):
        raise AssertionError("recomputed a stored measurement")

    monkeypatch.setattr(safety, "monte_carlo_changes", fail)
    assert safety.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **kw).to_json() == first.to_json()
    with pytest.raises(AssertionError, match="recomputed"):  # other inputs: not the stored one
        safety.cached_monte_carlo_changes(tmp_path, ENV, THETAS, 1.0, **{**kw, "seed": 3})


def test_spread_updates():
    assert safety.spread_updates(250, 5).tolist() == [0, 62, 124, 187, 249]
    assert safety.spread_updates(3, 10).tolist() == [0, 1, 2]
    with pytest.raises(ValueError, match="count"):
        safety.spread_updates(3, 0)


def test_normal_quantile():
    assert safety.normal_quantile("0.01") == pytest.approx(2.5758293035489004, abs=1e-15)
    assert safety.normal_quantile("0.05") == pytest.approx(1.959963984540054, abs=1e-15)
    with pytest.raises(ValueError, match="tails"):
        safety.normal_quantile("1.5")


def test_measure_runs_joins_the_runs(tmp_path):
    runs = [THETAS[:5], THETAS[4:]]
    out = safety.measure_runs(ENV, runs, 1.0, 2, tmp_path, looks=(300, 600), seed=4)
    assert out.updates.tolist() == [0, 3, 0, 4]
    one = safety.cached_monte_carlo_changes(tmp_path, ENV, runs[1], 1.0, np.array([0, 4]), (300, 600), seed=4)
    assert out.change[2:].tolist() == one.change.tolist()
    assert len(list(tmp_path.glob("*.json"))) == 2


def test_theorem_assumptions_name_the_two_discounts():
    from safepg.thesis import experiments as ex

    rows = {r["assumption"]: r for r in safety.theorem_assumptions(ex.get_experiment("table-5.4-authors").configs[0])}
    row = rows["c written for the discount the simulator optimises"]
    assert not row["holds"] and "gamma = 1" in row["why"] and "0.9" in row["why"]
    rows = {r["assumption"]: r for r in safety.theorem_assumptions(ex.get_experiment("table-5.4").configs[0])}
    assert rows["c written for the discount the simulator optimises"]["holds"]
