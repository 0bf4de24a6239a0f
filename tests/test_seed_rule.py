"""The seed rule (safepg.thesis.seed_rule): blocks up to the cap, the authors' column only where ours
does not reproduce, and a campaign that depends on the runs alone, not on the folder's history."""

from __future__ import annotations

import io
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from safepg.thesis.experiment_store import Campaign, read_campaign, write_campaign
from safepg.thesis.experiments import get_experiment
from safepg.thesis.seed_rule import MEMO, SEED_CAP, START_SEEDS, added, plan_seeds, rule_inputs_key, wanted_seeds

OURS = "table-5.1-authors/sigma=0.5-N=1000-alpha=1e-05"
THEIRS = "table-5.4/adaptive"
STALE = "table-5.1-authors/sigma=0.5-N=1000-alpha=1e-06"


@dataclass
class FakeRow:
    """What the rule reads of a row."""

    kind: str = "one run"
    sources: tuple[str, ...] = (OURS,)
    authors_sources: tuple[str, ...] = ()
    seeds_needed: int | None = None
    authors_seeds_needed: int | None = None
    status: str = "open"


def _seeds(root: Path, source: str) -> int:
    name, config = source.split("/", 1)
    exp = get_experiment(name)
    return read_campaign(root).counts(exp)[config]


def test_a_column_asks_its_start_then_what_its_test_needs_up_to_the_cap() -> None:
    assert wanted_seeds([FakeRow()]) == {OURS: START_SEEDS["one run"]}
    assert wanted_seeds([FakeRow(seeds_needed=15)]) == {OURS: 15}
    assert wanted_seeds([FakeRow(seeds_needed=400)]) == {OURS: SEED_CAP}
    # a configuration feeding two rows runs the most either asks for
    assert wanted_seeds([FakeRow(seeds_needed=10), FakeRow(kind="whole curve")]) == {OURS: 10}
    # rows that are not random ask nothing
    assert wanted_seeds([FakeRow(kind="closed form", seeds_needed=20)]) == {}


def test_the_authors_column_asks_only_where_ours_does_not_reproduce() -> None:
    row = FakeRow(authors_sources=(THEIRS,), authors_seeds_needed=15)
    assert wanted_seeds([row])[THEIRS] == 15
    row.status = "reproduced"
    assert wanted_seeds([row])[THEIRS] == START_SEEDS["one run"]


def _plan(root: Path, needed: dict[int, int | None], remember: bool = False,
          builds: list[Path] | None = None) -> tuple[Campaign, list[list[str]]]:
    """plan_seeds with a scorecard whose one row needs ``needed[seeds it has]`` seeds, and no runs; each
    build of the rows is appended to ``builds``."""
    calls: list[list[str]] = []

    def build(folder: Path) -> list[Any]:
        if builds is not None:
            builds.append(folder)
        return [FakeRow(seeds_needed=needed.get(_seeds(folder, OURS)))]

    def run(names: list[str], folder: Path, jobs: int) -> None:
        calls.append(names)

    return plan_seeds(root, build, run=run, stream=io.StringIO(), remember=remember), calls


def test_the_rule_adds_blocks_until_nothing_more_is_asked(tmp_path: Path) -> None:
    campaign, calls = _plan(tmp_path, {5: 10, 10: 15, 15: None})
    assert added(campaign) == {OURS: 15}
    assert read_campaign(tmp_path) == campaign
    assert calls == [["table-5.1-authors"], ["table-5.1-authors"]]  # one run per round that added seeds
    # a round never takes back what an earlier one gave: 15 stays though 15 seeds ask for 10
    campaign, _ = _plan(tmp_path / "b", {5: 15, 15: 10})
    assert added(campaign) == {OURS: 15}


def test_the_campaign_is_the_rule_s_whatever_the_folder_held_before(tmp_path: Path) -> None:
    """A folder whose campaign an earlier rule grew (a stale configuration, and more seeds than the rule now
    gives) ends with the campaign of a folder filled from empty."""
    fresh, _ = _plan(tmp_path / "fresh", {5: 10, 10: None})
    stale = tmp_path / "stale"
    cfg = {name: get_experiment(name.split("/")[0]).config(name.split("/", 1)[1]).key() for name in (OURS, STALE)}
    write_campaign(Campaign(0, {cfg[OURS]: 20, cfg[STALE]: 10}), stale)
    again, _ = _plan(stale, {5: 10, 10: None})
    assert again == fresh and added(again) == {OURS: 10}
    assert read_campaign(stale) == fresh
    # the first seed, which names the draw, is kept
    draw = tmp_path / "draw"
    write_campaign(Campaign(1_000_000, {cfg[STALE]: 10}), draw)
    campaign, _ = _plan(draw, {5: None})
    assert campaign == Campaign(1_000_000, {})


def test_a_remembered_rule_builds_no_row_until_a_run_or_the_campaign_changes(tmp_path: Path) -> None:
    """With ``remember``, a folder whose runs, campaign and code are as the rule left them keeps its campaign
    without a row built; a run written again, a new run, or another campaign makes the rule run again, and
    a file outside the experiments' folders (the sweep's, written after the rule) does not."""
    run_file = tmp_path / OURS.split("/")[0] / "some-config" / "seed-0.npz"
    run_file.parent.mkdir(parents=True)
    run_file.write_bytes(b"a run")
    builds: list[Path] = []
    first, _ = _plan(tmp_path, {5: 10, 10: None}, remember=True, builds=builds)
    assert len(builds) == 2 and (tmp_path / MEMO).read_text(encoding="utf-8") == rule_inputs_key(tmp_path)

    builds.clear()
    again, calls = _plan(tmp_path, {5: 10, 10: None}, remember=True, builds=builds)
    assert (again, builds, calls) == (first, [], [])

    (tmp_path / "table-5.1-sweep").mkdir()
    (tmp_path / "table-5.1-sweep" / "sweep.npz").write_bytes(b"not read by the rows")
    _plan(tmp_path, {5: 10, 10: None}, remember=True, builds=builds)
    assert builds == []

    # without remember, the memo is neither read nor written
    _plan(tmp_path, {5: 10, 10: None}, builds=builds)
    assert len(builds) == 2
    key = (tmp_path / MEMO).read_text(encoding="utf-8")

    changes = [
        lambda: os.utime(run_file, ns=(1, run_file.stat().st_mtime_ns + 1_000_000)),  # written again
        lambda: run_file.with_name("seed-1.npz").write_bytes(b"another run"),
        lambda: write_campaign(Campaign(0, {"not-a-config": 7}), tmp_path),
    ]
    for change in changes:
        change()
        assert rule_inputs_key(tmp_path) != key
        builds.clear()
        campaign, _ = _plan(tmp_path, {5: 10, 10: None}, remember=True, builds=builds)
        assert campaign == first and len(builds) == 2
        key = (tmp_path / MEMO).read_text(encoding="utf-8")


def test_the_rule_s_key_sees_the_package(tmp_path: Path, monkeypatch: Any) -> None:
    """Another file in the package (code changed on disk) gives another key."""
    import safepg.thesis.scorecard.stored as stored

    package = tmp_path / "package"
    package.mkdir()
    (package / "rule.py").write_text("SEED_CAP = 20\n")
    monkeypatch.setattr(stored, "PACKAGE", package)
    key = rule_inputs_key(tmp_path)
    assert rule_inputs_key(tmp_path) == key
    (package / "rule.py").write_text("SEED_CAP = 30\n")
    assert rule_inputs_key(tmp_path) != key
