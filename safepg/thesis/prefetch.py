r"""What the book's chapters compute, computed before ``jupyter-book build``, with progress.

``make book`` runs ``python -m safepg run-book`` first. It reads what the chapters compute and
store as :mod:`safepg.thesis.chapters` declares it (``_toc.yml``'s notebooks, in the book's order;
no notebook is parsed here, and a test checks the declaration against the notebooks' calls), one
:class:`Task` per computation:

- the experiments of ``run_experiment``, ``scorecard(..., run=True)`` and ``run_sweep``, with the
  seeds declared (else each experiment's own), and the experiments they warm-start from;
- ``sweep_paths(...)``: the Table 5.1 sweep, with its declared keyword arguments;
- ``measure_runs(...)``: the cart-pole chapter's safety measurements (:func:`safety_plan`);
- ``run_comparison(pendulum_comparison(...))``: the pendulum chapter's comparison
  (:func:`safepg.comparison.run_comparison`: its step search, its runs and their safety
  measurements), with the declared keyword arguments of ``pendulum_comparison``;
- ``false_alarms_stored(...)``: the scorecard's false-alarm checks of its rules;

and after the experiments, the scorecard's seed rule (:mod:`safepg.thesis.seed_rule`): the seeds its
rows ask for beyond their experiments', computed the same way.

Each is computed into the store the notebooks read (``results/`` beside ``book/``, their
``Path("..") / "results"``) by the very functions the notebooks call, with the same joblib
parallelism (all cores), so that the notebooks then only read, and a notebook run on its own
still computes whatever is missing. Nothing is computed twice: what is stored is loaded and
reported as stored in one line. Each folder runs are computed in gets a line of how long they took
(``timing.jsonl``, :func:`safepg.thesis.campaign.record_timing`: run-book asks the runner for it, the
library called from a notebook does not), which :mod:`safepg.thesis.budget` reads.

Progress: on a terminal, one tqdm bar per task (runs done / total, trajectories, elapsed time
and time left), redrawn every second; otherwise (CI, a log) plain lines: one when a task
starts, one when it ends, and at most one progress line every :data:`safepg.thesis.progress.PLAIN_INTERVAL` seconds.
"""

from __future__ import annotations

import os
import re
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO, cast

import numpy as np

from safepg import runner
from safepg.record import LearningRecord
from safepg.runner import RunConfig
from safepg.thesis import campaign
from safepg.thesis.chapters import CHAPTERS, Computation
from safepg.thesis.experiment_store import experiment_folder, read_campaign, run_experiment, run_experiments
from safepg.thesis.experiments import Experiment, get_experiment, scaled
from safepg.thesis.progress import PREFIX, Progress, duration, previous_seconds
from safepg.thesis.progress import reporting_stored_runs as _reporting_stored_runs

#: The book's notebooks: ``book/`` beside the package (an editable install of this clone).
BOOK = Path(__file__).resolve().parents[2] / "book"
#: The store's folder of the time :func:`safepg.thesis.campaign.compile_once` took (its ``timing.jsonl``).
COMPILE_ONCE = "compile-once"
#: The name of the pendulum chapter's comparison task (and its folder of the store).
COMPARISON = "pendulum"


