"""No silent skip: every skip in the tests fails under ``CI=true`` or is named in the README.

``skip_or_fail`` (tests/conftest.py) skips a test that needs something of the machine, or fails
it under CI, naming what to install. Any other skip must be named, with its reason, in the
README's section "What a test run skips". This file reads every test module and lists each
skip it can make; and it runs pytest on a small folder of tests to show that a run lists its
skips and that, under ``CI=true``, one the README does not name fails the run
(``tests/skip_report.py``).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from skip_report import README, SECTION, named_skips

TESTS = Path(__file__).resolve().parent
#: pytest's calls that skip: their reason is the first argument or ``reason=``.
SKIPS = {"skip", "importorskip", "xfail"}
#: ``pytest.mark.<name>``: skip or expect failure.
SKIP_MARKS = {"skip", "skipif", "xfail"}
#: The helpers of tests/conftest.py that skip, or fail under CI.
GUARDED = {"skip_or_fail", "require_node", "import_or_fail"}


@dataclass(frozen=True)
class Site:
    """One place in a test module that can skip."""

    module: str
    line: int
    call: str
    reason: str | None  # the reason's leading text, when it is a string literal or an f-string's first part
    in_function: str | None


def _literal(node: ast.AST | None) -> str | None:
    """The leading literal text of a string or f-string node."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr) and node.values and isinstance(node.values[0], ast.Constant):
        return str(node.values[0].value)
    return None


def _dotted(node: ast.AST) -> str:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
    return ".".join(reversed(parts))


def skip_sites() -> list[Site]:
    """Every call of pytest's skips and every skip mark in the modules of tests/, and every call of the
    helpers that skip or fail under CI."""
    sites = []
    for path in sorted(TESTS.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        owner: dict[int, str] = {}
        for fn in ast.walk(tree):
            if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                for node in ast.walk(fn):
                    if node is not fn:
                        owner.setdefault(id(node), fn.name)
        called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
        for node in ast.walk(tree):
            if id(node) in called:  # a call's function: the call is the site
                continue
            name = _dotted(node.func) if isinstance(node, ast.Call) else _dotted(node)
            skips = (isinstance(node, ast.Call) and name in {f"pytest.{s}" for s in SKIPS}) or (
                name in {f"pytest.mark.{m}" for m in SKIP_MARKS})
            guarded = isinstance(node, ast.Call) and name in GUARDED
            if not (skips or guarded):
                continue
            reason = None
            if isinstance(node, ast.Call):
                given = [k.value for k in node.keywords if k.arg == "reason"]
                args = node.args[1:] if name == "pytest.mark.skipif" else node.args
                reason = _literal(given[0] if given else (args[0] if args else None))
            sites.append(Site(path.name, node.lineno, name, reason, owner.get(id(node))))
    return sites


SITES = skip_sites()


def test_every_skip_fails_under_ci_or_is_named_in_the_readme() -> None:
    named = named_skips(README.read_text(encoding="utf-8"))
    assert len(named) >= 2, f"the README's section {SECTION!r} names no skip"
    plain = [s for s in SITES if s.call not in GUARDED]
    # pytest's own skips: inside skip_or_fail (the CI guard itself), or with a reason the README names.
    loose = [s for s in plain if not (s.module == "conftest.py" and s.in_function == "skip_or_fail")
             and not (s.reason and any(s.reason.startswith(n) for n in named))]
    assert not loose, "skips that neither go through skip_or_fail nor are named in the README: " + "; ".join(
        f"{s.module}:{s.line} {s.call}({s.reason!r})" for s in loose)
    # Each named reason is still made somewhere (a stale item would name nothing).
    made = [s.reason for s in plain if s.reason]
    assert all(any(r.startswith(n) for r in made) for n in named), (named, made)
    guarded = [s for s in SITES if s.call in GUARDED]
    print(f"\n{len(SITES)} places that can skip: {len(guarded)} through skip_or_fail and its helpers, "
          f"{len(plain)} of pytest's own")
    for s in SITES:
        print(f"  {s.module}:{s.line} {s.call}: {s.reason}")
    assert len(guarded) >= 12 and len(plain) >= 3, (len(guarded), len(plain))


def test_every_module_that_runs_node_is_marked() -> None:
    """A module that starts Node.js (``require_node`` or a helper that calls it) marks its tests ``node``:
    tests/conftest.py then skips them, or fails them under CI, before they run."""
    helpers = ("require_node()", "run_node(", "run_page(")
    users = [p for p in sorted(TESTS.glob("test_*.py")) if any(h in p.read_text(encoding="utf-8") for h in helpers)]
    unmarked = [p.name for p in users if "pytest.mark.node" not in p.read_text(encoding="utf-8")]
    assert len(users) >= 9 and not unmarked, (len(users), unmarked)


# ------------------------------------------------------------------ the skip report of a run
_CONFTEST = """
import sys
sys.path.insert(0, {tests!r})
from pathlib import Path
from skip_report import SkipReport


def pytest_configure(config):
    if not hasattr(config, "workerinput"):
        config.pluginmanager.register(SkipReport(ci={ci}, readme=Path({readme!r})), "safepg-skip-report")
"""
_TESTS = """
import pytest


def test_runs():
    pass


def test_named():
    pytest.skip("the authors' repository is not mirrored here: (a stand-in)")


def test_unnamed():
    pytest.skip("something else is missing")
"""


def run_pytest(folder: Path, ci: bool, tests: str, *args: str) -> subprocess.CompletedProcess:
    folder.mkdir()
    (folder / "pytest.ini").write_text("[pytest]\n")
    (folder / "conftest.py").write_text(_CONFTEST.format(tests=str(TESTS), ci=ci, readme=str(README)))
    (folder / "test_some.py").write_text(tests)
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "PYTEST_ADDOPTS")}
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", *args, str(folder)],
                          cwd=folder, env=env, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["one process", "pytest-xdist"])
