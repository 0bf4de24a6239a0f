"""The page's JavaScript learner on the 2-D LQG of Section 5.2 against safepg, under Node.js.

Deterministic parts (same inputs, same outputs, to 1e-12 relative): the closed-form J and
gradient, the gradient samples and returns of a batch fed safepg's own random numbers (relative
to the largest sample of the component: the baseline's sums are added in another order), the
bounds and steps of every option (constants, statistics, the unguarded step, the scalar step of
Pirotta et al. (2013) and the coordinate step at a fixed N), and whole runs fed safepg's random numbers.

Stochastic parts: 30 seeds each side on five settings (among them the authors' adaptive run and
the two fixed-N steps of Figures 5.5-5.6), the difference of the means inside its 99% Welch
interval, and each comparison able to detect a shift of its metric's stated limit
(:data:`POWER_LIMITS`) with 80% power. ``pytest -s`` prints the table; ``python
tests/test_learner2d_js.py`` writes it into benchmarks/js_learner_agreement.md, and the means and
standard deviations into benchmarks/js_learner_agreement.json.

The helpers (:func:`run_node`, :func:`welch_rows`, :func:`replay_draws`) serve
tests/test_cartpole_js.py too.
"""

from __future__ import annotations

import json
import math
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pytest
from scipy import stats

from conftest import require_node
from safepg.bounds import error_bound
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.learning import learn
from safepg.meta import coordinate_step, optimal_batch_size, penalty_constant, scalar_step
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Vanilla
from safepg.policies import LinearGaussianPolicy
from safepg.streams import batch_key, trajectory_draws
from safepg.thesis.explorers.js_tasks import learner_sources, lqg_task_data
from safepg.thesis.explorers.option_names import learner_options

pytestmark = pytest.mark.node  # Node.js runs the JavaScript (tests/conftest.py: skipped or failed without it)
RTOL = 1e-12
ROOT = Path(__file__).resolve().parents[1]
AGREEMENT = ROOT / "benchmarks" / "js_learner_agreement.md"
#: The agreement tests' statistics (means, standard deviations, detected shifts), written beside the table.
STATISTICS = ROOT / "benchmarks" / "js_learner_agreement.json"

HARNESS = r"""
const L = require(process.argv[2]);
const fs = require("fs");
const req = JSON.parse(fs.readFileSync(0, "utf8"));
const f64 = p => { const b = fs.readFileSync(p); return new Float64Array(b.buffer, b.byteOffset, b.length / 8); };
const out = {};
if (req.perf) out.perf = req.perf.map(q => ({J: L.lqgPerformanceN(q.theta, q.sigma, q.task),
                                            grad: L.lqgGradientN(q.theta, q.sigma, q.task)}));
if (req.steps) out.steps = req.steps.map(q => L.cartpoleStep(q.state, q.force, q.task));
if (req.batch) out.batch = req.batch.map(q => {
  const b = q.task.kind === "lqg" ? new L.LqgBatch(q.task) : new L.CartpoleBatch(q.task);
  const found = b.run(Float64Array.from(q.theta), q.sigma, q.n, q.opt, L.arraySource(f64(q.U), f64(q.Z), q.H));
  return {samples: Array.from(b.samples.subarray(0, q.n * q.m)), returns: Array.from(b.returns.subarray(0, q.n)),
          found: found};
});
if (req.update) out.update = req.update.map(q => {
  const run = new L.VectorRun(q.cfg, q.task), x = f64(q.samples), n = q.n, m = run.m;
  run.batch.grow(n);
  for (let p = 0; p < m; p++) { let a = 0; for (let j = 0; j < n; j++) a += x[p * n + j]; run.grad[p] = a / n; }
  const up = run.cfg.method === "Vanilla" ? run.vanilla(x, n) : run.adaptive(x, n, q.found);
  return {grad: Array.from(run.grad), step: Array.from(up.step), alpha: up.alpha, k: up.k, eps: up.eps, safe: up.safe,
          c: up.c, next_n: up.nextN, c_bounds: run.c};
});
if (req.replay) {
  const q = req.replay, run = new L.VectorRun(q.cfg, q.task, L.arraySource(f64(q.U), f64(q.Z), q.H));
  out.replay = run.finish().rec;
}
if (req.seeds) out.seeds = req.seeds.map(q => {
  const r = new L.VectorRun(q.cfg, q.task).finish(), rec = r.rec, I = rec.batchSize.length;
  let tot = 0, w = 0;
  for (let i = 0; i < I; i++) { tot += rec.batchSize[i]; w += rec.batchSize[i] * rec.Jhat[i]; }
  return {iterations: I, upsilon_bar: w / tot, J_final: rec.J[I], theta_final: rec.theta[I],
          moved: rec.theta[I].some((v, i) => v !== rec.theta[0][i])};
});
if (req.driver) {
  const d = new L.Driver(req.driver), parts = [];
  while (!d.done) parts.push(d.advance(50));
  out.driver = parts;
}
process.stdout.write(JSON.stringify(out));
"""


