"""The book from empty, and its campaign against the random-number floor.

1. Measures this machine's random-number generators on every core at once: NumPy's bit
   generators (PCG64, PCG64DXSM, SFC64, Philox, MT19937; ``standard_normal`` and ``random``
   into a preallocated buffer, one process per core) and safepg's own streams
   (:mod:`safepg.streams`, numba threads on every core). The fastest NumPy generator sets
   the floor: the time it needs to draw a computation's normals and uniforms.
2. Clones this repository's HEAD into an empty folder and runs there what a first ``make
   book`` runs, phase by phase: ``make setup`` (the venv, by uv; ``--cold`` also empties uv's
   cache), ``make book-assets``, ``python -m safepg run-book``, ``book/tools/execute_pages.py``
   and ``jupyter-book build``, with the share of the cores each phase kept busy.
   Nothing is carried over: no venv, no ``results/``, no execution cache and no numba cache
   (the clone's own ``safepg/__pycache__``). Each notebook's execution time comes from the
   build's jupyter-cache.
3. Reads what the build computed from its results store (:mod:`safepg.thesis.budget`): per
   experiment and per chapter, the trajectories, steps and random numbers, the floor, the
   measured time and their ratio.

Writes ``benchmarks/book_timings.json`` and prints the Markdown tables of the README.

Usage: ``python benchmarks/bench_book.py [--keep DIR] [--cold]``; ``--results DIR`` only re-reads the
store (and the execution cache) of an earlier build in DIR.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from machine import cpu

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).with_name("book_timings.json")
BIT_GENERATORS = ("PCG64", "PCG64DXSM", "SFC64", "Philox", "MT19937")
BUFFER = 1 << 20


def _numpy_rate(args: tuple[str, str, float]) -> tuple[int, float]:
    """(numbers drawn, seconds) by one process drawing for about ``seconds``."""
    name, kind, seconds = args
    gen = np.random.Generator(getattr(np.random, name)(12345))
    buf = np.empty(BUFFER)
    draw = gen.standard_normal if kind == "normal" else gen.random
    draw(out=buf)  # warm
    count, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        draw(out=buf)
        count += BUFFER
    return count, time.perf_counter() - t0


def generator_rates(seconds: float = 1.0) -> dict[str, dict[str, float]]:
    """Numbers per second on all cores at once, by generator and kind (normal, uniform)."""
    cores = os.cpu_count() or 1
    out: dict[str, dict[str, float]] = {}
    with ProcessPoolExecutor(cores) as pool:
        for name in BIT_GENERATORS:
            out[f"numpy {name}"] = {}
            for kind in ("normal", "uniform"):
                res = list(pool.map(_numpy_rate, [(name, kind, seconds)] * cores))
                out[f"numpy {name}"][kind] = sum(c for c, _ in res) / max(s for _, s in res)
    import numba

    from safepg import streams

    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    streams.normal_rate_probe(np.uint64(1), 64, 64)  # compile
    n_streams, per = 200_000, 500
    t0 = time.perf_counter()
    streams.normal_rate_probe(np.uint64(2), n_streams, per)
    out["safepg streams, one by one"] = {"normal": n_streams * per / (time.perf_counter() - t0)}
    floors = step_floors(repeat=3)
    out["safepg streams"] = {"normal": floors["normals"]}
    out["cart-pole bare step"] = {"step": floors["cart-pole bare step"]}
    return out


def step_floors(repeat: int = 3) -> dict[str, float]:
    """Per second on every core: normals as the kernels draw them (``draw_normals``, a chunk of streams
    at a time) and the cart-pole's bare steps (``bench_step_floor.py``)."""
    from bench_step_floor import STABLE, _cartpole_bare, _normals, bare_step_shape, best_ns_per_step

    n, horizon, key = 32768, 200, np.uint64(12345)
    shape = bare_step_shape()
    return {"normals": 1e9 / best_ns_per_step(lambda: _normals(key, n, horizon), n * horizon, repeat),
            "cart-pole bare step": 1e9 / best_ns_per_step(lambda: _cartpole_bare(key, n, horizon, STABLE, *shape),
                                                          n * horizon, repeat)}


