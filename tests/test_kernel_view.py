"""The explorers' kernel-backed view (safepg/explorers/kernel_view.py), without a browser.

Every control of every book explorer redraws the figure; a move supersedes the running
computation instead of queueing behind it; an error is one line in the view, never a
traceback. The same views in JupyterLab and Chromium: tests/test_browser_lab.py.
"""

from __future__ import annotations

import threading
from typing import Any

import pytest

from conftest import import_or_fail

import_or_fail("ipywidgets")

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
    moved = 0
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
        moved += 1
    assert moved == len(ex.controls) - (name == "live") >= 1  # every control moved but the live one's budget
    assert view.counts["failed"] == 0


class Gate:
    """The computations of a test explorer, driven by events instead of clocks.

    The computation of x logs ``("start", x)``, sets ``started[x]``, then reports progress (each report is
    the view's cancellation point) until ``release[x]`` is set, and logs ``("end", x)``. Values in ``hold``
    are not released: their computation ends only when a move supersedes it, so a test that reaches idle
    with such a computation started shows that the move stopped it. Every other value runs through at once.
    """

    def __init__(self, hold: tuple[float, ...] = ()) -> None:
        values = [float(v) for v in range(11)]  # the slider's values, each with its events made up front
        self.started = {v: threading.Event() for v in values}
        self.release = {v: threading.Event() for v in values}
        for v in values:
            if v not in hold:
                self.release[v].set()
        self.log: list[tuple[str, float]] = []
        self.threads: set[str] = set()

    def release_all(self) -> None:
        for e in self.release.values():
            e.set()


def gated_explorer(hold: tuple[float, ...] = (), fail_below: float | None = None) -> tuple[Explorer, Gate]:
    """An explorer whose computation of x is held until released (:class:`Gate`), or raises below ``fail_below``."""
    gate = Gate(hold)

    def compute_py(p: dict[str, Any], progress=None) -> dict[str, Any]:
        x = p["x"]
        gate.log.append(("start", x))
        gate.threads.add(threading.current_thread().name)
        gate.started[x].set()
        if fail_below is not None and x < fail_below:
            raise ValueError(f"x must be >= {fail_below}, got {x}")
        while not gate.release[x].wait(0.005):
            progress(0.5, f"holding x = {x}")
        progress(1.0, "released")
        gate.log.append(("end", x))
        return {"plots": {"P": {"series": [{"x": [0, 1], "y": [0, x]}]}}, "text": f"x = {x}"}

    class Gated(Explorer):
        compute_reports_progress = True

    return Gated("gated", [Slider("x", "x", 0.0, 10.0, 1.0, 1.0)], [Plot("P")], "", compute_py), gate


def when(widget: Any, predicate: Any) -> threading.Event:
    """An event set once ``predicate(widget.value)`` holds (now, or at a later change of the value)."""
    event = threading.Event()

    def check(change: dict[str, Any]) -> None:
        if predicate(change["new"]):
            event.set()

    widget.observe(check, names="value")
    check({"new": widget.value})
    return event


#: Seconds any single wait may take before the test fails: a safety net, never a measurement.
WAIT = 60


def test_a_move_supersedes_the_running_computation(views):
    ex, gate = gated_explorer(hold=(1.0, 2.0, 3.0, 4.0, 6.0, 7.0))
    view = ex.interactive()
    views.append(view)
    try:
        assert gate.started[1.0].wait(WAIT)
        # Progress is shown while the (held) computation runs.
        assert when(view.status, lambda v: "%" in v).wait(WAIT), view.status.value
        assert "computing…" in view.status.value and "holding" in view.status.value
        assert view.progress.layout.visibility == "visible" and 0 < view.progress.value < 1
        for x in (2.0, 3.0, 4.0, 5.0):  # a drag: four moves in a row while the first computation runs
            view.controls["x"].value = x
        # Idle with 5.0 drawn: the computation of 1.0, which nothing releases, was stopped by the moves; the
        # moves in between were not computed (or, if the worker took 2.0 before the others came, stopped too).
        assert view.wait(WAIT), view.status.value
        assert gate.log[0] == ("start", 1.0) and ("end", 1.0) not in gate.log
        assert [e for e in gate.log if e[0] == "end"] == [("end", 5.0)]
        assert len([e for e in gate.log if e[0] == "start"]) <= 3
        # A move after a move: each one stops the computation of the one before, once it has started.
        gate.log.clear()
        for x in (6.0, 7.0, 8.0):
            view.controls["x"].value = x
            assert gate.started[x].wait(WAIT), x
        assert view.wait(WAIT), view.status.value
        assert gate.log == [("start", 6.0), ("start", 7.0), ("start", 8.0), ("end", 8.0)]
        assert view.drawn == {"x": 8.0} and view.counts["drawn"] == 2 and view.counts["superseded"] >= 3
        assert "x = 8.0" in view.text.value
    finally:
        gate.release_all()


