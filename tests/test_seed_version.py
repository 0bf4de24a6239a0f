"""A version bump of the results does not reseed: every run keeps the random numbers it had at version 4.

``RESULTS_VERSION`` names the numbers the library computes; a run's place in the store hashes it
(:meth:`RunConfig.key`), so a bump recomputes every run. The run's random numbers come from
:meth:`RunConfig.seed_key`, which hashes the definition with ``SEED_VERSION``, frozen at 4:
recomputed runs read the streams they read before, and their numbers move only where the
computation changed. ``tests/data/seed_keys.json`` holds every configuration's key as it was at
version 4 (the copy of ``run_keys.json`` made then); unlike ``run_keys.json`` it is never
regenerated.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

import safepg.runner as runner
import safepg.thesis.table51_sweep as sweep
from safepg.options import Adaptive, Batches
from safepg.runner import RunConfig
from safepg.thesis.experiments import EXPERIMENTS, _registry

SEEDED_AT_4 = json.loads((Path(__file__).parent / "data" / "seed_keys.json").read_text())


def test_every_config_seeds_from_its_version_4_key():
    assert sorted(SEEDED_AT_4) == sorted(EXPERIMENTS)
    for name, exp in EXPERIMENTS.items():
        assert {c.name: c.seed_key() for c in exp.configs} == SEEDED_AT_4[name], name


def test_a_bump_moves_the_store_not_the_seeds(monkeypatch):
    """Under another RESULTS_VERSION every key changes and no seed does, warm starts included (their
    definition names the seed key of the run they start from)."""
    before = {n: {c.name: (c.key(), c.seed_key(), c.seed(3).entropy) for c in e.configs}
              for n, e in EXPERIMENTS.items()}
    monkeypatch.setattr(runner, "RESULTS_VERSION", "bumped")
    after = _registry()  # built again: the warm starts' keys are bound at build time
    assert sorted(after) == sorted(before)
    warm = 0
    for name, exp in after.items():
        for c in exp.configs:
            key, seed_key, entropy = before[name][c.name]
            assert c.key() != key, (name, c.name)
            assert c.seed_key() == seed_key == SEEDED_AT_4[name][c.name], (name, c.name)
            assert c.seed(3).entropy == entropy
            warm += c.warm_start is not None
    assert warm > 0  # the warm-started configurations were among them


def test_the_same_seed_draws_the_same_numbers_after_a_bump(monkeypatch):
    cfg = RunConfig("small", method=Adaptive(batches=Batches(n_min=50)), task="lqg1d", theta0=(-0.3,), budget=400)
    a = cfg.run(1)
    monkeypatch.setattr(runner, "RESULTS_VERSION", "bumped")
    b = cfg.run(1)
    for field in ("batch_size", "theta", "J_hat", "grad", "eps"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    other = replace(cfg, sigma=0.9).run(1)  # the check can fail: another definition, other numbers
    assert not np.array_equal(other.J_hat, a.J_hat[: other.J_hat.size])


def test_the_sweep_seeds_do_not_follow_its_version(monkeypatch):
    variant = sweep.Variant()
    seed = sweep._seed(variant, -0.5, 1.0, 100, 1e-3, 0).entropy
    monkeypatch.setattr(sweep, "SWEEP_VERSION", "bumped")
    assert sweep._seed(variant, -0.5, 1.0, 100, 1e-3, 0).entropy == seed
    assert sweep._seed(variant, -0.5, 1.0, 100, 1e-3, 1).entropy != seed