def chapter_times(work: Path) -> dict[str, float]:
    """Each notebook's execution seconds from the build's jupyter-cache."""
    from jupyter_cache import get_cache

    cache = get_cache(str(work / "_build" / ".jupyter_cache"))
    return {Path(r.uri).stem: round(r.data["execution_seconds"], 1) for r in cache.list_cache_records()}


def _clean_env(work: Path, cold_cache: Path | None) -> dict[str, str]:
    """The environment of a fresh shell in the clone ``work``, with the Makefile's venv variables."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("VIRTUAL_ENV", "NUMBA_CACHE_DIR", "JUPYTER_PATH", "JUPYTER_PREFER_ENV_PATH", "PYTHONPATH")}
    here = {str(ROOT / ".venv" / "bin"), str(Path(sys.executable).parent)}
    path = [d for d in env.get("PATH", "").split(os.pathsep) if d not in here]
    env["PATH"] = os.pathsep.join([str(work / ".venv" / "bin"), *path])
    if cold_cache is not None:
        env["UV_CACHE_DIR"] = str(cold_cache)
    return env


def _children_cpu() -> float:
    """User and system CPU seconds of this process's waited-for descendants so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def build(work: Path, cold: bool = False) -> dict[str, dict[str, float]]:
    """A first ``make book`` in a fresh clone of HEAD at ``work``; each phase's ``seconds`` and
    ``cores_busy`` (the CPU time of its processes over its wall time on every core)."""
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(work)], check=True)
    cold_cache = work / ".uv-cache" if cold else None
    env = _clean_env(work, cold_cache)
    venv_bin = work / ".venv" / "bin"
    # From inside the clone: _config.yml's cache path is relative to the working directory.
    phases = {
        "setup": ["make", "--no-print-directory", "setup"],
        "book-assets": ["make", "--no-print-directory", "book-assets"],
        "run-book": ["bash", "-c", f"bash book/tools/cache_guard.sh && {venv_bin}/python -m safepg run-book"],
        "notebooks": [str(venv_bin / "python"), "book/tools/execute_pages.py"],
        "pages": [str(venv_bin / "jupyter-book"), "build", ".", "-W", "-n", "--keep-going"],
    }
    measured: dict[str, dict[str, float]] = {}
    for phase, cmd in phases.items():
        t0, cpu0 = time.perf_counter(), _children_cpu()
        subprocess.run(cmd, cwd=work, env=env, check=True,
                       stdout=subprocess.DEVNULL if phase == "pages" else None)
        seconds = time.perf_counter() - t0
        # Every process of the phase, waited for (the workers too): how busy the cores were.
        busy = (_children_cpu() - cpu0) / (seconds * (os.cpu_count() or 1))
        measured[phase] = {"seconds": round(seconds, 1), "cores_busy": round(busy, 2)}
        print(f"{phase}: {seconds:.1f} s, cores {busy:.0%} busy", flush=True)
    wall = wall_seconds(measured)
    print(f"make book from empty: {wall / 60:.1f} min ({wall:.0f} s)", flush=True)
    if len(chapter_times(work)) < sum(1 for _ in (work / "book").glob("*.ipynb")):
        raise RuntimeError("some notebooks were not executed: the build did not start from empty")
    if cold_cache is not None:
        shutil.rmtree(cold_cache, ignore_errors=True)
    return measured


def wall_seconds(phases: dict[str, dict[str, float]]) -> float:
    """The whole build's wall time: its phases' seconds."""
    return sum(p["seconds"] for p in phases.values())


def venv_megabytes(work: Path) -> int:
    """The size of the clone's venv, in MB."""
    return round(sum(f.stat().st_size for f in (work / ".venv").rglob("*") if f.is_file()) / 1e6)


