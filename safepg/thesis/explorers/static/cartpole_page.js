// The cart-pole explorer's page object (cartpole_learner.py: adaptive_options, vanilla_options and
// cartpole_result are its Python twins, rule for rule).
function safepgCartpoleMoved(v) {
  if (v === null || v === undefined || !isFinite(v)) return "-";
  return v === 0 ? "0" : v < 1e-3 ? v.toExponential(1) : v.toFixed(4);
}
function safepgCartpoleSettings(p) {
  // cartpole_learner.settings_line.
  return "Settings: " + (p.gamma09 ? "gamma = 1 in the return, 0.9 in c" : "gamma = 0.99") +
    "; R and M_phi " + (p.batch_constants ? "measured per batch" : "the task's bounds") +
    "; " + (p.max_stats ? "largest variance and range over components" : "statistics of component k") +
    "; " + (p.unguarded ? "unguarded step" : "no step when eps >= |g_k|") +
    "; first batch " + (p.first1000 ? "1000, N_min 10" : "100, N_min 100") +
    "; " + (p.deg12 ? "12" : "41.8") + " deg; m l " +
    (p.ml005 ? "0.05 (the 1 m pole's)" : "0.1 (a consistent 2 m pole)") + ".";
}
const safepgCartpolePage = {
  configs(p, data) {
    const task = data.tasks[data.task_boxes.map(b => p[b] ? "1" : "0").join("")];
    const run = {theta0: data.starts[p.start], sigma: p.sigma, budget: +p.budget, seed: Math.round(p.seed)};
    // The methods as safepg holds them, under the page learner's names (option_names.learner_options),
    // then each ticked box's options.
    const adaptive = {...data.adaptive, ...run, delta: p.delta, stream: 0};
    for (const [box, opts] of Object.entries(data.settings)) if (p[box]) Object.assign(adaptive, opts);
    const vanilla = {...data.vanilla, ...run, stopOnDivergence: true, stream: 1};
    return {task: task, runs: [{name: "adaptive", cfg: adaptive}, {name: "vanilla", cfg: vanilla}]};
  },
  result(p, st, data) {
    const plots = {theta: {series: []}, ret: {series: []}, N: {series: []}, alpha: {series: []}, c: {series: []}};
    const values = {}, lines = [], pts = data.points;
    for (const name of ["adaptive", "vanilla"]) {
      const r = st.runs[name];
      if (!r) { values[name] = null; continue; }
      const label = name === "adaptive" ? "Algorithm 4.1" : data.vanilla_label;
      const style = {label: label, color: name === "adaptive" ? "#9467bd" : "#444444", dash: false};
      let [x, y] = safepgCh5TrajSeries(r, "Jhat", pts);
      plots.ret.series.push({...style, x: x, y: y});
      [x, y] = safepgCh5IterSeries(r, "batchSize", pts);
      plots.N.series.push({...style, x: x, y: y});
      [x, y] = safepgCh5IterSeries(r, "alpha", pts);
      plots.alpha.series.push({...style, x: x, y: y});
      const s = safepgCh5Summary(r), moved = s.theta_moved;
      const big = Math.max(0, ...moved.filter(m => m !== null));
      s.frozen = big < data.frozen;
      const as = r.alpha.filter(a => a !== null && isFinite(a)), cs = r.c.filter(c => c !== null);
      s.alpha_max = as.length ? Math.max(...as) : null;
      s.c_min = cs.length ? Math.min(...cs) : null; s.c_max = cs.length ? Math.max(...cs) : null;
      values[name] = s;
      const head = `${label}: ${s.iterations} iterations, ${s.trajectories} trajectories, mean batch return ` +
        `${safepgFixed(s.upsilon_bar, 2)}`;
      let tail;
      if (name === "adaptive") {
        const t0 = r.theta[0];
        data.theta_names.forEach((nm, j) => {
          const [tx, ty] = safepgCh5IterSeries(r, "theta", pts, j, true);
          plots.theta.series.push({label: `${nm} - ${nm}_0`, x: tx, color: data.theta_colors[j], dash: false,
                                   y: ty.map(v => v === null ? null : v - t0[j])});
        });
        // The band |change| < frozen: a frozen theta stays inside it, at a scale that shows it.
        const band = {x: [0, s.iterations], color: "#999999", dash: true};
        plots.theta.series.push({...band, label: `+/-${safepgCartpoleMoved(data.frozen)}: did not move`,
                                 y: [data.frozen, data.frozen]},
                                {...band, label: "", y: [-data.frozen, -data.frozen]});
        [x, y] = safepgCh5IterSeries(r, "c", pts);
        plots.c.series.push({...style, x: x, y: y});
        const cText = s.c_min === s.c_max ? safepgCh5Exp(s.c_min, 2)
          : `from ${safepgCh5Exp(s.c_min, 2)} to ${safepgCh5Exp(s.c_max, 2)}`;
        tail = s.frozen
          ? `theta did not move: no component changed by ${safepgCartpoleMoved(data.frozen)} or more (largest ` +
            `change ${safepgCartpoleMoved(big)}, largest step alpha ${safepgCh5Exp(s.alpha_max, 2)}, penalty ` +
            `constant c ${cText}).`
          : `theta moved: ${data.theta_names.map((nm, j) => `${nm} by ${safepgCartpoleMoved(moved[j])}`).join(", ")}` +
            ` (penalty constant c ${cText}).`;
      } else tail = `theta moved by up to ${safepgCartpoleMoved(big)}${s.diverged ? " (diverged)" : ""}.`;
      lines.push(`${head}; ${tail}`);
    }
    lines.push(safepgCartpoleSettings(p));
    return {plots: plots, values: values, text: lines.join("<br>")};
  },
};
