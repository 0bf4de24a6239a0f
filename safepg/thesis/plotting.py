"""Shared plotting style: one colour per bound, one line style per estimator.

The thesis draws G(PO)MDP solid and REINFORCE dashed; we keep that everywhere, and give
each concentration bound one colour across all chapters (and the browser explorers,
which read the same tables). Figures have a white background so they read the same in
the book's light and dark themes.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import matplotlib as mpl

ESTIMATOR_LABELS = {"reinforce": "REINFORCE", "gpomdp": "G(PO)MDP"}
ESTIMATOR_DASH = {"reinforce": "--", "gpomdp": "-"}
BOUND_COLORS = {
    ("chebyshev", False): "#3b6fb6",
    ("hoeffding", False): "#d98c2b",
    ("hoeffding", True): "#c0392b",
    ("bernstein", False): "#2e9e5b",
    ("bernstein", True): "#7d4fb0",
}
BOUND_LABELS = {"chebyshev": "Chebyshev", "hoeffding": "Hoeffding", "bernstein": "Bernstein"}
#: Colour for single-curve figures (J(theta), Upsilon).
ACCENT = "#3b6fb6"
MUTED = "#7f7f7f"
#: Colour of an estimator when estimators, not bounds, are compared (REINFORCE is also dashed).
ESTIMATOR_COLORS = {"reinforce": MUTED, "gpomdp": ACCENT}


def use_style(digest: bool = False) -> None:
    """Matplotlib defaults for the book, and high-DPI inline figures in a notebook.

    Under IPython, figures are shown as PNGs at twice the resolution (``"retina"``) with
    their display size recorded, so they stay sharp on high-density screens and when the
    browser zooms, and the book's pages keep their layout. No titles are drawn: the book
    numbers and captions its figures. matplotlib's warning that a legend's automatic placement
    was slow is silenced (it depends on the machine's load, not on the figure). With
    ``digest``, each figure's text form, which nbval compares and the book does not show, is
    what it plots (:func:`safepg.thesis.figure_digest.digest_figures`).
    """
    # matplotlib warns when placing a legend at loc="best" took more than a second of wall time: on a busy
    # machine a figure cell then writes to stderr, and nbval fails it for that alone (a clock in the tests).
    warnings.filterwarnings("ignore", message='Creating legend with loc="best" can be slow', category=UserWarning)
    mpl.rcParams.update({
        "figure.facecolor": "white", "axes.facecolor": "white", "savefig.facecolor": "white",
        "axes.grid": True, "grid.alpha": 0.3, "axes.spines.top": False, "axes.spines.right": False,
        "figure.dpi": 100, "font.size": 10, "legend.frameon": False, "savefig.pad_inches": 0.12,
    })
    try:
        from IPython import get_ipython
    except ImportError:  # plain Python: nothing is displayed inline
        return
    if get_ipython() is not None:
        from matplotlib_inline.backend_inline import set_matplotlib_formats

        set_matplotlib_formats("retina")
        if digest:
            from safepg.thesis.figure_digest import digest_figures

            digest_figures()


def estimator_style(estimator: str) -> dict[str, Any]:
    """Line style of an estimator (thesis: G(PO)MDP solid, REINFORCE dashed)."""
    return {"linestyle": ESTIMATOR_DASH[estimator]}


def estimator_color(estimator: str) -> str:
    """Colour of an estimator in figures that compare estimators (not bounds)."""
    return ESTIMATOR_COLORS[estimator]


def style_table() -> dict[str, Any]:
    """Every colour, label and dash of this module as JSON-ready data, for the browser
    explorers (``safepg.thesis.explorers.component``), so JavaScript and matplotlib draw alike.

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


def bound_color(bound: str, empirical_range: bool = False) -> str:
    """Colour of a concentration bound (Chebyshev has no range variant)."""
    return BOUND_COLORS[(bound, bool(empirical_range) and bound != "chebyshev")]


def bound_label(bound: str, empirical_range: bool = False) -> str:
    """Legend label of a bound, e.g. ``"Hoeffding (e.r.)"`` with the empirical range."""
    return BOUND_LABELS[bound] + (" (e.r.)" if empirical_range else "")


def delta_color(delta: float, deltas: Sequence[float]) -> str:
    """Colour of one delta among several (viridis, darkest for the smallest delta)."""
    ordered = sorted(deltas)
    x = ordered.index(delta) / max(1, len(ordered) - 1)
    return mpl.colors.to_hex(mpl.colormaps["viridis"](0.1 + 0.75 * x))
