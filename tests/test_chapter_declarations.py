"""The chapters' declarations (:mod:`safepg.thesis.chapters`) against what the notebooks call.

``run-book`` computes what :data:`~safepg.thesis.chapters.CHAPTERS` declares and parses no notebook,
so a declaration that drifts from the notebooks would silently skip a computation (or make one nobody
reads). :func:`mismatches` reads the notebooks' code cells with ``ast`` and reports, both ways, a
computing call a notebook makes that its declaration lacks and a declaration none of its calls
matches; the probes below feed it changed notebooks and declarations to show that it fails.

A notebook's computing calls, by the name it calls them (``f(...)`` or ``module.f(...)``):

- ``run_experiment``: each experiment named by a string of its cell (the ``names = [...]`` list,
  ``get_experiment("...")``), with its literal ``seeds`` if it passes one;
- ``scorecard``: only with ``run=True`` (without, it only reads);
- ``sweep_paths``: with its literal keyword arguments;
- ``run_comparison``: with the literal keyword arguments of the notebook's ``pendulum_comparison``;
- ``run_sweep``, ``measure_runs``, ``false_alarms_stored``: the call itself.

What ``scorecard(run=True)`` and ``run_sweep`` run is not in the notebooks: the probes at the end call
them with ``run_experiment`` replaced by a recorder and compare with their declared experiments.
"""

from __future__ import annotations

import ast
import importlib
import json
from collections import defaultdict
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from safepg.thesis import prefetch
from safepg.thesis.chapters import CALLS, CHAPTERS, Computation
from safepg.thesis.experiments import EXPERIMENTS, get_experiment

BOOK = Path(__file__).resolve().parents[1] / "book"

#: One computing call: (function, experiment or None, seeds or None, literal keyword arguments).
Call = tuple[str, str | None, int | None, tuple[tuple[str, Any], ...]]


