"""Import graph of a Python package read from its source with ``ast`` (nothing is imported).

:func:`scan` parses every ``.py`` file under a package directory and records each import
statement, wherever it stands (module level, inside functions, under ``if TYPE_CHECKING:``),
as :class:`Import` records resolved to the package's own modules:

- ``import a.b.c`` and ``import a.b.c as x`` import the module ``a.b.c``; the implicit imports
  of the parent packages ``a`` and ``a.b`` are not recorded;
- ``from . import x`` and ``from ..m import y`` are resolved against the importing file's
  package (a package's ``__init__`` is its own package);
- ``from p import name`` imports the module ``p.name`` when ``p.name`` is a module (a file or a
  package directory), and otherwise the name ``name`` from ``p`` itself (its ``__init__`` when
  ``p`` is a package); ``from p import *`` imports the name ``*`` from ``p``.

Attribute reads such as ``m._x``, where ``m`` was bound by an import of one of the package's
modules, are recorded separately (:attr:`Tree.attributes`) for the private-name rule.

The rule functions return one readable line per violation, each naming the file and line.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Module:
    """One module of the package: its dotted name, its file, whether it is a package's ``__init__``."""

    name: str
    path: Path
    is_package: bool

    @property
    def directory(self) -> str:
        """Dotted name of the package whose directory holds the file."""
        return self.name if self.is_package else self.name.rpartition(".")[0]


@dataclass(frozen=True)
class Import:
    """One imported thing: ``importer`` imports module ``target``, or the name ``name`` defined in it."""

    importer: str
    target: str
    line: int
    name: str | None = None


@dataclass
class Tree:
    """The modules of one package and every import (and module-attribute read) among them."""

    root: Path  # the directory holding the package directory (paths are shown relative to it)
    package: str
    modules: dict[str, Module] = field(default_factory=dict)
    imports: list[Import] = field(default_factory=list)
    attributes: list[Import] = field(default_factory=list)

    def where(self, module: str, line: int | None = None) -> str:
        """``path/to/file.py:line`` of a module, relative to :attr:`root`."""
        path = self.modules[module].path.relative_to(self.root).as_posix()
        return path if line is None else f"{path}:{line}"

    def is_internal(self, name: str) -> bool:
        """True when the dotted name lies in the package."""
        return name == self.package or name.startswith(self.package + ".")


def is_private(name: str) -> bool:
    """True for ``_x``; false for public names and dunders such as ``__version__``."""
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def within(name: str, prefix: str) -> bool:
    """True when the dotted ``name`` is ``prefix`` or lies under it."""
    return name == prefix or name.startswith(prefix + ".")


