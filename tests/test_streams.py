"""The counter-based streams of the fused kernels: construction, exactness, distribution.

Statistical checks use 4*10^6 normals with tolerances of 5 standard errors (or p-values
above 10^-4), so a correct generator fails one of them about once in 10^5 runs, while a
wrong table entry, a biased sign or a correlated stream fails them at once.
"""

from __future__ import annotations

import math

import mpmath
import numba
import numpy as np
import pytest
from scipy import stats

from safepg import portable, streams

MASK = (1 << 64) - 1


def _mix_reference(z: int) -> int:
    """SplitMix64's output function on Python integers (mod 2^64), from its published constants."""
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


@pytest.fixture(scope="module")
def normals() -> np.ndarray:
    return streams.trajectory_draws(np.uint64(20261125), 20_000, 0, 200)[1].ravel()


def test_uint64_stream_equals_python_integer_reference() -> None:
    key, n = 0x0123456789ABCDEF, 7
    base = _mix_reference((_mix_reference(key) + (n + 1) * 0x9E3779B97F4A7C15) & MASK)
    assert int(streams.stream_start(np.uint64(key), n)) == base
    state = streams.stream_start(np.uint64(key), n)
    for k in range(1, 50):
        bits, state = streams.next_uint64(np.uint64(state))  # numba returns a Python int
        assert int(bits) == _mix_reference((base + k * 0xD1B54A32D192ED03) & MASK)


def test_fast_path_equals_integer_arithmetic() -> None:
    """A draw accepted at the first comparison is j * w_idx, j the top 53 bits as a signed integer."""
    state = streams.stream_start(np.uint64(99), 0)
    checked = 0
    for _ in range(3000):
        start = np.uint64(state)  # numba returns a Python int
        bits, _ = streams.next_uint64(start)
        idx = int(bits) & 0xFF
        j = (int(bits) >> 11) - (1 << 53 if int(bits) >> 63 else 0)
        x, state = streams.next_normal(start)
        if abs(j) < int(streams._K[idx]):
            assert x == float(j) * streams._W[idx]
            checked += 1
    assert checked > 2900


@numba.njit
def _paths(st: np.ndarray) -> np.ndarray:
    """How many draws of each stream's next normal leave :func:`draw_normals`'s passes where:
    (first comparison, wedge test passed, finished one by one; of those in the base strip)."""
    out = np.zeros(4, dtype=np.int64)
    for j in range(st.size):
        _, state, accepted = streams.normal_candidate(st[j])
        if accepted:
            out[0] += 1
        else:
            out[1 + (not streams._wedge_test(state)[1])] += 1
            out[3] += (streams.mix(state) & np.uint64(0xFF)) == 0
    return out


