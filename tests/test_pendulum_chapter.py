"""The pendulum chapter imports only the library, sits in its own part after Chapter 5, and its
campaign is found by run-book."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from safepg.thesis import prefetch

ROOT = Path(__file__).resolve().parents[1]
CHAPTER = ROOT / "book" / "pendulum.ipynb"


def imported_modules(notebook: Path) -> list[str]:
    """Every module a code cell imports (``import a.b``, ``from a.b import c``: ``a.b`` and ``a.b.c``)."""
    found = []
    for cell in json.loads(notebook.read_text())["cells"]:
        if cell["cell_type"] != "code":
            continue
        src = "".join(cell["source"])
        src = "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in src.splitlines())
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, ast.Import):
                found += [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                module = node.module or ""
                found += [module] + [f"{module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Call) and getattr(node.func, "id", None) == "__import__":
                found += [a.value for a in node.args if isinstance(a, ast.Constant) and isinstance(a.value, str)]
    return found


def thesis_imports(notebook: Path) -> list[str]:
    return [m for m in imported_modules(notebook) if m == "safepg.thesis" or m.startswith("safepg.thesis.")]


def test_the_chapter_imports_only_the_library() -> None:
    modules = imported_modules(CHAPTER)
    assert any(m.startswith("safepg.") for m in modules)
    assert thesis_imports(CHAPTER) == []


@pytest.mark.parametrize("line", ["from safepg.thesis import plotting", "import safepg.thesis.safety",
                                  "from safepg import thesis", "x = __import__('safepg.thesis.report')"])
def test_the_import_check_fails_on_a_thesis_import(tmp_path: Path, line: str) -> None:
    nb = json.loads(CHAPTER.read_text())
    nb["cells"].append({"cell_type": "code", "metadata": {}, "source": [line], "outputs": [], "execution_count": None})
    path = tmp_path / "pendulum.ipynb"
    path.write_text(json.dumps(nb))
    assert thesis_imports(path)


def test_the_chapter_is_its_own_part_after_chapter_5() -> None:
    toc = (ROOT / "_toc.yml").read_text()
    assert toc.index("book/cartpole") < toc.index("caption: Beyond the thesis") < toc.index("book/pendulum")
    stems = [p.stem for p in prefetch.chapters(ROOT / "book")]
    assert stems[stems.index("cartpole") + 1] == "pendulum"


def test_run_book_finds_the_chapters_campaign() -> None:
    tasks = prefetch.chapter_requests(CHAPTER)
    assert [(t.name, t.kind) for t in tasks] == [(prefetch.COMPARISON, "comparison")]
    assert any(t.kind == "comparison" for t in prefetch.book_tasks(ROOT / "book"))


def test_run_book_computes_the_comparison_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """run-book's comparison task on an empty store: computed (three stages reported), then stored."""
    import io
    from dataclasses import replace

    from safepg.comparison import StepSearch, pendulum_comparison

    def small(**_: object) -> object:
        full = pendulum_comparison(seeds=2, budget=800, episodes=40)
        return replace(full, adaptive=full.adaptive[1:2], batch_sizes=(100,),
                       search=StepSearch((1e-4,), seeds=1, episodes=20), looks=(100,))

    monkeypatch.setattr(prefetch, "_comparison", lambda task: small())
    task = prefetch.Task("pendulum", prefetch.COMPARISON, "comparison")
    out = io.StringIO()
    assert prefetch.prefetch_comparison(task, tmp_path, jobs=1, stream=out, tty=False) == "computed"
    text = out.getvalue()
    assert "fixed steps chosen" in text and "safety measured" in text and "pendulum: done in" in text
    again = io.StringIO()
    assert prefetch.prefetch_comparison(task, tmp_path, jobs=1, stream=again, tty=False) == "stored"
    assert "pendulum: stored" in again.getvalue()