@dataclass(frozen=True)
class Task:
    """One stored computation a chapter needs.

    ``kind`` is ``"experiment"`` (``name`` in the registry, run for ``seeds`` seeds),
    ``"table-5.1-sweep"`` (``options``: the keyword arguments of ``sweep_paths``),
    ``"safety-mc"`` (the cart-pole chapter's Monte Carlo measurements), ``"comparison"`` (``options``:
    the keyword arguments of :func:`safepg.comparison.pendulum_comparison`) or ``"false-alarms"`` (the
    scorecard's measured false alarms).
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


#: The declared calls (:data:`safepg.thesis.chapters.CALLS`) whose computations are experiments.
EXPERIMENT_CALLS = frozenset({"run_experiment", "scorecard", "run_sweep"})
#: The task of each other declared call: (kind, name).
CALL_TASKS: dict[str, tuple[str, str]] = {
    "sweep_paths": ("table-5.1-sweep", "table-5.1-sweep"),
    "measure_runs": ("safety-mc", "safety-mc"),
    "run_comparison": ("comparison", COMPARISON),
    "false_alarms_stored": ("false-alarms", "false-alarms"),
}


def computation_tasks(chapter: str, computation: Computation) -> list[Task]:
    """The tasks of one declared computation of ``chapter``: one per experiment, or one of :data:`CALL_TASKS`."""
    if computation.call in EXPERIMENT_CALLS:
        return [Task(chapter, e, seeds=computation.seeds) for e in computation.experiments]
    kind, name = CALL_TASKS[computation.call]
    return [Task(chapter, name, kind, options=computation.options)]


def chapter_requests(notebook: Path, declared: Mapping[str, Sequence[Computation]] = CHAPTERS) -> list[Task]:
    """What one chapter computes and stores, as :mod:`safepg.thesis.chapters` declares it, in order.

    Raises
    ------
    ValueError
        If the notebook declares nothing (not even that it computes nothing): a chapter added to the
        book without a declaration would otherwise be computed by its notebook alone, unseen.
    """
    if notebook.stem not in declared:
        raise ValueError(f"{notebook.name}: no declaration of what it computes in safepg.thesis.chapters.CHAPTERS "
                         f"(declare its computing calls, or () if it has none)")
    return [t for c in declared[notebook.stem] for t in computation_tasks(notebook.stem, c)]


def book_tasks(book: Path = BOOK, declared: Mapping[str, Sequence[Computation]] = CHAPTERS) -> list[Task]:
    """Every task of every chapter of ``book`` (:func:`chapter_requests`), in the book's order, each once,
    each experiment after the experiment it warm-starts from (with as many seeds)."""
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
        for t in chapter_requests(nb, declared):
            add(t)
    return out


# ------------------------------------------------------------------ the tasks
def _say(stream: TextIO, text: str) -> None:
    print(f"{PREFIX}: {text}", file=stream, flush=True)


def _seeds(task: Task, exp: Experiment, root: Path) -> dict[str, range]:
    """Each config's seeds for an experiment task: the task's count, else the folder's campaign's."""
    campaign = read_campaign(root)
    counts = campaign.counts(exp) if task.seeds is None else {c.name: task.seeds for c in exp.configs}
    return {name: range(campaign.first_seed, campaign.first_seed + n) for name, n in counts.items()}


def _missing_runs(task: Task, root: Path) -> tuple[Experiment, Path, list[tuple[RunConfig, int]]]:
    """An experiment task's experiment (its seeds and budget applied), its folder under ``root``
    and its (config, seed) pairs that are not stored."""
    exp = scaled(get_experiment(task.name), seeds=task.seeds, budget=task.budget)
    folder = experiment_folder(exp, root)
    seeds = _seeds(task, exp, root)
    return exp, folder, [(c, k) for c in exp.configs for k in seeds[c.name]
                         if runner.stored_run(folder, c, k) is None]


def _total(task: Task, exp: Experiment, root: Path) -> int:
    """An experiment task's runs in all."""
    return sum(len(r) for r in _seeds(task, exp, root).values())


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
    total = _total(task, exp, root)
    if not missing:
        _say(stream, f"{exp.name}: stored ({total} runs)")
        return "stored"
    work = float(sum(c.budget for c, _ in missing))
    progress = Progress(exp.name, total, total - len(missing), work, stream=stream, tty=tty, interval=interval,
                        previous_s=_previous_share(task, exp, missing, book))
    try:
        with _reporting_stored_runs(progress):
            run_experiment(exp, jobs=jobs, root=root, progress=False, timing=True)
    except BaseException:
        progress.close(finished=False)
        raise
    progress.close()
    return "computed"


def _one_per_experiment(tasks: list[Task]) -> list[Task]:
    """One task per experiment and budget, the one with the most seeds, in the order first asked: two
    chapters may ask for one experiment at two counts (the scorecard's cart-pole baseline at 5 and 10),
    and the same seeds of one folder must not be computed, nor counted, twice."""
    best: dict[tuple[str, int | None], Task] = {}
    for t in tasks:
        key = (t.name, t.budget)
        if key not in best or _total_seeds(t) > _total_seeds(best[key]):
            best[key] = t
    return list(best.values())


def _total_seeds(t: Task) -> int:
    return scaled(get_experiment(t.name), seeds=t.seeds, budget=t.budget).seeds


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
    for t in _one_per_experiment(tasks):
        exp, folder, missing = _missing_runs(t, root)
        if missing:
            pending.append((t, exp, folder, missing))
        else:
            _say(stream, f"{exp.name}: stored ({_total(t, exp, root)} runs)")
            done[exp.name] = "stored"
    if len(pending) == 1:
        done[pending[0][0].name] = prefetch_experiment(pending[0][0], root, jobs, stream, tty, interval, book)
    if len(pending) < 2:
        return done
    total = sum(_total(t, exp, root) for t, exp, _, _ in pending)
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
                          f"{trajectories[folder]:.3g} trajectories, at {duration(progress.elapsed())}")
        return True

    try:
        with _reporting_stored_runs(progress, stored):
            run_experiments([exp for _, exp, _, _ in pending], jobs=jobs, root=root, progress=False, timing=True)
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


