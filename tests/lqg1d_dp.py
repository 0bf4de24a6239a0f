"""The clipped 1-D LQG of Section 5.1 by quadrature: what the simulator's numbers should be, derived without it.

The task (``LQG.thesis_1d()``): s_0 uniform on [-2, 2]; a_t ~ N(theta s_t, sigma^2), u_t = clip(a_t, -2, 2),
r_t = -(s_t^2 + u_t^2) / 2, s_{t+1} = clip(s_t + u_t, -2, 2); gamma = 0.9, H = 20. Its objective, the
expected discounted return J(theta) = E sum_t gamma^t r_t, has no closed form (the clipping), so it is
computed here by numerical integration, with nothing of safepg: the states on a grid of ``m`` nodes, the
applied action by the trapezoid rule on a grid of ``q`` points of (-2, 2) plus its two atoms at +-2 (the
Gaussian tails that clipping moves there).

- :func:`performance`: backward induction, V_H = 0, V_t(s) = E[r_t + gamma V_{t+1}(s_{t+1}) | s_t = s]
  (V_{t+1} interpolated linearly), J = the mean of V_0 over the uniform s_0.
- :func:`gradient`: the central difference of :func:`performance` in theta. The quadrature points do not
  move with theta (only their weights do), so J is smooth in theta and the difference is exact to O(h^2).
- :func:`gpomdp_mean`: the expectation of the G(PO)MDP gradient sample, with the raw or the clipped
  action's score and with or without the variance-minimising baseline, by a forward recursion of the
  state distribution and of the first two moments of the cumulated score. With the raw score and no
  baseline it is the likelihood-ratio gradient, which must equal :func:`gradient`: two independent
  computations (``tests/test_estimators.py`` checks it).

On the grids used (m = q = 801), halving the spacing changes J(-0.3) by 8e-5 (7e-6 relative) and its
gradient by 1e-6 relative.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

GAMMA, H, B = 0.9, 20, 2.0  # LQG.thesis_1d(): discount, horizon, state and action bound


def _trapezoid(x: np.ndarray) -> np.ndarray:
    w = np.full(x.size, x[1] - x[0])
    w[[0, -1]] /= 2
    return w


@dataclass(frozen=True)
class Actions:
    """The applied action's quadrature at every state node: points ``u`` (the grid of (-2, 2), then -2 and 2),
    probabilities ``p`` (m, q + 2), and the score's partial moments ``m1``, ``m2`` (m, q + 2):
    E[psi 1{u = point}] and E[psi^2 1{u = point}], psi the score d log pi / d theta."""

    u: np.ndarray
    p: np.ndarray
    m1: np.ndarray
    m2: np.ndarray


def actions(s: np.ndarray, theta: float, sigma: float, q: int, score: str) -> Actions:
    """The quadrature of the applied action u = clip(a, -2, 2), a ~ N(theta s, sigma^2), at each state of ``s``.

    ``score="clipped"`` scores u as the authors' code does, psi = (u - theta s) s / sigma^2;
    ``score="raw"`` scores a, psi = (a - theta s) s / sigma^2, whose moments over each clipped tail are
    the Gaussian's partial moments (E[Z 1{Z >= z}] = phi(z), E[Z^2 1{Z >= z}] = 1 - Phi(z) + z phi(z)).
    """
    grid = np.linspace(-B, B, q)
    mu = theta * s[:, None]
    z = (grid[None, :] - mu) / sigma
    phi = np.exp(-0.5 * z * z) / np.sqrt(2 * np.pi)
    inner = phi / sigma * _trapezoid(grid)[None, :]
    z_lo, z_hi = ((-B - mu) / sigma)[:, 0], ((B - mu) / sigma)[:, 0]
    phi_lo, phi_hi = np.exp(-0.5 * z_lo**2) / np.sqrt(2 * np.pi), np.exp(-0.5 * z_hi**2) / np.sqrt(2 * np.pi)
    p = np.hstack([inner, ndtr(z_lo)[:, None], ndtr(-z_hi)[:, None]])
    u = np.concatenate([grid, [-B, B]])
    c = (s / sigma)[:, None]  # psi = c Z with Z = (action - theta s) / sigma
    if score == "clipped":
        zu = (u[None, :] - mu) / sigma
        m1, m2 = p * c * zu, p * (c * zu) ** 2
    elif score == "raw":
        m1 = np.hstack([inner * c * z, (c[:, 0] * -phi_lo)[:, None], (c[:, 0] * phi_hi)[:, None]])
        m2 = np.hstack([inner * (c * z) ** 2, (c[:, 0] ** 2 * (ndtr(z_lo) - z_lo * phi_lo))[:, None],
                        (c[:, 0] ** 2 * (ndtr(-z_hi) + z_hi * phi_hi))[:, None]])
    else:
        raise ValueError(f"score must be 'clipped' or 'raw', got {score!r}")
    return Actions(u, p, m1, m2)


def performance(theta: float, sigma: float = 1.0, m: int = 801, q: int = 801) -> float:
    """J(theta) of the clipped 20-step task, by backward induction on the state grid."""
    s = np.linspace(-B, B, m)
    a = actions(s, theta, sigma, q, "clipped")
    reward = -0.5 * (s[:, None] ** 2 + a.u[None, :] ** 2)
    nxt = np.clip(s[:, None] + a.u[None, :], -B, B)
    V = np.zeros(m)
    for _ in range(H):
        V = np.sum(a.p * (reward + GAMMA * np.interp(nxt, s, V)), axis=1)
    return float(_trapezoid(s) @ V / (2 * B))


def gradient(theta: float, sigma: float = 1.0, h: float = 1e-4, m: int = 801, q: int = 801) -> float:
    """dJ/dtheta, the central difference of :func:`performance`."""
    return (performance(theta + h, sigma, m, q) - performance(theta - h, sigma, m, q)) / (2 * h)


def gpomdp_mean(theta: float, sigma: float = 1.0, score: str = "clipped", baseline: bool = True,
                m: int = 801, q: int = 801) -> dict[str, float]:
    """The expectation of the G(PO)MDP gradient sample, and J, by a forward recursion.

    With S_t = psi_0 + ... + psi_t, the sample is sum_t S_t (gamma^t r_t - b_t), b_t = E[S_t^2 gamma^t r_t] /
    E[S_t^2] (the variance-minimising baseline; its estimate from a batch of N trajectories has a bias of
    order 1/N), so its mean is sum_t (E[S_t gamma^t r_t] - b_t E[S_t]). The state distribution and E[S_{t-1}^k]
    over it (k = 0, 1, 2) are weights on the grid's nodes; a next state between two nodes splits its weight
    between them linearly. S_{t-1} and psi_t are independent given s_t.

    Returns
    -------
    dict
        ``"mean"``: the expectation of the sample; ``"J"``: E sum_t gamma^t r_t on the same grids.
    """
    s = np.linspace(-B, B, m)
    a = actions(s, theta, sigma, q, score)
    reward = -0.5 * (s[:, None] ** 2 + a.u[None, :] ** 2)
    x = (np.clip(s[:, None] + a.u[None, :], -B, B) + B) / (s[1] - s[0])
    left = np.minimum(np.floor(x).astype(int), m - 2)
    frac = x - left

    def spread(w: np.ndarray) -> np.ndarray:  # weights at (node, action) onto the nodes of the next state
        return (np.bincount(left.ravel(), (w * (1 - frac)).ravel(), minlength=m)
                + np.bincount(left.ravel() + 1, (w * frac).ravel(), minlength=m))

    mu0 = _trapezoid(s) / (2 * B)  # the uniform s_0
    mu1, mu2 = np.zeros(m), np.zeros(m)  # E[S_{-1}^k; s_0] with S_{-1} = 0
    total, J = 0.0, 0.0
    for t in range(H):
        w0 = mu0[:, None] * a.p
        w1 = mu1[:, None] * a.p + mu0[:, None] * a.m1
        w2 = mu2[:, None] * a.p + 2 * mu1[:, None] * a.m1 + mu0[:, None] * a.m2
        g = GAMMA**t * reward
        J += float(np.sum(w0 * g))
        S_r, S2_r, S, S2 = float(np.sum(w1 * g)), float(np.sum(w2 * g)), float(w1.sum()), float(w2.sum())
        total += S_r - (S2_r / S2 * S if baseline else 0.0)
        mu0, mu1, mu2 = spread(w0), spread(w1), spread(w2)
    return {"mean": total, "J": J}
