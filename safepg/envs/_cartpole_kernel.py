r"""Fused cart-pole simulation + gradient-sample kernel (numba).

The reference path (``CartPole.simulate`` then :mod:`safepg.estimators`) steps every
cart for as long as *any* cart is alive and then makes a dozen passes over (N, H, 4)
arrays, most of whose entries are the zeros of dead steps. This kernel steps only the
live trajectories, each until its last step, and gives the same numbers up to
floating-point rounding (tested). Each trajectory draws its initial state and its action
noise inside the loop from its own counter-based stream (:mod:`safepg.streams`), as many
normals as it lives steps; the reference path reads the same streams, so both paths see
the same batch.

Two things need care when the time loop stops early:

- After termination the score is zero but the *cumulative* score of G(PO)MDP is not: it
  stays at its final value, and the reference baseline's denominator
  :math:`\sum_n G_{n,l}^2` counts it at every dead step l. Each chunk therefore records
  the final :math:`G^2` of trajectories that ended at step T, and the denominators get
  their running sum over T <= l.
- The baseline term :math:`\sum_l G_{n,l} b_l` of a sample: the dead steps contribute
  :math:`G_{n,T_n} \sum_{l \ge T_n} b_l`, one suffix sum. The live steps' terms need
  :math:`b_l`, which depends on every trajectory's step l. With G(PO)MDP's baseline, time
  therefore runs outside, over the whole batch: once every chunk has made step l, its
  :math:`b_l` is formed and each live trajectory adds :math:`G_{n,l} b_l`, in one pass,
  with the terms and the order of a second pass over the trajectories.

As in :mod:`safepg.envs._lqg_kernel`, trajectories are processed in fixed-size chunks in
parallel; every chunk writes its own partial sums and the chunks are reduced in order,
so the result does not depend on the number of threads.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange

from safepg import portable
from safepg.envs._lqg_kernel import serial
from safepg.streams import draw_normals, next_uniform, normal_scratch, stream_start

#: Trajectories per chunk. Fixed (not per thread) so the reduction order, and hence every
#: bit of the result, is the same for any thread count; small enough that N = 4000 still
#: spreads over a few threads, large enough that the per-chunk (H, 4) sums stay small.
CHUNK = 512


# error_model="numpy": a float division by zero gives inf or nan, as NumPy's reference path
# does, instead of raising; without that test in the loop the compiler can vectorise it.
@njit(cache=True, error_model="numpy")
def _euler(x, x_dot, beta, beta_dot, sin, cos, force, half, ml, total, pole_mass, gravity, tau):
    """One explicit-Euler step; the same operations in the same order as ``step_dynamics``."""
    push = (force + ml * beta_dot * beta_dot * sin) / total
    beta_acc = (gravity * sin - cos * push) / (half * (4.0 / 3.0 - pole_mass * cos * cos / total))
    x_acc = push - ml * beta_acc * cos / total
    return x + tau * x_dot, x_dot + tau * x_acc, beta + tau * beta_dot, beta_dot + tau * beta_acc


@njit(cache=True, error_model="numpy")
def _semi_implicit(x, x_dot, beta, beta_dot, sin, cos, force, half, ml, total, pole_mass, gravity, tau):
    """One semi-implicit Euler step (velocities first, positions with the new velocities), the
    same operations as ``step_dynamics(..., integrator="semi-implicit")``."""
    push = (force + ml * beta_dot * beta_dot * sin) / total
    beta_acc = (gravity * sin - cos * push) / (half * (4.0 / 3.0 - pole_mass * cos * cos / total))
    x_acc = push - ml * beta_acc * cos / total
    x_dot_new = x_dot + tau * x_acc
    beta_dot_new = beta_dot + tau * beta_acc
    return x + tau * x_dot_new, x_dot_new, beta + tau * beta_dot_new, beta_dot_new


@njit(cache=True)
def _initial_state(key, n, init_bound):
    """Trajectory n's initial state, uniform on [-init_bound, init_bound)^4, and its stream."""
    state = stream_start(key, n)
    width = init_bound + init_bound
    v0, state = next_uniform(state)
    v1, state = next_uniform(state)
    v2, state = next_uniform(state)
    v3, state = next_uniform(state)
    return (-init_bound + width * v0, -init_bound + width * v1, -init_bound + width * v2,
            -init_bound + width * v3, state)


