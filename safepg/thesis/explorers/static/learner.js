/*
 * safepg's learner in plain JavaScript: Algorithm 4.1 (adaptive step and batch size) and
 * vanilla policy gradient on the one-dimensional LQG of Section 5.1, for the book's
 * kernel-free batch-size explorer (safepg/thesis/explorers/live_learner.py runs it in a Web Worker).
 *
 * It is the same algorithm as safepg.learning.adaptive_pg / vanilla_pg on LQG.thesis_1d():
 *   - simulation and gradient samples as safepg.envs._lqg_kernel.lqg1d_gradient_samples
 *     (clipped states and actions, REINFORCE or G(PO)MDP, variance-minimising baselines,
 *     the authors' clipped-action score or the raw one);
 *   - the bounds of safepg.bounds (eps(N) = d / sqrt(N) + f / N) and the meta-parameters of
 *     safepg.meta (penalty c, coordinate step, N* in closed form or by the Bernstein search);
 *   - the loop of safepg.learning._learn: first batch n_min, next batch N* clipped to
 *     [n_min, n_max], the last batch cut to the remaining budget (a run stops when fewer than
 *     2 trajectories remain), no step when eps >= |g_k|.
 * tests/test_learner_js.py checks the deterministic parts against safepg to 1e-12 relative
 * (same inputs, same outputs) and the whole runs statistically (30 seeds each).
 *
 * Random numbers: our own small generator, xoshiro128** (Blackman and Vigna, 2018; 128-bit
 * state of four 32-bit words, period 2^128 - 1), its state filled from the seed by
 * splitmix32. Uniforms in [0, 1) carry 53 random bits (two outputs); normals come from
 * our implementation of the ziggurat of Marsaglia and Tsang (2000), with the layer bits
 * drawn apart from the value bits (see fillNormal). A seed (and a stream
 * number: the adaptive and the vanilla run use streams 0 and 1) fixes every number.
 * These are not numpy's streams: the same seed gives other batches than safepg does.
 *
 * Loaded as a script it defines `safepgLearner`; under Node, `require` returns it. The vector
 * tasks (the 2-D LQG, the cart-pole) come in the files concatenated after this one
 * (live_learner.learner_js(): lqg_task.js, cartpole_task.js, vector_run.js), which add to it.
 */
