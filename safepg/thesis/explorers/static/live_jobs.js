// What the live learners' pages share (live_page.js, ch5_page.js): their runs, thinning and
// number format. A job runs the learner's Driver (passed
// as source, so the worker is built from an inline Blob: no file, no network, file:// works) in
// a Web Worker; starting a job terminates the one in flight, whose late messages the page drops
// by job number. A browser that refuses Blob workers runs the job in slices of the page's thread.
const SAFEPG_WORKER_GLUE = `
self.onmessage = function (e) {
  const msg = e.data;
  try {
    const driver = new safepgLearner.Driver(msg);
    let first = true;
    while (!driver.done) {
      const parts = driver.advance(first ? 15 : msg.every);
      first = false;
      self.postMessage({type: driver.done ? "done" : "progress", job: msg.job, parts: parts});
    }
  } catch (err) {
    self.postMessage({type: "error", job: msg.job, message: String((err && err.message) || err)});
  }
};`;
function safepgThin(n, points) {
  // At most `points` evenly spread indices of 0..n-1, first and last kept (ch5_live.thin).
  if (n <= points) { const o = []; for (let i = 0; i < n; i++) o.push(i); return o; }
  const o = [];
  for (let i = 0; i < points; i++) {
    const k = Math.floor(i * (n - 1) / (points - 1) + 0.5);
    if (!o.length || o[o.length - 1] !== k) o.push(k);
  }
  return o;
}
function safepgFixed(v, d) {
  // A number with d decimals for the summary lines; "-" for none (null, NaN, infinite).
  return (v === null || v === undefined || !isFinite(v)) ? "-" : v.toFixed(d);
}
function SafepgJobs(learnerSrc, receive) {
  // receive(msg): {type: "progress" | "done" | "error", job, parts | message}.
  let url = null, worker = null, local = null;
  try { url = URL.createObjectURL(new Blob([learnerSrc, SAFEPG_WORKER_GLUE], {type: "text/javascript"})); }
  catch (e) { url = null; }
  function runLocally(msg) {
    const L = new Function(learnerSrc + "\nreturn safepgLearner;")();
    const mine = msg.job;
    local = mine;
    let driver;
    (function slice() {
      if (local !== mine) return;  // cancelled by a newer job
      let parts;
      try { driver = driver || new L.Driver(msg); parts = driver.advance(25); }
      catch (err) { receive({type: "error", job: mine, message: String((err && err.message) || err)}); return; }
      receive({type: driver.done ? "done" : "progress", job: mine, parts: parts});
      if (!driver.done) setTimeout(slice, 0);
    })();
  }
  /** Ends the job in flight (its worker terminated, its slices stopped). */
  this.stop = function () {
    local = null;
    if (worker) { worker.terminate(); worker = null; }
  };
  /** Starts msg (msg.job its number) after stopping the job in flight; onPageThread() is called if
   * it ends up on the page's thread after all. Returns whether it runs in a Web Worker. */
  this.start = function (msg, onPageThread) {
    this.stop();
    if (url && typeof Worker !== "undefined") {
      try {
        worker = new Worker(url);
        worker.onmessage = e => { if (e.data.type !== "progress") this.stop(); receive(e.data); };
        worker.onerror = e => {  // a browser that refuses Blob workers: run in the page instead
          e.preventDefault();
          this.stop();
          if (onPageThread) onPageThread();
          runLocally(msg);
        };
        worker.postMessage(msg);
        return true;
      } catch (e) { worker = null; }
    }
    runLocally(msg);
    return false;
  };
}
