"""Kernel-free explorers: sliders that recompute curves in the browser.

An :class:`Explorer` renders as one self-contained ``text/html`` block (controls, an SVG
plot drawn by a few lines of our own JavaScript, no library and no CDN), so it works in
the static book with no kernel and no network, and in JupyterLab. Each explorer has a
JavaScript ``compute`` and a Python twin ``compute_py`` returning the same structure:
the JavaScript recomputes closed forms (and picks precomputed curves embedded as JSON
where a closed form is not enough), the Python twin is what the browser test compares
against, and what :meth:`Explorer.interactive` draws with ipywidgets when a kernel runs
(:mod:`~safepg.explorers.kernel_view`: computed in a worker thread, with progress,
superseded by the next move).

``compute(p, data, lib)`` returns ``{"plots": {plot_id: {"series": [...], "markers": [...]}},
"values": {...}, "text": "..."}``; a series is ``{"label", "x", "y", "color", "dash"}``.
The last result is written as JSON into a hidden ``<pre class="safepg-values">`` so
tests can read what is drawn.

The JavaScript is in files beside this module, in ``static/``, read by :func:`static_text`:
``lib.js`` (safepg's closed forms, ``lib``), ``runtime.js`` (controls, plots, values) and
each explorer's compute function.
"""

from __future__ import annotations

import hashlib
import html
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, ClassVar

import numpy as np

#: The package whose ``static/`` folder holds the component's JavaScript.
PACKAGE = "safepg.explorers"


@cache
def static_text(name: str, package: str = PACKAGE) -> str:
    """The text of a file shipped in a package's ``static/`` folder.

    Parameters
    ----------
    name : str
        File name inside the folder, e.g. ``"lib.js"`` (safepg's closed forms in JavaScript,
        ``lib`` in every compute function), ``"runtime.js"`` (the browser half: controls, SVG
        plots, the values written to the DOM) or ``"upsilon_compute.js"``.
    package : str
        The package, by default this one (``safepg/explorers/static/``).

    Returns
    -------
    str
        The file's text (UTF-8), read once per process through :mod:`importlib.resources`,
        so it works from an installed wheel as well as from a source checkout.
    """
    return resources.files(package).joinpath("static", name).read_text(encoding="utf-8")


def static_bytes(name: str, package: str = PACKAGE) -> bytes:
    """The bytes of a binary file in a package's ``static/`` folder, found as :func:`static_text`
    finds a text file."""
    return resources.files(package).joinpath("static", name).read_bytes()


@dataclass(frozen=True)
class Slider:
    """A numeric control."""

    name: str
    label: str
    min: float
    max: float
    step: float
    value: float


@dataclass(frozen=True)
class Select:
    """A choice among named options ``(value, label)``."""

    name: str
    label: str
    options: tuple[tuple[str, str], ...]
    value: str


@dataclass(frozen=True)
class Checkbox:
    """An on/off switch; the page passes ``true``/``false`` (``p[name]`` is a bool)."""

    name: str
    label: str
    value: bool = False


@dataclass(frozen=True)
class Plot:
    """One SVG plot of the explorer."""

    id: str
    xlabel: str = ""
    ylabel: str = ""
    xlog: bool = False
    ylog: bool = False
    ymin: float | None = None
    ymax: float | None = None


class _SetAfterwards:
    """What an explorer may be given after it is built, per class or per explorer: plain attributes,
    not fields of the dataclass :class:`Explorer` (which takes every name annotated in its own body)."""

    #: ``interactive()``: the heading, when the page's would be wrong in a kernel (None: ``title``).
    kernel_title: str | None = None


