"""How many seeds each configuration runs: a starting count by the kind of row it feeds, and blocks of
more where a row it feeds is inconclusive, up to a cap.

One configuration feeds several rows of the scorecard (``table-5.2`` feeds Table 5.2, Figures 5.1-5.4
and the step sizes), so the rule is applied per configuration: it runs the most seeds any row it feeds
asks for. A row asks for the starting count of its kind (:data:`START_SEEDS`); a column of it that is
inconclusive (:mod:`~safepg.thesis.scorecard.verdicts`: not rejected, its detectable difference above
what matters) asks for the seeds that would make it conclusive, in whole blocks
(:data:`~safepg.thesis.scorecard.verdicts.SEED_BLOCK`), at most :data:`SEED_CAP`, whether or not its test
rejects: the seeds added are decided by the tests' detectable differences, which depend on the runs'
spread and count, never on how far the printed number lies from ours, so that no test is repeated until
it rejects. The authors' settings' column asks only where ours does not reproduce the print.

:func:`plan_seeds` applies the rule to a results folder until nothing more is asked (the
extra seeds go to the folder's :class:`~safepg.thesis.experiment_store.Campaign`); ``run-book`` calls
it after the chapters' experiments. The campaign is a function of the stored runs and the code alone, so
``run-book`` lets it remember the state of its inputs (:func:`rule_inputs_key`) and, when nothing among them
changed since it last ran, keeps the campaign it left instead of building the scorecard's rows again.
"""

from __future__ import annotations

import hashlib
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TextIO

from safepg.thesis.experiment_store import (
    CAMPAIGN_FILE,
    Campaign,
    experiment_folder,
    read_campaign,
    run_experiments,
    write_campaign,
)
from safepg.thesis.experiments import CURVE_SEEDS, EXPERIMENTS, get_experiment
from safepg.thesis.scorecard.rules import Row
from safepg.thesis.scorecard.stored import FOLDER, hash_package, hash_run_files
from safepg.thesis.scorecard.verdicts import RANDOM_KINDS, SEED_BLOCK

#: The seeds a configuration starts with, by the kind of row it feeds (the most of its rows').
START_SEEDS: dict[str, int] = {"one run": 5, "mean of runs": 5, "read off a figure": 5, "whole curve": CURVE_SEEDS}
#: The most seeds the rule gives a configuration.
SEED_CAP = 20
#: The rule, as the scorecard page states it.
SEED_RULE = (
    "Each configuration starts with the seeds of the kind of row it feeds: " +
    ", ".join(f"{n} for a row of {kind}" for kind, n in START_SEEDS.items()) + " (the most, where it feeds "
    "several). Where the test of a column could not detect the difference that matters, its configurations "
    f"get seeds in blocks of {SEED_BLOCK}, as many as the test needs, up to {SEED_CAP}; the authors' settings' "
    "column asks only where ours does not reproduce the print. What is added depends on the runs' spread and count, "
    "never on the p-value, so that no test is repeated until it rejects. The rule is applied again after each "
    "addition, until no column asks for more.")


def _asks(row: Row) -> list[tuple[Sequence[str], int]]:
    """The seeds each column of a row asks for, with the configurations behind it: its start, or the seeds
    its test needs to detect the difference that matters (whether or not it rejects; the authors' column
    only where ours does not reproduce the print)."""
    start = START_SEEDS[row.kind]
    asks: list[tuple[Sequence[str], int]] = [(row.sources, start), (row.authors_sources, start)]
    if row.seeds_needed is not None:
        asks[0] = (row.sources, max(start, min(SEED_CAP, row.seeds_needed)))
    if row.status != "reproduced" and row.authors_seeds_needed is not None:
        asks[1] = (row.authors_sources, max(start, min(SEED_CAP, row.authors_seeds_needed)))
    return asks


def wanted_seeds(rows: Sequence[Row]) -> dict[str, int]:
    """The seeds the rule gives each configuration the random rows read, by ``"experiment/config"``."""
    out: dict[str, int] = {}
    for row in rows:
        if row.kind not in RANDOM_KINDS:
            continue
        for sources, seeds in _asks(row):
            for src in sources:
                out[src] = max(out.get(src, 0), seeds)
    return out


def _key(source: str) -> tuple[str, str]:
    """(experiment, config key) of ``"experiment/config"``."""
    name, config = source.split("/", 1)
    return name, get_experiment(name).config(config).key()


def planned_campaign(rows: Sequence[Row], campaign: Campaign) -> Campaign:
    """``campaign`` with the seeds the rule asks for on ``rows`` where they are more than it and the
    experiment's own (never fewer: a round of :func:`plan_seeds` never takes back what an earlier one gave,
    so the rule ends)."""
    seeds = dict(campaign.seeds)
    for source, n in wanted_seeds(rows).items():
        name, key = _key(source)
        if n > max(get_experiment(name).seeds, seeds.get(key, 0)):
            seeds[key] = n
    return Campaign(campaign.first_seed, seeds)


def added(campaign: Campaign) -> dict[str, int]:
    """The configurations that run more seeds than their experiment's, by ``"experiment/config"``."""
    out = {}
    for exp in EXPERIMENTS.values():
        for c in exp.configs:
            n = campaign.seeds.get(c.key())
            if n is not None and n > exp.seeds:
                out[f"{exp.name}/{c.name}"] = n
    return out


