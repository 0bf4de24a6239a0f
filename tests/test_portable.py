"""Outputs that do not depend on the CPU (:mod:`safepg.portable`).

Two kinds of evidence, without touching the machine's BLAS settings:

- **By construction.** Every output quantity equals a fixed-order reference (math.fsum or
  an explicit loop over Python floats) bit for bit, on many random inputs; a source scan
  finds no ``@``, ``np.dot``, ``np.linalg``, ``scipy.linalg`` or ``scipy.stats`` on an
  output path except the listed, justified ones.
- **By experiment.** Short learning runs recomputed in subprocesses give bit-identical records
  and reports on the host CPU (AVX-512 where it has it), with numba compiling for AVX2
  (``NUMBA_CPU_NAME=haswell``) and NumPy kept to its AVX2 loops, and with numba compiling for a
  generic x86-64 and glibc's libm and NumPy's dispatch restricted to their pre-AVX2, pre-FMA
  code. The AVX2 probe is the machine without AVX-512, measured on this one.
"""

from __future__ import annotations

import ast
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from safepg import portable
from safepg.bounds import ErrorBound
from safepg.envs.lqg import LQG
from safepg.learning import LearningRecord
from safepg.meta import scalar_step, upsilon

ROOT = Path(__file__).resolve().parents[1]
SEEDS = range(40)


# ------------------------------------------------------------ fixed-order references
def _ref_matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            acc = float(a[i, 0]) * float(b[0, j])
            for k in range(1, a.shape[1]):
                acc = acc + float(a[i, k]) * float(b[k, j])
            out[i, j] = acc
    return out


