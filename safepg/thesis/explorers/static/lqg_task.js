/*
 * The LQG of safepg.envs.lqg in any dimension m for the page's learner (Sections 5.1-5.2):
 * the closed-form J(theta) and gradient of the infinite-horizon, unclipped problem, and the
 * clipped H-step simulator with REINFORCE / G(PO)MDP gradient samples and the
 * variance-minimising baselines per component (safepg.envs._lqg_kernel.lqg_gradient_samples).
 *
 * Concatenated after learner.js (it extends safepgLearner). The policy is N(K s, sigma^2 I)
 * with K = theta as a row-major m x m gain. Sums are formed in the generic kernel's order,
 * so that fed the same random numbers the samples agree with safepg to rounding.
 */
"use strict";
(function (L) {
  const check = L.check;  // learner.js's: one argument check for every file of the learner
  function asMatrix(x, m, name) {
    if (typeof x === "number") {
      const out = new Float64Array(m * m);
      for (let i = 0; i < m; i++) out[i * m + i] = x;
      return out;
    }
    const flat = [].concat(...x.map(r => (Array.isArray(r) ? r : [r])));
    check(flat.length === m * m && flat.every(Number.isFinite), `${name} must be a number or an ${m} x ${m} matrix`);
    return Float64Array.from(flat);
  }
  function largestDiagonal(M, m) {
    let off = false, top = -Infinity;
    for (let i = 0; i < m; i++) for (let j = 0; j < m; j++) {
      if (i === j) top = Math.max(top, M[i * m + i]); else if (M[i * m + j] !== 0) off = true;
    }
    return off ? null : top;
  }
  /**
   * A TASK for the Driver from safepg's LQG fields (camelCase): {dim, gamma, H, stateBound,
   * actionBound, A, B, Q, R, clip}, defaults those of LQG(). The bound constants
   * (rewardBound, featureBound, actionVolume) are derived as safepg's properties unless given
   * (a cost matrix that is not diagonal needs its largest eigenvalue: pass rewardBound).
   */
  function lqgTask(settings) {
    const s = Object.assign({dim: 1, gamma: 0.9, H: 20, stateBound: 2, actionBound: 2, A: 1, B: 1, Q: 1, R: 1,
                             clip: true}, settings || {});
    check(Number.isInteger(s.dim) && s.dim >= 1, `dim must be a positive integer, got ${s.dim}`);
    check(s.gamma > 0 && s.gamma < 1, `gamma must be in (0, 1), got ${s.gamma}`);
    check(Number.isInteger(s.H) && s.H >= 1, `H must be a positive integer, got ${s.H}`);
    check(s.stateBound > 0 && isFinite(s.stateBound), `stateBound must be finite and > 0, got ${s.stateBound}`);
    check(s.actionBound > 0 && isFinite(s.actionBound), `actionBound must be finite and > 0, got ${s.actionBound}`);
    const m = s.dim, mats = {};
    for (const k of ["A", "B", "Q", "R"]) mats[k] = Array.from(asMatrix(s[k], m, k));
    let rb = s.rewardBound;
    if (rb == null) {
      const q = largestDiagonal(Float64Array.from(mats.Q), m), r = largestDiagonal(Float64Array.from(mats.R), m);
      check(q !== null && r !== null, "rewardBound must be given for a cost matrix that is not diagonal");
      rb = 0.5 * (q * m * (s.stateBound * s.stateBound) + r * m * (s.actionBound * s.actionBound));
    }
    return {kind: "lqg", dim: m, gamma: s.gamma, H: s.H, stateBound: s.stateBound, actionBound: s.actionBound,
            A: mats.A, B: mats.B, Q: mats.Q, R: mats.R, clip: s.clip !== false, rewardBound: rb,
            featureBound: s.featureBound != null ? s.featureBound : s.stateBound,
            actionVolume: s.actionVolume != null ? s.actionVolume : Math.pow(2 * s.actionBound, m)};
  }
  /** LQG.thesis_2d(): Section 5.2.1 as printed (gamma = 0.95); the experiments run gamma = 0.9. */
  const THESIS_2D = lqgTask({dim: 2, gamma: 0.95, H: 20});

  // ----------------------------------------------------------------- linear algebra
  function matmul(X, Y, m) {
    const out = new Float64Array(m * m);
    for (let i = 0; i < m; i++) for (let j = 0; j < m; j++) {
      let acc = 0.0;
      for (let k = 0; k < m; k++) acc += X[i * m + k] * Y[k * m + j];
      out[i * m + j] = acc;
    }
    return out;
  }
  function transpose(X, m) {
    const out = new Float64Array(m * m);
    for (let i = 0; i < m; i++) for (let j = 0; j < m; j++) out[j * m + i] = X[i * m + j];
    return out;
  }
  /** Solve M x = b (M n x n, row-major) by Gaussian elimination with partial pivoting. */
  function solve(M, b, n) {
    const a = Float64Array.from(M), x = Float64Array.from(b);
    for (let c = 0; c < n; c++) {
      let p = c;
      for (let r = c + 1; r < n; r++) if (Math.abs(a[r * n + c]) > Math.abs(a[p * n + c])) p = r;
      if (p !== c) {
        for (let k = 0; k < n; k++) { const t = a[c * n + k]; a[c * n + k] = a[p * n + k]; a[p * n + k] = t; }
        const t = x[c]; x[c] = x[p]; x[p] = t;
      }
      for (let r = c + 1; r < n; r++) {
        const f = a[r * n + c] / a[c * n + c];
        if (f === 0) continue;
        for (let k = c; k < n; k++) a[r * n + k] -= f * a[c * n + k];
        x[r] -= f * x[c];
      }
    }
    for (let r = n - 1; r >= 0; r--) {
      let acc = x[r];
      for (let k = r + 1; k < n; k++) acc -= a[r * n + k] * x[k];
      x[r] = acc / a[r * n + r];
    }
    return x;
  }
  /** P = M + gamma F^T P F, symmetrised (LQG._lyapunov). */
  function lyapunov(F, M, gamma, m) {
    const d2 = m * m, sys = new Float64Array(d2 * d2);
    for (let i = 0; i < m; i++) for (let j = 0; j < m; j++) for (let k = 0; k < m; k++) for (let l = 0; l < m; l++) {
      // vec(F^T P F)[i m + j] = sum_{k,l} F[k,i] F[l,j] P[k,l]
      sys[(i * m + j) * d2 + k * m + l] = (i * m + j === k * m + l ? 1 : 0) - gamma * F[k * m + i] * F[l * m + j];
    }
    const P = solve(sys, M, d2), out = new Float64Array(d2);
    for (let i = 0; i < m; i++) for (let j = 0; j < m; j++) out[i * m + j] = 0.5 * (P[i * m + j] + P[j * m + i]);
    return out;
  }
  /** Whether sqrt(gamma) (A + B K) has spectral radius < 1. */
  function stable(F, gamma, m) {
    if (m === 1) return Math.abs(F[0]) * Math.sqrt(gamma) < 1;
    if (m === 2) {
      const tr = F[0] + F[3], det = F[0] * F[3] - F[1] * F[2], disc = tr * tr / 4 - det;
      const radius = disc >= 0 ? Math.abs(tr / 2) + Math.sqrt(disc) : Math.sqrt(det);
      return radius * Math.sqrt(gamma) < 1;
    }
    // Larger m: (sqrt(gamma) F)^(2^k) shrinks to 0 exactly when the radius is below 1.
    let G = Float64Array.from(F, v => v * Math.sqrt(gamma));
    for (let k = 0; k < 60; k++) {
      let norm = 0;
      for (const v of G) norm = Math.max(norm, Math.abs(v));
      if (!(norm < 1e150)) return false;
      if (norm < 1e-150) return true;
      G = matmul(G, G, m);
    }
    return false;
  }
  function closedLoop(theta, task) {
    const m = task.dim, K = Float64Array.from(theta);
    check(K.length === m * m, `theta must have ${m * m} entries, got ${K.length}`);
    const BK = matmul(Float64Array.from(task.B), K, m), F = new Float64Array(m * m);
    for (let i = 0; i < m * m; i++) F[i] = task.A[i] + BK[i];
    return {K, F};
  }
  function valueMatrix(K, F, task) {
    const m = task.dim, KtR = matmul(transpose(K, m), Float64Array.from(task.R), m), KtRK = matmul(KtR, K, m);
    const M = new Float64Array(m * m);
    for (let i = 0; i < m * m; i++) M[i] = 0.5 * (task.Q[i] + KtRK[i]);
    return lyapunov(F, M, task.gamma, m);
  }
  function trace(X, m) { let t = 0; for (let i = 0; i < m; i++) t += X[i * m + i]; return t; }
  /** LQG.performance: J(theta) of the infinite-horizon, unclipped problem; -Infinity if unstable. */
  function lqgPerformanceN(theta, sigma, task) {
    const m = task.dim, {K, F} = closedLoop(theta, task);
    if (!stable(F, task.gamma, m)) return -Infinity;
    const P = valueMatrix(K, F, task), S = sigma * sigma, B = Float64Array.from(task.B);
    const BtPB = matmul(matmul(transpose(B, m), P, m), B, m);
    const noise = 0.5 * trace(task.R, m) * S + task.gamma * (trace(BtPB, m) * S);
    return -(trace(P, m) * (task.stateBound * task.stateBound / 3)) - noise / (1 - task.gamma);
  }
  /** LQG.gradient: -(R K + 2 gamma B^T P F) Y with Y = W + gamma F Y F^T, flattened like theta. */
  function lqgGradientN(theta, sigma, task) {
    const m = task.dim, {K, F} = closedLoop(theta, task);
    check(stable(F, task.gamma, m), "theta makes the closed loop unstable");
    const P = valueMatrix(K, F, task), B = Float64Array.from(task.B), R = Float64Array.from(task.R);
    const BBt = matmul(B, transpose(B, m), m), W = new Float64Array(m * m), S = sigma * sigma, g = task.gamma;
    for (let i = 0; i < m * m; i++) W[i] = g * (BBt[i] * S) / (1 - g);
    for (let i = 0; i < m; i++) W[i * m + i] += task.stateBound * task.stateBound / 3;
    const Y = lyapunov(transpose(F, m), W, g, m);
    const RK = matmul(R, K, m), BtPF = matmul(matmul(transpose(B, m), P, m), F, m), X = new Float64Array(m * m);
    for (let i = 0; i < m * m; i++) X[i] = RK[i] + 2 * g * BtPF[i];
    return Array.from(matmul(X, Y, m), v => -v);
  }

  // ------------------------------------------------------------------ the simulator
  /**
   * Workspace of the vector LQG's batches, rows of length cap (component-major, so each
   * gradient component's samples are one contiguous row for the bounds).
   */
  /**
   * REINFORCE's gradient samples from the scores' sums G (M rows of n) and the returns, with the
   * variance-minimising baseline of each component when `baseline` (b_p = sum G^2 R / sum G^2).
   */
  function reinforceSamples(G, returns, samples, n, M, baseline) {
    for (let p = 0; p < M; p++) {
      const o = p * n;
      let nb = 0.0, db = 0.0;
      for (let j = 0; j < n; j++) {
        const g = G[o + j], sq = g * g;
        nb += sq * returns[j]; db += sq;
        samples[o + j] = g * returns[j];
      }
      if (baseline) {
        const bp = db !== 0 ? nb / db : 0;
        for (let j = 0; j < n; j++) samples[o + j] -= G[o + j] * bp;
      }
    }
  }
  function LqgBatch(task) {
    this.task = task; this.m = task.dim; this.M = task.dim * task.dim; this.cap = 0;
    this.num = new Float64Array(task.H * this.M); this.den = new Float64Array(task.H * this.M);
    this.b = new Float64Array(task.H * this.M);
    this.mean = new Float64Array(this.m); this.araw = new Float64Array(this.m); this.u = new Float64Array(this.m);
    this.diff = new Float64Array(this.m); this.snext = new Float64Array(this.m);
  }
  LqgBatch.prototype.grow = function (n) {
    if (n <= this.cap) return;
    const cap = Math.max(n, Math.ceil(this.cap * 1.5)), m = this.m, M = this.M;
    this.s = new Float64Array(m * cap); this.z = new Float64Array(m * cap); this.G = new Float64Array(M * cap);
    this.samples = new Float64Array(M * cap); this.acc = new Float64Array(M * cap);
    this.returns = new Float64Array(cap); this.idx = new Int32Array(cap); this.scratch = new Float64Array(cap);
    for (let i = 0; i < cap; i++) this.idx[i] = i;
    this.cap = cap;
  };
  /**
   * n gradient samples (this.samples, component p of trajectory j at p * n + j) and discounted
   * returns (this.returns) with gain theta. src.init(s, n, m, lo, hi) fills the initial states
   * (s[i * n + j] uniform in [lo, hi)); src.step(z, n, m, t, idx) the step's standard normals.
   * Returns, with opt.batchConstants, the batch's [max |r_t|, max |s_i|] over its steps
   * (what safepg.learning measures on a simulated batch), else null.
   */
  LqgBatch.prototype.run = function (theta, sigma, n, opt, src) {
    this.kernel = "javascript";  // which code computed the last batch (run2 may say "webassembly")
    if (this.m === 1) return this.run1(theta, sigma, n, opt, src);
    if (this.m === 2) return this.run2(theta, sigma, n, opt, src);
    return this.runM(theta, sigma, n, opt, src);
  };
  /** run() in any dimension: the generic loop that run1 and run2 unroll (the tests compare them). */
  LqgBatch.prototype.runM = function (theta, sigma, n, opt, src) {
    const task = this.task, m = this.m, M = this.M, H = task.H, gamma = task.gamma;
    const bs = task.stateBound, ba = task.actionBound, clip = task.clip !== false;
    const A = task.A, B = task.B, Q = task.Q, R = task.R;
    const reinforce = opt.estimator === "reinforce", baseline = !!opt.baseline, scoreClipped = opt.scoreAction !== "raw";
    this.grow(n);
    const s = this.s, z = this.z, G = this.G, samples = this.samples, acc = this.acc, returns = this.returns;
    const num = this.num, den = this.den, b = this.b;
    const mean = this.mean, araw = this.araw, u = this.u, diff = this.diff, snext = this.snext;
    const invVar = 1.0 / (sigma * sigma);  // the precision of sigma^2 I
    src.init(s, n, m, -bs, bs);
    G.fill(0, 0, M * n); samples.fill(0, 0, M * n); acc.fill(0, 0, M * n); returns.fill(0, 0, n);
    num.fill(0); den.fill(0);
    let disc = 1.0, rmax = 0, fmax = 0;
    const maxima = opt.batchConstants;
    for (let t = 0; t < H; t++) {
      src.step(z, n, m, t, this.idx);
      const to = t * M;
      for (let j = 0; j < n; j++) {
        for (let i = 0; i < m; i++) {
          let a = 0.0;
          for (let k = 0; k < m; k++) a += theta[i * m + k] * s[k * n + j];
          mean[i] = a;
          araw[i] = a + sigma * z[i * n + j];
          u[i] = clip ? Math.min(Math.max(araw[i], -ba), ba) : araw[i];
        }
        let cost = 0.0;
        for (let i = 0; i < m; i++) {
          const si = s[i * n + j], ui = u[i];
          for (let k = 0; k < m; k++) cost += si * Q[i * m + k] * s[k * n + j] + ui * R[i * m + k] * u[k];
        }
        const dr = -0.5 * cost * disc;
        returns[j] += dr;
        if (maxima) {
          rmax = Math.max(rmax, Math.abs(-0.5 * cost));
          for (let i = 0; i < m; i++) fmax = Math.max(fmax, Math.abs(s[i * n + j]));
        }
        for (let i = 0; i < m; i++) diff[i] = invVar * ((scoreClipped ? u[i] : araw[i]) - mean[i]);
        for (let i = 0; i < m; i++) for (let k = 0; k < m; k++) {
          const p = i * m + k, o = p * n + j;
          const g = G[o] + diff[i] * s[k * n + j];  // the score of Section 2.3.13, summed over steps <= t
          G[o] = g;
          if (!reinforce) { samples[o] += g * dr; num[to + p] += g * g * dr; den[to + p] += g * g; }
        }
        for (let i = 0; i < m; i++) {
          let a = 0.0;
          for (let k = 0; k < m; k++) a += A[i * m + k] * s[k * n + j] + B[i * m + k] * u[k];
          snext[i] = clip ? Math.min(Math.max(a, -bs), bs) : a;
        }
        for (let i = 0; i < m; i++) s[i * n + j] = snext[i];
      }
      if (!reinforce && baseline) {
        // b_t is known once every trajectory has made step t: the baseline term of pass 2 in t order.
        for (let p = 0; p < M; p++) {
          const bt = den[to + p] !== 0 ? num[to + p] / den[to + p] : 0, o = p * n;
          b[to + p] = bt;
          for (let j = 0; j < n; j++) acc[o + j] += G[o + j] * bt;
        }
      }
      disc *= gamma;
    }
    if (reinforce) {
      reinforceSamples(G, returns, samples, n, M, baseline);
    } else if (baseline) {
      for (let i = 0; i < M * n; i++) samples[i] -= acc[i];
    }
    return maxima ? [rmax, fmax] : null;
  };

  /**
   * run() for m = 1 (the LQG of Section 5.1): the generic loop's operations in the generic loop's
   * order, so the same bits, but one trajectory at a time with its state in locals (several times
   * faster). Each sum over trajectories still runs in trajectory order, and each sum over steps in
   * step order, as there. The step normals are drawn first, step by step as runM draws them, into
   * an (H, n) array whose cells then keep each trajectory's score for the baseline.
   */
  LqgBatch.prototype.run1 = function (theta, sigma, n, opt, src) {
    const task = this.task, H = task.H, gamma = task.gamma;
    const bs = task.stateBound, ba = task.actionBound, clip = task.clip !== false;
    const A = task.A[0], B = task.B[0], Q = task.Q[0], R = task.R[0], th = theta[0];
    const reinforce = opt.estimator === "reinforce", baseline = !!opt.baseline, scoreClipped = opt.scoreAction !== "raw";
    this.grow(n);
    if (!this.zh || this.zh.length < H * n) this.zh = new Float64Array(H * this.cap);
    const s = this.s, zh = this.zh, samples = this.samples, returns = this.returns, G = this.G;
    const num = this.num, den = this.den, b = this.b;
    const invVar = 1.0 / (sigma * sigma);
    src.init(s, n, 1, -bs, bs);
    for (let t = 0; t < H; t++) src.step(zh.subarray(t * n, t * n + n), n, 1, t, this.idx);
    num.fill(0); den.fill(0);
    const maxima = opt.batchConstants;
    let rmax = 0, fmax = 0;
    for (let j = 0; j < n; j++) {
      let sj = s[j], g = 0.0, sample = 0.0, ret = 0.0, disc = 1.0;
      for (let t = 0, o = j; t < H; t++, o += n) {
        const mean = 0.0 + th * sj;
        const araw = mean + sigma * zh[o];
        const u = clip ? Math.min(Math.max(araw, -ba), ba) : araw;
        const cost = 0.0 + (sj * Q * sj + u * R * u);
        const dr = -0.5 * cost * disc;
        ret += dr;
        if (maxima) {
          rmax = Math.max(rmax, Math.abs(-0.5 * cost));
          fmax = Math.max(fmax, Math.abs(sj));
        }
        g = g + invVar * ((scoreClipped ? u : araw) - mean) * sj;
        if (!reinforce) { sample += g * dr; num[t] += g * g * dr; den[t] += g * g; zh[o] = g; }
        const next = 0.0 + (A * sj + B * u);
        sj = clip ? Math.min(Math.max(next, -bs), bs) : next;
        disc *= gamma;
      }
      returns[j] = ret; G[j] = g; samples[j] = sample;
    }
    if (reinforce) {
      reinforceSamples(G, returns, samples, n, 1, baseline);
    } else if (baseline) {
      for (let t = 0; t < H; t++) b[t] = den[t] !== 0 ? num[t] / den[t] : 0;
      for (let j = 0; j < n; j++) {
        let acc = 0.0;
        for (let t = 0, o = j; t < H; t++, o += n) acc += zh[o] * b[t];
        samples[j] -= acc;
      }
    }
    return maxima ? [rmax, fmax] : null;
  };

  /**
   * run() for m = 2 with the 2 x 2 algebra unrolled (the 2-D kernel of safepg): the same sums
   * in the same order as the generic loop, so the same bits, about three times faster. The
   * figures' case goes to the WebAssembly kernel of lqg2d_wasm.js when the run draws its own
   * numbers (the same bits again), else to run2gb.
   */
  LqgBatch.prototype.run2 = function (theta, sigma, n, opt, src) {
    if (opt.estimator !== "reinforce" && opt.baseline && opt.scoreAction !== "raw" && this.task.clip !== false) {
      const found = L.lqg2dWasm ? L.lqg2dWasm.run(this, theta, sigma, n, opt, src) : undefined;
      if (found === undefined) return this.run2gb(theta, sigma, n, opt, src);
      this.kernel = "webassembly";
      return found;
    }
    const task = this.task, H = task.H, gamma = task.gamma;
    const bs = task.stateBound, ba = task.actionBound, clip = task.clip !== false;
    const reinforce = opt.estimator === "reinforce", baseline = !!opt.baseline, scoreClipped = opt.scoreAction !== "raw";
    this.grow(n);
    const s = this.s, z = this.z, G = this.G, samples = this.samples, acc = this.acc, returns = this.returns;
    const [k00, k01, k10, k11] = theta, [a00, a01, a10, a11] = task.A, [b00, b01, b10, b11] = task.B;
    const [q00, q01, q10, q11] = task.Q, [r00, r01, r10, r11] = task.R;
    const iv = 1.0 / (sigma * sigma), n2 = 2 * n, n3 = 3 * n;
    src.init(s, n, 2, -bs, bs);
    G.fill(0, 0, 4 * n); samples.fill(0, 0, 4 * n); acc.fill(0, 0, 4 * n); returns.fill(0, 0, n);
    let disc = 1.0, rmax = 0, fmax = 0;
    const maxima = opt.batchConstants;
    // The baseline term of step t - 1 (b of the previous step, 0 at t = 0) joins step t's pass over
    // the batch: the same terms added in the same order as a pass of their own, one pass fewer.
    const gb = !reinforce && baseline;
    let b0 = 0, b1 = 0, b2 = 0, b3 = 0;
    for (let t = 0; t < H; t++) {
      src.step(z, n, 2, t, this.idx);
      let n0 = 0, n1 = 0, nn2 = 0, nn3 = 0, d0 = 0, d1 = 0, d2 = 0, d3 = 0;
      for (let j = 0; j < n; j++) {
        const x0 = s[j], x1 = s[n + j];
        const h0 = G[j], h1 = G[n + j], h2 = G[n2 + j], h3 = G[n3 + j];
        if (gb && t > 0) {
          acc[j] += h0 * b0; acc[n + j] += h1 * b1; acc[n2 + j] += h2 * b2; acc[n3 + j] += h3 * b3;
        }
        const m0 = 0.0 + k00 * x0 + k01 * x1, m1 = 0.0 + k10 * x0 + k11 * x1;
        const a0 = m0 + sigma * z[j], a1 = m1 + sigma * z[n + j];
        const u0 = clip ? Math.min(Math.max(a0, -ba), ba) : a0, u1 = clip ? Math.min(Math.max(a1, -ba), ba) : a1;
        let cost = 0.0 + (x0 * q00 * x0 + u0 * r00 * u0);
        cost += x0 * q01 * x1 + u0 * r01 * u1;
        cost += x1 * q10 * x0 + u1 * r10 * u0;
        cost += x1 * q11 * x1 + u1 * r11 * u1;
        const dr = -0.5 * cost * disc;
        returns[j] += dr;
        if (maxima) rmax = Math.max(rmax, Math.abs(-0.5 * cost), 0), fmax = Math.max(fmax, Math.abs(x0), Math.abs(x1));
        const e0 = iv * ((scoreClipped ? u0 : a0) - m0), e1 = iv * ((scoreClipped ? u1 : a1) - m1);
        const g0 = h0 + e0 * x0, g1 = h1 + e0 * x1, g2 = h2 + e1 * x0, g3 = h3 + e1 * x1;
        G[j] = g0; G[n + j] = g1; G[n2 + j] = g2; G[n3 + j] = g3;
        if (!reinforce) {
          samples[j] += g0 * dr; samples[n + j] += g1 * dr; samples[n2 + j] += g2 * dr; samples[n3 + j] += g3 * dr;
          n0 += g0 * g0 * dr; n1 += g1 * g1 * dr; nn2 += g2 * g2 * dr; nn3 += g3 * g3 * dr;
          d0 += g0 * g0; d1 += g1 * g1; d2 += g2 * g2; d3 += g3 * g3;
        }
        const y0 = 0.0 + (a00 * x0 + b00 * u0) + (a01 * x1 + b01 * u1);
        const y1 = 0.0 + (a10 * x0 + b10 * u0) + (a11 * x1 + b11 * u1);
        s[j] = clip ? Math.min(Math.max(y0, -bs), bs) : y0;
        s[n + j] = clip ? Math.min(Math.max(y1, -bs), bs) : y1;
      }
      if (gb) {
        b0 = d0 !== 0 ? n0 / d0 : 0; b1 = d1 !== 0 ? n1 / d1 : 0;
        b2 = d2 !== 0 ? nn2 / d2 : 0; b3 = d3 !== 0 ? nn3 / d3 : 0;
      }
      disc *= gamma;
    }
    if (gb) {
      for (let j = 0; j < n; j++) {
        acc[j] += G[j] * b0; acc[n + j] += G[n + j] * b1; acc[n2 + j] += G[n2 + j] * b2; acc[n3 + j] += G[n3 + j] * b3;
      }
    }
    if (reinforce) {
      reinforceSamples(G, returns, samples, n, 4, baseline);
    } else if (baseline) {
      for (let i = 0; i < 4 * n; i++) samples[i] -= acc[i];
    }
    return maxima ? [rmax, fmax] : null;
  };

  /**
   * The 2-D batch's 24 constants into cf, in the order run2gb and the WebAssembly kernel (its
   * io.cf) read them: theta, A, B, Q, R (row-major 2 x 2 each), stateBound, actionBound, sigma, gamma.
   */
  LqgBatch.prototype.constants2 = function (theta, sigma, cf) {
    const task = this.task;
    for (let i = 0; i < 4; i++) {
      cf[i] = theta[i]; cf[4 + i] = task.A[i]; cf[8 + i] = task.B[i]; cf[12 + i] = task.Q[i]; cf[16 + i] = task.R[i];
    }
    cf[20] = task.stateBound; cf[21] = task.actionBound; cf[22] = sigma; cf[23] = task.gamma;
    return cf;
  };

  /**
   * run2 for G(PO)MDP with baselines, clipped task, clipped-action score (the figures' runs):
   * each trajectory's state, score, baseline and sample sums sit side by side in one array
   * (ST = 16 doubles a trajectory), so a step reads and writes one block, with no branch on
   * the options; the same operations in the same order as run2, so the same bits.
   */
  const ST = 16;  // x0 x1 | G0..G3 | baseline sums 0..3 | sample sums 0..3 | return | pad
  LqgBatch.prototype.run2gb = function (theta, sigma, n, opt, src) {
    const task = this.task, H = task.H;
    this.grow(n);
    if (!this.st || this.st.length < ST * this.cap) this.st = new Float64Array(ST * this.cap);
    const st = this.st, s = this.s, z = this.z, samples = this.samples, returns = this.returns;
    // The constants pass through a Float64Array so that the loop holds them as doubles: a matrix
    // entry or bound that is an integer (1, 0, 2 from JSON) would otherwise be converted at each use.
    const cf = this.constants2(theta, sigma, this.cf || (this.cf = new Float64Array(24)));
    const k00 = cf[0], k01 = cf[1], k10 = cf[2], k11 = cf[3], a00 = cf[4], a01 = cf[5], a10 = cf[6], a11 = cf[7];
    const b00 = cf[8], b01 = cf[9], b10 = cf[10], b11 = cf[11], q00 = cf[12], q01 = cf[13], q10 = cf[14], q11 = cf[15];
    const r00 = cf[16], r01 = cf[17], r10 = cf[18], r11 = cf[19], bs = cf[20], ba = cf[21], sg = cf[22], gm = cf[23];
    const nbs = -bs, nba = -ba;
    const iv = 1.0 / (sg * sg), n2 = 2 * n, n3 = 3 * n, end = ST * n;
    src.init(s, n, 2, -task.stateBound, task.stateBound);
    st.fill(0, 0, end);
    for (let j = 0, o = 0; j < n; j++, o += ST) { st[o] = s[j]; st[o + 1] = s[n + j]; }
    let disc = 1.0, rmax = 0, fmax = 0;
    const maxima = opt.batchConstants;
    // b_t - 1 (0 at t = 0) times the score before step t joins step t's pass, as in run2.
    let b0 = 0, b1 = 0, b2 = 0, b3 = 0;
    for (let t = 0; t < H; t++) {
      src.step(z, n, 2, t, this.idx);
      let n0 = 0, n1 = 0, nn2 = 0, nn3 = 0, d0 = 0, d1 = 0, d2 = 0, d3 = 0;
      for (let o = 0, j = 0; o < end; o += ST, j++) {
        const x0 = st[o], x1 = st[o + 1];
        const h0 = st[o + 2], h1 = st[o + 3], h2 = st[o + 4], h3 = st[o + 5];
        st[o + 6] += h0 * b0; st[o + 7] += h1 * b1; st[o + 8] += h2 * b2; st[o + 9] += h3 * b3;
        const m0 = 0.0 + k00 * x0 + k01 * x1, m1 = 0.0 + k10 * x0 + k11 * x1;
        const a0 = m0 + sg * z[j], a1 = m1 + sg * z[n + j];
        const u0 = Math.min(Math.max(a0, nba), ba), u1 = Math.min(Math.max(a1, nba), ba);
        let cost = 0.0 + (x0 * q00 * x0 + u0 * r00 * u0);
        cost += x0 * q01 * x1 + u0 * r01 * u1;
        cost += x1 * q10 * x0 + u1 * r10 * u0;
        cost += x1 * q11 * x1 + u1 * r11 * u1;
        const dr = -0.5 * cost * disc;
        st[o + 14] += dr;
        if (maxima) rmax = Math.max(rmax, Math.abs(-0.5 * cost), 0), fmax = Math.max(fmax, Math.abs(x0), Math.abs(x1));
        const e0 = iv * (u0 - m0), e1 = iv * (u1 - m1);
        const g0 = h0 + e0 * x0, g1 = h1 + e0 * x1, g2 = h2 + e1 * x0, g3 = h3 + e1 * x1;
        st[o + 2] = g0; st[o + 3] = g1; st[o + 4] = g2; st[o + 5] = g3;
        st[o + 10] += g0 * dr; st[o + 11] += g1 * dr; st[o + 12] += g2 * dr; st[o + 13] += g3 * dr;
        const sq0 = g0 * g0, sq1 = g1 * g1, sq2 = g2 * g2, sq3 = g3 * g3;
        n0 += sq0 * dr; n1 += sq1 * dr; nn2 += sq2 * dr; nn3 += sq3 * dr;
        d0 += sq0; d1 += sq1; d2 += sq2; d3 += sq3;
        const y0 = 0.0 + (a00 * x0 + b00 * u0) + (a01 * x1 + b01 * u1);
        const y1 = 0.0 + (a10 * x0 + b10 * u0) + (a11 * x1 + b11 * u1);
        st[o] = Math.min(Math.max(y0, nbs), bs);
        st[o + 1] = Math.min(Math.max(y1, nbs), bs);
      }
      b0 = d0 !== 0 ? n0 / d0 : 0; b1 = d1 !== 0 ? n1 / d1 : 0;
      b2 = d2 !== 0 ? nn2 / d2 : 0; b3 = d3 !== 0 ? nn3 / d3 : 0;
      disc *= gm;
    }
    // The rows of run2's arrays: samples (sample sum - baseline sum, the last step's term added), G, acc.
    const G = this.G, acc = this.acc;
    for (let j = 0, o = 0; j < n; j++, o += ST) {
      const c0 = st[o + 6] + st[o + 2] * b0, c1 = st[o + 7] + st[o + 3] * b1;
      const c2 = st[o + 8] + st[o + 4] * b2, c3 = st[o + 9] + st[o + 5] * b3;
      samples[j] = st[o + 10] - c0; samples[n + j] = st[o + 11] - c1;
      samples[n2 + j] = st[o + 12] - c2; samples[n3 + j] = st[o + 13] - c3;
      acc[j] = c0; acc[n + j] = c1; acc[n2 + j] = c2; acc[n3 + j] = c3;
      G[j] = st[o + 2]; G[n + j] = st[o + 3]; G[n2 + j] = st[o + 4]; G[n3 + j] = st[o + 5];
      returns[j] = st[o + 14]; s[j] = st[o]; s[n + j] = st[o + 1];
    }
    return maxima ? [rmax, fmax] : null;
  };

  Object.assign(L, {lqgTask, THESIS_2D, lqgPerformanceN, lqgGradientN, lqgSolve: solve, lqgStable: stable, LqgBatch});
})(safepgLearner);
