"""The settings audit: where the authors' code and outputs differ from the thesis's text.

One table per section of Chapter 5 (``data/audit/section-5.1.toml``, ``-5.2``, ``-5.3``),
one row per setting that the authors' repository (``T3p/adaptive-batch-size``) runs
otherwise than the thesis says, or that the thesis leaves unstated. Each row gives the
thesis's words (with the line of ``thesis.txt``), what the authors' code or output files do,
where (``path@commit:line`` in that repository), what safepg runs by default and under the
authors' settings, and the effect on the printed numbers.

The rows are prose kept as data, so the book's tables and the tests read the same text; the
numbers a row quotes are recomputed in the chapter that shows it.
"""

from __future__ import annotations

import json
import re
import tomllib
from dataclasses import dataclass, fields
from functools import cache
from pathlib import Path

from safepg.tables import Table, markdown_table
from safepg.thesis.authors import REPOSITORY

#: Folder of the audit tables.
AUDIT_DIR = Path(__file__).resolve().parent / "data" / "audit"
#: The sections audited.
SECTIONS = ("5.1", "5.2", "5.3")
#: ``path@commit`` or ``path@commit:line`` (line or first-last) in the authors' repository.
SOURCE = re.compile(r"^(?P<path>[\w./-]+)@(?P<commit>[0-9a-f]{7,40})(?::(?P<line>\d+)(?:-(?P<last>\d+))?)?$")
#: Every file the audit cites, by ``path@commit``: its full commit, git blob, size and line count, read from
#: the authors' repository by ``tools/record_audit_sources.py`` (so that the citations can be checked without it).
SOURCES_FILE = AUDIT_DIR / "sources.json"


@dataclass(frozen=True)
class AuditRow:
    """One setting of one section: the thesis's words against what the authors ran."""

    setting: str
    thesis: str
    authors: str
    sources: tuple[str, ...]
    ours: str
    effect: str

    def source_links(self) -> str:
        """The sources as Markdown links to the authors' repository at the commit named."""
        return ", ".join(source_link(s) for s in self.sources)


def source_link(source: str) -> str:
    """``path@commit:line`` as a Markdown link to that line of the authors' repository."""
    m = SOURCE.match(source)
    if m is None:
        raise ValueError(f"source must read path@commit or path@commit:line, got {source!r}")
    url = f"{REPOSITORY}/blob/{m['commit']}/{m['path']}"
    if m["line"]:
        url += f"#L{m['line']}" + (f"-L{m['last']}" if m["last"] else "")
    return f"[`{source}`]({url})"


@cache
def audit(section: str) -> tuple[AuditRow, ...]:
    """The audit rows of ``section`` ("5.1", "5.2" or "5.3"), in the order of the file."""
    if section not in SECTIONS:
        raise ValueError(f"section must be one of {SECTIONS}, got {section!r}")
    data = tomllib.loads((AUDIT_DIR / f"section-{section}.toml").read_text(encoding="utf-8"))
    names = [f.name for f in fields(AuditRow)]
    rows = []
    for i, row in enumerate(data.get("row", [])):
        if sorted(row) != sorted(names):
            raise ValueError(f"section {section}, row {i}: fields must be {names}, got {sorted(row)}")
        for s in row["sources"]:
            source_link(s)  # every source must name a path and a commit
        rows.append(AuditRow(**{**row, "sources": tuple(row["sources"])}))
    return tuple(rows)


def cited_files() -> list[str]:
    """Every file the audit cites, as ``path@commit`` (the line part dropped), sorted, each once."""
    found = set()
    for section in SECTIONS:
        for row in audit(section):
            for s in row.sources:
                m = SOURCE.match(s)
                assert m is not None  # audit() checked every source
                found.add(f"{m['path']}@{m['commit']}")
    return sorted(found)


def recorded_sources() -> dict[str, dict]:
    """:data:`SOURCES_FILE`: ``{"path@commit": {"commit", "blob", "bytes", "lines"}}``; a file whose blob the
    repository's history names but does not hold has ``"absent": true`` and no size."""
    return json.loads(SOURCES_FILE.read_text(encoding="utf-8"))["files"]


def audit_table(section: str, name: str) -> Table:
    """The audit of ``section`` as a numbered book table (label ``name``)."""
    rows = [{"setting": r.setting, "thesis": r.thesis, "authors": f"{r.authors} ({r.source_links()})",
             "ours": r.ours, "effect": r.effect} for r in audit(section)]
    return markdown_table(rows, [("setting", "setting", ""), ("thesis", "the thesis's words", ""),
                                 ("authors", "what the authors' code does", ""), ("ours", "what we run", ""),
                                 ("effect", "effect on the printed numbers", "")],
                          caption=f"Section {section}: the thesis's text against the authors' code and outputs.",
                          name=name)
