"""Fused LQG simulation + gradient-sample kernel (numba).

The reference path (``LQG.simulate`` then :mod:`safepg.estimators`) materialises
several (N, H, m) arrays and makes a dozen passes over them; this kernel makes one pass
per trajectory and gives the same numbers up to floating-point rounding (tested). Each
trajectory draws its own random numbers inside the loop, from its counter-based stream
(:mod:`safepg.streams`: the batch key and the trajectory's index), so no (N, H, m) array
of normals is ever formed; the reference path reads the same streams through
:func:`safepg.streams.trajectory_draws`, so both paths see the same batch.

Trajectories are processed in fixed-size chunks in parallel; every chunk writes its own
partial sums and the chunks are reduced in order, so the result does not depend on the
number of threads.
"""

from __future__ import annotations

import types

import numpy as np
from numba import njit, prange

from safepg.streams import draw_normals, next_normal, next_uniform, normal_scratch, stream_start

CHUNK = 2048


# A chunk's per-trajectory quantities in one flat array of rows, trajectory i at row + i: one
# array with constant distances between rows lets the compiler prove that they do not
# overlap and vectorise the step without run-time tests. The rows are 64 bytes more than a
# multiple of 4 KiB apart, so that a trajectory's entries do not share a cache set (4K
# aliasing, which stalls loads behind unrelated stores).
ROW = CHUNK + 8
S1, CUM1, ACC1, RET1, Z1, DR1 = 0 * ROW, 1 * ROW, 2 * ROW, 3 * ROW, 4 * ROW, 5 * ROW
ROWS1 = 6


@njit(cache=True)
def _rows(rows, m):
    """A chunk's ``rows`` rows of ROW entries, the first m of each zero: only those are read. Zeroing
    whole rows (230 kB in 2-D) took 12% of a Table 5.3 run at N = 100."""
    T = np.empty(rows * ROW)
    for r in range(rows):
        T[r * ROW:r * ROW + m] = 0.0
    return T


@njit(cache=True, parallel=True, error_model="numpy")
def lqg1d_gradient_samples(theta, sigma, A, B, Q, R, key, N, H, gamma, bs, ba, clip, score_clipped,
                           reinforce_estimator, baseline):
    """Scalar (m = 1) version of :func:`lqg_gradient_samples`.

    Section 5.1's campaign is almost all scalar steps. Within a chunk, time runs in the outer
    loop and the chunk's trajectories in the inner ones, three per step: the normals for all
    of them (:func:`safepg.streams.draw_normals`); the policy, reward, score and dynamics in
    one branch-free loop that the compiler vectorises (:func:`_step1d`); then the baseline
    sums over trajectories in index order. Every trajectory's operations and every sum's
    order are those of following the trajectories one by one: the same bits.
    """
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.empty((N, 1))
    returns = np.empty(N)
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks, rows))
    den = np.zeros((n_chunks, rows))
    # G_{n,t} for pass 2, time-major: step t of a chunk writes, and pass 2 reads, one run of memory.
    kept = np.empty((rows, N if baseline else 1))
    inv_var = 1.0 / (sigma * sigma)
    for c in prange(n_chunks):
        lo = c * CHUNK
        m = min(N, lo + CHUNK) - lo
        T = _rows(ROWS1, m)
        st = np.empty(m, dtype=np.uint64)  # each trajectory's stream
        scratch = normal_scratch(m)
        for i in range(m):
            state = stream_start(key, lo + i)
            u0, st[i] = next_uniform(state)
            T[S1 + i] = -bs + (bs + bs) * u0  # uniform on [-bs, bs), as numpy's uniform(-bs, bs)
        disc = 1.0
        for t in range(H):
            draw_normals(st, T[Z1:Z1 + m], scratch)
            _step1d(m, T, theta, sigma, A, B, Q, R, disc, bs, ba, clip, score_clipped, reinforce_estimator, inv_var)
            if not reinforce_estimator:
                nt, dt = num[c, t], den[c, t]
                for i in range(m):  # in index order
                    g = T[CUM1 + i]
                    nt += g * g * T[DR1 + i]
                    dt += g * g
                    if baseline:
                        kept[t, lo + i] = g
                num[c, t], den[c, t] = nt, dt
            disc *= gamma
        for i in range(m):
            n = lo + i
            returns[n] = T[RET1 + i]
            if reinforce_estimator:
                g = T[CUM1 + i]
                num[c, 0] += g * g * T[RET1 + i]
                den[c, 0] += g * g
                T[ACC1 + i] = g * T[RET1 + i]
                if baseline:
                    kept[0, n] = g
            samples[n, 0] = T[ACC1 + i]
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            lo, hi = c * CHUNK, min(N, (c + 1) * CHUNK)
            m = hi - lo
            acc = np.zeros(m)  # sum_t G_{n,t} b_t, added in t order for each n
            for t in range(rows):
                bt = b[t]
                row = kept[t, lo:hi]  # a 1-D slice: the compiler vectorises this loop, not kept[t, n]
                for i in range(m):
                    acc[i] += row[i] * bt
            for i in range(m):
                samples[lo + i, 0] -= acc[i]
    return samples, returns


