r"""Counter-based random streams: every trajectory's random numbers from (batch key, index).

The fused kernels draw their own random numbers, inside the loop that uses them, instead
of reading an (N, H, m) array that NumPy filled beforehand on one core. Trajectory n of a
batch reads the stream

.. math::
    u_k = \operatorname{mix}(b_n + k\,\gamma_2), \quad k = 1, 2, \dots, \qquad
    b_n = \operatorname{mix}(\operatorname{mix}(\kappa) + (n + 1)\,\gamma_1),

where :math:`\kappa` is the batch's 64-bit key, :math:`\gamma_1, \gamma_2` are odd Weyl
increments and mix is SplitMix64's output function (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014), which passes BigCrush on a Weyl sequence.
A stream depends only on (key, n), not on which thread runs it or when, so a batch is
the same for any thread count and any chunking, and a kernel can replay a trajectory's
numbers without storing them (the cart-pole's second pass does, for big batches).

The key of every batch comes from the run's ``numpy.random.Generator``
(:func:`batch_key`), so a run's seed still fixes every batch.

Normals are drawn by the 256-layer ziggurat (Marsaglia & Tsang, "The ziggurat method for
generating random variables", J. Stat. Softw. 5(8), 2000) on signed 53-bit integers, laid
out as NumPy's ``standard_normal``. Its tables are computed here with mpmath at 40 digits
and rounded once, and the exponential of the wedge test and the logarithm of the tail use
:func:`safepg.portable.exp_kernel` and :func:`safepg.portable.log_kernel`: every draw is
integer arithmetic and single IEEE operations, the same bits on every x86-64 CPU.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from safepg import portable

_GAMMA_KEY = np.uint64(0x9E3779B97F4A7C15)  # 2^64 / golden ratio, odd
_GAMMA_DRAW = np.uint64(0xD1B54A32D192ED03)  # another odd increment, unrelated to the first
_MIX_1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX_2 = np.uint64(0x94D049BB133111EB)
_TWO_M53 = 1.0 / 9007199254740992.0

#: Right edge r of the ziggurat's base strip for 256 layers: the root, found with mpmath at
#: 60 digits, that makes the 256 equal-area layers close at x = 0 (tests/test_streams.py
#: checks it). NumPy's ``ziggurat_nor_r`` (3.6541528853610087963519472518) differs from it
#: in the 17th digit, enough to leave its top layer's area off by about 3e-14.
ZIGGURAT_R = "3.654152885361008771645429720399515762975"
ZIGGURAT_LAYERS = 256


def _ziggurat_tables(dps: int = 40) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""The tables (k_i, w_i, f_i) of the 256-layer ziggurat, computed at ``dps`` digits.

    With :math:`f(x) = e^{-x^2/2}`, the base strip's area (rectangle plus tail) is
    :math:`v = r f(r) + \sqrt{\pi/2}\,\operatorname{erfc}(r/\sqrt2)` and the layer edges
    satisfy :math:`x_{i-1} = f^{-1}(f(x_i) + v/x_i)`, from :math:`x_{255} = r` down to
    :math:`x_1`. A signed integer j (:math:`|j| < 2^{52}`) in layer i gives :math:`x = j w_i`,
    accepted at once when :math:`|j| < k_i`, i.e. when x lies under the next layer up.
    """
    import mpmath

    with mpmath.workdps(dps):
        r = mpmath.mpf(ZIGGURAT_R)
        f = lambda x: mpmath.exp(-x * x / 2)  # noqa: E731
        v = r * f(r) + mpmath.sqrt(mpmath.pi / 2) * mpmath.erfc(r / mpmath.sqrt(2))
        x = [mpmath.mpf(0)] * ZIGGURAT_LAYERS
        x[-1] = r
        for i in range(ZIGGURAT_LAYERS - 1, 1, -1):
            x[i - 1] = mpmath.sqrt(-2 * mpmath.log(v / x[i] + f(x[i])))
        scale = mpmath.mpf(2) ** 52
        q = v / f(r)  # the base strip as a rectangle of height f(r): its width
        k = np.zeros(ZIGGURAT_LAYERS, dtype=np.uint64)
        w = np.zeros(ZIGGURAT_LAYERS)
        fv = np.zeros(ZIGGURAT_LAYERS)
        k[0] = int(mpmath.floor(r / q * scale))
        w[0] = float(q / scale)
        fv[0] = 1.0
        for i in range(1, ZIGGURAT_LAYERS):
            k[i] = 0 if i == 1 else int(mpmath.floor(x[i - 1] / x[i] * scale))
            w[i] = float(x[i] / scale)
            fv[i] = float(f(x[i]))
    return k, w, fv


