"""The scorecard's rows: the experiments it reads, and :func:`scorecard`, which builds every row."""

from __future__ import annotations

from collections.abc import Collection, Mapping
from pathlib import Path

from safepg.record import LearningRecord
from safepg.store import results_dir
from safepg.thesis.experiment_store import load_experiment, run_experiment
from safepg.thesis.experiments import EXPERIMENTS, Experiment, get_experiment
from safepg.thesis.report import report
from safepg.thesis.scorecard.builder import Builder
from safepg.thesis.scorecard.curves import curve_rows
from safepg.thesis.scorecard.links import BOOK
from safepg.thesis.scorecard.rules import GROUPS, Row
from safepg.thesis.scorecard.runs import run_rows
from safepg.thesis.scorecard.stored import rows_if_stored, stored_rows

#: The experiments the scorecard reads; ``table-5.1-printed-theta0`` is Table 5.1 from the
#: printed theta_0, ``table-5.1`` our reconstruction of it (quoted beside).
NEEDED = ("table-5.1", "table-5.1-printed-theta0", "table-5.2", "figures-5.5-5.6", "table-5.3", "cartpole-baseline",
          "table-5.4")
#: The variant of Table 5.2 with Lemma 4.3.3's range (the text's), when the library defines it
#: (``table-5.2`` runs the authors' range).
RANGE_VARIANTS = ("table-5.2-lemma-range",)
#: Ours under the authors' settings (their code's where the text says otherwise or nothing). Read
#: from the store, never computed here (``python -m safepg run NAME`` computes them): rows whose
#: runs are missing or partly stored show them without judging them.
AUTHORS_VARIANTS = ("table-5.1-authors", "table-5.1-authors-tail", "table-5.2-authors", "figures-5.1-5.2-authors",
                    "table-5.3-authors", "cartpole-baseline-authors", "table-5.4-authors",
                    "table-5.4-authors-theta-star")


def _records(exp: Experiment, root: Path | None, run: bool, jobs: int) -> dict[str, list[LearningRecord]]:
    if run:
        return run_experiment(exp, root=root, jobs=jobs, progress=False)
    return load_experiment(exp, root)


#: The pages with rows measured on runs; the others' rows are all closed forms.
RUN_PAGES = ("lqg1d", "lqg2d", "cartpole")


def scorecard(root: Path | None = None, *, run: bool = False, experiments: Mapping[str, Experiment] | None = None,
              jobs: int = -1, book: Path | None = None, pages: Collection[str] | None = None,
              store: bool = True) -> list[Row]:
    """Every printed result of the thesis with ours, a status and a link.

    Parameters
    ----------
    root : Path, optional
        Results store (default ``$SAFEPG_RESULTS`` or ``results/``).
    run : bool
        Compute the missing runs of :data:`NEEDED` and :data:`RANGE_VARIANTS` first
        (:func:`~safepg.thesis.experiment_store.run_experiment`); with ``False`` only stored runs are
        read, and rows without runs are ``"open"``. The authors' variants
        (:data:`AUTHORS_VARIANTS`) are always only read.
    experiments : mapping, optional
        Replacements for the experiments of :data:`NEEDED`, :data:`RANGE_VARIANTS` and
        :data:`AUTHORS_VARIANTS` by name, e.g. :func:`~safepg.thesis.experiments.scaled` copies
        for a quick look or a test.
    jobs : int
        Parallel jobs when ``run`` (joblib's convention).
    book : Path, optional
        The book's folder, whose headings give the links' anchors (default ``book/``
        beside the package).
    pages : collection of str, optional
        Only the rows linking to these pages (``"errata"``, ...). Without any page of
        :data:`RUN_PAGES` no run is read: a theory chapter's counts are the stored rows' when
        ``store`` finds them, else its closed forms alone, and never load a record.
    store : bool
        With the default experiments and book, read the rows stored for the present state of
        their inputs, or build and store them (:mod:`~safepg.thesis.scorecard.stored`): the
        chapters of one build share one scorecard.

    Returns
    -------
    list of Row
        Ordered by :data:`GROUPS`, then as in the thesis.
    """
    shared = store and experiments is None and book is None
    base = results_dir() if root is None else Path(root)
    if pages is not None and not set(pages) & set(RUN_PAGES):
        # The build's shared rows when they are stored (reading them takes 0.2 s, deriving the
        # closed forms with sympy about 3 s); otherwise the closed forms alone, reading no run.
        rows = rows_if_stored(base, BOOK) if shared else None
        if rows is None:
            from safepg.thesis.scorecard.closed_forms import closed_form_rows  # sympy: 3 s to import

            b = Builder(book=book or BOOK)
            closed_form_rows(b)
            rows = b.rows
        return _on_pages(rows, pages)
    if shared:
        if run:
            for e in _default_experiments().values():
                run_experiment(e, root=base, jobs=jobs, progress=False)
        rows = stored_rows(base, BOOK, lambda: _build(base, False, None, jobs, BOOK))
    else:
        rows = _build(root, run, experiments, jobs, book or BOOK)
    return rows if pages is None else _on_pages(rows, pages)


def build_rows(root: Path, book: Path = BOOK) -> list[Row]:
    """Every row, built afresh from the runs stored under ``root`` (none computed, nothing stored)."""
    return _build(root, False, None, -1, book)


def _default_experiments() -> dict[str, Experiment]:
    """The experiments whose missing runs ``run=True`` computes: :data:`NEEDED` and the range variant."""
    exps = {n: get_experiment(n) for n in NEEDED}
    variant = next((n for n in RANGE_VARIANTS if n in EXPERIMENTS), None)
    if variant is not None:
        exps[variant] = get_experiment(variant)
    return exps


def _build(root: Path | None, run: bool, experiments: Mapping[str, Experiment] | None, jobs: int,
           book: Path) -> list[Row]:
    overrides = dict(experiments or {})
    known = NEEDED + RANGE_VARIANTS + AUTHORS_VARIANTS
    unknown = set(overrides) - set(known)
    if unknown:
        raise ValueError(f"experiments must be keyed by names in {known}, got {sorted(unknown)}")
    exps = {n: overrides.get(n) or get_experiment(n) for n in NEEDED}
    variant = next((n for n in RANGE_VARIANTS if n in overrides or n in EXPERIMENTS), None)
    if variant is not None:
        exps[variant] = overrides.get(variant) or get_experiment(variant)
    recs = {n: _records(e, root, run, jobs) for n, e in exps.items()}
    for n in AUTHORS_VARIANTS:
        if n in overrides or n in EXPERIMENTS:
            exps[n] = overrides.get(n) or get_experiment(n)
            recs[n] = load_experiment(exps[n], root)
    reps = {n: report(e, recs[n]) for n, e in exps.items()}

    from safepg.thesis.scorecard.closed_forms import closed_form_rows  # sympy: 3 s to import

    b = Builder(book=book)
    closed_form_rows(b)
    run_rows(b, exps, reps, recs, variant)
    curve_rows(b, recs)
    order = {g: i for i, g in enumerate(GROUPS)}
    return sorted(b.rows, key=lambda r: order[r.group])  # stable: the thesis's order within a group


def _on_pages(rows: list[Row], pages: Collection[str]) -> list[Row]:
    order = {g: i for i, g in enumerate(GROUPS)}
    keep = [r for r in rows if r.link.split(".html", 1)[0] in set(pages)]
    return sorted(keep, key=lambda r: order[r.group])