# The packed state of a chunk's live trajectories: one flat array of rows, packed trajectory j
# at offset row + j. One array with constant distances between its rows lets the compiler
# prove that the rows do not overlap, which it cannot for separate arrays; it then
# vectorises the step without run-time overlap tests. The rows are 64 bytes more than 4 KiB
# apart: at exactly 4 KiB the 17 entries of a trajectory would share one L1 cache set, and
# loads would wait on unrelated stores (4K aliasing), which made a step 4 times slower.
ROW = CHUNK + 8
X, X_DOT, BETA, BETA_DOT = 0 * ROW, 1 * ROW, 2 * ROW, 3 * ROW  # the state s
G0, G1, G2, G3 = 4 * ROW, 5 * ROW, 6 * ROW, 7 * ROW  # the cumulative score G_t
A0, A1, A2, A3 = 8 * ROW, 9 * ROW, 10 * ROW, 11 * ROW  # sum_t G_t gamma^t (G(PO)MDP's sample)
P0, P1, P2, P3 = 12 * ROW, 13 * ROW, 14 * ROW, 15 * ROW  # max |s| so far
B0, B1, B2, B3 = 16 * ROW, 17 * ROW, 18 * ROW, 19 * ROW  # sum_t G_t b_t (G(PO)MDP's baseline term)
PACKED = 20  # the rows above follow their trajectory when the pack closes up
Z = 20 * ROW  # this step's standard normals
SIN, COS = 21 * ROW, 22 * ROW  # sine and cosine of this step's angles
ROWS = 23


@njit(cache=True, error_model="numpy")
def _advance(n, S, alive, K, sigma, inv_var, score_clipped, action_bound, w0, w1, w2, w3, consts, x_threshold,
             angle_threshold, semi_implicit):
    """One step of the n packed trajectories: action, score, dynamics, peaks, and whether each
    lives on (``alive``); returns how many ended."""
    half, ml, total, pole_mass, gravity, tau = consts
    k0, k1, k2, k3 = K[0], K[1], K[2], K[3]
    # portable.sin/cos, not libm's: libm's last bit depends on the CPU (safepg.portable).
    # Every live angle is within the threshold; below 0.78 rad they are their polynomials
    # alone (the reduction is the identity there), with no branch, so this loop vectorises.
    if angle_threshold < 0.78:
        for j in range(n):
            S[SIN + j] = portable.sin_poly(S[BETA + j])
            S[COS + j] = portable.cos_poly(S[BETA + j])
    else:
        for j in range(n):
            S[SIN + j] = portable.sin(S[BETA + j])
            S[COS + j] = portable.cos(S[BETA + j])
    n_ended = 0
    for j in range(n):
        s0, s1, s2, s3 = S[X + j], S[X_DOT + j], S[BETA + j], S[BETA_DOT + j]
        mean = k0 * s0 + k1 * s1 + k2 * s2 + k3 * s3
        a_raw = mean + sigma * S[Z + j]
        u = min(max(a_raw, -action_bound), action_bound)
        d = ((u if score_clipped else a_raw) - mean) * inv_var
        c0 = S[G0 + j] + d * s0
        c1 = S[G1 + j] + d * s1
        c2 = S[G2 + j] + d * s2
        c3 = S[G3 + j] + d * s3
        S[G0 + j], S[G1 + j], S[G2 + j], S[G3 + j] = c0, c1, c2, c3
        S[A0 + j] += c0 * w0
        S[A1 + j] += c1 * w1
        S[A2 + j] += c2 * w2
        S[A3 + j] += c3 * w3
        sin, cos = S[SIN + j], S[COS + j]
        if semi_implicit:
            s0, s1, s2, s3 = _semi_implicit(s0, s1, s2, s3, sin, cos, u, half, ml, total, pole_mass, gravity, tau)
        else:
            s0, s1, s2, s3 = _euler(s0, s1, s2, s3, sin, cos, u, half, ml, total, pole_mass, gravity, tau)
        S[X + j], S[X_DOT + j], S[BETA + j], S[BETA_DOT + j] = s0, s1, s2, s3
        S[P0 + j] = max(S[P0 + j], abs(s0))
        S[P1 + j] = max(S[P1 + j], abs(s1))
        S[P2 + j] = max(S[P2 + j], abs(s2))
        S[P3 + j] = max(S[P3 + j], abs(s3))
        # "not <=" so that a NaN state also ends the episode, as in CartPole.alive.
        ok = abs(s0) <= x_threshold and abs(s2) <= angle_threshold
        alive[j] = ok
        n_ended += not ok
    return n_ended


