"""Command line: ``python -m safepg learn ...`` (and the experiment commands)."""

# The top of both layers: ``learn`` runs the method, ``list``/``run``/``report`` the thesis's
# experiments. Nothing imports this module but ``__main__``.

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from decimal import Decimal, InvalidOperation
from typing import Any, NamedTuple, TypeVar

import numpy as np

from safepg.envs.lqg import LQG
from safepg.learning import learn
from safepg.option_fields import option_field, option_fields
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.store import DamagedRunsError, DamagedRunWarning, results_dir
from safepg.thesis import experiment_store, experiments, report

#: The tasks of ``learn`` (those with a closed-form J, which its summary reports).
TASKS = {"lqg1d": LQG.thesis_1d, "lqg2d": LQG.thesis_2d}
_Option = TypeVar("_Option")


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


def choice_or_number(choices: tuple[str, ...]) -> Callable[[str], str | float]:
    """argparse type of a field that holds one of ``choices`` or a number (ErrorModel.range)."""
    def value(text: str) -> str | float:
        if text in choices:
            return text
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {', '.join(repr(c) for c in choices)} or a number, "
                                             f"got {text!r}") from None
    return value


class OptionFlag(NamedTuple):
    """A ``learn`` flag that sets the field ``field`` of the option object ``owner``."""

    flag: str
    owner: type
    field: str
    #: What giving the flag does, for a flag whose presence chooses its object (vanilla PG, a
    #: SafeStep, a Target): such a flag has no default, whatever the field's.
    chooses: str | None = None


#: The option objects each field of which is a ``learn`` flag spelt as the field (``n_min`` is
#: ``--n-min``), with what their group's title adds to the class's name.
OPTION_GROUPS: dict[type, str] = {Gradient: "", ErrorModel: "Algorithm 4.1, or a SafeStep", Batches: "Algorithm 4.1",
                                  Departures: "Algorithm 4.1, the authors' ways of running it"}
#: The fixed-batch method's flags: they set fields of several objects, some under other names
#: (two objects have a ``kind``), so each is listed.
VANILLA_FLAGS = (
    OptionFlag("--batch-size", Vanilla, "batch_size", "run vanilla PG with this batch size instead of Algorithm 4.1"),
    OptionFlag("--alpha", FixedStep, "alpha"),
    OptionFlag("--safe-step", SafeStep, "kind",
               "a SafeStep of this kind, with the ErrorModel flags, instead of a fixed --alpha"),
    OptionFlag("--kind", FixedStep, "kind"),
    OptionFlag("--target", Target, "value", "stop once a batch's mean return reaches it"),
    OptionFlag("--update", Target, "update"),
)


def _group_flags(cls: type) -> tuple[OptionFlag, ...]:
    """The flags of an object of :data:`OPTION_GROUPS`: one per field, spelt as the field."""
    return tuple(OptionFlag(f"--{f.name.replace('_', '-')}", cls, f.name) for f in option_fields(cls))


def learn_flags() -> tuple[OptionFlag, ...]:
    """Every ``learn`` flag that sets an option object's field, in the order ``--help`` lists them."""
    return sum((_group_flags(cls) for cls in OPTION_GROUPS), ()) + VANILLA_FLAGS


