r"""What the book's chapters compute, computed before ``jupyter-book build``, with progress.

``make book`` runs ``python -m safepg run-book`` first. It reads the chapters' code cells
(``_toc.yml``'s notebooks, in the book's order) and finds what they compute and store:

- every experiment named in a cell that calls ``run_experiment``, with the seeds the
  experiment defines, and the experiments they warm-start from;
- ``scorecard(..., run=True)``: the scorecard's experiments (``NEEDED``, ``RANGE_VARIANTS``);
- ``run_sweep(...)``: the cart-pole sweep's baseline searches (``SWEEP_SEEDS`` seeds), then
  ``cartpole-sweep``;
- ``sweep_paths(...)``: the Table 5.1 sweep (its literal keyword arguments kept);
- ``measure_runs(...)``: the cart-pole chapter's safety measurements (:func:`safety_plan`);
- ``run_comparison(pendulum_comparison(...))``: the pendulum chapter's comparison
  (:func:`safepg.comparison.run_comparison`: its step search, its runs and their safety
  measurements), with the literal keyword arguments of ``pendulum_comparison``.

Each is computed into the store the notebooks read (``results/`` beside ``book/``, their
``Path("..") / "results"``) by the very functions the notebooks call, with the same joblib
parallelism (all cores), so that the notebooks then only read, and a notebook run on its own
still computes whatever is missing. Nothing is computed twice: what is stored is loaded and
reported as stored in one line.

Progress: on a terminal, one tqdm bar per task (runs done / total, trajectories, elapsed time
and time left), redrawn every second; otherwise (CI, a log) plain lines: one when a task
starts, one when it ends, and at most one progress line every :data:`PLAIN_INTERVAL` seconds.
"""

from __future__ import annotations

import ast
import json
import os
import re
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np
from tqdm import tqdm

from safepg import runner
from safepg.learning import LearningRecord
from safepg.runner import RunConfig
from safepg.thesis.experiment_store import experiment_folder, run_experiment, run_experiments
from safepg.thesis.experiments import EXPERIMENTS, Experiment, get_experiment, scaled

#: The book's notebooks: ``book/`` beside the package (an editable install of this clone).
BOOK = Path(__file__).resolve().parents[2] / "book"
#: Seconds between two progress lines when the output is not a terminal.
PLAIN_INTERVAL = 30.0
#: Seconds between two redraws of a terminal's bar (its elapsed time and time left move).
TTY_INTERVAL = 1.0
PREFIX = "run-book"
#: The store's folder of the time :func:`safepg.runner.compile_once` took (its ``timing.jsonl``).
COMPILE_ONCE = "compile-once"
#: The name of the pendulum chapter's comparison task (and its folder of the store).
COMPARISON = "pendulum"


@dataclass(frozen=True)
class Task:
    """One stored computation a chapter needs.

    ``kind`` is ``"experiment"`` (``name`` in the registry, run for ``seeds`` seeds),
    ``"table-5.1-sweep"`` (``options``: the keyword arguments of ``sweep_paths``),
    ``"safety-mc"`` (the cart-pole chapter's Monte Carlo measurements) or ``"comparison"`` (``options``:
    the keyword arguments of :func:`safepg.comparison.pendulum_comparison`).
    """

    chapter: str
    name: str
    kind: str = "experiment"
    seeds: int | None = None
    options: tuple[tuple[str, Any], ...] = ()
    #: Another trajectory budget per run (a quick look, a test); None: the experiment's own.
    budget: int | None = None


# ------------------------------------------------------------------ what the chapters need
def chapters(book: Path = BOOK) -> list[Path]:
    """The book's notebooks in ``_toc.yml``'s order (every ``book/*.ipynb`` if there is no toc)."""
    toc = book.parent / "_toc.yml"
    if toc.exists():
        files = re.findall(r"^\s*-?\s*(?:file|root):\s*(\S+)\s*$", toc.read_text(), flags=re.M)
        paths = [book.parent / f"{f}.ipynb" for f in files]
        return [p for p in paths if p.exists()]
    return sorted(book.glob("*.ipynb"))


def _code_cells(notebook: Path) -> Iterator[ast.Module]:
    for cell in json.loads(notebook.read_text())["cells"]:
        if cell["cell_type"] != "code":
            continue
        src = "".join(cell["source"])
        # IPython magics and shell escapes are not Python.
        src = "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in src.splitlines())
        try:
            yield ast.parse(src)
        except SyntaxError:
            continue