def test_kernel_main_thread_stays_free(views):
    """The computation runs in the view's thread: the caller (the kernel) returns while it is still running."""
    ex, gate = gated_explorer(hold=(3.0,))
    view = ex.interactive()
    views.append(view)
    try:
        assert view.wait(WAIT)  # x = 1.0, released
        view.controls["x"].value = 3.0  # returns, with the computation of 3.0 started or about to start, and held
        assert gate.started[3.0].wait(WAIT)
        assert ("end", 3.0) not in gate.log and not view.wait(0)  # still running: the caller did not wait for it
        assert gate.threads == {view._thread.name} and view._thread is not threading.current_thread()
        gate.release[3.0].set()
        assert view.wait(WAIT) and gate.log[-1] == ("end", 3.0) and view.drawn == {"x": 3.0}
    finally:
        gate.release_all()


def test_an_error_is_one_line_and_no_traceback(views, capfd):
    ex, _ = gated_explorer(fail_below=0.5)
    view = ex.interactive()
    views.append(view)
    assert view.wait(WAIT)
    good = view.figure.value
    view.controls["x"].value = 0.0
    assert view.wait(WAIT)
    assert "ValueError: x must be &gt;= 0.5, got 0.0" in view.error.value and "x = 0" in view.error.value
    assert view.status.value == "error" and view.figure.value == good  # the last good figure stays
    assert isinstance(view.last_error, ValueError)
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err
    view.controls["x"].value = 2.0
    assert view.wait(WAIT) and view.error.value == "" and view.figure.value != good


def test_live_learner_run_is_cancelled_by_a_move(views):
    """A 3·10^6-trajectory run with safepg stops at its first progress report after the move, far from its end.

    The run's reports pass through a spy: once the status line shows the run's progress, the spy holds the
    worker at its next report (between two batches) until the test has moved the budget; the run must then
    stop at that report, with no batch after it.
    """
    ex = live_batch_size_explorer()
    compute = ex.compute_py
    armed, holding, moved = threading.Event(), threading.Event(), threading.Event()
    reports: list[tuple[str, float]] = []

    def spy(p: dict[str, Any], progress=None) -> dict[str, Any]:
        def report(fraction: float, message: str = "") -> None:
            reports.append((p["budget"], fraction))
            if p["budget"] == "3000000" and armed.is_set() and not moved.is_set():
                holding.set()
                moved.wait(WAIT)
            progress(fraction, message)

        return compute(p, progress=report)

    ex.compute_py = spy
    view = ex.interactive()
    views.append(view)
    view.controls["budget"].value = "3000000"
    shown = when(view.status, lambda v: "Algorithm 4.1:" in v)
    assert shown.wait(WAIT * 4), view.status.value  # numba may compile first
    assert "trajectories" in view.status.value, view.status.value
    armed.set()
    assert holding.wait(WAIT)
    at_move = reports[-1][1]
    view.controls["budget"].value = "10000"
    moved.set()
    assert view.wait(WAIT * 2), view.status.value
    long_run = [f for b, f in reports if b == "3000000"]
    # Stopped at the report where the move came: nothing of the 3·10^6 run was reported after it.
    assert long_run[-1] == at_move and at_move < 0.5, (at_move, long_run[-3:])
    assert view.drawn["budget"] == "10000" and view.counts["superseded"] >= 1 and view.error.value == ""
