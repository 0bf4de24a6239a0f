/*
 * Algorithm 4.1 and vanilla policy gradient (safepg.learning.adaptive_pg / vanilla_pg) on every
 * task of the page: the LQG of lqg_task.js in any dimension (the 1-D LQG of Section 5.1 is m = 1)
 * and the cart-pole of cartpole_task.js, with the authors' departures (constants measured per
 * batch, maxima over components, the unguarded step) and the fixed-N steps of Section 5.2.1 (the
 * scalar step of [24], the coordinate step Lambda*). A run's configuration uses the option
 * objects' own names (options.js, generated from safepg.options). Concatenated last (it extends
 * safepgLearner and sets Driver.makeRun).
 */
"use strict";
(function (L) {
  const check = L.check;  // learner.js's: one argument check for every file of the learner
  const O = L.OPTIONS;  // options.js: every option's name, default and allowed values
  /** The page's own settings beside the run's options, as the table states them: the stream of a seed
   *  (the runs of one seed draw apart). */
  const PAGE_FIELDS = Object.freeze({stream: {integer: true, default: 0}});

  function allowed(e, v) {
    if (e.types) return e.types.includes(v) || (v === null && !!e.nullable);
    if (v === null) return !!e.nullable;
    if (e.choices && e.choices.includes(v)) return true;
    if (e.integer && Number.isInteger(v)) return true;
    if (e.number && typeof v === "number" && !Number.isNaN(v)) return true;
    return !!e.list && (Array.isArray(v) || ArrayBuffer.isView(v));
  }
  function describe(e) {
    const kinds = [];
    if (e.types) kinds.push(...e.types.map(t => JSON.stringify(t)));
    if (e.choices) kinds.push(...e.choices.map(c => JSON.stringify(c)));
    if (e.integer) kinds.push("an integer");
    if (e.number) kinds.push("a number");
    if (e.list) kinds.push("a list of numbers");
    if (e.nullable) kinds.push("null");
    return kinds.join(" or ");
  }
  /**
   * A run's configuration completed from the option table: every option of its method (method:
   * "Adaptive" or "Vanilla", the types' names of safepg.options), each given or its default.
   * A name that is no option of this run, a value outside an option's values, or a missing
   * required option throws, naming it.
   */
  function runOptions(cfgIn) {
    const given = cfgIn || {};
    const cfg = {method: given.method === undefined ? "Adaptive" : given.method};
    check(O.methods.includes(cfg.method), `method must be one of ${O.methods.join(", ")}, got ${cfg.method}`);
    const known = new Set(["method"]);
    const fill = (name, e) => {
      known.add(name);
      const v = name in given ? given[name] : e.default;
      check(v !== undefined, `${name} is required for a ${cfg.method} run`);
      check(allowed(e, v), `${name} must be ${describe(e)}, got ${JSON.stringify(v)}`);
      cfg[name] = v;
      return v;
    };
    const visit = type => {
      for (const [name, e] of Object.entries(O.types[type])) {
        if (e.nested) visit(e.types[0]);
        else if (e.types) { const t = fill(name, e); if (t !== null) visit(t); }
        else fill(name, e);
      }
    };
    visit(cfg.method);
    for (const [name, e] of Object.entries({...O.run, ...PAGE_FIELDS})) fill(name, e);
    for (const name of Object.keys(given))
      check(known.has(name), `${name} is not an option of this ${cfg.method} run (its options: ${[...known].join(", ")})`);
    return cfg;
  }

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

  /** The checks of the option objects' __post_init__ that the table cannot state; the first batch's size. */
  function checkCfg(cfg, m) {
    check(cfg.target === undefined || cfg.target === null, "target: the page learner runs no target protocol");
    if (cfg.delta !== undefined) check(cfg.delta > 0 && cfg.delta < 1, `delta must be in (0, 1), got ${cfg.delta}`);
    check(cfg.sigma > 0 && isFinite(cfg.sigma), `sigma must be finite and > 0, got ${cfg.sigma}`);
    if (typeof cfg.range === "number")
      check(isFinite(cfg.range) && cfg.range > 0, `range must be "lemma", "empirical" or finite and > 0, got ${cfg.range}`);
    const th = Array.isArray(cfg.theta0) || ArrayBuffer.isView(cfg.theta0) ? Array.from(cfg.theta0) : null;
    check(th === null ? Number.isFinite(cfg.theta0) : th.length === m && th.every(Number.isFinite),
          `theta0 must be a finite number or ${m} finite numbers, got ${cfg.theta0}`);
    let first;
    if (cfg.method === "Adaptive") {
      check(cfg.nMin >= 2, `nMin must be an integer >= 2, got ${cfg.nMin}`);
      check(cfg.nMin <= cfg.nMax, `nMin must be <= nMax, got ${cfg.nMin} > ${cfg.nMax}`);
      check(cfg.first === null || cfg.first >= 2, `first must be an integer >= 2 or null, got ${cfg.first}`);
      first = cfg.first === null ? cfg.nMin : cfg.first;
    } else {
      check(cfg.batchSize >= 2, `batchSize must be an integer >= 2, got ${cfg.batchSize}`);
      if (cfg.step === "FixedStep") check(isFinite(cfg.alpha) && cfg.alpha >= 0, `alpha must be finite and >= 0, got ${cfg.alpha}`);
      first = cfg.batchSize;
    }
    check(cfg.budget >= first, `budget must be an integer >= the first batch size ${first}, got ${cfg.budget}`);
    return first;
  }

  /**
   * A learning run, one iteration at a time (so a worker can report progress and be stopped
   * between batches). cfg: see runOptions; task: lqgTask or cartpoleTask; src: the random numbers
   * (rngSource of the cfg's seed and stream by default).
   * rec: batchSize, alpha, coordinate, eps, Jhat, grad (arrays), safe, nextN, c (I each);
   * theta (arrays) and J (closed form for the LQG, null for the cart-pole) (I + 1).
   */
  function VectorRun(cfgIn, task, src) {
    const cfg = runOptions(cfgIn);
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
  /** A vector as the record keeps it: an array, or a number on the 1-D LQG. */
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
    const x = bt.samples;
    if (!this.gradient(x, n)) {
      if (!cfg.stopOnDivergence) throw new RangeError(`gradient estimate is not finite at theta=${Array.from(this.theta)}`);
      this.done = this.diverged = true;
      return false;
    }
    const Jhat = L.pairwiseSum(bt.returns, 0, n) / n;
    const up = cfg.method === "Adaptive" ? this.adaptive(x, n, found) : this.vanilla(x, n);
    for (let p = 0; p < m; p++) this.theta[p] += up.step[p];
    this.used += n;
    const r = this.rec;
    r.batchSize.push(n); r.alpha.push(up.alpha); r.coordinate.push(up.k); r.eps.push(up.eps); r.Jhat.push(Jhat);
    r.grad.push(this.vec(this.grad)); r.safe.push(up.safe); r.nextN.push(up.nextN); r.c.push(up.c);
    r.theta.push(this.vec(this.theta)); r.J.push(this.performance());
    this.n = up.nextN;
    return true;
  };
  /**
   * this.grad: the mean of the batch's samples x (component p of trajectory j at p * n + j) as
   * safepg computes it, samples.sum(axis=0) / n. numpy sums an (n, 1) array pairwise and an
   * (n, m) array row after row; true when every component is finite.
   */
  VectorRun.prototype.gradient = function (x, n) {
    const m = this.m, grad = this.grad;
    let finite = true;
    for (let p = 0; p < m; p++) {
      let acc = 0.0;
      if (m === 1) acc = L.pairwiseSum(x, 0, n);
      else for (let j = 0, o = p * n; j < n; j++) acc += x[o + j];
      grad[p] = acc / n;
      if (!isFinite(grad[p])) finite = false;
    }
    return finite;
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
    if (cfg.batchConstants) {
      kc = Object.assign({}, this.k, {R: found[0], M: found[1]});
      c = L.penaltyConstant(kc);
    }
    let spread = null;
    if (cfg.maxima) {
      spread = {variance: -Infinity, range: -Infinity};
      for (let p = 0; p < m; p++) {
        const st = rowStats(x, p, n, this.batch.scratch);
        spread.variance = Math.max(spread.variance, st.variance);
        spread.range = Math.max(spread.range, st.range);
      }
    }
    const bd = L.errorBound(cfg, x.subarray(k * n, k * n + n), n, kc, this.batch.scratch, spread);
    const e = L.eps(bd, n);
    const alpha = L.coordinateStep(g, e, c, !cfg.unguardedStep);
    const step = new Float64Array(m);
    step[k] = alpha * grad[k];
    return {step, alpha, k, eps: e, safe: e < g, c, d: bd.d, f: bd.f,
            nextN: L.optimalBatchSize(g, bd, c, cfg.nMin, cfg.nMax)};
  };
  /** The rule of safepg.learning.vanilla_pg. */
  VectorRun.prototype.vanilla = function (x, n) {
    const cfg = this.cfg, m = this.m, grad = this.grad, k = argmaxAbs(grad), scalar = cfg.kind === "scalar";
    let e = 0, safe = true, a = cfg.alpha;
    if (cfg.step === "SafeStep") {
      e = -Infinity;  // one eps for every component: the largest per-component bound
      for (let p = 0; p < m; p++) e = Math.max(e, L.eps(L.errorBound(cfg, x.subarray(p * n, p * n + n), n, this.k, this.batch.scratch), n));
      safe = e < Math.abs(grad[k]);
      a = scalar ? scalarStep(grad, e, this.c) : L.coordinateStep(Math.abs(grad[k]), e, this.c, true);
    }
    const step = new Float64Array(m);
    if (scalar) for (let p = 0; p < m; p++) step[p] = a * grad[p];
    else step[k] = a * grad[k];
    return {step, alpha: a, k: scalar ? -1 : k, eps: e, safe, c: this.c, nextN: cfg.batchSize};
  };
  VectorRun.prototype.finish = function () { while (this.step()); return this; };

  L.Driver.makeRun = (cfg, task) => new VectorRun(cfg, task);

  Object.assign(L, {runOptions, VectorRun, taskConstants, scalarStep, rngSource, arraySource});
})(safepgLearner);
