"""The authors' own raw outputs beside each row: Tables 5.1-5.4, the 2-D runs' final parameters,
batch and step sizes, and the cart-pole baseline, recomputed by :mod:`safepg.thesis.authors`
with their plot scripts' rules; each with ``path@commit`` of the file(s) behind it."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from safepg.thesis import authors
from safepg.thesis.scorecard.text import num, pct

#: Table 5.3's N = 100 run: its output file was committed but its blob is not in the authors'
#: repository, so that row cannot be checked against their output.
MISSING_T53_N100 = "lqgnd/results/polgrad_theta0_N100_alpha6_sample1.out (blob 2b2178b, added in 0e5c8b5)"


@dataclass(frozen=True)
class Output:
    """One of the authors' numbers: its value, the cell's text and ``path@commit`` of its file(s).

    ``complete``: every run the printed value averages is committed (a slip between their
    output and the print can only be named then). ``iterations``: how many iterations it averages.
    """

    value: float | None
    text: str
    source: str
    complete: bool = True
    iterations: int | None = None


def source(src: Mapping[str, Any], runs: int = 1) -> str:
    """``path@commit`` (seven hex digits) of a manifest source; ``runs`` > 1 writes the sample
    number as a range (``..._sample{1-5}.out``)."""
    path = src["path"]
    if runs > 1:
        path = re.sub(r"sample1(?=\.out$)", f"sample{{1-{runs}}}", path)
    return f"{path}@{src['commit'][:7]}"


def table_5_1(sigma: float, n: int, alpha: float) -> Output:
    """A cell of Table 5.1 from the authors' run: strict increases over 10^6/N - 1 updates."""
    cell = authors.table_5_1()[(sigma, n, alpha)]
    run = authors.table51_runs()[(sigma, n, alpha)]
    text = f"{pct(cell['improvement_ratio'])} ({cell['increases']}/{cell['updates']})"
    return Output(cell["improvement_ratio"], text, source(run.source))


def table_5_2(key: tuple[str, str, bool, float]) -> Output:
    """A row of Table 5.2 from the authors' runs: the mean over their runs of each run's average
    over the shortest run's iterations, with the 90% t-interval their script prints as 95%."""
    row = authors.table_5_2()[key]
    runs = authors.table52_runs()[key]
    lo, hi = row["ci90"]
    text = f"{num(row['mean'], 4)} [{num(lo, 4)}; {num(hi, 4)}]" if row["runs"] > 1 else \
        f"{num(row['mean'], 4)} (1 run)"
    return Output(row["mean"], text, source(runs[0].source, row["runs"]), complete=row["runs"] >= 5,
                  iterations=row["T"])


def lqg2d(run: str, quantity: str, entry: tuple[int, int] | None = None) -> Output:
    """A number of the authors' 2-D runs (``"adaptive"``, ``"N=1000"``, ``"scalar"``,
    ``"coordinate"``): ``"upsilon_bar"``, ``"improvement_ratio"``, ``"theta_final"`` (one
    ``entry``), ``"batch_first"`` / ``"batch_last"`` (mean batch over iterations 2-11 / the last 10
    full ones, as the scorecard measures ours) or ``"step"`` (median step)."""
    r = authors.lqg2d_runs()[run]
    src = source(r.source)
    if quantity == "theta_final":
        i, j = entry or (0, 0)
        v = float(authors.table_5_3()[run]["theta_final"][i, j])
        return Output(v, f"{v:.6g}", src)
    if quantity in ("batch_first", "batch_last"):
        n = r["N"][1:11] if quantity == "batch_first" else r["N"][-11:-1]
        v = float(np.mean(n))
        return Output(v, f"{v:.0f}", src)
    if quantity == "step":
        v = float(np.median(r["alpha"][r["alpha"] > 0]))
        return Output(v, f"median {v:.1e}", src)
    v = float(authors.table_5_3()[run][quantity])
    return Output(v, pct(v) if quantity == "improvement_ratio" else num(v, 4), src)


def lqg2d_missing() -> Output:
    """Table 5.3's N = 100 run, absent from the authors' repository."""
    return Output(None, "not in their repository", MISSING_T53_N100, complete=False)


def cartpole(run: str, quantity: str) -> Output:
    """A number of the authors' cart-pole runs: Table 5.4's ``"upsilon_bar"`` or
    ``"improvement_ratio"`` over their adaptive run's length (``run`` ``"adaptive"`` or
    ``"fixed"``), or the baseline's ``"iterations"``."""
    r = authors.cartpole_runs()[run]
    if quantity == "iterations":
        return Output(float(r.iterations), f"{r.iterations}", source(r.source))
    cell = authors.table_5_4()[run]
    v = float(cell[quantity])
    text = f"{pct(v)} ({cell['increases']}/{cell['batches'] - 1})" if quantity == "improvement_ratio" else num(v, 4)
    return Output(v, text, source(r.source))


def cartpole_components_updated() -> list[int]:
    """Components of theta the authors' adaptive doubled-pole run changed."""
    theta = authors.cartpole_runs()["adaptive"]["theta"]
    return [int(i) for i in np.flatnonzero(np.any(theta != theta[0], axis=0))]
