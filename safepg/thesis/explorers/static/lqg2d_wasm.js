/*
 * The 2-D LQG's batch as WebAssembly (../wasm/lqg2d_kernel.c): the same bits as
 * LqgBatch.prototype.run2gb fed by the run's own generator, in half the time over a whole run,
 * for the figures' runs (G(PO)MDP with baselines, clipped task and score). The binary travels inline, as
 * base64 (js_tasks.learner_sources fills it in), so the page still needs no file beside it.
 *
 * Concatenated after lqg_task.js. L.lqg2dWasm.run(batch, ...) returns undefined when it cannot
 * run (no WebAssembly, or a source that is not a run's own generator), and the caller then
 * runs the JavaScript; L.lqg2dWasm.enabled = false forces the JavaScript (the tests compare the two).
 */
"use strict";
(function (L) {
  const BASE64 = "@LQG2D_KERNEL_WASM@";
  const FIELDS = 15;  // doubles a trajectory keeps in the kernel (its enum FIELDS)
  // The members of the kernel's io struct, in the order of its io_members.
  const IO_MEMBERS = ["kn", "wn", "fn", "cf", "rng", "found", "exp2"];
  let kernel = null, failed = false;

  function bytes(text) {
    if (typeof atob === "function") return Uint8Array.from(atob(text), ch => ch.charCodeAt(0));
    return Uint8Array.from(Buffer.from(text, "base64"));
  }
  /** The instance, made at first use; null where WebAssembly is missing or refuses the module. */
  function instance() {
    if (kernel || failed) return kernel;
    try {
      const module = new WebAssembly.Module(bytes(BASE64));
      const inst = new WebAssembly.Instance(module, {env: {exp: Math.exp, log: Math.log}});
      const ex = inst.exports, mem = ex.memory.buffer, offsets = new Int32Array(mem, ex.io_members(), IO_MEMBERS.length);
      const at = {};
      IO_MEMBERS.forEach((name, i) => { at[name] = ex.io() + offsets[i]; });
      new Uint32Array(mem, at.kn, 128).set(L.ZIGGURAT.kn);  // integers below 2^31 (the kernel's io.kn)
      for (const name of ["wn", "fn"]) new Float64Array(mem, at[name], 128).set(L.ZIGGURAT[name]);
      new Float64Array(mem, at.exp2, 32).set(Array.from({length: 32}, (_, j) => Math.pow(2, j / 32)));
      kernel = {ex, io: at, base: (ex.__heap_base.value + 15) & ~15, cap: -1};
    } catch (err) {
      failed = true;  // e.g. a main thread that may not compile 5 kB synchronously: the JavaScript runs
    }
    return kernel;
  }
  /** Byte offsets of the kernel's arrays for n trajectories, the memory grown to hold them. */
  function layout(k, n) {
    if (n <= k.cap) return k.at;
    const cap = Math.max(n, Math.ceil(k.cap * 1.5));
    const sizes = {z: 2 * cap, st: 2 * FIELDS * Math.ceil(cap / 2), samples: 4 * cap, returns: cap};
    const at = {};
    let end = k.base;
    for (const [name, doubles] of Object.entries(sizes)) { at[name] = end; end += (8 * doubles + 15) & ~15; }
    const mem = k.ex.memory, short = end - mem.buffer.byteLength;
    if (short > 0) mem.grow(Math.ceil(short / 65536));
    k.cap = cap; k.at = at;
    return at;
  }

  /**
   * LqgBatch.run2gb on the kernel, which draws the initial states and the normals from a copy of
   * the run's generator state; the state comes back advanced as the JavaScript would leave it.
   * Fills batch.samples and batch.returns (its other arrays are the JavaScript's workspace).
   */
  function run(batch, theta, sigma, n, opt, src) {
    if (!L.lqg2dWasm.enabled || !src.rng) return undefined;
    const k = instance();
    if (!k) return undefined;
    const task = batch.task, at = layout(k, n);
    batch.grow(n);
    const buf = k.ex.memory.buffer;
    batch.constants2(theta, sigma, new Float64Array(buf, k.io.cf, 24));
    const state = new Int32Array(buf, k.io.rng, 4);
    state.set(src.rng.s);
    const maxima = opt.batchConstants;
    k.ex.lqg2_gpomdp_baseline(n, task.H, maxima ? 1 : 0, at.z, at.st, at.samples, at.returns);
    src.rng.s.set(state);
    batch.samples.set(new Float64Array(buf, at.samples, 4 * n));
    batch.returns.set(new Float64Array(buf, at.returns, n));
    if (!maxima) return null;
    const found = new Float64Array(buf, k.io.found, 2);
    return [found[0], found[1]];
  }

  L.lqg2dWasm = {enabled: true, run, available: () => instance() !== null,
                 /** The kernel's answer to level < Math.exp(y) (its zig_slow asks it; the tests check it). */
                 belowExp: (level, y) => instance().ex.below_exp(level, y) === 1};
})(safepgLearner);
