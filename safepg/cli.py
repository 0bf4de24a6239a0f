"""Command line: ``python -m safepg learn ...`` (and the experiment commands)."""

# The top of both layers: ``learn`` runs the method, ``list``/``run``/``report`` the thesis's
# experiments. Nothing imports this module but ``__main__``.

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from collections.abc import Sequence
from decimal import Decimal, InvalidOperation
from typing import Any

import numpy as np

from safepg.envs.lqg import LQG
from safepg.learning import learn
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.store import DamagedRunsError, DamagedRunWarning, results_dir
from safepg.thesis import experiment_store, experiments, report

#: The tasks of ``learn`` (those with a closed-form J, which its summary reports).
TASKS = {"lqg1d": LQG.thesis_1d, "lqg2d": LQG.thesis_2d}


def integer(text: str) -> int:
    """An integer count as users type it: ``3000000``, ``3_000_000`` or ``3e6``.

    Scientific notation is accepted when it is exactly a whole number (``1.5e3`` is 1500);
    ``1500.5`` or ``1e-3`` are refused rather than rounded. Parsed as a decimal, so no
    binary rounding can turn a non-integer into an integer.
    """
    try:
        value = Decimal(text.strip())
    except InvalidOperation:
        raise argparse.ArgumentTypeError(f"expected an integer such as 1000000 or 1e6, got {text!r}") from None
    if not value.is_finite() or value != value.to_integral_value():
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}")
    if value.adjusted() > 18:  # int() of 1e999999999 would build a billion-digit number
        raise argparse.ArgumentTypeError(f"expected at most 19 digits, got {text!r}")
    return int(value)