_K, _W, _F = _ziggurat_tables()
_R = float(ZIGGURAT_R)
_INV_R = 1.0 / _R


@njit(cache=True)
def mix(z: np.uint64) -> np.uint64:
    """SplitMix64's output function: a bijection of 64-bit integers that mixes every bit."""
    z = (z ^ (z >> np.uint64(30))) * _MIX_1
    z = (z ^ (z >> np.uint64(27))) * _MIX_2
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def stream_start(key: np.uint64, n: int) -> np.uint64:
    """The state of trajectory ``n``'s stream before its first draw, :math:`b_n`."""
    return mix(mix(np.uint64(key)) + np.uint64(n + 1) * _GAMMA_KEY)


@njit(cache=True)
def next_uint64(state: np.uint64) -> tuple[np.uint64, np.uint64]:
    """(next 64-bit output, new state) of a stream."""
    # uint64 even when called from Python with a state below 2^63, which numba would type as
    # int64 (and int64 + uint64 is a float in numba).
    state = np.uint64(state) + _GAMMA_DRAW
    return mix(state), state


@njit(cache=True)
def next_uniform(state: np.uint64) -> tuple[float, np.uint64]:
    """A uniform double in [0, 1) (the top 53 bits times 2^-53) and the new state."""
    bits, state = next_uint64(state)
    # Through int64 (exact below 2^63): one conversion instruction, unlike uint64's.
    return float(np.int64(bits >> np.uint64(11))) * _TWO_M53, state


@njit(cache=True)
def next_normal(state: np.uint64) -> tuple[float, np.uint64]:
    """A standard normal by the ziggurat, and the new state.

    One 64-bit draw gives the layer (its low 8 bits) and a signed 53-bit abscissa (its top
    53 bits); about 98.5% of draws return at the first comparison. The rest take the wedge
    test (:math:`f(x)` against a uniform height inside the layer) or, in the base strip,
    sample the tail beyond r by Marsaglia's exponential method (:func:`_normal_slow`).
    """
    z, state, accepted = normal_candidate(state)
    if accepted:
        return z, state
    return normal_redraw(state)


@njit(cache=True)
def normal_candidate(state: np.uint64) -> tuple[float, np.uint64, bool]:
    """The ziggurat's first comparison alone: (candidate, new state, accepted).

    Branch-free, so that a kernel can draw a whole array of streams in one vectorised loop
    and call :func:`normal_redraw` for the few rejected ones; the two together are
    :func:`next_normal`, the same bits.
    """
    bits, state = next_uint64(state)
    idx = np.intp(bits & np.uint64(0xFF))
    # The top 53 bits as a signed integer j in [-2^52, 2^52): sign and abscissa at once,
    # with no unpredictable branch on the sign.
    j = np.int64(bits) >> np.int64(11)
    return float(j) * _W[idx], state, np.uint64(abs(j)) < _K[idx]


@njit(cache=True)
def normal_redraw(state: np.uint64) -> tuple[float, np.uint64]:
    """The normal of a draw that :func:`normal_candidate` rejected, from the stream's state
    after that draw (whose 64 bits were ``mix(state)``)."""
    bits = mix(state)
    return _normal_slow(np.intp(bits & np.uint64(0xFF)), np.int64(bits) >> np.int64(11), state)


