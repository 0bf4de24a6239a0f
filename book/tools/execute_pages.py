"""Execute the book's notebooks on every core, into Jupyter Book's execution cache.

``jupyter-book build`` executes the notebooks one after another, as Sphinx reads them, and a
notebook's kernel mostly keeps one core busy. ``make book`` runs this first: it executes the
notebooks the cache does not hold yet, as many at once as the machine has cores, the longest
first, exactly as Jupyter Book would (jupyter-cache's ``single_nb_execution`` in the notebook's
folder, with ``_config.yml``'s timeout and ``allow_errors``), and stores them in the same cache
under the same hash. The build then finds every notebook there and executes none.

Each kernel runs numba's kernels on one thread: the cores are shared among the notebooks
instead (measured: the cart-pole chapter took 55 s beside another notebook with numba's threads
on both cores, 21 s with one thread; a seeded run gives the same numbers on any number of threads).
The chapters' shared scorecard is built first, beside the longest notebook, so that no two
kernels build it at once (:mod:`safepg.thesis.scorecard.stored`).

Usage: ``python book/tools/execute_pages.py`` from the repository's root.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import nbformat
import yaml
from jupyter_cache import get_cache
from jupyter_cache.base import CacheBundleIn

from safepg.thesis.prefetch import chapters

ROOT = Path(__file__).resolve().parents[2]
#: The previous build's execution seconds per notebook (benchmarks/bench_book.py): longest first.
TIMINGS = ROOT / "benchmarks" / "book_timings.json"


def build_scorecard() -> str:
    from safepg.thesis.scorecard import scorecard

    t = time.perf_counter()
    scorecard(root=ROOT / "results")
    return f"scorecard: {time.perf_counter() - t:.1f} s"


def execute(path: str, timeout: int, allow_errors: bool) -> tuple[str, str, float, str | None]:
    """Execute one notebook as myst-nb's cache mode does; (path, executed notebook, seconds, error)."""
    from jupyter_cache.executors.utils import single_nb_execution

    os.environ["NUMBA_NUM_THREADS"] = "1"  # inherited by the kernel this process starts
    nb = nbformat.read(path, as_version=4)
    result = single_nb_execution(nb, cwd=str(Path(path).parent), timeout=timeout, allow_errors=allow_errors,
                                 meta_override=True)
    return path, nbformat.writes(nb), result.time, result.exc_string if result.err is not None else None


def main() -> int:
    config = yaml.safe_load((ROOT / "_config.yml").read_text())["execute"]
    cache = get_cache(str(ROOT / config["cache"]))
    todo = []
    for path in chapters(ROOT / "book"):
        try:
            cache.match_cache_notebook(nbformat.read(path, as_version=4))
        except KeyError:
            todo.append(path)
    if not todo:
        print("execute-pages: every notebook is in the execution cache", flush=True)
        return 0
    try:
        previous = json.loads(TIMINGS.read_text())["notebook_execution_s"]
    except (OSError, KeyError, ValueError):
        previous = {}
    todo.sort(key=lambda p: -previous.get(p.stem, p.stat().st_size / 1e6))
    started = time.perf_counter()
    failed = []
    # spawn: each worker starts clean (no inherited event loop or ZeroMQ context).
    with ProcessPoolExecutor(max_workers=os.cpu_count() or 1,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        card = pool.submit(build_scorecard)
        jobs = [pool.submit(execute, str(p), config["timeout"], config["allow_errors"]) for p in todo]
        print(f"execute-pages: {card.result()}", flush=True)
        for job in as_completed(jobs):
            path, text, seconds, error = job.result()
            if error is not None:
                failed.append(path)
                print(f"execute-pages: {Path(path).name} failed after {seconds:.1f} s:\n{error}", flush=True)
                continue
            # As myst-nb stores what it executed: under the notebook's path, with its execution time.
            record = cache.add_nb_to_project(path)
            cache.cache_notebook_bundle(CacheBundleIn(nbformat.reads(text, as_version=4), record.uri,
                                                      data={"execution_seconds": seconds}),
                                        check_validity=False, overwrite=True)
            print(f"execute-pages: {Path(path).name} in {seconds:.1f} s", flush=True)
    print(f"execute-pages: {len(todo) - len(failed)} of {len(todo)} notebooks executed in "
          f"{time.perf_counter() - started:.0f} s on {os.cpu_count()} cores", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
