"""campaign.compile_once: one short run of each kind of config, each task family in one worker."""

from __future__ import annotations

from dataclasses import replace

from safepg.thesis import campaign
from safepg.thesis.experiments import get_experiment


def test_one_short_run_per_kind_of_config_and_none_for_warm_starts():
    # Table 5.3: the adaptive run and two fixed steps that differ only in their batch size (two
    # kinds); the cart-pole's baseline: one; a warm-started copy of it: left out.
    lqg2d = list(get_experiment("table-5.3").configs)
    cartpole = get_experiment("cartpole-baseline").configs[0]
    warm = replace(cartpole, name="warm", warm_start="cartpole-baseline", warm_start_key=cartpole.key())
    assert [c.algorithm for c in lqg2d] == ["adaptive", "vanilla", "vanilla"]
    assert campaign.compile_once([*lqg2d, cartpole, warm], jobs=2) == 3


def test_nothing_to_gain_nothing_run():
    # One worker compiles every kernel once anyway, and so do the workers of a single family.
    configs = list(get_experiment("table-5.3").configs) + [get_experiment("cartpole-baseline").configs[0]]
    assert campaign.compile_once(configs, jobs=1) == 0
    assert campaign.compile_once(list(get_experiment("table-5.3").configs), jobs=2) == 0
    assert campaign.compile_once([], jobs=2) == 0
