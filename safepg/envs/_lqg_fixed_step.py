"""Consecutive batches of vanilla policy gradient with a fixed step on the LQG, in one compiled call.

A run of vanilla G(PO)MDP with a small batch is mostly loop overhead when each batch is a Python
iteration: Table 5.3's N = 100 runs have 3*10^5 of them, and the step itself is one
multiply-add per component. Here the loop runs in numba around the fused serial kernels of
:mod:`!safepg.envs._lqg_kernel`, and does each Python step in NumPy's own order, so a run
gives the bits of :func:`safepg.learning.vanilla_pg`'s loop (tested):

* the gradient estimate ``samples.sum(axis=0) / n``: NumPy sums a column vector (m = 1) by
  its pairwise summation (:func:`safepg.numpy_order.pairwise_sum`), and the columns of an (n, m >= 2) array
  row after row into zeros;
* the batch's mean return ``returns.sum() / n``, pairwise;
* the step ``theta + alpha * grad`` (``"scalar"``), or ``alpha * g_k`` added to the first
  largest component only, zeros added to the others (``"coordinate"``).

The loop stops after the first batch whose gradient or new parameters are not finite; the
caller decides what that means.
"""

from __future__ import annotations

import types

import numpy as np
from numba import njit

from safepg.envs._lqg_kernel import (
    lqg1d_gradient_samples_serial,
    lqg2d_gradient_samples_serial,
    lqg_gradient_samples_serial,
)
from safepg.numpy_order import all_finite, column_means, pairwise_sum


@njit(cache=True)
def _step(theta, grad, alpha, coordinate):  # pragma: no cover - numba
    delta = np.zeros_like(grad)
    if coordinate:
        k = 0
        for j in range(1, grad.size):
            if abs(grad[j]) > abs(grad[k]):
                k = j
        delta[k] = alpha * grad[k]
    else:
        for j in range(grad.size):
            delta[j] = alpha * grad[j]
    return theta + delta


@njit(cache=True)
def _set_row(a, i, v):  # pragma: no cover - numba
    # Element by element: ``a[i] = v`` would compile numba's broadcasting and its shape-error
    # message (about 2 s of compilation per loop, once per cold cache).
    for j in range(v.size):
        a[i, j] = v[j]


# The adapters from the loop's arguments (the flat parameters, the policy's factors) to a kernel's:
# the 1-D kernel's scalars, or the gain matrix of the 2-D and the generic kernels.
@njit(cache=True)
def _samples_1d(theta, L, Pm, A, B, Q, R, key, n, H, gamma, bs, ba, clip, score_clipped, reinforce_estimator,
                baseline):  # pragma: no cover - numba
    return lqg1d_gradient_samples_serial(theta[0], L[0, 0], A[0, 0], B[0, 0], Q[0, 0], R[0, 0], key, n, H, gamma,
                                         bs, ba, clip, score_clipped, reinforce_estimator, baseline)


def _matrix_samples(theta, L, Pm, A, B, Q, R, key, n, H, gamma, bs, ba, clip, score_clipped, reinforce_estimator,
                    baseline):  # pragma: no cover - numba
    K = theta.reshape(Pm.shape[0], theta.size // Pm.shape[0])
    return _kernel(K, L, Pm, A, B, Q, R, key, n, H, gamma, bs, ba, clip, score_clipped, reinforce_estimator, baseline)


def _kernel(*args):  # pragma: no cover - replaced by a matrix kernel in each compiled adapter
    raise NotImplementedError


def _samples(*args):  # pragma: no cover - replaced by one of the adapters in each compiled loop
    raise NotImplementedError


def _batches(theta, L, Pm, A, B, Q, R, keys, sizes, H, gamma, bs, ba, clip, score_clipped, reinforce_estimator,
             baseline, alpha, coordinate):  # pragma: no cover - numba
    """Batch i draws ``sizes[i]`` trajectories with key ``keys[i]`` from ``theta_i`` and steps to
    ``theta_{i+1}``.

    ``theta`` is the flat start (m,), the gain row-major. Returns ``thetas`` (b + 1, m),
    ``grads`` (b, m) and ``j_hat`` (b,) for the b batches drawn: all of them, or up to the first
    whose gradient is not finite (then ``thetas`` has b rows) or whose new parameters are not
    (their row is the last).
    """
    b_max = keys.size
    m = theta.size
    thetas = np.empty((b_max + 1, m))
    grads = np.empty((b_max, m))
    j_hat = np.empty(b_max)
    _set_row(thetas, 0, theta)
    for i in range(b_max):
        n = sizes[i]
        samples, returns = _samples(theta, L, Pm, A, B, Q, R, keys[i], n, H, gamma, bs, ba, clip, score_clipped,
                                    reinforce_estimator, baseline)
        grad = column_means(samples, n)
        _set_row(grads, i, grad)
        j_hat[i] = pairwise_sum(returns) / n
        if not all_finite(grad):
            return thetas[:i + 1], grads[:i + 1], j_hat[:i + 1]
        theta = _step(theta, grad, alpha, coordinate)
        _set_row(thetas, i + 1, theta)
        if not all_finite(theta):
            return thetas[:i + 2], grads[:i + 1], j_hat[:i + 1]
    return thetas, grads, j_hat


def _compiled(function, name, **names):
    """``function`` compiled with some of its global ``names`` bound to other compiled functions,
    under its own ``name`` (its own entry in numba's cache): a run compiles only the kernel of its
    dimension."""
    g = types.FunctionType(function.__code__, {**globals(), **names}, name)
    g.__qualname__ = name
    g.__doc__ = function.__doc__
    return njit(cache=True, error_model="numpy")(g)


#: The loop by the LQG's state dimension (0: any other).
FIXED_STEP_BATCHES = {
    1: _compiled(_batches, "fixed_step_batches_1d", _samples=_samples_1d),
    2: _compiled(_batches, "fixed_step_batches_2d",
                 _samples=_compiled(_matrix_samples, "_samples_2d", _kernel=lqg2d_gradient_samples_serial)),
    0: _compiled(_batches, "fixed_step_batches",
                 _samples=_compiled(_matrix_samples, "_samples_any", _kernel=lqg_gradient_samples_serial)),
}
