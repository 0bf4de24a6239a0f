"""The LQG's compiled fixed-step loop gives the bits of the learning loop's Python iterations.

:func:`safepg.learning.vanilla_pg` runs a fixed step on the LQG through
``LQG.fixed_step_batches``; a callable ``progress`` keeps it on the Python loop, batch by batch,
which is the reference here. Every array of the two records must be bit-identical.
"""

import warnings

import numpy as np
import pytest

from safepg import learning
from safepg.envs._lqg_fixed_step import FIXED_STEP_BATCHES
from safepg.envs.lqg import LQG
from safepg.learning import LearningRecord, vanilla_pg
from safepg.numpy_order import column_means, pairwise_sum
from safepg.options import FixedStep, Gradient
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key, batch_keys

ARRAYS = ("batch_size", "alpha", "coordinate", "theta", "J", "J_hat", "grad", "eps", "safe")


def _python_loop(used: int, budget: int) -> None:
    """A callable progress: the learning loop then runs batch by batch in Python."""


def _assert_same(fused: LearningRecord, reference: LearningRecord) -> None:
    for k in ARRAYS:
        a, b = getattr(fused, k), getattr(reference, k)
        assert a.dtype == b.dtype and a.shape == b.shape, k
        assert a.tobytes() == b.tobytes(), k
    assert (fused.interrupted, fused.diverged, fused.reached_target) == (
        reference.interrupted, reference.diverged, reference.reached_target)
    assert fused.config == reference.config


def _both(task: LQG, **kw) -> tuple[LearningRecord, LearningRecord]:
    return vanilla_pg(task, **kw), vanilla_pg(task, progress=_python_loop, **kw)


def test_pairwise_sum_is_numpys_sum():
    rng = np.random.default_rng(0)
    # Below, at and around the block of 128 and its halvings, and long arrays with wide exponents,
    # where any other order of the additions changes the last bits.
    for n in [0, 1, 7, 8, 9, 127, 128, 129, 255, 256, 257, 1000, 4099, 100_000, *rng.integers(1, 50_000, 60)]:
        a = rng.standard_normal(n) * np.exp(rng.uniform(-30, 30, n))
        assert pairwise_sum(a) == a.sum(), n
    for n in (3, 20, 300):  # NumPy adds to +0.0: a sum of negative zeros is +0.0
        zeros = np.full(n, -0.0)
        assert np.signbit(pairwise_sum(zeros)) == np.signbit(zeros.sum()), n


def test_column_means_are_numpys():
    rng = np.random.default_rng(1)
    for n in (1, 9, 130, 1000, 10_007):
        for m in (1, 2, 4, 9):
            x = rng.standard_normal((n, m)) * np.exp(rng.uniform(-30, 30, (n, m)))
            assert column_means(x, n).tobytes() == (x.sum(axis=0) / n).tobytes(), (n, m)


def test_keys_drawn_at_once_are_the_batch_keys():
    a, b = np.random.default_rng(3), np.random.default_rng(3)
    assert batch_keys(a, 50).tolist() == [int(batch_key(b)) for _ in range(50)]


@pytest.mark.parametrize("sigma,n,alpha", [(0.5, 100, 1e-3), (1.0, 1000, 1e-4), (1.0, 10_000, 1e-3)])
def test_table_5_1_runs(sigma, n, alpha):
    _assert_same(*_both(LQG.thesis_1d(), theta0=-0.575, sigma=sigma, batch_size=n, step=FixedStep(alpha),
                        budget=300_000, rng=4))


@pytest.mark.parametrize("gradient", [Gradient("reinforce"), Gradient(baseline=False), Gradient(score_action="raw")])
@pytest.mark.parametrize("budget", [20_003, 20_001])  # a last batch of 3, and a remainder of 1 that is not drawn
def test_estimators_and_a_cut_last_batch(gradient, budget):
    fused, reference = _both(LQG.thesis_1d(), theta0=-0.3, sigma=0.7, batch_size=50, step=FixedStep(1e-3),
                             gradient=gradient, budget=budget, rng=5)
    _assert_same(fused, reference)
    assert fused.trajectories == budget - (budget % 50 == 1)


