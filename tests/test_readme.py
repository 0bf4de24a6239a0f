"""The README's Python examples run as written.

Every ```python block of README.md is executed in order, in one namespace, as a reader
pasting them into one Python session would, in a subprocess whose working directory is a
temporary folder and whose ``SAFEPG_RESULTS`` is another (nothing touches the clone's
``results/``). A block that cannot run in a test says so in the README itself, on the line
just before it::

    <!-- not run by tests/test_readme.py: why -->

Every other block must run without an exception; a failing block is reported with its line
in the README and the end of its traceback. ```bash blocks are not run.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: The marker of a block the test does not run; the reason after the colon is required.
SKIP = re.compile(r"^<!--\s*not run by tests/test_readme\.py:\s*(?P<why>\S.*?)\s*-->$")
FENCE = re.compile(r"^```(?P<lang>[\w+-]*)\s*$")
#: All the blocks together; a block that is too slow for a test is marked in the README.
TIMEOUT = 900


@dataclass(frozen=True)
class Block:
    """One fenced ```python block of the README."""

    line: int  # of its first code line, 1-based
    code: str
    skip: str | None  # the marker's reason, None when the block is run


def python_blocks(text: str) -> list[Block]:
    """The ```python blocks of a Markdown text, in order, each with its "not run" marker.

    Parameters
    ----------
    text : str
        The Markdown source.

    Returns
    -------
    list of Block
        The blocks; ``skip`` is the reason of a marker on the last non-blank line before
        the opening fence, else None.
    """
    lines = text.splitlines()
    blocks, i = [], 0
    while i < len(lines):
        fence = FENCE.match(lines[i])
        if fence is None:
            i += 1
            continue
        end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith("```")), None)
        if end is None:
            raise ValueError(f"README.md:{i + 1}: code block never closed")
        if fence["lang"] == "python":
            before = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            marker = SKIP.match(before)
            blocks.append(Block(i + 2, "\n".join(lines[i + 1:end]) + "\n", marker["why"] if marker else None))
        i = end + 1
    return blocks


#: Runs the blocks in one namespace; one JSON line per block in the report file, written as
#: each ends, so a block that hangs until the timeout still leaves the earlier ones' results.
RUNNER = textwrap.dedent("""
    import json, sys, time, traceback
    blocks, report = json.load(open(sys.argv[1])), open(sys.argv[2], "w")
    namespace = {"__name__": "__main__"}
    for block in blocks:
        start, error = time.perf_counter(), None
        try:
            exec(compile(block["code"], f"README.md:{block['line']}", "exec"), namespace)
        except BaseException:
            error = "".join(traceback.format_exc().splitlines(keepends=True)[-12:])
        report.write(json.dumps({"line": block["line"], "seconds": time.perf_counter() - start,
                                 "error": error}) + "\\n")
        report.flush()
""")


BLOCKS = python_blocks(README.read_text(encoding="utf-8"))
RUN = [b for b in BLOCKS if b.skip is None]


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> dict[int, dict]:
    """Run every unmarked block once; the report of each, by its README line."""
    tmp = tmp_path_factory.mktemp("readme")
    work, store = tmp / "cwd", tmp / "results"
    work.mkdir()
    store.mkdir()
    (tmp / "blocks.json").write_text(json.dumps([{"line": b.line, "code": b.code} for b in RUN]))
    (tmp / "runner.py").write_text(RUNNER)
    env = {**os.environ, "SAFEPG_RESULTS": str(store), "MPLBACKEND": "Agg"}
    try:
        proc = subprocess.run([sys.executable, str(tmp / "runner.py"), str(tmp / "blocks.json"),
                               str(tmp / "report.jsonl")], cwd=work, env=env, capture_output=True, text=True,
                              timeout=TIMEOUT)
        tail = proc.stderr[-3000:]
    except subprocess.TimeoutExpired as err:
        tail = f"timed out after {TIMEOUT} s\n{(err.stderr or b'')[-3000:]!r}"
    report = (tmp / "report.jsonl").read_text().splitlines() if (tmp / "report.jsonl").exists() else []
    done = {r["line"]: r for r in map(json.loads, report)}
    for block in RUN:
        done.setdefault(block.line, {"line": block.line, "seconds": None,
                                     "error": f"did not run: the runner stopped before it\n{tail}"})
    return done


def test_readme_has_python_blocks() -> None:
    assert RUN, "README.md has no ```python block to run"


def test_markers_give_a_reason() -> None:
    # A marker that is not directly before a python block (a typo, a block moved) marks nothing.
    text = README.read_text(encoding="utf-8").splitlines()
    marked = {b.line for b in BLOCKS if b.skip is not None}
    markers = 0
    for i, line in enumerate(text):
        if "not run by tests/test_readme.py" in line:
            assert SKIP.match(line.strip()), f"README.md:{i + 1}: malformed marker {line.strip()!r}"
            nxt = next((j for j in range(i + 1, len(text)) if text[j].strip()), None)
            assert nxt is not None and text[nxt].strip() == "```python" and nxt + 2 in marked, (
                f"README.md:{i + 1}: the marker is not directly before a ```python block")
            markers += 1
    assert markers == len(marked) >= 1  # every marked block was found through its marker


@pytest.mark.parametrize("block", RUN, ids=[f"README.md:{b.line}" for b in RUN])
def test_block_runs(block: Block, results: dict[int, dict]) -> None:
    result = results[block.line]
    assert result["error"] is None, (
        f"README.md:{block.line}: the ```python block starting there failed"
        f" (after {result['seconds'] or 0:.1f} s):\n{block.code}\n{result['error']}")


def test_every_unmarked_block_ran(results: dict[int, dict]) -> None:
    assert sorted(results) == sorted(b.line for b in RUN)
    assert all(r["seconds"] is not None for r in results.values()), [
        line for line, r in results.items() if r["seconds"] is None]
