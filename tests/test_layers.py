"""The import rules of the two layers, read from the source (nothing of ``safepg`` is imported).

- the core (``safepg`` outside ``safepg.thesis``, ``safepg.cli`` and ``safepg.__main__``)
  imports nothing from ``safepg.thesis`` or ``safepg.cli``;
- only ``safepg.__main__`` imports ``safepg.cli``;
- the modules import one another without cycles;
- no module imports another's private names, nor a private module from another directory;
- no module is longer than :data:`MAX_LINES` unless :data:`LONG_MODULES` says why;
- no core module defines the book's campaign machinery (:data:`CAMPAIGN_NAMES`, a prefetch): it is
  ``safepg.thesis.campaign``'s and ``safepg.thesis.prefetch``'s, and the runner only reports to a
  callback it is given.

The graph and the rules are in ``tests/layers.py``; :func:`test_probe_rules_fail` runs them on
small fake trees to show that each rule reports what it should, and nothing on a clean tree.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from layers import (
    Tree,
    cycles,
    importer_violations,
    layer_violations,
    private_violations,
    scan,
    size_violations,
    within,
)

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "safepg"
THESIS = f"{PACKAGE}.thesis"
CLI = f"{PACKAGE}.cli"
ENTRY = f"{PACKAGE}.__main__"
#: A module longer than this is split, or listed in :data:`LONG_MODULES`.
MAX_LINES = 600
#: Modules allowed over :data:`MAX_LINES`: ``{path relative to the repository: why it is one concept}``.
#: An entry is added only with the reason the module cannot be cut into smaller ones, and an
#: entry whose module is gone or back under the limit fails the test. DESIGN.md lists the same.
LONG_MODULES: dict[str, str] = {
    "safepg/envs/cartpole.py": "one task: the batched cart-pole and its gymnasium single-env form share one step "
                               "function, the physical constants and the setting names",
}


#: The book's campaign machinery (safepg.thesis.campaign): no core module defines these names.
CAMPAIGN_NAMES = ("compile_once", "record_timing", "TIMING_FILE")


def check_layers(tree: Tree) -> list[str]:
    """Core modules importing the thesis layer or the command line."""
    return layer_violations(tree, upper=(THESIS, CLI), exempt=(THESIS, CLI, ENTRY))


def check_cli(tree: Tree) -> list[str]:
    """Modules other than the entry point importing the command line."""
    return importer_violations(tree, CLI, allowed=(ENTRY,))


def _defined(path: Path) -> list[tuple[int, str]]:
    """Every name a module's source defines (functions, classes, assignments, at any depth), with its line."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            out.append((node.lineno, node.name))
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            out += [(t.lineno, t.id) for target in targets for t in ast.walk(target) if isinstance(t, ast.Name)]
    return out


def check_campaign(tree: Tree) -> list[str]:
    """Core modules that define the book's campaign machinery: a name of :data:`CAMPAIGN_NAMES`, a
    prefetch (a module or a name with ``prefetch`` in it)."""
    found = []
    for name, module in sorted(tree.modules.items()):
        if within(name, THESIS) or name in (CLI, ENTRY):
            continue
        if "prefetch" in name.rpartition(".")[2].lower():
            found.append(f"{tree.where(name)}: {name} is a prefetch")
        found += [f"{tree.where(name, line)}: {name} defines {n}" for line, n in sorted(_defined(module.path))
                  if n in CAMPAIGN_NAMES or "prefetch" in n.lower()]
    return found


def check_size(tree: Tree, allowed: dict[str, str] = LONG_MODULES) -> list[str]:
    """Modules over :data:`MAX_LINES` lines not allowed by ``allowed``."""
    return size_violations(tree, MAX_LINES, allowed)


def report(what: str, found: list[str]) -> str:
    return f"{len(found)} {what}:\n  " + "\n  ".join(found)


@pytest.fixture(scope="module")
def tree() -> Tree:
    return scan(ROOT / PACKAGE)


