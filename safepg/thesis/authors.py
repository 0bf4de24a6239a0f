r"""The authors' raw outputs (``T3p/adaptive-batch-size``) and the printed numbers recomputed from them.

The thesis's tables were computed by the authors' scripts from their runs' output files. The
files the book draws beside our runs are kept, with only the columns the plots and tables
need, under ``safepg/thesis/data/authors/`` (written by ``tools/extract_authors_data.py``,
which reads the authors' repository at commit 5810ee6). ``MANIFEST.json`` there records for
every source file its path, the last commit that changed it, its git blob, its size and its
header line, and the SHA-256 of every file written (:func:`verify_data`).

Loaders (each number as the authors wrote it):

- :func:`table51_runs`: the 24 fixed-step runs of Table 5.1 (theta and the closed-form J);
- :func:`table52_runs`: the runs of Table 5.2 (batch size and measured return per iteration);
- :func:`figure51_52_curves`: the curves of Figures 5.1-5.2 as the authors plotted them;
- :func:`lqg2d_runs`: the 2-D LQG runs of Table 5.3 and Figures 5.5-5.8;
- :func:`figure55_curves`: Figure 5.5 as the authors plotted it (their MATLAB figure's two lines);
- :func:`cartpole_runs`, :func:`cartpole_theta_star`: the cart-pole runs of Table 5.4 and
  Figure 5.9, the baseline search and the baseline policy.

The rules their plot scripts used, applicable to their runs and to ours:

- :func:`strict_improvement_ratio`: strict increases between consecutive values, over
  (values - 1) comparisons (Tables 5.1, 5.3, 5.4);
- :func:`truncated_average`: each run averaged over its first T iterations, T the shortest
  run of the row, and a 90% Student-t interval over runs (Table 5.2, ``plots/lqg.m``);
- :func:`budget_average`: only the batches that end before a trajectory budget (Table 5.4,
  ``plots/plot_cartpole.m``);
- :func:`grid_curve`: one run's values on a grid of trajectories, one update behind (Figures
  5.1-5.2, ``plots/scaleData.m``).

:func:`table_5_1` ... :func:`table_5_4` recompute the printed tables from the authors' files
with those rules. :func:`lqg2d_performance` is the 2-D closed form their code evaluates:
16 times the expectation over the initial state, the integral over the box [-2, 2]^2.
"""

from __future__ import annotations

import hashlib
import io
import json
import lzma
import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from safepg import portable
from safepg.stats import t_quantile

#: Folder of the authors' data files and their manifest.
DATA_DIR = Path(__file__).resolve().parent / "data" / "authors"
#: The authors' repository.
REPOSITORY = "https://github.com/T3p/adaptive-batch-size"

#: The 2-D LQG of their code (``lqgnd/lqgnd.py``): state and action bound b, discount.
LQG2D_BOUND = 2.0
LQG2D_GAMMA = 0.9


@dataclass(frozen=True)
class AuthorsRun:
    """One of the authors' output files, reduced to the kept columns.

    Attributes
    ----------
    key : dict
        What the run is (e.g. ``{"sigma": 0.5, "N": 100, "alpha": 0.001}`` or ``{"run": "adaptive"}``).
    columns : dict of str to ndarray
        The kept columns, one row per logged iteration (``theta`` of the cart-pole is (I, 4)).
    source : dict
        Provenance: ``path`` in the repository, ``commit`` (the last that changed it), ``blob``,
        ``bytes``, ``header`` (its first line) and ``columns`` (what its columns hold).
    """

    key: dict[str, Any]
    columns: dict[str, np.ndarray]
    source: dict[str, Any]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def iterations(self) -> int:
        """Number of logged iterations (rows)."""
        return int(next(iter(self.columns.values())).shape[0])


# ------------------------------------------------------------------ files
@cache
def manifest(folder: Path = DATA_DIR) -> dict[str, Any]:
    """The data folder's ``MANIFEST.json``: repository, commit read, and one entry per file
    (description, columns, rows, bytes, sha256, sources)."""
    return json.loads((folder / "MANIFEST.json").read_text())


