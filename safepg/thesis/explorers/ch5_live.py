r"""What the Chapter 5 live explorers share (the 2-D LQG of Section 5.2, the cart-pole of Section 5.3).

Each explorer is a :class:`Ch5LiveExplorer`: its page half (``static/ch5_page.js`` with the
explorer's own ``static/lqg2d_page.js`` or ``static/cartpole_page.js``, drawn by the component's
``static/runtime.js``) runs the JavaScript learner (:func:`learner_source`: the engine's
``safepgLearner.Driver`` for vector tasks) in a Web Worker built from an inline Blob, so it
works from ``file://`` with no kernel and no network. Every control move cancels the running
worker and starts a new one; the curves are drawn while the runs progress.

The page keeps each run as a *trace* (the per-iteration arrays of the learner: ``batchSize``,
``alpha``, ``eps``, ``Jhat``, ``grad``, ``theta``, ``J``, ``c``) and builds the plots and the
summary from the traces. The Python twins run :func:`safepg.learning.adaptive_pg` and
:func:`~safepg.learning.vanilla_pg` with the same settings, turn each record into the same
trace (:func:`record_trace`) and build the result with the same rules, so the structure a page
draws and the one ``.interactive()`` draws in a kernel are the same (their generators differ:
for one seed the curves differ as two seeds do).
"""

from __future__ import annotations

import hashlib
import html
import json
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from safepg.bounds import BOUNDS
from safepg.options import ErrorModel
from safepg.record import LearningRecord
from safepg.thesis.explorers.component import Explorer, static_text

#: Points of each drawn curve: enough for a 640 px plot.
CURVE_POINTS = 400
#: ``progress`` of a Python twin: ``report(fraction, message)``.
Reporter = Callable[[float, str], object]
#: Bounds offered: (value, label); "-er" is the empirical range.
BOUND_CHOICES = (("chebyshev", "Chebyshev"), ("hoeffding", "Hoeffding"), ("hoeffding-er", "Hoeffding (e.r.)"),
                 ("bernstein", "Bernstein"), ("bernstein-er", "Bernstein (e.r.)"))
#: Keys of a page's ``values`` that only the page has (the Web Worker, its timing, and which
#: code computed each run's batches: "webassembly" or "javascript").
PAGE_ONLY = ("worker", "elapsed_ms", "run_ms", "kernel", "error")


def learner_source() -> str:
    """The JavaScript learner for vector tasks: the engine's ``js_tasks.learner_sources()``
    (the learner with its 2-D LQG and cart-pole tasks), or the 1-D ``learner.js`` before it exists."""
    try:
        from safepg.thesis.explorers import js_tasks
    except ImportError:
        return static_text("learner.js")
    src = js_tasks.learner_sources()
    return src if isinstance(src, str) else "\n".join(src)


def finite(v: Any) -> float | None:
    """A float for the page's JSON: None for NaN or infinity (JSON.stringify's null)."""
    v = float(v)
    return v if math.isfinite(v) else None


def thin(n: int, points: int = CURVE_POINTS) -> list[int]:
    """Indices of at most ``points`` evenly spread entries of a length-n curve (first and last
    kept): the page's ``safepgThin`` (``static/live_jobs.js``)."""
    if n <= points:
        return list(range(n))
    out: list[int] = []
    for i in range(points):
        k = math.floor(i * (n - 1) / (points - 1) + 0.5)
        if not out or out[-1] != k:
            out.append(k)
    return out


def exp_text(v: float | None, digits: int = 2) -> str:
    """JavaScript's ``toExponential(digits)``: 5.75e+7, 1.30e-9; "-" for none."""
    if v is None or not math.isfinite(v):
        return "-"
    mantissa, exponent = f"{v:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent):+d}"


def fixed(v: float | None, digits: int) -> str:
    """JavaScript's ``toFixed(digits)``; "-" for none."""
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}f}"


def record_c(rec: LearningRecord, batch_constants: bool = False) -> list[float | None]:
    """The penalty constant c used at each iteration of an adaptive record: the bound-based
    ``config["c"]``, or with ``batch_constants`` (R and M_phi measured per batch) the batch's c, recovered from the step
    alpha = (g - eps)^2 / (2 c (g + eps)^2) on the updated component (None where alpha = 0)."""
    c0 = rec.config.get("c")
    if not batch_constants:
        return [finite(c0)] * rec.iterations if c0 is not None else [None] * rec.iterations
    out: list[float | None] = []
    for i in range(rec.iterations):
        g = float(np.max(np.abs(rec.grad[i])))
        lo, hi, a = g - rec.eps[i], g + rec.eps[i], rec.alpha[i]
        out.append(finite(lo * lo / (2 * a * hi * hi)) if a > 0 and hi > 0 else None)
    return out


