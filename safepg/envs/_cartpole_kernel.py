r"""Fused cart-pole simulation + gradient-sample kernel (numba).

The reference path (``CartPole.simulate`` then :mod:`safepg.estimators`) steps every
cart for as long as *any* cart is alive and then makes a dozen passes over (N, H, 4)
arrays, most of whose entries are the zeros of dead steps. This kernel follows one
trajectory at a time and stops at its last step, and gives the same numbers up to
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
- Pass 2 subtracts :math:`\sum_l G_{n,l} b_l`; the dead steps contribute
  :math:`G_{n,T_n} \sum_{l \ge T_n} b_l`, one suffix sum. The live steps' G come from pass 1,
  which keeps them when the batch is small enough (:data:`HISTORY_STEPS`); a bigger batch
  simulates each trajectory again from the start of its stream (the same numbers, the same
  code, so the same bits) instead of keeping an (N, H, 4) array of cumulative scores.

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
from safepg.streams import next_normal, next_uniform, stream_start

#: Trajectories per chunk. Fixed (not per thread) so the reduction order, and hence every
#: bit of the result, is the same for any thread count; small enough that N = 4000 still
#: spreads over a few threads, large enough that the per-chunk (H, 4) sums stay small.
CHUNK = 512
#: Largest N * H whose cumulative scores pass 1 keeps for pass 2 (2.4 * 10^7: 768 MB at most,
#: N = 120000 at H = 200; the pages of steps not lived are never touched).
HISTORY_STEPS = 24_000_000


@njit(cache=True)
def _euler(x, x_dot, beta, beta_dot, force, half, ml, total, pole_mass, gravity, tau):
    """One explicit-Euler step; the same operations in the same order as ``step_dynamics``."""
    sin = portable.sin(beta)  # not libm's: its last bit depends on the CPU (safepg.portable)
    cos = portable.cos(beta)
    push = (force + ml * beta_dot * beta_dot * sin) / total
    beta_acc = (gravity * sin - cos * push) / (half * (4.0 / 3.0 - pole_mass * cos * cos / total))
    x_acc = push - ml * beta_acc * cos / total
    return x + tau * x_dot, x_dot + tau * x_acc, beta + tau * beta_dot, beta_dot + tau * beta_acc


@njit(cache=True)
def _semi_implicit(x, x_dot, beta, beta_dot, force, half, ml, total, pole_mass, gravity, tau):
    """One semi-implicit Euler step (velocities first, positions with the new velocities), the
    same operations as ``step_dynamics(..., integrator="semi-implicit")``."""
    sin = portable.sin(beta)  # not libm's: its last bit depends on the CPU (safepg.portable)
    cos = portable.cos(beta)
    push = (force + ml * beta_dot * beta_dot * sin) / total
    beta_acc = (gravity * sin - cos * push) / (half * (4.0 / 3.0 - pole_mass * cos * cos / total))
    x_acc = push - ml * beta_acc * cos / total
    x_dot_new = x_dot + tau * x_acc
    beta_dot_new = beta_dot + tau * beta_acc
    return x + tau * x_dot_new, x_dot_new, beta + tau * beta_dot_new, beta_dot_new


@njit(cache=True)
def _step(x, x_dot, beta, beta_dot, force, half, ml, total, pole_mass, gravity, tau, semi_implicit):
    """The integrator the task asked for (a branch, so the Euler path keeps its exact operations)."""
    if semi_implicit:
        return _semi_implicit(x, x_dot, beta, beta_dot, force, half, ml, total, pole_mass, gravity, tau)
    return _euler(x, x_dot, beta, beta_dot, force, half, ml, total, pole_mass, gravity, tau)


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


@njit(cache=True)
def _first_pass(lo, hi, K, sigma, inv_var, consts, key, H, init_bound, gamma, action_bound, x_threshold,
                angle_threshold, score_clipped, reinforce_estimator, baseline, samples, lengths, num, den, ended,
                kept, semi_implicit, peak, history):
    """Simulate trajectories lo..hi-1 until they end; their samples without baseline, their
    lengths, their largest |state component| (``peak``, the initial and the final state
    included), and this chunk's baseline sums ``num``, ``den`` (rows, 4) and ``ended`` (H+1, 4).

    Time runs in the outer loop and the chunk's live trajectories in the inner one: a step of
    one trajectory waits on its previous step (sine, cosine, two divisions), and stepping the
    others in between keeps the CPU busy meanwhile. Every trajectory's operations are those
    of following it alone, and every sum over trajectories is formed in the order of their
    indices, as before: the same bits.

    ``history`` (N * H, 4), unless it has a single row: the cumulative scores G of trajectory
    n at step t go to row n * H + t, for :func:`_second_pass_stored`.
    """
    half, ml, total, pole_mass, gravity, tau = consts
    k0, k1, k2, k3 = K[0], K[1], K[2], K[3]
    m = hi - lo
    store = history.shape[0] > 1
    st = np.empty(m, dtype=np.uint64)  # each trajectory's stream
    s = np.empty((m, 4))  # x, x_dot, beta, beta_dot
    g = np.zeros((m, 4))  # cumulative scores
    a = np.zeros((m, 4))  # G(PO)MDP sample without baseline
    pk = np.empty((m, 4))
    ret = np.zeros(m)
    T = np.full(m, H)
    live = np.empty(m, dtype=np.intp)  # indices of the live trajectories, in increasing order
    for i in range(m):
        s[i, 0], s[i, 1], s[i, 2], s[i, 3], st[i] = _initial_state(key, lo + i, init_bound)
        for p in range(4):
            pk[i, p] = abs(s[i, p])
        live[i] = i
    n_live = m
    disc = 1.0
    for t in range(H):
        if n_live == 0:
            break
        kept_live = 0
        for j in range(n_live):
            i = live[j]
            x, x_dot, beta, beta_dot = s[i, 0], s[i, 1], s[i, 2], s[i, 3]
            mean = k0 * x + k1 * x_dot + k2 * beta + k3 * beta_dot
            zt, st[i] = next_normal(st[i])
            a_raw = mean + sigma * zt
            u = min(max(a_raw, -action_bound), action_bound)
            d = ((u if score_clipped else a_raw) - mean) * inv_var
            g0 = g[i, 0] + d * x
            g1 = g[i, 1] + d * x_dot
            g2 = g[i, 2] + d * beta
            g3 = g[i, 3] + d * beta_dot
            g[i, 0], g[i, 1], g[i, 2], g[i, 3] = g0, g1, g2, g3
            if store:
                row = (lo + i) * H + t
                history[row, 0], history[row, 1], history[row, 2], history[row, 3] = g0, g1, g2, g3
            ret[i] += disc  # reward 1: alive at t (the step into a failing state counts)
            if not reinforce_estimator:
                a[i, 0] += g0 * disc
                a[i, 1] += g1 * disc
                a[i, 2] += g2 * disc
                a[i, 3] += g3 * disc
                if baseline:
                    num[t, 0] += g0 * g0 * disc
                    num[t, 1] += g1 * g1 * disc
                    num[t, 2] += g2 * g2 * disc
                    num[t, 3] += g3 * g3 * disc
                    den[t, 0] += g0 * g0
                    den[t, 1] += g1 * g1
                    den[t, 2] += g2 * g2
                    den[t, 3] += g3 * g3
            x, x_dot, beta, beta_dot = _step(x, x_dot, beta, beta_dot, u, half, ml, total, pole_mass, gravity, tau,
                                             semi_implicit)
            s[i, 0], s[i, 1], s[i, 2], s[i, 3] = x, x_dot, beta, beta_dot
            pk[i, 0] = max(pk[i, 0], abs(x))
            pk[i, 1] = max(pk[i, 1], abs(x_dot))
            pk[i, 2] = max(pk[i, 2], abs(beta))
            pk[i, 3] = max(pk[i, 3], abs(beta_dot))
            # "not <=" so that a NaN state also ends the episode, as in CartPole.alive.
            if not (abs(x) <= x_threshold and abs(beta) <= angle_threshold):
                T[i] = t + 1
            else:
                live[kept_live] = i  # compacted in place, order kept
                kept_live += 1
        n_live = kept_live
        disc *= gamma
    for i in range(m):
        n = lo + i
        lengths[n] = T[i]
        for p in range(4):
            peak[n, p] = pk[i, p]
        g0, g1, g2, g3 = g[i, 0], g[i, 1], g[i, 2], g[i, 3]
        if reinforce_estimator:
            r = ret[i]
            samples[n, 0] = g0 * r
            samples[n, 1] = g1 * r
            samples[n, 2] = g2 * r
            samples[n, 3] = g3 * r
            if baseline:
                num[0, 0] += g0 * g0 * r
                num[0, 1] += g1 * g1 * r
                num[0, 2] += g2 * g2 * r
                num[0, 3] += g3 * g3 * r
                den[0, 0] += g0 * g0
                den[0, 1] += g1 * g1
                den[0, 2] += g2 * g2
                den[0, 3] += g3 * g3
                kept[n, 0], kept[n, 1], kept[n, 2], kept[n, 3] = g0, g1, g2, g3
        else:
            samples[n, 0], samples[n, 1], samples[n, 2], samples[n, 3] = a[i, 0], a[i, 1], a[i, 2], a[i, 3]
            if baseline and T[i] < H:
                ended[T[i], 0] += g0 * g0
                ended[T[i], 1] += g1 * g1
                ended[T[i], 2] += g2 * g2
                ended[T[i], 3] += g3 * g3


@njit(cache=True)
def _second_pass(lo, hi, K, sigma, inv_var, consts, key, init_bound, action_bound, score_clipped, b, suffix,
                 samples, lengths, semi_implicit):
    """Subtract sum_l G_{n,l} b_l from the G(PO)MDP samples lo..hi-1, simulating them again
    (time outside, trajectories inside, as in :func:`_first_pass`)."""
    half, ml, total, pole_mass, gravity, tau = consts
    k0, k1, k2, k3 = K[0], K[1], K[2], K[3]
    m = hi - lo
    st = np.empty(m, dtype=np.uint64)
    s = np.empty((m, 4))
    g = np.zeros((m, 4))
    a = np.zeros((m, 4))  # sum_l G_l b_l over the live steps
    T = np.empty(m, dtype=np.intp)
    live = np.empty(m, dtype=np.intp)
    H = 0
    for i in range(m):
        s[i, 0], s[i, 1], s[i, 2], s[i, 3], st[i] = _initial_state(key, lo + i, init_bound)
        T[i] = int(lengths[lo + i])
        H = max(H, T[i])
        live[i] = i
    n_live = m
    # Pass 1's trajectories again, operation for operation: each ends at its T, no need to test.
    for t in range(H):
        kept_live = 0
        for j in range(n_live):
            i = live[j]
            x, x_dot, beta, beta_dot = s[i, 0], s[i, 1], s[i, 2], s[i, 3]
            mean = k0 * x + k1 * x_dot + k2 * beta + k3 * beta_dot
            zt, st[i] = next_normal(st[i])
            a_raw = mean + sigma * zt
            u = min(max(a_raw, -action_bound), action_bound)
            d = ((u if score_clipped else a_raw) - mean) * inv_var
            g0 = g[i, 0] + d * x
            g1 = g[i, 1] + d * x_dot
            g2 = g[i, 2] + d * beta
            g3 = g[i, 3] + d * beta_dot
            g[i, 0], g[i, 1], g[i, 2], g[i, 3] = g0, g1, g2, g3
            a[i, 0] += g0 * b[t, 0]
            a[i, 1] += g1 * b[t, 1]
            a[i, 2] += g2 * b[t, 2]
            a[i, 3] += g3 * b[t, 3]
            if t + 1 < T[i]:  # the state after the last step is never used
                x, x_dot, beta, beta_dot = _step(x, x_dot, beta, beta_dot, u, half, ml, total, pole_mass,
                                                 gravity, tau, semi_implicit)
                s[i, 0], s[i, 1], s[i, 2], s[i, 3] = x, x_dot, beta, beta_dot
                live[kept_live] = i
                kept_live += 1
        n_live = kept_live
    for i in range(m):
        n, Ti = lo + i, T[i]
        samples[n, 0] -= a[i, 0] + g[i, 0] * suffix[Ti, 0]
        samples[n, 1] -= a[i, 1] + g[i, 1] * suffix[Ti, 1]
        samples[n, 2] -= a[i, 2] + g[i, 2] * suffix[Ti, 2]
        samples[n, 3] -= a[i, 3] + g[i, 3] * suffix[Ti, 3]


@njit(cache=True)
def _second_pass_stored(lo, hi, H, history, b, suffix, samples, lengths):
    """:func:`_second_pass` from the cumulative scores pass 1 stored: the same terms added in
    the same order, so the same bits, without simulating again."""
    for n in range(lo, hi):
        T = int(lengths[n])
        a0 = a1 = a2 = a3 = 0.0
        for t in range(T):
            row = n * H + t
            a0 += history[row, 0] * b[t, 0]
            a1 += history[row, 1] * b[t, 1]
            a2 += history[row, 2] * b[t, 2]
            a3 += history[row, 3] * b[t, 3]
        last = n * H + T - 1
        samples[n, 0] -= a0 + history[last, 0] * suffix[T, 0]
        samples[n, 1] -= a1 + history[last, 1] * suffix[T, 1]
        samples[n, 2] -= a2 + history[last, 2] * suffix[T, 2]
        samples[n, 3] -= a3 + history[last, 3] * suffix[T, 3]


@njit(cache=True)
def _baseline(num, den, ended, gpomdp_baseline):
    """Baselines b (rows, 4) = num / den (0 where den = 0) and their suffix sums (H + 1, 4).

    Serial, and in its own (non-parallel) function: inside the parallel kernel numba would
    turn every array expression here into a parallel region with its own barrier, about a
    thousand per call, which is slow on a busy machine. The chunks are added in order, so
    the result does not depend on the number of threads.
    """
    n_chunks, rows = num.shape[0], num.shape[1]
    nb = np.zeros((rows, 4))
    db = np.zeros((rows, 4))
    for c in range(n_chunks):
        for t in range(rows):
            for p in range(4):
                nb[t, p] += num[c, t, p]
                db[t, p] += den[c, t, p]
    H = ended.shape[1] - 1
    if gpomdp_baseline:
        dead = np.zeros(4)  # sum of the final G^2 of the trajectories already ended at step t
        for t in range(H):
            for c in range(n_chunks):
                for p in range(4):
                    dead[p] += ended[c, t, p]
            for p in range(4):
                db[t, p] += dead[p]
    b = np.zeros((rows, 4))
    for t in range(rows):
        for p in range(4):
            if db[t, p] != 0.0:
                b[t, p] = nb[t, p] / db[t, p]
    # suffix[T] = sum_{l >= T} b_l: what a trajectory's frozen G contributes after it ended.
    suffix = np.zeros((H + 1, 4))
    if gpomdp_baseline:
        for t in range(H - 1, -1, -1):
            for p in range(4):
                suffix[t, p] = suffix[t + 1, p] + b[t, p]
    return b, suffix


def cartpole_gradient_samples(K: np.ndarray, sigma: float, pole_length: float, cart_mass: float,
                              pole_mass: float, gravity: float, tau: float, key: np.uint64, n: int,
                              horizon: int, init_bound: float, gamma: float, action_bound: float,
                              x_threshold: float, angle_threshold: float,
                              score_clipped: bool, reinforce_estimator: bool,
                              baseline: bool, semi_implicit: bool = False, polemass_length: float | None = None,
                              peaks: bool = False, history_steps: int = HISTORY_STEPS) -> tuple[np.ndarray, ...]:
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
    history_steps : int
        G(PO)MDP with baseline: the largest N * H whose cumulative scores pass 1 keeps for
        pass 2; above it pass 2 simulates again (the same bits either way).

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
    # combination of argument types, e.g. an int constant or a numpy bool flag.
    K = np.ascontiguousarray(K, dtype=np.float64).reshape(4)
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
                                    bool(baseline), bool(semi_implicit), int(history_steps))
    return (samples, lengths, peak) if peaks else (samples, lengths)


@njit(cache=True, parallel=True)
def _fused(K, sigma, half, ml, cart_mass, pole_mass, gravity, tau, key, N, H, init_bound, gamma, action_bound,
           x_threshold, angle_threshold, score_clipped, reinforce_estimator, baseline, semi_implicit, history_steps):
    """:func:`cartpole_gradient_samples` on normalised arguments."""
    n_chunks = (N + CHUNK - 1) // CHUNK
    samples = np.zeros((N, 4))
    lengths = np.empty(N)
    peak = np.empty((N, 4))
    gpomdp_baseline = baseline and not reinforce_estimator
    rows = 1 if reinforce_estimator else H
    num = np.zeros((n_chunks if baseline else 1, rows, 4))
    den = np.zeros((n_chunks if baseline else 1, rows, 4))
    # Final G^2 of the trajectories of a chunk that ended at step T (index T), see above.
    ended = np.zeros((n_chunks if gpomdp_baseline else 1, H + 1, 4))
    # REINFORCE's baseline needs only the total score S_n, not a second simulation.
    kept = np.empty((N if baseline and reinforce_estimator else 1, 4))
    # G(PO)MDP's cumulative scores, kept for pass 2 up to history_steps trajectory-steps (32
    # bytes each; only the steps lived are written); a bigger batch simulates pass 2 again.
    store = gpomdp_baseline and N * H <= history_steps
    history = np.empty((N * H if store else 1, 4))
    inv_var = 1.0 / (sigma * sigma)
    consts = (half, ml, cart_mass + pole_mass, pole_mass, gravity, tau)
    # Without a baseline the sums are never touched: every chunk gets the same dummy row.
    i_step = 1 if baseline else 0
    j_step = 1 if gpomdp_baseline else 0
    for c in prange(n_chunks):
        i = c * i_step
        j = c * j_step
        _first_pass(c * CHUNK, min(N, (c + 1) * CHUNK), K, sigma, inv_var, consts, key, H, init_bound, gamma,
                    action_bound, x_threshold, angle_threshold, score_clipped, reinforce_estimator, baseline,
                    samples, lengths, num[i], den[i], ended[j], kept, semi_implicit, peak, history)
    if not baseline:
        return samples, lengths, peak

    b, suffix = _baseline(num, den, ended, gpomdp_baseline)
    if reinforce_estimator:
        for n in range(N):
            for p in range(4):
                samples[n, p] -= kept[n, p] * b[0, p]
        return samples, lengths, peak

    for c in prange(n_chunks):
        if store:
            _second_pass_stored(c * CHUNK, min(N, (c + 1) * CHUNK), H, history, b, suffix, samples, lengths)
        else:
            _second_pass(c * CHUNK, min(N, (c + 1) * CHUNK), K, sigma, inv_var, consts, key, init_bound,
                         action_bound, score_clipped, b, suffix, samples, lengths, semi_implicit)
    return samples, lengths, peak


_fused_serial = serial(_fused)
