// The Chapter 5 live explorers' page half (safepg/thesis/explorers/ch5_live.py): the learner runs
// in a Web Worker built from an inline Blob; each run is kept as a trace; the explorer's own
// object (safepgLqg2dSteps, safepgLqg2dAdaptive, safepgCartpolePage) says which runs a setting
// makes (configs) and what to draw from the traces (result), as its Python twin does.
function safepgCh5Num(v) { return (v === null || v === undefined || !isFinite(v)) ? null : +v; }
function safepgCh5Exp(v, d) { return (v === null || v === undefined || !isFinite(v)) ? "-" : v.toExponential(d); }
function safepgCh5Summary(r) {
  // ch5_live.trace_summary.
  const n = r.batchSize, I = n.length;
  let tot = 0, w = 0, up = 0;
  const hasJ = r.J.every(v => v !== null && v !== undefined && isFinite(v));
  for (let i = 0; i < I; i++) {
    tot += n[i]; w += n[i] * (r.Jhat[i] === null ? NaN : r.Jhat[i]);
    if (hasJ && r.J[i + 1] - r.J[i] >= 0) up++;
  }
  const t0 = r.theta[0], moved = t0.map(() => 0);
  for (let i = 1; i <= I; i++)
    r.theta[i].forEach((v, j) => {
      const d = (v === null || t0[j] === null) ? NaN : Math.abs(v - t0[j]);
      if (Number.isNaN(d)) moved[j] = NaN; else if (d > moved[j]) moved[j] = d;
    });
  return {iterations: I, trajectories: tot, upsilon_bar: I ? safepgCh5Num(w / tot) : null,
          improvement_ratio: I && hasJ ? up / I : null, J_final: safepgCh5Num(r.J[I]), theta_final: r.theta[I],
          theta_moved: moved.map(safepgCh5Num), done: !!r.done, diverged: !!r.diverged};
}
function safepgCh5Linked(links, name, value) {
  // Ch5LiveExplorer.linked: the controls that control `name` sets on taking `value`.
  for (const [v, sets] of (links && links[name]) || []) if (v === value) return sets;
  return {};
}
function safepgCh5IterSeries(r, key, points, index, perUpdate) {
  // ch5_live.iteration_series.
  const ys = r[key], keep = safepgThin(ys.length, points);
  return [keep.map(k => perUpdate ? k : k + 1), keep.map(k => index === undefined || index === null ? ys[k] : ys[k][index])];
}
function safepgCh5TrajSeries(r, key, points, shift) {
  // ch5_live.trajectory_series.
  const ends = [];
  let tot = 0;
  for (const k of r.batchSize) { tot += k; ends.push(tot); }
  const keep = safepgThin(ends.length, points);
  return [keep.map(k => ends[k]), keep.map(k => r[key][k + (shift || 0)])];
}
function safepgCh5Live(root, spec, learnerSrc, page) {
  const inputs = root.querySelectorAll("[data-param]");
  if (typeof safepgA11y === "function") safepgA11y(root, inputs);  // runtime.js: names, aria-live summary
  const valuesEl = root.querySelector(".safepg-values"), statusEl = root.querySelector(".safepg-status");
  const data = spec.data;
  let job = 0, st = null, pending = false;
  const jobs = new SafepgJobs(learnerSrc, receive);  // live_jobs.js
  function params() {
    const p = {};
    inputs.forEach(inp => { p[inp.dataset.param] = safepgParam(inp); });
    return p;
  }
  function draw() {
    pending = false;
    const res = page.result(st.p, st, data);
    Object.assign(res.values, {done: st.done, worker: st.worker, elapsed_ms: st.elapsed, error: st.error});
    res.values.run_ms = {};
    res.values.kernel = {};  // per run: "webassembly" (the 2-D LQG's kernel) or "javascript"
    for (const k in st.runs) { res.values.run_ms[k] = st.runs[k].ms; res.values.kernel[k] = st.runs[k].kernel; }
    const wasm = Object.values(st.runs).some(r => r.kernel === "webassembly");
    for (const plot of spec.plots)
      safepgPlot(root.querySelector(`svg[data-plot="${plot.id}"]`), plot, res.plots[plot.id]);
    root.querySelector(".safepg-text").innerHTML = res.text;
    let used = 0;
    for (const k in st.runs) used += st.runs[k].used || 0;
    statusEl.textContent = st.error ? `error: ${st.error}` : st.done
      ? `done in ${(st.elapsed / 1000).toFixed(2)} s (${st.worker ? "Web Worker" : "page thread"}` +
        `${wasm ? ", batches in WebAssembly" : ""})`
      : `running: ${used.toLocaleString("en-US")} of ${st.total.toLocaleString("en-US")} trajectories...`;
    valuesEl.textContent = JSON.stringify({params: st.p, job: st.job, result: res});
  }
  function schedule() { if (!pending) { pending = true; setTimeout(draw, 0); } }
  function receive(msg) {
    if (!st || msg.job !== st.job) return;  // a cancelled run's late message
    if (msg.type === "error") { st.error = msg.message; st.done = true; schedule(); return; }
    for (const part of msg.parts) {
      let r = st.runs[part.name];
      if (!r) {
        const cfg = st.cfgs[part.name];
        r = st.runs[part.name] = {batchSize: [], alpha: [], eps: [], Jhat: [], grad: [], c: [],
                                  theta: [part.theta0 !== undefined ? part.theta0 : cfg.theta0],
                                  J: [part.J0 !== undefined ? safepgCh5Num(part.J0) : null]};
      }
      const n = part.batchSize.length;
      for (const k of ["batchSize", "alpha", "eps", "Jhat", "grad", "theta"]) for (const v of part[k]) r[k].push(v);
      for (let i = 0; i < n; i++) {
        r.J.push(part.J ? safepgCh5Num(part.J[i]) : null);
        r.c.push(part.c ? safepgCh5Num(part.c[i]) : null);
      }
      r.used = part.used; r.done = part.done; r.diverged = part.diverged; r.ms = part.ms; r.kernel = part.kernel;
    }
    st.elapsed = performance.now() - st.t0;
    if (msg.type === "done") st.done = true;
    schedule();
  }
  function start() {
    job += 1;
    jobs.stop();  // cancel the run in flight, also when the new settings cannot run
    const p = params();
    inputs.forEach(inp => {
      const out = root.querySelector(`[data-show="${inp.dataset.param}"]`);
      if (out) out.textContent = inp.value;
    });
    let made;
    try { made = page.configs(p, data); }
    catch (err) {  // a setting the page cannot run: said in the status line, nothing drawn
      st = {job: job, p: p, cfgs: {}, total: 0, runs: {}, done: true, elapsed: 0, t0: performance.now(),
            worker: false, error: String((err && err.message) || err)};
      draw();
      return;
    }
    const cfgs = {};
    let total = 0;
    for (const r of made.runs) { cfgs[r.name] = r.cfg; total += r.cfg.budget; }
    const msg = {job: job, task: made.task, every: 150, runs: made.runs};
    st = {job: job, p: p, cfgs: cfgs, total: total, runs: {}, done: false, elapsed: 0, t0: performance.now(),
          worker: false, error: null};
    const mine = st;
    st.worker = jobs.start(msg, () => { mine.worker = false; });
    draw();
  }
  function set(name, value) {
    const inp = root.querySelector(`[data-param="${name}"]`);
    if (!inp) return;
    if (inp.type === "checkbox") inp.checked = !!value; else inp.value = String(value);
  }
  inputs.forEach(inp => inp.addEventListener(inp.type === "checkbox" ? "change" : "input", () => {
    for (const [k, v] of Object.entries(safepgCh5Linked(spec.links, inp.dataset.param, safepgParam(inp)))) set(k, v);
    start();
  }));
  root.querySelectorAll("[data-preset]").forEach(b => b.addEventListener("click", () => {
    for (const [k, v] of Object.entries(spec.presets[b.dataset.preset])) set(k, v);
    start();  // one run for the whole preset
  }));
  start();
}