def record_trace(rec: LearningRecord, c: Sequence[float | None] | None = None) -> dict[str, Any]:
    """A record as the page keeps a run (``st.runs[name]`` of ``static/ch5_page.js``)."""
    def col(a: Any) -> list[float | None]:
        return [finite(v) for v in np.asarray(a, dtype=float).ravel()]

    return {"batchSize": rec.batch_size.astype(int).tolist(), "alpha": col(rec.alpha), "eps": col(rec.eps),
            "Jhat": col(rec.J_hat), "grad": [col(g) for g in rec.grad], "theta": [col(t) for t in rec.theta],
            "J": col(rec.J), "c": list(c) if c is not None else [None] * rec.iterations,
            "used": int(rec.batch_size.sum()), "done": True, "diverged": bool(rec.diverged)}


def trace_summary(r: Mapping[str, Any]) -> dict[str, Any]:
    """What every run's summary holds (the page's ``safepgCh5Summary``): iterations,
    trajectories, Upsilon-bar (batch means weighted by batch size), J and theta at the end,
    how far each component of theta moved (the largest |theta_i - theta_0,i|), the improvement
    ratio on J (share of updates after which J did not fall; None without a closed-form J)."""
    n, jhat, J, theta = r["batchSize"], r["Jhat"], r["J"], r["theta"]
    I = len(n)
    tot = sum(n)
    w = sum(k * (v if v is not None else math.nan) for k, v in zip(n, jhat))
    up, has_j = 0, all(v is not None for v in J)
    for i in range(I):
        if has_j and J[i + 1] - J[i] >= 0:
            up += 1
    moved = [0.0] * len(theta[0])
    for t in theta[1:]:
        for j, v in enumerate(t):
            d = abs(v - theta[0][j]) if v is not None and theta[0][j] is not None else math.nan
            if math.isnan(d):
                moved[j] = math.nan  # NaN, as numpy's max
            elif d > moved[j]:
                moved[j] = d
    return {"iterations": I, "trajectories": tot, "upsilon_bar": finite(w / tot) if I else None,
            "improvement_ratio": up / I if I and has_j else None, "J_final": J[I], "theta_final": theta[I],
            "theta_moved": [finite(m) for m in moved], "done": bool(r["done"]), "diverged": bool(r["diverged"])}


def iteration_series(r: Mapping[str, Any], key: str, points: int, index: int | None = None,
                     per_update: bool = False) -> tuple[list[int], list[Any]]:
    """(x, y) of one per-iteration array of a trace, thinned: ``per_update`` arrays (theta, J:
    I + 1 entries) are drawn against the number of updates 0..I, the others against the
    iteration 1..I; ``index`` picks a component of a vector entry."""
    ys = r[key]
    keep = thin(len(ys), points)
    x = [k if per_update else k + 1 for k in keep]
    y = [ys[k] if index is None else ys[k][index] for k in keep]
    return x, y


def trajectory_series(r: Mapping[str, Any], key: str, points: int, shift: int = 0) -> tuple[list[int], list[Any]]:
    """(x, y) of a per-iteration array against the trajectories used by the end of each batch
    (``shift=1`` for theta or J: the value after the update that batch made)."""
    ends, tot = [], 0
    for k in r["batchSize"]:
        tot += k
        ends.append(tot)
    keep = thin(len(ends), points)
    return [ends[k] for k in keep], [r[key][k + shift] for k in keep]


def kernel_text(res: dict[str, Any]) -> dict[str, Any]:
    """A page result as the kernel twin returns it: done, and its lines joined by newlines, not <br>."""
    res["values"]["done"] = True
    res["text"] = res["text"].replace("<br>", "\n")
    return res