"use strict";
const safepgLearner = (function () {
  // ------------------------------------------------------------------- random numbers
  /** xoshiro128** seeded by splitmix32(seed, stream). */
  function Rng(seed, stream) {
    if (!Number.isInteger(seed) || seed < 0) throw new RangeError(`seed must be an integer >= 0, got ${seed}`);
    let x = (seed ^ Math.imul((stream | 0) + 1, 0x9e3779b1)) | 0;
    const hi = Math.floor(seed / 4294967296);  // seeds above 2^32 still differ
    const sm = () => {  // splitmix32
      x = (x + 0x9e3779b9) | 0;
      let z = x ^ hi;
      z = Math.imul(z ^ (z >>> 16), 0x85ebca6b);
      z = Math.imul(z ^ (z >>> 13), 0xc2b2ae35);
      return (z ^ (z >>> 16)) | 0;
    };
    this.s = new Int32Array([sm(), sm(), sm(), sm()]);
    if ((this.s[0] | this.s[1] | this.s[2] | this.s[3]) === 0) this.s[0] = 1;  // the one forbidden state
  }
  /** Next 32-bit output as an unsigned integer. */
  Rng.prototype.nextU32 = function () {
    const s = this.s;
    let a = s[0], b = s[1], c = s[2], d = s[3];
    const r = Math.imul(rotl(Math.imul(b, 5), 7), 9);
    const t = b << 9;
    c ^= a; d ^= b; b ^= c; a ^= d; c ^= t; d = rotl(d, 11);
    s[0] = a; s[1] = b; s[2] = c; s[3] = d;
    return r >>> 0;
  };
  function rotl(v, k) { return (v << k) | (v >>> (32 - k)); }
  /** Uniform in [0, 1) with 53 random bits. */
  Rng.prototype.uniform = function () {
    return ((this.nextU32() >>> 5) * 67108864 + (this.nextU32() >>> 6)) / 9007199254740992;
  };
  // Ziggurat tables (Marsaglia and Tsang, 2000; 128 layers): layer i has x-extent wn[i] * 2^31,
  // a value inside kn[i] is accepted at once, fn[i] = exp(-x_i^2 / 2).
  const ZIG_R = 3.442619855899;
  const kn = new Float64Array(128), wn = new Float64Array(128), fn = new Float64Array(128);
  (function () {
    const m1 = 2147483648.0, vn = 9.91256303526217e-3;
    let dn = ZIG_R, tn = dn;
    const q = vn / Math.exp(-0.5 * dn * dn);
    kn[0] = Math.floor((dn / q) * m1); kn[1] = 0;
    wn[0] = q / m1; wn[127] = dn / m1;
    fn[0] = 1; fn[127] = Math.exp(-0.5 * dn * dn);
    for (let i = 126; i >= 1; i--) {
      dn = Math.sqrt(-2 * Math.log(vn / dn + Math.exp(-0.5 * dn * dn)));
      kn[i + 1] = Math.floor((dn / tn) * m1);
      tn = dn;
      fn[i] = Math.exp(-0.5 * dn * dn);
      wn[i] = dn / m1;
    }
  })();
  /** Uniform in (0, 1] (for logarithms). */
  Rng.prototype.uniformPositive = function () { return 1 - this.uniform(); };
  /** A standard normal by the ziggurat's slow path: the wedges and the tail (about 1.2% of draws). */
  Rng.prototype._zigSlow = function (hz, iz) {
    for (;;) {
      const x = hz * wn[iz];
      if (iz === 0) {  // the tail beyond ZIG_R (Marsaglia's exponential method)
        let xt, y;
        do {
          xt = -Math.log(this.uniformPositive()) / ZIG_R;
          y = -Math.log(this.uniformPositive());
        } while (y + y < xt * xt);
        return hz > 0 ? ZIG_R + xt : -ZIG_R - xt;
      }
      if (fn[iz] + this.uniform() * (fn[iz - 1] - fn[iz]) < Math.exp(-0.5 * x * x)) return x;
      hz = this.nextU32() | 0;
      iz = this.nextU32() & 127;
      if (Math.abs(hz) < kn[iz]) return hz * wn[iz];
    }
  };
  /**
   * Fill out[from..to) with standard normals: the ziggurat of Marsaglia and Tsang (2000).
   * Each normal takes its signed 32-bit value from one output and its layer (7 bits) from
   * an output shared by four normals, so value and layer never share bits (the flaw
   * Doornik (2005) found in the original). The generator's state is kept in locals: this
   * is the hot path of a batch.
   */
  Rng.prototype.fillNormal = function (out, from, to) {
    const s = this.s;
    let a = s[0], b = s[1], c = s[2], d = s[3];
    let layers = 0, left = 0;
    for (let i = from; i < to; i++) {
      if (left === 0) {
        layers = Math.imul(rotl(Math.imul(b, 5), 7), 9);
        const t = b << 9;
        c ^= a; d ^= b; b ^= c; a ^= d; c ^= t; d = (d << 11) | (d >>> 21);
        left = 4;
      }
      const iz = layers & 127;
      layers >>>= 8; left -= 1;
      const hz = Math.imul(rotl(Math.imul(b, 5), 7), 9);
      const t = b << 9;
      c ^= a; d ^= b; b ^= c; a ^= d; c ^= t; d = (d << 11) | (d >>> 21);
      if (Math.abs(hz) < kn[iz]) out[i] = hz * wn[iz];
      else {
        s[0] = a; s[1] = b; s[2] = c; s[3] = d;
        out[i] = this._zigSlow(hz, iz);
        a = s[0]; b = s[1]; c = s[2]; d = s[3];
      }
    }
    s[0] = a; s[1] = b; s[2] = c; s[3] = d;
  };

  // ---------------------------------------------------------------------- numerics
  /** numpy's pairwise summation (numpy/_core/src/umath/loops_utils.h), so sums of long
   *  arrays are as accurate as safepg's: 8 accumulators below 128 values, halves above. */
  function pairwiseSum(a, lo, n) {
    if (n < 8) {
      let r = -0.0;  // numpy starts from -0.0 so that an all -0.0 sum stays -0.0
      for (let i = 0; i < n; i++) r += a[lo + i];
      return r;
    }
    if (n <= 128) {
      let r0 = a[lo], r1 = a[lo + 1], r2 = a[lo + 2], r3 = a[lo + 3],
        r4 = a[lo + 4], r5 = a[lo + 5], r6 = a[lo + 6], r7 = a[lo + 7];
      let i;
      for (i = 8; i < n - (n % 8); i += 8) {
        r0 += a[lo + i]; r1 += a[lo + i + 1]; r2 += a[lo + i + 2]; r3 += a[lo + i + 3];
        r4 += a[lo + i + 4]; r5 += a[lo + i + 5]; r6 += a[lo + i + 6]; r7 += a[lo + i + 7];
      }
      let res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7));
      for (; i < n; i++) res += a[lo + i];
      return res;
    }
    let n2 = Math.floor(n / 2);
    n2 -= n2 % 8;
    return pairwiseSum(a, lo, n2) + pairwiseSum(a, lo + n2, n - n2);
  }
  function sum(a, n) { return pairwiseSum(a, 0, n); }
  /** Sample variance with ddof = 1, two passes as numpy.var. */
  function sampleVariance(a, n, scratch) {
    const mean = sum(a, n) / n;
    for (let i = 0; i < n; i++) { const x = a[i] - mean; scratch[i] = x * x; }
    return sum(scratch, n) / (n - 1);
  }
  /** max - min (numpy.ptp). */
  function range(a, n) {
    let lo = a[0], hi = a[0];
    for (let i = 1; i < n; i++) { const x = a[i]; if (x < lo) lo = x; if (x > hi) hi = x; }
    return hi - lo;
  }

  // ----------------------------------------------------------------- task constants
  /** The 1-D LQG of LQG.thesis_1d() (SETTINGS.md); safepg passes its own values in. */
  const THESIS_1D = {gamma: 0.9, H: 20, bs: 2, ba: 2, A: 1, B: 1, Q: 1, Rc: 1,
                     R: 4, M: 2, Avol: 4, Abar: 2};
  /** Closed-form J(theta) of the infinite-horizon, unclipped 1-D problem (LQG.performance). */
  function lqgPerformance(theta, sigma, task) {
    const g = task.gamma, F = task.A + task.B * theta;
    if (!(Math.abs(F) * Math.sqrt(g) < 1)) return -Infinity;
    const P = 0.5 * (task.Q + theta * task.Rc * theta) / (1 - g * F * F);
    const S = sigma * sigma;
    const noise = 0.5 * (task.Rc * S) + g * (task.B * P * task.B * S);
    return -(P * (task.bs * task.bs / 3)) - noise / (1 - g);
  }

  // ------------------------------------------------------------------------ bounds
  // safepg.bounds and safepg.meta, operation for operation (same order, same rounding).
  function reinforceVarianceFactor(k) {
    const g = k.gamma, H = k.H;
    const x = k.R * k.M * (1 - Math.pow(g, H)) / (k.sigma * (1 - g));
    return x * x * H;
  }
  function gpomdpVarianceFactor(k) {
    const g = k.gamma, H = k.H;
    const bracket = (1 - Math.pow(g, 2 * H)) / (1 - g * g) + H * Math.pow(g, 2 * H)
      - 2 * Math.pow(g, H) * (1 - Math.pow(g, H)) / (1 - g);
    const x = k.R * k.M / (k.sigma * (1 - g));
    return x * x * bracket;
  }
  function gradientRangeBound(k) { return 2 * k.H * k.M * k.Abar * k.R / (k.sigma * k.sigma * (1 - k.gamma)); }
  /** safepg.meta.penalty_constant, the horizon factor h of TaskConstants.horizon_term included. */
  function penaltyConstant(k) {
    const g = k.gamma, s = k.sigma;
    if (!k.horizonTerm || k.horizonTerm === "effective") {
      return k.R * (k.M * k.M) / (((1 - g) * (1 - g)) * (s * s)) *
        (k.Avol / (Math.sqrt(2 * Math.PI) * s) + g / (2 * (1 - g)));
    }
    const h = k.horizonTerm === "horizon" || g === 1 ? k.H : (1 - Math.pow(g, k.H)) / (1 - g);
    return k.R * (k.M * k.M) * (h * h) / (s * s) * (k.Avol / (Math.sqrt(2 * Math.PI) * s) + g * h / 2);
  }
  function chebyshev(delta, variance) { return {d: Math.sqrt(variance / delta), f: 0}; }
  function hoeffding(delta, gradRange) { return {d: gradRange * Math.sqrt(Math.log(2 / delta) / 2), f: 0}; }
  function bernstein(delta, S, gradRange) {
    const l = Math.log(3 / delta);
    return {d: Math.sqrt(2 * S * l), f: 3 * gradRange * l};
  }
  function eps(bd, n) { return bd.d / Math.sqrt(n) + bd.f / n; }
  /**
   * safepg.bounds.error_bound for one component's samples x[0..n).
   * cfg: {bound, delta, estimator, empiricalRange, theoreticalRange}; k: task constants;
   * spread: {variance, range} in place of the samples' own (the maxima over components), or null.
   */
  function errorBound(cfg, x, n, k, scratch, spread = null) {
    if (cfg.bound === "chebyshev")
      return chebyshev(cfg.delta, cfg.estimator === "reinforce" ? reinforceVarianceFactor(k) : gpomdpVarianceFactor(k));
    const R = cfg.empiricalRange ? (spread ? spread.range : range(x, n))
      : (cfg.theoreticalRange != null ? cfg.theoreticalRange : gradientRangeBound(k));
    if (cfg.bound === "hoeffding") return hoeffding(cfg.delta, R);
    if (cfg.bound === "bernstein") return bernstein(cfg.delta, spread ? spread.variance : sampleVariance(x, n, scratch), R);
    throw new RangeError(`bound must be chebyshev, hoeffding or bernstein, got ${cfg.bound}`);
  }

  // -------------------------------------------------------------- meta-parameters
  const N_STAR_FACTOR = (13 + 3 * Math.sqrt(17)) / 2;
  /** Corollary 4.2.8: 0 when eps >= g (no guarantee, no move), unless unguarded (the authors' step). */
  function coordinateStep(g, e, c, guarded = true) {
    if (e >= g && guarded) return 0;
    const lo = g - e, hi = g + e;
    return hi === 0 ? 0 : lo * lo / (2 * c * (hi * hi));
  }
  function nZero(g, bd) {
    if (g === 0) return Infinity;
    const r = (bd.d + Math.sqrt(bd.d * bd.d + 4 * bd.f * g)) / (2 * g);
    return r * r;
  }
  /** Upsilon_delta(N), 0 where eps(N) >= g (safepg.meta.upsilon, saturate=True). */
  function upsilon(n, g, bd, c) {
    const e = bd.d / Math.sqrt(n) + bd.f / n;
    if (!(e < g)) return 0;
    const lo = g - e, hi = g + e;  // products, as safepg.meta.upsilon (not pow)
    return (lo * lo) * (lo * lo) / (4 * c * n * (hi * hi));
  }
  function nStarClosedForm(g, bd) {
    if (g === 0) return Infinity;
    return Math.ceil(N_STAR_FACTOR * (bd.d * bd.d) / (g * g));
  }
  /**
   * safepg.meta.n_star_search with n_max: the first n >= ceil(N_0) at which Upsilon starts
   * to decrease, n_max if it has not by then. Upsilon has one maximum on [N_0, inf), so
   * "decreases after n" is false then true: bisection finds the same n as the linear
   * search in log time (the linear search costs O(N*) per iteration).
   */
  function nStarSearch(g, bd, c, nMax) {
    if (g === 0) return nMax;
    const start = Math.max(1, Math.ceil(nZero(g, bd)));
    if (start >= nMax) return nMax;
    const drops = n => upsilon(n + 1, g, bd, c) < upsilon(n, g, bd, c);
    if (!drops(nMax - 1)) return nMax;
    let lo = start, hi = nMax - 1;  // drops(hi) holds
    while (lo < hi) {
      const mid = lo + Math.floor((hi - lo) / 2);
      if (drops(mid)) hi = mid; else lo = mid + 1;
    }
    return lo;
  }
  /** safepg.meta.optimal_batch_size: N* clipped to [nMin, nMax]. */
  function optimalBatchSize(g, bd, c, nMin, nMax) {
    let n = bd.f === 0 ? nStarClosedForm(g, bd) : nStarSearch(g, bd, c, nMax);
    n = Math.min(n, nMax);
    return Math.max(nMin, n);
  }
  /**
   * The update of Algorithm 4.1 after a batch (m = 1: the one component is k = 0):
   * the rule of safepg.learning.adaptive_pg.
   */
  function adaptiveUpdate(cfg, x, n, grad, k, c, scratch) {
    const g = Math.abs(grad);
    const bd = errorBound(cfg, x, n, k, scratch);
    const e = eps(bd, n);
    const alpha = coordinateStep(g, e, c);
    return {d: bd.d, f: bd.f, eps: e, alpha: alpha, step: alpha * grad, safe: e < g,
            nextN: optimalBatchSize(g, bd, c, cfg.nMin, cfg.nMax)};
  }

  // ---------------------------------------------------------- batch of trajectories
  const CHUNK = 1024;  // trajectories whose random numbers are drawn at once
  /**
   * Workspace of a run: sample, return and baseline buffers grown to the largest batch.
   */
  function Workspace(H) {
    this.H = H; this.cap = 0;
    this.s0 = new Float64Array(CHUNK); this.z = new Float64Array(CHUNK * H);
    this.num = new Float64Array(H); this.den = new Float64Array(H);
    this.grow(CHUNK);
  }
  Workspace.prototype.grow = function (n) {
    if (n <= this.cap) return;
    const cap = Math.max(n, Math.ceil(this.cap * 1.5));
    this.samples = new Float64Array(cap); this.returns = new Float64Array(cap);
    this.scratch = new Float64Array(cap); this.kept = new Float64Array(cap * this.H);
    this.cap = cap;
  };
  /**
   * n gradient samples and discounted returns with gain theta (lqg1d_gradient_samples).
   *
   * draw(s0, z, count) fills the initial states s0[0..count) and the standard normals
   * z[0..count*H) (row-major, trajectory by trajectory) of the next `count` trajectories;
   * the samples land in ws.samples[0..n), the returns in ws.returns[0..n).
   */
  function gradientSamples(theta, sigma, n, task, opt, ws, draw) {
    const H = task.H, gamma = task.gamma, bs = task.bs, ba = task.ba, clip = task.clip !== false;
    const A = task.A, B = task.B, Q = task.Q, Rc = task.Rc;
    const reinforce = opt.estimator === "reinforce", baseline = !!opt.baseline;
    const scoreClipped = opt.score !== "raw";
    ws.grow(n);
    const samples = ws.samples, returns = ws.returns, kept = ws.kept, num = ws.num, den = ws.den;
    const s0 = ws.s0, z = ws.z;
    const rows = reinforce ? 1 : H;
    num.fill(0); den.fill(0);
    const invVar = 1.0 / (sigma * sigma);
    for (let c0 = 0; c0 < n; c0 += CHUNK) {
      const count = Math.min(CHUNK, n - c0);
      draw(s0, z, count);
      for (let j = 0; j < count; j++) {
        const nn = c0 + j;
        let s = s0[j], cum = 0.0, acc = 0.0, disc = 1.0, ret = 0.0;
        const zo = j * H, ko = nn * rows;
        for (let t = 0; t < H; t++) {
          const mean = theta * s;
          const aRaw = mean + sigma * z[zo + t];
          const u = clip ? Math.min(Math.max(aRaw, -ba), ba) : aRaw;
          const dr = -0.5 * (Q * s * s + Rc * u * u) * disc;
          ret += dr;
          cum += ((scoreClipped ? u : aRaw) - mean) * s * invVar;
          if (!reinforce) {
            acc += cum * dr;
            const cc = cum * cum;
            num[t] += cc * dr;
            den[t] += cc;
            if (baseline) kept[ko + t] = cum;
          }
          disc *= gamma;
          s = A * s + B * u;
          if (clip) s = Math.min(Math.max(s, -bs), bs);
        }
        returns[nn] = ret;
        if (reinforce) {
          const cc = cum * cum;
          num[0] += cc * ret;
          den[0] += cc;
          acc = cum * ret;
          if (baseline) kept[nn] = cum;
        }
        samples[nn] = acc;
      }
    }
    if (baseline) {
      // b_t = sum G^2 r / sum G^2 (0 where no score): Sections 2.3.9-2.3.10
      const b = new Float64Array(rows);
      for (let t = 0; t < rows; t++) b[t] = den[t] !== 0 ? num[t] / den[t] : 0;
      for (let nn = 0; nn < n; nn++) {
        let acc = 0.0;
        const ko = nn * rows;
        for (let t = 0; t < rows; t++) acc += kept[ko + t] * b[t];
        samples[nn] -= acc;
      }
    }
  }
  /** The random-number source of a run: initial states uniform in [-bs, bs], then H normals. */
  function rngDraw(rng, task) {
    const H = task.H, bs = task.bs;
    return function (s0, z, count) {
      for (let j = 0; j < count; j++) s0[j] = bs * (2 * rng.uniform() - 1);
      rng.fillNormal(z, 0, count * H);
    };
  }

  // --------------------------------------------------------------------- the loops
  const DEFAULTS = {algorithm: "adaptive", theta0: 0, sigma: 1, estimator: "gpomdp", baseline: true,
                    bound: "chebyshev", delta: 0.95, empiricalRange: false, theoreticalRange: null,
                    nMin: 100, nMax: 500000, batchSize: 100, alpha: 1e-3, budget: 1000000,
                    score: "clipped", seed: 0, stream: 0};
  function check(cond, msg) { if (!cond) throw new RangeError(msg); }
  /**
   * A learning run advanced one iteration at a time (so a worker can report progress
   * and be stopped between batches). cfg: see DEFAULTS; task: see THESIS_1D.
   *
   * rec holds per-iteration arrays as in safepg.learning.LearningRecord: batchSize, alpha,
   * eps, Jhat, grad, safe, nextN (I each) and theta, J (I + 1).
   */
  function Run(cfgIn, taskIn, draw) {
    const cfg = Object.assign({}, DEFAULTS, cfgIn);
    const task = Object.assign({}, THESIS_1D, taskIn || {});
    check(cfg.algorithm === "adaptive" || cfg.algorithm === "vanilla", `algorithm must be adaptive or vanilla, got ${cfg.algorithm}`);
    check(cfg.delta > 0 && cfg.delta < 1, `delta must be in (0, 1), got ${cfg.delta}`);
    check(cfg.sigma > 0 && isFinite(cfg.sigma), `sigma must be finite and > 0, got ${cfg.sigma}`);
    check(cfg.estimator === "gpomdp" || cfg.estimator === "reinforce", `estimator must be gpomdp or reinforce, got ${cfg.estimator}`);
    check(cfg.score === "clipped" || cfg.score === "raw", `score must be clipped or raw, got ${cfg.score}`);
    const first = cfg.algorithm === "adaptive" ? cfg.nMin : cfg.batchSize;
    check(Number.isInteger(first) && first >= 2, `first batch size must be an integer >= 2, got ${first}`);
    check(Number.isInteger(cfg.budget) && cfg.budget >= first, `budget must be an integer >= the first batch size ${first}, got ${cfg.budget}`);
    if (cfg.algorithm === "adaptive") check(cfg.nMin <= cfg.nMax, `n_min must be <= n_max, got ${cfg.nMin} > ${cfg.nMax}`);
    else check(cfg.alpha >= 0 && isFinite(cfg.alpha), `alpha must be finite and >= 0, got ${cfg.alpha}`);
    this.cfg = cfg; this.task = task;
    this.k = {R: task.R, M: task.M, Avol: task.Avol, Abar: task.Abar, gamma: task.gamma, H: task.H, sigma: cfg.sigma};
    this.c = penaltyConstant(this.k);
    this.ws = new Workspace(task.H);
    this.draw = draw || rngDraw(new Rng(cfg.seed, cfg.stream), task);
    this.theta = cfg.theta0; this.used = 0; this.n = first;
    this.done = false; this.diverged = false;
    this.rec = {batchSize: [], alpha: [], eps: [], Jhat: [], grad: [], safe: [], nextN: [],
                theta: [this.theta], J: [lqgPerformance(this.theta, cfg.sigma, task)]};
  }
  /** One iteration of safepg.learning._learn; false once the run is over. */
  Run.prototype.step = function () {
    if (this.done) return false;
    const cfg = this.cfg, ws = this.ws;
    const n = Math.min(this.n, cfg.budget - this.used);  // the last batch is cut to the budget
    if (n < 2) { this.done = true; return false; }
    gradientSamples(this.theta, cfg.sigma, n, this.task, cfg, ws, this.draw);
    const grad = sum(ws.samples, n) / n;
    if (!isFinite(grad)) { this.done = this.diverged = true; return false; }  // theta diverged (fixed step)
    const Jhat = sum(ws.returns, n) / n;
    let up;
    if (cfg.algorithm === "adaptive") up = adaptiveUpdate(cfg, ws.samples, n, grad, this.k, this.c, ws.scratch);
    else up = {eps: 0, alpha: cfg.alpha, step: cfg.alpha * grad, safe: true, nextN: cfg.batchSize};
    this.theta = this.theta + up.step;
    this.used += n;
    const r = this.rec;
    r.batchSize.push(n); r.alpha.push(up.alpha); r.eps.push(up.eps); r.Jhat.push(Jhat); r.grad.push(grad);
    r.safe.push(up.safe); r.nextN.push(up.nextN); r.theta.push(this.theta);
    r.J.push(lqgPerformance(this.theta, cfg.sigma, this.task));
    this.n = up.nextN;
    return true;
  };
  /** Run to the end (Node, tests, benchmarks). */
  Run.prototype.finish = function () { while (this.step()); return this; };
  /** The summary safepg.learning.LearningRecord gives (upsilon_bar, improvement ratio, J_at). */
  function summary(rec, checkpoints) {
    const I = rec.batchSize.length;
    let tot = 0, w = 0, up = 0;
    for (let i = 0; i < I; i++) { tot += rec.batchSize[i]; w += rec.batchSize[i] * rec.Jhat[i]; }
    for (let i = 0; i < I; i++) if (rec.J[i + 1] - rec.J[i] >= 0) up += 1;
    const Jat = {};
    let end = 0, i = 0;
    for (const T of (checkpoints || [100000, 1000000, 3000000])) {
      if (T > tot) continue;
      while (end + rec.batchSize[i] < T) { end += rec.batchSize[i]; i += 1; }
      Jat[String(T)] = rec.J[i];
    }
    return {iterations: I, trajectories: tot, upsilon_bar: I ? w / tot : NaN,
            improvement_ratio: I ? up / I : NaN, theta_final: rec.theta[I], J_final: rec.J[I], J_at: Jat};
  }

  /**
   * Runs several learners side by side for a page: each call of advance(ms) steps whichever
   * run has used the fewest trajectories (so their curves grow together) for about ms
   * milliseconds and returns what is new since the last call. A Web Worker calls it in a
   * loop and posts each result; without a worker the page calls it from timers.
   *
   * msg: {runs: [{name, cfg}], task}.
   */
  function Driver(msg, clock) {
    this.clock = clock || (typeof performance !== "undefined" ? () => performance.now() : () => Date.now());
    this.runs = msg.runs.map(r => ({name: r.name, run: Driver.makeRun(r.cfg, msg.task), sent: 0, ms: 0}));
    this.done = false;
  }
  /** The run for a task: this file's 1-D Run; vector_run.js (loaded after it) widens it to every task. */
  Driver.makeRun = (cfg, task) => new Run(cfg, task);
  Driver.prototype.advance = function (ms) {
    const t0 = this.clock();
    let now = t0;
    while (now - t0 < ms) {
      let best = null;
      for (const r of this.runs) if (!r.run.done && (best === null || r.run.used < best.run.used)) best = r;
      if (best === null) { this.done = true; break; }
      best.run.step();
      const t = this.clock();
      best.ms += t - now;  // time spent in this run alone (the benchmark reports it)
      now = t;
    }
    return this.runs.map(r => {
      const rec = r.run.rec, i0 = r.sent, i1 = rec.batchSize.length;
      r.sent = i1;
      // The 1-D run's penalty constant is fixed; a vector run records one per batch (constants="batch").
      const c = rec.c ? rec.c.slice(i0, i1) : new Array(i1 - i0).fill(r.run.c);
      return {name: r.name, from: i0, theta0: rec.theta[0], J0: rec.J[0], c: c,
              batchSize: rec.batchSize.slice(i0, i1), alpha: rec.alpha.slice(i0, i1),
              eps: rec.eps.slice(i0, i1), Jhat: rec.Jhat.slice(i0, i1), grad: rec.grad.slice(i0, i1),
              theta: rec.theta.slice(i0 + 1, i1 + 1), J: rec.J.slice(i0 + 1, i1 + 1),
              used: r.run.used, done: r.run.done, diverged: r.run.diverged, ms: r.ms,
              kernel: r.run.kernel || "javascript"};
    });
  };

  return {check, Rng, pairwiseSum, sampleVariance, range, lqgPerformance, reinforceVarianceFactor, gpomdpVarianceFactor,
          gradientRangeBound, penaltyConstant, chebyshev, hoeffding, bernstein, eps, errorBound, coordinateStep,
          nZero, upsilon, nStarClosedForm, nStarSearch, optimalBatchSize, adaptiveUpdate, Workspace,
          gradientSamples, rngDraw, Run, Driver, summary, THESIS_1D, DEFAULTS, N_STAR_FACTOR,
          ZIGGURAT: Object.freeze({kn, wn, fn})};
})();
if (typeof module !== "undefined" && module.exports) module.exports = safepgLearner;
