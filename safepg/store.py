"""The on-disk store of finished runs: one file per run, written atomically.

A run's file is a :class:`~safepg.learning.LearningRecord` saved as ``.npz`` and stamped
with the key of the settings that produced it. A reader sees either the old file or the
whole new one, never half: the record is written to a temporary file in the same folder
and renamed over the target when complete. A writer killed mid-save (SIGKILL, power
loss) leaves that temporary file behind, named after its host and process id, so that
:func:`remove_stale_temp_files` can tell it from one a live writer is still writing. Two
writers may therefore share a folder.

The results folder is ``$SAFEPG_RESULTS`` or ``results/`` under the current directory.
"""

from __future__ import annotations

import os
import re
import socket
import tempfile
import time
from pathlib import Path

from safepg.learning import LearningRecord

#: Suffix of a run file being written. Its name is ``<stem>~<host>~<pid>~<random>.tmp.npz``:
#: the writer's host and process id tell a later runner whether the writer is still alive.
TEMP_SUFFIX = ".tmp.npz"
#: A temporary file whose writer cannot be checked (another host, or the unnamed files of
#: older versions) is stale after this long: writing one run file takes well under a second.
TEMP_MAX_AGE = 3600.0
_TEMP_NAME = re.compile(r"^(?P<stem>[^~]+)~(?P<host>[^~]+)~(?P<pid>\d+)~[^~]*" + re.escape(TEMP_SUFFIX) + "$")


def results_dir() -> Path:
    """The results folder: ``$SAFEPG_RESULTS``, or ``results/`` under the current directory."""
    return Path(os.environ.get("SAFEPG_RESULTS", "results"))


def load_stored(path: Path, key: str) -> LearningRecord | None:
    """The finished run stored at ``path`` if it was made by the settings whose key is ``key``.

    Returns ``None`` when the file is missing or unreadable, holds an interrupted run, or
    was made by other settings (or another library version, which is part of the key).
    """
    if not path.exists():
        return None
    try:
        rec = LearningRecord.load(path)
    except (OSError, ValueError, KeyError):
        return None
    if rec.interrupted or rec.config.get("run_key") != key:
        return None
    return rec


def save_atomic(rec: LearningRecord, path: Path) -> None:
    """Write ``rec`` to ``path`` so readers see the old file or the whole new one, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"{path.stem}~{socket.gethostname()}~{os.getpid()}~",
                               suffix=TEMP_SUFFIX)
    os.close(fd)
    try:
        rec.save(tmp)
        os.replace(tmp, path)  # atomic on POSIX and Windows within one filesystem
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _pid_alive(pid: int) -> bool:
    """Whether process ``pid`` of this host is running (a zombie counts as dead)."""
    if pid == os.getpid() or os.name == "nt":  # Windows' os.kill(pid, 0) would terminate the process
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    try:  # Linux: a killed child not yet reaped by its parent still answers kill(pid, 0)
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def remove_stale_temp_files(folder: Path) -> list[Path]:
    """Delete the temporary run files under ``folder`` whose writer is dead; return them.

    A file written by a process of this host is stale when that process no longer runs;
    one from another host (a results folder shared over the network) or without a writer
    in its name (older versions) when it is older than :data:`TEMP_MAX_AGE` seconds.
    A live runner's file is never touched, so two runners can share a folder. A dead
    writer's id reused by a new process only delays the removal to a later run.
    """
    removed = []
    host, now = socket.gethostname(), time.time()
    for tmp in sorted(folder.rglob(f"*{TEMP_SUFFIX}")) if folder.is_dir() else ():
        m = _TEMP_NAME.match(tmp.name)
        try:
            if m is not None and m["host"] == host:
                stale = not _pid_alive(int(m["pid"]))
            else:
                stale = now - tmp.stat().st_mtime > TEMP_MAX_AGE
            if stale:
                tmp.unlink()
                removed.append(tmp)
        except FileNotFoundError:  # its writer renamed or removed it meanwhile
            continue
    return removed
