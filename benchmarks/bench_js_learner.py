"""Speed of the page's JavaScript learner (safepg/static/learner.js) against safepg's numba kernel.

Measures, on one core:

- a batch: gradient samples of N = 10^5 trajectories (H = 20) at theta = -0.3, G(PO)MDP and
  REINFORCE with baselines, random numbers included: the JavaScript learner under Node.js,
  and ``LQG.gradient_batch`` (numpy's generator + the fused numba kernel, one thread);
- a run: Algorithm 4.1 for 10^6 trajectories (the explorer's default settings: G(PO)MDP,
  Bernstein with the empirical range, delta = 0.95, sigma = 1), both implementations.

Both wall time and process CPU time are recorded (the build machine is shared: CPU time
is the steadier figure). Results go to ``benchmarks/js_learner_timings.json``; the
browser's own time for the same run is measured by ``tests/test_browser_learner.py``.

Usage: ``python benchmarks/bench_js_learner.py [--repeat 5]``
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "js_learner_timings.json"

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
const ws = new L.Workspace(20), rng = new L.Rng(0, 0), draw = L.rngDraw(rng, L.THESIS_1D);
for (const est of ["gpomdp", "reinforce"])
  out["batch_1e5_" + est] = time(() => L.gradientSamples(-0.3, 1, 100000, L.THESIS_1D,
                                                       {estimator: est, baseline: true, score: "clipped"}, ws, draw));
let seed = 0;
out.run_1e6 = time(() => new L.Run({bound: "bernstein", empiricalRange: true, budget: 1000000, seed: seed++}).finish());
process.stdout.write(JSON.stringify(out));
"""


def best_of(f, repeat: int) -> dict[str, float]:
    """Best wall and CPU time (ms) of ``repeat`` calls, after a warm-up call."""
    f()
    wall, cpu = np.inf, np.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        f()
        wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
    return {"wall_ms": 1e3 * wall, "cpu_ms": 1e3 * cpu}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    node = shutil.which("node")
    if node is None:
        raise SystemExit("node is not installed")
    import numba

    from safepg import LQG, adaptive_pg
    from safepg.policies import LinearGaussianPolicy

    numba.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "bench.js"
        script.write_text(NODE_BENCH)
        js = json.loads(subprocess.run([node, str(script), str(ROOT / "safepg" / "static" / "learner.js"),
                                        str(args.repeat)], capture_output=True, text=True, check=True).stdout)
    env = LQG.thesis_1d()
    policy = LinearGaussianPolicy([[-0.3]], 1.0)
    rng = np.random.default_rng(0)
    py = {f"batch_1e5_{est}": best_of(lambda est=est: env.gradient_batch(policy, 100_000, rng, est), args.repeat)
          for est in ("gpomdp", "reinforce")}
    seeds = iter(range(1000))
    py["run_1e6"] = best_of(lambda: adaptive_pg(env, 0.0, 1.0, bound="bernstein", empirical_range=True,
                                                budget=1_000_000, rng=next(seeds)), args.repeat)
    result = {
        "what": "best of --repeat calls; batch: N = 1e5 trajectories, H = 20, random numbers included; run: "
                "Algorithm 4.1, G(PO)MDP, Bernstein (e.r.), delta 0.95, sigma 1, 1e6 trajectories",
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": __import__("os").cpu_count(),
                    "node": subprocess.run([node, "--version"], capture_output=True, text=True).stdout.strip(),
                    "numba": numba.__version__, "numba_threads": 1,
                    "load_average_1min": round(__import__("os").getloadavg()[0], 2)},
        "javascript_node": js,
        "safepg_numba": py,
        "ratio_js_over_numba": {k: {"wall": js[k]["wall_ms"] / py[k]["wall_ms"], "cpu": js[k]["cpu_ms"] / py[k]["cpu_ms"]}
                                for k in js},
        "per_step_ns_cpu": {f"{impl}_{k}": 1e6 * v[k]["cpu_ms"] / (2e6 if k.startswith("batch") else 2e7)
                            for impl, v in (("js", js), ("numba", py)) for k in v},
    }
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
