"""safepg.comparison: the step search's rule and seeds, the judgement on common episodes, a small
comparison run twice (stored, seeded, resumable), the costs of a guarantee, and the runner's first seed."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from safepg import comparison
from safepg.bounds import bernstein, chebyshev, gpomdp_variance_factor
from safepg.comparison import (
    Comparison,
    StepSearch,
    choose_steps,
    final_returns,
    guarantee_costs,
    is_computed,
    pendulum_comparison,
    run_comparison,
    update_terms,
)
from safepg.constants import TaskConstants
from safepg.envs.pendulum import Pendulum
from safepg.meta import n_star_closed_form, n_star_search, penalty_constant
from safepg.options import FixedStep, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.runner import RunConfig, RunGroup, run_configs


def small(seeds: int = 2) -> Comparison:
    """The pendulum's comparison at a toy scale: every stage, in seconds."""
    full = pendulum_comparison(seeds=seeds, budget=1200, episodes=50)
    adaptive = tuple(replace(c, budget=1200) for c in full.adaptive[1:])
    return replace(full, adaptive=adaptive, search=StepSearch((1e-5, 1e-4), seeds=2, episodes=40), looks=(100,))


def test_choose_steps_takes_the_best_finite_mean_and_the_smaller_of_ties() -> None:
    scores = {100: {1e-4: -10.0, 1e-3: math.nan, 1e-5: -20.0}, 1000: {1e-4: -5.0, 3e-5: -5.0}}
    assert choose_steps(scores) == {100: 1e-4, 1000: 3e-5}
    with pytest.raises(ValueError, match="^scores"):
        choose_steps({100: {1e-3: math.nan}})


def test_final_returns_judge_every_policy_on_the_same_episodes() -> None:
    task = Pendulum()
    thetas = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.3], [0.0, 0.0, 0.0]])
    got = final_returns(task, thetas, 1.0, 200, 5)
    assert got[0] == got[2] and got[0] != got[1]
    sim = task.simulate(LinearGaussianPolicy(thetas[1:2], 1.0), 200, 5)
    assert got[1] == pytest.approx(sim.rewards.sum(axis=1).mean(), rel=1e-12)
    assert final_returns(task, thetas[:1], 1.0, 200, 6)[0] != got[0]  # other episodes


def test_a_small_comparison_is_stored_seeded_and_resumable(tmp_path: Path) -> None:
    cmp = small()
    lines: list[str] = []
    assert not is_computed(cmp, tmp_path)
    first = run_comparison(cmp, tmp_path, jobs=1, report=lines.append)
    assert is_computed(cmp, tmp_path)
    assert any("fixed steps chosen on seeds 1000-1001" in line for line in lines)
    # The search ran on seeds 1000 and 1001 only, the comparison on 0 and 1.
    search = sorted(p.name for p in (tmp_path / "pendulum" / "search").rglob("seed-*.npz"))
    assert set(search) == {"seed-1000.npz", "seed-1001.npz"}
    names = [c.name for c in cmp.configs(first.steps)]
    assert list(first.scores) == names and all(len(first.records[n]) == 2 for n in names)
    assert all(sorted(p.name for p in (tmp_path / "pendulum" / n).glob("*/seed-*.npz")) == ["seed-0.npz", "seed-1.npz"]
               for n in names)
    # Read back, not recomputed: the same numbers, no new file.
    files = sorted(p.stat().st_mtime_ns for p in tmp_path.rglob("*.npz"))
    again = run_comparison(cmp, tmp_path, jobs=1)
    assert sorted(p.stat().st_mtime_ns for p in tmp_path.rglob("*.npz")) == files
    for n in names:
        assert np.array_equal(first.scores[n], again.scores[n])
    assert first.start_score == again.start_score and first.steps == again.steps
    rows = first.summary(reps=200)
    assert [r["method"] for r in rows] == names and rows == again.summary(reps=200)
    poi = first.improvement(reps=200)
    assert len(poi) == len(cmp.adaptive) * 2 * len(cmp.batch_sizes)
    assert all(0 <= r["ci95"][0] <= r["p"] <= r["ci95"][1] <= 1 for r in poi)
    counts = first.safety_counts()
    assert set(counts) == {c.name for c in cmp.adaptive}
    for name, c in counts.items():
        moved = sum(int(np.any(np.diff(r.theta, axis=0) != 0, axis=1).sum()) for r in first.records[name])
        assert c["updates"] == moved and c["lowered"] + c["raised"] + c["undetermined"] == moved


