"""The cart-pole overlay carries our runs' mean and 95% band and the authors' batch means."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from scipy import stats

from safepg.learning import LearningRecord
from safepg.thesis import overlays
from safepg.thesis.authors import cartpole_runs


def _record(batch_size, J_hat):
    I = len(batch_size)
    return LearningRecord(batch_size=np.asarray(batch_size), alpha=np.zeros(I), coordinate=np.zeros(I, dtype=int),
                          theta=np.zeros((I + 1, 4)), J=np.full(I + 1, np.nan), J_hat=np.asarray(J_hat, dtype=float),
                          grad=np.zeros((I, 4)), eps=np.zeros(I), safe=np.ones(I, dtype=bool))


RECORDS = {"adaptive": [_record([1000, 3000, 4000], [187.0, 188.0, 190.0]),
                        _record([1000, 2000, 5000], [186.0, 189.0, 191.0]),
                        _record([1000, 6000, 1000], [188.0, 187.5, 192.0])],
           "N=4000": [_record([4000, 4000], [187.0, 194.0]), _record([4000, 4000], [188.0, 180.0])]}


def test_curves_are_the_seed_mean_and_its_prediction_band():
    grid = np.array([1, 1000, 1001, 3500, 7999])
    c = overlays.cartpole_overlay_curves(RECORDS, grid)
    # Trajectory 3500: batch 2 of seed 0 (1001-4000), batch 3 of seed 1 (3001-8000), batch 2 of seed 2 (1001-7000).
    at_3500 = np.array([188.0, 191.0, 187.5])
    m, s = at_3500.mean(), at_3500.std(ddof=1)
    h = stats.t.ppf(0.975, 2) * s * np.sqrt(1 + 1 / 3)  # the band for one run: theirs is one run
    ours = c["ours"]["adaptive"]
    assert ours["mean"][3] == pytest.approx(m) and ours["lo"][3] == pytest.approx(m - h)
    assert ours["hi"][3] == pytest.approx(m + h)
    assert ours["mean"][0] == pytest.approx(187.0)  # first batches
    assert ours["seeds"] == 3
    a = c["authors"]["N=4000"]
    assert np.array_equal(a["J_hat"], cartpole_runs()["fixed"]["J_hat"])
    assert a["trajectories"][-1] == cartpole_runs()["fixed"]["N"].sum()


def test_figure_draws_those_curves():
    fig = overlays.figure_cartpole_overlay(RECORDS, {"adaptive": "adaptive", "N=4000": "fixed step"}, budget=8000,
                                           points=50)
    ax = fig.axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    grid = np.unique(np.linspace(1, 8000, 50).astype(np.int64))
    c = overlays.cartpole_overlay_curves(RECORDS, grid)
    ours = lines["ours: adaptive (3 seeds, 95% band for one run)"]
    assert np.allclose(ours.get_ydata(), c["ours"]["adaptive"]["mean"], equal_nan=True)
    theirs = lines["authors' run: fixed step"]
    assert np.array_equal(theirs.get_ydata()[1:], cartpole_runs()["fixed"]["J_hat"])
    assert len(ax.collections) == 2  # one band per method
    band = ax.collections[0].get_paths()[0].vertices[:, 1]
    assert np.nanmax(band) == pytest.approx(np.nanmax(c["ours"]["adaptive"]["hi"]))
    assert ax.get_xlim() == (0, 8000)


def test_safety_figure_draws_each_change_and_interval():
    from safepg.safety import MonteCarloOutcomes

    def outcomes(change, half):
        c = np.asarray(change, dtype=float)
        return MonteCarloOutcomes(np.arange(c.size), c, c - half, c + half, np.full(c.size, 4000),
                                  np.where(c - half > 0, "raised", "undetermined"), (4000,), "0.01")

    measured = {"their adaptive run": outcomes([0.01, 0.02], 0.005), "our adaptive runs": outcomes([0.03], 0.01),
                "their fixed-step run": outcomes([-1.0, 2.0, 0.5], 0.4)}
    fig = overlays.figure_cartpole_safety(measured)
    left, right = fig.axes
    points = [line.get_ydata() for line in left.get_lines() if line.get_linestyle() == "None"]
    assert [p.tolist() for p in points] == [[0.01, 0.02], [0.03]]
    right_points = [line.get_ydata() for line in right.get_lines() if line.get_linestyle() == "None"]
    assert right_points[0].tolist() == [-1.0, 2.0, 0.5]
    segments = right.collections[0].get_segments()  # the error bars
    assert [tuple(np.round(s[:, 1], 6)) for s in segments] == [(-1.4, -0.6), (1.6, 2.4), (0.1, 0.9)]