def positive_integer(text: str) -> int:
    """argparse type: an :func:`integer` >= 1 (seeds, budgets, batch sizes)."""
    value = integer(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def nonnegative_integer(text: str) -> int:
    """argparse type: an :func:`integer` >= 0 (a random seed)."""
    value = integer(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a non-negative integer, got {text!r}")
    return value


def jobs_integer(text: str) -> int:
    """argparse type: joblib's n_jobs, a number of workers or -1 for all cores (-2 all but one)."""
    value = integer(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"must be a number of parallel workers (>= 1) or negative "
                                         f"(-1: all cores, -2: all but one), got {text!r}")
    return value


def range_value(text: str) -> str | float:
    """argparse type of ``--range``: ``lemma``, ``empirical`` or a number (ErrorModel.range)."""
    if text in ("lemma", "empirical"):
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be 'lemma', 'empirical' or a number, got {text!r}") from None


def _learn_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    # Each flag is a field of an option object (safepg.options), spelt as that field.
    p = sub.add_parser("learn", help="run one learning loop and print a JSON summary",
                       description="Algorithm 4.1 (Adaptive), or vanilla PG with --batch-size (Vanilla). Each "
                                   "flag is the field of the option object named in its group.")
    p.add_argument("--task", choices=sorted(TASKS), default="lqg1d")
    p.add_argument("--theta0", type=float, nargs="+", default=[0.0])
    p.add_argument("--sigma", type=float, default=1.0)
    p.add_argument("--budget", type=positive_integer, default=30_000_000, help="total trajectories (3e7 is fine)")
    p.add_argument("--seed", type=nonnegative_integer, default=0)
    p.add_argument("--stop-on-divergence", action="store_true",
                   help="end the run when the gradient estimate is not finite (default: an error)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    g = p.add_argument_group("Gradient")
    g.add_argument("--estimator", choices=["reinforce", "gpomdp"], default="gpomdp")
    g.add_argument("--baseline", action=argparse.BooleanOptionalAction, default=True,
                   help="the variance-minimising baseline (--no-baseline: b = 0)")
    g.add_argument("--score-action", choices=["clipped", "raw"], default="clipped",
                   help="score the clipped action (authors' code) or the sampled one (unbiased)")
    g = p.add_argument_group("ErrorModel (Algorithm 4.1, or a SafeStep)")
    g.add_argument("--bound", choices=["chebyshev", "hoeffding", "bernstein"], default="chebyshev")
    g.add_argument("--delta", type=float, default=0.95)
    g.add_argument("--range", type=range_value, default="lemma", help="lemma, empirical, or a number")
    g = p.add_argument_group("Batches (Algorithm 4.1)")
    g.add_argument("--n-min", type=positive_integer, default=100)
    g.add_argument("--n-max", type=positive_integer, default=500_000)
    g.add_argument("--first", type=positive_integer, help="the first batch's size (default: N_min)")
    g = p.add_argument_group("Departures (Algorithm 4.1, the authors' ways of running it)")
    for name in ("batch_constants", "maxima", "unguarded_step"):
        g.add_argument(f"--{name.replace('_', '-')}", action="store_true")
    g = p.add_argument_group("Vanilla (fixed batch size)")
    g.add_argument("--batch-size", type=positive_integer, help="run vanilla PG with this batch size")
    g.add_argument("--alpha", type=float, help="FixedStep: the step size")
    g.add_argument("--safe-step", choices=["scalar", "coordinate"],
                   help="SafeStep of this kind, with the ErrorModel flags, instead of a fixed alpha")
    g.add_argument("--kind", choices=["scalar", "coordinate"], default="scalar",
                   help="FixedStep: update all components or only the largest")
    g.add_argument("--target", type=float, help="Target: stop once a batch's mean return reaches it")
    g.add_argument("--update", action="store_true", help="Target: the batch that reaches it still updates theta")


def _method(args: argparse.Namespace) -> Adaptive | Vanilla:
    """The method the ``learn`` flags describe, as option objects (each checks its own values)."""
    gradient = Gradient(args.estimator, args.baseline, args.score_action)
    error = ErrorModel(args.bound, args.delta, args.range)
    if args.batch_size is None:
        for flag in ("alpha", "safe_step", "target"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--{flag.replace('_', '-')} is an option of vanilla PG: give --batch-size too")
        return Adaptive(gradient, error, Batches(args.n_min, args.n_max, args.first),
                        Departures(args.batch_constants, args.maxima, args.unguarded_step))
    if (args.alpha is None) == (args.safe_step is None):
        raise ValueError("--batch-size needs a step: --alpha (a FixedStep) or --safe-step (a SafeStep)")
    step = FixedStep(args.alpha, args.kind) if args.alpha is not None else SafeStep(args.safe_step, error)
    return Vanilla(args.batch_size, step, gradient, None if args.target is None else Target(args.target, args.update))


def _run_learn(args: argparse.Namespace) -> dict[str, Any]:
    task = TASKS[args.task]()
    theta0 = np.asarray(args.theta0, dtype=float)
    if theta0.size == 1:
        theta0 = np.full(task.dim**2, theta0[0]) * np.eye(task.dim).ravel() if task.dim > 1 else theta0
    rec = learn(task, _method(args), theta0, args.sigma, budget=args.budget, rng=args.seed, progress=not args.quiet,
                stop_on_divergence=args.stop_on_divergence)
    out = rec.summary()
    out["J_star"] = task.performance(task.optimal_gain(), args.sigma)
    out["theta_star"] = task.optimal_gain().ravel().tolist()
    out["config"] = rec.config
    return out


class NothingStoredError(LookupError):
    """``report`` found no stored run of the experiment (the CLI exits with status 1)."""


class DamagedStoreError(LookupError):
    """``report`` found damaged run files (the CLI names each, says how to repair, exits with status 1)."""


def _experiment_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("list", help="name every experiment")
    p.add_argument("--json", action="store_true",
                   help="every experiment's configurations with their definitions and run keys, as JSON")
    p.set_defaults(func=_cmd_list)
    p = sub.add_parser("run", help="run an experiment (resumes; finished runs are kept)")
    p.add_argument("name")
    p.add_argument("--seeds", type=positive_integer, help="number of seeds (default: the thesis's)")
    p.add_argument("--budget", type=positive_integer, help="trajectories per run, e.g. 2e5 (default: the thesis's)")
    p.add_argument("--jobs", type=jobs_integer, default=-1,
                   help="parallel workers; -1 (default) all cores, -2 all but one")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=_cmd_run)
    p = sub.add_parser("report", help="summarise an experiment's stored runs")
    p.add_argument("name")
    p.add_argument("--seeds", type=positive_integer)
    p.add_argument("--budget", type=positive_integer)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_report)
    p = sub.add_parser("run-book", help="compute what the book's chapters need, with progress (make book)")
    p.add_argument("--book", help="the chapters' folder (default: book/ of this clone)")
    p.add_argument("--root", help="the results store (default: results/ beside the book's folder)")
    p.add_argument("--jobs", type=jobs_integer, default=-1, help="parallel workers, as the notebooks: all cores")
    p.add_argument("--list", action="store_true", help="only list what the chapters need")
    p.set_defaults(func=_cmd_run_book)
    p = sub.add_parser("two-draws", help="run the scorecard's campaign again on seeds disjoint from the book's and "
                                         "print every row's status under both draws")
    p.add_argument("--root", default="results-draw-2",
                   help="the second draw's results folder (default: results-draw-2); the first draw is "
                        "$SAFEPG_RESULTS or results/")
    p.add_argument("--jobs", type=jobs_integer, default=-1, help="parallel workers; -1 (default) all cores")
    p.add_argument("--json", action="store_true", help="print the comparison as JSON")
    p.set_defaults(func=_cmd_two_draws)


def _run_command(args: argparse.Namespace) -> str:
    """The ``run`` command that computes what ``report`` with these arguments reads."""
    extra = "".join(f" --{k} {getattr(args, k)}" for k in ("seeds", "budget") if getattr(args, k) is not None)
    return f"python -m safepg run {args.name}{extra}"


def _cmd_list(args: argparse.Namespace) -> dict[str, Any] | None:
    if args.json:
        return {e.name: {"description": e.description, "seeds": e.seeds,
                         "configs": {c.name: {"key": c.key(), "definition": c.definition()} for c in e.configs}}
                for e in experiments.EXPERIMENTS.values()}
    for e in experiments.EXPERIMENTS.values():
        print(f"{e.name:12s} {len(e.configs):3d} configs x {e.seeds} seeds  {e.description}")
    return None


def _cmd_run(args: argparse.Namespace) -> dict[str, Any]:
    exp = experiments.scaled(experiments.get_experiment(args.name), args.seeds, args.budget)
    recs = experiment_store.run_experiment(exp, jobs=args.jobs, progress=not args.quiet)
    return report.report(exp, recs)


def _cmd_run_book(args: argparse.Namespace) -> None:
    from pathlib import Path

    from safepg.thesis import prefetch

    book = Path(args.book) if args.book else prefetch.BOOK
    if args.list:
        for t in prefetch.book_tasks(book):
            print(f"{t.chapter:12s} {t.name}" + (f" ({t.seeds} seeds)" if t.seeds else ""))
        return
    prefetch.prefetch(book, Path(args.root) if args.root else None, jobs=args.jobs)


def _cmd_two_draws(args: argparse.Namespace) -> dict[str, Any] | None:
    import time
    from pathlib import Path

    from safepg.thesis import draws
    from safepg.thesis.scorecard.rows import build_rows

    started = time.monotonic()
    # With --json, standard output is the comparison alone: the draw's progress goes to standard error.
    draws.run_draw(Path(args.root), jobs=args.jobs, stream=sys.stderr if args.json else sys.stdout)
    seconds = time.monotonic() - started
    c = draws.compare_draws(build_rows(results_dir()), build_rows(Path(args.root)))
    if args.json:
        return {"seconds": seconds, "rows": [{"id": a.id, "draw_1": a.status, "draw_2": b.status,
                                              "p_1": [a.p_value, a.authors_p_value],
                                              "p_2": [b.p_value, b.authors_p_value]} for a, b in c.rows],
                "changed": [a.id for a, _ in c.changed], "flips": [a.id for a, _ in c.flips],
                "inconclusive": list(c.inconclusive)}
    print(draws.comparison_text(c))
    print(f"two-draws: the second draw and its seed rule in {seconds:.0f} s")
    return None


def _cmd_report(args: argparse.Namespace) -> dict[str, Any] | None:
    exp = experiments.scaled(experiments.get_experiment(args.name), args.seeds, args.budget)
    try:
        recs = experiment_store.load_experiment(exp, on_damaged="raise")
    except DamagedRunsError as err:
        # A report without them would look complete; ``run`` repairs them (set aside, recomputed).
        lines = [f"damaged run file {d.path}: {d.reason}" for d in err.damaged]
        lines.append(f"{len(err.damaged)} damaged run file{'s' * (len(err.damaged) > 1)} of {exp.name}; "
                     f"repair with: {_run_command(args)} (sets each aside as <file>.damaged-<time> and "
                     "computes its run again)")
        raise DamagedStoreError("\nsafepg: ".join(lines)) from None
    out = report.report(exp, recs)
    # The store is keyed by settings, so "nothing stored" often means other --seeds/--budget.
    stored, total = sum(r["seeds"] for r in out["configs"]), len(exp.configs) * exp.seeds
    if stored == 0:
        raise NothingStoredError(f"nothing stored for {exp.name} with these settings under {results_dir()}; "
                                 f"compute it first with: {_run_command(args)}")
    if stored < total:
        print(f"safepg: note: {stored} of {total} runs of {exp.name} stored; the rest with: "
              f"{_run_command(args)}", file=sys.stderr)
    if args.json:
        return out
    for row in out["configs"]:
        ups, ir = row["upsilon_bar"]["mean"], row["improvement_ratio"]["mean"]
        print(f"{row['name']:40s} seeds={row['seeds']}  upsilon_bar={ups}  improvement_ratio={ir}")
    return None


def _damage_in_one_line(show: Any) -> Any:
    """``warnings.showwarning`` printing a damaged run file as one line; others go to ``show``."""
    def show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                     file: Any = None, line: str | None = None) -> None:
        if issubclass(category, DamagedRunWarning):
            print(f"safepg: warning: {message}", file=sys.stderr if file is None else file)
        else:
            show(message, category, filename, lineno, file, line)
    return show_warning


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="safepg", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    _learn_parser(sub)
    _experiment_parsers(sub)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # a usage error (argparse printed it, exit status 2) or --help
        return exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _damage_in_one_line(warnings.showwarning)
            out = _run_learn(args) if args.command == "learn" else args.func(args)
        if out is not None:
            json.dump(out, sys.stdout, indent=None if args.command == "learn" else 1)
            sys.stdout.write("\n")
        sys.stdout.flush()
    except (ValueError, TypeError) as err:
        print(f"safepg: error: {err}", file=sys.stderr)
        return 2
    except (NothingStoredError, DamagedStoreError) as err:
        print(f"safepg: {err}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader stopped reading (``safepg report ... | head``): nothing is wrong with the
        # run. stdout goes to devnull so the interpreter's last flush does not raise again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