@njit(cache=True)
def _start_chunk(lo, m, key, init_bound, S, idx, st):
    """Pack trajectories lo..lo+m-1 of the batch into a chunk's rows: initial states, peaks, streams."""
    for i in range(m):
        S[X + i], S[X_DOT + i], S[BETA + i], S[BETA_DOT + i], st[i] = _initial_state(key, lo + i, init_bound)
        for r in range(4):
            S[P0 + r * ROW + i] = abs(S[X + r * ROW + i])
        idx[i] = i


@njit(cache=True)
def _step_chunk(n, S, st, scratch, alive, K, sigma, inv_var, score_clipped, action_bound, w, consts, x_threshold,
                angle_threshold, semi_implicit, dt, sums, num, den):
    """Step t of a chunk's n live trajectories: the normals (:func:`safepg.streams.draw_normals`),
    the step (:func:`_advance`, A += G_t w), and with ``sums`` the chunk's baseline sums of the
    step, ``num`` = sum_j G_j^2 dt and ``den`` = sum_j G_j^2; returns how many ended."""
    draw_normals(st, S[Z:Z + n], scratch)
    n_ended = _advance(n, S, alive, K, sigma, inv_var, score_clipped, action_bound, w, w, w, w, consts, x_threshold,
                       angle_threshold, semi_implicit)
    if sums:
        for p in range(4):
            num[p] = 0.0
            den[p] = 0.0
        _sums(n, S, dt, num, den)
    return n_ended


@njit(cache=True)
def _baseline_row(t, num, den, ended, dead, b):
    """b_t = num_t / den_t (0 where den_t = 0) as soon as every chunk has made step t: the
    chunks' sums added in chunk order, and den_t with the final G^2 of every trajectory
    already ended (``dead``, their running sum). Serial, in its own function: inside the
    parallel kernel every loop here would become a parallel region of its own."""
    for p in range(4):
        nb = 0.0
        db = 0.0
        for c in range(num.shape[0]):
            nb += num[c, p]
            db += den[c, p]
        for c in range(num.shape[0]):
            dead[p] += ended[c, t, p]
        db += dead[p]
        b[t, p] = nb / db if db != 0.0 else 0.0


@njit(cache=True)
def _reinforce_baseline(num, den):
    """REINFORCE's b = sum_c num_c / sum_c den_c (0 where the denominator is 0), the chunks in
    order (num, den: (chunks, 1, 4))."""
    b = np.zeros(4)
    for p in range(4):
        nb = 0.0
        db = 0.0
        for c in range(num.shape[0]):
            nb += num[c, 0, p]
            db += den[c, 0, p]
        if db != 0.0:
            b[p] = nb / db
    return b


@njit(cache=True)
def _close_step(lo, n, n_ended, t, H, S, idx, st, alive, gpomdp_baseline, b, ended, out_a, out_b, out_g, lengths,
                peak):
    """After step t of a chunk: with G(PO)MDP's baseline, B += G_t b_t; the trajectories that
    ended write their results (and their final G^2 to ``ended``) and leave the pack, which
    closes up in index order. Returns the number still alive."""
    if gpomdp_baseline:
        # One loop per component, at constant offsets: the compiler vectorises these, not one
        # loop at the offset p * ROW.
        b0, b1, b2, b3 = b[t, 0], b[t, 1], b[t, 2], b[t, 3]
        for j in range(n):
            S[B0 + j] += S[G0 + j] * b0
        for j in range(n):
            S[B1 + j] += S[G1 + j] * b1
        for j in range(n):
            S[B2 + j] += S[G2 + j] * b2
        for j in range(n):
            S[B3 + j] += S[G3 + j] * b3
    if n_ended == 0:
        return n
    rows = PACKED if gpomdp_baseline else B0 // ROW  # the B rows only matter with the baseline
    kept = 0
    for j in range(n):
        if not alive[j]:
            _finish(lo + idx[j], t + 1, S, j, out_a, out_b, out_g, lengths, peak)
            if gpomdp_baseline and t + 1 < H:
                for p in range(4):
                    g = S[G0 + p * ROW + j]
                    ended[t + 1, p] += g * g
            continue
        if kept != j:
            idx[kept], st[kept] = idx[j], st[j]
            for r in range(rows):
                S[r * ROW + kept] = S[r * ROW + j]
        kept += 1
    return kept


