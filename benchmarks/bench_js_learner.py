"""Speed of the page's JavaScript learner (safepg/thesis/explorers/static/: learner.js and the vector tasks) against
safepg's numba kernels.

Measures, on one core:

- a batch: gradient samples of N = 10^5 trajectories (H = 20) at theta = -0.3, G(PO)MDP and
  REINFORCE with baselines, random numbers included: the JavaScript learner under Node.js,
  and ``LQG.gradient_batch`` (numpy's generator + the fused numba kernel, one thread);
- a run: Algorithm 4.1 for 10^6 trajectories (the explorer's default settings: G(PO)MDP,
  Bernstein with the empirical range, delta = 0.95, sigma = 1), both implementations.

- the doubled-pole cart-pole as the authors ran it (2 m pole, m l = 0.05, 12 deg, undiscounted): 10^5
  trajectories from their theta* (about 190 steps each), in batches of 1000 (their first batch),
  G(PO)MDP with its baseline, random numbers included; budget: 3 s under Node;
- the 2-D adaptive run of Figure 5.7 (table-5.3's "adaptive": gamma = 0.9, Bernstein with the
  empirical range, delta = 0.95, n_max = 500000) at one tenth of its budget, 3*10^6
  trajectories; budget: 2 s. Its batches run on the WebAssembly kernel (lqg2d_wasm.js); the
  same run with the kernel switched off (``..._javascript``: the same record, bit for bit) is
  the time before it;
- both of these inside a Web Worker of headless Chromium as well (wall time; best of --repeat
  after a warm-up run), where the page runs them.

- the 1-D run in headless Chromium (Debian's, through Playwright): the explorer page of
  ``safepg.thesis.explorers.live_learner`` with vanilla PG off, time inside the Web Worker's learner and
  the page's time from the control move to the last curve (worker start, messages and
  drawing included), and the CPU time all of Chromium's processes used meanwhile, for a
  few seeds.

Both wall time and process CPU time are recorded where they can be (the build machine is
shared: CPU time is the steadier figure; the browser gives wall time only). Results go to
``benchmarks/js_learner_timings.json``.

Usage: ``python benchmarks/bench_js_learner.py [--repeat 5] [--no-browser]``. It prints the README table's lines.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from machine import cpu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "js_learner_timings.json"
#: The budgets (s, under Node on the 2-core build machine) of the vector tasks' figures.
TARGETS_S = {"cartpole_1e5": 3.0, "lqg2d_fig57_tenth": 2.0}
#: The budget (s) of the 1-D explorer's default run (10^6 trajectories) in the page's Web Worker. The browser
#: test of the explorer (tests/test_browser_learner.py) reports that run's time and no longer limits it.
EXPLORER_TARGET_S = 1.0

NODE_BENCH = r"""
const L = require(process.argv[2]);
const repeat = +process.argv[3];
const cpu = () => { const u = process.cpuUsage(); return (u.user + u.system) / 1e3; };
function time(f) {  // best of `repeat`, after one warm-up call
  f();
  let wall = Infinity, c = Infinity;
  for (let i = 0; i < repeat; i++) {
    const w0 = performance.now(), c0 = cpu();
    f();
    wall = Math.min(wall, performance.now() - w0); c = Math.min(c, cpu() - c0);
  }
  return {wall_ms: wall, cpu_ms: c};
}
const out = {};
const vec = JSON.parse(process.argv[4]);
const batch1 = new L.LqgBatch(vec.lqg1d), src1 = L.rngSource(new L.Rng(0, 0)), theta1 = Float64Array.of(-0.3);
for (const est of ["gpomdp", "reinforce"])
  out["batch_1e5_" + est] = time(() => batch1.run(theta1, 1, 100000,
                                                  {estimator: est, baseline: true, scoreAction: "clipped"}, src1));
let seed = 0;
out.run_1e6 = time(() => new L.VectorRun({bound: "bernstein", range: "empirical", budget: 1000000, seed: seed++},
                                         vec.lqg1d).finish());
