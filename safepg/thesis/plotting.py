"""The reproduction's plotting style: the core's (:mod:`safepg.plotting`), and one line style per estimator.

The thesis draws G(PO)MDP solid and REINFORCE dashed; we keep that everywhere, beside the core's
one colour per concentration bound (and the browser explorers read the same tables).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import matplotlib as mpl

from safepg.plotting import ACCENT, BOUND_COLORS, BOUND_LABELS, MUTED, bound_color, bound_label, use_style

ESTIMATOR_LABELS = {"reinforce": "REINFORCE", "gpomdp": "G(PO)MDP"}
ESTIMATOR_DASH = {"reinforce": "--", "gpomdp": "-"}
#: Colour of an estimator when estimators, not bounds, are compared (REINFORCE is also dashed).
ESTIMATOR_COLORS = {"reinforce": MUTED, "gpomdp": ACCENT}


def estimator_style(estimator: str) -> dict[str, Any]:
    """Line style of an estimator (thesis: G(PO)MDP solid, REINFORCE dashed)."""
    return {"linestyle": ESTIMATOR_DASH[estimator]}


def estimator_color(estimator: str) -> str:
    """Colour of an estimator in figures that compare estimators (not bounds)."""
    return ESTIMATOR_COLORS[estimator]


def style_table() -> dict[str, Any]:
    """Every colour, label and dash of this module as JSON-ready data, for the browser
    explorers (``safepg.explorers.component``), so JavaScript and matplotlib draw alike.

    Returns
    -------
    dict
        ``{"accent", "muted", "estimators": {name: {"label", "color", "dash"}},
        "bounds": {"chebyshev" | "hoeffding" | "hoeffding-er" | ...: {"label", "color"}}}``;
        ``dash`` is true for a dashed line.
    """
    return {
        "accent": ACCENT, "muted": MUTED,
        "estimators": {e: {"label": ESTIMATOR_LABELS[e], "color": ESTIMATOR_COLORS[e],
                           "dash": ESTIMATOR_DASH[e] != "-"} for e in ESTIMATOR_LABELS},
        "bounds": {b + ("-er" if er else ""): {"label": bound_label(b, er), "color": c}
                   for (b, er), c in BOUND_COLORS.items()},
    }


def delta_color(delta: float, deltas: Sequence[float]) -> str:
    """Colour of one delta among several (viridis, darkest for the smallest delta)."""
    ordered = sorted(deltas)
    x = ordered.index(delta) / max(1, len(ordered) - 1)
    return mpl.colors.to_hex(mpl.colormaps["viridis"](0.1 + 0.75 * x))


__all__ = ["ACCENT", "BOUND_COLORS", "BOUND_LABELS", "ESTIMATOR_COLORS", "ESTIMATOR_DASH", "ESTIMATOR_LABELS", "MUTED",
           "bound_color", "bound_label", "delta_color", "estimator_color", "estimator_style", "style_table",
           "use_style"]
