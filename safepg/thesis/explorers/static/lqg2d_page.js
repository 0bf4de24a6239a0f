// The 2-D LQG explorers' page objects (lqg2d_learner.py: steps_configs/steps_result and
// adaptive_configs/adaptive_result are their Python twins, rule for rule).
function safepgLqg2dBound(p) { return [p.bound.replace("-er", ""), p.bound.endsWith("-er")]; }
// The options under safepg.options' names (options.js); the rest are their defaults.
function safepgLqg2dCommon(p, data) {
  return {theta0: data.theta0, sigma: p.sigma, estimator: "gpomdp", baseline: true, scoreAction: "clipped",
          budget: +p.budget, seed: Math.round(p.seed)};
}
function safepgLqg2dError(p) {
  const [bound, er] = safepgLqg2dBound(p);
  return {bound: bound, range: er ? "empirical" : "lemma", delta: p.delta};
}
function safepgLqg2dTaskCheck(data) {
  if (data.task.missing) throw new Error(`the JavaScript engine for the 2-D LQG is missing (${data.task.missing})`);
}
const safepgLqg2dSteps = {
  configs(p, data) {
    safepgLqg2dTaskCheck(data);
    const runs = ["scalar", "coordinate"].map((step, k) => ({name: step, cfg: {
      ...safepgLqg2dCommon(p, data), ...safepgLqg2dError(p), method: "Vanilla", batchSize: +p.n, step: "SafeStep",
      kind: step, stopOnDivergence: true, stream: k}}));
    return {task: data.task, runs: runs};
  },
  result(p, st, data) {
    const plots = {theta: {series: []}, J: {series: []}}, values = {}, lines = [];
    const labels = {scalar: "scalar step (Pirotta et al. 2013)", coordinate: "coordinate step"};
    for (const step of ["scalar", "coordinate"]) {
      const r = st.runs[step];
      if (!r) { values[step] = null; continue; }
      const label = labels[step];
      data.theta_index.forEach((idx, j) => {
        const [x, y] = safepgCh5IterSeries(r, "theta", data.points, idx, true);
        plots.theta.series.push({label: `${label}: ${data.theta_names[j]}`, x: x, y: y, color: data.colors[step],
                                 dash: j === 1});
      });
      const [x, y] = safepgCh5IterSeries(r, "J", data.points, null, true);
      plots.J.series.push({label: label, x: x, y: y, color: data.colors[step], dash: false});
      const s = values[step] = safepgCh5Summary(r), th = s.theta_final;
      const ratio = s.improvement_ratio === null ? null : 100 * s.improvement_ratio;
      lines.push(`${label}: ${s.iterations} iterations, ${s.trajectories} trajectories, J ` +
        `${safepgFixed(s.J_final, 3)} at theta_11 ${safepgFixed(th[data.theta_index[0]], 6)}, theta_22 ` +
        `${safepgFixed(th[data.theta_index[1]], 6)}${s.diverged ? " (diverged)" : ""}; improvement ` +
        `ratio ${safepgFixed(ratio, 2)}%.`);
    }
    lines.push(data.printed);
    return {plots: plots, values: values, text: lines.join("<br>")};
  },
};
const safepgLqg2dAdaptive = {
  configs(p, data) {
    safepgLqg2dTaskCheck(data);
    const common = safepgLqg2dCommon(p, data);
    const adaptive = {...common, ...safepgLqg2dError(p), method: "Adaptive", nMin: 100, nMax: +p.n_max, stream: 0};
    if (p.authors) Object.assign(adaptive, data.authors);  // maxima, unguardedStep, first
    const runs = [{name: "adaptive", cfg: adaptive}];
    for (const [name, n] of [["N=1000", 1000], ["N=100", 100]])
      runs.push({name: name, cfg: {...common, method: "Vanilla", batchSize: n, step: "FixedStep", alpha: 1e-6,
                                   kind: "scalar", stopOnDivergence: true, stream: runs.length}});
    return {task: data.task, runs: runs};
  },
  result(p, st, data) {
    const plots = {J: {series: []}, N: {series: []}}, values = {}, lines = [];
    for (const [name, color] of data.runs) {
      const r = st.runs[name];
      if (!r) { values[name] = null; continue; }
      const label = name === "adaptive" ? "Algorithm 4.1" + (p.authors ? " (authors' settings)" : "")
                                        : `fixed ${name}, alpha = 1e-6`;
      const [x, y] = safepgCh5TrajSeries(r, "J", data.points, 1);
      plots.J.series.push({label: label, color: color, dash: false, x: [0, ...x], y: [r.J[0], ...y]});
      const [xn, yn] = safepgCh5IterSeries(r, "batchSize", data.points);
      plots.N.series.push({label: label, color: color, dash: false, x: xn, y: yn});
      const s = values[name] = safepgCh5Summary(r);
      const ratio = s.improvement_ratio === null ? null : 100 * s.improvement_ratio;
      lines.push(`${label}: ${s.iterations} iterations, ${s.trajectories} trajectories, Upsilon-bar ` +
        `${safepgFixed(s.upsilon_bar, 2)}, J ${safepgFixed(s.J_final, 3)}` +
        `${s.diverged ? " (diverged)" : ""}; improvement ratio ${safepgFixed(ratio, 2)}%.`);
    }
    lines.push(data.printed);
    return {plots: plots, values: values, text: lines.join("<br>")};
  },
};