@pytest.mark.parametrize("n", [1, 7, 8, 61, 2048])
def test_draw_normals_equals_next_normal(n: int) -> None:
    """The vectorised passes give each stream the numbers of next_normal, and leave its state
    where next_normal leaves it; every path through them is taken (for n = 2048: the wedge test
    passed and failed, the base strip's tail)."""
    st = np.array([streams.stream_start(np.uint64(20261128), i) for i in range(n)], dtype=np.uint64)
    ref = st.copy()
    out, scratch = np.full(n + 3, np.nan), streams.normal_scratch(n + 5)  # scratch may be larger than n
    paths = np.zeros(4, dtype=np.int64)
    for _ in range(max(20, 400_000 // n)):
        paths += _paths(st)
        streams.draw_normals(st, out[2:2 + n], scratch)
        want = np.empty(n)
        for j in range(n):
            want[j], ref[j] = streams.next_normal(np.uint64(ref[j]))
        assert out[2:2 + n].view(np.uint64).tolist() == want.view(np.uint64).tolist()
        assert st.tolist() == ref.tolist()
    assert np.isnan(out[:2]).all() and np.isnan(out[2 + n:]).all()
    if n == 2048:
        assert min(paths[1], paths[2]) > 2000 and paths[3] > 50, paths


@numba.njit
def _exp_loop(v: np.ndarray) -> np.ndarray:
    out = np.empty_like(v)
    for i in range(v.size):
        out[i] = portable.exp_in_range(v[i])
    return out


def test_exp_in_range_is_exp_kernel_in_a_vectorised_loop() -> None:
    """The wedge tests' exponential, in a loop the compiler vectorises, has exp_kernel's bits."""
    x = -0.5 * np.random.default_rng(3).uniform(-4.0, 4.0, 10_001) ** 2
    got = _exp_loop(x)
    assert got.view(np.uint64).tolist() == np.array([portable.exp_kernel.py_func(float(t)) for t in x]).view(
        np.uint64).tolist()


def test_ziggurat_layers_have_equal_areas_and_close_at_zero() -> None:
    """Rebuilt at 60 digits from r: every layer has area v, and the top one ends at x = 0
    within 10^-25 (r is right to ~28 digits), so the 256 layers tile the half-density."""
    with mpmath.workdps(60):
        r = mpmath.mpf(streams.ZIGGURAT_R)
        f = lambda x: mpmath.exp(-x * x / 2)  # noqa: E731
        v = r * f(r) + mpmath.sqrt(mpmath.pi / 2) * mpmath.erfc(r / mpmath.sqrt(2))
        x = [r]
        for _ in range(254):
            x.append(mpmath.sqrt(-2 * mpmath.log(v / x[-1] + f(x[-1]))))
        top = x[-1] * (1 - f(x[-1]))  # the last rectangle, from f(x_1) up to f(0) = 1
        assert abs(top - v) / v < mpmath.mpf(10) ** -25
        # The double tables: w_i = x_i / 2^52, f_i = f(x_i), k_i = floor(2^52 x_{i-1} / x_i).
        for i, xi in zip(range(255, 0, -1), x):
            assert streams._W[i] == float(xi / 2**52)
            assert streams._F[i] == float(f(xi))
        assert int(streams._K[1]) == 0 and streams._F[0] == 1.0
        assert int(streams._K[0]) == int(mpmath.floor(r * f(r) / v * 2**52))


def test_moments(normals: np.ndarray) -> None:
    n = normals.size
    assert abs(normals.mean()) < 5 / math.sqrt(n)
    assert abs(normals.var() - 1) < 5 * math.sqrt(2 / n)
    assert abs(stats.skew(normals)) < 5 * math.sqrt(6 / n)
    assert abs(stats.kurtosis(normals)) < 5 * math.sqrt(24 / n)


def test_kolmogorov_smirnov_and_histogram(normals: np.ndarray) -> None:
    assert stats.kstest(normals, "norm").pvalue > 1e-4
    # 400 equiprobable bins: the wedges of every layer and both signs, finely.
    edges = stats.norm.ppf(np.linspace(0, 1, 401))
    counts = np.histogram(normals, bins=edges)[0]
    assert stats.chisquare(counts).pvalue > 1e-4


@pytest.mark.parametrize("a", [1.0, 2.5, streams._R, 4.0, 4.5])
def test_tails(normals: np.ndarray, a: float) -> None:
    """P(|Z| > a) within 5 binomial standard deviations, past the base strip's r included."""
    n = normals.size
    p = 2 * stats.norm.sf(a)
    hits = np.count_nonzero(np.abs(normals) > a)
    assert abs(hits - n * p) < 5 * math.sqrt(n * p * (1 - p)) + 1


def test_streams_are_uncorrelated(normals: np.ndarray) -> None:
    z = normals.reshape(20_000, 200)
    lim = 5 / math.sqrt(z.shape[0])
    assert abs(np.corrcoef(z[:-1, 0], z[1:, 0])[0, 1]) < lim  # neighbouring trajectories
    assert abs(np.corrcoef(z[:, 0], z[:, 1])[0, 1]) < lim     # consecutive draws of one stream
    keys = streams.trajectory_draws(np.uint64(20261126), 20_000, 0, 1)[1][:, 0]
    assert abs(np.corrcoef(z[:, 0], keys)[0, 1]) < lim         # neighbouring batch keys


def test_uniforms() -> None:
    u = streams.trajectory_draws(np.uint64(5), 50_000, 4, 0)[0]
    assert u.min() >= 0 and u.max() < 1
    assert stats.kstest(u.ravel(), "uniform").pvalue > 1e-4
    assert abs(np.corrcoef(u[:, 0], u[:, 1])[0, 1]) < 5 / math.sqrt(u.shape[0])


def test_draws_depend_on_key_and_index_only() -> None:
    """Trajectory i's numbers do not depend on the batch size or the thread count."""
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        small = streams.trajectory_draws(np.uint64(11), 10, 2, 30)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        big = streams.trajectory_draws(np.uint64(11), 5000, 2, 30)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(small[0], big[0][:10]) and np.array_equal(small[1], big[1][:10])
    assert not np.array_equal(small[1], streams.trajectory_draws(np.uint64(12), 10, 2, 30)[1])


def test_batch_key_comes_from_the_generator() -> None:
    a, b = streams.batch_key(np.random.default_rng(4)), streams.batch_key(np.random.default_rng(4))
    assert a == b and isinstance(a, np.uint64)
    g = np.random.default_rng(4)
    assert streams.batch_key(g) != streams.batch_key(g)


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="^n "):
        streams.trajectory_draws(np.uint64(1), 0, 1, 1)
    with pytest.raises(ValueError, match="^n_normal "):
        streams.trajectory_draws(np.uint64(1), 3, 1, -1)


def test_kernel_exp_and_log_within_two_ulp_and_free_of_fma() -> None:
    gen = np.random.default_rng(2)
    x = np.concatenate([gen.uniform(-30, 0, 20_000), gen.uniform(-700, 700, 2000), [0.0, -0.5, 1e-20]])
    u = np.concatenate([gen.uniform(0, 1, 20_000), 10.0 ** gen.uniform(-300, 300, 2000), [1.0, 2.0**-53, 0.5]])
    with mpmath.workdps(30):
        want_exp = np.array([float(mpmath.exp(mpmath.mpf(v))) for v in x])
        want_log = np.array([float(mpmath.log(mpmath.mpf(v))) for v in u])
    got_exp = np.array([portable.exp_kernel(v) for v in x])
    got_log = np.array([portable.log_kernel(v) for v in u])
    assert np.all(np.abs(got_exp - want_exp) <= 2 * np.spacing(want_exp))
    assert np.all(np.abs(got_log - want_log) <= 2 * np.spacing(np.abs(want_log)) + 5e-324)
    # Compiled equals interpreted: no multiply-add was fused on this CPU.
    assert got_exp[:500].tolist() == [portable.exp_kernel.py_func(float(v)) for v in x[:500]]
    assert got_log[:500].tolist() == [portable.log_kernel.py_func(float(v)) for v in u[:500]]
    assert portable.exp_kernel(-800.0) == 0.0 and portable.log_kernel(0.0) == -math.inf
