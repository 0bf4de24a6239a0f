"""Fused LQG simulation + gradient-sample kernel (numba).

The reference path (``LQG.simulate`` then :mod:`safepg.estimators`) materialises
several (N, H, m) arrays and makes a dozen passes over them; this kernel makes one pass
per trajectory and gives the same numbers up to floating-point rounding (tested). The
random numbers are drawn by the caller from the same ``numpy.random.Generator`` in the
same order, so both paths see the same batch.

Trajectories are processed in fixed-size chunks in parallel; every chunk writes its own
partial sums and the chunks are reduced in order, so the result does not depend on the
number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

CHUNK = 2048


@njit(cache=True, parallel=True)
def lqg1d_gradient_samples(theta, sigma, A, B, Q, R, s0, z, gamma, bs, ba, clip, score_clipped,
                           reinforce_estimator, baseline):
    """Scalar (m = 1) version of :func:`lqg_gradient_samples`.

    Section 5.1's campaign is almost all scalar steps; with scalars in registers this
    runs about twice as fast as the matrix loops below at m = 1.
    """
    N, H = z.shape[0], z.shape[1]
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.empty((N, 1))
    returns = np.empty(N)
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks, rows))
    den = np.zeros((n_chunks, rows))
    kept = np.empty((N if baseline else 1, rows))
    inv_var = 1.0 / (sigma * sigma)
    for c in prange(n_chunks):
        for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            s = s0[n, 0]
            cum = 0.0
            acc = 0.0
            disc = 1.0
            ret = 0.0
            for t in range(H):
                mean = theta * s
                a_raw = mean + sigma * z[n, t, 0]
                u = min(max(a_raw, -ba), ba) if clip else a_raw
                dr = -0.5 * (Q * s * s + R * u * u) * disc
                ret += dr
                cum += ((u if score_clipped else a_raw) - mean) * s * inv_var
                if not reinforce_estimator:
                    acc += cum * dr
                    num[c, t] += cum * cum * dr
                    den[c, t] += cum * cum
                    if baseline:
                        kept[n, t] = cum
                disc *= gamma
                s = A * s + B * u
                if clip:
                    s = min(max(s, -bs), bs)
            returns[n] = ret
            if reinforce_estimator:
                num[c, 0] += cum * cum * ret
                den[c, 0] += cum * cum
                acc = cum * ret
                if baseline:
                    kept[n, 0] = cum
            samples[n, 0] = acc
    if baseline:
        b = _baseline(num, den)
        for c in prange(n_chunks):
            for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
                acc = 0.0
                for t in range(rows):
                    acc += kept[n, t] * b[t]
                samples[n, 0] -= acc
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
def lqg_gradient_samples(K, L, Pm, A, B, Q, R, s0, z, gamma, bs, ba, clip, score_clipped,
                         reinforce_estimator, baseline):
    """Per-trajectory REINFORCE or G(PO)MDP samples (N, m*m) and discounted returns (N,).

    Pass 1 simulates each trajectory and accumulates, per chunk, the sums that make the
    variance-minimising baselines of Sections 2.3.9-2.3.10; a sample without baseline is
    sum_l G_l gamma^l r_l (G(PO)MDP) or S * ret (REINFORCE). Pass 2 subtracts the
    baseline term using the cumulative scores kept from pass 1.
    """
    N, H, m = z.shape[0], z.shape[1], z.shape[2]
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
        for n in range(c * CHUNK, min(N, (c + 1) * CHUNK)):
            for i in range(m):
                s[i] = s0[n, i]
            for p in range(M):
                cum[p] = 0.0
            disc = 1.0
            ret = 0.0
            for t in range(H):
                for i in range(m):
                    acc = 0.0
                    for j in range(m):
                        acc += K[i, j] * s[j]
                    mean[i] = acc
                    acc = 0.0
                    for j in range(i + 1):
                        acc += L[i, j] * z[n, t, j]
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