@njit(cache=True)
def normal_scratch(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scratch space for :func:`draw_normals` on up to ``n`` streams: (flags, indices, values)."""
    return np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.intp), np.empty(n)


@njit(cache=True)
def draw_normals(st: np.ndarray, out: np.ndarray, scratch: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    """One standard normal from each of the streams ``st[:n]``, into ``out`` (n = ``out.size``).

    Each stream's numbers are those of :func:`next_normal`, drawn in three passes that the
    compiler vectorises where it matters:

    1. the ziggurat's first comparison for the whole array, branch-free;
    2. the wedge test of the 1.5% of draws it rejects, gathered by index, also branch-free
       (:func:`_wedge_test`; about half pass);
    3. the rest finished one by one (:func:`_after_wedge`).

    ``scratch`` is :func:`normal_scratch` of at least n. ``out`` is typically a slice of a
    kernel's rows: one compiled draw_normals for every caller, where a row offset passed as a
    constant would be compiled once per constant.
    """
    rejected, redo, xs = scratch
    n = out.size
    n_rejected = 0
    for j in range(n):
        out[j], st[j], accepted = normal_candidate(st[j])
        rejected[j] = not accepted
        n_rejected += not accepted
    if n_rejected == 0:
        return
    # The rejected indices, in order. Eight flags are tested at once: one branch per eight
    # draws, rarely taken, instead of one per draw.
    m = 0
    whole = n // 8
    words = rejected[:whole * 8].view(np.uint64)
    for w in range(whole):
        if words[w]:
            for j in range(8 * w, 8 * w + 8):
                redo[m] = j
                m += rejected[j]
    for j in range(whole * 8, n):
        redo[m] = j
        m += rejected[j]
    passed = rejected  # the flags are read: their space holds the wedge tests' outcomes
    for k in range(m):
        xs[k], passed[k] = _wedge_test(st[redo[k]])
    for k in range(m):
        j = redo[k]
        if passed[k]:
            out[j] = xs[k]
            st[j] = st[j] + _GAMMA_DRAW  # the wedge test's uniform
        else:
            out[j], st[j] = _after_wedge(st[j])


@njit(cache=True)
def _wedge_test(state: np.uint64) -> tuple[float, bool]:
    """The first wedge test of a draw that :func:`normal_candidate` rejected, from the stream's
    state after that draw: (x, passed). Branch-free; the base strip (layer 0) never passes here.
    :func:`_normal_slow`'s first test, with :func:`safepg.portable.exp_in_range` for its
    exponential: |x| is below 4, so -x^2/2 is in its range and the bits are exp_kernel's."""
    bits = mix(state)
    idx = np.intp(bits & np.uint64(0xFF))
    x = float(np.int64(bits) >> np.int64(11)) * _W[idx]
    u, _ = next_uniform(state)
    i = max(int(idx), 1)  # layer 0's test is the tail's, not this one: any in-bounds index will do
    return x, (idx != 0) & ((_F[i - 1] - _F[i]) * u + _F[i] < portable.exp_in_range(-0.5 * x * x))


@njit(cache=True)
def _after_wedge(state: np.uint64) -> tuple[float, np.uint64]:
    """The normal of a draw whose first wedge test failed (or whose layer is the base strip),
    from the stream's state after the rejected draw: :func:`normal_redraw` from its second test on."""
    bits = mix(state)
    idx = np.intp(bits & np.uint64(0xFF))
    j = np.int64(bits) >> np.int64(11)
    if idx == 0:
        return _normal_slow(idx, j, state)
    _, state = next_uniform(state)  # the failed wedge test's uniform
    bits, state = next_uint64(state)
    idx = np.intp(bits & np.uint64(0xFF))
    j = np.int64(bits) >> np.int64(11)
    if np.uint64(abs(j)) < _K[idx]:
        return float(j) * _W[idx], state
    return _normal_slow(idx, j, state)


@njit(cache=True)
def _normal_slow(idx: np.intp, j: np.int64, state: np.uint64) -> tuple[float, np.uint64]:
    """The ziggurat's rare branches for a draw (idx, j) that missed the rectangle test; kept
    out of :func:`next_normal` so that the common path stays a few instructions."""
    while True:
        x = float(j) * _W[idx]
        if idx == 0:
            while True:
                u1, state = next_uniform(state)
                u2, state = next_uniform(state)
                # 1 - u is in (0, 1]: its logarithm is finite.
                xx = -_INV_R * portable.log_kernel(1.0 - u1)
                yy = -portable.log_kernel(1.0 - u2)
                if yy + yy > xx * xx:
                    return (-(_R + xx) if j < 0 else _R + xx), state
        u, state = next_uniform(state)
        if (_F[idx - 1] - _F[idx]) * u + _F[idx] < portable.exp_kernel(-0.5 * x * x):
            return x, state
        bits, state = next_uint64(state)
        idx = np.intp(bits & np.uint64(0xFF))
        j = np.int64(bits) >> np.int64(11)
        if np.uint64(abs(j)) < _K[idx]:
            return float(j) * _W[idx], state


def batch_key(rng: np.random.Generator) -> np.uint64:
    """A batch's key: one 64-bit draw from the run's generator."""
    return np.uint64(rng.integers(0, 2**64, dtype=np.uint64))


def batch_keys(rng: np.random.Generator, count: int) -> np.ndarray:
    """The keys of ``count`` consecutive batches at once: the numbers as many calls of
    :func:`batch_key` draw (a whole-range draw takes one 64-bit output each)."""
    return rng.integers(0, 2**64, size=int(count), dtype=np.uint64)


@njit(cache=True, parallel=True)
def _draws(key, n, n_uniform, n_normal):
    uniforms = np.empty((n, n_uniform))
    normals = np.empty((n, n_normal))
    for i in prange(n):
        state = stream_start(key, i)
        for j in range(n_uniform):
            uniforms[i, j], state = next_uniform(state)
        for j in range(n_normal):
            normals[i, j], state = next_normal(state)
    return uniforms, normals


def trajectory_draws(key: np.uint64, n: int, n_uniform: int, n_normal: int) -> tuple[np.ndarray, np.ndarray]:
    """The numbers the fused kernels draw for trajectories 0..n-1 of batch ``key``.

    Each trajectory reads ``n_uniform`` uniforms on [0, 1) (its initial state) and then
    ``n_normal`` standard normals (its actions, step by step, component by component).
    The reference simulators use this to see the same batch as the fused kernels.

    Returns
    -------
    uniforms : ndarray, shape (n, n_uniform)
    normals : ndarray, shape (n, n_normal)
    """
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n}")
    for name, value in (("n_uniform", n_uniform), ("n_normal", n_normal)):
        if int(value) != value or value < 0:
            raise ValueError(f"{name} must be an integer >= 0, got {value}")
    draws: tuple[np.ndarray, np.ndarray] = _draws(np.uint64(key), int(n), int(n_uniform), int(n_normal))
    return draws


@njit(cache=True, parallel=True)
def _normal_sums(key, n, per_stream):
    chunks = np.zeros(n)
    for i in prange(n):
        state = stream_start(key, i)
        acc = 0.0
        for _ in range(per_stream):
            x, state = next_normal(state)
            acc += x
        chunks[i] = acc
    return chunks


def normal_rate_probe(key: np.uint64, streams: int, per_stream: int) -> float:
    """Sum of ``streams * per_stream`` normals drawn and discarded: the generator's own cost
    (benchmarks/bench_book.py times it against NumPy's generators)."""
    return float(_normal_sums(np.uint64(key), int(streams), int(per_stream)).sum())


__all__ = ["ZIGGURAT_LAYERS", "ZIGGURAT_R", "batch_key", "batch_keys", "mix", "next_normal", "next_uint64",
           "next_uniform", "normal_rate_probe", "normal_scratch", "stream_start", "trajectory_draws"]