def _called(tree: ast.AST) -> Iterator[tuple[str, ast.Call]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None
            if name:
                yield name, node


def _literal_keywords(call: ast.Call, names: tuple[str, ...]) -> tuple[tuple[str, Any], ...]:
    out = []
    for kw in call.keywords:
        if kw.arg in names:
            try:
                out.append((kw.arg, ast.literal_eval(kw.value)))
            except ValueError:
                continue
    return tuple(sorted(out))


def _experiment_names(tree: ast.AST) -> list[str]:
    """String constants of a cell that name an experiment, in order."""
    return [n.value for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and n.value in EXPERIMENTS]


def chapter_requests(notebook: Path) -> list[Task]:
    """What one chapter's cells compute and store, in the order of its cells."""
    from safepg.thesis.cartpole_sweep import baseline_experiments
    from safepg.thesis.scorecard.rows import NEEDED, RANGE_VARIANTS
    from safepg.thesis.sweep_settings import SWEEP_SEEDS

    chapter, tasks = notebook.stem, []
    for tree in _code_cells(notebook):
        for name, call in _called(tree):
            if name == "run_experiment":
                tasks += [Task(chapter, e) for e in dict.fromkeys(_experiment_names(tree))]
            elif name == "scorecard" and any(kw.arg == "run" and isinstance(kw.value, ast.Constant)
                                             and kw.value.value is True for kw in call.keywords):
                tasks += [Task(chapter, e) for e in (*NEEDED, *RANGE_VARIANTS) if e in EXPERIMENTS]
            elif name == "run_sweep":
                tasks += [Task(chapter, e, seeds=SWEEP_SEEDS) for e in baseline_experiments()]
                tasks.append(Task(chapter, "cartpole-sweep"))
            elif name == "sweep_paths":
                tasks.append(Task(chapter, "table-5.1-sweep", "table-5.1-sweep",
                                  options=_literal_keywords(call, ("jobs", "seeds", "budget"))))
            elif name == "measure_runs":
                tasks.append(Task(chapter, "safety-mc", "safety-mc"))
            elif name == "pendulum_comparison":
                tasks.append(Task(chapter, COMPARISON, "comparison",
                                  options=_literal_keywords(call, ("seeds", "budget", "episodes"))))
    return tasks


def book_tasks(book: Path = BOOK) -> list[Task]:
    """Every task of every chapter, in the book's order, each once, each experiment after the
    experiment it warm-starts from (with as many seeds)."""
    out: list[Task] = []

    def seeds_of(t: Task) -> int:
        return t.seeds if t.seeds is not None else get_experiment(t.name).seeds

    def covered(t: Task) -> bool:
        if t.kind != "experiment":
            return any(o.kind == t.kind and o.options == t.options for o in out)
        return any(o.kind == "experiment" and o.name == t.name and seeds_of(o) >= seeds_of(t) for o in out)

    def add(t: Task) -> None:
        if t.kind == "experiment":
            for dep in sorted({c.warm_start for c in get_experiment(t.name).configs if c.warm_start}):
                add(Task(t.chapter, dep, seeds=seeds_of(t)))
        if not covered(t):
            out.append(t)

    for nb in chapters(book):
        for t in chapter_requests(nb):
            add(t)
    return out


# ------------------------------------------------------------------ progress
def _duration(seconds: float | None) -> str:
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
                        + (f", last build took {_duration(previous_s)}" if previous_s else ""))
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
        return (f"{self.trajectories:.3g} trajectories, {_duration(self.elapsed())} elapsed, "
                + ("time left unknown yet" if left is None else f"about {_duration(left)} left"))

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
                self.bar.status = f"{self.trajectories:.3g} trajectories, {_duration(self.elapsed())}"
                self.bar.close()
            self._print(f"{self.name}: {'done' if finished else 'stopped'}, {self.done}/{self.total} {self.unit}, "
                        f"{self.trajectories:.3g} trajectories in {_duration(self.elapsed())}")


