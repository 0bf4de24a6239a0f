"""Run the Chapter 5 explorers' page objects (static/ch5_page.js + lqg2d_page.js or cartpole_page.js)
under Node: their ``configs`` and ``result`` on given settings and traces, to hold them against their
Python twins in tests/test_lqg2d_learner.py and tests/test_cartpole_learner.py."""

from __future__ import annotations

import json
import subprocess
from typing import Any

from conftest import require_node
from safepg.thesis.explorers.component import static_text
from safepg.thesis.explorers.js_tasks import learner_sources

#: Control moves that each change what the Chapter 5 explorers draw, in the page
#: (tests/test_browser_live_ch5.py) and in the kernel view (tests/test_kernel_view_ch5.py).
CH5_MOVES: dict[str, list[tuple[str, Any]]] = {
    "steps": [("budget", "30000"), ("delta", 0.5), ("sigma", 0.75), ("bound", "bernstein-er"), ("n", "1000"),
              ("seed", 5.0)],
    "adaptive": [("budget", "30000"), ("delta", 0.5), ("sigma", 1.5), ("bound", "chebyshev"), ("seed", 3.0),
                 ("n_max", "10000"), ("authors", True)],
    "cartpole": [("budget", "10000"), ("deg12", True), ("ml005", True), ("gamma09", True), ("batch_constants", True),
                 ("max_stats", True), ("unguarded", True), ("first1000", True), ("start", "theta_star"),
                 ("delta", 0.5), ("sigma", 0.75), ("seed", 2.0), ("budget", "20000")],
}
_SCRIPT = r"""
const src = require("fs").readFileSync(0, "utf8");
const req = JSON.parse(src);
const [page, linked, learner] = new Function(
  req.src + "\nreturn [" + req.object + ", safepgCh5Linked, safepgLearner];")();
const out = req.cases.map(c => ({
  configs: c.configs ? page.configs(c.p, c.data) : null,
  // each run's configuration as the learner completes it (the option table's defaults filled in)
  completed: c.configs ? page.configs(c.p, c.data).runs.map(r => learner.runOptions(r.cfg)) : null,
  result: c.traces ? page.result(c.p, {runs: c.traces}, c.data) : null,
  linked: c.linked ? linked(c.links, c.linked[0], c.linked[1]) : null}));
process.stdout.write(JSON.stringify(out));
"""


def run_page(script: str, obj: str, cases: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``obj`` (a page object of ``script``) on each case: ``{"p", "data", "configs": bool, "traces"}`` (with
    ``configs``, the answer's ``completed`` holds each run's configuration as the learner completes it), or
    ``{"links", "linked": [name, value]}`` for the page's answer to a control's move (``safepgCh5Linked``)."""
    src = "\n".join([learner_sources(), static_text("live_jobs.js"), static_text("ch5_page.js"), static_text(script)])
    proc = subprocess.run([require_node(), "-e", _SCRIPT],
                          input=json.dumps({"src": src, "object": obj, "cases": cases}), capture_output=True,
                          text=True, timeout=120, check=False)
    if proc.returncode:
        raise RuntimeError(proc.stderr)
    return json.loads(proc.stdout)
