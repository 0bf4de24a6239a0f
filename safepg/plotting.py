"""The book's matplotlib style and its colours: one colour per concentration bound.

Figures have a white background so they read the same in the book's light and dark themes, and
each bound keeps one colour across the chapters and the browser explorers (which read the same
values). The reproduction adds the thesis's line styles per estimator (:mod:`safepg.thesis.plotting`).
"""

from __future__ import annotations

import matplotlib as mpl

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


def use_style() -> None:
    """Matplotlib defaults for the book, and high-DPI inline figures in a notebook.

    Under IPython, figures are shown as PNGs at twice the resolution (``"retina"``) with
    their display size recorded, so they stay sharp on high-density screens and when the
    browser zooms, and the book's pages keep their layout. No titles are drawn: the book
    numbers and captions its figures.
    """
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


def bound_color(bound: str, empirical_range: bool = False) -> str:
    """Colour of a concentration bound (Chebyshev has no range variant)."""
    return BOUND_COLORS[(bound, bool(empirical_range) and bound != "chebyshev")]


def bound_label(bound: str, empirical_range: bool = False) -> str:
    """Legend label of a bound, e.g. ``"Hoeffding (e.r.)"`` with the empirical range."""
    return BOUND_LABELS[bound] + (" (e.r.)" if empirical_range else "")


__all__ = ["ACCENT", "BOUND_COLORS", "BOUND_LABELS", "MUTED", "bound_color", "bound_label", "use_style"]
