"""The progress of ``run-book``'s tasks: a tqdm bar on a terminal, plain lines in a log, with the time
left estimated from the work done and, before the first unit, from the last build's recorded time."""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TextIO

import numpy as np
from tqdm import tqdm

from safepg import runner
from safepg.record import LearningRecord
from safepg.runner import RunConfig

#: Seconds between two progress lines when the output is not a terminal.
PLAIN_INTERVAL = 30.0
#: Seconds between two redraws of a terminal's bar (its elapsed time and time left move).
TTY_INTERVAL = 1.0
PREFIX = "run-book"


def duration(seconds: float | None) -> str:
    if seconds is None or not np.isfinite(seconds):
        return "?"
    s = int(round(seconds))
    return f"{s // 3600}h{s % 3600 // 60:02d}m" if s >= 3600 else f"{s // 60}m{s % 60:02d}s" if s >= 60 else f"{s}s"


class _Bar(tqdm):  # type: ignore[misc]  # tqdm ships no types (an Any base to mypy), and subclassing is the API
    """A tqdm bar with one more field for its format, ``{status}``."""

    def __init__(self, *args: Any, status: str = "", **kwargs: Any) -> None:
        self.status = status
        super().__init__(*args, **kwargs)

    @property
    def format_dict(self) -> dict[str, Any]:
        return {**super().format_dict, "status": self.status}


class Progress:
    """Progress of one task: ``total`` units (runs, or measured runs) of which ``done`` were stored.

    The time left is the elapsed time times the work left over the work done since the start,
    the work of a run being its trajectory budget (an early-stopping run counts as its budget);
    before the first unit, the time the last build recorded (``benchmarks/book_timings.json``)
    scaled to the work left, if known. ``tty`` draws a tqdm bar; otherwise plain lines, a
    progress line at most every ``interval`` seconds.
    """

    def __init__(self, name: str, total: int, done: int, work_left: float, unit: str = "runs",
                 stream: TextIO | None = None, tty: bool | None = None, interval: float | None = None,
                 previous_s: float | None = None, clock: Callable[[], float] = time.monotonic,
                 ticker: bool = True) -> None:
        self.name, self.total, self.done, self.unit = name, total, done, unit
        self.stream = stream or sys.stdout
        self.tty = self.stream.isatty() if tty is None else tty
        self.interval = interval if interval is not None else TTY_INTERVAL if self.tty else PLAIN_INTERVAL
        self.work_left, self.work_done, self.previous_s = float(work_left), 0.0, previous_s
        self.trajectories = 0
        self.clock = clock
        self.started = self.last_line = clock()
        self.lock = threading.Lock()
        self.bar = None
        if self.tty:
            import shutil

            # A terminal that does not say its width (0 columns) gets 100, not an empty bar.
            width = shutil.get_terminal_size((100, 24)).columns
            self.bar = _Bar(total=total, initial=done, desc=f"{PREFIX}: {name}", file=self.stream,
                            bar_format="{desc}: {n_fmt}/{total_fmt} " + unit + " |{bar}| {status}",
                            ncols=width if width > 0 else 100, status=self._status())
        else:
            self._print(f"{name}: computing {total - done} of {total} {unit} ({done} stored)"
                        + (f", last build took {duration(previous_s)}" if previous_s else ""))
        self._stop = threading.Event()
        self._thread = None
        if ticker:
            self._thread = threading.Thread(target=self._tick, daemon=True)
            self._thread.start()

    def _print(self, text: str) -> None:
        print(f"{PREFIX}: {text}", file=self.stream, flush=True)

    def elapsed(self) -> float:
        return self.clock() - self.started

    def left(self) -> float | None:
        if self.work_done > 0:
            return self.elapsed() * self.work_left / self.work_done
        if self.previous_s is not None:
            return max(self.previous_s - self.elapsed(), 0.0)
        return None

    def _status(self) -> str:
        left = self.left()
        return (f"{self.trajectories:.3g} trajectories, {duration(self.elapsed())} elapsed, "
                + ("time left unknown yet" if left is None else f"about {duration(left)} left"))

    def _line(self) -> None:
        self.last_line = self.clock()
        self._print(f"{self.name}: {self.done}/{self.total} {self.unit}, {self._status()}")

    def _tick(self) -> None:
        while not self._stop.wait(min(self.interval, 1.0)):
            self.tick()

    def tick(self) -> None:
        """Redraw the bar, or print a progress line if ``interval`` has passed since the last."""
        with self.lock:
            if self.bar is not None:
                self.bar.status = self._status()
                self.bar.refresh()
            elif self.clock() - self.last_line >= self.interval:
                self._line()

    def advance(self, trajectories: int, work: float, units: int = 1) -> None:
        """``units`` more done, which simulated ``trajectories`` and were ``work`` of the work left."""
        with self.lock:
            self.done += units
            self.trajectories += int(trajectories)
            self.work_done += work
            self.work_left = max(self.work_left - work, 0.0)
            if self.bar is not None:
                self.bar.status = self._status()
                self.bar.update(units)
            elif self.clock() - self.last_line >= self.interval and self.done < self.total:
                self._line()

    def note(self, text: str) -> None:
        """One line about the task (above the bar on a terminal)."""
        with self.lock:
            if self.bar is not None:
                self.bar.write(f"{PREFIX}: {text}", file=self.stream)
            else:
                self._print(text)

    def close(self, finished: bool = True) -> None:
        """Stop the redraws and say how it ended: ``done``, or ``stopped`` (an error, Ctrl-C)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self.lock:
            if self.bar is not None:
                self.bar.status = f"{self.trajectories:.3g} trajectories, {duration(self.elapsed())}"
                self.bar.close()
            self._print(f"{self.name}: {'done' if finished else 'stopped'}, {self.done}/{self.total} {self.unit}, "
                        f"{self.trajectories:.3g} trajectories in {duration(self.elapsed())}")


def previous_seconds(book: Path, name: str) -> float | None:
    """The seconds the last measured build took for ``name`` (``benchmarks/book_timings.json``)."""
    try:
        t = json.loads((book.parent / "benchmarks" / "book_timings.json").read_text())
        return next(float(e["seconds"]) for e in t["experiments"] if e["name"] == name)
    except (OSError, ValueError, KeyError, TypeError, StopIteration):
        return None


@contextmanager
def reporting_stored_runs(progress: Progress,
                           counted: Callable[[LearningRecord, Path], bool] | None = None) -> Iterator[None]:
    """Tell ``progress`` of every run the runner stores (``run_configs`` stores each as it arrives),
    or of those for which ``counted(record, folder)`` is true."""
    store = runner.store_run

    def store_and_report(rec: LearningRecord, folder: str | os.PathLike[str], cfg: RunConfig, seed: int) -> None:
        store(rec, folder, cfg, seed)
        if counted is None or counted(rec, Path(folder)):
            progress.advance(int(np.sum(rec.batch_size)), float(cfg.budget))

    runner.store_run = store_and_report
    try:
        yield
    finally:
        runner.store_run = store


__all__ = ["PLAIN_INTERVAL", "PREFIX", "TTY_INTERVAL", "Progress", "duration", "previous_seconds",
           "reporting_stored_runs"]