def test_scan_sees_the_package(tree: Tree) -> None:
    assert {PACKAGE, CLI, ENTRY, THESIS, f"{PACKAGE}.policies"} <= set(tree.modules)
    assert tree.imports


def test_core_does_not_import_thesis_or_cli(tree: Tree) -> None:
    found = check_layers(tree)
    assert not found, report(f"imports of {THESIS} or {CLI} by the core", found)


def test_core_does_not_define_the_campaign_machinery(tree: Tree) -> None:
    found = check_campaign(tree)
    assert not found, report("definitions of the book's campaign machinery in the core", found)
    # ... and the thesis layer does (a rename there would leave this test checking nothing).
    campaign = tree.modules[f"{THESIS}.campaign"].path
    assert set(CAMPAIGN_NAMES) <= {n for _, n in _defined(campaign)}
    assert f"{THESIS}.prefetch" in tree.modules


def test_only_main_imports_cli(tree: Tree) -> None:
    found = check_cli(tree)
    assert not found, report(f"imports of {CLI} outside {ENTRY}", found)


def test_no_import_cycles(tree: Tree) -> None:
    found = cycles(tree)
    assert not found, report("import cycles", found)


def test_no_private_imports(tree: Tree) -> None:
    found = private_violations(tree)
    assert not found, report("imports of private names or modules", found)


def test_thesis_does_not_use_the_gym_adapter(tree: Tree) -> None:
    """The reproduction runs on the thesis's own tasks; the gymnasium adapter shows the core
    as a library and must not become something the printed numbers depend on."""
    adapter = f"{PACKAGE}.envs.gym_task"
    found = sorted(f"{tree.where(i.importer, i.line)}: {i.importer} imports {i.target}"
                   + ("" if i.name is None else f".{i.name}")
                   for i in tree.imports if within(i.importer, THESIS)
                   and (within(i.target, adapter) or (i.target == f"{PACKAGE}.envs" and i.name == "GymTask")))
    assert not found, report(f"imports of {adapter} by the thesis layer", found)


def test_module_size(tree: Tree) -> None:
    found = check_size(tree)
    assert not found, report(f"modules over {MAX_LINES} lines (split them, or say why in LONG_MODULES)", found)


# ------------------------------------------------------------------ probe
CLEAN = {
    "__init__.py": '"""Package."""\nfrom safepg.core import Thing\nfrom . import util\n__version__ = "0"\n',
    "__main__.py": "from safepg.cli import main\n\nraise SystemExit(main())\n",
    "cli.py": "from safepg import core\n\n\ndef main():\n    from safepg.thesis import report\n    return 0\n",
    # the parent's __init__ imports core; core reaching a sibling through the parent is no edge back
    "core.py": ("from typing import TYPE_CHECKING\n\nfrom safepg import util\nfrom safepg.util import helper\n"
                "\nif TYPE_CHECKING:\n    from safepg.envs import Env\n\n\nclass Thing:\n    pass\n"),
    # importing safepg.envs.env runs safepg/__init__.py, which imports util: implicit, no edge
    "util.py": "import safepg.envs.env as env_module\n\n\ndef helper():\n    return env_module.__name__\n",
    "envs/__init__.py": "from .env import Env\n",
    "envs/env.py": "from . import _kernel\nfrom ._kernel import fast\n\n\nclass Env:\n    pass\n",
    "envs/_kernel.py": "def fast():\n    pass\n",
    "thesis/__init__.py": "",
    "thesis/report.py": ("from safepg import Thing, __version__\nfrom safepg.core import Thing as T\n"
                         "from ..util import helper\n"),
    "long.py": "x = 1\n" * MAX_LINES,
}
#: Each violating file, with the line numbers and fragments its report must show.
DIRTY = {
    "layer.py": "import os\n\n\ndef f():\n    from safepg.thesis import report\n",
    "typed.py": "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    import safepg.thesis.report\n",
    "a.py": "from safepg.b import x\n",
    "b.py": "x = 1\nfrom . import a\n",
    "c.py": "from safepg import Thing\n\nC = Thing\n",
    "__init__.py": CLEAN["__init__.py"] + "from safepg.c import C\n",
    "private.py": "from safepg.core import _hidden\nimport safepg.util as u\n\nu._cache.clear()\n",
    "envs/_kernel.py": "def fast():\n    pass\n\n\n_hidden = 0\n",
    "reach.py": "from safepg.envs._kernel import fast\n\n\ndef g():\n    from safepg.envs import _kernel\n",
    "thesis/runner.py": "from safepg.cli import main\n",
    "huge.py": "x = 1\n" * (MAX_LINES + 1),
}