@njit(cache=True, error_model="numpy")
def _step1d(m, T, theta, sigma, A, B, Q, R, disc, bs, ba, clip, score_clipped, reinforce_estimator, inv_var):
    """One step of the chunk's m trajectories (rows of ``T``); ``T[DR1 + i]`` keeps each
    trajectory's discounted reward of the step for the baseline sums."""
    for i in range(m):
        si = T[S1 + i]
        mean = theta * si
        a_raw = mean + sigma * T[Z1 + i]
        u = min(max(a_raw, -ba), ba) if clip else a_raw
        dr = -0.5 * (Q * si * si + R * u * u) * disc
        T[DR1 + i] = dr
        T[RET1 + i] += dr
        g = T[CUM1 + i] + ((u if score_clipped else a_raw) - mean) * si * inv_var
        T[CUM1 + i] = g
        if not reinforce_estimator:
            T[ACC1 + i] += g * dr
        s_next = A * si + B * u
        T[S1 + i] = min(max(s_next, -bs), bs) if clip else s_next


@njit(cache=True, parallel=True, error_model="numpy")
def lqg2d_gradient_samples(K, L, Pm, A, B, Q, R, key, N, H, gamma, bs, ba, clip, score_clipped,
                           reinforce_estimator, baseline):
    """Two-dimensional (m = 2) version of :func:`lqg_gradient_samples`.

    Same arguments, semantics and outputs (samples (N, 4), returns (N,)). Section 5.2's
    campaign is all m = 2 steps; the runtime-sized m x m loops of the generic kernel keep
    state, action, scores and sample sums in memory and index every matrix through its
    strides, which dominates at m = 2. Here the 2 x 2 algebra is unrolled, and, as in
    :func:`lqg1d_gradient_samples`, time runs outside and each step is three loops over the
    chunk's trajectories: their two normals each, the step vectorised (:func:`_step2d`),
    and the baseline sums in index order (:func:`_sums2d`).

    Every sum is formed in the same order as in the generic kernel, so the two give the
    same bits (tested bit for bit, as is the 1-D kernel); swapping kernels does not change a seeded run.
    That rules out regrouping the cost quadratic forms to save a few multiplies.

    Parameters
    ----------
    K, L, Pm, A, B, Q, R : ndarray (2, 2)
        Gain, lower Cholesky factor of the policy covariance (its upper entry is not
        read), precision, dynamics and cost matrices.
    key : uint64
        The batch's key (:func:`safepg.streams.batch_key`): trajectory n draws its initial
        state (2 uniforms) and then its standard normals z (2 per step; the action noise
        is L z) from stream n of this key.
    N, H : int
        Batch size and horizon.
    gamma, bs, ba : float
        Discount, state and action box half-widths.
    clip, score_clipped, reinforce_estimator, baseline : bool
        As in :func:`lqg_gradient_samples`.

    Returns
    -------
    samples : ndarray (N, 4)
        Per-trajectory gradient samples, flattened like K (row-major).
    returns : ndarray (N,)
        Discounted returns.
    """
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.empty((N, 4))
    returns = np.empty(N)
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks, rows, 4))
    den = np.zeros((n_chunks, rows, 4))
    kept = np.empty((rows, 4, N if baseline else 1))  # time-major, as in the 1-D kernel
    for c in prange(n_chunks):
        lo = c * CHUNK
        m = min(N, lo + CHUNK) - lo
        T = _rows(ROWS2, m)
        st = np.empty(m, dtype=np.uint64)  # each trajectory's stream
        scratch = normal_scratch(m)
        for i in range(m):
            state = stream_start(key, lo + i)
            v0, state = next_uniform(state)
            v1, st[i] = next_uniform(state)
            T[X0 + i] = -bs + (bs + bs) * v0
            T[X1 + i] = -bs + (bs + bs) * v1
        disc = 1.0
        for t in range(H):
            draw_normals(st, T[Z0:Z0 + m], scratch)  # each stream: z0, then z1
            draw_normals(st, T[Z1_:Z1_ + m], scratch)
            _step2d(m, T, K, L, Pm, A, B, Q, R, disc, bs, ba, clip, score_clipped, reinforce_estimator)
            if not reinforce_estimator:
                _sums2d(m, T, num[c, t], den[c, t], kept, lo, t, baseline)
            disc *= gamma
        for i in range(m):
            n = lo + i
            ret = T[RET2 + i]
            returns[n] = ret
            g00, g01, g10, g11 = T[G00 + i], T[G01 + i], T[G10 + i], T[G11 + i]
            if reinforce_estimator:
                h00 = g00 * g00
                h01 = g01 * g01
                h10 = g10 * g10
                h11 = g11 * g11
                num[c, 0, 0] += h00 * ret
                num[c, 0, 1] += h01 * ret
                num[c, 0, 2] += h10 * ret
                num[c, 0, 3] += h11 * ret
                den[c, 0, 0] += h00
                den[c, 0, 1] += h01
                den[c, 0, 2] += h10
                den[c, 0, 3] += h11
                samples[n, 0] = g00 * ret
                samples[n, 1] = g01 * ret
                samples[n, 2] = g10 * ret
                samples[n, 3] = g11 * ret
                if baseline:
                    kept[0, 0, n] = g00
                    kept[0, 1, n] = g01
                    kept[0, 2, n] = g10
                    kept[0, 3, n] = g11
            else:
                samples[n, 0] = T[F00 + i]
                samples[n, 1] = T[F01 + i]
                samples[n, 2] = T[F10 + i]
                samples[n, 3] = T[F11 + i]
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            lo, hi = c * CHUNK, min(N, (c + 1) * CHUNK)
            m = hi - lo
            acc = np.empty(m)
            # Component by component, so that the running sums stay in one short array; for each
            # n, sum_t G_{n,t} b_t is still added in t order. One-dimensional slices: the compiler
            # vectorises these loops, not the same loops indexing the 3-D array.
            for p in range(4):
                acc[:] = 0.0
                for t in range(rows):
                    bt = b[t, p]
                    row = kept[t, p, lo:hi]
                    for i in range(m):
                        acc[i] += row[i] * bt
                for i in range(m):
                    samples[lo + i, p] -= acc[i]
    return samples, returns


