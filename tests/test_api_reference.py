"""The book's API reference (book/api.md) covers the method layer's public names.

The page lists modules; book/_ext/api_listing.py turns each into a section with an entry per
public name when the book is built. These tests expand the page as the build does and check
what it documents against the modules themselves, found independently of the extension, so
a name left out by either the page or the extension fails here without a book build. The
last test builds the page alone with Jupyter Book (warnings are errors, as in ``make book``).
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
import shutil
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest
import yaml
from script_module import load

from conftest import skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "book" / "api.md"
#: The modules the reference must cover; others (safepg.options, safepg.tasks) may be added.
REQUIRED = ["safepg", "safepg.options", "safepg.tasks", "safepg.envs", "safepg.definition", "safepg.runner",
            "safepg.record", "safepg.store"]


def _listing() -> ModuleType:
    return load("book/_ext/api_listing.py")


listing = _listing()
TEXT = PAGE.read_text(encoding="utf-8")
MODULES = listing.block_modules(TEXT)


def defined_names(modname: str) -> set[str]:
    """Public names a module defines, found without its ``__all__``: the public classes and
    functions whose ``__module__`` is the module, and the names its own ``#:`` comments document."""
    module = importlib.import_module(modname)
    names = {n for n, obj in vars(module).items()
             if not n.startswith("_") and getattr(obj, "__module__", None) == modname}
    source = inspect.getsource(module)
    names |= {n for n in re.findall(r"^#:.*\n(?:#:.*\n)*([A-Za-z]\w*)\s*[:=]", source, re.MULTILINE)}
    return names


def expected_names(modname: str) -> set[str]:
    """The names a module exports: its ``__all__``, which every listed module must have."""
    module = importlib.import_module(modname)
    assert hasattr(module, "__all__"), f"{modname} has no __all__"
    return set(module.__all__)


def documented(expanded: str, full_only: bool = False) -> dict[str, set[str]]:
    """Module -> the names the expanded page gives an entry (full, or also pointing elsewhere)."""
    out: dict[str, set[str]] = {}
    module = None
    kinds = "auto" if full_only else "(?:auto|py:)"
    for line in expanded.splitlines():
        if m := re.match(r"\.\. (?:currentmodule|py:module):: (\S+)$", line):
            module = m[1]
            out.setdefault(module, set())
        elif m := re.match(rf"\.\. {kinds}(?:class|exception|function|data):: (\S+)$", line):
            assert module is not None, line
            out[module].add(m[1])
    return out


#: Full class entries whose signature the built page must show, at least (33 when this was written).
MIN_CLASSES_CHECKED = 33
EXPANDED = listing.expand(TEXT)
ENTRIES = documented(EXPANDED)
FULL = documented(EXPANDED, full_only=True)


def test_page_lists_the_required_modules() -> None:
    missing = [m for m in REQUIRED if m not in MODULES]
    assert not missing, f"book/api.md's {{safepg-api}} block does not list {missing}"
    assert len(MODULES) == len(set(MODULES)), f"a module is listed twice: {MODULES}"


@pytest.mark.parametrize("modname", MODULES)
def test_every_public_name_has_an_entry(modname: str) -> None:
    want = expected_names(modname)
    have = ENTRIES.get(modname, set())
    assert not want - have, f"{modname}: no entry in the API reference for {sorted(want - have)}"
    extra = have - set(listing.public_names(modname))
    assert not extra, f"{modname}: entries for names that are not public: {sorted(extra)}"


@pytest.mark.parametrize("modname", [m for m in MODULES if m not in ("safepg", "safepg.envs")])
def test_each_module_exports_what_it_defines(modname: str) -> None:
    """A public class, function or documented value a module defines is in its ``__all__``."""
    missing = defined_names(modname) - expected_names(modname)
    assert not missing, f"{modname}.__all__ leaves out {sorted(missing)}"


def test_safepg_all_is_covered() -> None:
    import safepg

    assert set(safepg.__all__) <= ENTRIES["safepg"]


def test_one_section_per_module_with_its_summary_and_table() -> None:
    for modname in MODULES:
        module = importlib.import_module(modname)
        summary = inspect.getdoc(module).splitlines()[0]
        section = EXPANDED.split(f"## `{modname}`\n", 1)
        assert len(section) == 2, f"no section headed {modname}"
        body = section[1].split("\n## ", 1)[0]
        assert body.lstrip().startswith(summary), f"{modname}: the section does not open with {summary!r}"
        assert ".. autosummary::" in body, f"{modname}: no summary table"


def test_readme_links_the_page() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    use = readme.split("## Use the library", 1)[1].split("\n## ", 1)[0]
    assert "_build/html/book/api.html" in use


def test_page_is_in_the_toc() -> None:
    toc = yaml.safe_load((ROOT / "_toc.yml").read_text(encoding="utf-8"))
    last = toc["parts"][-1]
    assert last["caption"] == "Reference" and {"file": "book/api"} in last["chapters"]


