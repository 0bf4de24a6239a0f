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
  // A constant series sits in the middle of a unit range (a decade on a log axis), not on its edge.
  if (x1 === x0) x1 = x0 + 1; if (y1 === y0) { y0 -= 0.5; y1 += 0.5; }
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
  const lineOf = s => ({stroke: s.color || "currentColor", "stroke-width": 2, "stroke-dasharray": s.dash ? "6 4" : ""});
  for (const s of res.series) {
    const d = s.x.map((x, i) => [x, s.y[i]]).filter(p => isFinite(tx(p[0])) && isFinite(ty(p[1])))
      .map((p, i) => `${i ? "L" : "M"}${X(p[0]).toFixed(1)},${Y(p[1]).toFixed(1)}`).join("");
    el("path", {d: d, fill: "none", ...lineOf(s), class: "safepg-series"});
  }
  // The legend sits under the plot, not inside it, so that no entry covers a line: rows of a line
  // sample and its label, as many rows as the entries need; the drawing grows by them.
  const rows = [];
  let row = [], used = 0;
  for (const s of res.series.filter(s => s.label)) {
    const width = 30 + SAFEPG_CHAR_WIDTH * s.label.length;
    if (row.length && used + width > W - m.l - m.r) { rows.push(row); row = []; used = 0; }
    row.push([s, used]);
    used += width + 18;
  }
  if (row.length) rows.push(row);
  rows.forEach((r, i) => {
    const y = Hh + 12 + 16 * i;
    for (const [s, x] of r) {
      el("line", {x1: m.l + x, x2: m.l + x + 24, y1: y - 4, y2: y - 4, ...lineOf(s), class: "safepg-legend"});
      el("text", {x: m.l + x + 30, y: y, "font-size": 11, ...ink, class: "safepg-legend"}, s.label);
    }
  });
  if (rows.length) svg.setAttribute("viewBox", `0 0 ${W} ${Hh + 8 + 16 * rows.length}`);
  for (const mk of (res.markers || [])) {
    if (!isFinite(tx(mk.x)) || !isFinite(ty(mk.y))) continue;
    el("circle", {cx: X(mk.x), cy: Y(mk.y), r: 5, fill: mk.color || "currentColor", class: "safepg-marker"});
    if (mk.label) el("text", {x: X(mk.x) + 7, y: Y(mk.y) - 7, "font-size": 11, ...ink}, mk.label);
  }
}
function safepgParam(inp) {
  // A control's value: a checkbox's checked state (true/false), a select's string, a slider's number.
  if (inp.type === "checkbox") return inp.checked;
  return inp.tagName === "SELECT" ? inp.value : parseFloat(inp.value);
}
function safepgName(inp) {
  // Every control gets an accessible name: the <label> around it (component.py's markup), or
  // else its data-label or parameter name, so a control type added later is never nameless.
  // (ch5_page.js calls it too.)
  const labelled = inp.getAttribute("aria-label") || inp.getAttribute("aria-labelledby")
    || [...(inp.labels || [])].some(l => l.textContent.trim());
  if (!labelled) inp.setAttribute("aria-label", inp.dataset.label || inp.dataset.param);
}
function safepgA11y(root, inputs) {
  // Every control named (safepgName). A slider's shown value is hidden from assistive
  // technology: the slider announces its value itself, and its name (the label's words)
  // should not change as it moves. The numbers under the plot are read out after each move
  // (aria-live).
  inputs.forEach(safepgName);
  root.querySelectorAll("output[data-show]").forEach(o => o.setAttribute("aria-hidden", "true"));
  const text = root.querySelector(".safepg-text");
  if (text) text.setAttribute("aria-live", "polite");
}
function safepgExplorer(root, spec, compute, lib) {
  const inputs = root.querySelectorAll("[data-param]");
  safepgA11y(root, inputs);
  const valuesEl = root.querySelector(".safepg-values");
  function params() {
    const p = {};
    inputs.forEach(inp => { p[inp.dataset.param] = safepgParam(inp); });
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
