/*
 * The continuous cart-pole of safepg.envs.cartpole for the page's learner (Section 5.3):
 * the same step function (Florian's equations, explicit Euler by default, tau = 0.02),
 * forces clipped to [-actionBound, actionBound] before they act, reward 1 per live step,
 * and the gradient samples of safepg.envs._cartpole_kernel: an episode is followed only
 * while it lives; after its end its cumulative score stays in the baseline's denominators
 * and contributes G_T * sum_{l >= T} b_l to its baseline term.
 *
 * Time runs outside, over the whole batch (the kernel's order), so b_t is known once every
 * live episode has made step t; the live episodes are packed at the front of each row.
 * Concatenated after learner.js (it extends safepgLearner).
 */
"use strict";
(function (L) {
  const check = L.check;  // learner.js's: one argument check for every file of the learner
  /** safepg's CartPole() field by field (camelCase); polemassLength and constantsGamma null as there. */
  const CARTPOLE_DEFAULT = Object.freeze({
    kind: "cartpole", poleLength: 1.0, gamma: 0.99, H: 200, angleThresholdDeg: 41.8, xThreshold: 2.4,
    actionBound: 10.0, featureBound: 10.0, cartMass: 1.0, poleMass: 0.1, gravity: 9.8, tau: 0.02, initBound: 0.05,
    integrator: "euler", rewardBound: 1.0, actionSpaceVolume: null, horizonTerm: "effective", polemassLength: null,
    constantsGamma: null});
  /** A TASK for the Driver: CARTPOLE_DEFAULT with the given settings, checked as CartPole checks them. */
  function cartpoleTask(settings) {
    const t = Object.assign({}, CARTPOLE_DEFAULT, settings || {}, {kind: "cartpole"});
    check(t.gamma > 0 && t.gamma <= 1, `gamma must be in (0, 1], got ${t.gamma}`);
    check(Number.isInteger(t.H) && t.H >= 1, `H must be a positive integer, got ${t.H}`);
    for (const k of ["poleLength", "angleThresholdDeg", "xThreshold", "actionBound", "featureBound", "cartMass",
                     "poleMass", "gravity", "tau", "initBound", "rewardBound"])
      check(Number.isFinite(t[k]) && t[k] > 0, `${k} must be finite and > 0, got ${t[k]}`);
    for (const k of ["actionSpaceVolume", "polemassLength"])
      check(t[k] == null || (Number.isFinite(t[k]) && t[k] > 0), `${k} must be finite and > 0 or null, got ${t[k]}`);
    check(t.constantsGamma == null || (t.constantsGamma > 0 && t.constantsGamma <= 1),
          `constantsGamma must be in (0, 1] or null, got ${t.constantsGamma}`);
    check(t.integrator === "euler" || t.integrator === "semi-implicit",
          `integrator must be euler or semi-implicit, got ${t.integrator}`);
    check(["effective", "truncated", "horizon"].includes(t.horizonTerm),
          `horizonTerm must be effective, truncated or horizon, got ${t.horizonTerm}`);
    check(t.initBound < Math.min(t.xThreshold, t.angleThresholdDeg * Math.PI / 180),
          `initBound must leave the initial state alive, got ${t.initBound}`);
    return t;
  }
  function physics(task) {
    const half = 0.5 * task.poleLength;
    return {half, ml: task.polemassLength == null ? task.poleMass * half : task.polemassLength,
            total: task.cartMass + task.poleMass, poleMass: task.poleMass, gravity: task.gravity, tau: task.tau,
            semi: task.integrator === "semi-implicit"};
  }
  /** safepg.envs.cartpole.step_dynamics for one state [x, x_dot, beta, beta_dot] and a (clipped) force. */
  function cartpoleStep(state, force, task) {
    const p = physics(cartpoleTask(task)), out = new Float64Array(4);
    const [x, xd, b, bd] = state, sin = Math.sin(b), cos = Math.cos(b);
    const push = (force + p.ml * bd * bd * sin) / p.total;
    const bAcc = (p.gravity * sin - cos * push) / (p.half * (4.0 / 3.0 - p.poleMass * cos * cos / p.total));
    const xAcc = push - p.ml * bAcc * cos / p.total;
    out[1] = xd + p.tau * xAcc;
    out[3] = bd + p.tau * bAcc;
    out[0] = x + p.tau * (p.semi ? out[1] : xd);
    out[2] = b + p.tau * (p.semi ? out[3] : bd);
    return Array.from(out);
  }

  const ROWS = ["x", "xd", "b", "bd", "G0", "G1", "G2", "G3", "F0", "F1", "F2", "F3", "B0", "B1", "B2", "B3",
                "P0", "P1", "P2", "P3"];
  /** Workspace of the cart-pole's batches: packed rows of the live episodes, outputs by episode. */
  function CartpoleBatch(task) {
    this.task = cartpoleTask(task); this.cap = 0; this.H = this.task.H;
    this.disc = new Float64Array(this.H + 1); this.b = new Float64Array(this.H * 4);
    this.endedSq = new Float64Array((this.H + 1) * 4); this.suffix = new Float64Array((this.H + 1) * 4);
    this.disc[0] = 1.0;
    for (let t = 0; t < this.H; t++) this.disc[t + 1] = this.disc[t] * this.task.gamma;
    this.ret = new Float64Array(this.H + 1);  // sum_{t<T} gamma^t: REINFORCE's return of a length-T episode
    for (let t = 0; t < this.H; t++) this.ret[t + 1] = this.ret[t] + this.disc[t];
  }
  CartpoleBatch.prototype.grow = function (n) {
    if (n <= this.cap) return;
    const cap = Math.max(n, Math.ceil(this.cap * 1.5));
    this.S = new Float64Array(ROWS.length * cap); this.z = new Float64Array(cap); this.idx = new Int32Array(cap);
    this.samples = new Float64Array(4 * cap); this.lastG = new Float64Array(4 * cap);
    this.bAcc = new Float64Array(4 * cap); this.returns = new Float64Array(cap); this.scratch = new Float64Array(cap);
    this.init = new Float64Array(4 * cap);
    this.cap = cap;
  };
  /**
   * n gradient samples (component p of episode j at p * n + j) and undiscounted returns (the
   * episode lengths) with gain theta (4 entries). src.init(s, n, 4, lo, hi) fills the initial
   * states (s[i * n + j]); src.step(z, live, 1, t, idx) the normals of the live episodes
   * (idx: their indices in the batch). Returns [R, M_phi] measured on the batch: 1 and the
   * largest |state component| visited (initial and final states included), as
   * CartPole.gradient_batch_constants.
   */
  CartpoleBatch.prototype.run = function (theta, sigma, n, opt, src) {
    const task = this.task, H = this.H, ph = physics(task);
    const half = ph.half, ml = ph.ml, total = ph.total, pm = ph.poleMass, grav = ph.gravity, tau = ph.tau;
    const semi = ph.semi, ab = task.actionBound, xt = task.xThreshold;
    const at = task.angleThresholdDeg * Math.PI / 180;  // math.radians
    const reinforce = opt.estimator === "reinforce", baseline = !!opt.baseline, scoreClipped = opt.scoreAction !== "raw";
    const gb = baseline && !reinforce, w = reinforce ? 0.0 : 1.0;
    this.grow(n);
    const cap = this.cap, S = this.S, z = this.z, idx = this.idx, disc = this.disc, b = this.b;
    const samples = this.samples, lastG = this.lastG, bAcc = this.bAcc, returns = this.returns, endedSq = this.endedSq;
    const X = 0, XD = cap, BE = 2 * cap, BD = 3 * cap, G = 4 * cap, F = 8 * cap, BB = 12 * cap, P = 16 * cap;
    S.fill(0, 0, ROWS.length * cap); endedSq.fill(0); b.fill(0);
    src.init(this.init, n, 4, -task.initBound, task.initBound);
    for (let i = 0; i < 4; i++) for (let j = 0; j < n; j++) {
      const v = this.init[i * n + j];
      S[i * cap + j] = v; S[P + i * cap + j] = Math.abs(v);
    }
    for (let j = 0; j < n; j++) idx[j] = j;
    const k0 = theta[0], k1 = theta[1], k2 = theta[2], k3 = theta[3], invVar = 1.0 / (sigma * sigma);
    let live = n, dead0 = 0, dead1 = 0, dead2 = 0, dead3 = 0;
    for (let t = 0; t < H && live > 0; t++) {
      src.step(z, live, 1, t, idx);
      const dt = disc[t], ww = w * dt;
      let n0 = 0, n1 = 0, n2 = 0, n3 = 0, d0 = 0, d1 = 0, d2 = 0, d3 = 0;
      for (let j = 0; j < live; j++) {
        let s0 = S[X + j], s1 = S[XD + j], s2 = S[BE + j], s3 = S[BD + j];
        const mean = k0 * s0 + k1 * s1 + k2 * s2 + k3 * s3;
        const aRaw = mean + sigma * z[j];
        const u = Math.min(Math.max(aRaw, -ab), ab);
        const d = ((scoreClipped ? u : aRaw) - mean) * invVar;
        const c0 = S[G + j] + d * s0, c1 = S[G + cap + j] + d * s1;
        const c2 = S[G + 2 * cap + j] + d * s2, c3 = S[G + 3 * cap + j] + d * s3;
        S[G + j] = c0; S[G + cap + j] = c1; S[G + 2 * cap + j] = c2; S[G + 3 * cap + j] = c3;
        S[F + j] += c0 * ww; S[F + cap + j] += c1 * ww; S[F + 2 * cap + j] += c2 * ww; S[F + 3 * cap + j] += c3 * ww;
        if (gb) {
          n0 += c0 * c0 * dt; n1 += c1 * c1 * dt; n2 += c2 * c2 * dt; n3 += c3 * c3 * dt;
          d0 += c0 * c0; d1 += c1 * c1; d2 += c2 * c2; d3 += c3 * c3;
        }
        const sin = Math.sin(s2), cos = Math.cos(s2);
        const push = (u + ml * s3 * s3 * sin) / total;
        const bAccel = (grav * sin - cos * push) / (half * (4.0 / 3.0 - pm * cos * cos / total));
        const xAccel = push - ml * bAccel * cos / total;
        const v1 = s1 + tau * xAccel, v3 = s3 + tau * bAccel;
        s0 = s0 + tau * (semi ? v1 : s1);
        s2 = s2 + tau * (semi ? v3 : s3);
        s1 = v1; s3 = v3;
        S[X + j] = s0; S[XD + j] = s1; S[BE + j] = s2; S[BD + j] = s3;
        const a0 = Math.abs(s0), a1 = Math.abs(s1), a2 = Math.abs(s2), a3 = Math.abs(s3);
        if (a0 > S[P + j]) S[P + j] = a0;
        if (a1 > S[P + cap + j]) S[P + cap + j] = a1;
        if (a2 > S[P + 2 * cap + j]) S[P + 2 * cap + j] = a2;
        if (a3 > S[P + 3 * cap + j]) S[P + 3 * cap + j] = a3;
      }
      if (gb) {
        // b_t = num_t / den_t, the denominators with the final G^2 of the episodes already over.
        const e = t * 4;
        dead0 += endedSq[e]; dead1 += endedSq[e + 1]; dead2 += endedSq[e + 2]; dead3 += endedSq[e + 3];
        const D0 = d0 + dead0, D1 = d1 + dead1, D2 = d2 + dead2, D3 = d3 + dead3;
        const b0 = D0 !== 0 ? n0 / D0 : 0, b1 = D1 !== 0 ? n1 / D1 : 0;
        const b2 = D2 !== 0 ? n2 / D2 : 0, b3 = D3 !== 0 ? n3 / D3 : 0;
        b[e] = b0; b[e + 1] = b1; b[e + 2] = b2; b[e + 3] = b3;
        for (let j = 0; j < live; j++) {
          S[BB + j] += S[G + j] * b0; S[BB + cap + j] += S[G + cap + j] * b1;
          S[BB + 2 * cap + j] += S[G + 2 * cap + j] * b2; S[BB + 3 * cap + j] += S[G + 3 * cap + j] * b3;
        }
      }
      // Episodes whose new state is outside the thresholds (or NaN) end after t + 1 steps; the pack closes up.
      let kept = 0;
      for (let j = 0; j < live; j++) {
        if (Math.abs(S[X + j]) <= xt && Math.abs(S[BE + j]) <= at) {
          if (kept !== j) {
            idx[kept] = idx[j];
            for (let r = 0; r < ROWS.length; r++) S[r * cap + kept] = S[r * cap + j];
          }
          kept += 1;
          continue;
        }
        this._finish(j, idx[j], t + 1, n);
        if (gb && t + 1 < H) {
          const e = (t + 1) * 4;
          for (let p = 0; p < 4; p++) { const g = S[G + p * cap + j]; endedSq[e + p] += g * g; }
        }
      }
      live = kept;
    }
    for (let j = 0; j < live; j++) this._finish(j, idx[j], H, n);
    let peak = 0;
    for (let i = 0; i < 4 * n; i++) if (this.init[i] > peak) peak = this.init[i];  // the peaks, moved there
    if (reinforce) {
      for (let p = 0; p < 4; p++) {
        const o = p * n;
        let nb = 0.0, db = 0.0;
        for (let j = 0; j < n; j++) {
          const g = lastG[o + j], r = this.ret[returns[j]];
          samples[o + j] = g * r;
          nb += g * g * r; db += g * g;
        }
        if (baseline) {
          const bp = db !== 0 ? nb / db : 0;
          for (let j = 0; j < n; j++) samples[o + j] -= lastG[o + j] * bp;
        }
      }
    } else if (gb) {
      const suffix = this.suffix;
      suffix.fill(0);
      for (let t = H - 1; t >= 0; t--) for (let p = 0; p < 4; p++) suffix[t * 4 + p] = suffix[(t + 1) * 4 + p] + b[t * 4 + p];
      for (let p = 0; p < 4; p++) for (let j = 0; j < n; j++) {
        const o = p * n + j;
        samples[o] -= bAcc[o] + lastG[o] * suffix[returns[j] * 4 + p];
      }
    }
    return [1.0, peak];
  };
  /** Episode `to` of the batch, packed at j, ended after T steps: its sums leave the pack. */
  CartpoleBatch.prototype._finish = function (j, to, T, n) {
    const S = this.S, cap = this.cap;
    for (let p = 0; p < 4; p++) {
      const o = p * n + to;
      this.samples[o] = S[(8 + p) * cap + j];
      this.bAcc[o] = S[(12 + p) * cap + j];
      this.lastG[o] = S[(4 + p) * cap + j];
      this.init[o] = S[(16 + p) * cap + j];
    }
    this.returns[to] = T;
  };

  Object.assign(L, {CARTPOLE_DEFAULT, cartpoleTask, cartpoleStep, CartpoleBatch});
})(safepgLearner);
