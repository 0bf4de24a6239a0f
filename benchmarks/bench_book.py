"""The book from empty, and its campaign against the random-number floor.

1. Measures this machine's random-number generators on every core at once: NumPy's bit
   generators (PCG64, PCG64DXSM, SFC64, Philox, MT19937; ``standard_normal`` and ``random``
   into a preallocated buffer, one process per core) and safepg's own streams
   (:mod:`safepg.streams`, numba threads on every core). The fastest NumPy generator sets
   the floor: the time it needs to draw a computation's normals and uniforms.
2. Copies the book (``_config.yml``, ``_toc.yml``, ``book/``) into a folder with no
   ``results/`` and no execution cache and runs what ``make book`` runs (``python -m safepg
   run-book``, then ``jupyter-book build``); each notebook's execution time comes from the build's jupyter-cache.
3. Reads what the build computed from its results store (:mod:`safepg.thesis.budget`): per
   experiment and per chapter, the trajectories, steps and random numbers, the floor, the
   measured time and their ratio.

Writes ``benchmarks/book_timings.json`` and prints the Markdown tables of the README.

Usage: ``python benchmarks/bench_book.py [--keep DIR]``; ``--results DIR`` only re-reads the
store (and the execution cache) of an earlier build in DIR.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

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
    out["safepg streams"] = {"normal": n_streams * per / (time.perf_counter() - t0)}
    return out


def chapter_times(work: Path) -> dict[str, float]:
    """Each notebook's execution seconds from the build's jupyter-cache."""
    from jupyter_cache import get_cache

    cache = get_cache(str(work / "_build" / ".jupyter_cache"))
    return {Path(r.uri).stem: round(r.data["execution_seconds"], 1) for r in cache.list_cache_records()}


def build(work: Path) -> float:
    """Build the book from empty in ``work``; its wall time."""
    work.mkdir(parents=True, exist_ok=True)
    for name in ("_config.yml", "_toc.yml"):
        shutil.copy(ROOT / name, work / name)
    shutil.copytree(ROOT / "book", work / "book", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("_build", ".ipynb_checkpoints"))
    shutil.copytree(ROOT / "benchmarks", work / "benchmarks", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("*.py"))
    assert not (work / "results").exists() and not (work / "_build").exists()
    t0 = time.perf_counter()
    # As `make book`: the chapters' experiments first, then the pages (the notebooks read the stored runs).
    subprocess.run([sys.executable, "-m", "safepg", "run-book", "--book", str(work / "book"),
                    "--root", str(work / "results")], cwd=work, check=True)
    run_book = time.perf_counter() - t0
    # From inside the copy: _config.yml's cache path is relative to the working directory.
    # This interpreter's jupyter-book (.venv's, whose kernel is the venv's), not the PATH's first.
    subprocess.run([str(Path(sys.executable).with_name("jupyter-book")), "build", ".", "-W", "-n", "--keep-going"],
                   cwd=work, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    print(f"book from empty: {wall / 60:.1f} min, of which run-book {run_book / 60:.1f} min", flush=True)
    if len(chapter_times(work)) < sum(1 for _ in (work / "book").glob("*.ipynb")):
        raise RuntimeError("some notebooks were not executed: the build did not start from empty")
    return wall


def machine() -> dict[str, object]:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = None
    return {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__,
            "load_average_1min_at_end": load}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--keep", type=Path, help="build here (kept) instead of a temp folder")
    ap.add_argument("--results", type=Path,
                    help="no build: read the store and cache of an earlier build in this folder")
    args = ap.parse_args()
    rates = generator_rates()
    numpy_rates = {k: v for k, v in rates.items() if k.startswith("numpy")}
    fastest = max(numpy_rates, key=lambda k: numpy_rates[k]["normal"])
    normal_rate = numpy_rates[fastest]["normal"]
    uniform_rate = max(v["uniform"] for v in numpy_rates.values())
    work = args.results or args.keep or Path(tempfile.mkdtemp(prefix="safepg-book-"))
    try:
        wall = None if args.results else build(work)
        from safepg.thesis.budget import budget_rows, campaign, markdown

        chapters = chapter_times(work)
        budget = budget_rows(campaign(work / "results"), normal_rate, uniform_rate, chapters)
        out = {"date": time.strftime("%Y-%m-%d"), "cores": os.cpu_count(), "machine": machine(),
               "build_wall_s": None if wall is None
               else round(wall, 1), "notebook_execution_s": dict(sorted(chapters.items(), key=lambda kv: -kv[1])),
               "generators_per_s_all_cores": {k: {kk: float(f"{vv:.4g}") for kk, vv in v.items()}
                                              for k, v in rates.items()},
               "floor_generator": fastest, "floor_normal_rate": float(f"{normal_rate:.4g}"),
               "floor_uniform_rate": float(f"{uniform_rate:.4g}"), **budget}
        if wall is not None:
            out["sphinx_and_overhead_s"] = round(wall - sum(chapters.values()), 1)
        OUT.write_text(json.dumps(out, indent=1) + "\n")
        print(json.dumps({k: out[k] for k in ("machine", "build_wall_s", "notebook_execution_s", "floor_generator",
                                              "generators_per_s_all_cores")}, indent=1))
        print(markdown(budget))
    finally:
        if args.keep is None and args.results is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