# The 2-D kernel's rows (see ROW above): state, cumulative scores G, G(PO)MDP sums F,
# return, the step's two normals and its discounted reward.
X0, X1 = 0 * ROW, 1 * ROW
G00, G01, G10, G11 = 2 * ROW, 3 * ROW, 4 * ROW, 5 * ROW
F00, F01, F10, F11 = 6 * ROW, 7 * ROW, 8 * ROW, 9 * ROW
RET2, Z0, Z1_, DR2 = 10 * ROW, 11 * ROW, 12 * ROW, 13 * ROW
ROWS2 = 14


@njit(cache=True, error_model="numpy")
def _step2d(m, T, K, L, Pm, A, B, Q, R, disc, bs, ba, clip, score_clipped, reinforce_estimator):
    """One step of the chunk's m trajectories (rows of ``T``), the 2 x 2 algebra unrolled."""
    k00, k01, k10, k11 = K[0, 0], K[0, 1], K[1, 0], K[1, 1]
    l00, l10, l11 = L[0, 0], L[1, 0], L[1, 1]
    p00, p01, p10, p11 = Pm[0, 0], Pm[0, 1], Pm[1, 0], Pm[1, 1]
    a00, a01, a10, a11 = A[0, 0], A[0, 1], A[1, 0], A[1, 1]
    b00, b01, b10, b11 = B[0, 0], B[0, 1], B[1, 0], B[1, 1]
    q00, q01, q10, q11 = Q[0, 0], Q[0, 1], Q[1, 0], Q[1, 1]
    r00, r01, r10, r11 = R[0, 0], R[0, 1], R[1, 0], R[1, 1]
    for i in range(m):
        x0, x1 = T[X0 + i], T[X1 + i]
        m0 = k00 * x0 + k01 * x1
        m1 = k10 * x0 + k11 * x1
        z0, z1 = T[Z0 + i], T[Z1_ + i]
        a0 = m0 + l00 * z0
        a1 = m1 + (l10 * z0 + l11 * z1)
        if clip:
            u0 = min(max(a0, -ba), ba)
            u1 = min(max(a1, -ba), ba)
        else:
            u0 = a0
            u1 = a1
        # (i, j) terms summed in the generic kernel's order, so results match bit for bit.
        cost = (x0 * q00 * x0 + u0 * r00 * u0) + (x0 * q01 * x1 + u0 * r01 * u1)
        cost = cost + (x1 * q10 * x0 + u1 * r10 * u0)
        cost = cost + (x1 * q11 * x1 + u1 * r11 * u1)
        dr = -0.5 * cost * disc
        T[DR2 + i] = dr
        T[RET2 + i] += dr
        if score_clipped:
            e0 = u0 - m0
            e1 = u1 - m1
        else:
            e0 = a0 - m0
            e1 = a1 - m1
        d0 = p00 * e0 + p01 * e1
        d1 = p10 * e0 + p11 * e1
        g00 = T[G00 + i] + d0 * x0  # score of Section 2.3.13, summed over k <= t
        g01 = T[G01 + i] + d0 * x1
        g10 = T[G10 + i] + d1 * x0
        g11 = T[G11 + i] + d1 * x1
        T[G00 + i], T[G01 + i], T[G10 + i], T[G11 + i] = g00, g01, g10, g11
        if not reinforce_estimator:
            T[F00 + i] += g00 * dr
            T[F01 + i] += g01 * dr
            T[F10 + i] += g10 * dr
            T[F11 + i] += g11 * dr
        y0 = (a00 * x0 + b00 * u0) + (a01 * x1 + b01 * u1)
        y1 = (a10 * x0 + b10 * u0) + (a11 * x1 + b11 * u1)
        if clip:
            T[X0 + i] = min(max(y0, -bs), bs)
            T[X1 + i] = min(max(y1, -bs), bs)
        else:
            T[X0 + i] = y0
            T[X1 + i] = y1