def _ref_solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Gaussian elimination with partial pivoting on Python floats, one operation at a time."""
    A = [[float(v) for v in row] for row in a]
    X = [[float(v) for v in row] for row in b]
    n = len(A)
    for j in range(n):
        p = max(range(j, n), key=lambda i: (abs(A[i][j]), -i))
        A[j], A[p] = A[p], A[j]
        X[j], X[p] = X[p], X[j]
        for i in range(j + 1, n):
            f = A[i][j] / A[j][j]
            A[i] = A[i][:j] + [A[i][c] - f * A[j][c] for c in range(j, n)]
            X[i] = [X[i][c] - f * X[j][c] for c in range(len(X[i]))]
    for j in range(n - 1, -1, -1):
        acc = X[j]
        for i in range(j + 1, n):
            acc = [acc[c] - A[j][i] * X[i][c] for c in range(len(acc))]
        X[j] = [v / A[j][j] for v in acc]
    return np.array(X)


@pytest.mark.parametrize("seed", SEEDS)
def test_matmul_trace_solve_equal_explicit_loops(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, k = rng.integers(1, 6), rng.integers(1, 4)
    a, b = rng.normal(size=(n, n)) * 10.0 ** rng.integers(-3, 4), rng.normal(size=(n, k))
    assert np.array_equal(portable.matmul(a, b), _ref_matmul(a, b))
    assert portable.trace(a) == math.fsum([]) + sum_in_order(np.diag(a))
    x = portable.solve(a, b)
    assert np.array_equal(x, _ref_solve(a, b))
    np.testing.assert_allclose(a @ x, b, rtol=0, atol=1e-8 * np.abs(a).max() * np.abs(x).max())
    # batched: each system as if alone
    batch = rng.normal(size=(3, n, n))
    xb = portable.solve(batch, b)
    for i in range(3):
        assert np.array_equal(xb[i], portable.solve(batch[i], b))


def sum_in_order(v: np.ndarray) -> float:
    acc = float(v[0])
    for x in v[1:]:
        acc = acc + float(x)
    return acc


@pytest.mark.parametrize("seed", SEEDS)
def test_cholesky_powers_fsum(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(4, 4))
    cov = m @ m.T + 0.5 * np.eye(4)
    L = portable.cholesky(cov)
    np.testing.assert_allclose(L, np.linalg.cholesky(cov), rtol=1e-12, atol=1e-12)
    g = float(rng.uniform(0.5, 1.0))
    ref, p = [], 1.0
    for _ in range(25):
        ref.append(p)
        p = p * g
    assert portable.powers(g, 25).tolist() == ref
    x, w = rng.normal(size=500) * 1e3, rng.integers(1, 10**6, size=500)
    assert portable.fsum_mean(x, w) == math.fsum(float(a) * float(b) for a, b in zip(w, x)) / math.fsum(
        float(b) for b in w)


def test_scalar_functions_are_correctly_rounded() -> None:
    rng = np.random.default_rng(0)
    with mpmath.workdps(60):
        for x in rng.uniform(1e-3, 50, 300):
            x = float(x)
            assert portable.log(x) == float(mpmath.log(mpmath.mpf(x)))
            assert portable.exp(-x / 7) == float(mpmath.exp(mpmath.mpf(-x / 7)))
            k = int(rng.integers(0, 41))
            assert portable.ipow(x / 50, k) == float(mpmath.mpf(x / 50) ** k)
    with pytest.raises(ValueError, match="x must be > 0"):
        portable.log(0.0)
    with pytest.raises(ValueError, match="k must be an integer"):
        portable.ipow(0.9, 1.5)  # type: ignore[arg-type]


def test_sine_and_cosine_within_one_ulp_and_free_of_fma() -> None:
    x = np.random.default_rng(1).uniform(-20, 20, 100_000)
    x[:5] = [0.0, -0.0, 1e-300, np.pi / 4, -np.pi / 2]
    for ours, ref, py in ((portable.sin_array, np.sin, portable.sin.py_func),
                          (portable.cos_array, np.cos, portable.cos.py_func)):
        got = ours(x)
        assert np.all(np.abs(got - ref(x)) <= np.spacing(np.abs(ref(x))))
        # The compiled kernel equals the same code run as Python floats: numba fused no
        # multiply-add on this CPU (an FMA would change the last bit of some values).
        assert got[:2000].tolist() == [py(float(v)) for v in x[:2000]]


# --------------------------------------------------------------- output quantities
@pytest.mark.parametrize("seed", SEEDS)
def test_upsilon_bar_is_the_exact_weighted_mean(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 3000))
    batch = rng.integers(100, 500_000, size=n)
    J_hat = rng.normal(-10, 3, size=n)
    rec = LearningRecord(batch, np.zeros(n), np.zeros(n, int), np.zeros((n + 1, 1)), np.zeros(n + 1), J_hat,
                         np.zeros((n, 1)), np.zeros(n), np.ones(n, bool))
    ref = math.fsum(float(b) * float(j) for b, j in zip(batch, J_hat)) / math.fsum(float(b) for b in batch)
    assert rec.upsilon_bar() == ref


@pytest.mark.parametrize("seed", SEEDS)
def test_scalar_step_and_upsilon_equal_explicit_arithmetic(seed: int) -> None:
    rng = np.random.default_rng(seed)
    grad = rng.normal(size=int(rng.integers(1, 6))) * 10
    eps, c = float(rng.uniform(0, 5)), float(rng.uniform(1, 1e4))
    a = [abs(float(v)) for v in grad]
    lower = [max(v - eps, 0.0) for v in a]
    upper = math.fsum(v + eps for v in a)
    assert scalar_step(grad, eps, c) == math.fsum(v * v for v in lower) / (2 * c * (upper * upper))
    bound = ErrorBound(float(rng.uniform(1, 100)), float(rng.uniform(0, 100)))
    g = float(rng.uniform(1, 50))
    ns = rng.integers(1, 10**6, size=50).astype(float)
    vals = upsilon(ns, g, bound, c, saturate=False)
    for n, v in zip(ns, vals):
        e = bound.d / math.sqrt(n) + bound.f / n
        lo, hi = g - e, g + e
        assert v == (lo * lo) * (lo * lo) / (4 * c * n * (hi * hi))


def _ref_performance_1d(env: LQG, theta: float, sigma: float) -> float:
    """The 1-D closed form (tests/test_lqg.py's ``j_1d_settings``), evaluated one IEEE operation at a time in
    the library's order."""
    F = 1.0 + 1.0 * theta
    M = 0.5 * (1.0 + (theta * 1.0) * theta)
    P = M / (1.0 - env.gamma * (F * F))
    P = 0.5 * (P + P)
    S = sigma * sigma
    noise = 0.5 * (1.0 * S) + env.gamma * (((1.0 * P) * 1.0) * S)
    return -(P * (env.state_bound**2 / 3)) - noise / (1 - env.gamma)


def test_closed_form_J_equals_explicit_arithmetic() -> None:
    env = LQG.thesis_1d()
    rng = np.random.default_rng(0)
    thetas = rng.uniform(-1.2, 0.05, 500)
    for sigma in (0.5, 1.0, 1.7):
        batch = env.performance_batch(thetas[:, None], sigma)
        for t, J in zip(thetas, batch):
            assert J == _ref_performance_1d(env, float(t), sigma) == env.performance(t, sigma)


def test_2d_closed_forms_equal_fixed_order_reference() -> None:
    env = LQG.thesis_2d(gamma=0.9)
    rng = np.random.default_rng(3)
    thetas = np.column_stack([rng.uniform(-0.9, -0.1, 200), rng.uniform(-0.1, 0.1, (200, 2)),
                              rng.uniform(-0.9, -0.1, 200)])
    batch = env.performance_batch(thetas, 1.0)
    for t, J in zip(thetas, batch):
        K = t.reshape(2, 2)
        F = np.eye(2) + K
        M = 0.5 * (np.eye(2) + _ref_matmul(_ref_matmul(K.T, np.eye(2)), K))
        kron = np.array([[F[c, a] * F[e, b] for c in range(2) for e in range(2)] for a in range(2) for b in range(2)])
        P = _ref_solve(np.eye(4) - env.gamma * kron, M.reshape(4, 1)).reshape(2, 2)
        P = 0.5 * (P + P.T)
        mm = _ref_matmul
        noise = 0.5 * sum_in_order(np.diag(np.eye(2))) + env.gamma * sum_in_order(
            np.diag(mm(mm(mm(np.eye(2), P), np.eye(2)), np.eye(2))))
        ref = -sum_in_order(np.diag(mm(P, env.initial_second_moment()))) - noise / (1 - env.gamma)
        assert J == ref == env.performance(t, 1.0)


# ------------------------------------------------------------------ source scan
#: Modules left out of the scan, and why. Every other module of the package is scanned: its
#: numbers may reach a notebook output, a report or an embedded explorer.
NOT_SCANNED = {
    "portable": "the fixed-order reference implementation itself",
    "theory/__init__": "symbolic (sympy): exact arithmetic, no floating point",
    "theory/symbols": "symbolic (sympy)", "theory/step_size": "symbolic (sympy)",
    "theory/batch_size": "symbolic (sympy)", "theory/appendix_a": "symbolic (sympy)",
    "theory/appendix_b": "symbolic (sympy)",
    "envs/gym_task": "a user's gymnasium task: its dynamics are NumPy and libm, documented as not "
                     "CPU-independent; no thesis output uses it (tests/test_layers.py)",
    "thesis/lemma_checks": "numeric checks of the inequality lemmas, still on BLAS and NumPy's exp: their "
                           "verdicts hold with any last bit, but a printed violation at rounding level "
                           "(Table E.2's 4.82e-16) could change on another CPU; to be made portable",
}


def _modules() -> list[str]:
    return sorted(str(p.relative_to(ROOT / "safepg"))[:-3] for p in (ROOT / "safepg").rglob("*.py")
                  if "__pycache__" not in p.parts)


OUTPUT_MODULES = [m for m in _modules() if m not in NOT_SCANNED]
#: (module, enclosing function) pairs allowed to call CPU-dispatched linear algebra, and why.
ALLOWED = {
    # yes/no answers: only a gain exactly on the stability boundary could flip
    ("envs/lqg", "_stable"), ("envs/lqg", "_largest_eigenvalue"),
    # validation, and full (non-diagonal) covariances, which no experiment uses
    ("policies", "check_sigma"), ("policies", "sigma"), ("policies", "log_density"),
    # a cross-check of the Bernstein search in the tests, never an output
    ("meta", "n_star_bernstein_root"),
}


def _calls(module: str, package: Path = ROOT / "safepg") -> list[tuple[str, str, int]]:
    tree = ast.parse((package / f"{module}.py").read_text())
    found: list[tuple[str, str, int]] = []

    def visit(node: ast.AST, func: str) -> None:
        for child in ast.iter_child_nodes(node):
            name = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else func
            what = None
            if isinstance(child, ast.BinOp) and isinstance(child.op, ast.MatMult):
                what = "@"
            elif isinstance(child, ast.Attribute) and child.attr == "linalg":
                what = child.attr
            elif (isinstance(child, ast.Attribute) and child.attr in ("dot", "matmul", "tensordot", "inner", "vdot")
                  and getattr(child.value, "id", "") in ("np", "numpy")):
                what = "np." + child.attr
            elif (isinstance(child, ast.Attribute) and child.attr == "stats"
                  and getattr(child.value, "id", "") == "scipy"):
                what = "scipy.stats"
            elif isinstance(child, ast.ImportFrom) and child.module in ("scipy.linalg", "scipy.stats", "numpy.linalg"):
                what = child.module
            if what is not None:
                found.append((what, name, child.lineno))
            visit(child, name)

    visit(tree, "<module>")
    return found


def test_scan_covers_every_module() -> None:
    """The list of modules left out names only modules that exist (no silent loss of coverage)."""
    assert set(NOT_SCANNED) <= set(_modules()), sorted(set(NOT_SCANNED) - set(_modules()))
    assert {"learning", "stats", "thesis/experiments", "thesis/scorecard/runs", "thesis/explorers/live_learner"} <= set(
        OUTPUT_MODULES)


@pytest.mark.parametrize("module", OUTPUT_MODULES)
def test_output_paths_do_not_call_blas(module: str) -> None:
    bad = [(w, f, line) for w, f, line in _calls(module) if (module, f) not in ALLOWED]
    assert not bad, f"safepg/{module}.py uses CPU-dispatched linear algebra on an output path: {bad}"


def test_source_scan_can_fail(tmp_path: Path) -> None:
    src = "import numpy as np\ndef f(a, b):\n    return a @ b + np.linalg.norm(a)\n"
    (tmp_path / "probe.py").write_text(src)
    assert {w for w, _, _ in _calls("probe", tmp_path)} == {"@", "linalg"}


# -------------------------------------------------------------- by experiment
def _probe(env: dict[str, str], cache: Path | None) -> subprocess.Popen:
    """The probe in a subprocess under ``env``; ``cache``: a fresh numba cache (every kernel compiled for this
    CPU setting), None: the suite's own (the host's kernels, already compiled)."""
    full = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CPU_NAME", "GLIBC_TUNABLES",
                                                            "NPY_DISABLE_CPU_FEATURES")}
    # One thread each: the probes share the cores.
    full.update(env, NUMBA_NUM_THREADS="1")
    if cache is not None:
        full["NUMBA_CACHE_DIR"] = str(cache)
    return subprocess.Popen([sys.executable, str(ROOT / "tests" / "portable_probe.py")], env=full, cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _result(proc: subprocess.Popen) -> dict:
    out, err = proc.communicate(timeout=1800)
    assert proc.returncode == 0, err[-2000:]
    return json.loads(out)


def numpy_above_avx2() -> list[str]:
    """NumPy's dispatched features above AVX2 (x86-64-v3) that this CPU has: what NPY_DISABLE_CPU_FEATURES
    must name to keep NumPy to its AVX2 loops (naming a feature the CPU lacks is refused)."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return [f for f in __cpu_dispatch__ if __cpu_features__.get(f) and (f.startswith("AVX512") or f == "X86_V4")]


@pytest.mark.slow
def test_runs_are_bit_identical_across_cpu_settings(tmp_path: Path) -> None:
    """Host, AVX2 and pre-AVX2: the same bits. (A probe compiled for a generic x86-64 alone is not run: the
    pre-AVX2 probe compiles for it too and also changes libm and NumPy, so it differs from the host in more.)"""
    avx2 = {"NUMBA_CPU_NAME": "haswell"}
    if numpy_above_avx2():
        avx2["NPY_DISABLE_CPU_FEATURES"] = " ".join(numpy_above_avx2())
    procs = [_probe({}, None), _probe(avx2, tmp_path / "avx2"),
             # As on a CPU without AVX2 and FMA: glibc's plain-SSE2 libm and NumPy's baseline loops.
             _probe({"NUMBA_CPU_NAME": "generic", "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX",
                     "NPY_DISABLE_CPU_FEATURES": " ".join(["X86_V3", *numpy_above_avx2()])}, tmp_path / "old")]
    host, avx2_cpu, old_cpu = (_result(p) for p in procs)
    assert set(host) >= {"1d-bernstein-er", "2d-scalar-step", "cartpole-adaptive", "pendulum-adaptive",
                         "pendulum-vanilla", "pendulum-returns", "closed-forms", "significance"}
    for name in host:
        assert avx2_cpu[name] == host[name], f"{name} differs between AVX2 code (NUMBA_CPU_NAME=haswell) and the host's"
        assert old_cpu[name] == host[name], f"{name} differs with generic x86-64 code and a pre-AVX2 libm and NumPy"


def test_the_avx2_probe_keeps_numpy_to_avx2() -> None:
    """The AVX2 probe's NumPy dispatches to no loop above AVX2 (a subprocess with the probe's setting; in this
    process, on an AVX-512 host, the same check finds X86_V4)."""
    names = numpy_above_avx2()
    env = {**os.environ, "NPY_DISABLE_CPU_FEATURES": " ".join(names)} if names else dict(os.environ)
    code = ("from numpy._core._multiarray_umath import __cpu_dispatch__ as d, __cpu_features__ as f; "
            "print(sorted(k for k in d if f.get(k) and (k.startswith('AVX512') or k == 'X86_V4')))")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_small_angles_skip_the_reduction_with_the_same_bits() -> None:
    """Below 0.78 the fast path returns what the full reduction (k = 0, r = x) gives."""
    x = np.random.default_rng(3).uniform(-0.78, 0.78, 50_000)
    x[:4] = [0.0, -0.0, 0.7799999999999999, -0.7799999999999999]
    for v in x[:2000].tolist() + [0.7799999999999999]:
        r, q = portable._reduce(v)
        assert q == 0 and r == v
    assert portable.sin_array(x).tolist() == [portable.sin_poly(v) for v in x.tolist()]
    assert portable.cos_array(x).tolist() == [portable.cos_poly(v) for v in x.tolist()]
