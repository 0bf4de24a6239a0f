r"""How much of the authors' curves lies where our runs go: one number per curve of Chapter 5.

The book draws the authors' raw curves (:mod:`safepg.thesis.authors`) over ours
(:mod:`safepg.thesis.overlays`). This module scores each of their curves against the band our
seeds predict for a curve of its kind, at the authors' own x-values:

- a single run (Figures 5.3-5.9) is held against the 95% prediction band of one run,
  :math:`\bar x \pm t_{0.975,\,k-1}\, s\sqrt{1 + 1/k}`;
- a mean over :math:`n` runs (Figures 5.1-5.2 as the caption has them, :math:`n = 5`) against the
  band of such a mean, :math:`\bar x \pm t_{0.975,\,k-1}\, s\sqrt{1/n + 1/k}`;

with :math:`\bar x` and :math:`s` the mean and sample standard deviation of our :math:`k`
seeds at that x (:func:`safepg.stats.prediction_band95`). The score is the share of the
authors' points inside the band, the x-ranges where their curve leaves it and by how much.
Only the plotted range counts (where ours exists; Figure 5.9 up to Table 5.4's budget);
points there with fewer than two seeds have no band and are counted apart.

Figures 5.1, 5.2 and 5.5 are scored twice, each time with one processing for every curve
(:data:`~safepg.thesis.overlays.PROCESSINGS`): as the thesis's text has them (the J of the policy in
use; Figures 5.1-5.2 a five-run mean, on ``table-5.2``), and as the authors' plot script made them (one
run through :func:`~safepg.thesis.authors.grid_curve`, on our runs under their settings:
``figures-5.1-5.2-authors``, ``table-5.2-authors`` for the two theoretical-range rows, and
``figures-5.5-5.6``, whose settings are theirs).

The curves are the overlays' own (their series functions), against the experiment each figure
draws: ``table-5.2`` (Figures 5.1-5.4), ``figures-5.5-5.6``, ``table-5.3`` and
``table-5.3-authors`` (Figures 5.7-5.8), ``table-5.4`` and ``table-5.4-authors-theta-star`` (Figure 5.9).
A curve drawn in two figures (Chebyshev, G(PO)MDP, delta = 0.95, in 5.1 and 5.2, and in 5.3
and 5.4) is scored once, under the first.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from safepg.curve_tests import CurvePredictionTest, PermutationTest, block_means
from safepg.options import Adaptive
from safepg.record import LearningRecord
from safepg.stats import prediction_band95
from safepg.thesis import authors, overlays
from safepg.thesis.analysis import by_iteration
from safepg.thesis.authors import TABLE_5_4_BUDGET, AuthorsRun
from safepg.thesis.experiments import get_experiment, method_of

#: The share of a curve inside our band that the scorecard once took for "reproduced"; the share is now a
#: description (where the curves part), and the curve's test decides (:attr:`CurveScore.test`).
CURVE_SHARE = 0.9
#: A curve is tested as its means over this many equal blocks of the plotted range (early, middle, late).
CURVE_BLOCKS = 3
#: The share of the authors' values' range that matters for a curve (the scorecard's relevance).
CURVE_RELEVANT_SHARE = 0.05
#: The experiments whose runs the scored figures draw (load these for :func:`curve_scores`).
CURVE_EXPERIMENTS = ("table-5.2", "figures-5.1-5.2-authors", "table-5.2-authors", "figures-5.5-5.6", "table-5.3",
                     "table-5.3-authors", "table-5.4", "table-5.4-authors-theta-star")
#: Our runs of Figures 5.1-5.2 under the authors' settings, in the order looked up: a config's runs are
#: taken from the first of these that has them.
FIGURES_51_52_AUTHORS = ("figures-5.1-5.2-authors", "table-5.2-authors")
#: Ranges listed by :func:`outside_sentence` before "and n more".
LISTED_RANGES = 3
#: How the authors' files write their numbers: Figures 5.1-5.2's curves with 6 decimals
#: (``processed_data/*.txt``), every other column with 12 significant digits (Python 2's ``str``).
CURVE_DECIMALS = 6
RUN_DIGITS = 12

Records = Mapping[str, Mapping[str, Sequence[LearningRecord]]]


@dataclass(frozen=True)
class CurveScore:
    """One authors' curve held against our band.

    Attributes
    ----------
    figure : str
        The thesis figure, e.g. ``"5.1"``.
    curve : str
        The curve's label: our config's name, and ``/run-i`` for one of several runs of theirs.
    quantity : str
        What the curve plots, and in which units.
    where : str
        The figure(s) that draw it, e.g. ``"Figures 5.1 and 5.2"``.
    source : str
        The authors' file, ``path@commit`` (seven hex digits).
    experiment : str
        Our experiment the curve is held against (its config is ``curve`` up to ``/run-i``).
    kind : str
        ``"one run"`` or ``"mean of n runs"``: which band.
    seeds : int
        Our seeds k (the most at any point).
    points : int
        The authors' points scored (in the plotted range, with a band).
    points_without_band : int
        The authors' points in the plotted range where fewer than two of our seeds remain.
    share_inside : float
        Share of the scored points inside the band (NaN if none).
    outside : tuple of (x_from, x_to, largest excess, excess in half-widths)
        The maximal x-ranges of consecutive scored points outside the band; the excess is the
        distance to the nearer edge, its largest over the range, and the largest of excess /
        half-width (inf where the band has width 0).
    x_unit : str
        ``"trajectories"`` or ``"iterations"``.
    processing : str
        How their curve and ours were made from runs: ``"text"`` (as the thesis says; every figure) or
        ``"authors"`` (their plot script's, Figures 5.1, 5.2 and 5.5: :func:`~safepg.thesis.authors.grid_curve`).
    test : safepg.curve_tests.PermutationTest or safepg.curve_tests.CurvePredictionTest or None
        Their runs of the curve (or their one run) against ours, as block means (:func:`curve_test`); None
        where fewer than two of our runs cover the plotted range.
    relevance : float
        The difference that matters: :data:`CURVE_RELEVANT_SHARE` of the range of the authors' values over
        every curve of the figure (:func:`curve_scores`; :attr:`y_range` for this curve alone).
    x_range : (float, float)
        The range the test covers: where their runs and all of ours have values.
    y_range : (float, float)
        The least and the largest of their values there.
    """

    figure: str
    curve: str
    quantity: str
    where: str
    source: str
    experiment: str
    kind: str
    seeds: int
    points: int
    points_without_band: int
    share_inside: float
    outside: tuple[tuple[float, float, float, float], ...]
    x_unit: str
    processing: str = "text"
    test: Any = None
    relevance: float = math.nan
    x_range: tuple[float, float] = (math.nan, math.nan)
    y_range: tuple[float, float] = (math.nan, math.nan)


# ------------------------------------------------------------------ scoring one curve
def written_rounding(values: np.ndarray, decimals: int | None = None, digits: int | None = None) -> np.ndarray:
    r"""Half a unit in the last digit of numbers written with ``decimals`` decimals, :math:`\tfrac12 10^{-d}`,
    or with ``digits`` significant digits, :math:`\tfrac12 10^{\lfloor\log_{10}|y|\rfloor - p + 1}` (0 for 0)."""
    y = np.abs(np.asarray(values, dtype=float))
    if decimals is not None:
        return np.full(y.shape, 0.5 * 10.0 ** -decimals)
    if digits is None:
        raise ValueError("decimals or digits must be given")
    with np.errstate(divide="ignore", invalid="ignore"):
        exponent = np.floor(np.log10(np.where(y > 0, y, 1.0)))
    return np.where(np.isfinite(y) & (y > 0), 0.5 * 10.0 ** (exponent - digits + 1), 0.0)


def band_share(x: np.ndarray, theirs: np.ndarray, ours: np.ndarray, runs: int = 1,
               x_max: float | None = None, rounding: np.ndarray | float = 0.0) -> dict[str, Any]:
    r"""Share of a curve inside the 95% prediction band of our seeds, and where it leaves it.

    At each x with :math:`k \ge 2` seeds the band is
    :math:`[\bar x - h, \bar x + h]`, :math:`h = t_{0.975,\,k-1}\, s \sqrt{1/n + 1/k}`
    (:func:`safepg.stats.prediction_band95`, :math:`n` = ``runs``); a point is inside when
    :math:`|y - \bar x| \le h + r`, :math:`r` the rounding of the written :math:`y` (where our seeds
    all agree, e.g. at the first parameter, :math:`h = 0`), and its excess is :math:`|y - \bar x| - h`.

    Parameters
    ----------
    x : array_like, shape (P,)
        The authors' x-values, increasing.
    theirs : array_like, shape (P,)
        Their curve at ``x``; NaN points are not part of it.
    ours : array_like, shape (seeds, P)
        Each of our seeds at ``x``; NaN where a seed has no value.
    runs : int
        How many runs their curve averages.
    x_max : float, optional
        The figure's right end: points beyond it are not plotted.
    rounding : float or array_like, shape (P,)
        Half a unit in the last digit of their written numbers (:func:`written_rounding`).

    Returns
    -------
    dict
        ``points``, ``without_band``, ``share_inside``, ``outside`` (as :attr:`CurveScore.outside`)
        and ``seeds`` (the most seeds at any point).
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(theirs, dtype=float)
    mean, half, k = prediction_band95(ours, runs)
    exists = k >= 1
    plotted = np.isfinite(y)
    if exists.any():
        plotted &= (x >= x[exists].min()) & (x <= x[exists].max())
    else:
        plotted[:] = False
    if x_max is not None:
        plotted &= x <= x_max
    scored = plotted & (k >= 2)
    excess = np.zeros_like(y)
    r = np.broadcast_to(np.asarray(rounding, dtype=float), y.shape)
    with np.errstate(invalid="ignore"):
        distance = np.abs(y[scored] - mean[scored]) - half[scored]
        excess[scored] = np.where(distance > r[scored], distance, 0.0)
    out_idx = np.flatnonzero(scored & (excess > 0))
    ranges = []
    if out_idx.size:
        # Consecutive among the scored points: a range breaks at a scored point inside the band.
        rank = np.cumsum(scored) - 1
        breaks = np.flatnonzero(np.diff(rank[out_idx]) > 1) + 1
        for group in np.split(out_idx, breaks):
            e, h = excess[group], half[group]
            with np.errstate(divide="ignore"):
                widths = np.where(h > 0, e / np.where(h > 0, h, 1.0), math.inf)
            ranges.append((float(x[group[0]]), float(x[group[-1]]), float(e.max()), float(widths.max())))
    n_scored = int(scored.sum())
    share = float(np.sum(scored & (excess == 0)) / n_scored) if n_scored else math.nan
    return {"points": n_scored, "without_band": int(np.sum(plotted & ~scored)), "share_inside": share,
            "outside": tuple(ranges), "seeds": int(k.max()) if k.size else 0}


# ------------------------------------------------------------------ the figures' curves
def _source(run: AuthorsRun) -> str:
    return f"{run.source['path']}@{run.source['commit'][:7]}"


def _kind(runs: int) -> str:
    return "one run" if runs == 1 else f"mean of {runs} runs"


def curve_test(x: np.ndarray, theirs: np.ndarray, ours: np.ndarray, x_max: float | None = None
               ) -> tuple[PermutationTest | CurvePredictionTest | None, tuple[float, float], tuple[float, float]]:
    """Their runs of a curve against ours, each as its means over :data:`CURVE_BLOCKS` equal blocks of the
    range where every curve has a value (up to ``x_max``): the two-sample permutation test for several runs
    of theirs, Hotelling's test for one new curve for one.

    Parameters
    ----------
    x : array_like, shape (P,)
    theirs : array_like, shape (m, P) or (P,)
        Their runs (one run: 1-D).
    ours : array_like, shape (k, P)
    x_max : float, optional
        The figure's right end.

    Returns
    -------
    test, y_range, x_range
        The test (None with fewer than two of our runs there), the least and largest of their values there,
        and that range of x.
    """
    x = np.asarray(x, dtype=float)
    a = np.atleast_2d(np.asarray(theirs, dtype=float))
    o = np.asarray(ours, dtype=float)
    common = np.all(np.isfinite(a), axis=0) & np.all(np.isfinite(o), axis=0)
    if x_max is not None:
        common &= x <= x_max
    if o.shape[0] < 2 or np.count_nonzero(common) < CURVE_BLOCKS:
        return None, (math.nan, math.nan), (math.nan, math.nan)
    xs, a, o = x[common], a[:, common], o[:, common]
    x_range = (float(xs.min()), float(xs.max()))
    a_blocks, o_blocks = block_means(xs, a, CURVE_BLOCKS, x_range), block_means(xs, o, CURVE_BLOCKS, x_range)
    test = PermutationTest(a_blocks, o_blocks) if a.shape[0] > 1 else CurvePredictionTest(a_blocks[0], o_blocks)
    return test, (float(np.min(a)), float(np.max(a))), x_range


def _score(figure: str, curve: str, quantity: str, where: str, source: str, experiment: str, runs: int,
           x_unit: str, x: np.ndarray, theirs: np.ndarray, ours: np.ndarray, x_max: float | None = None,
           rounding: np.ndarray | float | None = None, processing: str = "text",
           their_runs: np.ndarray | None = None) -> CurveScore:
    """A curve's score: its share inside our band (``theirs``, the plotted curve, against the band for
    ``runs`` runs) and its test (:func:`curve_test`: ``their_runs`` where their history holds several
    runs, else ``theirs``)."""
    rounding = written_rounding(theirs, digits=RUN_DIGITS) if rounding is None else rounding
    s = band_share(x, theirs, ours, runs, x_max, rounding)
    test, y_range, x_range = curve_test(x, theirs if their_runs is None else their_runs, ours, x_max)
    return CurveScore(figure, curve, quantity, where, source, experiment, _kind(runs), s["seeds"], s["points"],
                      s["without_band"], s["share_inside"], s["outside"], x_unit, processing, test, math.nan,
                      x_range, y_range)


def _pad(theirs: np.ndarray, ours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Their curve (P,) and our seeds (seeds, Q) on a common length max(P, Q), NaN-padded."""
    length = max(theirs.size, ours.shape[1])
    padded_ours = np.full((ours.shape[0], length), np.nan)
    padded_ours[:, : ours.shape[1]] = ours
    padded = np.full(length, np.nan)
    padded[: theirs.size] = theirs
    return padded, padded_ours


#: What Figures 5.1-5.2's curves plot under each processing (:data:`~safepg.thesis.overlays.PROCESSINGS`).
FIGURES_51_52_QUANTITY = {
    "text": "J(θ) of the policy in use (closed form), every 1000 trajectories",
    "authors": "J(θ) of the policy of the last batch ended 1000 trajectories before x (closed form; their "
               "scaleData.m), every 1000 trajectories",
}


def figure_of_51_52(error: Any) -> str:
    """The figure that draws a curve of Table 5.2's rows: Chebyshev's in Figure 5.1, the other bounds' in 5.2."""
    return "5.1" if error.bound == "chebyshev" else "5.2"


def figures51_52_authors_runs(records: Records, name: str) -> tuple[str, Sequence[LearningRecord]] | None:
    """Our runs of the Figure 5.1-5.2 curve ``name`` under the authors' settings: the first experiment
    of :data:`FIGURES_51_52_AUTHORS` that has them, and the runs (None if none has)."""
    for exp in FIGURES_51_52_AUTHORS:
        recs = records.get(exp, {}).get(name)
        if recs:
            return exp, recs
    return None


def figures51_52_score(records: Mapping[str, Sequence[LearningRecord]], cfg: Any, experiment: str,
                       processing: overlays.Processing) -> CurveScore:
    """One curve of Figures 5.1-5.2 held against our band under ``processing`` (the runs of ``records``
    for ``cfg``, an experiment's config of Table 5.2's rows)."""
    error = cfg.method.error
    key = (cfg.method.gradient.estimator, error.bound, error.empirical_range, error.delta)
    both = error.bound == "chebyshev" and cfg.method.gradient.estimator == "gpomdp" and error.delta == 0.95
    figure = figure_of_51_52(error)
    where = "Figures 5.1 and 5.2" if both else f"Figure {figure}"
    s = overlays.figure51_52_overlay_series(records, cfg, processing)
    return _score(figure, cfg.name, FIGURES_51_52_QUANTITY[processing], where,
                  _source(authors.figure51_52_curves()[key]), experiment, s["runs"], "trajectories", s["x"],
                  s["authors"], s["values"], rounding=written_rounding(s["authors"], decimals=CURVE_DECIMALS),
                  processing=processing, their_runs=figures51_52_their_runs(key, s["x"], processing))


def figures51_52_their_runs(key: tuple[str, str, bool, float], grid: np.ndarray,
                            processing: overlays.Processing) -> np.ndarray:
    """Each of the authors' committed runs of a Table 5.2 row (:func:`~safepg.thesis.authors.table52_runs`:
    five, one for Bernstein e.r.) on the grid of Figures 5.1-5.2, processed as ``processing`` says: ``"text"``,
    the J of the policy that collected trajectory T (as :func:`~safepg.record.on_trajectories` maps ours);
    ``"authors"``, their ``scaleData.m`` (:func:`~safepg.thesis.authors.grid_curve`). Shape (runs, points),
    NaN past a run's last trajectory."""
    grid = np.asarray(grid)
    out = []
    for run in authors.table52_runs()[key]:
        if processing == "authors":
            x, z = authors.grid_curve(run["N"], run["J"])
            if not np.array_equal(x, grid):
                raise ValueError(f"{key}: the grid is not grid_curve's")
            out.append(np.asarray(z, dtype=float))
            continue
        idx = np.searchsorted(np.cumsum(np.asarray(run["N"], dtype=np.int64)), grid)
        row = np.full(grid.size, np.nan)
        ok = idx < run.iterations
        row[ok] = np.asarray(run["J"], dtype=float)[idx[ok]]
        out.append(row)
    return np.array(out)


def _lqg1d_scores(records: Records) -> list[CurveScore]:
    """Figures 5.1-5.2 (the authors' curves of J, under each processing) and 5.3-5.4 (each of their
    runs' batch sizes) against ``table-5.2``, and Figures 5.1-5.2 under the authors' processing against
    our runs under their settings (:func:`figures51_52_authors_runs`)."""
    exp = get_experiment("table-5.2")
    recs = records.get("table-5.2", {})
    runs52 = authors.table52_runs()
    scores = []
    for cfg in exp.configs:
        if recs.get(cfg.name):
            scores.append(figures51_52_score(recs, cfg, exp.name, "text"))
        theirs = figures51_52_authors_runs(records, cfg.name)
        if theirs is not None:
            name, mine = theirs
            scores.append(figures51_52_score({cfg.name: mine}, get_experiment(name).config(cfg.name), name,
                                             "authors"))
        method = method_of(cfg, Adaptive)
        estimator, error = method.gradient.estimator, method.error
        if not (recs.get(cfg.name) and estimator == "gpomdp" and error.delta == 0.95):
            continue
        key = (estimator, error.bound, error.empirical_range, error.delta)
        figure, where = ("5.3", "Figures 5.3 and 5.4") if error.bound == "chebyshev" else ("5.4", "Figure 5.4")
        sides: list[tuple[str, Sequence[LearningRecord]]] = [(exp.name, recs[cfg.name])]
        sides += [] if theirs is None else [theirs]
        for name, side in sides:
            scores += _batch_size_scores(figure, where, cfg.name, name, runs52.get(key, []), side)
    return scores


def _batch_size_scores(figure: str, where: str, curve: str, experiment: str, theirs_runs: Sequence[AuthorsRun],
                       recs: Sequence[LearningRecord]) -> list[CurveScore]:
    """Figures 5.3-5.4: each of the authors' runs' batch sizes per iteration against our runs of ``experiment``
    (its own share of the band), all their runs at once in the curve's test."""
    ours = by_iteration(recs, "batch_size")
    length = max([ours.shape[1]] + [r.iterations for r in theirs_runs])
    matrix = np.full((len(theirs_runs), length), np.nan)
    for i, run in enumerate(theirs_runs):
        matrix[i, : run.iterations] = np.asarray(run["N"], dtype=float)
    _, mine_all = _pad(matrix[0], ours)
    test, y_range, x_range = curve_test(np.arange(1, length + 1), matrix, mine_all)
    out = []
    for run in theirs_runs:
        theirs_n, mine_n = _pad(np.asarray(run["N"], dtype=float), ours)
        one = _score(figure, f"{curve}/run-{run.key['run']}", "batch size N per iteration", where, _source(run),
                     experiment, 1, "iterations", np.arange(1, theirs_n.size + 1), theirs_n, mine_n)
        out.append(replace(one, test=test, y_range=y_range, x_range=x_range))
    return out


def _held_score(figure: str, curve: str, quantity: str, experiment: str, run: AuthorsRun,
                recs: Sequence[LearningRecord]) -> CurveScore:
    """A 2-D J curve held over batches (Figures 5.5, 5.8) at the authors' batch ends: their batch's
    J (÷ 16) against the J of our batch that holds the same trajectory (:func:`overlays.lqg2d_held`)."""
    x = np.cumsum(np.asarray(run["N"], dtype=float)).astype(np.int64)
    written = np.asarray(run["J"], dtype=float)
    theirs = written / overlays.LQG2D_AUTHORS_SCALE
    ours = np.array([overlays.lqg2d_held(r.batch_size, r.J, x) for r in recs])
    return _score(figure, curve, quantity, f"Figure {figure}", _source(run), experiment, 1, "trajectories", x,
                  theirs, ours, rounding=written_rounding(written, digits=RUN_DIGITS) / overlays.LQG2D_AUTHORS_SCALE)


def figure55_series(run: AuthorsRun, recs: Sequence[LearningRecord]) -> dict[str, np.ndarray]:
    """A curve of Figure 5.5 as the authors' plot script made it (``plots/plot_lqg2d.m@4ff60e7:8-20``,
    ``plots/plot_scaledData2.m@4ff60e7:1-8``): their run's J (÷ 16) and each of our seeds through
    :func:`~safepg.thesis.authors.grid_curve`, on their grid of 1000 trajectories; ``rounding`` is half a
    unit of their written J, in our units."""
    scale = overlays.LQG2D_AUTHORS_SCALE
    x, written = authors.grid_curve(run["N"], run["J"])
    ours = np.array([authors.grid_curve(r.batch_size, r.J[:-1])[1] for r in recs])
    return {"x": x, "theirs": written / scale, "values": ours,
            "rounding": written_rounding(written, digits=RUN_DIGITS) / scale}


def _lqg2d_scores(records: Records) -> list[CurveScore]:
    """Figures 5.5-5.8 against ``figures-5.5-5.6``, ``table-5.3`` and ``table-5.3-authors``."""
    runs = authors.lqg2d_runs()
    scale = overlays.LQG2D_AUTHORS_SCALE
    j_held = f"J(θ) (closed form; theirs ÷ {scale:g}), each batch's held over its trajectories"
    scores = []
    step = records.get("figures-5.5-5.6", {})
    if all(step.get(k) for k in ("scalar", "coordinate")):
        for key in ("scalar", "coordinate"):
            scores.append(_held_score("5.5", key, j_held, "figures-5.5-5.6", runs[key], step[key]))
            # As their plot script made it: their guard (stop the run when eps >= |g|) never fires, in
            # their runs or ours, so our runs are theirs in law and only the processing changes.
            g = figure55_series(runs[key], step[key])
            scores.append(_score("5.5", key, f"J(θ) (closed form; theirs ÷ {scale:g}) of the policy of the last batch "
                                 "ended 1000 trajectories before x (their scaleData.m)", "Figure 5.5",
                                 _source(runs[key]), "figures-5.5-5.6", 1, "trajectories", g["x"], g["theirs"],
                                 g["values"], rounding=g["rounding"], processing="authors"))
        s = overlays.lqg2d_iteration_series("alpha", {k: step[k] for k in ("scalar", "coordinate")},
                                            {k: runs[k] for k in ("scalar", "coordinate")})
        for key in ("scalar", "coordinate"):
            scores.append(_binned_score("5.6", key, f"step size (α̂* or ‖Λ*‖∞), means over blocks of {s['width']} "
                                        "iterations", "figures-5.5-5.6", runs[key], s, key))
    t53, t53a = records.get("table-5.3", {}), records.get("table-5.3-authors", {})
    if t53.get("adaptive"):
        ours = {"adaptive": t53["adaptive"]}
        if t53a.get("adaptive"):
            ours["adaptive-authors"] = t53a["adaptive"]
        s = overlays.lqg2d_iteration_series("batch_size", ours, {"adaptive": runs["adaptive"]})
        quantity = f"batch size N, means over blocks of {s['width']} iterations"
        for key, name in (("adaptive", "table-5.3"), ("adaptive-authors", "table-5.3-authors")):
            if key in ours:
                scores.append(_binned_score("5.7", "adaptive", quantity, name, runs["adaptive"], s, key))
        for name, recs in (("table-5.3", t53), ("table-5.3-authors", t53a)):
            if recs.get("adaptive"):
                scores.append(_held_score("5.8", "adaptive", j_held, name, runs["adaptive"], recs["adaptive"]))
    if t53.get("N=1000"):
        scores.append(_held_score("5.8", "N=1000", j_held, "table-5.3", runs["N=1000"], t53["N=1000"]))
    return scores


def _binned_score(figure: str, curve: str, quantity: str, experiment: str, run: AuthorsRun,
                  series: Mapping[str, Any], key: str) -> CurveScore:
    """A block-mean curve of :func:`safepg.thesis.overlays.lqg2d_iteration_series` (Figures 5.6-5.7):
    the authors' run ``curve``'s block means against those of each seed of our ``key``, at the block centres."""
    theirs, ours = _pad(series["theirs"][curve], series["ours"][key])
    x = series["width"] * np.arange(theirs.size) + (series["width"] + 1) / 2
    return _score(figure, curve, quantity, f"Figure {figure}", _source(run), experiment, 1, "iterations", x, theirs,
                  ours)


def _cartpole_scores(records: Records) -> list[CurveScore]:
    """Figure 5.9 against ``table-5.4`` (the thesis's text) and ``table-5.4-authors-theta-star``, up to
    Table 5.4's budget (the figure's x-axis)."""
    runs = authors.cartpole_runs()
    scores = []
    for name, ours, theirs in ((n, o, t) for n in ("table-5.4", "table-5.4-authors-theta-star")
                               for o, t in overlays.CARTPOLE_AUTHORS_RUN.items()):
        recs = records.get(name, {})
        if not recs.get(ours):
            continue
        grid = np.cumsum(np.asarray(runs[theirs]["N"], dtype=float)).astype(np.int64)
        curves = overlays.cartpole_overlay_curves({ours: recs[ours]}, grid)
        a = curves["authors"][ours]
        scores.append(_score("5.9", ours, "batch-average return (episode length), each batch's held over its "
                             "trajectories", "Figure 5.9", _source(runs[theirs]), name, 1, "trajectories",
                             a["trajectories"], a["J_hat"], curves["ours"][ours]["values"], TABLE_5_4_BUDGET))
    return scores


def curve_scores(records: Records) -> list[CurveScore]:
    """Every authors' curve of Figures 5.1-5.9 held against our band, in the figures' order.

    Parameters
    ----------
    records : mapping of experiment name to (config name to records)
        Loaded runs (``load_experiment(get_experiment(name), root)``) of :data:`CURVE_EXPERIMENTS`;
        the curves of an experiment (or config) that is missing or has no run are left out.

    Returns
    -------
    list of CurveScore
    """
    scores = _lqg1d_scores(records) + _lqg2d_scores(records) + _cartpole_scores(records)
    # The figure's scale: the range of the authors' values over all its curves, as its y-axis spans them.
    spans: dict[str, tuple[float, float]] = {}
    for sc in scores:
        lo, hi = spans.get(sc.figure, (math.inf, -math.inf))
        if all(math.isfinite(v) for v in sc.y_range):
            spans[sc.figure] = (min(lo, sc.y_range[0]), max(hi, sc.y_range[1]))
    scores = [replace(sc, relevance=CURVE_RELEVANT_SHARE * (spans[sc.figure][1] - spans[sc.figure][0]))
              if sc.figure in spans else sc for sc in scores]
    return sorted(scores, key=lambda s: tuple(int(p) for p in s.figure.split(".")))


# ------------------------------------------------------------------ verdicts and rows
def curve_holds(score: CurveScore) -> bool:
    """Reproduced: at least :data:`CURVE_SHARE` of the authors' curve lies in our band."""
    return bool(score.points > 0 and score.share_inside >= CURVE_SHARE)


def _x_text(x: float) -> str:
    return f"{x:,.0f}" if float(x).is_integer() else f"{x:,.1f}"


def outside_sentence(score: CurveScore) -> str:
    """Where the curve leaves the band, in one short sentence: the :data:`LISTED_RANGES` ranges of
    largest excess, in the order of x, and how many more."""
    if score.points == 0:
        return "no point with a band."
    if not score.outside:
        return "inside the band at every scored point."
    listed = sorted(score.outside, key=lambda r: -r[2])[:LISTED_RANGES]
    parts = []
    for lo, hi, excess, widths in sorted(listed):
        span = _x_text(lo) if lo == hi else f"{_x_text(lo)}–{_x_text(hi)}"
        w = "∞" if math.isinf(widths) else f"{widths:.2g}"
        parts.append(f"{span} (by up to {excess:.3g}, {w} half-widths)")
    more = len(score.outside) - len(listed)
    tail = f"; and {more} more range{'s' if more > 1 else ''}" if more else ""
    n = len(score.outside)
    return f"leaves it on {n} range{'s' if n > 1 else ''} of {score.x_unit}: {'; '.join(parts)}{tail}."


def curve_score_rows(scores: Sequence[CurveScore]) -> list[dict[str, Any]]:
    """One row per score for the scorecard: ``id``, ``quantity``, ``where``, ``share`` (text),
    ``share_inside`` (number), ``holds``, ``outside`` (a sentence), ``kind``, ``seeds``,
    ``points``, ``points_without_band``, ``experiment``, ``source``.

    The id is ``figure-<figure>/<curve>``, followed by ``/<experiment>`` when one curve of a
    figure is held against several experiments, and by ``/authors-processing`` when it is held as
    the authors' plot script made it (``processing``: ``"text"`` or ``"authors"``).
    """
    experiments: dict[tuple[str, str], set[str]] = {}
    for s in scores:
        experiments.setdefault((s.figure, s.curve), set()).add(s.experiment)
    rows = []
    for s in scores:
        several = len(experiments[(s.figure, s.curve)]) > 1
        ident = (f"figure-{s.figure}/{s.curve}" + (f"/{s.experiment}" if several else "")
                 + ("/authors-processing" if s.processing == "authors" else ""))
        share = "no band" if s.points == 0 else f"{s.share_inside:.1%} of {s.points} points"
        rows.append({"id": ident, "quantity": s.quantity, "where": s.where, "share": share,
                     "share_inside": s.share_inside, "holds": curve_holds(s), "outside": outside_sentence(s),
                     "kind": s.kind, "seeds": s.seeds, "points": s.points,
                     "points_without_band": s.points_without_band, "experiment": s.experiment, "source": s.source,
                     "processing": s.processing})
    return rows


__all__ = ["CURVE_EXPERIMENTS", "CURVE_SHARE", "FIGURES_51_52_AUTHORS", "FIGURES_51_52_QUANTITY", "CurveScore",
           "band_share", "curve_holds", "curve_score_rows", "curve_scores", "figure55_series", "figure_of_51_52",
           "figures51_52_authors_runs", "figures51_52_score", "outside_sentence", "written_rounding"]
