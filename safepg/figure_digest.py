"""A figure as text that nbval can compare: what each axes plots, to a stated precision, and a hash of it.

nbval compares a notebook's stored outputs with a new run's, but not images: a figure cell passes
whatever it draws, and its text form, ``<Figure size 700x400 with 1 Axes>``, says nothing of the
data. :func:`figure_digest` writes what a figure plots: per axes its labels, scales and artists,
per artist (line, band, markers, bars, image, text) its label, how many points, the range of x and
y and the last y, and a hash of every plotted value rounded to the printed precision, so that a
change that shows at that precision changes the text. :func:`digest_figures` makes it the text
form of every figure the kernel displays (``plotting.use_style(digest=True)``), where nbval
compares it and the book, which shows the image, never prints it.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

#: Significant digits of the printed values, and of the values hashed.
DIGITS = 4


def _text(values: np.ndarray, digits: int) -> list[str]:
    """Each value with ``digits`` significant digits (NaN for a masked or missing one, never "-0")."""
    a = np.ma.filled(np.ma.masked_invalid(np.ma.asarray(values, dtype=float)), np.nan).ravel() + 0.0
    return [f"{v:.{digits}g}" for v in a]


def _xy(artist: Any) -> tuple[str, np.ndarray] | None:
    """The kind of an artist and the data it plots, in data coordinates: (n, 2) points or an array."""
    from matplotlib.collections import LineCollection, PathCollection, PolyCollection, QuadMesh
    from matplotlib.image import AxesImage
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle
    from matplotlib.text import Text

    if isinstance(artist, Line2D):
        return "line", np.ma.filled(np.ma.asarray(artist.get_xydata(), dtype=float), np.nan)
    if isinstance(artist, PathCollection):  # scatter: the markers' positions
        return "markers", np.ma.filled(np.ma.asarray(artist.get_offsets(), dtype=float), np.nan).reshape(-1, 2)
    if isinstance(artist, QuadMesh | AxesImage):
        return "image", np.ma.filled(np.ma.asarray(artist.get_array(), dtype=float), np.nan)
    if isinstance(artist, LineCollection):
        segments = artist.get_segments()
        return "segments", np.concatenate(segments) if segments else np.empty((0, 2))
    if isinstance(artist, PolyCollection):  # fill_between: the band's outline
        paths = [p.vertices for p in artist.get_paths()]
        return "band", np.concatenate(paths) if paths else np.empty((0, 2))
    if isinstance(artist, Rectangle):  # a bar
        return "bar", np.array([[artist.get_x(), artist.get_y()], [artist.get_width(), artist.get_height()]])
    if isinstance(artist, Text):
        return "text", np.asarray(artist.get_position(), dtype=float).reshape(1, 2)
    return None


def _artists(ax: Any) -> list[Any]:
    """What an axes plots, in drawing order: lines, collections, patches, images and texts (not its frame)."""
    return [*ax.get_lines(), *ax.collections, *ax.patches, *ax.images, *ax.texts]


def _range(v: np.ndarray, digits: int) -> str:
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return "none"
    lo, hi = _text(np.array([finite.min(), finite.max()]), digits)
    return lo if lo == hi else f"{lo} to {hi}"


def _describe(kind: str, label: str, data: np.ndarray, digits: int) -> str:
    """One artist's line: its kind and label, its size, and its key values."""
    name = f'{kind} "{label}"' if label and not label.startswith("_") else kind
    if kind == "image":
        return f"{name}: {'x'.join(map(str, data.shape))} values, {_range(data, digits)}"
    if kind == "bar":
        return f"{name}: at x {_text(data[0, :1], digits)[0]}, height {_text(data[1, 1:], digits)[0]}"
    x, y = data[:, 0], data[:, 1]
    if kind == "text":
        return f"{name} at ({_text(x, digits)[0]}, {_text(y, digits)[0]})"
    finite = y[np.isfinite(y)]
    last = f", last {_text(finite[-1:], digits)[0]}" if kind == "line" and finite.size else ""
    return f"{name}: {len(data)} points; x {_range(x, digits)}; y {_range(y, digits)}{last}"


def figure_digest(fig: Any, digits: int = DIGITS) -> str:
    """What a matplotlib figure plots, as a few lines of text, with a hash of its data.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure. Its axes (twins and inset axes included) are read in order; in each, the lines,
        collections (bands, markers, segments, meshes), patches (bars), images and texts.
    digits : int
        Significant digits of every printed value and of the values hashed.

    Returns
    -------
    str
        The figure's own text form (``<Figure size 700x400 with 1 Axes>``), a line with the SHA-256
        (first 16 hex digits) of every plotted value rounded to ``digits`` significant digits (and of
        each text's string), then one line per axes and one per artist: its kind and label, its
        number of points, the range of x and y and, for a line, its last y. A plotted value that
        changes at the printed precision changes the hash.
    """
    lines: list[str] = []
    digest = hashlib.sha256()
    seen: set[int] = set()

    def walk(ax: Any, name: str) -> None:
        if id(ax) in seen:
            return
        seen.add(id(ax))
        artists = [(a, _xy(a)) for a in _artists(ax)]
        drawn = [(a, d) for a, d in artists if d is not None]
        kinds: dict[str, int] = {}
        for _, (kind, _data) in drawn:
            kinds[kind] = kinds.get(kind, 0) + 1
        counts = ", ".join(f"{k} ×{n}" for k, n in kinds.items()) or "nothing plotted"
        lines.append(f"axes {name} (x: {ax.get_xlabel() or '-'}, {ax.get_xscale()}; y: {ax.get_ylabel() or '-'}, "
                     f"{ax.get_yscale()}): {counts}")
        for artist, (kind, data) in drawn:
            label = artist.get_text() if kind == "text" else str(artist.get_label() or "")
            values = _text(data, digits)
            digest.update(f"{name}|{kind}|{label}|{data.shape}|{','.join(values)}\n".encode())
            lines.append("  " + _describe(kind, label, data, digits))
        for k, child in enumerate(getattr(ax, "child_axes", []), 1):
            walk(child, f"{name}.{k}")

    for i, ax in enumerate(fig.axes, 1):
        walk(ax, str(i))
    head = f"plotted data to {digits} significant digits, sha256 {digest.hexdigest()[:16]}"
    return "\n".join([repr(fig), head, *lines])


def digest_figures() -> bool:
    """Make :func:`figure_digest` the text form of every matplotlib figure this IPython kernel displays.

    A notebook shows a figure as its PNG; its text form, which the notebook stores beside the PNG and
    nbval compares (it skips images), becomes the digest. Outside IPython nothing is changed.

    Returns
    -------
    bool
        Whether a kernel was found (and its text formatter given the digest).
    """
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    ip = get_ipython()
    if ip is None:
        return False
    from matplotlib.figure import Figure

    ip.display_formatter.formatters["text/plain"].for_type(Figure, lambda fig, p, cycle: p.text(figure_digest(fig)))
    return True


__all__ = ["DIGITS", "digest_figures", "figure_digest"]
