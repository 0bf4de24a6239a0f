"""Kernel-free explorers: sliders that recompute curves in the browser.

An :class:`Explorer` renders as one self-contained ``text/html`` block (controls, an SVG
plot drawn by a few lines of our own JavaScript, no library and no CDN), so it works in
the static book with no kernel and no network, and in JupyterLab. Each explorer has a
JavaScript ``compute`` and a Python twin ``compute_py`` returning the same structure:
the JavaScript recomputes closed forms (and picks precomputed curves embedded as JSON
where a closed form is not enough), the Python twin is what the browser test compares
against, and what :meth:`Explorer.interactive` draws with ipywidgets when a kernel runs.

``compute(p, data, lib)`` returns ``{"plots": {plot_id: {"series": [...], "markers": [...]}},
"values": {...}, "text": "..."}``; a series is ``{"label", "x", "y", "color", "dash"}``.
The last result is written as JSON into a hidden ``<pre class="safepg-values">`` so
tests can read what is drawn.
"""

from __future__ import annotations

import hashlib
import html
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

#: safepg's closed forms in JavaScript, shared by every explorer (``lib`` in compute).
LIB_JS = r"""
const lib = {
  linspace(a, b, n) { const o = []; for (let i = 0; i < n; i++) o.push(a + (b - a) * i / (n - 1)); return o; },
  geomspace(a, b, n) { const o = []; for (let i = 0; i < n; i++) o.push(a * Math.pow(b / a, i / (n - 1))); return o; },
  // 1-D LQG closed form (SETTINGS.md): J = -(b^2/3) P - sigma^2 (0.5 + gamma P)/(1 - gamma)
  lqgP(theta, gamma) { return 0.5 * (1 + theta * theta) / (1 - gamma * (1 + theta) * (1 + theta)); },
  lqgJ(theta, sigma, gamma, b) {
    if (gamma * (1 + theta) * (1 + theta) >= 1) return -Infinity;
    const P = lib.lqgP(theta, gamma);
    return -(b * b / 3) * P - sigma * sigma * (0.5 + gamma * P) / (1 - gamma);
  },
  // Theorem 4.2.3
  penalty(k) {
    const g = k.gamma, s = k.sigma;
    return k.R * k.M * k.M / ((1 - g) * (1 - g) * s * s) * (k.Avol / (Math.sqrt(2 * Math.PI) * s) + g / (2 * (1 - g)));
  },
  // Section 4.3.1 variance bounds and Lemma 4.3.3
  varReinforce(k) {
    const g = k.gamma, H = k.H;
    const x = k.R * k.M * (1 - Math.pow(g, H)) / (k.sigma * (1 - g));
    return x * x * H;
  },
  varGpomdp(k) {
    const g = k.gamma, H = k.H;
    const br = (1 - Math.pow(g, 2 * H)) / (1 - g * g) + H * Math.pow(g, 2 * H)
      - 2 * Math.pow(g, H) * (1 - Math.pow(g, H)) / (1 - g);
    const x = k.R * k.M / (k.sigma * (1 - g)); return x * x * br;
  },
  rangeBound(k) { return 2 * k.H * k.M * k.Abar * k.R / (k.sigma * k.sigma * (1 - k.gamma)); },
  // Section 4.3: eps(N) = d/sqrt(N) + f/N
  chebyshev(delta, variance) { return { d: Math.sqrt(variance / delta), f: 0 }; },
  hoeffding(delta, range) { return { d: range * Math.sqrt(Math.log(2 / delta) / 2), f: 0 }; },
  bernstein(delta, S, range) { const l = Math.log(3 / delta); return { d: Math.sqrt(2 * S * l), f: 3 * range * l }; },
  eps(bd, N) { return bd.d / Math.sqrt(N) + bd.f / N; },
  // Corollary 4.2.8 and Definition 4.1
  step(g, e, c) { return e >= g ? 0 : (g - e) * (g - e) / (2 * c * (g + e) * (g + e)); },
  improvement(g, e, c) { return e >= g ? 0 : Math.pow(g - e, 4) / (4 * c * (g + e) * (g + e)); },
  upsilon(N, g, bd, c) { const e = lib.eps(bd, N); return Math.pow(g - e, 4) / (4 * c * N * (g + e) * (g + e)); },
  nZero(g, bd) { const r = (bd.d + Math.sqrt(bd.d * bd.d + 4 * bd.f * g)) / (2 * g); return r * r; },
  // Theorem 4.3.2 (f = 0) or the search of Section 4.3.3
  nStar(g, bd, c) {
    if (bd.f === 0) return Math.ceil((13 + 3 * Math.sqrt(17)) / 2 * bd.d * bd.d / (g * g));
    let n = Math.max(1, Math.ceil(lib.nZero(g, bd)));
    let u = lib.upsilon(n, g, bd, c);
    for (;;) { const v = lib.upsilon(n + 1, g, bd, c); if (v < u) return n; n += 1; u = v; }
  },
};
"""