def scan(package_dir: Path) -> Tree:
    """Parse every ``.py`` file under ``package_dir`` (the directory of the top-level package)."""
    package_dir = Path(package_dir)
    tree = Tree(root=package_dir.parent, package=package_dir.name)
    files = sorted(p for p in package_dir.rglob("*.py")
                   if not any(part == "__pycache__" or part.startswith(".")
                              for part in p.relative_to(package_dir).parts))
    for path in files:
        parts = list(path.relative_to(tree.root).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts.pop()
        name = ".".join(parts)
        if name in tree.modules and not is_package:
            continue  # ``m.py`` next to ``m/__init__.py``: Python imports the package
        tree.modules[name] = Module(name, path, is_package)
    for module in tree.modules.values():
        _read_imports(tree, module)
    return tree


def _resolve_from(tree: Tree, module: Module, node: ast.ImportFrom) -> str | None:
    """The dotted module a ``from ... import`` statement reads from, or None when outside reach."""
    if node.level == 0:
        return node.module
    base = module.directory.split(".")
    if node.level - 1 >= len(base):
        return None
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _read_imports(tree: Tree, module: Module) -> None:
    source = ast.parse(module.path.read_text(encoding="utf-8"), filename=str(module.path))
    bound: dict[str, str] = {}  # local name -> internal module it was bound to by an import
    for node in ast.walk(source):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if not tree.is_internal(alias.name):
                    continue
                tree.imports.append(Import(module.name, alias.name, node.lineno))
                if alias.asname:
                    bound[alias.asname] = alias.name
                else:
                    head = alias.name.partition(".")[0]
                    bound[head] = head
        elif isinstance(node, ast.ImportFrom):
            base = _resolve_from(tree, module, node)
            if base is None or not tree.is_internal(base):
                continue
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                if sub in tree.modules:
                    tree.imports.append(Import(module.name, sub, node.lineno))
                    bound[alias.asname or alias.name] = sub
                else:
                    tree.imports.append(Import(module.name, base, node.lineno, alias.name))
    if not bound:
        return
    for node in ast.walk(source):
        if not isinstance(node, ast.Attribute):
            continue
        chain: list[str] = []
        value: ast.expr = node
        while isinstance(value, ast.Attribute):
            chain.append(value.attr)
            value = value.value
        if not isinstance(value, ast.Name) or value.id not in bound:
            continue
        chain.reverse()
        target = bound[value.id]
        for attr in chain:
            if f"{target}.{attr}" in tree.modules:
                target = f"{target}.{attr}"
                continue
            tree.attributes.append(Import(module.name, target, node.lineno, attr))
            break


# ------------------------------------------------------------------ rules
def layer_violations(tree: Tree, upper: Iterable[str], exempt: Iterable[str]) -> list[str]:
    """Imports, by a module outside ``exempt``, of anything under one of the ``upper`` prefixes."""
    upper, exempt = tuple(upper), tuple(exempt)
    found = []
    for imp in tree.imports:
        if any(within(imp.importer, e) for e in exempt):
            continue
        imported = imp.target if imp.name is None else f"{imp.target}.{imp.name}"
        if any(within(imp.target, u) for u in upper):
            found.append(f"{tree.where(imp.importer, imp.line)}: {imp.importer} imports {imported}")
    return sorted(set(found))


def importer_violations(tree: Tree, target: str, allowed: Iterable[str]) -> list[str]:
    """Imports of ``target`` (or anything under it) by a module not in ``allowed``."""
    allowed = set(allowed)
    return sorted({f"{tree.where(imp.importer, imp.line)}: {imp.importer} imports {imp.target}"
                   for imp in tree.imports
                   if within(imp.target, target) and imp.importer not in allowed
                   and not within(imp.importer, target)})


def edges(tree: Tree) -> dict[str, dict[str, list[int]]]:
    """The import graph among the package's modules: ``{importer: {imported: [lines]}}``.

    An import of a module is an edge to it; an import of a name is an edge to the module
    defining it (a package's ``__init__``). Self-imports are left out.
    """
    graph: dict[str, dict[str, list[int]]] = {m: {} for m in tree.modules}
    for imp in tree.imports:
        if imp.target in tree.modules and imp.target != imp.importer:
            graph[imp.importer].setdefault(imp.target, []).append(imp.line)
    return graph


def _components(graph: Mapping[str, Mapping[str, list[int]]]) -> list[list[str]]:
    """Strongly connected components of more than one module (iterative Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return sorted(found)


def _shortest_path(graph: Mapping[str, Mapping[str, list[int]]], start: str, goal: str,
                   allowed: set[str]) -> list[str]:
    """Shortest path ``start -> ... -> goal`` through ``allowed`` modules (breadth first)."""
    previous: dict[str, str | None] = {start: None}
    frontier = [start]
    while frontier and goal not in previous:
        following = []
        for node in frontier:
            for child in sorted(graph[node]):
                if child in allowed and child not in previous:
                    previous[child] = node
                    following.append(child)
        frontier = following
    path: list[str] = []
    node: str | None = goal
    while node is not None:
        path.append(node)
        node = previous[node]
    return path[::-1]


def cycles(tree: Tree) -> list[str]:
    """Import cycles, as chains ``a -> b -> a`` with the file and line of every edge.

    Every edge lying on some cycle is shown on at least one chain: for each such edge
    ``u -> v`` (taken in order), the shortest cycle through it unless an earlier chain shows it.
    """
    graph = edges(tree)
    found = []
    for component in _components(graph):
        members = set(component)
        shown: set[tuple[str, str]] = set()
        for u in component:
            for v in sorted(graph[u]):
                if v not in members or (u, v) in shown:
                    continue
                chain = [u] + _shortest_path(graph, v, u, members)
                shown.update(zip(chain, chain[1:]))
                lines = ", ".join(f"{tree.where(a)}:{','.join(map(str, sorted(set(graph[a][b]))))}"
                                  for a, b in zip(chain, chain[1:]))
                found.append(f"{' -> '.join(chain)}  ({lines})")
    return found


def private_violations(tree: Tree) -> list[str]:
    """Imports of another module's private names, and of private modules from another directory.

    A name is private when it starts with one underscore (dunders are public). A module is
    private when a component of its dotted name is private; it may be imported only by
    modules whose file lies in the directory holding it, or inside it when it is a package.
    """
    found = set()
    for imp in tree.attributes:
        if imp.target != imp.importer and imp.name is not None and is_private(imp.name):
            found.add(f"{tree.where(imp.importer, imp.line)}: {imp.importer} reads the private name "
                      f"{imp.name} of {imp.target}")
    for imp in tree.imports:
        if imp.target == imp.importer:
            continue
        where = tree.where(imp.importer, imp.line)
        if imp.name is not None and is_private(imp.name):
            found.add(f"{where}: {imp.importer} imports the private name {imp.name} of {imp.target}")
        parts = imp.target.split(".")
        for i, part in enumerate(parts):
            if not is_private(part):
                continue
            home, private = ".".join(parts[:i]), ".".join(parts[: i + 1])
            if tree.modules[imp.importer].directory != home and not within(imp.importer, private):
                found.add(f"{where}: {imp.importer} imports the private module {private}, "
                          f"private to {home}")
            break
    return sorted(found)


def line_counts(tree: Tree) -> dict[str, int]:
    """Lines of every file of the package, by path relative to :attr:`Tree.root`."""
    return {tree.where(m.name): len(m.path.read_text(encoding="utf-8").splitlines())
            for m in tree.modules.values()}


def size_violations(tree: Tree, limit: int, allowed: Mapping[str, str]) -> list[str]:
    """Files over ``limit`` lines not in ``allowed``, and ``allowed`` entries no longer needed."""
    counts = line_counts(tree)
    found = [f"{path}:1: {n} lines (> {limit})" for path, n in sorted(counts.items())
             if n > limit and path not in allowed]
    found += [f"{path}: in the allow-list but {'absent' if path not in counts else f'{counts[path]} lines'}"
              for path in sorted(allowed) if counts.get(path, 0) <= limit]
    return found