def verify_data(folder: Path = DATA_DIR) -> list[str]:
    """Files of the manifest whose bytes or SHA-256 differ from the record (empty: all intact).

    Parameters
    ----------
    folder : Path
        The data folder (default :data:`DATA_DIR`).

    Returns
    -------
    list of str
        One message per missing or altered file, and per file in the folder the manifest does not list.
    """
    entries = json.loads((folder / "MANIFEST.json").read_text())["files"]
    bad = []
    for name, entry in entries.items():
        path = folder / name
        if not path.is_file():
            bad.append(f"{name}: missing")
            continue
        data = path.read_bytes()
        if len(data) != entry["bytes"] or hashlib.sha256(data).hexdigest() != entry["sha256"]:
            bad.append(f"{name}: bytes or sha256 differ from MANIFEST.json")
    extra = sorted(p.name for p in folder.iterdir() if p.name not in entries and p.name != "MANIFEST.json")
    return bad + [f"{name}: not in MANIFEST.json" for name in extra]


@cache
def _read(name: str) -> tuple[tuple[str, ...], np.ndarray]:
    """Header and float64 table of one data file (xz-compressed if its name ends in .xz)."""
    data = (DATA_DIR / name).read_bytes()
    text = lzma.decompress(data).decode() if name.endswith(".xz") else data.decode()
    header, _, body = text.partition("\n")
    table = np.loadtxt(io.StringIO(body), delimiter=",", dtype=float, ndmin=2)
    table.setflags(write=False)
    return tuple(header.split(",")), table


@cache
def _rows_by_source(name: str, sources: int) -> tuple[np.ndarray, ...]:
    """The rows of each source of a data file, in file order (read-only): one pass over the
    table, where a mask per source read it whole once per run, for each of the chapters'
    several hundred lookups."""
    header, table = _read(name)
    which = table[:, header.index("source")].astype(int)
    order = np.argsort(which, kind="stable")
    # Rows of a source number beyond the manifest's fall into a last part, which is dropped.
    parts = np.split(table[order], np.searchsorted(which[order], np.arange(1, sources + 1)))[:sources]
    for part in parts:
        part.setflags(write=False)
    return tuple(parts)


def _runs(name: str, groups: dict[str, tuple[str, ...]] | None = None) -> list[AuthorsRun]:
    """The runs of a data file with a ``source`` column, in the manifest's order.

    ``groups`` joins several columns into one 2-D column (e.g. the four theta components).
    """
    header, _ = _read(name)
    sources = manifest()["files"][name]["sources"]
    col = {h: i for i, h in enumerate(header)}
    grouped = {c for cs in (groups or {}).values() for c in cs}
    runs = []
    for src, rows in zip(sources, _rows_by_source(name, len(sources))):
        columns = {h: rows[:, j] for h, j in col.items() if h != "source" and h not in grouped}
        for g, cs in (groups or {}).items():
            columns[g] = rows[:, [col[c] for c in cs]]
        runs.append(AuthorsRun(dict(src["key"]), columns, {k: v for k, v in src.items() if k != "key"}))
    return runs


def table51_runs() -> dict[tuple[float, int, float], AuthorsRun]:
    """The 24 runs of Table 5.1 by (sigma, N, alpha): columns ``theta`` (before each update) and
    ``J``, the closed form at it as their code computed it (sigma read as the variance)."""
    return {(r.key["sigma"], r.key["N"], r.key["alpha"]): r for r in _runs("table51.csv.xz")}


def table52_runs() -> dict[tuple[str, str, bool, float], list[AuthorsRun]]:
    """The runs of Table 5.2 by (estimator, bound, empirical range, delta), five per row (one for
    Bernstein with empirical range, the only one committed), in the order of their ``run`` key
    (the file's ``sample`` number): columns ``N`` (the batch collected at that iteration),
    ``theta`` (before the update), ``J`` (the closed form at ``theta``) and ``J_hat`` (the
    batch's mean discounted return)."""
    out: dict[tuple[str, str, bool, float], list[AuthorsRun]] = {}
    for r in _runs("table52.csv.xz"):
        k = r.key
        out.setdefault((k["estimator"], k["bound"], k["empirical_range"], k["delta"]), []).append(r)
    return out


