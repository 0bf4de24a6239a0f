"""The explorers' kernel-backed view (safepg/explorers/kernel_view.py), without a browser.

Every control of every book explorer redraws the figure; a move supersedes the running
computation instead of queueing behind it; an error is one line in the view, never a
traceback. The same views in JupyterLab and Chromium: tests/test_browser_lab.py.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

pytest.importorskip("ipywidgets")

from safepg.explorers.component import Explorer, Plot, Select, Slider  # noqa: E402
from safepg.thesis.explorers.curves import lqg_explorer, upsilon_explorer  # noqa: E402
from safepg.thesis.explorers.live_learner import live_batch_size_explorer  # noqa: E402


def other_value(c: Slider | Select) -> Any:
    """A value of control c other than its default (a slider's far end, a select's next option)."""
    if isinstance(c, Slider):
        return c.max if c.value != c.max else c.min
    values = [v for v, _ in c.options]
    return values[(values.index(c.value) + 1) % len(values)]


def explorers() -> dict[str, Explorer]:
    live = live_batch_size_explorer()
    return {"lqg": lqg_explorer(), "upsilon": upsilon_explorer(), "live": live}


@pytest.mark.parametrize("name", ["lqg", "upsilon", "live"])
def test_every_control_redraws(views, name):
    ex = explorers()[name]
    view = ex.interactive()
    views.append(view)
    if name == "live":
        view.controls["budget"].value = "10000"  # a short run per move (the default is 10^6 trajectories)
    assert view.wait(120), view.status.value
    for c in ex.controls:
        if name == "live" and c.name == "budget":
            continue
        before = view.figure.value
        view.controls[c.name].value = other_value(c)
        assert view.wait(120), view.status.value
        assert view.error.value == "", view.error.value
        assert view.drawn == view.values() and view.drawn[c.name] == other_value(c)
        assert view.figure.value != before, f"{c.name} did not change the figure"
        assert "drawn in" in view.status.value and view.progress.layout.visibility == "hidden"
    assert view.counts["failed"] == 0


def slow_explorer(steps: int = 200, pause: float = 0.01, fail_below: float | None = None) -> tuple[Explorer, list]:
    """An explorer whose computation takes ``steps`` x ``pause`` seconds and reports each step."""
    log: list[tuple[str, float]] = []

    def compute_py(p: dict[str, Any], progress=None) -> dict[str, Any]:
        log.append(("start", p["x"]))
        if fail_below is not None and p["x"] < fail_below:
            raise ValueError(f"x must be >= {fail_below}, got {p['x']}")
        for i in range(steps):
            time.sleep(pause)
            progress((i + 1) / steps, f"step {i + 1}")
        log.append(("end", p["x"]))
        return {"plots": {"P": {"series": [{"x": [0, 1], "y": [0, p["x"]]}]}}, "text": f"x = {p['x']}"}

    class Slow(Explorer):
        compute_reports_progress = True

    return Slow("slow", [Slider("x", "x", 0.0, 10.0, 1.0, 1.0)], [Plot("P")], "", compute_py), log


def test_a_move_supersedes_the_running_computation(views):
    ex, log = slow_explorer()  # 2 s per computation
    view = ex.interactive()
    views.append(view)
    deadline = time.monotonic() + 30
    while "%" not in view.status.value and time.monotonic() < deadline:  # progress is shown while it runs
        time.sleep(0.05)
    assert "computing…" in view.status.value and "step" in view.status.value
    assert view.progress.layout.visibility == "visible" and 0 < view.progress.value < 1
    start = time.monotonic()
    for x in (2.0, 3.0, 4.0, 5.0):  # a drag: four moves in a row while the first computation runs
        view.controls["x"].value = x
    assert view.wait(30)
    took = time.monotonic() - start
    # The first computation stopped, the moves in between were not computed: 5.0 was next
    # (or, if the worker took 2.0 before the others arrived, 2.0 was stopped too).
    assert log[0] == ("start", 1.0) and ("end", 1.0) not in log
    assert [e for e in log if e[0] == "end"] == [("end", 5.0)]
    assert len([e for e in log if e[0] == "start"]) <= 3
    # A move after a move: each one stops the computation of the one before.
    log.clear()
    for x in (6.0, 7.0, 8.0):
        view.controls["x"].value = x
        time.sleep(0.3)
    assert view.wait(30)
    assert [e for e in log if e[0] == "end"] == [("end", 8.0)] and ("start", 6.0) in log and ("start", 7.0) in log
    assert took < 2 * 2.0 + 1.5, f"moves queued behind each other: {took:.1f} s"
    assert view.drawn == {"x": 8.0} and view.counts["drawn"] == 2 and view.counts["superseded"] >= 3
    assert "x = 8.0" in view.text.value


def test_kernel_main_thread_stays_free(views):
    """The computation runs in the view's thread: the caller (the kernel) returns at once."""
    ex, _ = slow_explorer(steps=100, pause=0.02)
    start = time.monotonic()
    view = ex.interactive()
    views.append(view)
    view.controls["x"].value = 3.0
    assert time.monotonic() - start < 1.0
    assert view._thread is not threading.current_thread() and view.wait(30)


def test_an_error_is_one_line_and_no_traceback(views, capfd):
    ex, _ = slow_explorer(steps=2, pause=0.0, fail_below=0.5)
    view = ex.interactive()
    views.append(view)
    assert view.wait(30)
    good = view.figure.value
    view.controls["x"].value = 0.0
    assert view.wait(30)
    assert "ValueError: x must be &gt;= 0.5, got 0.0" in view.error.value and "x = 0" in view.error.value
    assert view.status.value == "error" and view.figure.value == good  # the last good figure stays
    assert isinstance(view.last_error, ValueError)
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err
    view.controls["x"].value = 2.0
    assert view.wait(30) and view.error.value == "" and view.figure.value != good


def test_live_learner_run_is_cancelled_by_a_move(views):
    """A 3·10^6-trajectory run with safepg stops at the batch after the move, not at its end."""
    ex = live_batch_size_explorer()
    view = ex.interactive()
    views.append(view)
    view.controls["budget"].value = "3000000"
    deadline = time.monotonic() + 120
    while "Algorithm 4.1:" not in view.status.value and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "trajectories" in view.status.value, view.status.value
    start = time.monotonic()
    view.controls["budget"].value = "10000"
    assert view.wait(120)
    took = time.monotonic() - start
    assert view.drawn["budget"] == "10000" and view.counts["superseded"] >= 1 and view.error.value == ""
    # One batch (at most 5·10^5 trajectories) and a 10^4-trajectory pair of runs, far from a 3·10^6 run.
    assert took < 30, f"{took:.1f} s"
