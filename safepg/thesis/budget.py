"""The campaign's time budget: what each chapter computes, the random numbers and simulated
steps it takes, the time it took, and how that compares with the random-number floor.

The floor of a piece of work is the time this machine's fastest generator needs to draw its
random numbers alone (the normals of the actions and the uniforms of the initial states),
on every core. No simulation can beat it by much: a step costs a few multiplies, a normal
about as many. benchmarks/bench_book.py measures the generators and builds the book from
empty; this module reads, from the results store the build filled, what was computed and
how long it took (``timing.jsonl`` of :func:`safepg.thesis.campaign.record_timing`, which ``run-book``
asks the runner for, the ``seconds`` of the Table 5.1 sweep and of the safety measurements).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from safepg import portable
from safepg.envs.cartpole import CartPole
from safepg.record import LearningRecord
from safepg.runner import RESULTS_VERSION
from safepg.thesis.campaign import TIMING_FILE
from safepg.thesis.chapters import CHAPTERS, chapter_experiments
from safepg.thesis.experiment_store import experiment_folder, load_experiment
from safepg.thesis.experiments import get_experiment
from safepg.thesis.prefetch import COMPARISON, COMPILE_ONCE

#: The experiments each chapter's notebook runs (its ``names`` list and its sweeps), in order: the
#: chapters that run any, as :mod:`safepg.thesis.chapters` declares them.
CHAPTER_EXPERIMENTS: dict[str, tuple[str, ...]] = {ch: chapter_experiments(ch) for ch in CHAPTERS
                                                   if chapter_experiments(ch)}
#: Stored computations that are not experiments: (folder, chapter).
TABLE_51_SWEEP = "table-5.1-sweep"
SAFETY_MC = "safety-mc"


@dataclass(frozen=True)
class Work:
    """One stored computation: its counts and the wall time it took.

    ``normals`` and ``uniforms`` are the random numbers the work needs; ``None`` where they
    are not known (the 2-D LQG's safety measurement, and measurements stored before their
    step count was).
    """

    name: str
    chapter: str
    trajectories: int
    steps: int | None
    normals: int | None
    uniforms: int | None
    seconds: float | None

    def floor(self, normal_rate: float, uniform_rate: float, step_rate: float | None = None) -> float | None:
        """Seconds to draw the work's random numbers at the given rates (numbers per second), or,
        with ``step_rate`` (bare steps per second, each with its normal), to make its steps and
        draw its uniforms."""
        if self.normals is None or self.uniforms is None:
            return None
        if step_rate is not None and self.steps is not None:
            return self.steps / step_rate + self.uniforms / uniform_rate
        return self.normals / normal_rate + self.uniforms / uniform_rate


def _timing_seconds(folder: Path) -> float | None:
    """Total seconds of the computing calls recorded in ``folder/timing.jsonl`` (this version's)."""
    path = folder / TIMING_FILE
    if not path.exists():
        return None
    lines = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    lines = [d for d in lines if d.get("results_version") == RESULTS_VERSION]
    return sum(d["seconds"] for d in lines) if lines else None


def experiment_work(name: str, chapter: str, root: Path) -> Work:
    """The counts of experiment ``name`` from its stored records, and its recorded time.

    LQG: H steps of m normals per trajectory, m uniforms for the initial state. Cart-pole: one
    normal per step it lived (the record's batch averages of the episode length give the
    steps), four uniforms per trajectory.
    """
    exp = get_experiment(name)
    recs = load_experiment(exp, root)
    totals = [0, 0, 0, 0]
    for cfg in exp.configs:
        env = cfg.make_task()
        for rec in recs.get(cfg.name, []):
            totals = [a + b for a, b in zip(totals, run_counts(env, rec))]
    traj, steps, normals, uniforms = totals
    return Work(name, chapter, traj, steps, normals, uniforms, _timing_seconds(experiment_folder(exp, root)))


def run_counts(env: Any, rec: LearningRecord) -> tuple[int, int, int, int]:
    """(trajectories, steps, normals, uniforms) of one run ``rec`` on task ``env``, as
    :func:`experiment_work` counts them."""
    n = int(rec.batch_size.sum())
    if isinstance(env, CartPole):
        # Each batch's mean episode length times its size, summed exactly (no BLAS).
        lived = round(portable.dot(rec.batch_size.astype(float), rec.J_hat))
        return n, lived, lived, 4 * n
    return n, n * env.horizon, n * env.horizon * env.dim, n * env.dim


def sweep_work(root: Path) -> Work | None:
    """The stored Table 5.1 sweeps (1-D LQG, H = 20): trajectories and seconds."""
    files = sorted((root / TABLE_51_SWEEP).glob("*.json"))
    if not files:
        return None
    data = [json.loads(p.read_text()) for p in files]
    traj = sum(d.get("trajectories", 0) for d in data)
    seconds = [d["seconds"] for d in data if "seconds" in d]
    return Work(TABLE_51_SWEEP, "lqg1d", traj, 20 * traj, 20 * traj, traj, sum(seconds) if seconds else None)


def safety_work(root: Path) -> list[Work]:
    """The stored safety measurements by chapter: rollouts, the steps they lived and seconds.

    On the cart-pole a rollout draws 4 uniforms and a normal per step lived; the 2-D LQG's
    random numbers are left uncounted (``None``).
    """
    by_chapter: dict[str, list[dict[str, Any]]] = {}
    for p in sorted((root / SAFETY_MC).glob("*.json")):
        d = json.loads(p.read_text())
        chapter = "cartpole" if json.loads(d["key"])[0].startswith("CartPole") else "lqg2d"
        by_chapter.setdefault(chapter, []).append(d)
    out = []
    for chapter, ds in by_chapter.items():
        rollouts = sum(2 * sum(d["outcomes"]["rollouts"]) for d in ds)
        seconds = [d["seconds"] for d in ds if "seconds" in d]
        # Measurements stored before the step count was recorded have none.
        counted = chapter == "cartpole" and all(d["outcomes"].get("steps") for d in ds)
        steps = sum(d["outcomes"]["steps"] for d in ds) if counted else None
        out.append(Work(SAFETY_MC, chapter, rollouts, steps, steps, 4 * rollouts if counted else None,
                        sum(seconds) if seconds else None))
    return out


def comparison_work(root: Path) -> Work | None:
    """The pendulum chapter's comparison (:func:`safepg.comparison.run_comparison`): its runs (the step
    search's and the methods'), every trajectory H = 200 steps of one normal and two uniforms, and its
    safety measurements (their steps from the stored outcomes), with the recorded seconds of all three."""
    from safepg.record import LearningRecord, RecordFileError

    folder = root / COMPARISON
    if not folder.is_dir():
        return None
    traj = steps = uniforms = 0
    for path in sorted(folder.rglob("seed-*.npz")):
        try:
            rec = LearningRecord.load(path)
        except (OSError, RecordFileError):  # a damaged file: its run is counted when computed again
            continue
        n = int(rec.batch_size.sum())
        traj += n
        steps += n * int(rec.config["task"]["horizon"])
        uniforms += 2 * n
    seconds = [_timing_seconds(folder), _timing_seconds(folder / "search")]
    for p in sorted((folder / "safety-mc").glob("*.json")):
        d = json.loads(p.read_text())
        rollouts = 2 * sum(d["outcomes"]["rollouts"])
        traj += rollouts
        steps += d["outcomes"].get("steps", 0)
        uniforms += 2 * rollouts
        seconds.append(d.get("seconds"))
    known = [x for x in seconds if x is not None]
    return Work(COMPARISON, "pendulum", traj, steps, steps, uniforms, sum(known) if known else None)


def compile_seconds(root: Path) -> float | None:
    """The seconds ``run-book`` spent compiling the kernels once before its tasks
    (:func:`safepg.thesis.campaign.compile_once`; in no experiment's time), or None if it did not."""
    return _timing_seconds(root / COMPILE_ONCE)


def campaign(root: Path) -> list[Work]:
    """Every stored computation of the book's campaign, chapter by chapter."""
    out = [experiment_work(n, ch, root) for ch, names in CHAPTER_EXPERIMENTS.items() for n in names]
    sweep = sweep_work(root)
    pendulum = comparison_work(root)
    return out + ([sweep] if sweep else []) + safety_work(root) + ([pendulum] if pendulum else [])


def budget_rows(works: list[Work], normal_rate: float, uniform_rate: float,
                chapter_seconds: Mapping[str, float] | None = None,
                step_rates: Mapping[str, float] | None = None) -> dict[str, list[dict[str, Any]]]:
    """Per experiment and per chapter: counts, floor, measured seconds and their ratio.

    A chapter's ``campaign_s`` is the sum of its computations' recorded times and its floor
    that of the computations whose random numbers are known, so its ratio errs high.
    ``chapter_seconds`` (the notebooks' execution times) adds each chapter's ``notebook_s``.
    ``step_rates`` gives, by chapter, a bare step's rate (a step with its normal and nothing of an
    estimator, e.g. the cart-pole's with its sine and cosine): that chapter's floor is its steps at
    that rate instead of its normals at ``normal_rate``.
    """
    step_rates = step_rates or {}
    def ratio(measured: float | None, floor: float | None) -> float | None:
        return None if measured is None or not floor else round(measured / floor, 2)

    rows = []
    for w in works:
        floor = w.floor(normal_rate, uniform_rate, step_rates.get(w.chapter))
        rows.append({**asdict(w), "floor_s": None if floor is None else round(floor, 2),
                     "ratio": ratio(w.seconds, floor)})
    chapters = []
    for ch in dict.fromkeys(w.chapter for w in works):
        mine = [r for r in rows if r["chapter"] == ch]
        floor = sum(r["floor_s"] or 0.0 for r in mine)
        measured = sum(r["seconds"] or 0.0 for r in mine)
        chapters.append({"chapter": ch, "trajectories": sum(r["trajectories"] for r in mine),
                         "steps": sum(r["steps"] or 0 for r in mine), "normals": sum(r["normals"] or 0 for r in mine),
                         "uniforms": sum(r["uniforms"] or 0 for r in mine), "floor_s": round(floor, 1),
                         "campaign_s": round(measured, 1), "ratio": ratio(measured, floor),
                         **({"notebook_s": chapter_seconds.get(ch)} if chapter_seconds else {})})
    return {"experiments": rows, "chapters": chapters}


def markdown(budget: Mapping[str, list[dict[str, Any]]]) -> str:
    """The per-chapter and per-experiment tables of :func:`budget_rows`, in Markdown."""
    def num(x: Any, fmt: str) -> str:
        return "—" if x is None else format(x, fmt)

    lines = ["| chapter | trajectories | steps | normals | floor (s) | campaign (s) | ratio | notebook (s) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for c in budget["chapters"]:
        lines.append(f"| {c['chapter']} | {c['trajectories']:.3g} | {c['steps']:.3g} | {c['normals']:.3g} | "
                     f"{c['floor_s']:.1f} | {c['campaign_s']:.1f} | {num(c['ratio'], '.2f')} | "
                     f"{num(c.get('notebook_s'), '.1f')} |")
    lines += ["", "| experiment | chapter | trajectories | normals | floor (s) | measured (s) | ratio |",
              "|---|---|---:|---:|---:|---:|---:|"]
    for r in budget["experiments"]:
        lines.append(f"| {r['name']} | {r['chapter']} | {r['trajectories']:.3g} | {num(r['normals'], '.3g')} | "
                     f"{num(r['floor_s'], '.2f')} | {num(r['seconds'], '.1f')} | {num(r['ratio'], '.2f')} |")
    return "\n".join(lines) + "\n"
