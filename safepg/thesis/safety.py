"""Is an adaptive run safe: the core's measurement (:mod:`safepg.safety`), read by the reproduction's
chapters under its old name."""

from __future__ import annotations

from safepg.safety import (
    MC_ALPHA,
    MC_LOOKS,
    MC_LOOKS_OUR_RUNS,
    MonteCarloOutcomes,
    clopper_pearson_upper,
    closed_form_outcomes,
    closed_form_summary,
    monte_carlo_changes,
    moved_updates,
    normal_quantile,
    paired_returns,
    safety_summary,
    theorem_assumptions,
)

__all__ = ["MC_ALPHA", "MC_LOOKS", "MC_LOOKS_OUR_RUNS", "MonteCarloOutcomes", "closed_form_outcomes",
           "closed_form_summary", "clopper_pearson_upper", "monte_carlo_changes", "moved_updates", "normal_quantile",
           "paired_returns", "safety_summary", "theorem_assumptions"]
