"""Resolve ``{numref}`` reading each target page's doctree once per build, not once per reference.

Sphinx's standard domain resolves a ``{numref}`` by unpickling the whole doctree of the page
that holds the target, only to read the target node's type and ids: the chapters cite their
figures and tables over a hundred times, and their doctrees (outputs included) take about
0.15 s each to unpickle, so the references cost about 20 s of every full build. Here the
lookup reads the doctrees through one unpickled copy per page, kept for the writing phase.
The copies are only read (the target node's type and ids), never written to the pages:
the page being written is still Sphinx's own fresh copy.
"""

from __future__ import annotations

import weakref
from typing import Any

from sphinx.domains.std import StandardDomain

#: Per build environment: document name -> its doctree, as read for numref lookups only.
_DOCTREES: weakref.WeakKeyDictionary[Any, dict[str, Any]] = weakref.WeakKeyDictionary()


class _ReadOnlyDoctrees:
    """The build environment, but ``get_doctree`` returns one shared copy per document."""

    def __init__(self, env: Any) -> None:
        self._env = env
        self._doctrees = _DOCTREES.setdefault(env, {})

    def get_doctree(self, docname: str) -> Any:
        if docname not in self._doctrees:
            self._doctrees[docname] = self._env.get_doctree(docname)
        return self._doctrees[docname]

    def __getattr__(self, name: str) -> Any:
        return getattr(self._env, name)


def _shared_lookup(resolve: Any) -> Any:
    def _resolve_numref_xref(self: Any, env: Any, *args: Any) -> Any:
        return resolve(self, _ReadOnlyDoctrees(env), *args)

    _resolve_numref_xref.shared_lookup = True  # type: ignore[attr-defined]
    return _resolve_numref_xref


def _forget(app: Any, env: Any) -> None:
    # The pages were read again: the copies of the last writing phase may be stale.
    _DOCTREES.pop(env, None)


def setup(app: Any) -> dict[str, Any]:
    if not getattr(StandardDomain._resolve_numref_xref, "shared_lookup", False):
        StandardDomain._resolve_numref_xref = _shared_lookup(StandardDomain._resolve_numref_xref)  # type: ignore[method-assign]
    app.connect("env-updated", _forget)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