@pytest.mark.parametrize("kind", ["scalar", "coordinate"])
@pytest.mark.parametrize("dim", [2, 3])
def test_matrix_gains(kind, dim, monkeypatch):
    # Groups of 6 batches: the keys of later groups, and the start of each group, are checked too.
    monkeypatch.setattr(learning, "FUSED_TRAJECTORIES", 600)
    task = LQG.thesis_2d() if dim == 2 else LQG(dim=3)
    fused, reference = _both(task, theta0=np.full(dim * dim, -0.1), sigma=1.0, batch_size=100,
                             step=FixedStep(1e-4, kind), budget=10_000, rng=7)
    _assert_same(fused, reference)
    if kind == "coordinate":
        assert np.all(np.count_nonzero(np.diff(fused.theta, axis=0), axis=1) <= 1)


@pytest.mark.parametrize("group", [2**18, 500])
def test_divergence(group, monkeypatch):
    # alpha = 10 makes theta blow up within a few hundred batches; 500 trajectories per call puts
    # the non-finite gradient inside a later group.
    monkeypatch.setattr(learning, "FUSED_TRAJECTORIES", group)
    kw = dict(theta0=-0.5, sigma=1.0, batch_size=100, step=FixedStep(10.0), budget=1_000_000, rng=2)
    fused, reference = _both(LQG.thesis_1d(), stop_on_divergence=True, **kw)
    _assert_same(fused, reference)
    assert fused.diverged and 10 < fused.iterations < 10_000
    messages = []
    for progress in (False, _python_loop):
        with pytest.raises(ValueError, match="gradient estimate is not finite") as err:
            vanilla_pg(LQG.thesis_1d(), progress=progress, **kw)
        messages.append(str(err.value))
    assert messages[0] == messages[1]


@pytest.mark.filterwarnings("ignore:overflow encountered")
def test_parameters_that_overflow_raise_as_in_the_python_loop():
    kw = dict(theta0=0.5, sigma=1.0, batch_size=100, step=FixedStep(1e308), budget=10_000, rng=2)
    for progress in (False, _python_loop):
        with pytest.raises(ValueError, match="theta must be finite"):
            vanilla_pg(LQG.thesis_1d(), progress=progress, **kw)


def test_an_interruption_keeps_the_groups_done(monkeypatch):
    monkeypatch.setattr(learning, "FUSED_TRAJECTORIES", 1000)
    calls = 0
    loop = FIXED_STEP_BATCHES[1]

    def interrupted_third_call(*args):
        nonlocal calls
        calls += 1
        if calls == 3:
            raise KeyboardInterrupt
        return loop(*args)

    monkeypatch.setitem(FIXED_STEP_BATCHES, 1, interrupted_third_call)
    kw = dict(theta0=-0.575, sigma=1.0, batch_size=100, step=FixedStep(1e-3), rng=4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rec = vanilla_pg(LQG.thesis_1d(), budget=10_000, **kw)
    assert rec.interrupted and rec.trajectories == 2000
    assert any("interrupted after 2000 trajectories" in str(w.message) for w in caught)
    monkeypatch.undo()
    full = vanilla_pg(LQG.thesis_1d(), budget=10_000, **kw)
    assert rec.theta.tobytes() == full.theta[:21].tobytes() and rec.grad.tobytes() == full.grad[:20].tobytes()


def test_bad_input_names_the_parameter():
    env = LQG.thesis_1d()
    policy = LinearGaussianPolicy(np.array([[-0.5]]), 1.0)
    keys = np.zeros(3, dtype=np.uint64)
    with pytest.raises(ValueError, match="keys must have the shape of sizes"):
        env.fixed_step_batches(policy, np.array([10, 10]), keys, 1e-3)
    with pytest.raises(ValueError, match="sizes must be positive"):
        env.fixed_step_batches(policy, np.array([10, 0, 10]), keys, 1e-3)
    with pytest.raises(ValueError, match="kind must be"):
        env.fixed_step_batches(policy, np.full(3, 10), keys, 1e-3, kind="diagonal")
    with pytest.raises(ValueError, match="estimator"):
        env.fixed_step_batches(policy, np.full(3, 10), keys, 1e-3, estimator="gpomdp2")
