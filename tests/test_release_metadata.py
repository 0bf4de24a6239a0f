"""The release metadata agree with one another and with what they describe.

- ``CITATION.cff`` is valid Citation File Format 1.2.0: it is checked against the format's
  own JSON Schema, kept in ``tests/data/`` (its origin in ``tests/data/README.md``), so the
  test needs no network;
- one version: ``safepg.__version__`` (written once, in ``safepg/__init__.py``, as a literal
  that ``pyproject.toml`` reads without importing safepg) is the installed distribution's,
  ``CITATION.cff``'s and that of the top released entry of ``CHANGELOG.md``;
- ``LICENSE`` is the MIT License, and ``pyproject.toml`` and ``CITATION.cff`` say MIT;
- ``NOTICE`` names the authors' repository, the commit read and every file of
  ``safepg/thesis/data/authors/MANIFEST.json`` with its source commits, and the MathJax and
  axe-core versions that ``book/tools/vendor_assets.sh`` pins.

PyYAML and jsonschema are not pinned in ``requirements.txt`` themselves: the pinned
jupyter-book (and nbformat, myst-parser, dask) depend on them, so every ``make setup``
installs them.
"""

from __future__ import annotations

import ast
import datetime
import hashlib
import importlib.metadata
import json
import re
import tomllib
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml

import safepg

ROOT = Path(__file__).resolve().parents[1]
CITATION = ROOT / "CITATION.cff"
CHANGELOG = ROOT / "CHANGELOG.md"
LICENSE = ROOT / "LICENSE"
NOTICE = ROOT / "NOTICE"
PYPROJECT = ROOT / "pyproject.toml"
INIT = ROOT / "safepg" / "__init__.py"
MANIFEST = ROOT / "safepg" / "thesis" / "data" / "authors" / "MANIFEST.json"
VENDOR = ROOT / "book" / "tools" / "vendor_assets.sh"
SCHEMA = Path(__file__).parent / "data" / "citation-file-format-1.2.0.schema.json"
#: SHA-256 of ``schema.json`` at the tag 1.2.0 of citation-file-format/citation-file-format, the
#: same bytes as ``cffconvert/schemas/1.2.0/schema.json`` in the cffconvert 2.0.0 wheel.
SCHEMA_SHA256 = "0b8d22140da702d766df318dcff3a91af2f39521298dcf36d76315fd99cc169b"

#: The MIT License (SPDX ``MIT``) after its copyright line, whitespace-normalised.
MIT_BODY = (
    "Permission is hereby granted, free of charge, to any person obtaining a copy of this software and "
    "associated documentation files (the \"Software\"), to deal in the Software without restriction, including "
    "without limitation the rights to use, copy, modify, merge, publish, distribute, sublicense, and/or sell "
    "copies of the Software, and to permit persons to whom the Software is furnished to do so, subject to the "
    "following conditions: The above copyright notice and this permission notice shall be included in all "
    "copies or substantial portions of the Software. THE SOFTWARE IS PROVIDED \"AS IS\", WITHOUT WARRANTY OF "
    "ANY KIND, EXPRESS OR IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR "
    "A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE "
    "FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING "
    "FROM, OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE."
)
COPYRIGHT = "Copyright (c) 2026 the safepg authors"

#: A released entry of Keep a Changelog: ``## [1.2.3] - 2026-01-31`` (``## [Unreleased]`` is not one).
RELEASE = re.compile(r"^## \[(?P<version>[^\]]+)\](?:\s+-\s+(?P<date>\d{4}-\d{2}-\d{2}))?\s*$", re.MULTILINE)