def table52_settings() -> dict[tuple[str, str, bool, float], dict[str, int]]:
    """The batch limits each row of Table 5.2 ran with, from its run files' header line
    (``N_min N_max delta estimator bound total``, written by ``lqg/lqg_adabatch.py@eb78917:161``),
    by (estimator, bound, empirical range, delta): ``n_min``, ``n_max`` and ``total``.

    Raises
    ------
    ValueError
        If the runs of one row were written with different headers.
    """
    out = {}
    for key, runs in table52_runs().items():
        headers = {r.source["header"] for r in runs}
        if len(headers) != 1:
            raise ValueError(f"the runs of {key} have different headers: {sorted(headers)}")
        n_min, n_max, _, _, _, total = headers.pop().split()
        out[key] = {"n_min": int(n_min), "n_max": int(n_max), "total": int(total)}
    return out


def figure51_52_curves() -> dict[tuple[str, str, bool, float], AuthorsRun]:
    """The curves of Figures 5.1-5.2 as the authors plotted them, by (estimator, bound, empirical
    range, delta): columns ``trajectories`` (1000, 2000, ..., 30 001 000) and ``J``, written with 6
    decimals. Each is one run, their run 1 of the row, through :func:`grid_curve` (not the
    caption's mean of 5 runs)."""
    return {(r.key["estimator"], r.key["bound"], r.key["empirical_range"], r.key["delta"]): r
            for r in _runs("figures51_52.csv.xz")}


def lqg2d_runs() -> dict[str, AuthorsRun]:
    """The 2-D LQG runs by name: ``"adaptive"`` (Table 5.3, Figures 5.7-5.8), ``"N=1000"``
    (Table 5.3), ``"coordinate"`` and ``"scalar"`` (Figures 5.5-5.6).

    Columns ``N``, ``alpha``, ``J`` (:func:`lqg2d_performance`, 16 times the expectation) and
    ``J_hat`` (the batch's mean discounted return); :func:`lqg2d_theta_ends` has their first and
    last parameters. Table 5.3's N = 100 run is not in the authors' repository.
    """
    return {r.key["run"]: r for r in _runs("lqg2d.csv.xz")}


def figure55_curves() -> dict[str, AuthorsRun]:
    """Figure 5.5 as the authors plotted it (``plots/compare_stepsize.fig@4ff60e7``, read from the MATLAB
    figure): ``"coordinate"`` and ``"scalar"``, columns ``trajectories`` (1000, 2000, ..., 30 001 000) and
    ``J`` (16 times the expectation); :func:`grid_curve` of their run gives it."""
    return {r.key["run"]: r for r in _runs("figure55.csv.xz")}


def lqg2d_theta_ends() -> dict[str, dict[str, Any]]:
    """First and last logged parameters of each 2-D run (row-major 2 x 2, before the update of
    that iteration), with their iteration numbers and J (16 times the expectation)."""
    header, table = _read("lqg2d_theta.csv")
    col = {h: i for i, h in enumerate(header)}
    names = [s["key"]["run"] for s in manifest()["files"]["lqg2d_theta.csv"]["sources"]]
    thetas = [col[f"theta{i}{j}"] for i in (1, 2) for j in (1, 2)]
    out = {}
    for i, name in enumerate(names):
        first, last = table[table[:, col["source"]] == i]
        out[name] = {"iterations": (int(first[col["iteration"]]), int(last[col["iteration"]])),
                     "theta": (first[thetas].reshape(2, 2), last[thetas].reshape(2, 2)),
                     "J": (float(first[col["J"]]), float(last[col["J"]]))}
    return out


def cartpole_runs() -> dict[str, AuthorsRun]:
    """The cart-pole runs by name: ``"adaptive"`` and ``"fixed"`` (Table 5.4, Figure 5.9; the
    fixed one is their coordinate-step "vanilla"), ``"fixed-short"`` (an earlier, shorter fixed
    run) and ``"baseline"`` (the baseline search on the 1 m pole).

    Columns ``N``, ``theta`` (I, 4) before each update, ``alpha`` and ``J_hat`` (the batch's mean
    undiscounted return, i.e. episode length).
    """
    theta = ("theta_x", "theta_xdot", "theta_beta", "theta_betadot")
    return {r.key["run"]: r for r in _runs("cartpole.csv.xz", {"theta": theta})}


