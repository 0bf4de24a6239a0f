/*
 * Algorithm 4.1 and vanilla policy gradient on a vector theta (safepg.learning.adaptive_pg /
 * vanilla_pg): the LQG of lqg_task.js in m > 1 dimensions and the cart-pole of
 * cartpole_task.js, with the authors' options (constants measured per batch, statistics as
 * maxima over components, the unguarded step) and the fixed-N steps of Section 5.2.1 (the
 * scalar step of [24], the coordinate step Lambda*). The 1-D LQG keeps learner.js's Run, so
 * a seeded 1-D run gives the numbers it always did. Concatenated last (it extends safepgLearner
 * and widens Driver.makeRun to every task).
 */
"use strict";
(function (L) {
  const check = L.check;  // learner.js's: one argument check for every file of the learner
  const VECTOR_DEFAULTS = Object.freeze({
    algorithm: "adaptive", theta0: 0, sigma: 1, estimator: "gpomdp", baseline: true, bound: "chebyshev",
    delta: 0.95, empiricalRange: false, theoreticalRange: null, nMin: 100, nMax: 500000, nFirst: null,
    budget: 1000000, score: "clipped", constants: "bounds", statistics: "component", stepWhenUnsafe: false,
    batchSize: 100, alpha: 1e-3, step: "scalar", stopOnDivergence: true, seed: 0, stream: 0});

  /** The bound constants of a task (TaskConstants.from_task): the discount is constantsGamma when set. */
  function taskConstants(task, sigma) {
    if (task.kind === "cartpole") {
      return {R: task.rewardBound, M: task.featureBound, Avol: task.actionSpaceVolume != null
        ? task.actionSpaceVolume : 2 * task.actionBound, Abar: task.actionBound,
              gamma: task.constantsGamma != null ? task.constantsGamma : task.gamma, H: task.H, sigma: sigma,
              horizonTerm: task.horizonTerm || "effective"};
    }
    return {R: task.rewardBound, M: task.featureBound, Avol: task.actionVolume, Abar: task.actionBound,
            gamma: task.gamma, H: task.H, sigma: sigma, horizonTerm: "effective"};
  }
  /** safepg.meta.scalar_step: the step of [24], ||(|g| - eps)+||_2^2 / (2 c ||(|g| + eps)||_1^2). */
  function scalarStep(grad, e, c) {
    let lo2 = 0, up = 0;
    for (const v of grad) { const a = Math.abs(v), lo = Math.max(a - e, 0); lo2 += lo * lo; up += a + e; }
    return up === 0 ? 0 : lo2 / (2 * c * (up * up));
  }
  /** Sample variance (ddof = 1) and range of row p of an (m, n) component-major array. */
  function rowStats(x, p, n, scratch) {
    const row = x.subarray(p * n, p * n + n);
    return {variance: L.sampleVariance(row, n, scratch), range: L.range(row, n)};
  }
  /** The random numbers of a run from its own generator (learner.js's Rng). */
  function rngSource(rng) {
    return {
      rng,  // the WebAssembly kernel draws the same normals from this generator's state (lqg2d_wasm.js)
      init(s, n, dim, lo, hi) {
        for (let j = 0; j < n; j++) for (let i = 0; i < dim; i++) s[i * n + j] = lo + (hi - lo) * rng.uniform();
      },
      step(z, n, dim) { rng.fillNormal(z, 0, n * dim); },
    };
  }
  /**
   * The random numbers of given arrays, trajectory by trajectory as safepg.streams hands them
   * out: U[j * dim + i] (initial states), Z[j * H * dim + t * dim + i] (normals); each batch
   * reads the next n trajectories. For tests: fed numpy's draws, a batch is safepg's batch.
   */
  function arraySource(U, Z, H) {
    let base = 0, pending = 0;
    return {
      init(s, n, dim, lo, hi) {
        base += pending; pending = n;
        for (let j = 0; j < n; j++) for (let i = 0; i < dim; i++) s[i * n + j] = lo + (hi - lo) * U[(base + j) * dim + i];
      },
      step(z, n, dim, t, idx) {
        for (let j = 0; j < n; j++) {
          const o = (base + idx[j]) * H * dim + t * dim;
          for (let i = 0; i < dim; i++) z[i * n + j] = Z[o + i];
        }
      },
    };
  }

  function checkCfg(cfg, m) {
    check(cfg.algorithm === "adaptive" || cfg.algorithm === "vanilla", `algorithm must be adaptive or vanilla, got ${cfg.algorithm}`);
    check(cfg.delta > 0 && cfg.delta < 1, `delta must be in (0, 1), got ${cfg.delta}`);
    check(cfg.sigma > 0 && isFinite(cfg.sigma), `sigma must be finite and > 0, got ${cfg.sigma}`);
    check(cfg.estimator === "gpomdp" || cfg.estimator === "reinforce", `estimator must be gpomdp or reinforce, got ${cfg.estimator}`);
    check(["chebyshev", "hoeffding", "bernstein"].includes(cfg.bound), `bound must be chebyshev, hoeffding or bernstein, got ${cfg.bound}`);
    check(cfg.score === "clipped" || cfg.score === "raw", `score must be clipped or raw, got ${cfg.score}`);
    check(cfg.constants === "bounds" || cfg.constants === "batch", `constants must be bounds or batch, got ${cfg.constants}`);
    check(cfg.statistics === "component" || cfg.statistics === "max", `statistics must be component or max, got ${cfg.statistics}`);
    check(cfg.step === "scalar" || cfg.step === "coordinate", `step must be scalar or coordinate, got ${cfg.step}`);
    check(typeof cfg.stepWhenUnsafe === "boolean", `stepWhenUnsafe must be true or false, got ${cfg.stepWhenUnsafe}`);
    check(typeof cfg.stopOnDivergence === "boolean", `stopOnDivergence must be true or false, got ${cfg.stopOnDivergence}`);
    check(cfg.theoreticalRange == null || (isFinite(cfg.theoreticalRange) && cfg.theoreticalRange > 0),
          `theoreticalRange must be finite and > 0 or null, got ${cfg.theoreticalRange}`);
    const th = Array.isArray(cfg.theta0) || ArrayBuffer.isView(cfg.theta0) ? Array.from(cfg.theta0) : null;
    check(th === null ? Number.isFinite(cfg.theta0) : th.length === m && th.every(Number.isFinite),
          `theta0 must be a finite number or ${m} finite numbers, got ${cfg.theta0}`);
    let first;
    if (cfg.algorithm === "adaptive") {
      check(Number.isInteger(cfg.nMin) && cfg.nMin >= 2, `nMin must be an integer >= 2, got ${cfg.nMin}`);
      check(cfg.nMin <= cfg.nMax, `nMin must be <= nMax, got ${cfg.nMin} > ${cfg.nMax}`);
      check(cfg.nFirst == null || (Number.isInteger(cfg.nFirst) && cfg.nFirst >= 2), `nFirst must be an integer >= 2 or null, got ${cfg.nFirst}`);
      first = cfg.nFirst == null ? cfg.nMin : cfg.nFirst;
    } else {
      check(Number.isInteger(cfg.batchSize) && cfg.batchSize >= 2, `batchSize must be an integer >= 2, got ${cfg.batchSize}`);
      check(cfg.alpha === null || (isFinite(cfg.alpha) && cfg.alpha >= 0), `alpha must be finite and >= 0 or null, got ${cfg.alpha}`);
      first = cfg.batchSize;
    }
    check(Number.isInteger(cfg.budget) && cfg.budget >= first, `budget must be an integer >= the first batch size ${first}, got ${cfg.budget}`);
    return first;
  }

  /**
   * A learning run on a vector task, one iteration at a time (learner.js's Run, for theta in R^m).
   * rec: batchSize, alpha, coordinate, eps, Jhat, grad (arrays), safe, nextN, c (I each);
   * theta (arrays) and J (closed form for the LQG, null for the cart-pole) (I + 1).
   */
  function VectorRun(cfgIn, task, src) {
    const cfg = Object.assign({}, VECTOR_DEFAULTS, cfgIn);
    check(task && (task.kind === "lqg" || task.kind === "cartpole"), `task.kind must be lqg or cartpole, got ${task && task.kind}`);
    const m = task.kind === "lqg" ? task.dim * task.dim : 4;
    const first = checkCfg(cfg, m);
    this.cfg = cfg; this.task = task; this.m = m;
    this.batch = task.kind === "lqg" ? new L.LqgBatch(task) : new L.CartpoleBatch(task);
    this.k = taskConstants(task, cfg.sigma);
    this.c = L.penaltyConstant(this.k);
    this.src = src || rngSource(new L.Rng(cfg.seed, cfg.stream));
    const th = Array.isArray(cfg.theta0) || ArrayBuffer.isView(cfg.theta0) ? cfg.theta0 : null;
    this.theta = Float64Array.from({length: m}, (_, i) => (th ? th[i] : cfg.theta0));
    this.grad = new Float64Array(m);
    this.used = 0; this.n = first; this.done = false; this.diverged = false;
    this.rec = {batchSize: [], alpha: [], coordinate: [], eps: [], Jhat: [], grad: [], safe: [], nextN: [], c: [],
                theta: [this.vec(this.theta)], J: [this.performance()]};
  }
  /** A vector as the record keeps it: an array, or a number on the 1-D LQG (as learner.js's Run). */
  VectorRun.prototype.vec = function (v) { return this.m === 1 ? v[0] : Array.from(v); };
  VectorRun.prototype.performance = function () {
    if (this.task.kind !== "lqg") return null;
    const J = L.lqgPerformanceN(this.theta, this.cfg.sigma, this.task);
    return J;
  };
  /** One iteration of safepg.learning._learn; false once the run is over. */
  VectorRun.prototype.step = function () {
    if (this.done) return false;
    const cfg = this.cfg, m = this.m, bt = this.batch;
    const n = Math.min(this.n, cfg.budget - this.used);
    if (n < 2) { this.done = true; return false; }
    const found = bt.run(this.theta, cfg.sigma, n, cfg, this.src);
    this.kernel = bt.kernel || "javascript";
    const x = bt.samples, grad = this.grad;
    // numpy's samples.sum(axis=0) adds the rows one after the other.
    let finite = true;
    for (let p = 0; p < m; p++) {
      let acc = 0.0;
      for (let j = 0, o = p * n; j < n; j++) acc += x[o + j];
      grad[p] = acc / n;
      if (!isFinite(grad[p])) finite = false;
    }
    if (!finite) {
      if (!cfg.stopOnDivergence) throw new RangeError(`gradient estimate is not finite at theta=${Array.from(this.theta)}`);
      this.done = this.diverged = true;
      return false;
    }
    const Jhat = L.pairwiseSum(bt.returns, 0, n) / n;
    const up = cfg.algorithm === "adaptive" ? this.adaptive(x, n, found) : this.vanilla(x, n);
    for (let p = 0; p < m; p++) this.theta[p] += up.step[p];
    this.used += n;
    const r = this.rec;
    r.batchSize.push(n); r.alpha.push(up.alpha); r.coordinate.push(up.k); r.eps.push(up.eps); r.Jhat.push(Jhat);
    r.grad.push(this.vec(grad)); r.safe.push(up.safe); r.nextN.push(up.nextN); r.c.push(up.c);
    r.theta.push(this.vec(this.theta)); r.J.push(this.performance());
    this.n = up.nextN;
    return true;
  };
  function argmaxAbs(grad) {
    let k = 0;
    for (let p = 1; p < grad.length; p++) if (Math.abs(grad[p]) > Math.abs(grad[k])) k = p;
    return k;
  }
  /** The rule of safepg.learning.adaptive_pg. */
  VectorRun.prototype.adaptive = function (x, n, found) {
    const cfg = this.cfg, m = this.m, grad = this.grad, k = argmaxAbs(grad), g = Math.abs(grad[k]);
    let kc = this.k, c = this.c;
    if (cfg.constants === "batch") {
      kc = Object.assign({}, this.k, {R: found[0], M: found[1]});
      c = L.penaltyConstant(kc);
    }
    let spread = null;
    if (cfg.statistics === "max") {
      spread = {variance: -Infinity, range: -Infinity};
      for (let p = 0; p < m; p++) {
        const st = rowStats(x, p, n, this.batch.scratch);
        spread.variance = Math.max(spread.variance, st.variance);
        spread.range = Math.max(spread.range, st.range);
      }
    }
    const bd = L.errorBound(cfg, x.subarray(k * n, k * n + n), n, kc, this.batch.scratch, spread);
    const e = L.eps(bd, n);
    const alpha = L.coordinateStep(g, e, c, !cfg.stepWhenUnsafe);
    const step = new Float64Array(m);
    step[k] = alpha * grad[k];
    return {step, alpha, k, eps: e, safe: e < g, c, d: bd.d, f: bd.f,
            nextN: L.optimalBatchSize(g, bd, c, cfg.nMin, cfg.nMax)};
  };
  /** The rule of safepg.learning.vanilla_pg. */
  VectorRun.prototype.vanilla = function (x, n) {
    const cfg = this.cfg, m = this.m, grad = this.grad, k = argmaxAbs(grad);
    let e = 0, safe = true, a = cfg.alpha;
    if (a === null) {
      e = -Infinity;  // one eps for every component: the largest per-component bound
      for (let p = 0; p < m; p++) e = Math.max(e, L.eps(L.errorBound(cfg, x.subarray(p * n, p * n + n), n, this.k, this.batch.scratch), n));
      safe = e < Math.abs(grad[k]);
      a = cfg.step === "scalar" ? scalarStep(grad, e, this.c) : L.coordinateStep(Math.abs(grad[k]), e, this.c, true);
    }
    const step = new Float64Array(m);
    if (cfg.step === "scalar") for (let p = 0; p < m; p++) step[p] = a * grad[p];
    else step[k] = a * grad[k];
    return {step, alpha: a, k: cfg.step === "scalar" ? -1 : k, eps: e, safe, c: this.c, nextN: cfg.batchSize};
  };
  VectorRun.prototype.finish = function () { while (this.step()); return this; };

  /** The 1-D task of learner.js's Run from an lqgTask(dim: 1). */
  function oneDTask(task) {
    return {gamma: task.gamma, H: task.H, bs: task.stateBound, ba: task.actionBound, A: task.A[0], B: task.B[0],
            Q: task.Q[0], Rc: task.R[0], R: task.rewardBound, M: task.featureBound, Avol: task.actionVolume,
            Abar: task.actionBound, clip: task.clip};
  }
  /** Whether a cfg sets an option learner.js's 1-D Run does not have. */
  function needsVectorRun(cfg) {
    const d = VECTOR_DEFAULTS, c = cfg || {};
    return ["nFirst", "constants", "statistics", "stepWhenUnsafe", "step", "stopOnDivergence"]
      .some(k => c[k] !== undefined && c[k] !== d[k]) || c.alpha === null;
  }
  /**
   * A run for any task: learner.js's Run for the 1-D LQG (so its numbers do not change) unless the
   * cfg needs an option only VectorRun has; else a VectorRun.
   */
  function makeRun(cfg, task) {
    if (!task || !task.kind) return new L.Run(cfg, task);
    if (task.kind === "lqg" && task.dim === 1 && !needsVectorRun(cfg)) return new L.Run(cfg, oneDTask(task));
    return new VectorRun(cfg, task);
  }
  L.Driver.makeRun = makeRun;

  Object.assign(L, {VECTOR_DEFAULTS, VectorRun, makeRun, taskConstants, scalarStep, rngSource, arraySource,
                    oneDTask});
})(safepgLearner);