@njit(cache=True)
def _sums(n, S, dt, num, den):
    """num += sum_j G_j^2 dt and den += sum_j G_j^2 over the n packed trajectories, added in
    index order (the reference path's order, so the same bits), in registers."""
    n0, n1, n2, n3 = num[0], num[1], num[2], num[3]
    d0, d1, d2, d3 = den[0], den[1], den[2], den[3]
    for j in range(n):
        c0, c1, c2, c3 = S[G0 + j], S[G1 + j], S[G2 + j], S[G3 + j]
        n0 += c0 * c0 * dt
        n1 += c1 * c1 * dt
        n2 += c2 * c2 * dt
        n3 += c3 * c3 * dt
        d0 += c0 * c0
        d1 += c1 * c1
        d2 += c2 * c2
        d3 += c3 * c3
    num[0], num[1], num[2], num[3] = n0, n1, n2, n3
    den[0], den[1], den[2], den[3] = d0, d1, d2, d3


@njit(cache=True)
def _finish(n, T, S, j, out_a, out_b, out_g, lengths, peak):
    """Write the results of trajectory n, packed at j, which ended after T steps."""
    for p in range(4):
        out_a[n, p] = S[A0 + p * ROW + j]
        out_b[n, p] = S[B0 + p * ROW + j]
        out_g[n, p] = S[G0 + p * ROW + j]
        peak[n, p] = S[P0 + p * ROW + j]
    lengths[n] = T


def cartpole_gradient_samples(K: np.ndarray, sigma: float, pole_length: float, cart_mass: float,
                              pole_mass: float, gravity: float, tau: float, key: np.uint64, n: int,
                              horizon: int, init_bound: float, gamma: float, action_bound: float,
                              x_threshold: float, angle_threshold: float,
                              score_clipped: bool, reinforce_estimator: bool,
                              baseline: bool, semi_implicit: bool = False, polemass_length: float | None = None,
                              peaks: bool = False) -> tuple[np.ndarray, ...]:
    """Per-trajectory REINFORCE or G(PO)MDP samples (N, 4) and episode lengths (N,).

    Parameters
    ----------
    K : ndarray, shape (4,)
        Policy gain; the action is ``K @ s + sigma * z``.
    sigma : float
        Action standard deviation.
    pole_length, cart_mass, pole_mass, gravity, tau : float
        Physical constants (whole pole length, as in :class:`CartPole`).
    key : uint64
        The batch's key (:func:`safepg.streams.batch_key`): trajectory i draws its initial
        state (4 uniforms on [-init_bound, init_bound)) and then one standard normal per
        step it lives from stream i of this key.
    n, horizon : int
        Batch size N and horizon H.
    init_bound : float
        Half-width of the initial-state box.
    gamma : float
        Discount factor of the estimators.
    action_bound, x_threshold, angle_threshold : float
        Force clip A-bar, termination |x| and |beta| (radians).
    score_clipped, reinforce_estimator, baseline : bool
        Score the clipped (applied) action instead of the sampled one; REINFORCE instead
        of G(PO)MDP; subtract the variance-minimising baseline.
    semi_implicit : bool
        Integrate with the semi-implicit Euler scheme instead of the explicit one (default).
    polemass_length : float or None
        m l of the pole's momentum terms; None: ``pole_mass * pole_length / 2`` (see
        :func:`safepg.envs.cartpole.step_dynamics`).
    peaks : bool
        Also return each trajectory's largest |state component|.

    Returns
    -------
    samples : ndarray, shape (N, 4)
        Gradient samples, as ``gradient_samples`` on the simulated batch.
    lengths : ndarray, shape (N,)
        Episode lengths (float), i.e. the undiscounted returns (reward 1 per live step).
    peak : ndarray, shape (N, 4)
        Only with ``peaks=True``: max |s_i| over the states of each trajectory, from the initial
        state to the last one reached (the failing state, or s_H), component by component.
    """
    # One compiled specialisation only: numba compiles again (about 10 s) for every new
    # combination of argument types, e.g. an int constant, a numpy bool flag or a read-only
    # array (a policy's gain): K is always a fresh, writable copy.
    K = np.array(K, dtype=np.float64).reshape(4)
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n}")
    if int(horizon) != horizon or horizon < 1:
        raise ValueError(f"horizon must be a positive integer, got {horizon}")
    half = 0.5 * float(pole_length)
    # pole_mass * half is the product the consistent equations form first: the same bits.
    ml = float(pole_mass) * half if polemass_length is None else float(polemass_length)
    fused = _fused_serial if n <= CHUNK or numba.get_num_threads() == 1 else _fused  # the same numbers
    samples, lengths, peak = fused(K, float(sigma), half, ml, float(cart_mass), float(pole_mass), float(gravity),
                                    float(tau), np.uint64(key), int(n), int(horizon), float(init_bound),
                                    float(gamma), float(action_bound), float(x_threshold),
                                    float(angle_threshold), bool(score_clipped), bool(reinforce_estimator),
                                    bool(baseline), bool(semi_implicit))
    return (samples, lengths, peak) if peaks else (samples, lengths)


