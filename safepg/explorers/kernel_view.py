"""The explorers in a live kernel: the ipywidgets view that :meth:`Explorer.interactive` returns.

In the static book an explorer recomputes in the reader's browser; in Jupyter,
``.interactive()`` shows the same controls and draws from the explorer's Python twin
``compute_py``, which may take long (the live learner reruns up to 3·10^6 trajectories
with safepg). So that a slider move always gets an answer, an :class:`ExplorerView`

- computes in a worker thread of its own, never in the kernel's main thread, which stays
  free to receive the next moves;
- keeps only the newest request: a move bumps a generation counter; the running
  computation sees it at its next progress report (the live learner reports after every
  batch of trajectories) and stops by raising :class:`Superseded`, and the worker goes on
  with the newest values. Moves made in between are never computed: nothing queues;
- shows progress: a status line (what runs, how far) and a progress bar, sent to the
  page at most every :data:`REPORT_EVERY` seconds;
- shows an error as one line (the exception's type and message) above the figure, keeps
  the last good figure, and prints no traceback (the exception is kept in
  :attr:`ExplorerView.last_error`).

The figure is a PNG drawn with matplotlib's object-oriented API (pyplot's global figure list is
not for threads) into an ``<img>`` with alt text in an ``ipywidgets.HTML``, which is updated by
assigning its value, which ipywidgets sends to the page from any thread.
"""

from __future__ import annotations

import base64
import html
import io
import json
import threading
import time
from typing import Any

import ipywidgets as w

#: Seconds between two progress messages to the page: a run of N = 100 batches reports
#: thousands of times a second, which the page need not see.
REPORT_EVERY = 0.2
#: One computation at a time in the kernel, whichever view asks: two learning runs would
#: only share the cores, and numba's "workqueue" threading layer (used where neither OpenMP
#: nor TBB is installed) aborts the process when two threads launch parallel kernels at once.
_COMPUTE = threading.Lock()


class Superseded(Exception):
    """Raised inside a computation whose control values are no longer the newest."""


def render_png(explorer: Any, res: dict[str, Any], dpi: int = 100) -> bytes:
    """Draw ``compute_py``'s result as one PNG, one panel per plot of the explorer.

    Parameters
    ----------
    explorer : safepg.explorers.component.Explorer
        Gives the plots (axis labels, scales, limits) and the panel width.
    res : dict
        ``compute_py``'s result: ``{"plots": {plot_id: {"series": [...], "markers": [...]}}}``.
    dpi : int
        Pixels per inch of the PNG.

    Returns
    -------
    bytes
        The PNG file.
    """
    from matplotlib.figure import Figure  # no pyplot: see the module docstring
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    fig = Figure(figsize=(explorer.plot_width * len(explorer.plots), 3.6))
    axes = fig.subplots(1, len(explorer.plots), squeeze=False)
    for ax, spec in zip(axes[0], explorer.plots):
        r = res["plots"][spec.id]
        for s in r["series"]:
            ax.plot(s["x"], s["y"], color=s.get("color"), linestyle="--" if s.get("dash") else "-",
                    label=s.get("label"))
        for mk in r.get("markers", []):
            ax.plot([mk["x"]], [mk["y"]], "o", color=mk.get("color"), label=mk.get("label"))
        ax.set_xscale("log" if spec.xlog else "linear")
        ax.set_yscale("log" if spec.ylog else "linear")
        for axis, log in ((ax.xaxis, spec.xlog), (ax.yaxis, spec.ylog)):
            if log:
                # Labels at 1, 2, 5 x 10^k: matplotlib's default labels every minor tick on a
                # range of one or two decades (Upsilon_delta(N)), and the labels overlap.
                axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
                axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
                axis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(spec.xlabel)
        ax.set_ylabel(spec.ylabel)
        if spec.ymin is not None or spec.ymax is not None:
            ax.set_ylim(spec.ymin, spec.ymax)
        if ax.get_legend_handles_labels()[1]:
            ax.legend(fontsize="small")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def _short(v: Any) -> str:
    """A control or result value as the status line shows it."""
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def result_text(res: dict[str, Any]) -> str:
    """The line under the figure: the result's ``text``, else its scalar ``values``."""
    if res.get("text"):
        return str(res["text"])
    vals = res.get("values") or {}
    return ", ".join(f"{k} = {_short(v)}" for k, v in vals.items() if isinstance(v, int | float))


