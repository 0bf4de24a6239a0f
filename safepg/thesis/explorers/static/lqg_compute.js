const th = lib.linspace(data.theta_min, data.theta_max, data.points);
const J = th.map(t => lib.lqgJ(t, p.sigma, data.gamma, data.b));
const js = lib.lqgJ(data.theta_star, p.sigma, data.gamma, data.b);
const interp = (xs, ys, x) => { let i = 1; while (i < xs.length - 1 && xs[i] < x) i++;
  const w = (x - xs[i - 1]) / (xs[i] - xs[i - 1]); return ys[i - 1] + w * (ys[i] - ys[i - 1]); };
const vr = interp(data.sigmas, data.var_reinforce, p.sigma), vg = interp(data.sigmas, data.var_gpomdp, p.sigma);
return {
  plots: {
    J: {series: [{label: "J(theta), sigma = " + p.sigma, x: th, y: J, color: data.accent}],
        markers: [{x: data.theta_star, y: js, label: "theta*", color: data.accent}]},
    var: {series: [{label: "REINFORCE", x: data.sigmas, y: data.var_reinforce, color: data.c_rf, dash: true},
                   {label: "G(PO)MDP", x: data.sigmas, y: data.var_gpomdp, color: data.c_gp}],
          markers: [{x: p.sigma, y: vr, color: data.c_rf}, {x: p.sigma, y: vg, color: data.c_gp}]},
  },
  values: {J_star: js, var_reinforce: vr, var_gpomdp: vg},
  text: `J(theta*) = ${js.toFixed(3)} at theta* = ${data.theta_star.toFixed(4)}; per-trajectory variance at theta = ${data.theta_var}: REINFORCE ${vr.toFixed(1)}, G(PO)MDP ${vg.toFixed(1)}`,
};
