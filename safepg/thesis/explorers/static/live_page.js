function safepgLiveSummary(r, tol) {
  // safepg.learning.LearningRecord's summary of a (possibly partial) record, with how far
  // theta moved (live_learner.theta_moved) and whether that is under tol (the ratio is vacuous).
  const I = r.batchSize.length;
  let tot = 0, w = 0, up = 0, moved = 0;
  for (let i = 0; i < I; i++) {
    tot += r.batchSize[i]; w += r.batchSize[i] * r.Jhat[i];
    if (r.J[i + 1] - r.J[i] >= 0) up++;
  }
  for (let i = 1; i <= I; i++) {
    const d = Math.abs(r.theta[i] - r.theta[0]);
    if (Number.isNaN(d)) { moved = NaN; break; }  // NaN, as numpy's max
    if (d > moved) moved = d;
  }
  const Jat = {};
  let end = 0, i = 0;
  for (const T of [100000, 1000000, 3000000]) {
    if (T > tot) continue;
    while (end + r.batchSize[i] < T) { end += r.batchSize[i]; i++; }
    Jat[String(T)] = r.J[i];
  }
  return {iterations: I, trajectories: tot, upsilon_bar: I ? w / tot : null, improvement_ratio: I ? up / I : null,
          J_final: r.J[I], theta_final: r.theta[I], theta_moved: moved, ratio_vacuous: I === 0 || moved < tol,
          J_at: Jat, first_batches: r.batchSize.slice(0, 3), done: r.done, diverged: r.diverged};
}
function safepgLiveLine(name, v, data) {
  // One run's summary line: live_learner.run_line, word for word.
  const m = v.theta_moved;
  const moved = !isFinite(m) ? "-" : m === 0 ? "0" : m < 1e-3 ? m.toExponential(1) : m.toFixed(4);
  const ratio = v.ratio_vacuous
    ? `theta moved by ${moved}, less than ${100 * data.still}% of the way to theta* = ` +
      `${safepgFixed(data.theta_star, 2)}: the improvement ratio carries no information`
    : `theta moved by ${moved}, improvement ratio ${safepgFixed(100 * v.improvement_ratio, 2)}%`;
  return `${name}: ${v.iterations} iterations, ${v.trajectories} trajectories, ` +
    `Upsilon-bar ${safepgFixed(v.upsilon_bar, 4)}, J ${safepgFixed(v.J_final, 3)} at theta ` +
    `${safepgFixed(v.theta_final, 4)}${v.diverged ? " (diverged)" : ""}; ${ratio}.`;
}
function safepgLiveObjectives(data) {
  // Which objective each number is on: live_learner.objectives_line.
  const t = data.task;
  return `Upsilon-bar: the simulated return (clipped states and actions, ${t.H} steps, discounted by ` +
    `gamma = ${t.gamma}), averaged over all trajectories. J and the improvement ratio (share of ` +
    "updates after which J did not fall): the closed-form J(theta) of the J plot (infinite horizon, " +
    "no clipping).";
}
function safepgLiveText(values, data, B) {
  // The lines under the plots: live_learner.summary_text (joined here with <br>).
  const lines = [];
  if (values.adaptive) lines.push(safepgLiveLine("Algorithm 4.1", values.adaptive, data));
  if (values.vanilla) lines.push(safepgLiveLine("vanilla PG", values.vanilla, data));
  lines.push(values.thesis.found
    ? `stored safepg run ${values.thesis.name} (seed mean, first ${B} trajectories): ` +
      `${values.thesis.iterations.toFixed(0)} iterations, Upsilon-bar ${safepgFixed(values.thesis.upsilon_bar, 4)}.`
    : "no stored run for these settings (Table 5.2 ran sigma = 1, baseline on, " +
      "delta in {0.05, 0.25, 0.5, 0.75, 0.95}).");
  lines.push(safepgLiveObjectives(data));
  return lines.join("<br>");
}
function safepgLiveResult(p, st, data) {
  // The same structure as compute_py: plots (series), values, text.
  const plots = {N: {series: []}, J: {series: []}, alpha: {series: []}};
  const values = {done: st.done, worker: st.worker, elapsed_ms: st.elapsed, run_ms: {}};
  const key = `${p.estimator}-${p.bound}-delta=${+p.delta}-${p.score}`;
  const run = (p.sigma === 1 && p.baseline === "on") ? data.runs[key] : undefined;
  const B = +p.budget;
  if (run) {
    const its = [], ns = [], as = [];
    for (let i = 0; i < run.iteration.length; i++) {
      if (run.start[i] === null || run.start[i] >= B) break;
      its.push(run.iteration[i]); ns.push(run.batch_size[i]); as.push(run.alpha[i]);
    }
    const gx = [], gy = [];
    for (let i = 0; i < data.grid.length && data.grid[i] <= B; i++) { gx.push(data.grid[i]); gy.push(run.J[i]); }
    const label = `stored safepg run (${run.seeds} seed${run.seeds === 1 ? "" : "s"})`;
    const thin = {color: data.muted, dash: true};
    plots.N.series.push({label: label, x: its, y: ns, ...thin});
    plots.J.series.push({label: label, x: gx, y: gy, ...thin});
    plots.alpha.series.push({label: label, x: its, y: as, ...thin});
    values.thesis = {found: true, key: key, name: run.name, ...run.budgets[String(B)]};
  } else values.thesis = {found: false, key: key};
  for (const name of ["adaptive", "vanilla"]) {
    const r = st.runs[name];
    if (!r) { values[name] = null; continue; }
    const I = r.batchSize.length;
    const style = name === "adaptive" ? {color: data.colors[p.bound], dash: p.estimator === "reinforce"}
                                      : {color: data.vanilla_color, dash: false};
    const label = name === "adaptive" ? "Algorithm 4.1 (live)"
                                      : `vanilla, N = ${p.vanilla_n}, alpha = ${p.vanilla_alpha}`;
    const keep = safepgThin(I, data.points);
    plots.N.series.push({label: label, x: keep.map(i => i + 1), y: keep.map(i => r.batchSize[i]), ...style});
    plots.alpha.series.push({label: label, x: keep.map(i => i + 1), y: keep.map(i => r.alpha[i]), ...style});
    // J of the policy that generated trajectory T (Figures 5.1-5.2), on a grid of T.
    const gx = [], gy = [];
    let end = 0, i = 0;
    for (let k = 0; k < data.points; k++) {
      const T = Math.max(1, Math.round(1 + k * (B - 1) / (data.points - 1)));
      if (T > r.used) break;
      while (i < I && end + r.batchSize[i] < T) { end += r.batchSize[i]; i++; }
      gx.push(T); gy.push(r.J[Math.min(i, I)]);
    }
    plots.J.series.push({label: label, x: gx, y: gy, ...style});
    values[name] = safepgLiveSummary(r, data.still * Math.abs(data.theta_star - r.theta[0]));
    values.run_ms[name] = r.ms;
  }
  const text = safepgLiveText(values, data, B);
  return {plots: plots, values: values, text: text};
}
function safepgLiveLearner(root, spec, learnerSrc) {
  const inputs = root.querySelectorAll("[data-param]");
  if (typeof safepgA11y === "function") safepgA11y(root, inputs);  // runtime.js: names, aria-live summary
  const valuesEl = root.querySelector(".safepg-values"), statusEl = root.querySelector(".safepg-status");
  const data = spec.data;
  let job = 0, st = null, pending = false;
  const jobs = new SafepgJobs(learnerSrc, receive);  // live_jobs.js
  function params() {
    const p = {};
    inputs.forEach(inp => { p[inp.dataset.param] = inp.tagName === "SELECT" ? inp.value : parseFloat(inp.value); });
    return p;
  }
  function configs(p) {
    // The options under safepg.options' names (options.js); the rest are their defaults.
    const common = {sigma: p.sigma, estimator: p.estimator, baseline: p.baseline === "on", scoreAction: p.score,
                    budget: +p.budget, seed: Math.round(p.seed), theta0: 0};
    const runs = [{name: "adaptive", cfg: {...common, method: "Adaptive", bound: p.bound.replace("-er", ""),
                                           delta: p.delta, range: p.bound.endsWith("-er") ? "empirical" : "lemma",
                                           stream: 0}}];
    if (p.vanilla_n !== "off")
      runs.push({name: "vanilla", cfg: {...common, method: "Vanilla", batchSize: +p.vanilla_n, step: "FixedStep",
                                        alpha: +p.vanilla_alpha, stream: 1}});
    return runs;
  }
  function draw() {
    pending = false;
    const res = safepgLiveResult(st.p, st, data);
    for (const plot of spec.plots)
      safepgPlot(root.querySelector(`svg[data-plot="${plot.id}"]`), plot, res.plots[plot.id]);
    root.querySelector(".safepg-text").innerHTML = res.text;
    const a = st.runs.adaptive;
    statusEl.textContent = st.error ? `error: ${st.error}` : st.done
      ? `done in ${(st.elapsed / 1000).toFixed(2)} s (${st.worker ? "Web Worker" : "page thread"})`
      : `running: ${a ? a.used : 0} of ${st.p.budget} trajectories...`;
    valuesEl.textContent = JSON.stringify({params: st.p, job: st.job, result: res});
  }
  function schedule() { if (!pending) { pending = true; setTimeout(draw, 0); } }
  function receive(msg) {
    if (!st || msg.job !== st.job) return;  // a cancelled run's late message
    if (msg.type === "error") { st.error = msg.message; st.done = true; schedule(); return; }
    for (const part of msg.parts) {
      let r = st.runs[part.name];
      if (!r) r = st.runs[part.name] = {batchSize: [], alpha: [], eps: [], Jhat: [], grad: [],
                                        theta: [part.theta0], J: [part.J0]};
      for (const k of ["batchSize", "alpha", "eps", "Jhat", "grad", "theta", "J"])
        for (const v of part[k]) r[k].push(v);
      r.used = part.used; r.done = part.done; r.diverged = part.diverged; r.ms = part.ms;
    }
    st.elapsed = performance.now() - st.t0;
    if (msg.type === "done") st.done = true;
    schedule();
  }
  function start() {
    job += 1;
    const p = params();
    inputs.forEach(inp => {
      const out = root.querySelector(`[data-show="${inp.dataset.param}"]`);
      if (out) out.textContent = inp.value;
    });
    const msg = {job: job, task: data.task, every: 150, runs: configs(p)};
    st = {job: job, p: p, runs: {}, done: false, elapsed: 0, t0: performance.now(), worker: false, error: null};
    const mine = st;
    st.worker = jobs.start(msg, () => { mine.worker = false; });  // cancels the run in flight
    draw();
  }
  inputs.forEach(inp => inp.addEventListener("input", start));
  start();
}
