"""The pendulum task's speed: its fused learning kernel, the generic GymTask path, and the chapter's
campaign from empty.

1. **The fused learning kernel** (``Pendulum.gradient_batch``: simulation, G(PO)MDP samples with the
   variance-minimising baseline, the returns) on both cores (numba's threads), N = 20 000 episodes
   of H = 200 steps at a gain that swings the pendulum (the speed limit binds, a third of the
   torques are clipped); steps a second, best of ``--repeat``, in a fresh process per CPU setting:
   numba compiling for the host (AVX-512 here) and for ``haswell`` (AVX2, no AVX-512), each with an
   empty numba cache of its own.
2. **The generic path**: ``GymTask("Pendulum-v1", ...)`` simulates through gymnasium's vector API
   (``SyncVectorEnv``, one Python ``step`` per episode and time step), then the estimators; steps a
   second of a batch of 200 episodes, best of ``--repeat``.
3. **The campaign from empty** (``safepg.comparison.run_comparison(pendulum_comparison())``, what
   ``run-book`` computes for the chapter), in a fresh process with an empty results folder and an
   empty numba cache, numba compiling for ``haswell``, on every core: its wall time.

Writes ``benchmarks/pendulum_timings.json`` (with the CPU's name and flags) and prints a table.
Usage: ``python benchmarks/bench_pendulum.py [--repeat R] [--skip-campaign]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from machine import cpu

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).with_name("pendulum_timings.json")
N, H = 20_000, 200

KERNEL = textwrap.dedent("""
    import json, sys, time
    import numba, numpy as np
    from safepg.envs.pendulum import Pendulum
    from safepg.policies import LinearGaussianPolicy
    task, repeat, N, H = Pendulum(), int(sys.argv[1]), int(sys.argv[2]), 200
    policy = LinearGaussianPolicy(np.array([[0.0, -1.0, 1.0]]), 1.0)
    t0 = time.perf_counter()
    task.gradient_batch(policy, 1000, 0, "gpomdp", True, "raw")  # compiles the kernels
    compile_s = time.perf_counter() - t0
    best = {}
    for threads in (1, numba.config.NUMBA_NUM_THREADS):
        numba.set_num_threads(threads)
        times = []
        for k in range(repeat + 1):
            t = time.perf_counter()
            task.gradient_batch(policy, N, k, "gpomdp", True, "raw")
            times.append(time.perf_counter() - t)
        best[threads] = min(times[1:])
    print(json.dumps({"compile_s": compile_s, "threads": numba.config.NUMBA_NUM_THREADS,
                      "steps_per_s": {str(k): N * H / v for k, v in best.items()}}))
""")

CAMPAIGN = textwrap.dedent("""
    import json, sys, time
    from pathlib import Path
    t0 = time.perf_counter()
    from safepg.comparison import pendulum_comparison, run_comparison
    res = run_comparison(pendulum_comparison(), Path(sys.argv[1]))
    print(json.dumps({"seconds": time.perf_counter() - t0, "runs": sum(len(v) for v in res.records.values())}))
""")


def run(code: str, args: list[str], env: dict[str, str]) -> dict[str, object]:
    full = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CPU_NAME", "NUMBA_CACHE_DIR")}
    full.update(env)
    out = subprocess.run([sys.executable, "-c", code, *args], env=full, cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    return dict(json.loads(out.strip().splitlines()[-1]))


def gym_rate(repeat: int, n: int = 200) -> float:
    """Steps a second of ``GymTask("Pendulum-v1")``: a batch simulated and its G(PO)MDP samples."""
    import numpy as np

    from safepg.envs.gym_task import GymTask
    from safepg.estimators import gradient_samples
    from safepg.policies import LinearGaussianPolicy

    task = GymTask("Pendulum-v1", horizon=H, gamma=0.99, reward_bound=16.2736044, feature_bound=8.0)
    policy = LinearGaussianPolicy(np.array([[0.0, -1.0, 1.0]]), 1.0)
    times = []
    for k in range(repeat + 1):
        t = time.perf_counter()
        gradient_samples(policy, task.simulate(policy, n, k), "gpomdp", True, "raw")
        times.append(time.perf_counter() - t)
    return n * H / min(times[1:])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--skip-campaign", action="store_true")
    args = ap.parse_args()
    # The host is shared: the load before and after says whether another program ran meanwhile.
    result: dict[str, object] = {"date": time.strftime("%Y-%m-%d %H:%M"), "cpu": cpu(), "N": N, "H": H,
                                 "load_average_1min_at_start": os.getloadavg()[0]}
    kernels = {}
    with tempfile.TemporaryDirectory() as tmp:
        for setting, env in (("host", {}), ("haswell", {"NUMBA_CPU_NAME": "haswell"})):
            kernels[setting] = run(KERNEL, [str(args.repeat), str(N)], {**env, "NUMBA_CACHE_DIR": f"{tmp}/{setting}"})
        result["kernel"] = kernels
        result["gym_task_steps_per_s"] = gym_rate(args.repeat)
        if not args.skip_campaign:
            result["campaign_from_empty"] = run(CAMPAIGN, [f"{tmp}/results"],
                                                {"NUMBA_CPU_NAME": "haswell", "NUMBA_CACHE_DIR": f"{tmp}/campaign"})
    both = str(kernels["haswell"]["threads"])
    result["load_average_1min_at_end"] = os.getloadavg()[0]
    ours = float(kernels["haswell"]["steps_per_s"][both])  # type: ignore[index]
    result["speedup_over_gym_task"] = ours / float(result["gym_task_steps_per_s"])  # type: ignore[arg-type]
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    c = result["cpu"]
    print(f"CPU: {c['model']} ({c['cores']} cores, AVX2 {c['avx2']}, AVX-512 {c['avx512f']}); load average "  # type: ignore[index]
          f"{result['load_average_1min_at_start']:.2f} before, {result['load_average_1min_at_end']:.2f} after")
    for setting, k in kernels.items():
        rates = ", ".join(f"{t} thread(s) {float(v):.3g}" for t, v in k["steps_per_s"].items())  # type: ignore[attr-defined]
        print(f"fused learning kernel, numba for {setting}: {rates} steps/s (compiled in {k['compile_s']:.1f} s)")
    print(f"GymTask (gymnasium's vector API): {result['gym_task_steps_per_s']:.3g} steps/s; "
          f"the kernel on {both} threads (AVX2) is {result['speedup_over_gym_task']:.0f} times faster")
    if "campaign_from_empty" in result:
        print(f"the chapter's campaign from empty (AVX2): {result['campaign_from_empty']['seconds']:.1f} s")  # type: ignore[index]


if __name__ == "__main__":
    main()
