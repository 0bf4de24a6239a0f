"""The explorers' axis ticks (``safepgTicks``, ``safepgTickLabels`` in safepg/thesis/explorers/static/runtime.js),
evaluated with Node.js: every label distinct, and as short as that allows.

The browser test (test_browser_book.py) checks the drawn labels stay inside each plot.
"""

from __future__ import annotations

import json
import subprocess

import pytest

from conftest import require_node
from safepg.explorers.component import static_text

pytestmark = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)


def axis(lo: float, hi: float, log: bool) -> tuple[list[float], list[str]]:
    """Tick values and labels of an axis from lo to hi (for a log axis, lo and hi are log10)."""
    script = (static_text("runtime.js") + f"\nconst t = safepgTicks({lo}, {hi}, {str(log).lower()});"
              f"\nconsole.log(JSON.stringify([t, safepgTickLabels(t, {str(log).lower()})]));")
    out = subprocess.run([require_node(), "-e", script], capture_output=True, text=True, check=True).stdout
    ticks, labels = json.loads(out)
    return ticks, labels


@pytest.mark.parametrize("lo, hi, log", [
    (0, 3e7, False),          # the batch-size explorer's trajectories axis
    (1, 3e7, False),
    (0, 1.2, False), (-120, 0, False), (1000, 2500, False), (-0.95, -0.35, False),
    (2, 5, True), (5, 7.5, True), (-7, -2, True), (0.3, 0.9, True),
])
def test_labels_are_distinct_and_read_back(lo, hi, log):
    ticks, labels = axis(lo, hi, log)
    assert len(ticks) >= 2
    assert len(set(labels)) == len(labels), labels
    for v, text in zip(ticks, labels):
        # each label reads back as its tick's value to the precision the labels need
        assert float(text) == pytest.approx(v, rel=0.05, abs=1e-12), (v, text)


def test_trajectory_axis_labels():
    """The defect of the old axis: 1.5e7 and 2.5e7 were printed as "2e+7" and "3e+7"."""
    ticks, labels = axis(0, 3e7, False)
    assert labels == ["0", "5e6", "1e7", "1.5e7", "2e7", "2.5e7", "3e7"]


def test_shortest_labels():
    assert axis(0, 1.2, False)[1] == ["0", "0.2", "0.4", "0.6", "0.8", "1", "1.2"]
    assert axis(3, 5, True)[1][:3] == ["1000", "2000", "5000"]  # a log axis: each label on its own


def test_one_style_per_linear_axis():
    """A linear axis reaching 1e5 writes every label in exponent form (not "50000" beside "1e5")."""
    assert axis(0, 3e5, False)[1] == ["0", "5e4", "1e5", "1.5e5", "2e5", "2.5e5", "3e5"]
    assert axis(0, 5e4, False)[1][-1] == "50000"
