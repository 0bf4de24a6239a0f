"""The on-disk store of finished runs: one file per run, written atomically.

A run's file is a :class:`~safepg.record.LearningRecord` saved as ``.npz`` and stamped
with the key of the settings that produced it. A reader sees either the old file or the
whole new one, never half: the record is written to a temporary file in the same folder
and renamed over the target when complete. A writer killed mid-save (SIGKILL, power
loss) leaves that temporary file behind, named after its host and process id, so that
:func:`remove_stale_temp_files` can tell it from one a live writer is still writing. Two
writers may therefore share a folder.

A run file that exists but cannot be read as a record (empty, truncated, overwritten,
arrays that do not fit together: :class:`!safepg.record.RecordFileError`) is *damaged*.
A damaged file is never deleted: the readers leave it out with a warning, and a runner
about to compute its run again sets it aside first (:func:`set_aside`), keeping it for
inspection. A readable file of other settings or another ``RESULTS_VERSION`` is not
damaged but *stale*: it is not this run. The runner stores each definition's runs in a folder
of its own key (:func:`safepg.runner.run_path`), so a stale run is never overwritten; it stays
until :func:`safepg.runner.prune` removes it.

The results folder is ``$SAFEPG_RESULTS`` or ``results/`` under the current directory.
"""

from __future__ import annotations

import os
import re
import socket
import tempfile
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

from safepg.record import LearningRecord, RecordFileError

#: Suffix of a run file being written. Its name is ``<stem>~<host>~<pid>~<random>.tmp.npz``:
#: the writer's host and process id tell a later runner whether the writer is still alive.
TEMP_SUFFIX = ".tmp.npz"
#: A temporary file whose writer cannot be checked (another host, or the unnamed files of
#: older versions) is stale after this long: writing one run file takes well under a second.
TEMP_MAX_AGE = 3600.0
_TEMP_NAME = re.compile(r"^(?P<stem>[^~]+)~(?P<host>[^~]+)~(?P<pid>\d+)~[^~]*" + re.escape(TEMP_SUFFIX) + "$")
#: A damaged run file set aside: ``seed-3.npz`` becomes ``seed-3.npz.damaged-<UTC time>``, a
#: name that no reader, runner or clean-up of this module looks at again.
DAMAGED_SUFFIX = ".damaged-"

#: What a reader does with a damaged run file: ``"warn"`` leaves it out (and where it is)
#: with a :class:`DamagedRunWarning`, ``"set_aside"`` also moves it aside (for a caller that
#: computes the run again), ``"raise"`` raises :class:`DamagedRunsError`.
OnDamaged = Literal["warn", "set_aside", "raise"]


class DamagedRunWarning(UserWarning):
    """A damaged run file was left out of what was read (and perhaps set aside)."""


class DamagedRunsError(Exception):
    """Run files that exist but cannot be read.

    ``damaged`` lists them, one :class:`!safepg.record.RecordFileError` (``path``,
    ``reason``) per file.
    """

    def __init__(self, damaged: Sequence[RecordFileError]) -> None:
        self.damaged = list(damaged)
        super().__init__("damaged run files: " + "; ".join(map(str, self.damaged)))


def results_dir() -> Path:
    """The results folder: ``$SAFEPG_RESULTS``, or ``results/`` under the current directory."""
    return Path(os.environ.get("SAFEPG_RESULTS", "results"))


def load_stored(path: Path, key: str, on_damaged: OnDamaged = "warn") -> LearningRecord | None:
    """The finished run stored at ``path`` if it was made by the settings whose key is ``key``.

    Returns ``None`` when the file is missing, holds an interrupted run, or is stale: made
    by other settings or another library version (which is part of the key). A damaged
    file (:class:`!safepg.record.RecordFileError`) is handled as ``on_damaged`` says
    (:data:`OnDamaged`); unless that raises, it counts as missing. A file that cannot be
    opened at all (no permission) raises ``OSError``: that says nothing about its contents.
    """
    try:
        inode = path.stat().st_ino
        rec = LearningRecord.load(path)
    except FileNotFoundError:
        return None
    except RecordFileError as err:
        if on_damaged == "raise":
            raise DamagedRunsError([err]) from err
        if on_damaged == "set_aside":
            moved = set_aside(path, inode)
            if moved is not None:  # None: another runner has already set it aside
                warnings.warn(f"damaged run file {path} set aside as {moved.name}, its run is computed again: "
                              f"{err.reason}", DamagedRunWarning, stacklevel=2)
        else:
            warnings.warn(f"damaged run file {path} left out: {err.reason}; computing its run again sets it "
                          "aside", DamagedRunWarning, stacklevel=2)
        return None
    if rec.interrupted or rec.config.get("run_key") != key:
        return None
    return rec


def set_aside(path: Path, inode: int | None = None) -> Path | None:
    """Rename the damaged run file ``path`` to ``<name>.damaged-<UTC time>`` beside it.

    The file is kept for inspection, never deleted. Returns its new path, or ``None`` when
    there was nothing to move: ``path`` is gone, or is no longer the file whose inode is
    ``inode`` (the one found damaged), because another runner sharing the folder set it
    aside and stored the run again meanwhile. That check is what keeps two runners from
    setting a good file aside.
    """
    try:
        if inode is not None and path.stat().st_ino != inode:
            return None
    except FileNotFoundError:
        return None
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    dest, n = path.with_name(f"{path.name}{DAMAGED_SUFFIX}{stamp}"), 1
    while dest.exists():  # damaged again within the same second: keep both
        dest, n = path.with_name(f"{path.name}{DAMAGED_SUFFIX}{stamp}-{n}"), n + 1
    try:
        os.rename(path, dest)
    except FileNotFoundError:
        return None
    return dest


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


__all__ = ["DAMAGED_SUFFIX", "DamagedRunWarning", "DamagedRunsError", "OnDamaged", "TEMP_MAX_AGE", "TEMP_SUFFIX",
           "load_stored", "remove_stale_temp_files", "results_dir", "save_atomic", "set_aside"]
