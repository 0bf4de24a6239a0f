"""Time one adaptive iteration on the 1-D LQG against its random-number floor.

One iteration = simulate N trajectories (H = 20), G(PO)MDP samples with baseline,
Bernstein bound with empirical range, coordinate step and N* search. The floor is the
time NumPy's default generator (PCG64) takes to draw the random numbers that iteration
consumes (N uniforms + N*H normals); the kernel draws its own (safepg.streams).
Run: ``python benchmarks/bench_iteration.py [--repeat R]``.

``--kernel2d`` instead times the 2-D LQG gradient kernels single-threaded (generic m x m
loops against the unrolled m = 2 kernel) at N = 100 and 2000, H = 20, in ns per
trajectory-step, and ``--vanilla2d`` adds the wall time of a 10^4-iteration 2-D
``vanilla_pg`` run in a fresh interpreter (best of ``--repeat``).
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
from safepg.streams import batch_key

FUSED = True


def one_iteration(env: LQG, policy: LinearGaussianPolicy, n: int, rng: np.random.Generator) -> int:
    consts = TaskConstants.from_task(env, policy.sigma)
    c = penalty_constant(consts)
    samples = env.gradient_batch(policy, n, rng)[0] if FUSED else \
        gradient_samples(policy, env.simulate(policy, n, rng), "gpomdp", True)
    grad = samples.mean(axis=0)
    k = int(np.argmax(np.abs(grad)))
    eb = error_bound("bernstein", samples[:, k], 0.95, consts, "gpomdp", "empirical")
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


VANILLA_2D = ("from safepg.envs.lqg import LQG; from safepg.learning import vanilla_pg; "
              "from safepg.options import FixedStep; "
              "import numpy as np, numba; numba.set_num_threads(1); "
              "vanilla_pg(LQG.thesis_2d(gamma=0.9), np.zeros(4), 1.0, batch_size=100, step=FixedStep(1e-6), "
              "budget=1_000_000, rng=0)")


def kernel2d(repeat: int, vanilla: bool) -> list[dict]:
    """Single-threaded ns per trajectory-step of the generic and the m = 2 LQG kernels.

    One thread because the campaign runs one seed per core; the two kernels are timed
    alternately so a neighbour's load affects both alike, and the best time is kept.
    """
    import numba

    from safepg.envs._lqg_kernel import lqg2d_gradient_samples, lqg_gradient_samples

    numba.set_num_threads(1)
    env = LQG.thesis_2d()
    pol = LinearGaussianPolicy([[-0.3, 0.1], [0.05, -0.2]], np.array([[1.0, 0.2], [0.2, 0.5]]))
    A, B, Q, R = env._mats
    kernels = {"generic": lqg_gradient_samples, "m=2": lqg2d_gradient_samples}
    rows = []
    for n in (100, 2000):
        key = batch_key(np.random.default_rng(0))  # the kernels draw the batch's numbers themselves
        args = (pol.gain, pol.cov_chol, pol.precision, A, B, Q, R, key, n, env.horizon, env.gamma, env.state_bound,
                env.action_bound, True, True, False, True)  # G(PO)MDP with baseline, as the campaign
        best = {}
        for name, f in kernels.items():
            f(*args)  # compile / load from cache
            best[name] = np.inf
        for _ in range(repeat * (20 if n == 100 else 4)):  # short calls: more tries
            for name, f in kernels.items():
                t = time.perf_counter()
                f(*args)
                best[name] = min(best[name], time.perf_counter() - t)
        steps = n * env.horizon
        row = {"N": n, **{f"{k}_us": v * 1e6 for k, v in best.items()},
               **{f"{k}_ns_per_step": v / steps * 1e9 for k, v in best.items()}}
        rows.append(row)
        print(f"N={n:>5}  generic {best['generic']*1e6:8.1f} us ({best['generic']/steps*1e9:5.1f} ns/step)   "
              f"m=2 {best['m=2']*1e6:8.1f} us ({best['m=2']/steps*1e9:5.1f} ns/step)   "
              f"x{best['generic']/best['m=2']:.1f}")
    if vanilla:
        walls = []
        for _ in range(repeat):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-c", VANILLA_2D], check=True)
            walls.append(time.perf_counter() - t)
        print(f"2-D vanilla_pg, batch 100, budget 1e6, 1 thread: {min(walls):.2f} s wall (best of {repeat})")
        rows.append({"vanilla2d_wall_s": min(walls)})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--reference", action="store_true", help="time the numpy reference path instead")
    ap.add_argument("--learn", action="store_true", help="also time `python -m safepg learn --budget 3000000`")
    ap.add_argument("--kernel2d", action="store_true", help="time the 2-D kernels instead (single thread)")
    ap.add_argument("--vanilla2d", action="store_true", help="with --kernel2d: also time a 2-D vanilla_pg run")
    args = ap.parse_args()
    if args.kernel2d:
        print(json.dumps(kernel2d(args.repeat, args.vanilla2d)))
        return
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