@njit(cache=True, parallel=True)
def _fused(K, sigma, half, ml, cart_mass, pole_mass, gravity, tau, key, N, H, init_bound, gamma, action_bound,
           x_threshold, angle_threshold, score_clipped, reinforce_estimator, baseline, semi_implicit):
    r""":func:`cartpole_gradient_samples` on normalised arguments.

    Time runs in the outer loop over the whole batch and the chunks in parallel inside it, so
    that G(PO)MDP's baseline :math:`b_t` is known as soon as every chunk has made step t:
    :math:`\sum_t G_{n,t} b_t` then accumulates in the same pass, with the same terms in the
    same order as a second pass over the trajectories would add them.
    """
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.empty((N, 4))
    a = np.empty((N, 4))  # sum_{t<T} G_t b_t (G(PO)MDP with its baseline)
    last_g = np.empty((N, 4))
    lengths = np.empty(N)
    peak = np.empty((N, 4))
    gpomdp_baseline = baseline and not reinforce_estimator
    disc = np.empty(H + 1)  # gamma^t as the running product
    disc[0] = 1.0
    for t in range(H):
        disc[t + 1] = disc[t] * gamma
    inv_var = 1.0 / (sigma * sigma)
    consts = (half, ml, cart_mass + pole_mass, pole_mass, gravity, tau)
    S = np.zeros((n_chunks, ROWS * ROW))  # every chunk's packed rows
    idx = np.empty((n_chunks, CHUNK), dtype=np.intp)
    st = np.empty((n_chunks, CHUNK), dtype=np.uint64)
    scratch = [normal_scratch(CHUNK) for _ in range(n_chunks)]  # draw_normals' space, a chunk each
    alive = np.empty((n_chunks, CHUNK), dtype=np.bool_)
    n_live = np.empty(n_chunks, dtype=np.intp)
    n_ended = np.zeros(n_chunks, dtype=np.intp)
    num = np.zeros((n_chunks, 4))  # each chunk's baseline sums of the current step
    den = np.zeros((n_chunks, 4))
    # Final G^2 of the trajectories of each chunk that ended at step T < H (index T): after its
    # end a trajectory's G stays in the denominators (module docstring).
    ended = np.zeros((n_chunks, H + 1, 4))
    dead = np.zeros(4)
    b = np.zeros((H, 4))
    for c in prange(n_chunks):
        n_live[c] = min(N, (c + 1) * CHUNK) - c * CHUNK
        _start_chunk(c * CHUNK, n_live[c], key, init_bound, S[c], idx[c], st[c])
    # The flags below are gpomdp_baseline itself, not the literals True and False: numba would
    # compile _step_chunk and _close_step once per literal (about 2 s from empty).
    if gpomdp_baseline:
        # One parallel region per step: closing step t - 1 (which needs b_{t-1}, hence every
        # chunk's step t - 1) and making step t.
        live = N
        for t in range(H + 1):
            if t > 0:
                _baseline_row(t - 1, num, den, ended, dead, b)
            if live == 0:  # every chunk's sums are 0 from here on: the remaining rows all the same
                for rest in range(t, H):
                    _baseline_row(rest, num, den, ended, dead, b)
                break
            for c in prange(n_chunks):
                if t > 0 and n_live[c] > 0:
                    n_live[c] = _close_step(c * CHUNK, n_live[c], n_ended[c], t - 1, H, S[c], idx[c], st[c],
                                            alive[c], gpomdp_baseline, b, ended[c], samples, a, last_g, lengths,
                                            peak)
                if t < H and n_live[c] > 0:
                    n_ended[c] = _step_chunk(n_live[c], S[c], st[c], scratch[c], alive[c], K, sigma, inv_var,
                                             score_clipped, action_bound, disc[t], consts, x_threshold,
                                             angle_threshold, semi_implicit, disc[t], gpomdp_baseline, num[c],
                                             den[c])
                else:  # a chunk whose trajectories have all ended adds nothing to the step's sums
                    for p in range(4):
                        num[c, p] = 0.0
                        den[c, p] = 0.0
            live = 0
            for c in range(n_chunks):
                live += n_live[c]
    else:
        # Without G(PO)MDP's baseline the chunks do not wait for each other: each runs its whole
        # time loop while its rows stay in the cache.
        w_sample = 0.0 if reinforce_estimator else 1.0  # G(PO)MDP's sample sums G_t gamma^t
        for c in prange(n_chunks):
            for t in range(H):
                if n_live[c] == 0:
                    break
                ne = _step_chunk(n_live[c], S[c], st[c], scratch[c], alive[c], K, sigma, inv_var, score_clipped,
                                 action_bound, w_sample * disc[t], consts, x_threshold, angle_threshold,
                                 semi_implicit, disc[t], gpomdp_baseline, num[c], den[c])
                n_live[c] = _close_step(c * CHUNK, n_live[c], ne, t, H, S[c], idx[c], st[c], alive[c],
                                        gpomdp_baseline, b, ended[c], samples, a, last_g, lengths, peak)
    for c in prange(n_chunks):
        for j in range(n_live[c]):  # alive at the horizon
            _finish(c * CHUNK + idx[c, j], H, S[c], j, samples, a, last_g, lengths, peak)
    if reinforce_estimator:
        ret = np.zeros(H + 1)  # the discounted return of a trajectory of length T, sum_{t<T} gamma^t
        for t in range(H):
            ret[t + 1] = ret[t] + disc[t]
        for n in range(N):
            r = ret[int(lengths[n])]
            for p in range(4):
                samples[n, p] = last_g[n, p] * r
        if not baseline:
            return samples, lengths, peak
        # b = sum_n S_n^2 R_n / sum_n S_n^2, each chunk summed in index order, the chunks in order.
        num1 = np.zeros((n_chunks, 1, 4))
        den1 = np.zeros((n_chunks, 1, 4))
        for n in range(N):
            c = n // CHUNK
            r = ret[int(lengths[n])]
            for p in range(4):
                num1[c, 0, p] += last_g[n, p] * last_g[n, p] * r
                den1[c, 0, p] += last_g[n, p] * last_g[n, p]
        b1 = _reinforce_baseline(num1, den1)
        for n in range(N):
            for p in range(4):
                samples[n, p] -= last_g[n, p] * b1[p]
        return samples, lengths, peak
    if not baseline:
        return samples, lengths, peak

    # suffix[T] = sum_{l >= T} b_l: what a trajectory's frozen G contributes after it ended.
    suffix = np.zeros((H + 1, 4))
    for t in range(H - 1, -1, -1):
        for p in range(4):
            suffix[t, p] = suffix[t + 1, p] + b[t, p]
    for n in range(N):
        T = int(lengths[n])
        for p in range(4):
            samples[n, p] -= a[n, p] + last_g[n, p] * suffix[T, p]
    return samples, lengths, peak


_fused_serial = serial(_fused)