#: The browser half: controls, SVG line plots, and the values written to the DOM.
_RUNTIME_JS = r"""
function safepgTicks(lo, hi, log) {
  // "Nice" tick values in data units: 1-2-5 steps (linear) or powers of ten (log10 axis; lo, hi are logs).
  if (log) {
    const out = [];
    for (let k = Math.floor(lo); k <= Math.ceil(hi); k++)
      for (const m of (hi - lo > 3 ? [1] : [1, 2, 5])) {
        const v = Math.log10(m) + k;
        if (v >= lo - 1e-9 && v <= hi + 1e-9) out.push(+Math.pow(10, v).toPrecision(12));
      }
    return out.length >= 2 ? out : [Math.pow(10, lo), Math.pow(10, hi)];
  }
  const raw = (hi - lo) / 5, p = Math.pow(10, Math.floor(Math.log10(raw))), r = raw / p;
  const step = (r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10) * p;
  const out = [];
  for (let i = Math.ceil(lo / step - 1e-9); i * step <= hi + 1e-9 * step; i++) out.push(+(i * step).toPrecision(12));
  return out;
}
//: Width of one tick-label character at font-size 11, in SVG units (an upper estimate).
const SAFEPG_CHAR_WIDTH = 6.5;
function safepgTickLabels(ticks, log) {
  // The shortest labels that still tell every tick apart: "1.5e7" next to "2e7" (never two
  // "2e+7"), "1500" next to "1000". Exponent form below 1e-3 and from 1e5 on; on a linear
  // axis reaching 1e5 every label takes it ("5e4", "1e5", "1.5e5", not "50000", "1e5").
  const top = Math.max(...ticks.map(Math.abs));
  const axisExp = !log && (top >= 1e5 || (top > 0 && top < 1e-3));
  for (let digits = 0; digits <= 12; digits++) {
    const labels = ticks.map(v => {
      const a = Math.abs(v);
      if (v === 0) return "0";
      if (axisExp || a >= 1e5 || a < 1e-3) {
        const [mant, exp] = v.toExponential(digits).split("e");
        return `${+mant}e${+exp}`;
      }
      return (+v.toPrecision(digits + 1)).toString();
    });
    if (new Set(labels).size === labels.length) return labels;
  }
  return ticks.map(String);
}
function safepgPlot(svg, spec, res) {
  // A small SVG line plot. Colours: series colours from safepg.thesis.plotting, everything else
  // currentColor, so the plot follows the page's light or dark theme.
  const W = 640, Hh = 320, m = {l: 62, r: 12, t: 12, b: 40};
  const NS = "http://www.w3.org/2000/svg";
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  svg.setAttribute("viewBox", `0 0 ${W} ${Hh}`);
  const tx = spec.xlog ? Math.log10 : (v => v), ty = spec.ylog ? Math.log10 : (v => v);
  const pts = [];
  const ok = (x, y) => isFinite(tx(x)) && isFinite(ty(y));
  for (const s of res.series) s.x.forEach((x, i) => { if (ok(x, s.y[i])) pts.push([tx(x), ty(s.y[i])]); });
  for (const mk of (res.markers || [])) if (ok(mk.x, mk.y)) pts.push([tx(mk.x), ty(mk.y)]);
  if (!pts.length) {  // nothing to draw for this choice: say so instead of an empty frame
    const t = document.createElementNS(NS, "text");
    for (const [k, v] of Object.entries({x: W / 2, y: Hh / 2, "text-anchor": "middle", "font-size": 13,
                                         fill: "currentColor", "fill-opacity": 0.7})) t.setAttribute(k, v);
    t.textContent = "no data for this choice";
    svg.appendChild(t);
    return;
  }
  let x0 = Math.min(...pts.map(p => p[0])), x1 = Math.max(...pts.map(p => p[0]));
  let y0 = spec.ymin != null ? ty(spec.ymin) : Math.min(...pts.map(p => p[1]));
  let y1 = spec.ymax != null ? ty(spec.ymax) : Math.max(...pts.map(p => p[1]));
  if (x1 === x0) x1 = x0 + 1; if (y1 === y0) y1 = y0 + 1;
  const pad = 0.05 * (y1 - y0); y0 -= pad; y1 += pad;
  const X = v => m.l + (tx(v) - x0) / (x1 - x0) * (W - m.l - m.r);
  const Y = v => Hh - m.b - (Math.min(Math.max(ty(v), y0), y1) - y0) / (y1 - y0) * (Hh - m.t - m.b);
  const el = (name, attrs, text) => {
    const e = document.createElementNS(NS, name);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    svg.appendChild(e);
    return e;
  };
  const ink = {fill: "currentColor"}, thin = {stroke: "currentColor", "stroke-opacity": 0.12};
  const xt = safepgTicks(x0, x1, spec.xlog), xl = safepgTickLabels(xt, spec.xlog);
  xt.forEach((xv, i) => {
    el("line", {x1: X(xv), x2: X(xv), y1: m.t, y2: Hh - m.b, ...thin});
    // A label at either end is anchored inside the plot instead of centred across its edge.
    const half = SAFEPG_CHAR_WIDTH * xl[i].length / 2;
    const anchor = X(xv) + half > W ? "end" : X(xv) - half < 0 ? "start" : "middle";
    const x = anchor === "end" ? W - 1 : anchor === "start" ? 1 : X(xv);
    el("text", {x, y: Hh - m.b + 16, "text-anchor": anchor, "font-size": 11, ...ink, class: "safepg-tick"}, xl[i]);
  });
  const yt = safepgTicks(y0, y1, spec.ylog), yl = safepgTickLabels(yt, spec.ylog);
  yt.forEach((yv, i) => {
    el("line", {x1: m.l, x2: W - m.r, y1: Y(yv), y2: Y(yv), ...thin});
    el("text", {x: m.l - 6, y: Y(yv) + 4, "text-anchor": "end", "font-size": 11, ...ink, class: "safepg-tick"}, yl[i]);
  });
  el("rect", {x: m.l, y: m.t, width: W - m.l - m.r, height: Hh - m.t - m.b, fill: "none",
              stroke: "currentColor", "stroke-opacity": 0.4});
  el("text", {x: (W + m.l) / 2, y: Hh - 6, "text-anchor": "middle", "font-size": 12, ...ink}, spec.xlabel || "");
  el("text", {x: 14, y: (Hh - m.b) / 2, "text-anchor": "middle", "font-size": 12, ...ink,
              transform: `rotate(-90 14 ${(Hh - m.b) / 2})`}, spec.ylabel || "");
  let ly = m.t + 16;
  for (const s of res.series) {
    const d = s.x.map((x, i) => [x, s.y[i]]).filter(p => isFinite(tx(p[0])) && isFinite(ty(p[1])))
      .map((p, i) => `${i ? "L" : "M"}${X(p[0]).toFixed(1)},${Y(p[1]).toFixed(1)}`).join("");
    const dash = s.dash ? "6 4" : "";
    const line = {stroke: s.color || "currentColor", "stroke-width": 2, "stroke-dasharray": dash};
    el("path", {d: d, fill: "none", ...line, class: "safepg-series"});
    if (s.label) {  // legend: label and a line sample, top right
      el("text", {x: W - m.r - 38, y: ly, "text-anchor": "end", "font-size": 11, ...ink}, s.label);
      el("line", {x1: W - m.r - 32, x2: W - m.r - 8, y1: ly - 4, y2: ly - 4, ...line});
      ly += 15;
    }
  }
  for (const mk of (res.markers || [])) {
    if (!isFinite(tx(mk.x)) || !isFinite(ty(mk.y))) continue;
    el("circle", {cx: X(mk.x), cy: Y(mk.y), r: 5, fill: mk.color || "currentColor", class: "safepg-marker"});
    if (mk.label) el("text", {x: X(mk.x) + 7, y: Y(mk.y) - 7, "font-size": 11, ...ink}, mk.label);
  }
}
function safepgExplorer(root, spec, compute, lib) {
  const inputs = root.querySelectorAll("[data-param]");
  const valuesEl = root.querySelector(".safepg-values");
  function params() {
    const p = {};
    inputs.forEach(inp => { p[inp.dataset.param] = inp.tagName === "SELECT" ? inp.value : parseFloat(inp.value); });
    return p;
  }
  function update() {
    const p = params();
    inputs.forEach(inp => {
      const out = root.querySelector(`[data-show="${inp.dataset.param}"]`);
      if (out) out.textContent = inp.value;
    });
    const res = compute(p, spec.data, lib);
    for (const plot of spec.plots)
      safepgPlot(root.querySelector(`svg[data-plot="${plot.id}"]`), plot, res.plots[plot.id]);
    root.querySelector(".safepg-text").innerHTML = res.text || "";
    valuesEl.textContent = JSON.stringify({params: p, result: res});
  }
  inputs.forEach(inp => inp.addEventListener("input", update));
  update();
}
"""


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
class Plot:
    """One SVG plot of the explorer."""

    id: str
    xlabel: str = ""
    ylabel: str = ""
    xlog: bool = False
    ylog: bool = False
    ymin: float | None = None
    ymax: float | None = None


