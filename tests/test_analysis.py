"""Curves and tables drawn from records."""

import numpy as np

from safepg.analysis import by_iteration, markdown_table, mean_band, performance_on_grid, table_5_2
from safepg.learning import LearningRecord


def rec(batch, J):
    I = len(batch)
    return LearningRecord(np.array(batch), np.zeros(I), np.zeros(I, int), np.zeros((I + 1, 1)), np.array(J),
                          np.array(J[:-1]) + 1, np.zeros((I, 1)), np.zeros(I), np.ones(I, bool))


def test_performance_on_grid_holds_each_J_for_its_batch():
    r = rec([10, 20, 5], [-5.0, -4.0, -3.0, -2.5])
    got = performance_on_grid([r], np.array([1, 10, 11, 30, 31, 35, 36]))[0]
    np.testing.assert_array_equal(got, [-5, -5, -4, -4, -3, -3, np.nan])


def test_by_iteration_and_band():
    a, b = rec([1, 2, 3], [0, 0, 0, 0]), rec([4, 5], [0, 0, 0])
    v = by_iteration([a, b])
    np.testing.assert_array_equal(v, [[1, 2, 3], [4, 5, np.nan]])
    m, lo, hi = mean_band(v)
    np.testing.assert_array_equal(m, [2.5, 3.5, 3])
    np.testing.assert_array_equal(lo, [1, 2, 3])


def test_table_5_2_differences():
    report = {"configs": [{"estimator": "gpomdp", "bound": "bernstein", "empirical_range": True, "delta": 0.95,
                           "seeds": 5, "upsilon_bar": {"mean": -9.7, "ci95": [-9.8, -9.6]},
                           "improvement_ratio": {"mean": 1.0}, "thesis": {"upsilon_bar": -9.6623, "ci95": [1, 2]}}]}
    row = table_5_2(report)[0]
    assert abs(row["difference"] - (-9.7 + 9.6623)) < 1e-12
    md = markdown_table([row], [("ours", "ours", ".3f"), ("ci95", "CI", ".1f"), ("missing", "x", "")])
    assert md.splitlines()[2] == "| -9.700 | [-9.8; -9.6] | - |"
