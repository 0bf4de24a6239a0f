"""Numeric checks of the inequality lemmas hold as printed and fail with broken constants."""

import math

import numpy as np
import pytest

from safepg.thesis import lemma_checks as L


def test_gaussian_second_derivative_shape_sup():
    z = np.linspace(-8, 8, 16001)
    vals = np.abs(L.gaussian_second_derivative_shape(z))
    assert vals.max() == pytest.approx(1 / math.sqrt(2 * math.pi), rel=1e-12)
    assert z[np.argmax(vals)] == 0.0
    assert abs(L.gaussian_second_derivative_shape(np.sqrt(3.0))) == pytest.approx(
        2 * math.exp(-1.5) / math.sqrt(2 * math.pi)
    )


def test_lemma_a01_hessian_holds_and_is_tight():
    res = L.check_lemma_a01_hessian(rng=1)
    assert res.holds
    assert res.max_violation > -1e-9  # attained at z = 0
    assert res.details["fd_max_rel_error"] < 1e-5
    assert res.details["grid_sup_shape"] == pytest.approx(res.details["sup_shape_exact"])


@pytest.mark.parametrize("kwargs", [{"constant": 0.9}, {"sigma_power": 2.0, "sigma_range": (0.2, 0.9)}])
def test_lemma_a01_hessian_fails_when_broken(kwargs):
    res = L.check_lemma_a01_hessian(rng=1, n_draws=400, **kwargs)
    assert not res.holds
    assert res.max_violation > 0.05


def test_lemma_a01_taylor_printed_constant_and_half():
    printed = L.check_lemma_a01_taylor(rng=2)
    assert printed.holds and printed.max_violation < -0.45  # loose by a factor 2
    half = L.check_lemma_a01_taylor(rng=2, constant=0.5)
    assert half.holds
    assert half.details["worst_ratio"] == pytest.approx(0.5, abs=1e-3)  # tight


def test_lemma_a01_taylor_fails_below_half():
    res = L.check_lemma_a01_taylor(rng=2, n_draws=400, constant=0.4)
    assert not res.holds and res.max_violation > 0.05


def test_lemma_a02_pinsker_direction():
    ok = L.check_lemma_a02(rng=3)
    assert ok.holds
    assert ok.details["statement_violation"] <= 0
    assert ok.details["kl_max_rel_error"] < 1e-6
    assert ok.details["sum_of_squares_max_rel_gap"] > 0.1  # the printed sum of squares is not 2 KL
    printed = L.check_lemma_a02(rng=3, direction=">=")
    assert not printed.holds
    with pytest.raises(ValueError, match="direction"):
        L.check_lemma_a02(direction="<")


def test_lemma_b03_holds_and_fails_when_broken():
    ok = L.check_lemma_b03(rng=4)
    assert ok.holds
    assert ok.details["max_ratio"] == pytest.approx(4 * math.sqrt(3) / 18, rel=1e-9)
    assert ok.details["fd_max_abs_error"] < 1e-5
    broken = L.check_lemma_b03(rng=4, n_draws=100, constant=0.35)
    assert not broken.holds


def test_softmax_hessian_matches_finite_differences():
    rng = np.random.default_rng(5)
    features = rng.uniform(-1, 1, size=(5, 3))
    theta = rng.normal(size=3)
    h = 1e-4
    hess = L.softmax_hessian(theta, features)
    e = np.eye(3) * h
    for i in range(3):
        for j in range(3):
            fd = (
                L.softmax_probs(theta + e[i] + e[j], features)
                - L.softmax_probs(theta + e[i] - e[j], features)
                - L.softmax_probs(theta - e[i] + e[j], features)
                + L.softmax_probs(theta - e[i] - e[j], features)
            ) / (4 * h * h)
            np.testing.assert_allclose(hess[:, i, j], fd, atol=1e-6)


def test_lemma_b05_holds_and_fails_when_broken():
    ok = L.check_lemma_b05(rng=6)
    assert ok.holds
    assert ok.details["kl_violation"] <= 0 and ok.details["pinsker_violation"] <= 0
    assert not L.check_lemma_b05(rng=6, n_draws=200, constant=0.01).holds


def test_lemma_4_3_3_counterexample():
    # mean 0: the construction stays within the printed bound (ratio 1 - gamma^H)
    ok = L.check_lemma_4_3_3(mean=0.0)
    assert ok.holds
    assert ok.details["range"] / ok.details["printed_bound"] == pytest.approx(1 - 0.9**20, rel=1e-6)
    # |theta^T phi| = 1 = A_bar / 2 (reachable in the 1-D LQG): the printed range bound is exceeded
    for mean in (1.0, -1.0):
        bad = L.check_lemma_4_3_3(mean=mean)
        assert not bad.holds
        assert bad.details["range"] / bad.details["printed_bound"] == pytest.approx(
            bad.details["predicted_ratio_reinforce"], rel=1e-6
        )
    assert L.check_lemma_4_3_3(estimator="gpomdp").holds
    assert not L.check_lemma_4_3_3(estimator="gpomdp", mean=5.0).holds
    with pytest.raises(ValueError, match="estimator"):
        L.check_lemma_4_3_3(estimator="ppo")
