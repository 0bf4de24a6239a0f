"""What each chapter of the book computes and stores, declared as data.

``python -m safepg run-book`` (``make book``, :mod:`safepg.thesis.prefetch`) computes all of it before
the notebooks execute, so that they then only read; a notebook run on its own still computes whatever
is missing through the same calls. :data:`CHAPTERS` holds, for every notebook of ``_toc.yml``, in its
order, the calls of its code cells that compute and store (:class:`Computation`), in the order of its
cells; run-book reads this and parses no notebook.

A declaration that drifts from the notebooks would make run-book skip a computation (the notebook then
computes it on one core while the book builds) or compute one nobody reads, so
``tests/test_chapter_declarations.py`` checks it against the notebooks' code both ways: a computing call
of a notebook that is not declared here fails it, and so does a declaration no call of its notebook
matches; it also checks that each declared call computes the experiments declared for it (the
scorecard's and the cart-pole sweep's).

The module imports nothing of the library (it is read by every ``run-book`` and
:mod:`safepg.thesis.budget`, and the scorecard alone takes seconds to import): the names are strings,
checked by the tests.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

#: The functions a chapter computes and stores through, by the name its cells call them, with the module
#: that defines each (the tests import it, so a function renamed in the library fails them).
CALLS: dict[str, str] = {
    "run_experiment": "safepg.thesis.experiment_store",
    "scorecard": "safepg.thesis.scorecard.rows",  # with run=True; without it, it only reads
    "run_sweep": "safepg.thesis.cartpole_sweep",
    "sweep_paths": "safepg.thesis.table51_sweep",
    "measure_runs": "safepg.thesis.safety_store",
    "run_comparison": "safepg.comparison",
    "false_alarms_stored": "safepg.thesis.false_alarms",
}


@dataclass(frozen=True)
class Computation:
    """One call of a chapter's cells that computes and stores.

    Attributes
    ----------
    call : str
        The function the cells call, a key of :data:`CALLS`.
    experiments : tuple of str
        The experiments the call runs (:mod:`safepg.thesis.experiments` names): those a cell passes to
        ``run_experiment``, those ``scorecard(run=True)`` and ``run_sweep`` run. Empty for the other calls.
    seeds : int or None
        Seeds of each of ``experiments``; None: each experiment's own count (and the seed rule's, in the
        results folder's campaign).
    options : tuple of (str, value) pairs
        The literal keyword arguments of the call that change what it computes, sorted by name: those of
        ``sweep_paths``, and for ``run_comparison`` those of the ``pendulum_comparison`` it is given.
    """

    call: str
    experiments: tuple[str, ...] = ()
    seeds: int | None = None
    options: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if self.call not in CALLS:
            raise ValueError(f"call must be one of {sorted(CALLS)}, got {self.call!r}")
        if self.options != tuple(sorted(self.options)):
            raise ValueError(f"options must be sorted by name, got {self.options!r}")


#: Each notebook's computations (``book/<name>.ipynb`` by name), in ``_toc.yml``'s order, each
#: notebook's in the order of its cells.
CHAPTERS: Mapping[str, tuple[Computation, ...]] = {
    "scorecard": (
        # rows = scorecard(root=..., run=True): NEEDED and the range variant of safepg.thesis.scorecard.rows.
        Computation("scorecard", ("table-5.1", "table-5.1-printed-theta0", "table-5.2", "figures-5.5-5.6",
                                  "table-5.3", "cartpole-baseline", "table-5.4", "table-5.2-lemma-range")),
        Computation("false_alarms_stored"),
    ),
    "preliminaries": (),
    "adaptive_step": (),
    "adaptive_batch": (),
    "lqg1d": (
        Computation("run_experiment", ("table-5.1", "table-5.1-printed-theta0", "table-5.1-no-baseline",
                                       "table-5.2", "table-5.2-lemma-range", "table-5.2-raw-score",
                                       "table-5.1-authors", "table-5.2-authors", "figures-5.1-5.2-authors",
                                       "table-5.1-authors-tail")),
        Computation("sweep_paths", options=(("jobs", 2),)),
    ),
    "lqg2d": (
        Computation("run_experiment", ("figures-5.5-5.6", "table-5.3", "table-5.3-authors")),
    ),
    "cartpole": (
        Computation("run_experiment", ("cartpole-baseline", "table-5.4", "cartpole-baseline-authors",
                                       "table-5.4-authors", "table-5.4-authors-theta-star")),
        Computation("measure_runs"),
        # run_sweep(root=...): the sweep's baseline searches (SWEEP_SEEDS seeds each), then the sweep.
        Computation("run_sweep", ("cartpole-baseline", "cartpole-baseline-gamma=0.95",
                                  "cartpole-baseline-gamma=0.995", "cartpole-baseline-gamma=0.999",
                                  "cartpole-baseline-semi-implicit", "cartpole-baseline-angle=12",
                                  "cartpole-baseline-tau=0.01", "cartpole-baseline-init=0.1",
                                  "cartpole-baseline-normalised"), seeds=2),
        Computation("run_sweep", ("cartpole-sweep",)),
    ),
    "pendulum": (
        # run_comparison(pendulum_comparison(), ...): its step search, its runs and their safety.
        Computation("run_comparison"),
    ),
    "errata": (),
}


def chapter_experiments(chapter: str, declared: Mapping[str, tuple[Computation, ...]] = CHAPTERS) -> tuple[str, ...]:
    """The experiments a chapter's own cells run (``run_experiment``, ``run_sweep``), each once, in order.

    The scorecard's ``run=True`` is left out: the chapters run its experiments too, and they are
    counted there (:data:`safepg.thesis.budget.CHAPTER_EXPERIMENTS`).
    """
    names = [e for c in declared.get(chapter, ()) if c.call in ("run_experiment", "run_sweep") for e in c.experiments]
    return tuple(dict.fromkeys(names))


__all__ = ["CALLS", "CHAPTERS", "Computation", "chapter_experiments"]