def figure_alt(explorer: Any) -> str:
    """The figure's alt text: what each of its plots draws against what, and where its numbers are."""
    parts = [f"{p.ylabel or p.id} against {p.xlabel}" if p.xlabel else (p.ylabel or p.id) for p in explorer.plots]
    return (f"{explorer.kernel_title or explorer.title}: {'; '.join(parts)}, for the values of the controls "
            "above; the numbers are in the text below the figure.")


def figure_html(explorer: Any, png: bytes, width: int) -> str:
    """The figure as an ``<img>`` with alt text (:func:`figure_alt`), ``width`` px wide at most."""
    src = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
    return (f'<img class="safepg-figure" src="{src}" alt="{html.escape(figure_alt(explorer), quote=True)}" '
            f'style="width:{width}px;max-width:100%;height:auto">')


class ExplorerView(w.VBox):  # type: ignore[misc]  # ipywidgets ships no types: its VBox is Any to mypy
    """An explorer's controls, status, progress bar and figure, computed in a worker thread.

    Parameters
    ----------
    explorer : safepg.explorers.component.Explorer
        Not imported here: the component imports this module when asked for a view. Its
        controls become ipywidgets (sliders act while they move when the explorer's
        ``continuous_update`` is True, on release otherwise); its ``compute_py`` is called
        with the control values, and with ``progress=report`` when the explorer's
        ``compute_reports_progress`` is True. ``report(fraction, message)`` shows how far
        the computation is and raises :class:`Superseded` once newer values arrived.

    Attributes
    ----------
    controls : dict
        The control widgets by parameter name.
    status, error, text : ipywidgets.HTML
        The status line (computing, how far, or how long the shown figure took), the
        error line (empty unless the newest values failed) and the result's text.
    progress : ipywidgets.FloatProgress
        Fraction done, shown while a computation that reports progress runs.
    figure : ipywidgets.HTML
        The PNG of the newest result.
    drawn : dict or None
        The control values the figure shows.
    counts : dict
        How many computations were ``started``, ``drawn``, ``superseded`` and ``failed``.
    last_error : BaseException or None
        The exception behind the error line, for a traceback on demand.
    """

    def __init__(self, explorer: Any) -> None:
        self.explorer = explorer
        self.controls: dict[str, w.ValueWidget] = {}
        style = {"description_width": "initial"}
        for c in explorer.controls:
            if not hasattr(c, "options") and not hasattr(c, "min"):  # a Checkbox
                ctl = w.Checkbox(value=bool(c.value), description=c.label, indent=False, style=style,
                                 layout=w.Layout(width="auto"))
            elif not hasattr(c, "options"):  # a Slider; a Select has options
                ctl = w.FloatSlider(value=c.value, min=c.min, max=c.max, step=c.step, description=c.label,
                                    continuous_update=explorer.continuous_update, style=style,
                                    layout=w.Layout(width="auto", min_width="260px"))
            else:
                ctl = w.Dropdown(options=[(lbl, v) for v, lbl in c.options], value=c.value, description=c.label,
                                 style=style, layout=w.Layout(width="auto"))
            ctl.add_class(f"safepg-control-{c.name}")
            self.controls[c.name] = ctl
        self.status = w.HTML()
        self.status.add_class("safepg-status")
        self.progress = w.FloatProgress(value=0.0, min=0.0, max=1.0,
                                        layout=w.Layout(width="180px", visibility="hidden"))
        self.progress.add_class("safepg-progress")
        self.error = w.HTML()
        self.error.add_class("safepg-error")
        # An <img> in an HTML widget, not ipywidgets.Image, which cannot carry alt text. Shown at
        # its own size (render_png's 100 dpi), narrowed to the output area if wider.
        self._figure_width = round(explorer.plot_width * len(explorer.plots) * 100)
        self.figure = w.HTML()
        self.figure.add_class("safepg-figure-box")
        self.text = w.HTML()
        self.text.add_class("safepg-text")
        self.drawn: dict[str, Any] | None = None
        self.counts = {"started": 0, "drawn": 0, "superseded": 0, "failed": 0}
        self.last_error: BaseException | None = None
        self._cond = threading.Condition()
        self._generation = 0
        self._pending: tuple[int, dict[str, Any]] | None = None
        self._busy = False
        self._closed = False
        title = w.HTML(f"<b>{html.escape(explorer.kernel_title or explorer.title)}</b>")
        controls = w.HBox(list(self.controls.values()), layout=w.Layout(flex_flow="row wrap"))
        super().__init__([title, controls, w.HBox([self.progress, self.status]), self.error, self.figure,
                          self.text])
        self.add_class("safepg-interactive")
        for ctl in self.controls.values():
            ctl.observe(self._moved, names="value")
        self._thread = threading.Thread(target=self._work, name=f"safepg view: {explorer.title}", daemon=True)
        self._thread.start()
        self.request()

    # ---------------------------------------------------------------- main thread
    def values(self) -> dict[str, Any]:
        """The control values, by parameter name."""
        return {name: ctl.value for name, ctl in self.controls.items()}

    def _moved(self, change: dict[str, Any]) -> None:
        self.request()

    def request(self) -> None:
        """Ask for the figure of the current control values; supersedes any running computation."""
        with self._cond:
            self._generation += 1
            self._pending = (self._generation, self.values())
            self.status.value = "computing…"
            self._cond.notify_all()

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until the newest request is drawn or failed (for scripts and tests).

        Parameters
        ----------
        timeout : float
            Seconds to wait at most.

        Returns
        -------
        bool
            True if the view is idle, False if the time ran out.
        """
        with self._cond:
            return self._cond.wait_for(lambda: self._pending is None and not self._busy, timeout)

    def close(self) -> None:
        """Stop the worker thread (after its current batch) and close the widgets."""
        with self._cond:
            self._closed = True
            self._generation += 1
            self._cond.notify_all()
        for child in [*self.controls.values(), self.status, self.progress, self.error, self.figure, self.text]:
            child.close()
        super().close()

    # -------------------------------------------------------------- worker thread
    def _work(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._pending is not None or self._closed)
                if self._closed:
                    return
                assert self._pending is not None
                gen, p = self._pending
                self._pending = None
                self._busy = True
            try:
                self._compute(gen, p)
            finally:
                with self._cond:
                    self._busy = False
                    self._cond.notify_all()

    def _current(self, gen: int) -> None:
        if gen != self._generation:
            raise Superseded

    def _compute(self, gen: int, p: dict[str, Any]) -> None:
        start = time.monotonic()
        last = [start]

        def report(fraction: float, message: str = "") -> None:
            self._current(gen)  # the cancellation point: cheap, called as often as the computation likes
            now = time.monotonic()
            if now - last[0] < REPORT_EVERY:
                return
            last[0] = now
            with self._cond:
                self._current(gen)
                self.progress.value = min(max(float(fraction), 0.0), 1.0)
                self.progress.layout.visibility = "visible"
                self.status.value = html.escape(f"computing… {100 * fraction:.0f}%" + (f" · {message}" if message
                                                                                        else ""))

        try:
            if not _COMPUTE.acquire(blocking=False):
                with self._cond:
                    self._current(gen)
                    self.status.value = "waiting for another explorer's computation…"
                _COMPUTE.acquire()
            try:
                self._current(gen)
                self.counts["started"] += 1
                if self.explorer.compute_reports_progress:
                    res = self.explorer.compute_py(p, progress=report)
                else:
                    res = self.explorer.compute_py(p)
                self._current(gen)
                png = render_png(self.explorer, res)
            finally:
                _COMPUTE.release()
        except Superseded:
            self.counts["superseded"] += 1
            return
        except Exception as e:  # shown as one line, never a traceback: see the module docstring
            with self._cond:
                self.counts["failed"] += 1
                self.last_error = e
                if gen != self._generation:
                    return
                self.progress.layout.visibility = "hidden"
                self.status.value = "error"
                shown = ", ".join(f"{k} = {_short(v)}" for k, v in p.items())
                self.error.value = (f'<span style="color:#b00020">Cannot draw {html.escape(shown)}: '
                                    f"{html.escape(type(e).__name__)}: {html.escape(str(e))}</span>")
            return
        with self._cond:
            if gen != self._generation:  # newer values came while drawing: the worker draws those next
                self.counts["superseded"] += 1
                return
            self.figure.value = figure_html(self.explorer, png, self._figure_width)
            self.text.value = f'<span style="font-family:monospace">{html.escape(result_text(res))}</span>'
            self.error.value = ""
            self.progress.layout.visibility = "hidden"
            params = html.escape(json.dumps(p), quote=True)
            self.status.value = (f'<span data-params="{params}">drawn in {time.monotonic() - start:.1f} s'
                                 "</span>")
            self.drawn = p
            self.counts["drawn"] += 1

    def __repr__(self) -> str:
        return f"ExplorerView({self.explorer.kernel_title or self.explorer.title!r})"


__all__ = ["ExplorerView", "Superseded", "figure_alt", "figure_html", "render_png", "result_text"]