def test_search_and_comparison_share_no_seed() -> None:
    cmp = pendulum_comparison()
    assert cmp.search.first_seed >= cmp.seeds
    assert cmp.seeds >= 20 and cmp.budget == 20_000 and cmp.episodes == 1000
    fixed = cmp.fixed_configs({100: 1e-4, 1000: 3e-5})
    assert [c.name for c in fixed] == ["N=100-safe-step", "N=100-fixed-step", "N=1000-safe-step",
                                       "N=1000-fixed-step"]
    assert isinstance(fixed[1].method, Vanilla) and fixed[1].method.step == FixedStep(1e-4)
    relaxed = cmp.adaptive[-1]
    assert relaxed.make_task().gamma == 1.0 and relaxed.make_task().constants_gamma == 0.9
    assert relaxed.method.departures.changed() == ("batch_constants", "maxima", "unguarded_step")


def test_guarantee_costs_are_the_bounds_closed_forms() -> None:
    task = Pendulum()
    rows = guarantee_costs(task, 1.0, 900.0, 2.5e6, 2e4, (0.95, 0.05))
    assert len(rows) == 10
    constants = TaskConstants.from_task(task, 1.0)
    c = penalty_constant(constants)
    cheb = rows[0]
    assert cheb["bound"] == "chebyshev" and cheb["Nstar"] == n_star_closed_form(
        900.0, chebyshev(0.95, gpomdp_variance_factor(constants)))
    bern_er = rows[4]
    assert bern_er["bound"] == "bernstein" and bern_er["empirical_range"]
    assert bern_er["Nstar"] == n_star_search(900.0, bernstein(0.95, 2.5e6, 2e4), c)
    assert all(r["c"] == c and r["alpha"] <= 1 / (2 * c) for r in rows)
    # A smaller delta (a surer step) costs more trajectories.
    assert all(a["Nstar"] <= b["Nstar"] for a, b in zip(rows[:5], rows[5:]))


def test_update_terms_read_the_records(tmp_path: Path) -> None:
    cfg = pendulum_comparison().adaptive[1]
    recs = run_configs([replace(cfg, budget=1500)], 2, tmp_path, jobs=1, progress=False)[cfg.name]
    terms = update_terms(recs)
    assert terms["updates"] == sum(r.iterations for r in recs)
    assert terms["c"] == recs[0].config["c"] and 0 <= terms["share_eps_below_g"] <= 1
    assert terms["alpha_max"] <= 1 / (2 * terms["c"])
    assert terms["moved_max"] == max(float(np.abs(r.theta - r.theta[0]).max()) for r in recs)


def test_run_group_first_seed(tmp_path: Path) -> None:
    cfg = RunConfig("x", method=Vanilla(100, FixedStep(1e-4)), task=Pendulum(), theta0=(0.0, 0.0, 0.0), budget=200)
    recs = run_configs([cfg], 2, tmp_path, jobs=1, progress=False, first_seed=5)["x"]
    stored = sorted(p.name for p in (tmp_path / "x" / cfg.key()).iterdir() if p.suffix == ".npz")
    assert stored == ["seed-5.npz", "seed-6.npz"]
    assert [r.config["seed"] for r in recs] == [5, 6]
    assert np.array_equal(recs[0].theta, cfg.run(5).theta)
    with pytest.raises(ValueError, match="^first_seed"):
        RunGroup([cfg], 1, tmp_path, first_seed=-1)
    # A warm-started config with another first seed takes its starts in the same order, one per seed
    # (a second draw of the thesis's campaign: tests/test_draws.py).


def test_module_names_its_exports() -> None:
    assert set(comparison.__all__) >= {"run_comparison", "pendulum_comparison", "guarantee_costs"}