def phases_markdown(phases: dict[str, dict[str, float]]) -> str:
    """The phases of the first ``make book`` as a Markdown table."""
    rows = [f"| `{k}` | {p['seconds']:.1f} | {p['cores_busy']:.0%} |" for k, p in phases.items()]
    return "\n".join(["| phase | seconds | cores busy |", "|---|---:|---:|", *rows,
                      f"| **`make book` from empty** | **{wall_seconds(phases):.0f}** | |"])


def machine() -> dict[str, object]:
    info = cpu()
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = None
    return {"cpu": info["model"], "cores": info["cores"], "avx2": info["avx2"], "avx512f": info["avx512f"],
            "numba_cpu_name": info["numba_cpu_name"], "python": platform.python_version(), "numpy": np.__version__,
            "load_average_1min_at_end": load}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--keep", type=Path, help="clone and build here (kept; must not exist) instead of a temp folder")
    ap.add_argument("--cold", action="store_true", help="also start uv from an empty cache (downloads every package)")
    ap.add_argument("--results", type=Path,
                    help="no build: read the store and cache of an earlier build in this folder")
    args = ap.parse_args()
    rates = generator_rates()
    numpy_rates = {k: v for k, v in rates.items() if k.startswith("numpy")}
    fastest = max(numpy_rates, key=lambda k: numpy_rates[k]["normal"])
    # The floor: our streams' normals as the kernels draw them, measured in this run; the cart-pole's
    # (learning runs and safety-mc) its bare steps, each a normal, a sine and a cosine.
    normal_rate = rates["safepg streams"]["normal"]
    step_rates = {"cartpole": rates["cart-pole bare step"]["step"]}
    uniform_rate = max(v["uniform"] for v in numpy_rates.values())
    work = args.results or args.keep or Path(tempfile.mkdtemp(prefix="safepg-book-")) / "clone"
    try:
        phases = None if args.results else build(work, cold=args.cold)
        from safepg.thesis.budget import budget_rows, campaign, compile_seconds, markdown

        chapters = chapter_times(work)
        works = campaign(work / "results")
        budget = budget_rows(works, normal_rate, uniform_rate, chapters, step_rates)
        numpy_floor = budget_rows(works, numpy_rates[fastest]["normal"], uniform_rate)
        for row, other in zip(budget["chapters"], numpy_floor["chapters"]):
            row[f"ratio_{fastest.split()[-1]}"] = other["ratio"]
        out = {"date": time.strftime("%Y-%m-%d"), "cores": os.cpu_count(), "machine": machine(),
               "build_wall_s": None if phases is None else round(wall_seconds(phases), 1), "phases": phases,
               "venv_MB": None if phases is None else venv_megabytes(work),
               "uv_cache": "cold" if args.cold else "warm",
               "notebook_execution_s": dict(sorted(chapters.items(), key=lambda kv: -kv[1])),
               "generators_per_s_all_cores": {k: {kk: float(f"{vv:.4g}") for kk, vv in v.items()}
                                              for k, v in rates.items()},
               "floor_generator": "safepg streams (draw_normals)", "floor_normal_rate": float(f"{normal_rate:.4g}"),
               "floor_step_rates": {k: float(f"{v:.4g}") for k, v in step_rates.items()},
               "fastest_numpy_generator": fastest,
               "floor_uniform_rate": float(f"{uniform_rate:.4g}"),
               # Part of run-book's time, in no experiment's: the kernels compiled once before them.
               "compile_once_s": compile_seconds(work / "results"), **budget}
        OUT.write_text(json.dumps(out, indent=1) + "\n")
        print(json.dumps({k: out[k] for k in ("machine", "build_wall_s", "phases", "compile_once_s",
                                              "notebook_execution_s", "floor_generator",
                                              "generators_per_s_all_cores")}, indent=1))
        if phases is not None:
            print(phases_markdown(phases) + "\n")
        print(markdown(budget))
    finally:
        if args.keep is None and args.results is None:
            shutil.rmtree(work.parent, ignore_errors=True)


if __name__ == "__main__":
    main()
