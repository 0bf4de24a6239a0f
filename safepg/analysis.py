"""Curves and tables from stored learning records (what the figures and tables show).

Kept apart from plotting so the numbers behind every figure can be tested and printed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from safepg.learning import LearningRecord


def performance_on_grid(records: Sequence[LearningRecord], grid: np.ndarray) -> np.ndarray:
    """J of the policy that generated trajectory T, for T in ``grid`` (1-based), per seed.

    This is the thesis's "expected performance over sample trajectories": each
    iteration's J is held for all the trajectories of its batch (Figures 5.1, 5.2).
    Returns an array (seeds, len(grid)); NaN past a run's last trajectory.
    """
    grid = np.asarray(grid)
    out = np.full((len(records), grid.size), np.nan)
    for i, r in enumerate(records):
        ends = np.cumsum(r.batch_size)
        idx = np.searchsorted(ends, grid)
        ok = idx < r.iterations
        out[i, ok] = r.J[idx[ok]]
    return out


def measured_on_grid(records: Sequence[LearningRecord], grid: np.ndarray) -> np.ndarray:
    """Batch-average return of the batch containing trajectory T (Figure 5.9's curve)."""
    grid = np.asarray(grid)
    out = np.full((len(records), grid.size), np.nan)
    for i, r in enumerate(records):
        idx = np.searchsorted(np.cumsum(r.batch_size), grid)
        ok = idx < r.iterations
        out[i, ok] = r.J_hat[idx[ok]]
    return out


def by_iteration(records: Sequence[LearningRecord], field: str = "batch_size") -> np.ndarray:
    """A per-iteration field (e.g. batch size, step size) per seed, NaN-padded: (seeds, max I)."""
    length = max(r.iterations for r in records)
    out = np.full((len(records), length), np.nan)
    for i, r in enumerate(records):
        out[i, : r.iterations] = getattr(r, field)
    return out


def mean_band(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seed mean and the min-max band, ignoring missing (NaN) entries."""
    with np.errstate(all="ignore"):
        return np.nanmean(values, axis=0), np.nanmin(values, axis=0), np.nanmax(values, axis=0)


def compare(ours: float | None, thesis: float | None) -> dict[str, Any]:
    """Our value, the thesis's and the difference (ours - thesis)."""
    diff = None if ours is None or thesis is None else ours - thesis
    return {"ours": ours, "thesis": thesis, "difference": diff}


def table_5_1(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of Table 5.1: improvement ratio by sigma, N, alpha, ours beside the thesis's."""
    rows = []
    for c in report["configs"]:
        ir = c["improvement_ratio"]
        rows.append({"sigma": c["sigma"], "N": c["batch_size"], "alpha": c["alpha"], "seeds": c["seeds"],
                     "ci95": ir["ci95"], **compare(ir["mean"], (c["thesis"] or {}).get("improvement_ratio"))})
    return rows


def table_5_2(report: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of Table 5.2: average performance with 95% CI, ours beside the thesis's."""
    rows = []
    for c in report["configs"]:
        ub, th = c["upsilon_bar"], c["thesis"] or {}
        rows.append({"estimator": c["estimator"], "bound": c["bound"], "empirical_range": c["empirical_range"],
                     "delta": c["delta"], "seeds": c["seeds"], "ci95": ub["ci95"], "thesis_ci95": th.get("ci95"),
                     "improvement_ratio": c["improvement_ratio"]["mean"],
                     **compare(ub["mean"], th.get("upsilon_bar"))})
    return rows


def markdown_table(rows: Sequence[dict[str, Any]], columns: Sequence[tuple[str, str, str]]) -> str:
    """A Markdown table from rows; ``columns`` holds (key, header, format spec)."""
    def fmt(v: Any, spec: str) -> str:
        if v is None:
            return "-"
        if isinstance(v, (list, tuple)):
            return "[" + "; ".join(fmt(x, spec) for x in v) + "]"
        return format(v, spec) if spec else str(v)

    head = "| " + " | ".join(h for _, h, _ in columns) + " |"
    sep = "|" + "|".join("---" for _ in columns) + "|"
    body = ["| " + " | ".join(fmt(r.get(k), s) for k, _, s in columns) + " |" for r in rows]
    return "\n".join([head, sep, *body])