def code_cells(notebook: Path) -> list[str]:
    """The sources of a notebook's code cells, IPython magics and shell escapes blanked (not Python)."""
    out = []
    for cell in json.loads(notebook.read_text())["cells"]:
        if cell["cell_type"] == "code":
            src = "".join(cell["source"])
            out.append("\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in src.splitlines()))
    return out


def book_cells(book: Path = BOOK) -> dict[str, list[str]]:
    """Each notebook of the book (``_toc.yml``'s order) by name: its code cells."""
    return {nb.stem: code_cells(nb) for nb in prefetch.chapters(book)}


def _calls(tree: ast.AST) -> Iterator[tuple[str, ast.Call]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None
            if name:
                yield name, node


def _literals(call: ast.Call) -> tuple[tuple[str, Any], ...]:
    """The keyword arguments of a call whose values are literals, sorted by name."""
    out = []
    for kw in call.keywords:
        if kw.arg is None:
            continue
        try:
            out.append((kw.arg, ast.literal_eval(kw.value)))
        except ValueError:  # a name or an expression: not something a declaration can state
            continue
    return tuple(sorted(out))


def _experiment_names(tree: ast.AST) -> list[str]:
    return [n.value for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and n.value in EXPERIMENTS]


def called(cells: Sequence[str]) -> set[Call]:
    """The computing calls of a notebook's code cells (the module's docstring says which)."""
    trees = [ast.parse(src) for src in cells]
    comparisons = [_literals(c) for tree in trees for name, c in _calls(tree) if name == "pendulum_comparison"]
    found: set[Call] = set()
    for tree in trees:
        for name, call in _calls(tree):
            options = _literals(call)
            if name == "run_experiment":
                seeds = dict(options).get("seeds")
                # A call whose cell names no experiment is reported as run_experiment(?): it must name them.
                names: list[str | None] = [*_experiment_names(tree)] or [None]
                found |= {(name, e, seeds, ()) for e in names}
            elif name == "scorecard":
                if dict(options).get("run") is True:
                    found.add((name, None, None, ()))
            elif name == "sweep_paths":
                found.add((name, None, None, options))
            elif name == "run_comparison":
                found |= {(name, None, None, o) for o in comparisons or [()]}
            elif name in CALLS:
                found.add((name, None, None, ()))
    return found


def declared(computations: Sequence[Computation]) -> set[Call]:
    """A chapter's declarations as :func:`called` finds calls (the experiments of ``scorecard`` and
    ``run_sweep`` are checked by the probes, not here)."""
    out: set[Call] = set()
    for c in computations:
        if c.call == "run_experiment":
            out |= {(c.call, e, c.seeds, c.options) for e in c.experiments}
        else:
            out.add((c.call, None, None, c.options))
    return out


def shown(call: Call) -> str:
    name, experiment, seeds, options = call
    args = [] if experiment is None and name != "run_experiment" else [repr(experiment) if experiment else "?"]
    args += [] if seeds is None else [f"seeds={seeds}"]
    kwargs = ", ".join(args + [f"{k}={v!r}" for k, v in options])
    if name == "scorecard":
        return "scorecard(run=True)"
    if name == "run_comparison":
        return f"run_comparison(pendulum_comparison({kwargs}))"
    return f"{name}({kwargs})"


def mismatches(notebooks: Mapping[str, Sequence[str]],
               declarations: Mapping[str, Sequence[Computation]]) -> list[str]:
    """Each computing call of ``notebooks`` (name: code cells) that ``declarations`` lacks, each declaration
    that no call of its notebook matches, and each notebook declared or not but not both, one line each."""
    out = []
    for nb in [*notebooks, *(n for n in declarations if n not in notebooks)]:
        if nb not in declarations:
            out.append(f"{nb}: not in safepg.thesis.chapters.CHAPTERS")
        if nb not in notebooks:
            out.append(f"{nb}: declared, but the book has no such notebook")
        found, want = called(notebooks.get(nb, ())), declared(declarations.get(nb, ()))
        out += [f"{nb}: calls {shown(c)}, not declared" for c in sorted(found - want, key=repr)]
        out += [f"{nb}: declares {shown(c)}, which none of its cells calls" for c in sorted(want - found, key=repr)]
    return out


# ------------------------------------------------------------------ the book as it is
def test_the_declarations_match_the_notebooks() -> None:
    found = mismatches(book_cells(), CHAPTERS)
    assert not found, "\n".join(found)


def test_every_notebook_of_the_toc_is_declared_in_its_order() -> None:
    assert list(CHAPTERS) == [nb.stem for nb in prefetch.chapters(BOOK)]
    assert {nb.stem for nb in BOOK.glob("*.ipynb")} == set(CHAPTERS)


def test_the_declared_calls_are_library_functions_run_book_computes() -> None:
    for name, module in CALLS.items():
        assert callable(getattr(importlib.import_module(module), name, None)), f"{module}.{name} is gone"
    assert set(CALLS) == prefetch.EXPERIMENT_CALLS | set(prefetch.CALL_TASKS)
    for chapter, computations in CHAPTERS.items():
        for c in computations:
            assert bool(c.experiments) == (c.call in prefetch.EXPERIMENT_CALLS), (chapter, c)
            assert set(c.experiments) <= set(EXPERIMENTS), (chapter, c)
    with pytest.raises(ValueError, match="call must be one of"):
        Computation("compute_experiment", ("table-5.1",))
    with pytest.raises(ValueError, match="sorted"):
        Computation("sweep_paths", options=(("seeds", 1), ("jobs", 2)))


def test_scorecard_run_computes_the_declared_experiments(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from safepg.thesis.scorecard import rows

    ran: list[tuple[str, int | None]] = []

    def record(exp: Any, seeds: int | None = None, **_: Any) -> dict[str, list[Any]]:
        ran.append((exp if isinstance(exp, str) else exp.name, seeds))
        return {}

    monkeypatch.setattr(rows, "run_experiment", record)
    monkeypatch.setattr(rows, "stored_rows", lambda *args, **kwargs: [])  # the runs are what is checked
    rows.scorecard(root=tmp_path, run=True)
    assert ran == [(e, c.seeds) for c in CHAPTERS["scorecard"] if c.call == "scorecard" for e in c.experiments]


def test_run_sweep_computes_the_declared_experiments(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from safepg.thesis import cartpole_sweep

    ran: list[tuple[str, int | None]] = []

    def record(exp: Any, seeds: int | None = None, **_: Any) -> defaultdict[str, list[Any]]:
        ran.append((exp if isinstance(exp, str) else exp.name, seeds))
        return defaultdict(list)

    monkeypatch.setattr(cartpole_sweep, "run_experiment", record)
    cartpole_sweep.run_sweep(root=tmp_path)
    assert ran == [(e, c.seeds) for c in CHAPTERS["cartpole"] if c.call == "run_sweep" for e in c.experiments]


def test_run_book_computes_the_declarations() -> None:
    """Every declared computation is a task of run-book's (the experiments at least at their seeds)."""
    tasks = prefetch.book_tasks(BOOK)

    def seeds(t: prefetch.Task) -> int:
        return 0 if t.kind != "experiment" else t.seeds if t.seeds is not None else get_experiment(t.name).seeds

    for chapter, computations in CHAPTERS.items():
        for c in computations:
            for t in prefetch.computation_tasks(chapter, c):
                assert any(o.kind == t.kind and o.name == t.name and o.options == t.options
                           and seeds(o) >= seeds(t) for o in tasks), t
    with pytest.raises(ValueError, match="no declaration"):
        prefetch.book_tasks(BOOK, {k: v for k, v in CHAPTERS.items() if k != "errata"})


# ------------------------------------------------------------------ probes: the check fails when it should
def _edit(cells: dict[str, list[str]], notebook: str, old: str, new: str) -> dict[str, list[str]]:
    """``cells`` with ``old`` replaced by ``new`` in ``notebook``'s cells (it must be there)."""
    assert any(old in src for src in cells[notebook]), (notebook, old)
    return {**cells, notebook: [src.replace(old, new) for src in cells[notebook]]}


NOTEBOOK_EDITS = {
    "a renamed call": (
        ("lqg2d", "run_experiment(name,", "compute_experiment(name,"),
        ["lqg2d: declares run_experiment('figures-5.5-5.6'), which none of its cells calls",
         "lqg2d: declares run_experiment('table-5.3'), which none of its cells calls",
         "lqg2d: declares run_experiment('table-5.3-authors'), which none of its cells calls"]),
    "one more experiment": (
        ("lqg2d", '"table-5.3-authors"]', '"table-5.3-authors", "table-5.4"]'),
        ["lqg2d: calls run_experiment('table-5.4'), not declared"]),
    "run with other seeds": (
        ("lqg2d", "run_experiment(name, root=RESULTS,", "run_experiment(name, seeds=3, root=RESULTS,"),
        ["lqg2d: calls run_experiment('figures-5.5-5.6', seeds=3), not declared",
         "lqg2d: calls run_experiment('table-5.3', seeds=3), not declared",
         "lqg2d: calls run_experiment('table-5.3-authors', seeds=3), not declared",
         "lqg2d: declares run_experiment('figures-5.5-5.6'), which none of its cells calls",
         "lqg2d: declares run_experiment('table-5.3'), which none of its cells calls",
         "lqg2d: declares run_experiment('table-5.3-authors'), which none of its cells calls"]),
    "other sweep arguments": (
        ("lqg1d", "sweep_paths(jobs=2,", "sweep_paths(jobs=2, seeds=3,"),
        ["lqg1d: calls sweep_paths(jobs=2, seeds=3), not declared",
         "lqg1d: declares sweep_paths(jobs=2), which none of its cells calls"]),
    "the scorecard only reads": (
        ("scorecard", "run=True", "run=False"),
        ["scorecard: declares scorecard(run=True), which none of its cells calls"]),
    "another comparison": (
        ("pendulum", "pendulum_comparison()", "pendulum_comparison(seeds=3)"),
        ["pendulum: calls run_comparison(pendulum_comparison(seeds=3)), not declared",
         "pendulum: declares run_comparison(pendulum_comparison()), which none of its cells calls"]),
    "no sweep": (
        ("cartpole", "sweep_runs = run_sweep(root=RESULTS)", "sweep_runs = {}"),
        ["cartpole: declares run_sweep(), which none of its cells calls"]),
}


@pytest.mark.parametrize("case", list(NOTEBOOK_EDITS))
def test_the_check_fails_on_a_changed_notebook(case: str) -> None:
    (notebook, old, new), expected = NOTEBOOK_EDITS[case]
    assert mismatches(_edit(book_cells(), notebook, old, new), CHAPTERS) == expected


def test_the_check_fails_on_a_new_computing_cell() -> None:
    cells = book_cells()
    more = {**cells, "errata": [*cells["errata"], "checks = false_alarms_stored(RESULTS)"],
            "adaptive_step": [*cells["adaptive_step"], "run_experiment(NAMES[0], root=RESULTS)"]}
    assert mismatches(more, CHAPTERS) == ["adaptive_step: calls run_experiment(?), not declared",
                                          "errata: calls false_alarms_stored(), not declared"]
    new_chapter = {**cells, "acrobot": ['run_experiment("table-5.1")']}
    assert mismatches(new_chapter, CHAPTERS) == ["acrobot: not in safepg.thesis.chapters.CHAPTERS",
                                                 "acrobot: calls run_experiment('table-5.1'), not declared"]


def _redeclare(chapter: str, computations: tuple[Computation, ...]) -> dict[str, tuple[Computation, ...]]:
    return {**CHAPTERS, chapter: computations}


def test_the_check_fails_on_a_changed_declaration() -> None:
    cells = book_cells()
    lqg2d = CHAPTERS["lqg2d"][0]
    more = _redeclare("lqg2d", (replace(lqg2d, experiments=(*lqg2d.experiments, "table-5.4")),))
    assert mismatches(cells, more) == ["lqg2d: declares run_experiment('table-5.4'), which none of its cells calls"]
    fewer = _redeclare("cartpole", tuple(c for c in CHAPTERS["cartpole"] if c.call != "measure_runs"))
    assert mismatches(cells, fewer) == ["cartpole: calls measure_runs(), not declared"]
    elsewhere = _redeclare("errata", (Computation("false_alarms_stored"),))
    assert mismatches(cells, elsewhere) == ["errata: declares false_alarms_stored(), which none of its cells calls"]
    sweep = _redeclare("lqg1d", (CHAPTERS["lqg1d"][0], Computation("sweep_paths", options=(("jobs", 4),))))
    assert mismatches(cells, sweep) == ["lqg1d: calls sweep_paths(jobs=2), not declared",
                                        "lqg1d: declares sweep_paths(jobs=4), which none of its cells calls"]
    gone = {k: v for k, v in CHAPTERS.items() if k != "errata"}
    assert mismatches(cells, gone) == ["errata: not in safepg.thesis.chapters.CHAPTERS"]
    extra = {**CHAPTERS, "appendix": ()}
    assert mismatches(cells, extra) == ["appendix: declared, but the book has no such notebook"]
