"""The page learner's WebAssembly kernel of the 2-D LQG (``safepg/thesis/explorers/wasm/lqg2d_kernel.c``).

It must change nothing but the time a run takes: a seeded run gives the same record, bit for
bit, with the kernel and with the JavaScript it replaces (``LqgBatch.run2gb``), whatever the
options, the task's matrices, an odd batch size or a batch that makes the kernel's memory grow.
The committed binary is what the source compiles to, and the kernel's shortcut past Math.exp
answers as Math.exp does, also next to the boundary.
"""

from __future__ import annotations

import json
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from script_module import load

from conftest import import_or_fail, require_node
from safepg.envs.lqg import LQG
from safepg.thesis.explorers.js_tasks import learner_sources, lqg_task_data

pytestmark = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)
ROOT = Path(__file__).resolve().parents[1]

HARNESS = r"""
const L = require(process.argv[2]);
const req = JSON.parse(require("fs").readFileSync(0, "utf8"));
const out = {available: L.lqg2dWasm.available()};
if (req.runs) out.runs = req.runs.map(q => {
  const recs = [false, true].map(on => {
    L.lqg2dWasm.enabled = on;
    return new L.VectorRun(q.cfg, q.task).finish().rec;
  });
  return {js: recs[0], wasm: recs[1]};
});
if (req.exp) {
  // Levels at and around Math.exp(y): the float itself, its neighbours, and relative offsets.
  const f = new Float64Array(1), u = new BigInt64Array(f.buffer), wrong = [];
  const neighbour = (x, d) => { f[0] = x; u[0] += BigInt(d); return f[0]; };
  let checked = 0;
  for (const y of req.exp.ys) {
    const e = Math.exp(y);
    const levels = [e, neighbour(e, 1), neighbour(e, -1), neighbour(e, 2), neighbour(e, -2)];
    for (const r of req.exp.offsets) levels.push(e * (1 + r), e * (1 - r));
    for (const level of levels) {
      checked++;
      if (L.lqg2dWasm.belowExp(level, y) !== (level < e)) wrong.push([level, y]);
    }
  }
  out.exp = {checked, wrong};
}
process.stdout.write(JSON.stringify(out));
"""


def run_node(request: dict[str, Any], *, prelude: str = "") -> dict[str, Any]:
    """The harness's answer to ``request``; ``prelude`` runs before the learner loads."""
    with tempfile.TemporaryDirectory() as d:
        learner, harness = Path(d) / "learner_all.js", Path(d) / "harness.js"
        learner.write_text(prelude + learner_sources())
        harness.write_text(HARNESS)
        proc = subprocess.run([require_node(), str(harness), str(learner)], input=json.dumps(request),
                              capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def task(**kw: Any) -> dict[str, Any]:
    """The learner's TASK of a 2-D LQG (Section 5.2's unless ``kw`` says otherwise)."""
    return lqg_task_data(LQG.thesis_2d(**kw))


#: Settings that reach every branch of the kernel: the figures' run, the authors' departures
#: (per-batch constants with the maxima, the unguarded step), odd batch sizes (the pair loop's
#: single trajectory), a large first batch (the kernel's memory grows), other matrices, sigma
#: and bounds, a policy that clips, and vanilla's safe step at a fixed N.
RUNS = [
    {"cfg": {"bound": "bernstein", "range": "empirical", "budget": 200_000, "seed": 1},
     "task": task(gamma=0.9, horizon=20)},
    {"cfg": {"bound": "bernstein", "range": "empirical", "budget": 150_000, "seed": 2, "batchConstants": True,
             "maxima": True, "unguardedStep": True, "first": 1001},
     "task": task(gamma=0.9, horizon=20)},
    {"cfg": {"bound": "chebyshev", "budget": 120_000, "seed": 3, "nMin": 101, "delta": 0.5},
     "task": task(gamma=0.95, horizon=20)},
    {"cfg": {"bound": "hoeffding", "range": "empirical", "budget": 300_000, "seed": 4, "first": 150_001,
             "nMin": 77, "sigma": 0.5},
     "task": task(gamma=0.9, horizon=15)},
    {"cfg": {"bound": "bernstein", "range": "empirical", "budget": 100_000, "seed": 5, "sigma": 2.5,
             "theta0": [-3.0, 0.4, 0.2, -2.0]},
     "task": task(gamma=0.9, horizon=20, A=[[1.0, 0.1], [-0.2, 0.9]], B=[[0.5, 0.2], [0.0, 1.0]],
                  Q=[[1.0, 0.2], [0.2, 0.5]], R=[[0.3, 0.0], [0.0, 0.7]])},
    {"cfg": {"method": "Vanilla", "batchSize": 99, "step": "SafeStep", "kind": "coordinate", "budget": 40_000,
             "seed": 6},
     "task": task(gamma=0.9, horizon=20)},
]


@pytest.fixture(scope="module")
def runs() -> list[dict[str, Any]]:
    return run_node({"runs": RUNS})["runs"]


def test_the_kernel_runs_under_node() -> None:
    assert run_node({})["available"] is True


@pytest.mark.parametrize("i", range(len(RUNS)))
def test_a_seeded_run_is_the_same_with_and_without_the_kernel(runs: list[dict[str, Any]], i: int) -> None:
    js, wasm = runs[i]["js"], runs[i]["wasm"]
    assert len(js["batchSize"]) > 3
    assert wasm == js  # every field of every iteration, bit for bit (JSON keeps a double's 17 digits)


def test_the_runs_exercise_what_they_claim(runs: list[dict[str, Any]]) -> None:
    sizes = [n for r in runs for n in r["js"]["batchSize"]]
    assert any(n % 2 for n in sizes), "an odd batch size (the kernel's single trajectory)"
    assert max(sizes) > 150_000, "a batch that grows the kernel's memory"
    c = runs[1]["js"]["c"]
    assert len(set(c)) > 1, "per-batch constants measured by the kernel (maxima)"


def test_without_webassembly_the_javascript_runs_the_same_record(runs: list[dict[str, Any]]) -> None:
    out = run_node({"runs": RUNS[:1]}, prelude="delete globalThis.WebAssembly;\n")
    assert out["available"] is False
    assert out["runs"][0]["js"] == runs[0]["js"]
    assert out["runs"][0]["wasm"] == runs[0]["js"]


def test_the_shortcut_past_math_exp_answers_as_math_exp() -> None:
    rng = np.random.default_rng(0)
    r = 3.442619855899  # the ziggurat's R: the kernel asks about y in [-R^2 / 2, 0]
    ys = np.concatenate([-0.5 * (rng.uniform(0, r, 3000) ** 2), [0.0, -0.5 * r * r, -np.log(2) * 4.5]])
    offsets = [1e-16, 1e-15, 1e-13, 1e-12, 2e-12, 1e-10, 1e-6, 1e-2]
    out = run_node({"exp": {"ys": ys.tolist(), "offsets": offsets}})["exp"]
    assert out["checked"] == len(ys) * (5 + 2 * len(offsets))
    assert out["wrong"] == []


def test_the_committed_binary_is_what_the_source_compiles_to(tmp_path: Path) -> None:
    import_or_fail("ziglang", "requirements-dev.txt")  # the kernel's compiler
    build = load("tools/build_wasm.py")
    out = tmp_path / "kernel.wasm"
    build.compile_kernel(out)
    assert out.read_bytes() == build.BINARY.read_bytes(), "run `make wasm` and commit the binary"