def learner_file(directory: Path) -> Path:
    """The concatenated learner (:func:`learner_sources`) as a file Node can require."""
    path = directory / "learner_all.js"
    path.write_text(learner_sources())
    return path


def run_node(request: dict[str, Any]) -> dict[str, Any]:
    """Answer of the harness to one request (see HARNESS); large arrays travel as .bin files."""
    with tempfile.TemporaryDirectory() as d:
        harness = Path(d) / "harness.js"
        harness.write_text(HARNESS)
        proc = subprocess.run([require_node(), str(harness), str(learner_file(Path(d)))], input=json.dumps(request),
                              capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def save(path: Path, a: np.ndarray) -> str:
    np.ascontiguousarray(a, dtype=np.float64).tofile(path)
    return str(path)


def replay_draws(seed: int, sizes: Any, dim: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """safepg's random numbers of a run: per batch one key, trajectory i its dim uniforms then its normals."""
    rng = np.random.default_rng(seed)
    us, zs = [], []
    for n in sizes:
        u, z = trajectory_draws(batch_key(rng), int(n), dim, steps)
        us.append(u.ravel())
        zs.append(z.ravel())
    return np.concatenate(us), np.concatenate(zs)


def close_to_scale(js: np.ndarray, py: np.ndarray, rtol: float = RTOL) -> None:
    """Each column agrees to rtol relative to its largest magnitude."""
    scale = np.maximum(np.abs(py).max(axis=0), 1e-300)
    assert np.all(np.abs(js - py) <= rtol * scale), np.max(np.abs(js - py) / scale)


def welch_rows(label: str, values: dict[str, tuple[np.ndarray, np.ndarray]],
               limits: dict[str, float] | None = None) -> list[dict[str, Any]]:
    """Per metric: the two means and standard deviations, their difference, its 99% half-interval (Welch),
    ``detect80``, the shift between the means that this comparison detects with 80% power (two-sided, at
    99%: a learner biased by that much fails it 4 times in 5), and ``limit``, the shift it must detect:
    ``limits[metric]`` (a share of the metric's safepg mean) times that mean's size."""
    rows = []
    for metric, (a, b) in values.items():
        a, b = np.asarray(a, float), np.asarray(b, float)
        diff = a.mean() - b.mean()
        va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
        se = math.sqrt(va + vb)
        half = detect = 0.0
        if se > 0:
            df = (va + vb) ** 2 / (va**2 / (a.size - 1) + vb**2 / (b.size - 1))
            half = float(stats.t.ppf(0.995, df)) * se
            detect = half + float(stats.t.ppf(0.80, df)) * se
        share = (limits or {}).get(metric)
        rows.append({"setting": label, "metric": metric, "js": a.mean(), "py": b.mean(), "diff": diff,
                     "js_sd": a.std(ddof=1), "py_sd": b.std(ddof=1), "half_ci99": half, "inside": abs(diff) <= half,
                     "detect80": detect, "share": share, "limit": None if share is None else share * abs(b.mean()),
                     "seeds": a.size, "values": (a.tolist(), b.tolist())})
    return rows


def check_agreement(rows: list[dict[str, Any]]) -> None:
    """Each comparison: the difference of the means inside its 99% interval, and its power stated and met: it
    detects a shift of its metric's limit with 80% power. A metric on which every seed of both sides gives
    the same number (a fixed batch size, an entry no step moves) must give that number on both sides."""
    for row in rows:
        if row["half_ci99"] == 0:
            assert row["diff"] == 0, row
            continue
        assert row["inside"], row
        assert row["limit"] is not None, ("a compared metric needs its stated limit", row)
        assert row["detect80"] <= row["limit"], ("too few seeds to detect a shift of the stated limit", row)
    assert len(rows) >= 3


def table(rows: list[dict[str, Any]], setting: tuple[str, ...] = ("setting",)) -> str:
    """The rows as a Markdown table; ``setting`` names the columns that each row's ``setting`` fills
    (cells of its text separated by " | ")."""
    n = rows[0]["seeds"]
    head = [*setting, "metric", f"JS ({n} seeds)", f"safepg ({n} seeds)", "difference", "99% CI half-width",
            "inside", "shift detected with 80% power", "stated limit"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def limit(r: dict[str, Any]) -> str:
        if r["half_ci99"] == 0:
            return "(equal)"
        return "-" if r["share"] is None else f"{r['limit']:.3g} ({r['share']:.0%})"

    lines += [f"| {r['setting']} | {r['metric']} | {r['js']:.6g} | {r['py']:.6g} | {r['diff']:+.3g} | "
              f"{r['half_ci99']:.3g} | {'yes' if r['inside'] else 'NO'} | {r['detect80']:.3g} | {limit(r)} |"
              for r in rows]
    return "\n".join(lines)


def write_statistics(section: str, rows: list[dict[str, Any]], per_seed: Any = lambda row: False) -> None:
    """Replace the section ``section`` of benchmarks/js_learner_agreement.json: each row's means, standard
    deviations, seeds, detected shift and limit, and for the rows where ``per_seed(row)`` holds every seed's
    value of each side (tests/test_browser_learner.py holds the page's own run against them)."""
    old = json.loads(STATISTICS.read_text()) if STATISTICS.exists() else {}
    keep = ("js", "js_sd", "py", "py_sd", "seeds", "diff", "half_ci99", "detect80", "limit")
    old[section] = [{"setting": r["setting"], "metric": r["metric"],
                     **{k: None if r[k] is None else float(r[k]) for k in keep},
                     **({"js_values": r["values"][0], "py_values": r["values"][1]} if per_seed(r) else {})}
                    for r in rows]
    STATISTICS.write_text(json.dumps(old, indent=1, sort_keys=True) + "\n")


def write_section(title: str, text: str) -> None:
    """Replace (or append) the section ``## title`` of benchmarks/js_learner_agreement.md."""
    old = AGREEMENT.read_text() if AGREEMENT.exists() else ""
    head = f"## {title}"
    start = old.find(head)
    if start >= 0:
        end = old.find("\n## ", start + len(head))
        old = old[:start].rstrip("\n") + ("\n" + old[end:] if end >= 0 else "")
    AGREEMENT.write_text(old.rstrip("\n") + f"\n\n{head}\n\n{text}\n")


def one_thread(fn: Any) -> Any:
    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # one core: the machine is shared
    try:
        return fn()
    finally:
        numba.set_num_threads(threads)


# ------------------------------------------------------------------------ deterministic parts
ENV = LQG.thesis_2d(gamma=0.9)  # the discount the Section 5.2 experiments run with
TASK = lqg_task_data(ENV)


def test_task_data_matches_the_javascript_helper():
    got = run_node({"driver": {"task": TASK, "runs": [{"name": "a", "cfg": {"budget": 200, "nMin": 100}}]}})
    part = {key: [v for p in got["driver"] for v in p[0][key]] for key in ("theta", "J", "c", "Jhat")}
    assert isinstance(part["theta"][0], list) and len(part["theta"][0]) == 4
    assert part["J"][0] is not None and len(part["c"]) == len(part["Jhat"]) == 2
    assert got["driver"][-1][0]["done"] and len(got["driver"][0][0]["theta0"]) == 4
    # safepgLearner.THESIS_2D is LQG.thesis_2d()
    learner = json.dumps(str(learner_file(Path(tempfile.mkdtemp()))))
    script = f"const L=require({learner});console.log(JSON.stringify([L.THESIS_2D, L.lqgTask({{dim: 2, gamma: 0.9}})]))"
    js = subprocess.run([require_node(), "-e", script],
                        capture_output=True, text=True, check=True)
    thesis, ours = json.loads(js.stdout)
    assert thesis == lqg_task_data(LQG.thesis_2d())
    assert ours == TASK


def test_closed_forms_match_safepg():
    rng = np.random.default_rng(3)
    cases, expected = [], []
    for _ in range(60):
        theta = rng.uniform(-0.6, 0.2, 4)
        sigma = float(rng.uniform(0.3, 1.5))
        if not ENV.is_stable(theta):
            continue
        cases.append({"theta": theta.tolist(), "sigma": sigma, "task": TASK})
        expected.append((ENV.performance(theta, sigma), ENV.gradient(theta, sigma)))
    got = run_node({"perf": cases})["perf"]
    assert len(got) > 20
    for js, (J, grad) in zip(got, expected):
        assert abs(js["J"] - J) <= RTOL * abs(J)
        assert np.all(np.abs(np.array(js["grad"]) - grad) <= RTOL * np.abs(grad).max())


@pytest.mark.parametrize("estimator,baseline,score,clip", [("gpomdp", True, "clipped", True),
                                                           ("gpomdp", False, "raw", True),
                                                           ("reinforce", True, "clipped", True),
                                                           ("gpomdp", True, "raw", False)])
@pytest.mark.parametrize("dim", [2, 3])
def test_gradient_samples_match_the_kernel(estimator, baseline, score, clip, dim, tmp_path):
    env = replace(ENV, clip=clip, dim=dim)
    m = dim * dim
    theta = np.array([-0.3, 0.05, -0.02, -0.25]) if dim == 2 else -0.2 * np.eye(3).ravel() + 0.01
    sigma, n, seed = 0.8, 1500, 11
    policy = LinearGaussianPolicy(theta.reshape(dim, dim), sigma)
    samples, returns = env.gradient_batch(policy, n, np.random.default_rng(seed), estimator, baseline, score)
    batch = env.simulate(policy, n, np.random.default_rng(seed))
    U, Z = replay_draws(seed, [n], dim, env.horizon * dim)
    q = {"task": lqg_task_data(env), "theta": theta.tolist(), "sigma": sigma, "n": n, "m": m, "H": env.horizon,
         "opt": {"estimator": estimator, "baseline": baseline, "scoreAction": score, "batchConstants": True},
         "U": save(tmp_path / "u.bin", U), "Z": save(tmp_path / "z.bin", Z)}
    js = run_node({"batch": [q]})["batch"][0]
    close_to_scale(np.array(js["samples"]).reshape(m, n).T, samples)
    np.testing.assert_allclose(js["returns"], returns, rtol=RTOL)
    # batchConstants: the largest |reward| and |feature| of the batch, as safepg.learning measures them
    assert js["found"] == pytest.approx([np.abs(batch.rewards).max(), np.abs(batch.features).max()], rel=RTOL)


def expected_update(method: Adaptive | Vanilla, x: np.ndarray, found: tuple[float, float] | None,
                    k_task: TaskConstants) -> dict[str, Any]:
    """safepg.learning's rules (adaptive_pg, vanilla_pg) on samples x (n, m)."""
    n = x.shape[0]
    grad = x.sum(axis=0) / n
    c_bounds = penalty_constant(k_task)
    k = int(np.argmax(np.abs(grad)))
    g = float(abs(grad[k]))
    step = np.zeros_like(grad)
    if isinstance(method, Vanilla):
        assert isinstance(method.step, SafeStep)
        e = method.step.error
        eps = max(float(error_bound(e.bound, x[:, i], e.delta, k_task, "gpomdp", e.range).eps(n))
                  for i in range(grad.size))
        scalar = method.step.kind == "scalar"
        a = scalar_step(grad, eps, c_bounds) if scalar else coordinate_step(g, eps, c_bounds)
        if scalar:
            step = a * grad
        else:
            step[k] = a * grad[k]
        return {"step": step, "alpha": a, "eps": eps, "safe": eps < g, "c": c_bounds, "next_n": n}
    e, d, b = method.error, method.departures, method.batches
    batch_k, c = k_task, c_bounds
    if d.batch_constants:
        batch_k = replace(k_task, R=found[0], M_phi=found[1])
        c = penalty_constant(batch_k)
    spread = {}
    if d.maxima:
        spread = dict(variance=float(np.var(x, axis=0, ddof=1).max()), sample_range=float(np.ptp(x, axis=0).max()))
    eb = error_bound(e.bound, x[:, k], e.delta, batch_k, "gpomdp", e.range, **spread)
    eps = float(eb.eps(n))
    alpha = coordinate_step(g, eps, c, guarded=not d.unguarded_step)
    step[k] = alpha * grad[k]
    return {"step": step, "alpha": alpha, "eps": eps, "safe": eps < g, "c": c,
            "next_n": optimal_batch_size(g, eb, c, b.n_min, b.n_max)}


def update_cases(task: dict[str, Any], k_task: TaskConstants, found_scale: float, rng: np.random.Generator,
                 tmp_path: Path, count: int = 120) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Random samples and every option, the JavaScript request and safepg's answers. The page's
    configuration is the method's own (option_names.learner_options)."""
    cases, expected = [], []
    for i in range(count):
        n = int(rng.choice([2, 7, 130, 1000, 5000]))
        x = rng.standard_normal((n, 4)) * 10 ** rng.uniform(-1, 2, 4) + 10 ** rng.uniform(-2, 1.5, 4)
        x *= rng.choice([-1, 1], 4)
        error = ErrorModel(("chebyshev", "hoeffding", "bernstein")[i % 3], float(rng.uniform(0.05, 0.95)),
                           "empirical" if bool(rng.integers(2)) or i % 3 == 0 else "lemma")
        method: Adaptive | Vanilla
        if i % 2 == 0:
            method = Adaptive(error=error, batches=Batches(10, 100_000),
                              departures=Departures(batch_constants=bool((i // 2) % 2), maxima=bool((i // 4) % 2),
                                                    unguarded_step=bool((i // 8) % 2)))
        else:
            method = Vanilla(n, SafeStep(("scalar", "coordinate")[(i // 2) % 2], error))
        batch = isinstance(method, Adaptive) and method.departures.batch_constants
        found = (1.0, float(found_scale * rng.uniform(0.5, 1))) if batch else None
        cases.append({"cfg": {**learner_options(method), "budget": 10**7}, "task": task, "n": n, "found": found,
                      "samples": save(tmp_path / f"x{i}.bin", x.T.ravel())})
        expected.append(expected_update(method, x, found, k_task))
    return cases, expected


def check_updates(got: list[dict[str, Any]], expected: list[dict[str, Any]]) -> None:
    moved = 0
    for js, py in zip(got, expected):
        assert js["safe"] == py["safe"] and js["next_n"] == py["next_n"], (js, py)
        for key in ("alpha", "eps", "c"):
            assert math.isclose(js[key], py[key], rel_tol=RTOL, abs_tol=0), (key, js[key], py[key])
        np.testing.assert_allclose(js["step"], py["step"], rtol=RTOL, atol=0)
        moved += any(js["step"])
    assert moved > len(got) // 4


def test_bounds_and_steps_under_every_option(tmp_path):
    rng = np.random.default_rng(5)
    k_task = TaskConstants.from_task(ENV, 1.0)
    cases, expected = update_cases(TASK, k_task, ENV.state_bound, rng, tmp_path)
    got = run_node({"update": cases})["update"]
    check_updates(got, expected)
    assert got[0]["c_bounds"] == pytest.approx(penalty_constant(k_task), rel=RTOL)


#: The bound of the adaptive runs (Table 5.3): Bernstein with the batch's range.
BERNSTEIN_ER = ErrorModel("bernstein", range="empirical")
#: The authors' 2-D adaptive run: their N_max, the maxima over the components, the unguarded step.
AUTHORS_OPTIONS = dict(error=BERNSTEIN_ER, batches=Batches(n_max=100_000),
                       departures=Departures(maxima=True, unguarded_step=True))


@pytest.mark.parametrize("kind", ["adaptive-authors", "scalar", "coordinate"])
def test_whole_run_with_safepgs_random_numbers(kind, tmp_path):
    """Fed the random numbers safepg draws, the page's learner makes the same run."""
    seed, budget = 8, 40_000
    method = (Adaptive(**AUTHORS_OPTIONS) if kind == "adaptive-authors"
              else Vanilla(2000, SafeStep(kind)))
    py = learn(ENV, method, np.zeros(4), 1.0, budget=budget, rng=seed)
    cfg = learner_options(method)
    U, Z = replay_draws(seed, py.batch_size, 2, ENV.horizon * 2)
    js = run_node({"replay": {"cfg": {**cfg, "budget": budget}, "task": TASK, "H": ENV.horizon,
                              "U": save(tmp_path / "u.bin", U), "Z": save(tmp_path / "z.bin", Z)}})["replay"]
    assert py.iterations >= 8
    assert js["batchSize"] == py.batch_size.tolist()
    np.testing.assert_allclose(np.array(js["theta"]), py.theta, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(js["alpha"], py.alpha, rtol=1e-9)
    np.testing.assert_allclose(js["Jhat"], py.J_hat, rtol=1e-12)
    np.testing.assert_allclose(js["J"], py.J, rtol=1e-9)


# --------------------------------------------------------------------------- stochastic parts
SEEDS = 30
#: name -> the method (safepg's, and the page's through learner_options); budgets small enough for a minute in all.
SETTINGS: dict[str, Adaptive | Vanilla] = {
    "adaptive, Bernstein (e.r.), 10^5": Adaptive(error=BERNSTEIN_ER),
    "adaptive, authors' options, 10^5": Adaptive(**AUTHORS_OPTIONS),
    "scalar step of Pirotta et al. (2013), N = 2000, 10^5": Vanilla(2000, SafeStep("scalar")),
    "coordinate step, N = 2000, 10^5": Vanilla(2000, SafeStep("coordinate")),
    "N = 100, alpha = 10^-6, REINFORCE, 10^5": Vanilla(100, FixedStep(1e-6), Gradient("reinforce")),
}
#: Every setting's budget.
BUDGET = 100_000
#: The shift, as a share of the metric's safepg mean, that each comparison must detect with 80% power.
#: theta's diagonal is compared through its trace: its two entries move alike (the task's two dimensions
#: are the same), and their sum halves the relative spread of either. The off-diagonal entries are not
#: compared in the mean: by the task's symmetry their mean is 0, so a shift cannot be stated as a share of
#: it; under coordinate steps they never move, which both sides must show exactly
#: (:func:`test_runs_agree_statistically`).
POWER_LIMITS = {"mean J_hat over the run": 0.01, "final J": 0.01, "final trace theta_00 + theta_11": 0.05,
                "iterations": 0.05}
#: The settings whose steps move one diagonal entry at a time: theta's off-diagonal entries stay 0.
COORDINATE_STEPS = ("adaptive, Bernstein (e.r.), 10^5", "adaptive, authors' options, 10^5",
                    "coordinate step, N = 2000, 10^5")


def agreement(name: str, seeds: int = SEEDS) -> tuple[list[dict[str, Any]], np.ndarray, np.ndarray]:
    """The Welch rows of setting ``name`` (:func:`welch_rows`), and each seed's final off-diagonal entries of
    theta, (seeds, 2), JavaScript's then safepg's."""
    method = SETTINGS[name]
    cfg = {**learner_options(method), "budget": BUDGET}  # the page's configuration of the same method
    js = run_node({"seeds": [{"task": TASK, "cfg": {**cfg, "seed": k}} for k in range(seeds)]})["seeds"]
    py = one_thread(lambda: [learn(ENV, method, np.zeros(4), 1.0, budget=BUDGET, rng=1000 + k) for k in range(seeds)])
    theta_js = np.array([s["theta_final"] for s in js])
    theta_py = np.array([r.theta[-1] for r in py])
    values = {"mean J_hat over the run": ([s["upsilon_bar"] for s in js], [r.upsilon_bar() for r in py]),
              "final J": ([s["J_final"] for s in js], [r.J[-1] for r in py]),
              "final trace theta_00 + theta_11": (theta_js[:, 0] + theta_js[:, 3], theta_py[:, 0] + theta_py[:, 3]),
              "iterations": ([s["iterations"] for s in js], [r.iterations for r in py])}
    return welch_rows(f"2-D LQG: {name}", values, POWER_LIMITS), theta_js[:, 1:3], theta_py[:, 1:3]


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SETTINGS))
def test_runs_agree_statistically(name):
    rows, off_js, off_py = agreement(name)
    print("\n" + table(rows))
    check_agreement(rows)
    if name in COORDINATE_STEPS:
        assert not off_js.any() and not off_py.any(), (off_js, off_py)
    else:  # they move, around 0
        assert np.count_nonzero(off_js) == np.count_nonzero(off_py) == off_js.size


if __name__ == "__main__":  # the 2-D section of benchmarks/js_learner_agreement.md and .json
    all_rows = [r for name in SETTINGS for r in agreement(name)[0]]
    text = table(all_rows)
    print(text)
    write_statistics("2-D LQG", all_rows)
    write_section("2-D LQG (Section 5.2), gamma = 0.9", f"{SEEDS} seeds each side, theta_0 = 0, sigma = 1, G(PO)MDP; "
                  "Welch 99% interval of the difference of means, the shift it detects with 80% power, and the "
                  "shift the test requires it to detect (a share of the safepg mean; \"(equal)\": every seed "
                  "gives the same number on both sides, which must agree exactly). Computed by "
                  "`python tests/test_learner2d_js.py`."
                  "\n\n" + text)