def _dates_as_text(value: Any) -> Any:
    """``value`` with every YAML date made an ISO string, as the schema's ``date`` asks of tools."""
    if isinstance(value, dict):
        return {k: _dates_as_text(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_dates_as_text(v) for v in value]
    if isinstance(value, datetime.date):
        return value.isoformat()
    return value


def citation() -> dict[str, Any]:
    """CITATION.cff as YAML, its dates as strings."""
    return _dates_as_text(yaml.safe_load(CITATION.read_text(encoding="utf-8")))


def cff_errors(document: dict[str, Any]) -> list[str]:
    """Every violation of the CFF 1.2.0 schema in ``document``, as ``path: message``."""
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    validator = jsonschema.Draft7Validator(schema, format_checker=jsonschema.Draft7Validator.FORMAT_CHECKER)
    return [f"{'/'.join(map(str, e.absolute_path)) or '(top)'}: {e.message}"
            for e in sorted(validator.iter_errors(document), key=lambda e: list(map(str, e.absolute_path)))]


def released_entries() -> list[tuple[str, str | None]]:
    """``(version, date)`` of each released entry of CHANGELOG.md, newest (top) first."""
    entries = [(m["version"], m["date"]) for m in RELEASE.finditer(CHANGELOG.read_text(encoding="utf-8"))]
    return [(v, d) for v, d in entries if v.lower() != "unreleased"]


def pyproject() -> dict[str, Any]:
    return tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))


# --- (a) CITATION.cff is valid CFF 1.2.0 -------------------------------------------------------


def test_schema_is_the_cff_1_2_0_schema() -> None:
    """The schema file is the one its origin says (tests/data/README.md), byte for byte."""
    assert hashlib.sha256(SCHEMA.read_bytes()).hexdigest() == SCHEMA_SHA256, (
        f"{SCHEMA.name} is not schema.json of CFF 1.2.0 (cffconvert 2.0.0's copy); see tests/data/README.md")
    assert json.loads(SCHEMA.read_text(encoding="utf-8"))["$id"] == "https://citation-file-format.github.io/1.2.0/schema.json"


def test_citation_cff_validates() -> None:
    document = citation()
    assert document.get("cff-version") == "1.2.0", "CITATION.cff must declare cff-version: 1.2.0 (the schema kept here)"
    errors = cff_errors(document)
    assert not errors, "CITATION.cff is not valid CFF 1.2.0:\n" + "\n".join(errors)


@pytest.mark.parametrize("change", ["no authors", "unknown key", "bad reference type", "bad date"])
def test_schema_check_rejects(change: str) -> None:
    """The check above can fail: each of these breakages of CITATION.cff is reported."""
    document = citation()
    if change == "no authors":
        del document["authors"]
    elif change == "unknown key":
        document["versions"] = document["version"]
    elif change == "bad reference type":
        document["references"][0]["type"] = "masters-thesis"
    else:
        document["date-released"] = "27/11/2026"
    assert cff_errors(document), f"the schema check accepted CITATION.cff with {change}"


def test_citation_references_the_thesis_and_the_paper() -> None:
    references = {r["type"]: r for r in citation()["references"]}
    thesis, paper = references["thesis"], references["conference-paper"]
    assert thesis["title"] == "Adaptive Batch Size for Safe Policy Gradient Methods"
    assert [a["family-names"] for a in thesis["authors"]] == ["Papini"]
    assert thesis["institution"]["name"] == "Politecnico di Milano" and thesis["year"] == 2017
    assert paper["title"] == "Adaptive Batch Size for Safe Policy Gradients"
    assert [a["family-names"] for a in paper["authors"]] == ["Papini", "Pirotta", "Restelli"]
    assert paper["collection-title"] == "Advances in Neural Information Processing Systems 30"
    assert paper["year"] == 2017


# --- (b) one version everywhere ------------------------------------------------------------------


