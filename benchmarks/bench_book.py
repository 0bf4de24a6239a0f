"""Wall time of the whole book from an empty cache: every chapter, every experiment.

Copies the book (``_config.yml``, ``_toc.yml``, ``book/``) into a temporary folder with
no ``results/`` and no execution cache, runs the same ``jupyter-book build`` as
``make book``, and reads each notebook's execution time from the build's jupyter-cache.
A chapter's time includes the experiments it computes (Chapter 5's campaigns run inside
the first cell that needs them). Writes ``benchmarks/book_timings.json``.

Usage: ``python benchmarks/bench_book.py [--keep DIR]``
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from jupyter_cache import get_cache

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).with_name("book_timings.json")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--keep", type=Path, help="build here (kept) instead of a temp folder")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="safepg-book-"))
    try:
        work.mkdir(parents=True, exist_ok=True)
        for name in ("_config.yml", "_toc.yml"):
            shutil.copy(ROOT / name, work / name)
        shutil.copytree(ROOT / "book", work / "book", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("_build", ".ipynb_checkpoints"))
        shutil.copytree(ROOT / "benchmarks", work / "benchmarks", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("*.py"))
        assert not (work / "results").exists() and not (work / "_build").exists()
        t0 = time.perf_counter()
        # From inside the copy: _config.yml's cache path is relative to the working directory.
        # This interpreter's jupyter-book (.venv's, whose kernel is the venv's), not the PATH's first.
        subprocess.run([str(Path(sys.executable).with_name("jupyter-book")), "build", ".", "-W", "-n",
                        "--keep-going"], cwd=work, check=True,
                       stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
        cache = get_cache(str(work / "_build" / ".jupyter_cache"))
        chapters = {Path(r.uri).stem: round(r.data["execution_seconds"], 1) for r in cache.list_cache_records()}
        if len(chapters) < sum(1 for _ in (work / "book").glob("*.ipynb")):
            raise RuntimeError(f"only {sorted(chapters)} were executed: the build did not start from empty")
        out = {"cores": os.cpu_count(), "date": time.strftime("%Y-%m-%d"), "build_wall_s": round(wall, 1),
               "notebook_execution_s": dict(sorted(chapters.items(), key=lambda kv: -kv[1])),
               "sphinx_and_overhead_s": round(wall - sum(chapters.values()), 1)}
        OUT.write_text(json.dumps(out, indent=1) + "\n")
        print(json.dumps(out, indent=1))
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
