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

from safepg.streams import next_normal, next_uniform, stream_start

CHUNK = 2048


@njit(cache=True, parallel=True)
def lqg1d_gradient_samples(theta, sigma, A, B, Q, R, key, N, H, gamma, bs, ba, clip, score_clipped,
                           reinforce_estimator, baseline):
    """Scalar (m = 1) version of :func:`lqg_gradient_samples`.

    Section 5.1's campaign is almost all scalar steps; with scalars in registers this
    runs about twice as fast as the matrix loops below at m = 1. Within a chunk, time runs
    in the outer loop and the trajectories in the inner one, so that consecutive steps of
    different trajectories overlap (about 13% faster than following one trajectory at a
    time); every trajectory's operations and every sum's order over trajectories are those
    of following them one by one: the same bits.
    """
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.empty((N, 1))
    returns = np.empty(N)
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks, rows))
    den = np.zeros((n_chunks, rows))
    kept = np.empty((N if baseline else 1, rows))
    inv_var = 1.0 / (sigma * sigma)
    for c in prange(n_chunks):
        lo = c * CHUNK
        m = min(N, lo + CHUNK) - lo
        st = np.empty(m, dtype=np.uint64)  # each trajectory's stream
        s = np.empty(m)
        cum = np.zeros(m)
        acc = np.zeros(m)
        ret = np.zeros(m)
        for i in range(m):
            state = stream_start(key, lo + i)
            u0, st[i] = next_uniform(state)
            s[i] = -bs + (bs + bs) * u0  # uniform on [-bs, bs), as numpy's uniform(-bs, bs)
        disc = 1.0
        for t in range(H):
            for i in range(m):
                si = s[i]
                mean = theta * si
                zt, st[i] = next_normal(st[i])
                a_raw = mean + sigma * zt
                u = min(max(a_raw, -ba), ba) if clip else a_raw
                dr = -0.5 * (Q * si * si + R * u * u) * disc
                ret[i] += dr
                g = cum[i] + ((u if score_clipped else a_raw) - mean) * si * inv_var
                cum[i] = g
                if not reinforce_estimator:
                    acc[i] += g * dr
                    num[c, t] += g * g * dr
                    den[c, t] += g * g
                    if baseline:
                        kept[lo + i, t] = g
                s_next = A * si + B * u
                s[i] = min(max(s_next, -bs), bs) if clip else s_next
            disc *= gamma
        for i in range(m):
            n = lo + i
            returns[n] = ret[i]
            if reinforce_estimator:
                g = cum[i]
                num[c, 0] += g * g * ret[i]
                den[c, 0] += g * g
                acc[i] = g * ret[i]
                if baseline:
                    kept[n, 0] = g
            samples[n, 0] = acc[i]
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
                acc = 0.0
                for t in range(rows):
                    acc += kept[n, t] * b[t]
                samples[n, 0] -= acc
    return samples, returns


