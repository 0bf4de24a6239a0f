"""Time one cart-pole batch: gradient samples + undiscounted returns, numpy path vs fused kernel.

One batch = N = 4000 episodes of at most H = 200 steps, G(PO)MDP samples with baseline
(clipped score) and the episode lengths, at theta = 0 (episodes end after a few dozen
steps) and at a stabilising gain (every episode lasts 200 steps). The numpy path is
``CartPole.simulate`` + ``gradient_samples`` + ``undiscounted_returns``; the fused path
is ``CartPole.gradient_batch``. Best of ``--repeat`` runs after a warm-up (which also
loads or compiles the kernel). Run: ``python benchmarks/bench_cartpole.py [--repeat R]``.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

import numba
import numpy as np

from safepg.envs.cartpole import CartPole
from safepg.estimators import gradient_samples
from safepg.policies import LinearGaussianPolicy

STABLE = np.array([1.0, 2.0, 40.0, 8.0])  # balances the 1 m pole for all 200 steps


def reference(task: CartPole, pol: LinearGaussianPolicy, n: int, rng: np.random.Generator) -> None:
    batch = task.simulate(pol, n, rng)
    gradient_samples(pol, batch, "gpomdp", True, "clipped")
    task.undiscounted_returns(batch)


def fused(task: CartPole, pol: LinearGaussianPolicy, n: int, rng: np.random.Generator) -> None:
    task.gradient_batch(pol, n, rng, "gpomdp", True, "clipped")


def best_time(fn: Callable[[], None], repeat: int) -> float:
    fn()  # warm-up (JIT cache load, page faults)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("-n", type=int, default=4000)
    args = ap.parse_args()
    task = CartPole.thesis()
    rows = []
    print(f"N = {args.n}, H = {task.horizon}, numba threads = {numba.get_num_threads()}")
    print(f"{'theta':<10} {'mean length':>11} {'numpy ms':>9} {'fused ms':>9} {'speed-up':>9}")
    for name, gain in (("0", np.zeros(4)), ("stable", STABLE)):
        pol = LinearGaussianPolicy(gain, 1.0)
        length = task.gradient_batch(pol, args.n, 0)[1].mean()
        t_ref = best_time(lambda pol=pol: reference(task, pol, args.n, np.random.default_rng(0)), args.repeat)
        t_fus = best_time(lambda pol=pol: fused(task, pol, args.n, np.random.default_rng(0)), args.repeat)
        rows.append(dict(theta=name, N=args.n, mean_length=float(length), numpy_s=t_ref, fused_s=t_fus,
                         speedup=t_ref / t_fus))
        print(f"{name:<10} {length:>11.1f} {t_ref * 1e3:>9.2f} {t_fus * 1e3:>9.2f} {t_ref / t_fus:>8.1f}x")
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
