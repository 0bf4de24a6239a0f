"""Time one adaptive iteration on the 1-D LQG against its random-number floor.

One iteration = simulate N trajectories (H = 20), G(PO)MDP samples with baseline,
Bernstein bound with empirical range, coordinate step and N* search. The floor is the
time to draw the random numbers that iteration consumes (N uniforms + N*H normals)
with the same generator. Run: ``python benchmarks/bench_iteration.py [--repeat R]``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np

from safepg.bounds import error_bound
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.estimators import gradient_samples
from safepg.meta import coordinate_step, optimal_batch_size, penalty_constant
from safepg.policies import LinearGaussianPolicy

FUSED = True


def one_iteration(env: LQG, policy: LinearGaussianPolicy, n: int, rng: np.random.Generator) -> int:
    consts = TaskConstants.from_task(env, policy.sigma)
    c = penalty_constant(consts)
    samples = env.gradient_batch(policy, n, rng)[0] if FUSED else \
        gradient_samples(policy, env.simulate(policy, n, rng), "gpomdp", True)
    grad = samples.mean(axis=0)
    k = int(np.argmax(np.abs(grad)))
    eb = error_bound("bernstein", samples[:, k], 0.95, consts, "gpomdp", True)
    coordinate_step(abs(grad[k]), eb.eps(n), c)
    return optimal_batch_size(abs(grad[k]), eb, c, 100, 500_000)


def floor(env: LQG, n: int, rng: np.random.Generator) -> None:
    rng.uniform(-2, 2, size=(n, 1))
    rng.standard_normal((n, env.horizon, 1))


def best_time(fn, repeat: int) -> float:
    fn()  # warm-up (JIT, caches)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--reference", action="store_true", help="time the numpy reference path instead")
    ap.add_argument("--learn", action="store_true", help="also time `python -m safepg learn --budget 3000000`")
    args = ap.parse_args()
    global FUSED
    FUSED = not args.reference
    env = LQG.thesis_1d()
    pol = LinearGaussianPolicy([[-0.3]], 1.0)
    rows = []
    for n in (10_000, 100_000, 1_000_000):
        rng = np.random.default_rng(0)
        t_it = best_time(lambda n=n, rng=rng: one_iteration(env, pol, n, rng), args.repeat)
        t_fl = best_time(lambda n=n, rng=rng: floor(env, n, rng), args.repeat)
        steps = n * env.horizon
        rows.append(dict(N=n, iteration_s=t_it, floor_s=t_fl, steps_per_s=steps / t_it,
                         floor_steps_per_s=steps / t_fl, speed_vs_floor=t_fl / t_it))
        print(f"N={n:>9,}  iteration {t_it*1e3:8.2f} ms  ({steps/t_it/1e6:6.1f} M steps/s)   "
              f"RNG floor {t_fl*1e3:7.2f} ms  -> {100*t_fl/t_it:5.1f}% of floor speed")
    if args.learn:
        cmd = [sys.executable, "-m", "safepg", "learn", "--estimator", "gpomdp", "--bound", "bernstein",
               "--empirical-range", "--delta", "0.95", "--budget", "3000000", "--quiet"]
        t = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t
        print(f"`{' '.join(cmd[1:])}`: {wall:.1f} s wall")
        rows.append(dict(learn_3e6_wall_s=wall))
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