def previous_seconds(book: Path, name: str) -> float | None:
    """The seconds the last measured build took for ``name`` (``benchmarks/book_timings.json``)."""
    try:
        t = json.loads((book.parent / "benchmarks" / "book_timings.json").read_text())
        return next(float(e["seconds"]) for e in t["experiments"] if e["name"] == name)
    except (OSError, ValueError, KeyError, TypeError, StopIteration):
        return None


@contextmanager
def _reporting_stored_runs(progress: Progress,
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


# ------------------------------------------------------------------ the tasks
def _say(stream: TextIO, text: str) -> None:
    print(f"{PREFIX}: {text}", file=stream, flush=True)


def _missing_runs(task: Task, root: Path) -> tuple[Experiment, Path, list[tuple[RunConfig, int]]]:
    """An experiment task's experiment (its seeds and budget applied), its folder under ``root``
    and its (config, seed) pairs that are not stored."""
    exp = scaled(get_experiment(task.name), seeds=task.seeds, budget=task.budget)
    folder = experiment_folder(exp, root)
    return exp, folder, [(c, k) for c in exp.configs for k in range(exp.seeds)
                         if runner.stored_run(folder, c, k) is None]


def _previous_share(task: Task, exp: Experiment, missing: list[tuple[RunConfig, int]], book: Path) -> float | None:
    """The seconds the last measured build took for ``missing`` (its share of the experiment's
    budget), or None if unknown or if the task has another budget."""
    last = previous_seconds(book, exp.name) if task.budget is None else None
    if last is None:
        return None
    return last * sum(c.budget for c, _ in missing) / (sum(c.budget for c in exp.configs) * exp.seeds)


def prefetch_experiment(task: Task, root: Path, jobs: int = -1, stream: TextIO | None = None,
                        tty: bool | None = None, interval: float | None = None, book: Path = BOOK) -> str:
    """Compute the missing runs of an experiment task into ``root``; ``"stored"`` or ``"computed"``."""
    stream = stream or sys.stdout
    exp, _, missing = _missing_runs(task, root)
    total = len(exp.configs) * exp.seeds
    if not missing:
        _say(stream, f"{exp.name}: stored ({total} runs)")
        return "stored"
    work = float(sum(c.budget for c, _ in missing))
    progress = Progress(exp.name, total, total - len(missing), work, stream=stream, tty=tty, interval=interval,
                        previous_s=_previous_share(task, exp, missing, book))
    try:
        with _reporting_stored_runs(progress):
            run_experiment(exp, jobs=jobs, root=root, progress=False)
    except BaseException:
        progress.close(finished=False)
        raise
    progress.close()
    return "computed"


def prefetch_experiments(tasks: list[Task], root: Path, jobs: int = -1, stream: TextIO | None = None,
                         tty: bool | None = None, interval: float | None = None,
                         book: Path = BOOK) -> dict[str, str]:
    """Compute the missing runs of several experiment tasks into ``root``, dispatched together
    (:func:`safepg.thesis.experiment_store.run_experiments`); ``{name: "stored" | "computed"}``.

    One progress bar (or plain lines) for all of them, and a line as each experiment is done.
    A single experiment with runs to compute is :func:`prefetch_experiment`.
    """
    stream = stream or sys.stdout
    done: dict[str, str] = {}
    pending = []
    for t in tasks:
        exp, folder, missing = _missing_runs(t, root)
        if missing:
            pending.append((t, exp, folder, missing))
        else:
            _say(stream, f"{exp.name}: stored ({len(exp.configs) * exp.seeds} runs)")
            done[exp.name] = "stored"
    if len(pending) == 1:
        done[pending[0][0].name] = prefetch_experiment(pending[0][0], root, jobs, stream, tty, interval, book)
    if len(pending) < 2:
        return done
    total = sum(len(exp.configs) * exp.seeds for _, exp, _, _ in pending)
    work = float(sum(c.budget for *_, missing in pending for c, _ in missing))
    shares = [_previous_share(t, exp, missing, book) for t, exp, _, missing in pending]
    previous = None if None in shares else sum(s for s in shares if s is not None)
    name = f"{len(pending)} experiments"
    progress = Progress(name, total, total - sum(len(m) for *_, m in pending), work, stream=stream, tty=tty,
                        interval=interval, previous_s=previous)
    names = {folder: exp.name for _, exp, folder, _ in pending}
    runs = {folder: len(missing) for *_, folder, missing in pending}
    left, trajectories = dict(runs), dict.fromkeys(runs, 0)

    def stored(rec: LearningRecord, folder: Path) -> bool:
        """Count a run of the experiments (not of one they start from, run at its own budget)."""
        if left.get(folder, 0) == 0:
            return False
        left[folder] -= 1
        trajectories[folder] += int(np.sum(rec.batch_size))
        if left[folder] == 0:
            progress.note(f"{names[folder]}: done, {runs[folder]}/{runs[folder]} runs, "
                          f"{trajectories[folder]:.3g} trajectories, at {_duration(progress.elapsed())}")
        return True

    try:
        with _reporting_stored_runs(progress, stored):
            run_experiments([exp for _, exp, _, _ in pending], jobs=jobs, root=root, progress=False)
    except BaseException:
        progress.close(finished=False)
        raise
    progress.close()
    done.update({exp.name: "computed" for _, exp, _, _ in pending})
    return done


def _sweep_path(root: Path, seeds: int = 1, budget: int = 1_000_000) -> Path:
    """The file ``sweep_paths(CHAPTER_PLAN, seeds, budget)`` stores."""
    from safepg.thesis.table51_sweep import CHAPTER_PLAN, sweep_file

    return sweep_file(CHAPTER_PLAN, seeds, budget, root)


def prefetch_sweep(task: Task, root: Path, stream: TextIO | None = None, tty: bool | None = None,
                   interval: float | None = None, book: Path = BOOK) -> str:
    """The Table 5.1 sweep of the lqg1d chapter (``sweep_paths`` with the chapter's arguments)."""
    from safepg.thesis.table51_sweep import sweep_paths

    stream = stream or sys.stdout
    opts = dict(task.options)
    if _sweep_path(root, opts.get("seeds", 1), opts.get("budget", 1_000_000)).exists():
        _say(stream, f"{task.name}: stored (1 sweep)")
        return "stored"
    progress = Progress(task.name, 1, 0, 1.0, unit="sweep", stream=stream, tty=tty, interval=interval,
                        previous_s=previous_seconds(book, task.name))
    try:
        result = sweep_paths(root=root, **opts)
        progress.advance(result.get("trajectories", 0), 1.0)
    except BaseException:
        progress.close(finished=False)
        raise
    progress.close()
    return "computed"


def safety_plan(root: Path) -> list[tuple[str, Any, np.ndarray, tuple[int, ...]]]:
    """The cart-pole chapter's safety measurements, one per run: (label, task, run's thetas, looks).

    :func:`safepg.thesis.safety_store.table_5_4_runs`, the chapter's own list, run by run; the
    table-5.4 experiments are read from ``root``.
    """
    from safepg.thesis import authors
    from safepg.thesis.experiment_store import load_experiment
    from safepg.thesis.safety_store import table_5_4_runs

    records = {name: load_experiment(name, root)
               for name in ("table-5.4-authors", "table-5.4-authors-theta-star", "table-5.4")}
    runs = table_5_4_runs(records, authors.cartpole_runs(), authors.table_5_4()["fixed"]["batches"])
    return [(f"{label}, run {k}", task, thetas, looks)
            for label, (task, thetas_list, looks) in runs.items() for k, thetas in enumerate(thetas_list)]


def prefetch_safety(task: Task, root: Path, stream: TextIO | None = None, tty: bool | None = None,
                    interval: float | None = None, book: Path = BOOK) -> str:
    """The cart-pole chapter's safety measurements, run by run, with the chapter's processes per run."""
    from safepg.safety_store import is_measured, measure_runs

    stream = stream or sys.stdout
    folder = root / "safety-mc"
    plan = safety_plan(root)
    todo = [p for p in plan if not is_measured(folder, p[1], p[2], 1.0, p[3])]
    if not todo:
        _say(stream, f"{task.name}: stored ({len(plan)} measured runs)")
        return "stored"
    work = [float(len(p[2]) * p[3][-1]) for p in todo]  # updates x largest look: the most rollouts it can take
    progress = Progress(task.name, len(plan), len(plan) - len(todo), sum(work), unit="measured runs", stream=stream,
                        tty=tty, interval=interval, previous_s=previous_seconds(book, task.name))
    try:
        for (_label, env, thetas, looks), w in zip(todo, work):
            out = measure_runs(env, [thetas], 1.0, folder, looks=looks, jobs=os.cpu_count() or 1)[0]
            progress.advance(out.counts()["rollouts"], w)
    except BaseException:
        progress.close(finished=False)
        raise
    progress.close()
    return "computed"


def _comparison(task: Task) -> Any:
    from safepg.comparison import pendulum_comparison

    return pendulum_comparison(**dict(task.options))


def prefetch_comparison(task: Task, root: Path, jobs: int = -1, stream: TextIO | None = None,
                        tty: bool | None = None, interval: float | None = None, book: Path = BOOK) -> str:
    """The pendulum chapter's comparison (:func:`safepg.comparison.run_comparison`): its step search,
    runs and safety measurements, a line as each ends; ``"stored"`` or ``"computed"``."""
    from safepg.comparison import is_computed, run_comparison

    stream, cmp = stream or sys.stdout, _comparison(task)
    if is_computed(cmp, root):
        _say(stream, f"{task.name}: stored (its comparison: the step search, the runs, their safety)")
        return "stored"
    started = time.monotonic()
    _say(stream, f"{task.name}: computing its step search, its runs and their safety measurements")
    run_comparison(cmp, root, jobs, report=lambda line: _say(stream, f"{task.name}: {line}"))
    _say(stream, f"{task.name}: done in {_duration(time.monotonic() - started)}")
    return "computed"


def _compile_once(tasks: list[Task], root: Path, jobs: int, stream: TextIO) -> None:
    """:func:`safepg.runner.compile_once` on the configs of the experiments that have runs to compute
    (and of the pendulum's comparison, if it has)."""
    from joblib import effective_n_jobs

    from safepg.comparison import is_computed

    configs = []
    for t in tasks:
        if t.kind == "comparison":
            cmp = _comparison(t)
            if not is_computed(cmp, root):
                configs += [*cmp.adaptive, *cmp.search_configs()]
            continue
        if t.kind == "experiment":
            exp = scaled(get_experiment(t.name), seeds=t.seeds, budget=t.budget)
            folder = experiment_folder(exp, root)
            # A file's presence is enough here (a stale or damaged one is recomputed all the same).
            configs += [c for c in exp.configs if not all(runner.run_path(folder, c, k).exists()
                                                          for k in range(exp.seeds))]
    started = time.monotonic()
    runs = runner.compile_once(configs, jobs)
    if runs:
        seconds = time.monotonic() - started
        (root / COMPILE_ONCE).mkdir(parents=True, exist_ok=True)
        # benchmarks/bench_book.py reads it
        runner.record_timing(root / COMPILE_ONCE, seconds, runs, effective_n_jobs(jobs))
        _say(stream, f"kernels compiled once, each task family in one worker, in {_duration(seconds)}")


def prefetch(book: Path = BOOK, root: Path | None = None, jobs: int = -1, stream: TextIO | None = None,
             tty: bool | None = None, interval: float | None = None,
             tasks: list[Task] | None = None) -> dict[str, str]:
    """Compute every task the chapters need (:func:`book_tasks`) into ``root`` (default: the
    ``results/`` beside ``book/``, the notebooks' store); returns ``{task name: "stored" | "computed"}``."""
    stream = stream or sys.stdout
    root = root if root is not None else book.parent / "results"
    tasks = book_tasks(book) if tasks is None else tasks
    started = time.monotonic()
    _say(stream, f"{len(tasks)} computation{'s' * (len(tasks) != 1)} the chapters need, stored in {root}")
    _compile_once(tasks, root, jobs, stream)
    kw: dict[str, Any] = dict(stream=stream, tty=tty, interval=interval, book=book)
    # The experiments first, together (no worker waits at the end of one), then the rest in order.
    done = prefetch_experiments([t for t in tasks if t.kind == "experiment"], root, jobs=jobs, **kw)
    for t in tasks:
        if t.kind == "experiment":
            continue
        if t.kind == "table-5.1-sweep":
            done[t.name] = prefetch_sweep(t, root, **kw)
        elif t.kind == "comparison":
            done[t.name] = prefetch_comparison(t, root, jobs=jobs, **kw)
        else:
            done[t.name] = prefetch_safety(t, root, **kw)
    computed = sum(v == "computed" for v in done.values())
    _say(stream, f"{computed} computed, {len(done) - computed} already stored, in "
                 f"{_duration(time.monotonic() - started)}")
    return done