def prefetch_false_alarms(task: Task, root: Path, jobs: int = -1, stream: TextIO | None = None,
                          tty: bool | None = None, interval: float | None = None, book: Path = BOOK) -> str:
    """The scorecard's false-alarm checks (:func:`safepg.thesis.false_alarms.false_alarms_stored`) for the
    present rules."""
    from safepg.thesis.false_alarms import checks_path, false_alarms_stored

    stream = stream or sys.stdout
    if checks_path(root).exists():
        _say(stream, f"{task.name}: stored (the checks of the present rules)")
        return "stored"
    progress = Progress(task.name, 1, 0, 1.0, unit="checks", stream=stream, tty=tty, interval=interval,
                        previous_s=previous_seconds(book, task.name))
    try:
        false_alarms_stored(root, jobs=jobs)
        progress.advance(0, 1.0)
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
    run_comparison(cmp, root, jobs, report=lambda line: _say(stream, f"{task.name}: {line}"),
                   on_computed=campaign.record_timing)
    _say(stream, f"{task.name}: done in {duration(time.monotonic() - started)}")
    return "computed"


def _compile_once(tasks: list[Task], root: Path, jobs: int, stream: TextIO) -> None:
    """:func:`safepg.thesis.campaign.compile_once` on the configs of the experiments that have runs to compute
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
            seeds = _seeds(t, exp, root)
            configs += [c for c in exp.configs if not all(runner.is_stored(folder, c, k)
                                                          for k in seeds[c.name])]
    started = time.monotonic()
    runs = campaign.compile_once(configs, jobs)
    if runs:
        seconds = time.monotonic() - started
        (root / COMPILE_ONCE).mkdir(parents=True, exist_ok=True)
        # benchmarks/bench_book.py reads it
        campaign.record_timing(root / COMPILE_ONCE, seconds, runs, effective_n_jobs(jobs))
        _say(stream, f"kernels compiled once, each task family in one worker, in {duration(seconds)}")


def _scorecard_tasks(tasks: list[Task]) -> bool:
    """The tasks hold every experiment the scorecard reads, at their own seeds and budgets: the seed rule
    applies to them."""
    from safepg.thesis.scorecard.rows import AUTHORS_VARIANTS, NEEDED, RANGE_VARIANTS

    full = {t.name for t in tasks if t.seeds is None and t.budget is None}
    return set(NEEDED + RANGE_VARIANTS + AUTHORS_VARIANTS) <= full


def _apply_seed_rule(root: Path, jobs: int, book: Path, kw: dict[str, Any]) -> None:
    """:func:`safepg.thesis.seed_rule.plan_seeds` on the scorecard's rows, its runs computed like the
    chapters' experiments (progress, a line as each is done); remembered, so that a build whose runs and code
    did not change builds no row here."""
    from safepg.thesis.scorecard.rows import build_rows
    from safepg.thesis.seed_rule import plan_seeds

    stream = kw["stream"]
    started = time.monotonic()

    def run(names: list[str], folder: Path, n: int) -> None:
        prefetch_experiments([Task("scorecard", name) for name in names], folder, jobs=n, **kw)

    campaign = plan_seeds(root, lambda folder: build_rows(folder, book), jobs, run=run,
                          stream=cast(TextIO, _Prefixed(stream)), remember=True)
    _say(stream, f"seed rule: {len(campaign.seeds)} configurations beyond their experiment's seeds, in "
                 f"{duration(time.monotonic() - started)}")


class _Prefixed:
    """A text stream that writes each line with :data:`PREFIX`."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        body = text.rstrip("\n")
        if body:
            _say(self.stream, body)
        return len(text)

    def flush(self) -> None:
        self.stream.flush()


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
    experiments = [t for t in tasks if t.kind == "experiment"]
    done = prefetch_experiments(experiments, root, jobs=jobs, **kw)
    if _scorecard_tasks(experiments):
        _apply_seed_rule(root, jobs, book, kw)
    for t in tasks:
        if t.kind == "experiment":
            continue
        if t.kind == "table-5.1-sweep":
            done[t.name] = prefetch_sweep(t, root, **kw)
        elif t.kind == "false-alarms":
            done[t.name] = prefetch_false_alarms(t, root, jobs, **kw)
        elif t.kind == "comparison":
            done[t.name] = prefetch_comparison(t, root, jobs=jobs, **kw)
        else:
            done[t.name] = prefetch_safety(t, root, **kw)
    computed = sum(v == "computed" for v in done.values())
    _say(stream, f"{computed} computed, {len(done) - computed} already stored, in "
                 f"{duration(time.monotonic() - started)}")
    return done