@njit(cache=True, parallel=True)
def lqg2d_gradient_samples(K, L, Pm, A, B, Q, R, key, N, H, gamma, bs, ba, clip, score_clipped,
                           reinforce_estimator, baseline):
    """Two-dimensional (m = 2) version of :func:`lqg_gradient_samples`.

    Same arguments, semantics and outputs (samples (N, 4), returns (N,)). Section 5.2's
    campaign is all m = 2 steps; the runtime-sized m x m loops of the generic kernel keep
    state, action, scores and sample sums in memory and index every matrix through its
    strides, which dominates at m = 2. Here the 2 x 2 algebra is unrolled: the matrices
    are read once into locals and the per-trajectory state (s, a, u, the four cumulative
    scores, the four sample sums) lives in registers. The only per-step memory traffic
    left is adding to the chunk's L1-resident baseline sums
    num/den[c, t, :] and, with a G(PO)MDP baseline, storing the four cumulative scores
    kept[n, t, :] contiguously (pass 2 needs them).

    Every sum is formed in the same order as in the generic kernel, so the two give the
    same bits (tested to 1e-12 relative); swapping kernels does not change a seeded run.
    That rules out regrouping the cost quadratic forms to save a few multiplies.
    Interleaving two trajectories, to overlap their serial state -> action -> state
    chains, measured no faster: the step is bound by scalar arithmetic, not latency.

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
    kept = np.empty((N if baseline else 1, rows, 4))
    k00, k01, k10, k11 = K[0, 0], K[0, 1], K[1, 0], K[1, 1]
    l00, l10, l11 = L[0, 0], L[1, 0], L[1, 1]
    p00, p01, p10, p11 = Pm[0, 0], Pm[0, 1], Pm[1, 0], Pm[1, 1]
    a00, a01, a10, a11 = A[0, 0], A[0, 1], A[1, 0], A[1, 1]
    b00, b01, b10, b11 = B[0, 0], B[0, 1], B[1, 0], B[1, 1]
    q00, q01, q10, q11 = Q[0, 0], Q[0, 1], Q[1, 0], Q[1, 1]
    r00, r01, r10, r11 = R[0, 0], R[0, 1], R[1, 0], R[1, 1]
    for c in prange(n_chunks):
        for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            state = stream_start(key, n)
            v0, state = next_uniform(state)
            v1, state = next_uniform(state)
            x0 = -bs + (bs + bs) * v0
            x1 = -bs + (bs + bs) * v1
            g00 = 0.0
            g01 = 0.0
            g10 = 0.0
            g11 = 0.0
            f00 = 0.0
            f01 = 0.0
            f10 = 0.0
            f11 = 0.0
            disc = 1.0
            ret = 0.0
            for t in range(H):
                m0 = k00 * x0 + k01 * x1
                m1 = k10 * x0 + k11 * x1
                z0, state = next_normal(state)
                z1, state = next_normal(state)
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
                ret += dr
                if score_clipped:
                    e0 = u0 - m0
                    e1 = u1 - m1
                else:
                    e0 = a0 - m0
                    e1 = a1 - m1
                d0 = p00 * e0 + p01 * e1
                d1 = p10 * e0 + p11 * e1
                g00 += d0 * x0  # score of Section 2.3.13, summed over k <= t
                g01 += d0 * x1
                g10 += d1 * x0
                g11 += d1 * x1
                if not reinforce_estimator:
                    f00 += g00 * dr
                    f01 += g01 * dr
                    f10 += g10 * dr
                    f11 += g11 * dr
                    h00 = g00 * g00
                    h01 = g01 * g01
                    h10 = g10 * g10
                    h11 = g11 * g11
                    num[c, t, 0] += h00 * dr
                    num[c, t, 1] += h01 * dr
                    num[c, t, 2] += h10 * dr
                    num[c, t, 3] += h11 * dr
                    den[c, t, 0] += h00
                    den[c, t, 1] += h01
                    den[c, t, 2] += h10
                    den[c, t, 3] += h11
                    if baseline:
                        kept[n, t, 0] = g00
                        kept[n, t, 1] = g01
                        kept[n, t, 2] = g10
                        kept[n, t, 3] = g11
                disc *= gamma
                y0 = (a00 * x0 + b00 * u0) + (a01 * x1 + b01 * u1)
                y1 = (a10 * x0 + b10 * u0) + (a11 * x1 + b11 * u1)
                if clip:
                    x0 = min(max(y0, -bs), bs)
                    x1 = min(max(y1, -bs), bs)
                else:
                    x0 = y0
                    x1 = y1
            returns[n] = ret
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
                f00 = g00 * ret
                f01 = g01 * ret
                f10 = g10 * ret
                f11 = g11 * ret
                if baseline:
                    kept[n, 0, 0] = g00
                    kept[n, 0, 1] = g01
                    kept[n, 0, 2] = g10
                    kept[n, 0, 3] = g11
            samples[n, 0] = f00
            samples[n, 1] = f01
            samples[n, 2] = f10
            samples[n, 3] = f11
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
                c0 = 0.0
                c1 = 0.0
                c2 = 0.0
                c3 = 0.0
                for t in range(rows):
                    c0 += kept[n, t, 0] * b[t, 0]
                    c1 += kept[n, t, 1] * b[t, 1]
                    c2 += kept[n, t, 2] * b[t, 2]
                    c3 += kept[n, t, 3] * b[t, 3]
                samples[n, 0] -= c0
                samples[n, 1] -= c1
                samples[n, 2] -= c2
                samples[n, 3] -= c3
    return samples, returns


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