@njit(cache=True)
def _sums2d(m, T, num, den, kept, lo, t, baseline):
    """The chunk's baseline sums at step t over its m trajectories, in index order (the
    order of following them one by one), and with a baseline their G for pass 2."""
    n0, n1, n2, n3 = num[0], num[1], num[2], num[3]
    e0, e1, e2, e3 = den[0], den[1], den[2], den[3]
    for i in range(m):
        g00, g01, g10, g11 = T[G00 + i], T[G01 + i], T[G10 + i], T[G11 + i]
        dr = T[DR2 + i]
        h00 = g00 * g00
        h01 = g01 * g01
        h10 = g10 * g10
        h11 = g11 * g11
        n0 += h00 * dr
        n1 += h01 * dr
        n2 += h10 * dr
        n3 += h11 * dr
        e0 += h00
        e1 += h01
        e2 += h10
        e3 += h11
        if baseline:
            kept[t, 0, lo + i] = g00
            kept[t, 1, lo + i] = g01
            kept[t, 2, lo + i] = g10
            kept[t, 3, lo + i] = g11
    num[0], num[1], num[2], num[3] = n0, n1, n2, n3
    den[0], den[1], den[2], den[3] = e0, e1, e2, e3


@njit(cache=True)
def _baseline(num, den):
    """b = (sum of chunk numerators) / (sum of chunk denominators), 0 where den = 0.

    Chunks are added in order, so the result does not depend on the thread count.
    """
    nb = np.zeros(num.shape[1:])
    db = np.zeros(den.shape[1:])
    for c in range(num.shape[0]):
        nb += num[c]
        db += den[c]
    b = np.zeros_like(nb)
    flat_b, flat_n, flat_d = b.reshape(-1), nb.reshape(-1), db.reshape(-1)
    for i in range(flat_b.size):
        if flat_d[i] != 0.0:
            flat_b[i] = flat_n[i] / flat_d[i]
    return b