def write(root: Path, files: dict[str, str]) -> Tree:
    for name, text in files.items():
        path = root / PACKAGE / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return scan(root / PACKAGE)


def test_probe_clean_tree_passes(tmp_path: Path) -> None:
    tree = write(tmp_path, CLEAN)
    assert len(tree.modules) == len(CLEAN)
    assert check_layers(tree) == []
    assert check_cli(tree) == []
    assert cycles(tree) == []
    assert private_violations(tree) == []
    assert check_size(tree, allowed={}) == []  # long.py is at the limit, not over


def test_probe_rules_fail(tmp_path: Path) -> None:
    tree = write(tmp_path, {**CLEAN, **DIRTY})

    assert check_layers(tree) == [
        "safepg/layer.py:5: safepg.layer imports safepg.thesis.report",
        "safepg/typed.py:4: safepg.typed imports safepg.thesis.report",
    ]
    assert check_cli(tree) == ["safepg/thesis/runner.py:1: safepg.thesis.runner imports safepg.cli"]
    assert cycles(tree) == [
        "safepg -> safepg.c -> safepg  (safepg/__init__.py:5, safepg/c.py:1)",
        "safepg.a -> safepg.b -> safepg.a  (safepg/a.py:1, safepg/b.py:2)",
    ]
    assert private_violations(tree) == [
        "safepg/private.py:1: safepg.private imports the private name _hidden of safepg.core",
        "safepg/private.py:4: safepg.private reads the private name _cache of safepg.util",
        "safepg/reach.py:1: safepg.reach imports the private module safepg.envs._kernel, private to safepg.envs",
        "safepg/reach.py:5: safepg.reach imports the private module safepg.envs._kernel, private to safepg.envs",
    ]
    assert check_size(tree, allowed={}) == [f"safepg/huge.py:1: {MAX_LINES + 1} lines (> {MAX_LINES})"]
    assert check_size(tree, allowed={"safepg/huge.py": "one table", "safepg/gone.py": "split"}) == [
        "safepg/gone.py: in the allow-list but absent",
    ]


def test_probe_campaign_rule_fails(tmp_path: Path) -> None:
    """The campaign machinery in the core is reported, name by name; in the thesis layer it is not."""
    tree = write(tmp_path, {**CLEAN,
                            "runner.py": ("import json\n\nTIMING_FILE = 'timing.jsonl'\n\n\n"
                                          "def record_timing(folder):\n    pass\n"),
                            "envs/warm.py": "def run():\n    def compile_once(configs):\n        return 0\n",
                            "book_prefetch.py": "x = 1\n",
                            "tasks.py": "class Prefetcher:\n    pass\n",
                            "thesis/campaign.py": ("TIMING_FILE = 'timing.jsonl'\n\n\n"
                                                   "def compile_once(configs):\n    return 0\n"),
                            "thesis/prefetch.py": "def prefetch():\n    pass\n"})
    assert check_campaign(tree) == [
        "safepg/book_prefetch.py: safepg.book_prefetch is a prefetch",
        "safepg/envs/warm.py:2: safepg.envs.warm defines compile_once",
        "safepg/runner.py:3: safepg.runner defines TIMING_FILE",
        "safepg/runner.py:6: safepg.runner defines record_timing",
        "safepg/tasks.py:1: safepg.tasks defines Prefetcher",
    ]
    assert check_campaign(write(tmp_path / "clean", CLEAN)) == []
