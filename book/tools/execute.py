"""Re-execute chapter notebooks in place so their committed outputs are current.

Usage: ``python book/tools/execute.py book/preliminaries.ipynb [...]``. nbval then
re-executes them in the tests and compares against these outputs.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient


def main(paths: list[str]) -> None:
    for p in map(Path, paths):
        nb = nbformat.read(p, as_version=4)
        t = time.perf_counter()
        folder = {"metadata": {"path": str(p.parent)}}
        client = NotebookClient(nb, timeout=3600, kernel_name="python3", resources=folder)
        client.execute()
        nbformat.write(nb, p)
        print(f"{p}: {time.perf_counter() - t:.1f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
