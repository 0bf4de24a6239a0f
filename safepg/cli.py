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
from safepg.learning import adaptive_pg, vanilla_pg
from safepg.options import Batches, ErrorModel, FixedStep, Gradient
from safepg.store import DamagedRunsError, DamagedRunWarning, results_dir
from safepg.thesis import experiment_store, experiments, report

ENVS = {"lqg1d": LQG.thesis_1d, "lqg2d": LQG.thesis_2d}


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


def _learn_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("learn", help="run one learning loop and print a JSON summary")
    p.add_argument("--env", choices=sorted(ENVS), default="lqg1d")
    p.add_argument("--estimator", choices=["reinforce", "gpomdp"], default="gpomdp")
    p.add_argument("--no-baseline", action="store_true", help="use b = 0")
    p.add_argument("--bound", choices=["chebyshev", "hoeffding", "bernstein"], default="chebyshev")
    p.add_argument("--empirical-range", action="store_true")
    p.add_argument("--delta", type=float, default=0.95)
    p.add_argument("--sigma", type=float, default=1.0)
    p.add_argument("--theta0", type=float, nargs="+", default=[0.0])
    p.add_argument("--budget", type=positive_integer, default=30_000_000, help="total trajectories (3e7 is fine)")
    p.add_argument("--n-min", type=positive_integer, default=100)
    p.add_argument("--n-max", type=positive_integer, default=500_000)
    p.add_argument("--fixed-alpha", type=float, help="vanilla PG with this step size")
    p.add_argument("--fixed-n", type=positive_integer, help="vanilla PG with this batch size")
    p.add_argument("--step", choices=["scalar", "coordinate"], default="scalar",
                   help="vanilla PG: update all components or only the largest")
    p.add_argument("--score-action", choices=["clipped", "raw"], default="clipped",
                   help="score the clipped action (authors' code) or the sampled one (unbiased)")
    p.add_argument("--seed", type=nonnegative_integer, default=0)
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _run_learn(args: argparse.Namespace) -> dict[str, Any]:
    env = ENVS[args.env]()
    theta0 = np.asarray(args.theta0, dtype=float)
    if theta0.size == 1:
        theta0 = np.full(env.dim**2, theta0[0]) * np.eye(env.dim).ravel() if env.dim > 1 else theta0
    gradient = Gradient(args.estimator, not args.no_baseline, args.score_action)
    common = dict(gradient=gradient, budget=args.budget, rng=args.seed, progress=not args.quiet)
    if args.fixed_alpha is not None or args.fixed_n is not None:
        if args.fixed_alpha is None or args.fixed_n is None:
            raise ValueError("--fixed-alpha and --fixed-n must be given together for vanilla PG")
        rec = vanilla_pg(env, theta0, args.sigma, batch_size=args.fixed_n, step=FixedStep(args.fixed_alpha, args.step),
                         **common)
    else:
        error = ErrorModel(args.bound, args.delta, "empirical" if args.empirical_range else "lemma")
        rec = adaptive_pg(env, theta0, args.sigma, error=error, batches=Batches(args.n_min, args.n_max), **common)
    out = rec.summary()
    out["J_star"] = env.performance(env.optimal_gain(), args.sigma)
    out["theta_star"] = env.optimal_gain().ravel().tolist()
    return out


class NothingStoredError(LookupError):
    """``report`` found no stored run of the experiment (the CLI exits with status 1)."""


class DamagedStoreError(LookupError):
    """``report`` found damaged run files (the CLI names each, says how to repair, exits with status 1)."""


def _experiment_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("list", help="name every experiment")
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


def _run_command(args: argparse.Namespace) -> str:
    """The ``run`` command that computes what ``report`` with these arguments reads."""
    extra = "".join(f" --{k} {getattr(args, k)}" for k in ("seeds", "budget") if getattr(args, k) is not None)
    return f"python -m safepg run {args.name}{extra}"


def _cmd_list(args: argparse.Namespace) -> None:
    for e in experiments.EXPERIMENTS.values():
        print(f"{e.name:12s} {len(e.configs):3d} configs x {e.seeds} seeds  {e.description}")


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
