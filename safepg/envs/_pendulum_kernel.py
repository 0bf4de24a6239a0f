r"""Fused pendulum simulation + gradient-sample kernel (numba).

The reference path (``Pendulum.simulate`` then :mod:`safepg.estimators`) materialises (N, H, 3)
arrays and makes a dozen passes over them; this kernel makes one pass and gives the same numbers
up to floating-point rounding (tested). Each trajectory draws its start and its action noise
inside the loop from its own counter-based stream (:mod:`safepg.streams`); the reference path
reads the same streams, so both paths see the same batch.

Every episode lasts H steps (the pendulum has no terminal state). Within a chunk of
trajectories time runs outside and the chunk's trajectories inside, in three loops per step:
the normals of the whole chunk (:func:`safepg.streams.draw_normals`), the sines and cosines of
its angles (:func:`safepg.portable.sincos`, branch-free, so the loop vectorises), and the policy,
reward, score and dynamics. The reward's normalised angle takes a floating-point remainder (an
``fmod`` per step, which no vector unit has); it stays in the last loop.

G(PO)MDP's variance-minimising baseline :math:`b_t` needs every trajectory's step t. As in
:mod:`safepg.envs._cartpole_kernel`, time then runs outside over the whole batch: once every
chunk has made step t, :math:`b_t` is formed from the chunks' sums (added in chunk order) and
each trajectory adds :math:`G_{n,t} b_t` in the same pass. Every sum runs in a fixed order, so
the result does not depend on the number of threads.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit, prange

from safepg import portable
from safepg.envs._lqg_kernel import serial
from safepg.streams import draw_normals, next_uniform, normal_scratch, stream_start

#: Trajectories per chunk: fixed (not per thread), so the reduction order, and every bit of the
#: result, is the same for any thread count; a chunk's rows (about 80 kB) stay in the L2 cache.
CHUNK = 512
# A chunk's quantities in one flat array of rows, trajectory j at row + j: one array with constant
# distances between its rows lets the compiler prove they do not overlap and vectorise. The rows
# are 64 bytes more than a multiple of 4 KiB apart, so a trajectory's entries do not share a
# cache set (4K aliasing).
ROW = CHUNK + 8
TH, THD = 0 * ROW, 1 * ROW  # the state: angle and speed
G0, G1, G2 = 2 * ROW, 3 * ROW, 4 * ROW  # the cumulative score G_t
A0, A1, A2 = 5 * ROW, 6 * ROW, 7 * ROW  # sum_t G_t gamma^t r_t (G(PO)MDP's sample without baseline)
B0, B1, B2 = 8 * ROW, 9 * ROW, 10 * ROW  # sum_t G_t b_t (G(PO)MDP's baseline term)
RD, RU = 11 * ROW, 12 * ROW  # the discounted and the undiscounted return
PR, PF = 13 * ROW, 14 * ROW  # the largest |r_t| and |phi_i(s_t)| so far
Z, DR = 15 * ROW, 16 * ROW  # this step's standard normals, and gamma^t r_t
SIN, COS = 17 * ROW, 18 * ROW  # sine and cosine of this step's angles
ROWS = 19
_PI = math.pi
_TWO_PI = 2 * math.pi


@njit(cache=True)
def _start_chunk(lo, m, key, init_angle, init_speed, S, st):
    """Trajectories lo..lo+m-1: their starts (two uniforms each, gymnasium's ``low + (high - low) u``)
    and streams; every sum row at 0."""
    for r in range(G0 // ROW, ROWS):
        S[r * ROW:r * ROW + m] = 0.0
    wa, ws = init_angle + init_angle, init_speed + init_speed
    for i in range(m):
        state = stream_start(key, lo + i)
        v0, state = next_uniform(state)
        v1, st[i] = next_uniform(state)
        S[TH + i] = -init_angle + wa * v0
        S[THD + i] = -init_speed + ws * v1


@njit(cache=True, error_model="numpy")
def _advance(m, S, k0, k1, k2, sigma, inv_var, score_clipped, max_torque, disc, gravity_term, torque_term, dt,
             max_speed):
    """Step t of the chunk's m trajectories: action, reward, score, G(PO)MDP's sums, peaks, dynamics.

    gymnasium's operations in gymnasium's order: the reward of the state the step starts from,
    ``-(norm(th)**2 + 0.1 * thdot**2 + 0.001 * u**2)``, then ``thdot + (3g/(2l) sin th + 3/(m l^2) u) dt``
    clipped to the speed limit, then ``th + thdot' dt``.
    """
    for j in range(m):
        th, w = S[TH + j], S[THD + j]
        s, c = S[SIN + j], S[COS + j]
        mean = k0 * c + k1 * s + k2 * w
        a_raw = mean + sigma * S[Z + j]
        u = min(max(a_raw, -max_torque), max_torque)
        na = (th + _PI) % _TWO_PI - _PI  # Python's float remainder: numba's %, NumPy's, gymnasium's
        r = -((na * na + 0.1 * (w * w)) + 0.001 * (u * u))
        dr = r * disc
        S[DR + j] = dr
        S[RD + j] += dr
        S[RU + j] += r
        d = ((u if score_clipped else a_raw) - mean) * inv_var
        g0 = S[G0 + j] + d * c
        g1 = S[G1 + j] + d * s
        g2 = S[G2 + j] + d * w
        S[G0 + j], S[G1 + j], S[G2 + j] = g0, g1, g2
        S[A0 + j] += g0 * dr
        S[A1 + j] += g1 * dr
        S[A2 + j] += g2 * dr
        S[PR + j] = max(S[PR + j], abs(r))
        S[PF + j] = max(S[PF + j], max(max(abs(c), abs(s)), abs(w)))
        speed = w + (gravity_term * s + torque_term * u) * dt
        speed = min(max(speed, -max_speed), max_speed)
        S[TH + j] = th + speed * dt
        S[THD + j] = speed


@njit(cache=True)
def _step_chunk(m, S, st, scratch, k0, k1, k2, sigma, inv_var, score_clipped, max_torque, disc, gravity_term,
                torque_term, dt, max_speed, sums, num, den):
    """One step of a chunk: its normals, its sines and cosines (a vectorised loop), the step, and with
    ``sums`` the chunk's baseline sums of the step, ``num`` = sum_j G_j^2 gamma^t r_j and ``den`` =
    sum_j G_j^2, in index order."""
    draw_normals(st, S[Z:Z + m], scratch)
    for j in range(m):
        S[SIN + j], S[COS + j] = portable.sincos(S[TH + j])
    _advance(m, S, k0, k1, k2, sigma, inv_var, score_clipped, max_torque, disc, gravity_term, torque_term, dt,
             max_speed)
    if sums:
        n0 = n1 = n2 = 0.0
        d0 = d1 = d2 = 0.0
        for j in range(m):
            c0, c1, c2, dr = S[G0 + j], S[G1 + j], S[G2 + j], S[DR + j]
            n0 += c0 * c0 * dr
            n1 += c1 * c1 * dr
            n2 += c2 * c2 * dr
            d0 += c0 * c0
            d1 += c1 * c1
            d2 += c2 * c2
        num[0], num[1], num[2] = n0, n1, n2
        den[0], den[1], den[2] = d0, d1, d2


@njit(cache=True)
def _add_baseline_term(m, S, b0, b1, b2):
    """B += G_t b_t for the chunk's trajectories, one loop per component (each vectorises)."""
    for j in range(m):
        S[B0 + j] += S[G0 + j] * b0
    for j in range(m):
        S[B1 + j] += S[G1 + j] * b1
    for j in range(m):
        S[B2 + j] += S[G2 + j] * b2


@njit(cache=True)
def _baseline_row(num, den, b):
    """b = sum_c num_c / sum_c den_c (0 where the denominator is 0), the chunks in order. Serial, in a
    function of its own: inside the parallel kernel every loop here would become a parallel region."""
    for p in range(3):
        nb = 0.0
        db = 0.0
        for c in range(num.shape[0]):
            nb += num[c, p]
            db += den[c, p]
        b[p] = nb / db if db != 0.0 else 0.0


def pendulum_gradient_samples(K: np.ndarray, sigma: float, gravity_term: float, torque_term: float, dt: float,
                              max_speed: float, max_torque: float, init_angle: float, init_speed: float,
                              key: np.uint64, n: int, horizon: int, gamma: float, score_clipped: bool,
                              reinforce_estimator: bool, baseline: bool) -> tuple[np.ndarray, ...]:
    """Per-trajectory REINFORCE or G(PO)MDP samples (N, 3), returns and peaks of a fresh batch.

    Parameters
    ----------
    K : ndarray, shape (3,)
        Policy gain on (cos th, sin th, thdot); the action is ``K @ phi + sigma * z``.
    sigma : float
        Action standard deviation.
    gravity_term, torque_term : float
        3 g / (2 l) and 3 / (m l^2) of the speed's update.
    dt, max_speed, max_torque : float
        Time step, speed limit and torque limit.
    init_angle, init_speed : float
        The start is uniform in [-init_angle, init_angle) x [-init_speed, init_speed).
    key : uint64
        The batch's key (:func:`safepg.streams.batch_key`): trajectory i draws two uniforms (its
        start), then one standard normal per step, from stream i of this key.
    n, horizon : int
        Batch size N and horizon H.
    gamma : float
        Discount of the estimators and of the discounted return.
    score_clipped, reinforce_estimator, baseline : bool
        Score the applied (clipped) torque instead of the sampled action; REINFORCE instead of
        G(PO)MDP; subtract the variance-minimising baseline.

    Returns
    -------
    samples : ndarray, shape (N, 3)
        Gradient samples, as ``gradient_samples`` on the simulated batch.
    discounted, undiscounted : ndarray, shape (N,)
        Each episode's discounted return and its sum of rewards.
    peak_reward, peak_feature : ndarray, shape (N,)
        Each episode's largest |r_t| and |phi_i(s_t)| over its H steps.
    """
    # One compiled specialisation: a fresh, writable float64 gain and plain Python scalars.
    K = np.array(K, dtype=np.float64).reshape(3)
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n}")
    if int(horizon) != horizon or horizon < 1:
        raise ValueError(f"horizon must be a positive integer, got {horizon}")
    fused = _fused_serial if n <= CHUNK or numba.get_num_threads() == 1 else _fused  # the same numbers
    out: tuple[np.ndarray, ...] = fused(
        K, float(sigma), float(gravity_term), float(torque_term), float(dt), float(max_speed), float(max_torque),
        float(init_angle), float(init_speed), np.uint64(key), int(n), int(horizon), float(gamma),
        bool(score_clipped), bool(reinforce_estimator), bool(baseline))
    return out


