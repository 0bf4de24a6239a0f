"""Repository-wide pytest setup (loaded for ``tests/`` and for the notebooks in ``book/``).

nbval runs every notebook on the Jupyter kernel named ``python3``. ``make setup`` registers
that kernel inside ``.venv`` (never in ``~/.local``), and the Makefile makes Jupyter look
there first. Refuse to start when the kernel is missing, or when it would run another
interpreter than the one running the tests: the notebooks would then import another
environment's (another clone's) ``safepg`` and test that instead of this one.
"""

from __future__ import annotations

import subprocess
import sys

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
