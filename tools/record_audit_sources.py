"""Record every file the settings audit cites: ``safepg/thesis/data/audit/sources.json``.

For each ``path@commit`` that a row of ``safepg/thesis/data/audit/section-*.toml`` cites, reads the
authors' repository ``T3p/adaptive-batch-size`` from a local git directory (no network) and records
the full commit, the git blob of the file at that commit, its size in bytes and its number of lines.
A file whose blob the commit's tree names but the repository does not hold is recorded with its
blob and ``"absent": true``. ``tests/test_lqg2d_authors.py`` checks the citations against this
record on any machine, and the record against the repository where ``SAFEPG_AUTHORS_MIRROR`` names
a copy of it. Rerunning it rewrites a byte-identical file.

Usage::

    python tools/record_audit_sources.py [/path/to/adaptive-batch-size/.git]   # default: $SAFEPG_AUTHORS_MIRROR
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from safepg.thesis import audit
from safepg.thesis.authors import REPOSITORY


def git(git_dir: str, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", git_dir, *args], capture_output=True, check=check)


def record(git_dir: str, cited: str) -> dict:
    """The record of one cited ``path@commit``."""
    path, short = cited.rsplit("@", 1)
    commit = git(git_dir, "rev-parse", "--verify", f"{short}^{{commit}}").stdout.decode().strip()
    blob = git(git_dir, "rev-parse", f"{commit}:{path}").stdout.decode().strip()
    data = git(git_dir, "cat-file", "blob", blob, check=False)
    if data.returncode:  # named by the tree, not in the repository
        return {"commit": commit, "blob": blob, "absent": True}
    return {"commit": commit, "blob": blob, "bytes": len(data.stdout), "lines": len(data.stdout.splitlines())}


def main(git_dir: str) -> None:
    files = {cited: record(git_dir, cited) for cited in audit.cited_files()}
    out = {"repository": REPOSITORY, "recorded_by": "tools/record_audit_sources.py",
           "note": "Every path@commit the audit cites: the full commit, the git blob of the file there, its "
                   "bytes and lines ('absent': the tree names the blob, the repository does not hold it).",
           "files": files}
    audit.SOURCES_FILE.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"{len(files)} cited files recorded in {audit.SOURCES_FILE}")


if __name__ == "__main__":
    where = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("SAFEPG_AUTHORS_MIRROR")
    if not where:
        sys.exit("usage: python tools/record_audit_sources.py GIT_DIR (or set SAFEPG_AUTHORS_MIRROR)")
    main(where)