@dataclass
class Explorer:
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
    controls: list[Slider | Select]
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
        """The sliders and selects, as labelled form elements the page's script reads."""
        style = 'style="display:inline-block;margin:0 1.2em 0.4em 0"'
        rows = []
        for c in self.controls:
            if isinstance(c, Slider):
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
            f"<script>(function(){{{LIB_JS}{_RUNTIME_JS}"
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

    def interactive(self) -> Any:
        """ipywidgets version for a live kernel: the same controls, drawn with matplotlib
        from ``compute_py``."""
        import ipywidgets as w
        import matplotlib.pyplot as plt

        kw: dict[str, Any] = {}
        for c in self.controls:
            if isinstance(c, Slider):
                kw[c.name] = w.FloatSlider(value=c.value, min=c.min, max=c.max, step=c.step, description=c.label,
                                           continuous_update=self.continuous_update)
            else:
                kw[c.name] = w.Dropdown(options=[(lbl, v) for v, lbl in c.options], value=c.value,
                                        description=c.label)

        def draw(**p: Any) -> None:
            res = self.compute_py(p)
            fig, axes = plt.subplots(1, len(self.plots), figsize=(self.plot_width * len(self.plots), 3.6),
                                     squeeze=False)
            for ax, spec in zip(axes[0], self.plots):
                r = res["plots"][spec.id]
                for s in r["series"]:
                    ax.plot(s["x"], s["y"], color=s.get("color"), linestyle="--" if s.get("dash") else "-",
                            label=s.get("label"))
                for mk in r.get("markers", []):
                    ax.plot([mk["x"]], [mk["y"]], "o", color=mk.get("color"), label=mk.get("label"))
                ax.set_xscale("log" if spec.xlog else "linear")
                ax.set_yscale("log" if spec.ylog else "linear")
                ax.set_xlabel(spec.xlabel)
                ax.set_ylabel(spec.ylabel)
                if spec.ymin is not None or spec.ymax is not None:
                    ax.set_ylim(spec.ymin, spec.ymax)
                if ax.get_legend_handles_labels()[1]:
                    ax.legend(fontsize="small")
            fig.tight_layout()
            plt.show()
            print(res.get("text", ""))

        return w.interactive(draw, **kw)


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
