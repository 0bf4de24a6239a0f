r"""Is an adaptive run *safe*? The theorem's assumptions, and how often an update lowered J.

Theorem 4.2.3 and Corollary 4.2.8 certify that, with probability at least :math:`1 - \delta`,
the step :math:`\Lambda^*` does not lower the performance :math:`J`, provided that

* the penalty constant :math:`c` is built from bounds :math:`R \ge |r|` and
  :math:`M_\phi \ge |\phi|` of the task (Assumption 4.2.1), for the discounted :math:`J`
  that the simulator optimises;
* the step is taken only where the estimate is accurate enough, :math:`\epsilon < |\hat g_k|`
  (Assumption 4.2.7);
* :math:`\epsilon` bounds the gradient's estimation error with probability :math:`1 - \delta`
  (a valid error bound on the batch actually drawn).

:func:`theorem_assumptions` checks these on a run's settings; :func:`closed_form_outcomes`
counts, from a learning record, how many updates lowered the closed-form :math:`J`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from safepg.learning import LearningRecord
from safepg.runner import RunConfig


def theorem_assumptions(cfg: RunConfig) -> list[dict[str, Any]]:
    """The assumptions of Theorem 4.2.3 / Corollary 4.2.8 for an adaptive run ``cfg``.

    Returns one row per assumption: ``assumption`` (its words), ``holds`` (bool) and
    ``why`` (the setting that decides it).
    """
    if cfg.algorithm != "adaptive":
        raise ValueError(f"cfg must be an adaptive run, got algorithm={cfg.algorithm!r}")
    constants = cfg.constants or "bounds"
    statistics = cfg.statistics or "component"
    rows = [
        {"assumption": "c from bounds of |r| and |phi| (Assumption 4.2.1)",
         "holds": constants == "bounds",
         "why": "R and M_phi are the task's bounds" if constants == "bounds"
         else "R and M_phi are measured on each batch, so c changes with the batch"},
        {"assumption": "c written for the discount the simulator optimises",
         "holds": "constants_gamma" not in cfg.env,
         "why": "one discount" if "constants_gamma" not in cfg.env
         else f"the simulated return and c use different discounts ({cfg.env})"},
        {"assumption": "step only where eps < |g_k| (Assumption 4.2.7)",
         "holds": not cfg.step_when_unsafe,
         "why": "no step when eps >= |g_k|" if not cfg.step_when_unsafe
         else "the step formula is applied even when eps >= |g_k|"},
        {"assumption": "eps a per-component error bound",
         "holds": statistics == "component",
         "why": "variance and range of component k" if statistics == "component"
         else "the largest variance and range over the components"},
        {"assumption": "eps from a range bound, not the batch's own range",
         "holds": not (cfg.bound in ("bernstein", "hoeffding") and cfg.empirical_range),
         "why": "theoretical range" if not cfg.empirical_range else "the empirical range of the batch"},
        {"assumption": "batch sizes as Algorithm 4.1 sets them (N_min, then N* of the bound)",
         "holds": cfg.n_first is None,
         "why": "the first batch is the algorithm's N_min, every later one the bound's N*" if cfg.n_first is None
         else f"the first batch is fixed at {cfg.n_first}, outside the algorithm"},
    ]
    return rows


def closed_form_outcomes(record: LearningRecord) -> dict[str, Any]:
    """How the updates of ``record`` changed the closed-form J (``record.J``, one per theta row).

    Counts only updates that moved theta. Returns ``updates`` (their number), ``lowered``
    (those with a strictly lower J after than before), ``share_lowered``,
    ``unguarded`` (moves taken where eps >= |g_k|, ``record.safe`` False),
    ``lowered_unguarded`` and ``largest_drop`` (the largest decrease of J, 0 if none).
    """
    J = np.asarray(record.J, dtype=float)
    if J.shape != (record.theta.shape[0],) or not np.all(np.isfinite(J)):
        raise ValueError("record.J must hold a finite closed-form J per theta row")
    moved = np.any(np.diff(record.theta, axis=0) != 0, axis=1)
    dJ = np.diff(J)
    lowered = moved & (dJ < 0)
    unguarded = moved & ~np.asarray(record.safe, dtype=bool)
    n = int(moved.sum())
    return {"updates": n, "lowered": int(lowered.sum()), "share_lowered": lowered.sum() / n if n else 0.0,
            "unguarded": int(unguarded.sum()), "lowered_unguarded": int((lowered & unguarded).sum()),
            "largest_drop": float(-dJ[lowered].min()) if lowered.any() else 0.0}


# ---------------------------------------------------------------- Monte Carlo J (cart-pole)
