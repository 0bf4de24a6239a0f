"""Repository-wide pytest setup (loaded for ``tests/`` and for the notebooks in ``book/``).

nbval runs every notebook on the Jupyter kernel named ``python3``. ``make setup`` registers
that kernel inside ``.venv`` (never in ``~/.local``), and the Makefile makes Jupyter look
there first. Refuse to start when the kernel is missing, or when it would run another
interpreter than the one running the tests: the notebooks would then import another
environment's (another clone's) ``safepg`` and test that instead of this one.

Under pytest-xdist the workers already share the cores, so each worker's notebooks run on a
copy of that kernel whose numba starts on one thread (``NUMBA_NUM_THREADS=1`` in the copy's
``env``), as ``book/tools/execute_pages.py`` runs them for the book: beside the other worker,
the cart-pole chapter's longest cell took 28 to 54 s in CI with two threads, under 10 s with
one. The copy has its own name, so ``python3`` itself, which JupyterLab and the setup tests
use, is untouched.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest


def _prefix(python: str) -> str | None:
    """``sys.prefix`` of the interpreter ``python`` (a venv's own folder), or None if it does not run."""
    try:
        return subprocess.run([python, "-c", "import sys; print(sys.prefix)"], capture_output=True, text=True,
                              timeout=60, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None


def pytest_configure(config: pytest.Config) -> None:
    if not (getattr(config.option, "nbval", False) or getattr(config.option, "nbval_lax", False)):
        return
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    try:
        spec = KernelSpecManager().get_kernel_spec("python3")
    except NoSuchKernel:
        raise pytest.UsageError("nbval needs the Jupyter kernel 'python3': run `make setup` (it registers "
                                "the kernel of .venv), then the tests with `make test`") from None
    kernel_python = spec.argv[0]
    if kernel_python != sys.executable and _prefix(kernel_python) != sys.prefix:
        raise pytest.UsageError(
            f"nbval would run the notebooks with {kernel_python} (the kernel 'python3' of "
            f"{spec.resource_dir}), not with {sys.executable} that runs the tests, so with another "
            "safepg: run `make test`, or pytest from the activated .venv (`. .venv/bin/activate`)")
    if hasattr(config, "workerinput") and not config.option.nbval_kernel_name:
        config.option.nbval_kernel_name = _one_thread_kernel(config, spec.to_dict())


ONE_THREAD_KERNEL = "safepg-one-thread"


def _one_thread_kernel(config: pytest.Config, spec: dict) -> str:
    """Register, for this process only, a copy of the kernel ``spec`` whose numba runs one thread."""
    data = tempfile.mkdtemp(prefix="safepg-kernels-")
    config.add_cleanup(lambda: shutil.rmtree(data, ignore_errors=True))
    folder = os.path.join(data, "kernels", ONE_THREAD_KERNEL)
    os.makedirs(folder)
    spec = {**spec, "display_name": f"{spec['display_name']} (numba on one thread)",
            "env": {**spec.get("env", {}), "NUMBA_NUM_THREADS": "1"}}
    with open(os.path.join(folder, "kernel.json"), "w") as f:
        json.dump(spec, f)
    # Last on the path: the copy adds a kernel and shadows none.
    os.environ["JUPYTER_PATH"] = os.pathsep.join(p for p in (os.environ.get("JUPYTER_PATH"), data) if p)
    return ONE_THREAD_KERNEL