def test_version_is_written_once() -> None:
    """pyproject.toml has no version of its own: setuptools reads safepg.__version__, a literal."""
    project = pyproject()
    assert "version" not in project["project"], "pyproject.toml repeats the version: keep it in safepg/__init__.py"
    assert "version" in project["project"].get("dynamic", []), "pyproject.toml must declare dynamic = [\"version\"]"
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "safepg.__version__"}
    assigned = [node for node in ast.parse(INIT.read_text(encoding="utf-8")).body
                if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__version__" for t in node.targets)]
    assert len(assigned) == 1, "safepg/__init__.py must assign __version__ exactly once, at module level"
    # setuptools' attr: reads the value statically (no import of safepg or numba) only from a literal.
    assert ast.literal_eval(assigned[0].value) == safepg.__version__


def test_one_version_everywhere() -> None:
    version = safepg.__version__
    installed = importlib.metadata.version("safepg")
    assert installed == version, (
        f"the installed safepg says {installed}, safepg.__version__ {version}: reinstall it "
        "(.venv/bin/python -m pip install --no-deps -e .; make setup reinstalls only when requirements.txt "
        "or pyproject.toml change)")
    assert str(citation()["version"]) == version, "CITATION.cff's version is not safepg.__version__"
    entries = released_entries()
    assert entries, "CHANGELOG.md has no released entry (## [x.y.z] - YYYY-MM-DD)"
    assert entries[0][0] == version, (
        f"CHANGELOG.md's top released entry is {entries[0][0]}, safepg.__version__ is {version}")


def test_release_date_agrees() -> None:
    """CITATION.cff's date-released is the date of the changelog's entry for this version."""
    (_, date), = [e for e in released_entries() if e[0] == safepg.__version__]
    assert date is not None, "CHANGELOG.md's entry for this version has no date"
    assert citation().get("date-released") == date


# --- (c) MIT, said the same way everywhere -------------------------------------------------------


def test_license_is_mit() -> None:
    lines = LICENSE.read_text(encoding="utf-8").strip().splitlines()
    assert lines[0].strip() == "MIT License"
    assert COPYRIGHT in [line.strip() for line in lines], f"LICENSE must carry '{COPYRIGHT}'"
    body = " ".join(" ".join(lines[lines.index(COPYRIGHT) + 1:]).split())
    assert body == MIT_BODY, "LICENSE's text after the copyright line is not the MIT License's"


def test_license_declared_as_mit() -> None:
    license_ = pyproject()["project"]["license"]
    assert (license_.get("text") if isinstance(license_, dict) else license_) == "MIT", (
        f"pyproject.toml's license is {license_!r}, LICENSE is MIT")
    assert citation()["license"] == "MIT"
    metadata = importlib.metadata.metadata("safepg")
    assert "MIT" in (metadata.get("License-Expression"), metadata.get("License")), (
        "the installed safepg's metadata does not say MIT: reinstall it "
        "(.venv/bin/python -m pip install --no-deps -e .)")


# --- (d) NOTICE covers the third-party material --------------------------------------------------


def test_notice_names_the_authors_outputs() -> None:
    notice = NOTICE.read_text(encoding="utf-8")
    manifest = json.loads(MANIFEST.read_text(encoding="utf-8"))
    assert manifest["repository"] in notice, "NOTICE does not name the authors' repository"
    assert manifest["read_at"] in notice, "NOTICE does not give the commit of the authors' repository that was read"
    missing = [name for name in manifest["files"] if not re.search(rf"(?<![\w.-]){re.escape(name)}(?![\w-])", notice)]
    assert not missing, f"NOTICE does not name these files of MANIFEST.json: {missing}"
    for name, entry in manifest["files"].items():
        commits = sorted({source["commit"][:7] for source in entry["sources"]})
        absent = [c for c in commits if c not in notice]
        assert not absent, f"NOTICE does not give {name}'s source commits {absent} (MANIFEST.json)"


def test_notice_names_the_pinned_javascript() -> None:
    """MathJax and axe-core in NOTICE at the versions vendor_assets.sh fetches, with their licenses."""
    script = VENDOR.read_text(encoding="utf-8")
    pins = dict(re.findall(r'dest="[^"]*/(mathjax|axe-core)"\s*\n\s*version="([^"]+)"', script))
    assert set(pins) == {"mathjax", "axe-core"}, f"vendor_assets.sh's pins not found: {pins}"
    notice = NOTICE.read_text(encoding="utf-8")
    for name, title, license_ in (("mathjax", "MathJax", "Apache License, Version 2.0"),
                                  ("axe-core", "axe-core", "Mozilla Public License, Version 2.0")):
        assert f"{title} {pins[name]}" in notice, f"NOTICE must name {title} {pins[name]} (vendor_assets.sh's pin)"
        assert license_ in notice, f"NOTICE must give {title}'s license ({license_})"


def test_notice_names_the_cff_schema() -> None:
    notice = NOTICE.read_text(encoding="utf-8")
    assert f"tests/data/{SCHEMA.name}" in notice and "CC BY 4.0" in notice