def _add_option(group: argparse._ArgumentGroup, o: OptionFlag, group_owner: type) -> None:
    """``o``'s argument: its default, values and help read from its field (safepg.option_fields)."""
    f = option_field(o.owner, o.field)
    default = None if f.required or o.chooses else f.default
    kw: dict[str, Any] = {"default": default}
    if f.boolean:
        # A switch that is on by default can only be turned off (--no-baseline).
        kw["action"] = argparse.BooleanOptionalAction if default else "store_true"
    elif f.choices and f.number:
        kw["type"] = choice_or_number(f.choices)
        kw["metavar"] = "{" + ",".join(f.choices + ("NUMBER",)) + "}"
    elif f.choices and not f.integer:
        kw["choices"] = list(f.choices)
    elif f.number:
        kw["type"] = float
    elif f.integer and not f.choices:
        # Counts as users type them (1e6); the option object refuses a count below its own minimum.
        kw["type"] = positive_integer
    else:
        raise TypeError(f"{o.flag}: no command-line spelling of {o.owner.__name__}.{o.field}")
    where = "" if o.owner is group_owner else f"{o.owner.__name__}.{o.field}: "
    text = where + f.help + (f" Given: {o.chooses}." if o.chooses else "")
    # argparse formats help with %: the docstring's own % are escaped; the default is argparse's own.
    shown = default is not None and default is not False
    kw["help"] = text.replace("%", "%%") + (" (default: %(default)s)" if shown else "")
    group.add_argument(o.flag, **kw)


def _learn_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    # Each flag is a field of an option object (safepg.options), spelt as that field; its default,
    # values and help are the dataclass's (learn_flags), so that they cannot drift apart.
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
    for cls, note in OPTION_GROUPS.items():
        g = p.add_argument_group(f"{cls.__name__} ({note})" if note else cls.__name__)
        for o in _group_flags(cls):
            _add_option(g, o, cls)
    g = p.add_argument_group("Vanilla (fixed batch size)")
    for o in VANILLA_FLAGS:
        _add_option(g, o, Vanilla)
    return p


def _options(args: argparse.Namespace, cls: type[_Option]) -> _Option:
    """The option object of :data:`OPTION_GROUPS` ``cls``, from the flags of its fields."""
    return cls(**{f.name: getattr(args, f.name) for f in option_fields(cls)})


def _method(args: argparse.Namespace) -> Adaptive | Vanilla:
    """The method the ``learn`` flags describe, as option objects (each checks its own values)."""
    gradient, error = _options(args, Gradient), _options(args, ErrorModel)
    if args.batch_size is None:
        for flag in ("alpha", "safe_step", "target"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--{flag.replace('_', '-')} is an option of vanilla PG: give --batch-size too")
        return Adaptive(gradient, error, _options(args, Batches), _options(args, Departures))
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
    p = sub.add_parser("prune", help="remove the stored runs of definitions that no experiment asks for any longer")
    p.add_argument("names", nargs="*", help="experiments to prune (default: every experiment the book's chapters "
                                            "compute, at the seeds and budgets they ask for)")
    p.add_argument("--budget", type=positive_integer,
                   help="the named experiments' budget whose runs are kept (default: the thesis's)")
    p.add_argument("--dry-run", action="store_true", help="only list what would be removed")
    p.add_argument("--json", action="store_true", help="print {\"removed\": [paths]}")
    p.set_defaults(func=_cmd_prune)
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


def _cmd_prune(args: argparse.Namespace) -> dict[str, Any] | None:
    from safepg import runner

    if args.names:
        exps = [experiments.scaled(experiments.get_experiment(n), budget=args.budget) for n in args.names]
    else:
        from safepg.thesis import prefetch

        if args.budget is not None:
            raise ValueError("budget must come with the names of the experiments it applies to")
        exps = [experiments.scaled(experiments.get_experiment(t.name), seeds=t.seeds, budget=t.budget)
                for t in prefetch.book_tasks() if t.kind == "experiment"]
    asked: dict[Any, list[Any]] = {}
    for exp in exps:  # an experiment asked for at two budgets keeps both definitions in its folder
        asked.setdefault(experiment_store.experiment_folder(exp), []).extend(exp.configs)
    removed = [str(p) for folder, configs in asked.items() for p in runner.prune(folder, configs, args.dry_run)]
    if args.json:
        return {"removed": removed}
    for path in removed:
        print(f"{'would remove' if args.dry_run else 'removed'} {path}")
    print(f"{len(removed)} run file{'s' * (len(removed) != 1)} of definitions no longer asked for "
          f"{'found' if args.dry_run else 'removed'} under {results_dir()}")
    return None


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