#: Where :func:`plan_seeds` remembers, inside a results folder, the key of the inputs it last left the campaign
#: for (beside the stored scorecard, which is not among the rule's inputs).
MEMO = Path(FOLDER) / "seed-rule.key"


def rule_inputs_key(root: Path) -> str:
    """SHA-256 (hex) of what the rule's campaign depends on in ``root``: every experiment's run files (path,
    size and modification time: a run written again is another input), the campaign file's bytes and the
    package's files (the rule, the scorecard's tests and the authors' data).

    The other folders of ``root`` (the sweep, the safety measurements, the false alarms, comparisons) are
    not read by the scorecard's rows, so they are left out: ``run-book`` writes them after the rule.
    """
    h = hashlib.sha256()
    for name in sorted(EXPERIMENTS):
        hash_run_files(h, root, experiment_folder(name, root))
    campaign = root / CAMPAIGN_FILE
    h.update(b"campaign " + (campaign.read_bytes() if campaign.is_file() else b"none") + b"\n")
    hash_package(h)
    return h.hexdigest()


def plan_seeds(root: Path, build: Callable[[Path], Sequence[Row]], jobs: int = -1, rounds: int = 6,
               run: Callable[[list[str], Path, int], object] | None = None,
               stream: TextIO | None = None, remember: bool = False) -> Campaign:
    """Apply the rule to the results folder ``root`` until no column asks for more seeds.

    The rule starts from the starting counts whatever the folder's campaign says, so the campaign it
    writes is a function of the runs alone: a folder that a change of the rule left with more seeds
    than the rule now gives ends with the same campaign as a folder filled from empty (the runs beyond
    it stay stored, unread, and are used again if the rule asks for them).

    Parameters
    ----------
    root : Path
        The results folder; its campaign (:func:`~safepg.thesis.experiment_store.read_campaign`) becomes
        the rule's: its first seed kept, its seeds the starting counts and what the rule adds.
    build : callable
        The scorecard's rows from the runs stored in a folder (``build(root)``).
    jobs : int
        Workers of the runs added (joblib's convention).
    rounds : int
        The most applications of the rule (each adds at least one block, so the cap ends it sooner).
    run : callable, optional
        ``run(experiment names, root, jobs)`` computes what the campaign now lacks (default
        :func:`~safepg.thesis.experiment_store.run_experiments`).
    stream : text stream, optional
        Where each round's additions are said (default stdout).
    remember : bool
        Store the key of the inputs the rule leaves (:func:`rule_inputs_key`, in :data:`MEMO`) and, when the
        folder's inputs still have that key, return its campaign without building any row: the rule on the
        same runs and code gives the same campaign. What the key cannot see is a ``build`` other than the
        package's scorecard, or code changed in memory: leave it False then.

    Returns
    -------
    Campaign
        The folder's campaign once the rule asks for nothing more.
    """
    stream = stream or sys.stdout
    memo = root / MEMO
    if remember and memo.is_file() and memo.read_text(encoding="utf-8") == rule_inputs_key(root):
        print("seed rule: no run and no code changed since it was last applied: its campaign stands",
              file=stream, flush=True)
        return read_campaign(root)
    campaign = _apply(root, build, jobs, rounds, run, stream)
    if remember:
        memo.parent.mkdir(parents=True, exist_ok=True)
        memo.write_text(rule_inputs_key(root), encoding="utf-8")
    return campaign


def _apply(root: Path, build: Callable[[Path], Sequence[Row]], jobs: int, rounds: int,
           run: Callable[[list[str], Path, int], object] | None, stream: TextIO) -> Campaign:
    """The rounds of :func:`plan_seeds`."""
    run = run or (lambda names, folder, n: run_experiments(names, jobs=n, root=folder, progress=False))
    campaign = Campaign(read_campaign(root).first_seed, {})
    if read_campaign(root) != campaign:
        write_campaign(campaign, root)
    for _ in range(rounds):
        planned = planned_campaign(build(root), campaign)
        more = {k: v for k, v in planned.seeds.items() if campaign.seeds.get(k) != v}
        if not more:
            return campaign
        write_campaign(planned, root)
        names = sorted({name for name, exp in EXPERIMENTS.items() for c in exp.configs if c.key() in more})
        shown = {s: n for s, n in added(planned).items() if s.split("/", 1)[0] in names}
        print(f"seed rule: more seeds for {len(more)} configuration{'s' * (len(more) != 1)}: "
              + ", ".join(f"{s} ({n})" for s, n in shown.items()), file=stream, flush=True)
        run(names, root, jobs)
        campaign = planned
    return campaign


def seed_table(campaign: Campaign) -> list[Mapping[str, object]]:
    """The configurations the rule gave more seeds, for the page: experiment, config, its experiment's seeds
    and the campaign's."""
    out: list[Mapping[str, object]] = []
    for source, n in added(campaign).items():
        name, config = source.split("/", 1)
        out.append({"experiment": name, "config": config, "start": get_experiment(name).seeds, "seeds": n})
    return out


__all__ = ["MEMO", "SEED_CAP", "SEED_RULE", "START_SEEDS", "added", "plan_seeds", "planned_campaign",
           "rule_inputs_key", "seed_table", "wanted_seeds"]
