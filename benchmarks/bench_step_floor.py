"""The floors of a simulated step on every core: what a step costs before any estimator.

The campaign's kernels draw their normals with :func:`safepg.streams.draw_normals`, a chunk of
streams at a time, and the cart-pole (the learning runs and ``safety-mc``, whose rollouts are
cart-pole batches) also pays ``safepg.portable``'s sine and cosine at every step. This measures,
with numba's threads on every core and the kernels' own chunking (a chunk of 512 trajectories,
time in the outer loop), the nanoseconds per trajectory-step of

- ``normals``: ``draw_normals`` alone, one normal per trajectory-step (the streams' floor as the
  kernels draw);
- ``cart-pole bare step``: the normal, ``portable.sin_poly``/``cos_poly`` of the angle, the
  clipped linear action and one explicit-Euler step with the library's ``_euler``, and the
  termination test, with no score, no sample and no baseline: what a cart-pole step costs at
  the least with these random numbers and this sine. Every episode runs its 200 steps (a gain
  that balances the pole), so that no packing is measured.

Best of ``--repeat`` timings after a warm-up that compiles. Writes ``benchmarks/step_floor.json``
with the CPU (``benchmarks/machine.py``) and numba's target. Run:
``python benchmarks/bench_step_floor.py`` (``NUMBA_CPU_NAME=haswell`` for AVX2 code).
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
from machine import cpu
from numba import njit, prange

from safepg import portable
from safepg.envs._cartpole_kernel import _euler
from safepg.envs.cartpole import CartPole
from safepg.streams import draw_normals, next_uniform, normal_scratch, stream_start

OUT = Path(__file__).with_name("step_floor.json")
CHUNK = 512  # the cart-pole kernel's chunk
STABLE = np.array([1.0, 2.0, 40.0, 8.0])  # balances the 1 m pole for all 200 steps (bench_cartpole.py)


@njit(cache=True, parallel=True)
def _normals(key, n, horizon):
    """``horizon`` normals for each of n streams, drawn a chunk at a time; their sum."""
    n_chunks = (n + CHUNK - 1) // CHUNK
    sums = np.zeros(n_chunks)
    for c in prange(n_chunks):
        lo = c * CHUNK
        m = min(n, lo + CHUNK) - lo
        st = np.empty(m, dtype=np.uint64)
        for i in range(m):
            st[i] = stream_start(key, lo + i)
        z = np.empty(m)
        scratch = normal_scratch(m)
        acc = 0.0
        for _ in range(horizon):
            draw_normals(st, z, scratch)
            acc += z[0]
        sums[c] = acc
    return sums


@njit(cache=True, parallel=True, error_model="numpy")
def _cartpole_bare(key, n, horizon, K, sigma, bound, consts, init_bound, x_threshold, angle_threshold):
    """``horizon`` bare cart-pole steps of n trajectories; how many stayed alive."""
    half, ml, total, pole_mass, gravity, tau = consts
    n_chunks = (n + CHUNK - 1) // CHUNK
    alive_count = np.zeros(n_chunks)
    for c in prange(n_chunks):
        lo = c * CHUNK
        m = min(n, lo + CHUNK) - lo
        st = np.empty(m, dtype=np.uint64)
        s = np.empty((4, m))
        for i in range(m):
            state = stream_start(key, lo + i)
            for r in range(4):
                v, state = next_uniform(state)
                s[r, i] = -init_bound + (init_bound + init_bound) * v
            st[i] = state
        z = np.empty(m)
        sn = np.empty(m)
        cs = np.empty(m)
        ok = np.empty(m, dtype=np.bool_)
        scratch = normal_scratch(m)
        for _ in range(horizon):
            draw_normals(st, z, scratch)
            for i in range(m):
                sn[i] = portable.sin_poly(s[2, i])
                cs[i] = portable.cos_poly(s[2, i])
            for i in range(m):
                s0, s1, s2, s3 = s[0, i], s[1, i], s[2, i], s[3, i]
                u = min(max(K[0] * s0 + K[1] * s1 + K[2] * s2 + K[3] * s3 + sigma * z[i], -bound), bound)
                s0, s1, s2, s3 = _euler(s0, s1, s2, s3, sn[i], cs[i], u, half, ml, total, pole_mass, gravity, tau)
                s[0, i], s[1, i], s[2, i], s[3, i] = s0, s1, s2, s3
                ok[i] = abs(s0) <= x_threshold and abs(s2) <= angle_threshold
        alive = 0.0
        for i in range(m):
            alive += ok[i]
        alive_count[c] = alive
    return alive_count


def bare_step_shape() -> tuple[object, ...]:
    """``_cartpole_bare``'s arguments after the gain: sigma = 1 and the thesis's 1 m pole."""
    task = CartPole.thesis()  # its angle threshold (0.73 rad) takes portable's polynomials alone
    if task.angle_threshold >= 0.78:
        raise RuntimeError("the kernel's sine needs its range reduction at this threshold: not measured here")
    half = 0.5 * task.pole_length
    consts = (half, task.pole_mass * half, task.cart_mass + task.pole_mass, task.pole_mass, task.gravity, task.tau)
    return 1.0, task.action_bound, consts, task.init_bound, task.x_threshold, task.angle_threshold


def best_ns_per_step(fn: Callable[[], object], steps: int, repeat: int) -> float:
    """Nanoseconds per trajectory-step, best of ``repeat`` after a warm-up."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times) / steps * 1e9


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("-n", type=int, default=32768, help="trajectories per call")
    ap.add_argument("--horizon", type=int, default=200)
    args = ap.parse_args()
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    steps = args.n * args.horizon
    key = np.uint64(12345)
    shape = (STABLE, *bare_step_shape())
    lived = _cartpole_bare(key, args.n, args.horizon, *shape).sum()
    if lived < 0.99 * args.n:
        raise RuntimeError(f"only {lived:.0f} of {args.n} episodes lived {args.horizon} steps: not a bare step")
    normals = best_ns_per_step(lambda: _normals(key, args.n, args.horizon), steps, args.repeat)
    bare = best_ns_per_step(lambda: _cartpole_bare(key, args.n, args.horizon, *shape), steps,
                            args.repeat)
    threads = numba.get_num_threads()
    out = {"date": time.strftime("%Y-%m-%d %H:%M"), "machine": cpu(), "numba_threads": threads,
           "trajectories": args.n, "horizon": args.horizon, "repeat": args.repeat,
           "ns_per_step_all_cores": {"normals": round(normals, 3), "cart-pole bare step": round(bare, 3)},
           "rate_per_s_all_cores": {"normals": float(f"{1e9 / normals:.4g}"),
                                    "cart-pole bare step": float(f"{1e9 / bare:.4g}")}}
    OUT.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
