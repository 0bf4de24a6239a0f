r"""The runs whose safety the cart-pole chapter measures; the measurement and its store are the
core's (:mod:`safepg.safety_store`), read here under their old names.

:func:`table_5_4_runs` lists the runs whose updates the cart-pole chapter measures (the chapter
and ``python -m safepg run-book`` both take them from here, so the book's build computes each
measurement once, before the chapter reads it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from safepg.safety import MC_LOOKS, MC_LOOKS_OUR_RUNS
from safepg.safety_store import (
    cached_monte_carlo_changes,
    is_measured,
    measure_runs,
    measurement_file,
    stored_measurement,
)

#: A measured run list of the chapter: (task, the runs' thetas, the looks).
MeasuredRuns = tuple[Any, list[np.ndarray], tuple[int, ...]]


def table_5_4_runs(records: Any, their_runs: Any, window: int) -> dict[str, MeasuredRuns]:
    """The runs whose every update the cart-pole chapter measures: ``{label: (task, runs, looks)}``.

    The authors' two logged runs (their fixed-step run within Table 5.4's ``window`` of batches)
    with :data:`~safepg.safety.MC_LOOKS`, and each seed of ours under their settings, from
    their theta*, and under the thesis's text with :data:`~safepg.safety.MC_LOOKS_OUR_RUNS`.
    ``records`` maps the three table-5.4 experiments to their records by configuration;
    ``their_runs`` is :func:`safepg.thesis.authors.cartpole_runs`.
    """
    from safepg.thesis.experiments import get_experiment

    task = get_experiment("table-5.4-authors-theta-star").config("adaptive").make_task()
    text_task = get_experiment("table-5.4").config("adaptive").make_task()  # gamma = 0.99, 41.8 degrees
    runs: dict[str, MeasuredRuns] = {
        "authors' adaptive run": (task, [their_runs["adaptive"]["theta"]], MC_LOOKS),
        "authors' fixed-step run": (task, [their_runs["fixed"]["theta"][:window]], MC_LOOKS)}
    for name, setting, t in (("table-5.4-authors", "ours, their settings", task),
                             ("table-5.4-authors-theta-star", "ours, their settings, their θ*", task),
                             ("table-5.4", "ours, thesis's text", text_task)):
        for cfg, method in (("adaptive", "adaptive"), ("N=4000", "fixed step" if "authors" in name else "vanilla")):
            runs[f"{setting}: {method}"] = (t, [r.theta for r in records[name][cfg]], MC_LOOKS_OUR_RUNS)
    return runs


__all__ = ["MeasuredRuns", "cached_monte_carlo_changes", "is_measured", "measure_runs", "measurement_file",
           "stored_measurement", "table_5_4_runs"]
