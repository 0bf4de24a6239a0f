"""The skips of a test run, listed at its end; under ``CI=true`` a skip the README does not name fails it.

A test that needs something of the machine skips through ``conftest.skip_or_fail``, which fails
it under ``CI=true`` instead. What may still skip in CI is named in the README's section
:data:`SECTION`, one item per reason: an item opens with the reason's first words in backquotes
(``- `the authors' repository is not mirrored here`: why``). :class:`SkipReport` (registered by
``tests/conftest.py`` in the process that reports the run) collects every skip, prints them all
after the run's summary, and under ``CI=true`` turns a run whose skips include one the README
does not name into a failed run.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
#: The README's section that names what a test run may skip under CI, and why.
SECTION = "## What a test run skips"


def named_skips(readme: str) -> list[str]:
    """The reasons :data:`SECTION` of ``readme`` names: the backquoted words that open each of its items."""
    start = readme.find(f"\n{SECTION}\n")
    if start < 0:
        return []
    body = readme[start + len(SECTION) + 2:]
    body = body[:body.find("\n## ")] if "\n## " in body else body
    return re.findall(r"^- `([^`]+)`", body, flags=re.MULTILINE)


def skip_reason(report: Any) -> str:
    """The reason of a skipped test's or collector's report, without pytest's "Skipped: "."""
    longrepr = report.longrepr
    reason = longrepr[2] if isinstance(longrepr, tuple) else str(longrepr)
    return reason.removeprefix("Skipped: ")


class SkipReport:
    """Collect the run's skips, list them at the end, and under CI fail the run on one the README does not name.

    Parameters
    ----------
    ci : bool
        Whether this is a CI run (``CI=true``).
    readme : Path
        The README whose :data:`SECTION` names the skips allowed under CI.
    """

    def __init__(self, ci: bool, readme: Path = README) -> None:
        self.ci = ci
        self.readme = readme
        self.skips: list[tuple[str, str]] = []

    def _add(self, report: Any) -> None:
        if report.skipped and not hasattr(report, "wasxfail"):
            self.skips.append((report.nodeid, skip_reason(report)))

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        self._add(report)

    def pytest_collectreport(self, report: pytest.CollectReport) -> None:
        self._add(report)

    def unnamed(self) -> list[tuple[str, str]]:
        """The skips whose reason no item of the README's :data:`SECTION` names."""
        named = named_skips(self.readme.read_text(encoding="utf-8"))
        return [(node, reason) for node, reason in self.skips if not any(reason.startswith(n) for n in named)]

    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        if self.ci and self.unnamed() and session.exitstatus == pytest.ExitCode.OK:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        tr = terminalreporter
        tr.write_sep("-", f"skips: {len(self.skips)}")
        for node, reason in sorted(self.skips):
            tr.write_line(f"SKIPPED {node}: {reason}")
        unnamed = self.unnamed()
        if self.ci and unnamed:
            tr.write_line(f"CI=true: {len(unnamed)} skip(s) not named in the README's section {SECTION!r} "
                          "(each must be named there with its reason, or fail under CI): the run fails", red=True)
