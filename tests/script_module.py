"""A script of the repository (a Sphinx extension of book/_ext, a tool of tools/) as a module, for
the tests of its functions: these folders are not packages, and each script is loaded by its path."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]


def load(relative: str) -> ModuleType:
    """The module of the script at ``ROOT / relative`` (for example ``"book/_ext/static_digest.py"``)."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None, path
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
