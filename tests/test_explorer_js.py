"""The explorers' JavaScript closed forms against safepg, evaluated with Node.js.

A fast check of every formula in ``static/lib.js`` over many parameter values; the browser
test then checks the same code running inside the built page. Every JavaScript file the
explorers ship parses.
"""

from __future__ import annotations

import json
import math
import subprocess
from importlib import resources

import numpy as np
import pytest

from conftest import require_node
from safepg.bounds import (
    ErrorBound,
    bernstein,
    chebyshev,
    gpomdp_variance_factor,
    gradient_range_bound,
    hoeffding,
    reinforce_variance_factor,
)
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    n_star_closed_form,
    n_star_search,
    n_zero,
    penalty_constant,
    upsilon,
)
from safepg.thesis.explorers.component import static_text

pytestmark = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)


def run_js(expr_cases: list[str]) -> list:
    script = static_text("lib.js") + "\nconsole.log(JSON.stringify([" + ",".join(expr_cases) + "]));"
    out = subprocess.run([require_node(), "-e", script], capture_output=True, text=True, check=True).stdout
    return json.loads(out)



def test_static_sources_parse(tmp_path):
    names = sorted(f.name for package in ("safepg.explorers", "safepg.thesis.explorers")
                   for f in resources.files(package).joinpath("static").iterdir() if f.name.endswith(".js"))
    assert {"lib.js", "runtime.js", "lqg_compute.js", "upsilon_compute.js", "live_page.js", "learner.js"} <= set(names)
    for name in names:
        src = static_text(name)
        if name.endswith("_compute.js"):  # a function body: its top-level return needs the function
            src = f"(function (p, data, lib) {{{src}}});"
        path = tmp_path / name
        path.write_text(src, encoding="utf-8")
        proc = subprocess.run([require_node(), "--check", str(path)], capture_output=True, text=True)
        assert proc.returncode == 0, (name, proc.stderr)


def test_lqg_closed_form():
    env = LQG.thesis_1d()
    # Stable for |1 + theta| sqrt(0.9) < 1, theta in (-2.054, 0.054): the grid, and two gains outside it.
    cases = [(t, s) for t in np.linspace(-1.5, 0.05, 13) for s in (0.3, 1.0, 1.7)] + [(0.1, 1.0), (-2.2, 0.5)]
    js = run_js([f"lib.lqgJ({t}, {s}, 0.9, 2)" for t, s in cases])
    unstable = 0
    for (t, s), v in zip(cases, js):
        expected = env.performance(t, s)
        if math.isinf(expected):
            assert v is None  # JSON has no -Infinity: stringified as null
            unstable += 1
        else:
            assert v == pytest.approx(expected, rel=1e-12)
    assert len(js) == len(cases) == 41 and unstable == 2  # both branches checked


@pytest.mark.parametrize("sigma", [0.5, 1.0, 2.0])
def test_constants_and_bounds(sigma):
    k = TaskConstants.from_task(LQG.thesis_1d(), sigma)
    kj = (f"{{R: {k.R}, M: {k.M_phi}, Avol: {k.action_volume}, Abar: {k.A_bar}, gamma: {k.gamma}, H: {k.H}, "
          f"sigma: {sigma}}}")
    js = run_js([f"lib.penalty({kj})", f"lib.varReinforce({kj})", f"lib.varGpomdp({kj})", f"lib.rangeBound({kj})",
                 "lib.chebyshev(0.3, 50)", "lib.hoeffding(0.3, 40)", "lib.bernstein(0.3, 12, 40)"])
    assert js[0] == pytest.approx(penalty_constant(k), rel=1e-12)
    assert js[1] == pytest.approx(reinforce_variance_factor(k), rel=1e-12)
    assert js[2] == pytest.approx(gpomdp_variance_factor(k), rel=1e-12)
    assert js[3] == pytest.approx(gradient_range_bound(k), rel=1e-12)
    for got, b in zip(js[4:], [chebyshev(0.3, 50), hoeffding(0.3, 40), bernstein(0.3, 12, 40)]):
        assert (got["d"], got["f"]) == pytest.approx((b.d, b.f), rel=1e-12)


@pytest.mark.parametrize("d,f,g,c", [(30.0, 0.0, 5.0, 100.0), (3.0, 40.0, 0.7, 9753.0), (120.0, 300.0, 25.0, 1e4),
                                     (8.0, 2.0, 0.05, 1.0)])
def test_meta_parameters(d, f, g, c):
    b = ErrorBound(d, f)
    bd = f"{{d: {d}, f: {f}}}"
    js = run_js([f"lib.nZero({g}, {bd})", f"lib.nStar({g}, {bd}, {c})", f"lib.upsilon(1234, {g}, {bd}, {c})",
                 f"lib.step({g}, lib.eps({bd}, 5000), {c})", f"lib.improvement({g}, lib.eps({bd}, 5000), {c})"])
    assert js[0] == pytest.approx(n_zero(g, b), rel=1e-12)
    assert js[1] == (n_star_closed_form(g, b) if f == 0 else n_star_search(g, b, c))
    assert js[2] == pytest.approx(upsilon(1234, g, b, c, saturate=False), rel=1e-12)
    assert js[3] == pytest.approx(coordinate_step(g, b.eps(5000), c), rel=1e-12)
    assert js[4] == pytest.approx(guaranteed_improvement(g, b.eps(5000), c), rel=1e-12)