@pytest.fixture(scope="module")
def built_page(tmp_path_factory: pytest.TempPathFactory) -> str:
    """book/api.md built alone with the book's configuration; its HTML."""
    jb = Path(sys.executable).with_name("jupyter-book")
    if not jb.exists() and shutil.which("jupyter-book") is None:
        skip_or_fail("jupyter-book is not installed: run `make setup` (it is pinned in requirements.txt)")
    book = tmp_path_factory.mktemp("apibook")
    config = yaml.safe_load((ROOT / "_config.yml").read_text(encoding="utf-8"))
    # The chapters are left out: nothing to execute, and only this page's warnings count.
    config["exclude_patterns"] = [*config.get("exclude_patterns", []), "book/intro.md"]
    sphinx = config["sphinx"]
    sphinx["local_extensions"] = {name: str(ROOT / path) for name, path in sphinx["local_extensions"].items()}
    # book/_vendor (MathJax) exists only once `make book-assets` has run; a missing folder warns.
    sphinx["config"]["html_static_path"] = [str(ROOT / p) for p in sphinx["config"]["html_static_path"]
                                            if (ROOT / p).is_dir()]
    (book / "_config.yml").write_text(yaml.safe_dump(config))
    # The References page and its bibliography: the docstrings' citations link there.
    (book / "_toc.yml").write_text("format: jb-book\nroot: book/api\nchapters:\n- file: book/references\n")
    (book / "book").mkdir()
    shutil.copy(PAGE, book / "book" / "api.md")
    shutil.copy(ROOT / "book" / "references.md", book / "book" / "references.md")
    shutil.copy(ROOT / "references.bib", book / "references.bib")
    proc = subprocess.run([str(jb) if jb.exists() else "jupyter-book", "build", str(book), "-W", "-n",
                           "--keep-going"], capture_output=True, text=True, timeout=600)
    log = re.sub(r"\x1b\[[0-9;]*m", "", proc.stdout + proc.stderr)
    problems = [line for line in log.splitlines() if re.search(r"\b(WARNING|ERROR|CRITICAL|SEVERE)\b", line)]
    assert proc.returncode == 0 and not problems, "\n".join(problems) or log[-3000:]
    return (book / "_build" / "html" / "book" / "api.html").read_text(encoding="utf-8")


def test_built_page_has_an_anchor_per_name(built_page: str) -> None:
    missing = [f"{m}.{n}" for m, names in ENTRIES.items() for n in names
               if f'id="{m}.{n}"' not in built_page]
    assert not missing, f"no entry in the built page for {missing}"


def test_built_classes_show_their_parameters(built_page: str) -> None:
    # A class's entry opens with its signature: every constructor parameter is named there.
    bare, checked, headless, unsigned = [], [], [], []
    for modname, names in ENTRIES.items():
        module = importlib.import_module(modname)
        for name in names:
            cls = getattr(module, name)
            # Only full entries: the one-line entry of an object described in another section has no signature.
            if not inspect.isclass(cls) or name not in FULL.get(modname, set()):
                continue
            anchor = re.escape(f"{modname}.{name}")
            head = re.search(rf'<dt class="sig[^"]*" id="{anchor}">(.*?)</dt>', built_page, re.DOTALL)
            if head is None:  # a full entry opens with its signature line: none found is a failure
                headless.append(f"{modname}.{name}")
                continue
            try:
                params = [p for p in inspect.signature(cls).parameters if p not in ("args", "kwargs")]
            except (TypeError, ValueError):  # no signature Python can read: nothing to hold the page to
                unsigned.append(f"{modname}.{name}")
                continue
            # A parameter with a default is one span, "name=value", under autodoc_typehints none.
            shown = set(re.findall(r'<span class="pre">(\w+)(?:</span>|=)', head[1]))
            if not set(params) <= shown:
                bare.append(f"{modname}.{name}: {sorted(set(params) - shown)}")
            checked.append(f"{modname}.{name}")
    assert not bare, f"signatures without their parameters: {bare}"
    assert not headless, f"full entries without a signature line in the built page: {headless}"
    # What was checked: every full class entry but those Python gives no signature for (counted, and few).
    print(f"\n{len(checked)} class signatures checked; no signature to read: {unsigned}")
    assert len(checked) >= MIN_CLASSES_CHECKED and len(unsigned) <= 2, (len(checked), unsigned)


def test_every_parameter_name_is_a_name(built_page: str) -> None:
    # A paragraph left below a numpydoc Parameters list (no section header of its own) is read as
    # one more parameter: its first line becomes a bold "name" that cannot wrap on a phone.
    names = re.findall(r"<dt><strong>([^<]*)</strong>", built_page)
    assert names, "no parameter lists found in the built page"
    # A name, or names joined by commas ("progress, desc"); never words separated by spaces.
    sentences = [n for n in names if any(" " in part.strip() for part in n.split(","))]
    assert not sentences, f"text read as parameter names (a paragraph after a Parameters list?): {sentences}"


def test_documented_names_are_computed_once_per_writing_phase(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every missing reference of a build reads the same map; a new read of the pages renews it."""
    calls: list[object] = []

    def documented_now(env: object) -> dict[int, str]:
        calls.append(env)
        return {len(calls): "safepg.name"}

    class Environment:  # a stand-in for Sphinx's: only its identity matters
        pass

    monkeypatch.setattr(listing, "_documented_now", documented_now)
    env, other = Environment(), Environment()
    first = listing._documented(env)
    assert listing._documented(env) is first and calls == [env]
    assert listing._documented(other) == {2: "safepg.name"}
    listing._forget(None, env)
    assert listing._documented(env) == {3: "safepg.name"} and calls == [env, other, env]
