"""Why a chapter's runs stand above their floor: the kernels against the streams, and Python around them.

``bench_book.py`` sets each chapter's campaign against its floor (its normals at the rate our streams
reach, the cart-pole's steps at its bare step's rate). This splits one seed of each chapter's main
experiments into the two parts of that ratio, on one thread as a campaign's worker runs:

- **in the kernels**: the time inside the fused numba kernels the learning loop calls (the LQG's and the
  cart-pole's ``gradient_batch`` kernels; a fixed-step LQG run's whole loop is one compiled kernel, so
  all of it counts here), against the floor of the same work (``kernel / floor``);
- **around them**: the rest of the run, the Python of ``safepg.learning``'s loop (the bound, the step,
  the batch size, the record), as a share of the run (``around``).

The chapters: Section 5.1's ``table-5.2`` (its 12 configurations), Section 5.2's ``table-5.3`` (the
adaptive run, N = 1000 and N = 100), Section 5.3's ``cartpole-baseline`` and ``table-5.4`` (warm-started
from the baseline run measured here).
Each configuration runs seed 0 at its full budget, after a run at a hundredth of it (at least 10^4
trajectories) that compiles and warms up. The floors are measured in the same process on one thread:
``draw_normals`` as the kernels draw (a chunk of 512 streams at a time) and the cart-pole's bare step
(``bench_step_floor.py``'s kernels).

Run: ``python benchmarks/bench_overhead.py`` (``NUMBA_CPU_NAME=haswell`` for AVX2 code); writes
``benchmarks/overhead.json`` with the CPU.
"""

from __future__ import annotations

import argparse
import functools
import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any

import numba
import numpy as np
from bench_step_floor import STABLE, _cartpole_bare, _normals, bare_step_shape, best_ns_per_step
from machine import cpu

from safepg.envs import _cartpole_kernel, _lqg_fixed_step, _lqg_kernel
from safepg.envs.cartpole import CartPole
from safepg.thesis.budget import run_counts
from safepg.thesis.experiments import get_experiment

OUT = Path(__file__).with_name("overhead.json")
#: (chapter, experiments) measured: each chapter's largest experiments.
CHAPTERS = (("lqg1d", ("table-5.2",)), ("lqg2d", ("table-5.3",)), ("cartpole", ("cartpole-baseline", "table-5.4")))
#: The kernels the loop calls from Python, by module: their time is "in the kernels".
ENTRIES = {
    _lqg_kernel: ("lqg1d_gradient_samples", "lqg1d_gradient_samples_serial", "lqg2d_gradient_samples",
                  "lqg2d_gradient_samples_serial", "lqg_gradient_samples", "lqg_gradient_samples_serial"),
    _cartpole_kernel: ("cartpole_gradient_samples",),
}


class Clock:
    """Seconds spent inside the wrapped calls."""

    def __init__(self) -> None:
        self.seconds = 0.0

    def wrap(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(fn)
        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - t0
        return timed


@contextmanager
def kernels_timed(clock: Clock) -> Iterator[None]:
    """The loop's kernel entries wrapped by ``clock`` (module attributes, which the tasks look up at each
    call), and the fixed-step loop's compiled batches."""
    saved = [(mod, name, getattr(mod, name)) for mod, names in ENTRIES.items() for name in names]
    fixed = dict(_lqg_fixed_step.FIXED_STEP_BATCHES)
    try:
        for mod, name, fn in saved:
            setattr(mod, name, clock.wrap(fn))
        for key, fn in fixed.items():
            _lqg_fixed_step.FIXED_STEP_BATCHES[key] = clock.wrap(fn)
        yield
    finally:
        for mod, name, fn in saved:
            setattr(mod, name, fn)
        _lqg_fixed_step.FIXED_STEP_BATCHES.update(fixed)


def measure(repeat: int) -> dict[str, Any]:
    numba.set_num_threads(1)
    key = np.uint64(12345)
    n, horizon = 32768, 200
    normal_ns = best_ns_per_step(lambda: _normals(key, n, horizon), n * horizon, repeat)
    bare_ns = best_ns_per_step(lambda: _cartpole_bare(key, n, horizon, STABLE, *bare_step_shape()), n * horizon,
                               repeat)
    rows = []
    for chapter, names in CHAPTERS:
        finals: dict[str, np.ndarray] = {}
        for name in names:
            exp = get_experiment(name)
            for cfg in exp.configs:
                theta0 = finals.get(cfg.warm_start) if cfg.warm_start is not None else None
                replace(cfg, budget=max(10_000, cfg.budget // 100)).run(0, theta0=theta0)  # compile, warm up
                clock = Clock()
                with kernels_timed(clock):
                    t0 = time.perf_counter()
                    rec = cfg.run(0, theta0=theta0)
                    total = time.perf_counter() - t0
                finals[name] = rec.theta[-1]
                env = cfg.make_task()
                trajectories, steps, normals, _ = run_counts(env, rec)
                floor = (steps * bare_ns if isinstance(env, CartPole) else normals * normal_ns) / 1e9
                rows.append({"chapter": chapter, "experiment": name, "config": cfg.name,
                             "trajectories": trajectories, "iterations": int(rec.batch_size.size),
                             "mean_batch": float(rec.batch_size.mean()), "steps": steps, "normals": normals,
                             "seconds": round(total, 3), "kernel_s": round(clock.seconds, 3),
                             "floor_s": round(floor, 3), "ratio": round(total / floor, 2),
                             "kernel_over_floor": round(clock.seconds / floor, 2),
                             "around": round(1 - clock.seconds / total, 3)})
                print(json.dumps(rows[-1]), flush=True)
    by_chapter = {}
    for chapter, _ in CHAPTERS:
        rs = [r for r in rows if r["chapter"] == chapter]
        total, kernel, floor = (sum(r[k] for r in rs) for k in ("seconds", "kernel_s", "floor_s"))
        by_chapter[chapter] = {"seconds": round(total, 2), "kernel_s": round(kernel, 2), "floor_s": round(floor, 2),
                               "ratio": round(total / floor, 2), "kernel_over_floor": round(kernel / floor, 2),
                               "around": round(1 - kernel / total, 3)}
    return {"date": time.strftime("%Y-%m-%d %H:%M"), "machine": cpu(), "numba_threads": 1,
            "ns_one_thread": {"normal": round(normal_ns, 3), "cart-pole bare step": round(bare_ns, 3)},
            "chapters": by_chapter, "runs": rows}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    out = measure(args.repeat)
    OUT.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out["chapters"], indent=1))


if __name__ == "__main__":
    main()
