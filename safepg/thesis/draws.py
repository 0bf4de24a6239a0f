"""A second draw of the scorecard's campaign: the same experiments, seeds disjoint from the book's, scored by
the same rules, and every row's status under both.

The book's campaign (draw 1) runs seeds 0, 1, ...; the second draw runs the same configurations from seed
:data:`SECOND_DRAW_FIRST_SEED` on, in a results folder of its own, with the same starting counts and seed
rule (:mod:`safepg.thesis.seed_rule`). It confirms the verdicts: it is not a tuning set, and nothing of the
book reads it. ``python -m safepg two-draws`` runs it (outside ``make book`` and the tests) and prints
:func:`compare_draws`'s table.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from safepg.thesis.experiment_store import Campaign, read_campaign, run_experiments, write_campaign
from safepg.thesis.scorecard.rows import AUTHORS_VARIANTS, NEEDED, RANGE_VARIANTS, build_rows
from safepg.thesis.scorecard.rules import AUTHORS_ERROR_STATUS, AUTHORS_STATUS, INCONCLUSIVE_STATUS, Row
from safepg.thesis.scorecard.verdicts import RANDOM_KINDS, p_text
from safepg.thesis.seed_rule import plan_seeds

#: The second draw's first seed: far above any count of the first draw's (the cap is 20, Table 5.1's tail
#: cell runs 50), so that the two draws share no seed.
SECOND_DRAW_FIRST_SEED = 1_000_000
#: Statuses that reproduce the printed number, in either form.
REPRODUCED = ("reproduced", AUTHORS_STATUS, AUTHORS_ERROR_STATUS)
#: Statuses that say it is not reproduced.
NOT_REPRODUCED = ("differs (explained)", "open")


def scorecard_experiments() -> tuple[str, ...]:
    """Every experiment the scorecard reads (the warm-started ones bring their start)."""
    return NEEDED + RANGE_VARIANTS + AUTHORS_VARIANTS


def run_draw(root: Path, first_seed: int = SECOND_DRAW_FIRST_SEED, jobs: int = -1,
             stream: TextIO | None = None) -> Campaign:
    """Run the scorecard's campaign into ``root`` from ``first_seed``, then the seed rule on it.

    Raises
    ------
    ValueError
        If ``root`` already holds a campaign from another first seed.
    """
    stream = stream or sys.stdout
    campaign = read_campaign(root)
    if campaign.first_seed not in (0, first_seed) or (campaign.first_seed == 0 and campaign.seeds):
        raise ValueError(f"root {root} holds a campaign from seed {campaign.first_seed}, not {first_seed}")
    write_campaign(Campaign(first_seed, campaign.seeds), root)
    started = time.monotonic()
    run_experiments(list(scorecard_experiments()), jobs=jobs, root=root, progress=True)
    print(f"two-draws: the experiments in {time.monotonic() - started:.0f} s", file=stream, flush=True)
    return plan_seeds(root, build_rows, jobs, stream=stream)


@dataclass(frozen=True)
class Comparison:
    """The random rows under two draws.

    Attributes
    ----------
    rows : list of (Row, Row)
        Each random row under draw 1 and draw 2, in the scorecard's order.
    changed : list of (Row, Row)
        Those whose status differs.
    flips : list of (Row, Row)
        Those that move between reproduced (in either form) and "open" or "differs".
    inconclusive : (int, int)
        Inconclusive rows under each draw.
    """

    rows: list[tuple[Row, Row]]
    changed: list[tuple[Row, Row]]
    flips: list[tuple[Row, Row]]
    inconclusive: tuple[int, int]


def compare_draws(first: Sequence[Row], second: Sequence[Row]) -> Comparison:
    """The random rows of two scorecards matched by id.

    Raises
    ------
    ValueError
        If the two scorecards do not hold the same random rows.
    """
    one = {r.id: r for r in first if r.kind in RANDOM_KINDS}
    two = {r.id: r for r in second if r.kind in RANDOM_KINDS}
    if set(one) != set(two):
        raise ValueError(f"the draws' random rows differ: {sorted(set(one) ^ set(two))}")
    pairs = [(one[i], two[i]) for i in one]
    changed = [(a, b) for a, b in pairs if a.status != b.status]
    flips = [(a, b) for a, b in changed
             if (a.status in REPRODUCED and b.status in NOT_REPRODUCED)
             or (a.status in NOT_REPRODUCED and b.status in REPRODUCED)]
    return Comparison(pairs, changed, flips, (sum(a.status == INCONCLUSIVE_STATUS for a, _ in pairs),
                                              sum(b.status == INCONCLUSIVE_STATUS for _, b in pairs)))


def _p(r: Row) -> str:
    ours = "-" if r.p_value is None else p_text(r.p_value)
    theirs = "" if r.authors_p_value is None else f", authors' settings {p_text(r.authors_p_value)}"
    return f"{ours}{theirs}"


def comparison_text(c: Comparison) -> str:
    """Every random row's status under both draws, then the rows that differ with both draws' p-values,
    then the counts."""
    lines = ["row | draw 1 | draw 2"]
    lines += [f"{a.id} | {a.status} | {b.status}" for a, b in c.rows]
    lines.append("")
    lines.append(f"{len(c.changed)} of {len(c.rows)} random rows differ:")
    lines += [f"  {a.id}: {a.status} ({_p(a)}) -> {b.status} ({_p(b)})" for a, b in c.changed]
    lines.append(f"between reproduced (either form) and open or differs: {len(c.flips)}")
    lines += [f"  {a.id}" for a, _ in c.flips]
    n = len(c.rows)
    lines.append(f"inconclusive: {c.inconclusive[0]} of {n} (draw 1), {c.inconclusive[1]} of {n} (draw 2)")
    return "\n".join(lines)


__all__ = ["NOT_REPRODUCED", "REPRODUCED", "SECOND_DRAW_FIRST_SEED", "Comparison", "compare_draws",
           "comparison_text", "run_draw", "scorecard_experiments"]