Object.assign(out, vectorBench(L, vec, time));
L.lqg2dWasm.enabled = false;
out.lqg2d_fig57_tenth_javascript = time(() => fig57Tenth(L, vec, 7));
process.stdout.write(JSON.stringify(out));
"""
#: The two vector-task measurements, shared by Node and the Chromium worker.
VECTOR_BENCH = r"""
function fig57Tenth(L, vec, seed) {  // Figure 5.7's adaptive run at a tenth of its budget
  return new L.VectorRun({bound: "bernstein", range: "empirical", budget: 3000000, seed: seed}, vec.lqg2d).finish();
}
function vectorBench(L, vec, time) {
  const out = {}, star = Float64Array.from(vec.theta);
  const cp = new L.CartpoleBatch(vec.cartpole), cpSrc = L.rngSource(new L.Rng(1, 0));
  let steps = 0;
  out.cartpole_1e5 = time(() => {
    steps = 0;
    for (let b = 0; b < 100; b++) {
      cp.run(star, 1, 1000, {estimator: "gpomdp", baseline: true, scoreAction: "clipped"}, cpSrc);
      for (let j = 0; j < 1000; j++) steps += cp.returns[j];
    }
  });
  out.cartpole_1e5.mean_steps = steps / 1e5;
  let seed = 7;
  out.lqg2d_fig57_tenth = time(() => {
    out.lqg2d_fig57_tenth_iterations = fig57Tenth(L, vec, seed++).rec.batchSize.length;
  });
  out.lqg2d_kernel = L.lqg2dWasm.available() ? "webassembly" : "javascript";
  return out;
}
"""
WORKER_PAGE = r"""<!doctype html><html><body><script>
const worker = new Worker(URL.createObjectURL(new Blob([@LEARNER@, @VECTOR_BENCH@, `
onmessage = e => {
  const repeat = e.data.repeat;
  function time(f) {
    f();
    let wall = Infinity;
    for (let i = 0; i < repeat; i++) {
      const w0 = performance.now();
      f();
      wall = Math.min(wall, performance.now() - w0);
    }
    return {wall_ms: wall};
  }
  postMessage(vectorBench(safepgLearner, e.data.vec, time));
};`], {type: "text/javascript"})));
worker.onmessage = e => { window.benchResult = e.data; };
worker.onerror = e => { window.benchResult = {error: String(e.message)}; };
worker.postMessage({vec: @VEC@, repeat: @REPEAT@});
</script></body></html>"""


def best_of(f, repeat: int) -> dict[str, float]:
    """Best wall and CPU time (ms) of ``repeat`` calls, after a warm-up call."""
    f()
    wall, cpu = np.inf, np.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        f()
        wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
    return {"wall_ms": 1e3 * wall, "cpu_ms": 1e3 * cpu}


def chromium_path() -> str | None:
    """Debian's Chromium, if it and Playwright are installed (the browser measurements need both)."""
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return None
    return chromium if Path(chromium).exists() else None


