"""Repository-wide pytest setup (loaded for ``tests/`` and for the notebooks in ``book/``).

nbval runs every notebook on the Jupyter kernel named ``python3``; say how to install it
instead of failing on each notebook with ``NoSuchKernel``.
"""

from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    if not (getattr(config.option, "nbval", False) or getattr(config.option, "nbval_lax", False)):
        return
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    try:
        KernelSpecManager().get_kernel_spec("python3")
    except NoSuchKernel:
        raise pytest.UsageError(
            "nbval needs the Jupyter kernel 'python3': run `python -m ipykernel install --user` "
            "(or `make setup`)") from None
