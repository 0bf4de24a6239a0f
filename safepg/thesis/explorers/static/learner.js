/*
 * safepg's learner in plain JavaScript, for the book's kernel-free explorers (run in a Web Worker):
 * this file holds what every task shares, the random numbers, the bounds of safepg.bounds
 * (eps(N) = d / sqrt(N) + f / N), the meta-parameters of safepg.meta (penalty c, coordinate
 * step, N* in closed form or by the Bernstein search), the record's summary and the Driver that
 * runs several learners side by side. The tasks (lqg_task.js: the LQG in any dimension, the 1-D
 * LQG of Section 5.1 included; cartpole_task.js), the option table (options.js, generated from
 * safepg.options) and the loop of safepg.learning (vector_run.js) come in the files concatenated
 * after this one (js_tasks.learner_sources()), which add to it.
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
 * Loaded as a script it defines `safepgLearner`; under Node, `require` of the concatenated files
 * returns it.
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
   * cfg: {bound, delta, estimator, range} (range: "lemma", "empirical" or a number); k: task constants;
   * spread: {variance, range} in place of the samples' own (the maxima over components), or null.
   */
  function errorBound(cfg, x, n, k, scratch, spread = null) {
    if (cfg.bound === "chebyshev")
      return chebyshev(cfg.delta, cfg.estimator === "reinforce" ? reinforceVarianceFactor(k) : gpomdpVarianceFactor(k));
    const R = cfg.range === "empirical" ? (spread ? spread.range : range(x, n))
      : (typeof cfg.range === "number" ? cfg.range : gradientRangeBound(k));
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
  function check(cond, msg) { if (!cond) throw new RangeError(msg); }
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
  /** The run for a task: vector_run.js (loaded last) sets it to its VectorRun. */
  Driver.makeRun = () => { throw new Error("the learner's files are incomplete: vector_run.js sets Driver.makeRun"); };
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
      const c = rec.c.slice(i0, i1);  // one per batch: measured constants change c
      return {name: r.name, from: i0, theta0: rec.theta[0], J0: rec.J[0], c: c,
              batchSize: rec.batchSize.slice(i0, i1), alpha: rec.alpha.slice(i0, i1),
              eps: rec.eps.slice(i0, i1), Jhat: rec.Jhat.slice(i0, i1), grad: rec.grad.slice(i0, i1),
              theta: rec.theta.slice(i0 + 1, i1 + 1), J: rec.J.slice(i0 + 1, i1 + 1),
              used: r.run.used, done: r.run.done, diverged: r.run.diverged, ms: r.ms,
              kernel: r.run.kernel || "javascript"};
    });
  };

  return {check, Rng, pairwiseSum, sampleVariance, range, reinforceVarianceFactor, gpomdpVarianceFactor,
          gradientRangeBound, penaltyConstant, chebyshev, hoeffding, bernstein, eps, errorBound, coordinateStep,
          nZero, upsilon, nStarClosedForm, nStarSearch, optimalBatchSize, Driver, summary, N_STAR_FACTOR,
          ZIGGURAT: Object.freeze({kn, wn, fn})};
})();
if (typeof module !== "undefined" && module.exports) module.exports = safepgLearner;