def chromium_runs(seeds: int) -> dict[str, list[float]] | None:
    """Wall times (s) of the explorer's 10^6-trajectory adaptive run in headless Chromium."""
    chromium = chromium_path()
    if chromium is None:
        return None
    import psutil
    from playwright.sync_api import sync_playwright

    from safepg.thesis.explorers.live_learner import live_batch_size_explorer

    def browser_cpu() -> float:
        """CPU seconds used so far by this process's Chromium processes (all of them: an
        upper bound on the worker's own time, which the machine's load does not inflate)."""
        total = 0.0
        for proc in psutil.Process().children(recursive=True):
            try:
                if "chrom" in proc.name():
                    t = proc.cpu_times()
                    total += t.user + t.system
            except psutil.NoSuchProcess:
                pass
        return total

    out: dict[str, list[float]] = {"worker_s": [], "page_s": [], "browser_cpu_s": []}
    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as p:
        page_path = Path(tmp) / "live.html"
        page_path.write_text(f"<!doctype html><html><body>{live_batch_size_explorer().to_html()}</body></html>")
        browser = p.chromium.launch(executable_path=chromium, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_page()
        page.goto(page_path.as_uri())
        done = """job => { const v = JSON.parse(document.querySelector('.safepg-values').textContent);
                           return v.job === job && v.result.values.done; }"""
        page.locator('[data-param="vanilla_n"]').select_option("off")  # job 2
        page.wait_for_function(done, arg=2, timeout=120_000)
        for k in range(seeds):
            cpu0 = browser_cpu()
            page.locator('[data-param="seed"]').fill(str(k + 1))
            page.wait_for_function(done, arg=3 + k, timeout=120_000)
            out["browser_cpu_s"].append(browser_cpu() - cpu0)
            v = json.loads(page.locator(".safepg-values").text_content())["result"]["values"]
            assert v["worker"] and v["adaptive"]["trajectories"] == 1_000_000
            out["worker_s"].append(v["run_ms"]["adaptive"] / 1e3)
            out["page_s"].append(v["elapsed_ms"] / 1e3)
        browser.close()
    return out


def chromium_worker(vec: dict[str, object], repeat: int) -> dict[str, object] | None:
    """The vector tasks' measurements (VECTOR_BENCH) inside a Web Worker of headless Chromium."""
    chromium = chromium_path()
    if chromium is None:
        return None
    from playwright.sync_api import sync_playwright

    from safepg.thesis.explorers.js_tasks import learner_sources

    # The small placeholders first: the learner's text is inserted last, as it is.
    page_html = (WORKER_PAGE.replace("@VEC@", json.dumps(vec)).replace("@REPEAT@", str(repeat))
                 .replace("@VECTOR_BENCH@", json.dumps(VECTOR_BENCH))
                 .replace("@LEARNER@", json.dumps(learner_sources()).replace("</", "<\\/")))
    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as p:
        path = Path(tmp) / "worker.html"
        path.write_text(page_html)
        browser = p.chromium.launch(executable_path=chromium, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_page()
        page.goto(path.as_uri())
        page.wait_for_function("() => window.benchResult !== undefined", timeout=600_000)
        result = page.evaluate("() => window.benchResult")
        browser.close()
    if "error" in result:
        raise RuntimeError(f"the worker failed: {result['error']}")
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-browser", action="store_true", help="skip the headless Chromium runs")
    args = ap.parse_args()
    node = shutil.which("node")
    if node is None:
        raise SystemExit("node is not installed")
    import numba

    from safepg import LQG, adaptive_pg
    from safepg.envs.cartpole import CartPole
    from safepg.options import ErrorModel
    from safepg.policies import LinearGaussianPolicy
    from safepg.thesis.authors import cartpole_theta_star
    from safepg.thesis.experiments import AUTHORS_DOUBLED, make_env
    from safepg.thesis.explorers.js_tasks import cartpole_task_data, learner_sources, lqg_task_data

    numba.set_num_threads(1)
    cartpole, lqg2d = CartPole.thesis_doubled(**AUTHORS_DOUBLED), make_env("lqg2d-gamma0.9")
    star = cartpole_theta_star()
    vec = {"cartpole": cartpole_task_data(cartpole), "lqg2d": lqg_task_data(lqg2d),
           "lqg1d": lqg_task_data(LQG.thesis_1d()), "theta": star.tolist()}
    with tempfile.TemporaryDirectory() as tmp:
        script, learner = Path(tmp) / "bench.js", Path(tmp) / "learner_all.js"
        script.write_text(VECTOR_BENCH + NODE_BENCH)
        learner.write_text(learner_sources())
        js = json.loads(subprocess.run([node, str(script), str(learner), str(args.repeat), json.dumps(vec)],
                                       capture_output=True, text=True, check=True).stdout)
    env = LQG.thesis_1d()
    policy = LinearGaussianPolicy([[-0.3]], 1.0)
    rng = np.random.default_rng(0)
    py = {f"batch_1e5_{est}": best_of(lambda est=est: env.gradient_batch(policy, 100_000, rng, est), args.repeat)
          for est in ("gpomdp", "reinforce")}
    seeds = iter(range(1000))
    # Trajectory-steps of each measurement, for the per-step figures.
    steps = {"batch_1e5_gpomdp": 2e6, "batch_1e5_reinforce": 2e6, "run_1e6": 2e7, "lqg2d_fig57_tenth": 6e7,
             "cartpole_1e5": 1e5 * js["cartpole_1e5"]["mean_steps"]}
    bernstein_er = ErrorModel("bernstein", range="empirical")
    py["run_1e6"] = best_of(lambda: adaptive_pg(env, 0.0, 1.0, error=bernstein_er, budget=1_000_000,
                                                rng=next(seeds)), args.repeat)
    star_policy = LinearGaussianPolicy(star.reshape(1, 4), 1.0)
    py["cartpole_1e5"] = best_of(lambda: [cartpole.gradient_batch(star_policy, 1000, rng) for _ in range(100)],
                                 args.repeat)
    py["lqg2d_fig57_tenth"] = best_of(lambda: adaptive_pg(lqg2d, np.zeros(4), 1.0, error=bernstein_er,
                                                          budget=3_000_000, rng=next(seeds)), args.repeat)
    browser = None if args.no_browser else chromium_runs(args.repeat)
    worker = None if args.no_browser else chromium_worker(vec, args.repeat)
    result = {
        "what": "best of --repeat calls; batch: N = 1e5 trajectories, H = 20, random numbers included; run: "
                "Algorithm 4.1, G(PO)MDP, Bernstein (e.r.), delta 0.95, sigma 1, 1e6 trajectories",
        "machine": {**cpu(),
                    "node": subprocess.run([node, "--version"], capture_output=True, text=True).stdout.strip(),
                    "numba": numba.__version__, "numba_threads": 1,
                    "load_average_1min": round(__import__("os").getloadavg()[0], 2)},
        "javascript_node": js,
        "safepg_numba": py,
        "chromium_explorer_run_1e6": browser and {**browser, "worker_best_s": min(browser["worker_s"]),
                                                  "page_best_s": min(browser["page_s"]),
                                                  "browser_cpu_best_s": min(browser["browser_cpu_s"]),
                                                  "target_s": EXPLORER_TARGET_S,
                                                  "met": min(browser["worker_s"]) <= EXPLORER_TARGET_S},
        "ratio_js_over_numba": {k: {"wall": js[k]["wall_ms"] / py[k]["wall_ms"],
                                    "cpu": js[k]["cpu_ms"] / py[k]["cpu_ms"]} for k in py},
        "per_step_ns_cpu": {f"{impl}_{k}": 1e6 * v[k]["cpu_ms"] / steps[k]
                            for impl, v in (("js", js), ("numba", py)) for k in py},
        "chromium_worker": worker,
        "targets_s": {k: {"target": t, "js_cpu_s": js[k]["cpu_ms"] / 1e3, "js_wall_s": js[k]["wall_ms"] / 1e3,
                          "met_cpu": js[k]["cpu_ms"] / 1e3 <= t,
                          "worker_wall_s": worker and worker[k]["wall_ms"] / 1e3,
                          "met_worker": worker and worker[k]["wall_ms"] / 1e3 <= t} for k, t in TARGETS_S.items()},
    }
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    print("\nREADME table lines:")
    for k, label in (("cartpole_1e5", "cart-pole, 10^5 episodes of the authors' doubled pole from theta* "
                                      f"({js['cartpole_1e5']['mean_steps']:.0f} steps each)"),
                     ("lqg2d_fig57_tenth", "2-D LQG, Figure 5.7's adaptive run at 3*10^6 trajectories")):
        in_worker = f" ({worker[k]['wall_ms'] / 1e3:.2f} s in Chromium's worker)" if worker else ""
        print(f"| {label} | {js[k]['cpu_ms'] / 1e3:.2f} s{in_worker} | {py[k]['cpu_ms'] / 1e3:.2f} s | "
              f"{TARGETS_S[k]:.0f} s |")
    print(f"2-D run with the kernel off: {js['lqg2d_fig57_tenth_javascript']['cpu_ms'] / 1e3:.2f} s (CPU, Node)")


if __name__ == "__main__":
    main()
