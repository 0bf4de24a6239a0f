"""Every configuration of every experiment keeps the run key it had.

Stored runs (``<results>/<experiment>/<config>/<key>/seed-<k>.npz``) are found, and accepted, by
their configuration's :meth:`safepg.runner.RunConfig.key`: a key that changes makes every
stored run of that configuration stale, so the whole campaign (hours of computation) would be
recomputed, and a refactor of the options or of how a configuration is spelt must not change
any key. ``tests/data/run_keys.json`` holds ``{experiment: {config: key}}`` as captured when the
key became the hash of the whole definition (RESULTS_VERSION 4); it is data, not a computation of
the present code.

When ``safepg.runner.RESULTS_VERSION`` is bumped on purpose (a change that alters the numbers
a run produces), every key changes: regenerate the file then, and only then, with::

    .venv/bin/python -c "import json; from safepg.thesis.experiments import EXPERIMENTS; \\
    print(json.dumps({e.name: {c.name: c.key() for c in e.configs} for e in EXPERIMENTS.values()}, \\
    indent=1, sort_keys=True))" > tests/data/run_keys.json

and say in the commit which RESULTS_VERSION it was made with.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from safepg.thesis.experiments import EXPERIMENTS

RECORDED = json.loads((Path(__file__).parent / "data" / "run_keys.json").read_text())


def test_the_recorded_experiments_are_the_experiments():
    assert sorted(RECORDED) == sorted(EXPERIMENTS)


@pytest.mark.parametrize("name", sorted(EXPERIMENTS))
def test_every_config_keeps_its_recorded_key(name):
    exp = EXPERIMENTS[name]
    assert {c.name: c.key() for c in exp.configs} == RECORDED[name]


def test_the_check_can_fail():
    """A changed setting changes the key (so the comparison above is not vacuous)."""
    from dataclasses import replace

    cfg = EXPERIMENTS["table-5.3"].config("adaptive")
    assert replace(cfg, sigma=0.5).key() != RECORDED["table-5.3"]["adaptive"]
    assert replace(cfg, name="renamed").key() == RECORDED["table-5.3"]["adaptive"]  # the name is not in the key
