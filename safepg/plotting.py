"""The book's matplotlib style and its colours: one colour per concentration bound.

Figures have a white background so they read the same in the book's light and dark themes, and
each bound keeps one colour across the chapters and the browser explorers (which read the same
values). The reproduction adds the thesis's line styles per estimator (:mod:`safepg.thesis.plotting`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib as mpl
import numpy as np

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


def use_style(digest: bool = False) -> None:
    """Matplotlib defaults for the book, and high-DPI inline figures in a notebook.

    Under IPython, figures are shown as PNGs at twice the resolution (``"retina"``) with
    their display size recorded, so they stay sharp on high-density screens and when the
    browser zooms, and the book's pages keep their layout. No titles are drawn: the book
    numbers and captions its figures. matplotlib's warning that a legend's automatic placement
    was slow is silenced (it depends on the machine's load, not on the figure). With
    ``digest``, each figure's text form, which nbval compares and the book does not show, is
    what it plots (:func:`safepg.figure_digest.digest_figures`).
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
            from safepg.figure_digest import digest_figures

            digest_figures()


def bound_color(bound: str, empirical_range: bool = False) -> str:
    """Colour of a concentration bound (Chebyshev has no range variant)."""
    return BOUND_COLORS[(bound, bool(empirical_range) and bound != "chebyshev")]


def bound_label(bound: str, empirical_range: bool = False) -> str:
    """Legend label of a bound, e.g. ``"Hoeffding (e.r.)"`` with the empirical range."""
    return BOUND_LABELS[bound] + (" (e.r.)" if empirical_range else "")


def figure_upsilon(bounds: Sequence[tuple[str, bool, Any]], g: float, c: float, budget: int | None = None,
                   n: np.ndarray | None = None) -> Any:
    r"""Upsilon_delta(N) of several bounds against N (log-log), each in its bound's colour.

    Parameters
    ----------
    bounds : sequence of (bound, empirical range, ErrorBound)
        The curves, e.g. ``("bernstein", True, bernstein(0.95, S, r))``.
    g : float
        The gradient magnitude.
    c : float
        The penalty constant.
    budget : int, optional
        Drawn as a dotted vertical line, labelled as one run's budget.
    n : array, optional
        The batch sizes (default: 10 to 10^13).

    Returns
    -------
    matplotlib.figure.Figure
        Zero values (eps(N) >= g) are not drawn.
    """
    import matplotlib.pyplot as plt

    from safepg.meta import upsilon

    N = np.geomspace(10, 1e13, 400) if n is None else np.asarray(n, dtype=float)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for bound, empirical, bd in bounds:
        U = np.asarray(upsilon(N, g, bd, c))
        ax.plot(N, np.where(U > 0, U, np.nan), color=bound_color(bound, empirical), label=bound_label(bound, empirical))
    if budget is not None:
        ax.axvline(budget, color=MUTED, linestyle=":", linewidth=1)
        ax.text(budget * 1.3, 0.02, "one run's budget", transform=ax.get_xaxis_transform(), color=MUTED,
                fontsize="small")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("batch size N (trajectories)")
    ax.set_ylabel(r"$\Upsilon_\delta(N)$")
    ax.legend(fontsize="small", loc="lower left")
    fig.tight_layout()
    return fig


def figure_scores(scores: Mapping[str, np.ndarray], labels: Mapping[str, str], highlighted: Sequence[str] = (),
                  reference: float | None = None, xlabel: str = "final policy's return") -> Any:
    """One row of dots per method, one dot per run's score; the ``highlighted`` methods in the accent
    colour, a dotted vertical line at ``reference`` (e.g. the start's score)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 0.45 * len(scores) + 1.0))
    for i, (name, x) in enumerate(scores.items()):
        x = np.asarray(x, dtype=float)
        ax.plot(x, i + np.linspace(-0.25, 0.25, x.size), "o", markersize=3,
                color=ACCENT if name in highlighted else MUTED)
    if reference is not None:
        ax.axvline(reference, color="black", linestyle=":", linewidth=1)
    ax.set_yticks(range(len(scores)), [labels.get(n, n) for n in scores], fontsize="small")
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    fig.tight_layout()
    return fig


__all__ = ["ACCENT", "BOUND_COLORS", "BOUND_LABELS", "MUTED", "bound_color", "bound_label", "figure_scores",
           "figure_upsilon", "use_style"]