@dataclass
class Explorer(_SetAfterwards):
    """An interactive figure that needs no kernel (see the module docstring).

    Parameters
    ----------
    title : heading shown above the controls
    controls : sliders and selects; their names are the keys of ``p``
    plots : the SVG plots, by id
    compute_js : body of ``function (p, data, lib) { ... }`` returning the result object
    compute_py : the same computation in Python, ``compute_py(p) -> result``
    data : JSON-serialisable precomputed curves (``data`` in compute)
    """

    title: str
    controls: Sequence[Slider | Select | Checkbox]
    plots: list[Plot]
    compute_js: str
    compute_py: Callable[[dict[str, Any]], dict[str, Any]]
    data: dict[str, Any] = field(default_factory=dict)

    def defaults(self) -> dict[str, Any]:
        """Control values as the page starts."""
        return {c.name: c.value for c in self.controls}

    def _spec(self) -> dict[str, Any]:
        return {"plots": [p.__dict__ for p in self.plots], "data": self.data}

    def _controls_html(self) -> str:
        """The sliders and selects, as labelled form elements the page's script reads.

        Each control sits in the ``<label>`` that names it (its accessible name is the visible
        label). The page's script (``safepgA11y`` in ``runtime.js``, not here, so that the
        notebooks' stored outputs, which nbval compares, stay as they are) hides a slider's
        shown value from assistive technology (the slider announces its value itself, and its
        name should not change as it moves), names any control that comes without a label,
        and makes the numbers under the plot an ``aria-live`` region.
        """
        style = 'style="display:inline-block;margin:0 1.2em 0.4em 0"'
        rows = []
        for c in self.controls:
            if isinstance(c, Checkbox):  # the <label> wraps the box: clicking the words toggles it
                rows.append(f'<label {style}><input type="checkbox" data-param="{c.name}"'
                            f'{" checked" if c.value else ""} style="vertical-align:middle"> '
                            f"{html.escape(c.label)}</label>")
            elif isinstance(c, Slider):
                rows.append(f'<label {style}>{html.escape(c.label)} <input type="range" data-param="{c.name}" '
                            f'min="{c.min}" max="{c.max}" step="{c.step}" value="{c.value}" '
                            f'style="vertical-align:middle"> <output data-show="{c.name}">{c.value}</output></label>')
            else:
                opts = "".join(f'<option value="{html.escape(v)}"{" selected" if v == c.value else ""}>'
                               f"{html.escape(lbl)}</option>" for v, lbl in c.options)
                rows.append(f'<label {style}>{html.escape(c.label)} <select data-param="{c.name}">{opts}</select>'
                            "</label>")
        return "".join(rows)

    def _plots_html(self) -> str:
        """One empty SVG per plot, drawn by the page's script."""
        return "".join(f'<svg data-plot="{p.id}" role="img" aria-label="{html.escape(p.ylabel)} over '
                       f'{html.escape(p.xlabel)}" style="width:100%;max-width:640px;height:auto;display:block">'
                       "</svg>" for p in self.plots)

    def to_html(self) -> str:
        """The self-contained HTML + JavaScript block."""
        spec = json.dumps(self._spec(), separators=(",", ":"), default=_json_default)
        uid = "safepg-" + hashlib.sha1((self.title + spec + self.compute_js).encode()).hexdigest()[:10]
        return (
            f'<div class="safepg-explorer" id="{uid}" style="border:1px solid rgba(127,127,127,.4);'
            f'border-radius:6px;padding:0.8em;margin:1em 0">'
            f'<div style="font-weight:600;margin-bottom:0.4em">{html.escape(self.title)}</div>'
            f'{self._controls_html()}{self._plots_html()}'
            '<div class="safepg-text" style="font-family:monospace;font-size:0.9em"></div>'
            '<pre class="safepg-values" hidden></pre>'
            f'<script>(function(){{\n{static_text("lib.js")}\n{static_text("runtime.js")}'
            f"const spec={spec};"
            f"const compute=function(p,data,lib){{{self.compute_js}}};"
            f'safepgExplorer(document.getElementById("{uid}"),spec,compute,lib);}})();</script></div>'
        )

    def __repr__(self) -> str:
        return f"Explorer({self.title!r})"

    def _repr_html_(self) -> str:
        return self.to_html()

    #: ``interactive()``: whether a slider redraws while it moves (False: on release, for a costly ``compute_py``).
    continuous_update: ClassVar[bool] = True
    #: ``interactive()``: width in inches of each plot.
    plot_width: ClassVar[float] = 6.0
    #: ``interactive()``: whether ``compute_py`` takes ``progress=report``, a callable
    #: ``report(fraction, message)`` to call while it computes: the view shows how far it is,
    #: and ``report`` raises once the controls have moved on, which stops the computation.
    compute_reports_progress: ClassVar[bool] = False

    def interactive(self) -> Any:
        """ipywidgets version for a live kernel: the same controls, drawn with matplotlib
        from ``compute_py`` in a worker thread, with a status line and a progress bar; a
        move supersedes the running computation, an error is shown as one line.

        Returns
        -------
        safepg.explorers.kernel_view.ExplorerView
            An ``ipywidgets.VBox``; it has started computing the figure of the defaults.
        """
        from safepg.explorers.kernel_view import ExplorerView

        return ExplorerView(self)


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
