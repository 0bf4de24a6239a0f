"""Table 5.2's theoretical range: the reconstructed 1280 is the default, Lemma 4.3.3's 6400 a variant."""

import math

import numpy as np
import pytest

from safepg.bounds import error_bound
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.thesis.experiments import RECONSTRUCTED_RANGE, get_experiment

THEORETICAL_ROWS = {"gpomdp-hoeffding-delta=0.95", "gpomdp-bernstein-delta=0.95"}


def test_table_5_2_uses_the_reconstructed_range_on_exactly_the_theoretical_range_rows():
    exp = get_experiment("table-5.2")
    ranged = {c.name: c.method.error.range for c in exp.configs if not isinstance(c.method.error.range, str)}
    assert ranged == {name: 1280.0 for name in THEORETICAL_ROWS}
    # Chebyshev has no range and the empirical-range rows measure theirs.
    assert all(c.method.error.bound != "chebyshev" for c in exp.configs if c.name in ranged)
    assert {c.method.error.range for c in exp.configs if c.name not in ranged} == {"lemma", "empirical"}


def test_reconstructed_range_is_four_h_mphi_abar_r_over_sigma_squared():
    env = LQG.thesis_1d()
    assert RECONSTRUCTED_RANGE == 4 * env.horizon * env.feature_bound * env.action_bound * env.reward_bound / 1.0**2


def test_lemma_range_variant_runs_the_same_rows_with_the_lemma_range_6400():
    t52, lemma = get_experiment("table-5.2"), get_experiment("table-5.2-lemma-range")
    assert {c.name for c in lemma.configs} == {f"{n}-lemma-range" for n in THEORETICAL_ROWS}
    k = TaskConstants.from_task(LQG.thesis_1d(), 1.0)
    for c in lemma.configs:
        base = t52.config(c.name.removesuffix("-lemma-range"))
        assert c.method.error.range == "lemma"  # Lemma 4.3.3
        assert lemma.thesis[c.name] == t52.thesis[base.name]
        assert c.key() != base.key()  # a different setting, so a different stored run
        delta = c.method.error.delta
        d = error_bound("hoeffding", np.zeros(4), delta, k, c.method.gradient.estimator, c.method.error.range).d
        assert d == pytest.approx(6400 * math.sqrt(math.log(2 / delta) / 2), rel=1e-12)


def test_old_range_experiment_name_is_gone():
    with pytest.raises(ValueError, match="experiment must be one of"):
        get_experiment("table-5.2-range")