@njit(cache=True, parallel=True)
def lqg_gradient_samples(K, L, Pm, A, B, Q, R, key, N, H, gamma, bs, ba, clip, score_clipped,
                         reinforce_estimator, baseline):
    """Per-trajectory REINFORCE or G(PO)MDP samples (N, m*m) and discounted returns (N,).

    Pass 1 simulates each trajectory and accumulates, per chunk, the sums that make the
    variance-minimising baselines of Sections 2.3.9-2.3.10; a sample without baseline is
    sum_l G_l gamma^l r_l (G(PO)MDP) or S * ret (REINFORCE). Pass 2 subtracts the
    baseline term using the cumulative scores kept from pass 1.
    """
    m = K.shape[0]
    M = m * m
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.zeros((N, M))
    returns = np.empty(N)
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks, rows, M))
    den = np.zeros((n_chunks, rows, M))
    # What pass 2 needs: G_{n,l} for G(PO)MDP, the total score S_n for REINFORCE.
    kept = np.empty((N if baseline else 1, rows, M))
    for c in prange(n_chunks):
        s = np.empty(m)
        s_next = np.empty(m)
        mean = np.empty(m)
        a_raw = np.empty(m)
        u = np.empty(m)
        diff = np.empty(m)
        cum = np.empty(M)
        zt = np.empty(m)
        for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            state = stream_start(key, n)
            for i in range(m):
                v, state = next_uniform(state)
                s[i] = -bs + (bs + bs) * v
            for p in range(M):
                cum[p] = 0.0
            disc = 1.0
            ret = 0.0
            for t in range(H):
                for i in range(m):
                    zt[i], state = next_normal(state)
                for i in range(m):
                    acc = 0.0
                    for j in range(m):
                        acc += K[i, j] * s[j]
                    mean[i] = acc
                    acc = 0.0
                    for j in range(i + 1):
                        acc += L[i, j] * zt[j]
                    a_raw[i] = mean[i] + acc
                    u[i] = min(max(a_raw[i], -ba), ba) if clip else a_raw[i]
                cost = 0.0
                for i in range(m):
                    for j in range(m):
                        cost += s[i] * Q[i, j] * s[j] + u[i] * R[i, j] * u[j]
                dr = -0.5 * cost * disc
                ret += dr
                for i in range(m):
                    acc = 0.0
                    for j in range(m):
                        acc += Pm[i, j] * ((u[j] if score_clipped else a_raw[j]) - mean[j])
                    diff[i] = acc
                for i in range(m):
                    for j in range(m):
                        p = i * m + j
                        cum[p] += diff[i] * s[j]  # score of Section 2.3.13, summed over k <= t
                        if not reinforce_estimator:
                            g = cum[p]
                            samples[n, p] += g * dr
                            num[c, t, p] += g * g * dr
                            den[c, t, p] += g * g
                            if baseline:
                                kept[n, t, p] = g
                disc *= gamma
                for i in range(m):
                    acc = 0.0
                    for j in range(m):
                        acc += A[i, j] * s[j] + B[i, j] * u[j]
                    s_next[i] = min(max(acc, -bs), bs) if clip else acc
                for i in range(m):
                    s[i] = s_next[i]
            returns[n] = ret
            if reinforce_estimator:
                for p in range(M):
                    sq = cum[p] * cum[p]
                    num[c, 0, p] += sq * ret
                    den[c, 0, p] += sq
                    samples[n, p] = cum[p] * ret
                    if baseline:
                        kept[n, 0, p] = cum[p]
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
                for p in range(M):
                    acc = 0.0
                    for t in range(rows):
                        acc += kept[n, t, p] * b[t, p]
                    samples[n, p] -= acc
    return samples, returns


def serial(kernel):
    """The same kernel compiled without threads (``prange`` runs as ``range``): the same chunks
    in the same order, so the same bits, without the thread pool's start-up of a few
    microseconds per call, which a one-thread worker at N = 100 pays on every batch."""
    f = kernel.py_func
    g = types.FunctionType(f.__code__, f.__globals__, f.__name__ + "_serial", f.__defaults__, f.__closure__)
    g.__qualname__ = f.__qualname__ + "_serial"  # its own entry in numba's cache
    g.__doc__ = f"Serial :func:`{f.__name__}`."
    return njit(cache=True)(g)


lqg1d_gradient_samples_serial = serial(lqg1d_gradient_samples)
lqg2d_gradient_samples_serial = serial(lqg2d_gradient_samples)
lqg_gradient_samples_serial = serial(lqg_gradient_samples)