class Ch5LiveExplorer(Explorer):
    """An :class:`~safepg.explorers.component.Explorer` whose page runs the JavaScript
    learner in a Web Worker (see the module docstring); ``compute_js`` names the page script,
    ``presets`` are one-click buttons setting several controls (name -> (label, values)), and
    ``links`` controls that set others when they take a value (name -> ((value, {other: value}), ...)),
    in the page and in the kernel view alike."""

    continuous_update = False
    compute_reports_progress = True
    plot_width = 4.0
    page_script: str = ""
    page_object: str = ""
    presets: dict[str, tuple[str, dict[str, Any]]] = {}
    links: dict[str, tuple[tuple[Any, dict[str, Any]], ...]] = {}

    def linked(self, name: str, value: Any) -> dict[str, Any]:
        """The controls that control ``name`` sets on taking ``value``, and their values (``{}`` for none)."""
        for v, sets in self.links.get(name, ()):
            if v == value:
                return dict(sets)
        return {}

    def _presets_html(self) -> str:
        return "".join(f'<button type="button" data-preset="{html.escape(k)}" style="margin:0 0.6em 0.4em 0">'
                       f"{html.escape(label)}</button>" for k, (label, _) in self.presets.items())

    def _spec(self) -> dict[str, Any]:
        return {**super()._spec(), "presets": {k: v for k, (_, v) in self.presets.items()},
                "links": {k: [[v, sets] for v, sets in pairs] for k, pairs in self.links.items()}}

    def to_html(self) -> str:
        """The self-contained HTML + JavaScript block (learner, worker and plots inline)."""
        spec = json.dumps(self._spec(), separators=(",", ":"), allow_nan=False)
        learner = json.dumps(learner_source())
        page = static_text(self.page_script)
        uid = "safepg-" + hashlib.sha1((self.title + spec + learner + page).encode()).hexdigest()[:10]
        return (
            f'<div class="safepg-explorer safepg-live" id="{uid}" style="border:1px solid rgba(127,127,127,.4);'
            f'border-radius:6px;padding:0.8em;margin:1em 0">'
            f'<div style="font-weight:600;margin-bottom:0.4em">{html.escape(self.title)}</div>'
            f'{self._presets_html()}{self._controls_html()}'
            '<div class="safepg-status" role="status" style="font-size:0.85em;opacity:0.8;margin:0.2em 0"></div>'
            f'{self._plots_html()}<div class="safepg-text" style="font-family:monospace;font-size:0.9em;'
            'overflow-wrap:anywhere"></div><pre class="safepg-values" hidden></pre>'
            f'<script>(function(){{\n{static_text("runtime.js")}\n{static_text("live_jobs.js")}\n'
            f'{static_text("ch5_page.js")}\n{page}\n'
            f"const spec={spec};const learnerSrc={learner};"
            f'safepgCh5Live(document.getElementById("{uid}"),spec,learnerSrc,{self.page_object});}})();</script></div>'
        )

    def interactive(self) -> Any:
        """The kernel view, with the preset buttons (a click sets the controls they name) and the
        links (a control that takes a linked value sets the others, as in the page)."""
        import ipywidgets as w

        view = super().interactive()

        def follow(name: str) -> Callable[[Mapping[str, Any]], None]:
            def moved(change: Mapping[str, Any]) -> None:
                for k, v in self.linked(name, change["new"]).items():
                    view.controls[k].value = v
            return moved

        for name in self.links:
            view.controls[name].observe(follow(name), names="value")

        def press(values: Mapping[str, Any]) -> Callable[[Any], None]:
            def click(_: Any) -> None:
                for k, v in values.items():
                    view.controls[k].value = v
            return click

        buttons = []
        for label, values in self.presets.values():
            b = w.Button(description=label, layout=w.Layout(width="auto"))
            b.on_click(press(values))
            buttons.append(b)
        # compute_py's text has a line per run (kernel_text): kept as lines in the view.
        style = w.HTML("<style>.safepg-ch5 .safepg-text span{white-space:pre-wrap}</style>")
        view.add_class("safepg-ch5")
        view.children = (view.children[0], *([w.HBox(buttons)] if buttons else []), *view.children[1:], style)
        return view

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.title!r})"



def bound_control_error(control: str, delta: float) -> ErrorModel:
    """The :class:`~safepg.options.ErrorModel` of a page's bound control: ``"bernstein-er"`` is
    Bernstein's bound with the empirical range, ``"bernstein"`` with Lemma 4.3.3's."""
    bound = control.removesuffix("-er")
    if bound not in BOUNDS:  # as ErrorModel would say
        raise ValueError(f"bound must be one of {', '.join(repr(c) for c in BOUNDS)}, got {bound!r}")
    return ErrorModel(bound, delta, "empirical" if control.endswith("-er") else "lemma")

__all__ = ["BOUND_CHOICES", "CURVE_POINTS", "PAGE_ONLY", "Ch5LiveExplorer", "bound_control_error", "exp_text", "finite",
           "fixed", "iteration_series", "kernel_text", "learner_source", "record_c", "record_trace", "thin",
           "trace_summary", "trajectory_series"]
