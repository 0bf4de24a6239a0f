"""The live batch-size explorer (Algorithm 4.1 in a Web Worker) in headless Chromium.

The explorer is rendered into its own page (no book build needed), opened from disk with
every non-file request blocked, and driven like a reader would: every control is moved and
must change the curves; a long run must draw progressively and be cancelled by the next
move; no console error may appear. The 10^6-trajectory adaptive run (the page's default) is held
against the statistics that tests/test_learner_js.py's agreement runs stored for the same settings
(``benchmarks/js_learner_agreement.json``). Its time is printed and written to
``_build/screenshots/live_learner_timing.json``; the limit on it is ``benchmarks/bench_js_learner.py``'s.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from browser_pages import OfflinePage

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "_build" / "screenshots"
pytestmark = pytest.mark.browser
#: The agreement runs' statistics (``python tests/test_learner_js.py`` writes them).
STATISTICS = ROOT / "benchmarks" / "js_learner_agreement.json"
#: Their row of the page's default settings: Bernstein (e.r.), G(PO)MDP, sigma = 1, delta = 0.95, 10^6 trajectories.
PAGE_DEFAULT = ("bernstein (e.r.) | gpomdp | 1.0", "mean J at 10^6")


def stored_runs(budget: int = 3_000_000, seeds: int = 1) -> tuple[dict[str, list[Any]], list[Any]]:
    """A Table 5.2 configuration run for the overlay (few seeds, up to the largest budget)."""
    from safepg.thesis.experiments import get_experiment, t52_name

    exp = get_experiment("table-5.2")
    configs = [replace(exp.config(t52_name(*k)), budget=budget)
               for k in (("gpomdp", "bernstein", True, 0.95),)]
    return {c.name: [c.run(k) for k in range(seeds)] for c in configs}, configs


@pytest.fixture(scope="module")
def explorer_page(tmp_path_factory) -> tuple[Path, Any]:
    from safepg.thesis.explorers.live_learner import live_batch_size_explorer

    records, configs = stored_runs()
    explorer = live_batch_size_explorer(records, configs)
    path = tmp_path_factory.mktemp("live") / "live.html"
    path.write_text(f'<!doctype html><html><head><meta charset="utf-8"><title>live learner</title></head>'
                    f"<body>{explorer.to_html()}</body></html>", encoding="utf-8")
    return path, explorer


def stored_statistics() -> dict[str, Any]:
    """The agreement runs' row of the page's default settings: JS and safepg means, standard deviations, seeds,
    and every seed's value."""
    rows = json.loads(STATISTICS.read_text())["1-D LQG"]
    return next(r for r in rows if (r["setting"], r["metric"]) == PAGE_DEFAULT)


def one_run_interval(mean: float, sd: float, seeds: int, level: float = 0.999) -> tuple[float, float]:
    """The ``level`` prediction interval for one new run of a process whose ``seeds`` runs had ``mean``, ``sd``."""
    from scipy import stats

    half = float(stats.t.ppf(0.5 + level / 2, seeds - 1)) * sd * math.sqrt(1 + 1 / seeds)
    return mean - half, mean + half


def values(pg: OfflinePage) -> dict:
    return pg.values()


def wait_done(pg: OfflinePage, job: int | None = None, timeout: float = 60_000) -> dict:
    """The explorer's values once the run of ``job`` (default: the latest) has finished."""
    pg.page.wait_for_function(
        """job => { const t = document.querySelector('.safepg-values').textContent;
                    if (!t) return false; const v = JSON.parse(t);
                    return v.result.values.done && (job === null || v.job === job); }""",
        arg=job, timeout=timeout)
    return values(pg)


def set_control(pg: OfflinePage, name: str, value: str) -> None:
    el = pg.page.locator(f'[data-param="{name}"]').first
    if el.evaluate("e => e.tagName") == "SELECT":
        el.select_option(value)
    else:
        el.fill(value)


def curves(v: dict) -> dict:
    return v["result"]["plots"]


