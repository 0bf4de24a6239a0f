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