def test_under_ci_a_skip_the_readme_does_not_name_fails_the_run(tmp_path: Path, workers: list[str]) -> None:
    proc = run_pytest(tmp_path / "ci", True, _TESTS, *workers)
    out = proc.stdout
    assert proc.returncode == pytest.ExitCode.TESTS_FAILED, out + proc.stderr
    assert "1 passed, 2 skipped" in out and "skips: 2" in out, out
    assert "test_some.py::test_unnamed: something else is missing" in out, out
    assert "CI=true: 1 skip(s) not named in the README" in out, out


def test_under_ci_a_named_skip_passes_and_off_ci_every_skip_is_listed(tmp_path: Path) -> None:
    named_only = _TESTS[:_TESTS.index("\n\ndef test_unnamed")] + "\n"
    proc = run_pytest(tmp_path / "ci", True, named_only)
    assert proc.returncode == pytest.ExitCode.OK, proc.stdout + proc.stderr
    assert "skips: 1" in proc.stdout and "not named" not in proc.stdout, proc.stdout
    proc = run_pytest(tmp_path / "local", False, _TESTS)
    assert proc.returncode == pytest.ExitCode.OK, proc.stdout + proc.stderr
    assert "skips: 2" in proc.stdout and "not named" not in proc.stdout, proc.stdout
    assert "test_some.py::test_named: the authors' repository is not mirrored here" in proc.stdout, proc.stdout


def test_named_skips_read_the_readme_section_only() -> None:
    text = f"# x\n\n- `not a skip`: before the section\n\n{SECTION}\n\nWhy.\n\n- `first reason`: why\n" \
           "- `second`: why,\n  on two lines\n\n## Next\n\n- `after`: not one\n"
    assert named_skips(text) == ["first reason", "second"]
    assert named_skips("# no such section\n") == []