def test_live_learner_runs_offline_and_every_control_redraws(browser, explorer_page):
    from safepg.envs.lqg import LQG

    path, explorer = explorer_page
    pg = OfflinePage(browser, path, width=1000, height=2000)
    first = wait_done(pg)
    res = first["result"]["values"]
    assert res["worker"], "the learner must run in a Web Worker"
    a = res["adaptive"]
    assert a["trajectories"] == 1_000_000 and a["first_batches"][0] == 100
    live_J = next(s for s in curves(first)["J"]["series"] if s["label"].startswith("Algorithm 4.1"))
    assert live_J["x"][0] == 1 and live_J["y"][0] == pytest.approx(LQG.thesis_1d().performance(0.0, 1.0), rel=1e-12)
    # The stored run (safepg) is drawn for the default settings, with safepg's numbers.
    py = explorer.compute_py(first["params"])
    assert res["thesis"]["found"] and res["thesis"] == py["values"]["thesis"]
    assert curves(first)["N"]["series"][0]["y"] == py["plots"]["N"]["series"][0]["y"]
    # Same structure as the Python twin, and the same kind of numbers (another generator): J at 10^6
    # trajectories inside the 99.9% prediction interval for one run of safepg's stored seeds (it detects a
    # shift of 4.6 of their standard deviations, 0.032 on -14.74, with 80% power) ...
    assert set(a) == set(py["values"]["adaptive"])
    stored = stored_statistics()
    lo, hi = one_run_interval(stored["py"], stored["py_sd"], int(stored["seeds"]))
    J = a["J_at"]["1000000"]
    assert lo <= J <= hi, (J, lo, hi)
    # ... and, the same learner with the same seed, the JavaScript agreement run of seed 0 under Node.
    assert int(first["params"]["seed"]) == 0 and J == pytest.approx(stored["js_values"][0], rel=1e-12)
    seconds = res["run_ms"]["adaptive"] / 1000
    SHOTS.mkdir(parents=True, exist_ok=True)
    (SHOTS / "live_learner_timing.json").write_text(json.dumps(
        {"adaptive_1e6_run_s": seconds, "vanilla_1e6_run_s": res["run_ms"]["vanilla"] / 1000,
         "page_elapsed_s": res["elapsed_ms"] / 1000}, indent=1))
    print(f"\n10^6-trajectory adaptive run in headless Chromium: {seconds:.3f} s "
          f"(both runs, page wall time {res['elapsed_ms'] / 1000:.3f} s); J at 10^6 {J:.4f}, one run of safepg's "
          f"{int(stored['seeds'])} stored seeds lies in [{lo:.4f}, {hi:.4f}] with probability 0.999")
    pg.page.locator(".safepg-explorer").first.screenshot(path=str(SHOTS / "live-learner.png"))

    # Every control: a move starts a new run whose curves differ from the previous ones.
    moves = [("budget", "100000"), ("delta", "0.5"), ("sigma", "0.75"), ("bound", "chebyshev"),
             ("bound", "hoeffding"), ("bound", "hoeffding-er"), ("bound", "bernstein"), ("estimator", "reinforce"),
             ("baseline", "off"), ("score", "raw"), ("seed", "7"), ("vanilla_n", "100"), ("vanilla_alpha", "1e-5"),
             ("vanilla_n", "off"), ("bound", "bernstein-er"), ("budget", "30000")]
    before = wait_done(pg)
    for name, value in moves:
        set_control(pg, name, value)
        after = wait_done(pg, before["job"] + 1)
        assert after["params"][name] == (value if name not in ("delta", "sigma", "seed") else float(value))
        assert curves(after) != curves(before), (name, value)
        assert after["result"]["values"]["worker"]
        before = after
    v = before["result"]["values"]
    assert v["vanilla"] is None and v["adaptive"]["trajectories"] == 30_000
    assert not v["thesis"]["found"]  # sigma = 0.75: no stored run
    assert not pg.remote, f"requests left the disk: {pg.remote}"
    assert not pg.errors, pg.errors


def test_long_run_draws_progressively_and_is_cancelled(browser, explorer_page):
    path, _ = explorer_page
    pg = OfflinePage(browser, path, width=1000, height=2000)
    wait_done(pg)
    job = values(pg)["job"]
    set_control(pg, "budget", "3000000")
    # Part of the run is drawn before it ends.
    pg.page.wait_for_function(
        """job => { const v = JSON.parse(document.querySelector('.safepg-values').textContent);
                    const a = v.result.values.adaptive;
                    return v.job === job && !v.result.values.done && a && a.trajectories > 0; }""",
        arg=job + 1, timeout=30_000)
    partial = values(pg)["result"]["values"]["adaptive"]["trajectories"]
    assert 0 < partial < 3_000_000
    set_control(pg, "seed", "3")  # cancels the 3*10^6 run
    done = wait_done(pg, job + 2)
    assert done["params"]["seed"] == 3.0 and done["params"]["budget"] == "3000000"
    assert done["result"]["values"]["adaptive"]["trajectories"] == 3_000_000
    assert not pg.errors and not pg.remote
    assert np.isfinite(done["result"]["values"]["adaptive"]["upsilon_bar"])