def cartpole_theta_star() -> np.ndarray:
    """The authors' baseline policy (their ``theta_star.npy``), shape (4,): every doubled-pole run
    starts from it. It is the parameter after the 72nd update of their baseline search."""
    return np.array(_read("cartpole_theta_star.csv")[1][0])


# ------------------------------------------------------------------ their rules
#: Figures 5.1-5.2's grid: ``scaleData(batchsize, performance, 30000000, 1000)``
#: (``plots/save_scaledData.m@5810ee6:5``).
FIGURES_51_52_TOTAL = 30_000_000
FIGURES_51_52_STEP = 1000


def grid_curve(batch_size: np.ndarray, values: np.ndarray, total: int = FIGURES_51_52_TOTAL,
               step: int = FIGURES_51_52_STEP) -> tuple[np.ndarray, np.ndarray]:
    r"""A run's per-iteration values on the authors' trajectory grid, as ``plots/scaleData.m`` maps them.

    Their Figures 5.1-5.2 are this map of one run file each (``plots/save_scaledData.m@5810ee6:1-11``,
    ``plots/scaleData.m@e4cdc9e:1-11``): for :math:`i = 0, \dots, \text{total}/\text{step}`,

    .. math::
        n_i = \text{step}\; i, \qquad j_i = \max\big(1,\ \#\{k : N_1 + \dots + N_k < n_i\}\big), \qquad
        z_i = y_{j_i}, \quad \text{drawn at } x_i = \text{step}\,(i + 1),

    with :math:`N_k` the batch collected at iteration :math:`k` and :math:`y_k` its logged value. Their
    J column is the closed form at the parameter that collected batch :math:`k`, so at :math:`n`
    trajectories the curve shows the policy of the last batch that *ended* before :math:`n`, one
    update behind the policy collecting trajectory :math:`n`, and it is drawn one step to the right
    (:math:`x = n + \text{step}`). Past the run's last batch the last value is held.

    Parameters
    ----------
    batch_size : array_like, shape (I,)
        The batch of each iteration.
    values : array_like, shape (I,)
        The value logged at each iteration (for the authors' J and ours: ``record.J[:-1]``).
    total, step : int
        The grid's end (in trajectories) and spacing.

    Returns
    -------
    x, z : ndarray, shape (total / step + 1,)
        The grid's x (int64) and the values there.
    """
    n = np.asarray(batch_size, dtype=float)
    y = np.asarray(values, dtype=float)
    if n.ndim != 1 or n.size == 0 or y.shape != n.shape:
        raise ValueError(f"values must have the shape of batch_size, a non-empty (I,), got {y.shape} and {n.shape}")
    if total % step:
        raise ValueError(f"total must be a multiple of step, got total={total}, step={step}")
    i = np.arange(total // step + 1, dtype=np.int64)
    finished = np.searchsorted(np.cumsum(n), step * i, side="left")  # batches whose running total is < n_i
    return step * (i + 1), y[np.maximum(finished, 1) - 1]


def strict_improvement_ratio(values: np.ndarray) -> float:
    """Share of strict increases between consecutive values, over (len - 1) comparisons.

    The authors' count in Tables 5.1, 5.3 and 5.4: ``values`` are the performances at the
    start of each batch, so the last update is never evaluated. Applied to one of our records,
    pass ``record.J[:-1]`` (or ``record.J_hat``).

    Parameters
    ----------
    values : array_like, shape (I,)
        Performance at the start of each batch (closed-form J, or the batch's mean return).

    Returns
    -------
    float
        NaN for fewer than two values.
    """
    v = np.asarray(values, dtype=float)
    if v.size < 2:
        return float("nan")
    return float(np.count_nonzero(np.diff(v) > 0) / (v.size - 1))


def truncated_average(runs: list[tuple[np.ndarray, np.ndarray]]) -> dict[str, Any]:
    r"""Table 5.2's average performance: each run averaged over its first T iterations only, T the
    smallest iteration count among the runs, then the mean over runs and its 90% t-interval.

    ``plots/lqg.m``: :math:`\overline\Upsilon_i = \sum_{t \le T} N_t \hat J_t / \sum_{t \le T} N_t`,
    interval :math:`\bar x \pm t_{0.95,\,n-1}\, s / \sqrt n` (``tinv([0.05, 0.95], n - 1)``), which the
    thesis prints as a 95% interval.

    Parameters
    ----------
    runs : list of (batch sizes, mean returns) pairs
        One pair of arrays per run.

    Returns
    -------
    dict
        ``T``, ``per_run`` (each run's average), ``mean`` and ``ci90`` ([lo, hi]; equal ends for one run).
    """
    T = min(len(n) for n, _ in runs)
    per_run = [portable.fsum_mean(np.asarray(j)[:T], weights=np.asarray(n)[:T]) for n, j in runs]
    x = np.array(per_run)
    m = math.fsum(per_run) / x.size
    h = 0.0 if x.size < 2 else t_quantile(x.size - 1, "0.1") * float(x.std(ddof=1)) / math.sqrt(x.size)
    return {"T": T, "per_run": per_run, "mean": m, "ci90": [m - h, m + h]}


def budget_average(batch_size: np.ndarray, returns: np.ndarray, budget: int) -> dict[str, Any]:
    r"""Table 5.4's average performance and improvement ratio over a trajectory budget.

    ``plots/plot_cartpole.m``: only the X batches whose cumulative size is below ``budget``
    count; :math:`\overline\Upsilon = \sum_{t \le X} N_t \hat J_t / \sum_{t \le X} N_t` and the
    ratio is :func:`strict_improvement_ratio` of their mean returns. The authors used the
    length of their adaptive run, 1 151 669 trajectories, for both runs.

    Parameters
    ----------
    batch_size, returns : array_like, shape (I,)
        Batch sizes and the batches' mean returns.
    budget : int
        The trajectory budget.

    Returns
    -------
    dict
        ``batches`` (X), ``trajectories`` (their total), ``upsilon_bar``, ``improvement_ratio``, ``increases``.
    """
    n = np.asarray(batch_size, dtype=float)
    j = np.asarray(returns, dtype=float)
    X = int(np.count_nonzero(np.cumsum(n) < budget))
    if X < 1:
        raise ValueError(f"budget must exceed the first batch ({n[0]:.0f}), got {budget}")
    return {"batches": X, "trajectories": int(n[:X].sum()), "upsilon_bar": portable.fsum_mean(j[:X], weights=n[:X]),
            "improvement_ratio": strict_improvement_ratio(j[:X]),
            "increases": int(np.count_nonzero(np.diff(j[:X]) > 0))}


# ------------------------------------------------------------------ the printed tables
def table_5_1() -> dict[tuple[float, int, float], dict[str, Any]]:
    """Table 5.1 recomputed from the authors' 24 runs with :func:`strict_improvement_ratio` on
    their J column.

    Returns
    -------
    dict
        By (sigma, N, alpha): ``improvement_ratio``, ``increases``, ``updates`` (rows - 1),
        ``theta0`` and ``theta_final`` (the last logged theta, before the last update).
    """
    out = {}
    for key, run in table51_runs().items():
        J = run["J"]
        out[key] = {"improvement_ratio": strict_improvement_ratio(J),
                    "increases": int(np.count_nonzero(np.diff(J) > 0)),
                    "updates": int(J.size - 1), "theta0": float(run["theta"][0]),
                    "theta_final": float(run["theta"][-1])}
    return out


def table_5_2() -> dict[tuple[str, str, bool, float], dict[str, Any]]:
    """Table 5.2 recomputed from the authors' runs with :func:`truncated_average`.

    Returns
    -------
    dict
        By (estimator, bound, empirical range, delta): ``T``, ``per_run``, ``mean`` and ``ci90``,
        and ``runs`` (how many runs the repository holds).
    """
    return {key: {**truncated_average([(r["N"], r["J_hat"]) for r in runs]), "runs": len(runs)}
            for key, runs in table52_runs().items()}


def table_5_3() -> dict[str, dict[str, Any]]:
    """Table 5.3 (adaptive and N = 1000) and the improvement ratios of Figures 5.5-5.6, recomputed
    from the 2-D runs: the batch-weighted mean of the measured return over the whole run, and
    :func:`strict_improvement_ratio` on their J.

    Returns
    -------
    dict
        By run: ``upsilon_bar``, ``improvement_ratio``, ``iterations``, ``trajectories``, ``theta_final``.
    """
    ends = lqg2d_theta_ends()
    return {name: {"upsilon_bar": portable.fsum_mean(r["J_hat"], weights=r["N"]),
                   "improvement_ratio": strict_improvement_ratio(r["J"]), "iterations": r.iterations,
                   "trajectories": int(r["N"].sum()), "theta_final": ends[name]["theta"][1]}
            for name, r in lqg2d_runs().items()}


def table_5_4() -> dict[str, dict[str, Any]]:
    """Table 5.4 recomputed from the doubled-pole runs with :func:`budget_average`, the budget
    being the adaptive run's total length (as ``plots/plot_cartpole.m`` has it).

    Returns
    -------
    dict
        ``"adaptive"`` and ``"fixed"``: :func:`budget_average`'s fields and ``budget``.
    """
    runs = cartpole_runs()
    budget = int(runs["adaptive"]["N"].sum())
    return {name: {**budget_average(runs[name]["N"], runs[name]["J_hat"], budget), "budget": budget}
            for name in ("adaptive", "fixed")}


#: Table 5.4's trajectory budget: the length of the authors' adaptive run (``plot_cartpole.m``).
TABLE_5_4_BUDGET = 1_151_669


# ------------------------------------------------------------------ the 2-D closed form of their code
def lqg2d_performance(theta: np.ndarray, sigma: float = 1.0, gamma: float = LQG2D_GAMMA) -> float:
    r"""The 2-D LQG's J as the authors' code computes it (``LQGND.computeJ``).

    .. math::
        P = (Q + K^\top R K)\,\big(I - \gamma (I + 2K + K\circ K)\big)^{-1}, \qquad
        W = \frac{\operatorname{tr}\big(\Sigma (R + \gamma P)\big)}{1 - \gamma}, \qquad
        J = -4 b^2 \Big(\frac{b^2}{3}\operatorname{tr} P + W\Big)

    with Q = R = I/2, A = B = I, b = 2, Sigma = sigma I and :math:`K\circ K` the element-wise
    square. For a diagonal K, P is the value matrix and J is 16 = (2b)^2 times the consistent
    expectation :math:`-\operatorname{tr}(P\,\mathbb E[s_0 s_0^\top]) - W`: the integral of
    :math:`s_0^\top P s_0 + W` over the initial-state box [-2, 2]^2 instead of its mean. (The
    element-wise square makes P inexact off the diagonal; the runs' off-diagonal entries stay
    below 2e-4.) This is what makes their printed J(theta*) = -422.616 at gamma = 0.9.

    Parameters
    ----------
    theta : array_like, 4 entries or (2, 2)
        Gain K, row-major.
    sigma : float
        Their ``Sigma`` argument, a multiple of the identity (their runs pass 1).
    gamma : float
        Discount (their code's 0.9).

    Returns
    -------
    float
    """
    K = np.asarray(theta, dtype=float).reshape(2, 2)
    eye = np.eye(2)
    half = 0.5 * eye
    M = portable.matmul(portable.matmul(K.T, half), K) + half
    D = eye - gamma * (eye + 2 * K + K * K)
    # P = M D^-1, i.e. P^T = D^-T M^T (fixed-order solve, not LAPACK)
    P = portable.solve(D.T, M.T).T
    W = float(portable.trace(sigma * (half + gamma * P))) / (1 - gamma)
    b2 = LQG2D_BOUND * LQG2D_BOUND
    return -4 * b2 * (b2 / 3 * float(portable.trace(P)) + W)


__all__ = ["DATA_DIR", "FIGURES_51_52_STEP", "FIGURES_51_52_TOTAL", "REPOSITORY", "TABLE_5_4_BUDGET", "AuthorsRun",
           "budget_average", "cartpole_runs", "cartpole_theta_star", "figure51_52_curves", "figure55_curves",
           "grid_curve", "lqg2d_performance", "lqg2d_runs", "lqg2d_theta_ends", "manifest", "strict_improvement_ratio",
           "table51_runs", "table52_runs", "table52_settings", "table_5_1", "table_5_2", "table_5_3", "table_5_4",
           "truncated_average", "verify_data"]
