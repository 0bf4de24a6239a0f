const k = {R: data.R, M: data.M, Avol: data.Avol, Abar: data.Abar, gamma: data.gamma, H: data.H, sigma: p.sigma};
const c = lib.penalty(k), g = p.g;
const interp = (xs, ys, x) => { let i = 1; while (i < xs.length - 1 && xs[i] < x) i++;
  const w = (x - xs[i - 1]) / (xs[i] - xs[i - 1]); return ys[i - 1] + w * (ys[i] - ys[i - 1]); };
const S = interp(data.sigmas, data.sample_var, p.sigma), er = interp(data.sigmas, data.emp_range, p.sigma);
let bd;
if (p.bound === "chebyshev-gpomdp") bd = lib.chebyshev(p.delta, lib.varGpomdp(k));
else if (p.bound === "chebyshev-reinforce") bd = lib.chebyshev(p.delta, lib.varReinforce(k));
else if (p.bound === "hoeffding") bd = lib.hoeffding(p.delta, lib.rangeBound(k));
else if (p.bound === "hoeffding-er") bd = lib.hoeffding(p.delta, er);
else if (p.bound === "bernstein") bd = lib.bernstein(p.delta, S, lib.rangeBound(k));
else bd = lib.bernstein(p.delta, S, er);
const n0 = lib.nZero(g, bd), ns = lib.nStar(g, bd, c);
const N = lib.geomspace(Math.max(1, n0), 6 * ns, data.points);
const U = N.map(n => lib.upsilon(n, g, bd, c));
const e = lib.eps(bd, ns), a = lib.step(g, e, c), imp = lib.improvement(g, e, c);
return {
  plots: {U: {series: [{label: "Upsilon(N)", x: N, y: U, color: data.accent}],
              markers: [{x: n0, y: 0, label: "N0", color: data.muted},
                        {x: ns, y: lib.upsilon(ns, g, bd, c), label: "N*", color: data.accent}]}},
  values: {c: c, d: bd.d, f: bd.f, N0: n0, Nstar: ns, alpha: a, improvement: imp},
  text: `c = ${c.toPrecision(5)}, d = ${bd.d.toPrecision(5)}, f = ${bd.f.toPrecision(5)}<br>` +
        `N0 = ${n0.toFixed(1)}, N* = ${ns}, step alpha* = ${a.toExponential(4)}, guaranteed improvement = ${imp.toExponential(4)}`,
};