@njit(cache=True, parallel=True)
def _fused(K, sigma, gravity_term, torque_term, dt, max_speed, max_torque, init_angle, init_speed, key, N, H, gamma,
           score_clipped, reinforce_estimator, baseline):
    """:func:`pendulum_gradient_samples` on normalised arguments."""
    n_chunks = (N + CHUNK - 1) // CHUNK
    k0, k1, k2 = K[0], K[1], K[2]
    inv_var = 1.0 / (sigma * sigma)
    disc = np.empty(H)  # gamma^t as the running product (safepg.portable.powers)
    p = 1.0
    for t in range(H):
        disc[t] = p
        p = p * gamma
    S = np.empty((n_chunks, ROWS * ROW))
    st = np.empty((n_chunks, CHUNK), dtype=np.uint64)
    scratch = [normal_scratch(CHUNK) for _ in range(n_chunks)]
    size = np.empty(n_chunks, dtype=np.intp)
    num = np.zeros((n_chunks, 3))
    den = np.zeros((n_chunks, 3))
    b = np.zeros(3)
    gpomdp_baseline = baseline and not reinforce_estimator
    for c in prange(n_chunks):
        size[c] = min(N, (c + 1) * CHUNK) - c * CHUNK
        _start_chunk(c * CHUNK, size[c], key, init_angle, init_speed, S[c], st[c])
    if gpomdp_baseline:
        # One parallel region per step: B += G_{t-1} b_{t-1} (b_{t-1} needs every chunk's step t - 1),
        # then step t.
        for t in range(H + 1):
            if t > 0:
                _baseline_row(num, den, b)
            b0, b1, b2 = b[0], b[1], b[2]
            for c in prange(n_chunks):
                if t > 0:
                    _add_baseline_term(size[c], S[c], b0, b1, b2)
                if t < H:
                    _step_chunk(size[c], S[c], st[c], scratch[c], k0, k1, k2, sigma, inv_var, score_clipped,
                                max_torque, disc[t], gravity_term, torque_term, dt, max_speed, gpomdp_baseline,
                                num[c], den[c])
    else:
        # Without G(PO)MDP's baseline the chunks do not wait for each other: each runs its whole time
        # loop while its rows stay in the cache. (The flag passed is gpomdp_baseline, not the literal
        # False: numba would compile _step_chunk once per literal.)
        for c in prange(n_chunks):
            for t in range(H):
                _step_chunk(size[c], S[c], st[c], scratch[c], k0, k1, k2, sigma, inv_var, score_clipped,
                            max_torque, disc[t], gravity_term, torque_term, dt, max_speed, gpomdp_baseline,
                            num[c], den[c])
    samples = np.empty((N, 3))
    discounted = np.empty(N)
    undiscounted = np.empty(N)
    peak_reward = np.empty(N)
    peak_feature = np.empty(N)
    for c in prange(n_chunks):
        T = S[c]
        for j in range(size[c]):
            n = c * CHUNK + j
            discounted[n] = T[RD + j]
            undiscounted[n] = T[RU + j]
            peak_reward[n] = T[PR + j]
            peak_feature[n] = T[PF + j]
            if reinforce_estimator:  # G_H times the return; the baseline comes below
                for q in range(3):
                    samples[n, q] = T[G0 + q * ROW + j] * T[RD + j]
            elif gpomdp_baseline:
                for q in range(3):
                    samples[n, q] = T[A0 + q * ROW + j] - T[B0 + q * ROW + j]
            else:
                for q in range(3):
                    samples[n, q] = T[A0 + q * ROW + j]
    if reinforce_estimator and baseline:
        # b = sum_n G_n^2 R_n / sum_n G_n^2, each chunk in index order, the chunks in order; then
        # G (R - b), the reference's order.
        for c in prange(n_chunks):
            T = S[c]
            for q in range(3):
                nq = 0.0
                dq = 0.0
                for j in range(size[c]):
                    g = T[G0 + q * ROW + j]
                    nq += g * g * T[RD + j]
                    dq += g * g
                num[c, q] = nq
                den[c, q] = dq
        _baseline_row(num, den, b)
        for c in prange(n_chunks):
            T = S[c]
            for j in range(size[c]):
                n = c * CHUNK + j
                for q in range(3):
                    samples[n, q] = T[G0 + q * ROW + j] * (T[RD + j] - b[q])
    return samples, discounted, undiscounted, peak_reward, peak_feature


_fused_serial = serial(_fused)
