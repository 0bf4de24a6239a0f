r"""Which LQG setting produces the numbers printed in the thesis's Section 5.2?

Section 5.2.1 states, for the two-dimensional LQG with Q = R = I, sigma_1 = sigma_2 = 1
and gamma = 0.95, that :math:`\theta^* \simeq \operatorname{diag}(-0.588)` and
:math:`J_\mu(\theta^*) \simeq -422.616`. The closed form of :class:`~safepg.envs.lqg.LQG`
gives :math:`\theta^* = \operatorname{diag}(-0.6037)` and :math:`J(\theta^*) = -52.609`
for that setting (and :math:`J(0) = -426.667`). This module holds the tools used to
look for the nearby setting that does reproduce the printed numbers:

* :func:`second_moments` and :func:`finite_horizon_performance`: exact expected
  discounted return of the *unclipped* H-step problem, by propagating
  :math:`\mathbb E[s_t s_t^\top]` (no sampling);
* :func:`finite_horizon_optimal_gain`: the best stationary diagonal gain for it;
* :func:`measured_return`: Monte Carlo mean of the simulator's discounted return
  (clipped or not), the quantity behind the thesis's :math:`\overline\Upsilon`;
* :func:`candidate_settings` and :func:`search_printed_settings`: enumerate a grid of
  readings of the printed setting (discount, reward scale with or without the 0.5,
  sigma read as a standard deviation or a variance, state range, summed or
  per-dimension J, horizon, clipping, and the parameter J is evaluated at) and keep
  those within a relative tolerance of each printed number;
* :func:`horizon_matching_value`: the horizon at which the finite-horizon J comes
  closest to a target (a check that a match is not a tuned coincidence).

What the search found: -0.588 is theta* for gamma = 0.9 (any horizon >= 20, any state
range, either sigma reading, since sigma = 1); no reading reproduces -422.616 within
0.1%; the closest natural value is J(0) = -426.667 at gamma = 0.95. With the simulator
at gamma = 0.9 (H = 20, clipping to [-2, 2]), the learning runs of Section 5.2 reproduce
the printed final parameters and Table 5.3; at gamma = 0.95 they do not.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from safepg import portable
from safepg.envs.lqg import LQG
from safepg.policies import LinearGaussianPolicy, check_sigma
from safepg.rng import RNGLike, as_generator

#: Numbers printed in Section 5.2.1 (theta* is the (1,1) = (2,2) entry).
PRINTED_THETA_STAR = -0.588
PRINTED_J_STAR = -422.616
#: Final parameters printed after 3e7 trajectories (Section 5.2.1).
PRINTED_FINAL_SCALAR = np.array([[-0.014676, 1.4e-06], [1.7e-06, -0.013678]])
PRINTED_FINAL_COORDINATE = np.diag([-0.0275, -0.0274])
#: Table 5.3: average measured performance (adaptive N, N = 1000, N = 100).
PRINTED_UPSILON = {"adaptive": -20.50, "N=1000": -22.39, "N=100": -19.77}

#: Parameters at which J can be evaluated, besides each setting's own optimum.
FIXED_POINTS: dict[str, np.ndarray] = {
    "zero": np.zeros((2, 2)),
    "printed_theta_star": np.diag([PRINTED_THETA_STAR, PRINTED_THETA_STAR]),
    "printed_final_scalar": PRINTED_FINAL_SCALAR,
    "printed_final_coordinate": PRINTED_FINAL_COORDINATE,
}


# --------------------------------------------------------------------- exact values
def second_moments(env: LQG, theta: np.ndarray | float, sigma: float | np.ndarray, horizon: int) -> np.ndarray:
    r"""State second moments :math:`S_t = \mathbb E[s_t s_t^\top]`, t = 0, ..., H-1, without clipping.

    With :math:`a_t = K s_t + \varepsilon_t`, :math:`\varepsilon_t\sim\mathcal N(0,\Sigma)`
    independent of :math:`s_t`, and no state noise,

    .. math:: S_{t+1} = (A + BK)\,S_t\,(A + BK)^\top + B\Sigma B^\top,
              \qquad S_0 = \mathbb E[s_0 s_0^\top] = \tfrac{b^2}{3} I.

    Parameters
    ----------
    env : LQG
        The task (its ``clip`` flag is ignored: this is the unclipped problem).
    theta : array_like
        Gain K, (m, m) or flat.
    sigma : float or ndarray
        Policy standard deviation, per-action stds or covariance (as in
        :class:`~safepg.policies.LinearGaussianPolicy`).
    horizon : int
        Number of steps H >= 1.

    Returns
    -------
    ndarray, shape (H, m, m)
    """
    _check_horizon(horizon)
    A, B, _, _ = env._mats
    K = env._gain(theta)
    S_pol = check_sigma(sigma, env.dim)
    mm = portable.matmul  # fixed-order products: these values are printed (safepg.portable)
    F = A + mm(B, K)
    noise = mm(mm(B, S_pol), B.T)
    out = np.empty((horizon, env.dim, env.dim))
    S = env.initial_second_moment()
    for t in range(horizon):
        out[t] = S
        S = mm(mm(F, S), F.T) + noise
    return out


def expected_rewards(env: LQG, theta: np.ndarray | float, sigma: float | np.ndarray, horizon: int) -> np.ndarray:
    r"""Exact :math:`\mathbb E[r_t]`, t = 0, ..., H-1, of the unclipped problem.

    .. math:: \mathbb E[r_t] = -\tfrac12\big(\operatorname{tr}(Q S_t)
              + \operatorname{tr}(R (K S_t K^\top + \Sigma))\big)

    Returns
    -------
    ndarray, shape (H,)
    """
    _, _, Q, R = env._mats
    K = env._gain(theta)
    S_pol = check_sigma(sigma, env.dim)
    S = second_moments(env, K, sigma, horizon)
    mm = portable.matmul
    action_m2 = mm(mm(K, S), K.T) + S_pol  # (H, m, m)
    return -0.5 * (portable.trace(mm(Q, S)) + portable.trace(mm(R, action_m2)))


def finite_horizon_performance(
    env: LQG, theta: np.ndarray | float, sigma: float | np.ndarray, horizon: int | None = None
) -> float:
    r"""Exact expected discounted return of the unclipped H-step problem.

    .. math:: J_H(\theta) = \sum_{t=0}^{H-1}\gamma^t\,\mathbb E[r_t]

    computed from :func:`expected_rewards` (second-moment recursion, no sampling). It is
    finite for any gain, stable or not, and tends to :meth:`LQG.performance` as H grows
    when the closed loop is stable.

    Parameters
    ----------
    env : LQG
    theta : array_like
        Gain K.
    sigma : float or ndarray
        Policy standard deviation(s) or covariance.
    horizon : int, optional
        H; defaults to ``env.horizon``.

    Returns
    -------
    float
    """
    H = env.horizon if horizon is None else horizon
    r = expected_rewards(env, theta, sigma, H)
    return float(np.sum(r * portable.powers(env.gamma, H)))


def finite_horizon_optimal_gain(
    env: LQG, sigma: float | np.ndarray, horizon: int | None = None, bracket: tuple[float, float] = (-2.0, 0.0)
) -> float:
    r"""Best stationary diagonal gain :math:`t` (K = t I) for :func:`finite_horizon_performance`.

    With Q, R, A, B multiples of the identity and a diagonal covariance the m tasks are
    independent and identical, so the optimum is a multiple of I; a bounded scalar search
    over ``bracket`` finds it.

    Returns
    -------
    float
        The optimal t (the thesis's theta* for this horizon).
    """
    H = env.horizon if horizon is None else horizon
    eye = np.eye(env.dim)

    def cost(t: float) -> float:
        return -finite_horizon_performance(env, t * eye, sigma, H)

    res = minimize_scalar(cost, bounds=bracket, method="bounded", options={"xatol": 1e-9})
    return float(res.x)


def horizon_matching_value(
    env: LQG, theta: np.ndarray | float, sigma: float | np.ndarray, target: float, max_horizon: int = 2000
) -> tuple[int, float]:
    """Horizon H <= ``max_horizon`` whose exact unclipped J_H is closest to ``target``.

    Returns
    -------
    (int, float)
        The horizon and its J_H.
    """
    r = expected_rewards(env, theta, sigma, max_horizon)
    J = np.cumsum(r * portable.powers(env.gamma, max_horizon))
    h = int(np.argmin(np.abs(J - target)))
    return h + 1, float(J[h])


def measured_return(
    env: LQG, theta: np.ndarray | float, sigma: float | np.ndarray, n: int, rng: RNGLike = None
) -> tuple[float, float]:
    """Monte Carlo mean discounted return of ``env.simulate`` and its standard error.

    This is the "measured performance" of the thesis (clipped if ``env.clip``).

    Returns
    -------
    (float, float)
        Mean and standard error over ``n`` trajectories.
    """
    policy = LinearGaussianPolicy(env._gain(theta), sigma)
    ret = env.simulate(policy, n, as_generator(rng)).discounted_returns()
    return float(ret.mean()), float(ret.std(ddof=1) / np.sqrt(n))


def _check_horizon(horizon: int) -> None:
    if int(horizon) != horizon or horizon < 1:
        raise ValueError(f"horizon must be a positive integer, got {horizon}")


# --------------------------------------------------------------------------- search
@dataclass(frozen=True)
class SettingsGrid:
    """Readings of the printed 2-D setting to enumerate.

    Attributes
    ----------
    gammas : discount factors.
    reward_scales : c in r = -c (s'Qs + a'Ra) with Q = R = I (0.5 is the printed one).
    sigma_readings : "std" (C = sigma^2 I) and/or "variance" (C = sigma I, as printed).
    sigmas : the printed sigma_1 = sigma_2 values.
    state_bounds : b, the initial-state (and, if clipped, state and action) half-range.
    per_dimension : report J summed over the m = 2 tasks (False) and/or divided by m (True).
    horizons : None for the infinite-horizon closed form, or H for the exact H-step value.
    clipped_horizons : horizons for Monte Carlo values of the clipped simulator (empty: none).
    points : where J is taken: "optimum" (the setting's own theta*) and keys of FIXED_POINTS.
    mc_trajectories : trajectories per Monte Carlo value (clipped rows).
    seed : seed of the Monte Carlo values.
    """

    gammas: tuple[float, ...] = (0.9, 0.95, 0.975, 0.99, 0.995, 0.999)
    reward_scales: tuple[float, ...] = (0.5, 1.0)
    sigma_readings: tuple[str, ...] = ("std", "variance")
    sigmas: tuple[float, ...] = (1.0,)
    state_bounds: tuple[float, ...] = (1.0, 2.0, 3.0, 4.0, 5.0, 10.0)
    per_dimension: tuple[bool, ...] = (False, True)
    horizons: tuple[int | None, ...] = (None, 20, 50, 100, 200)
    clipped_horizons: tuple[int, ...] = ()
    points: tuple[str, ...] = ("optimum", *FIXED_POINTS)
    mc_trajectories: int = 20_000
    seed: int = 0


def _env(gamma: float, scale: float, bound: float, horizon: int | None, clip: bool) -> LQG:
    # The environment's reward is -0.5 (s'Qs + a'Ra): scale c means Q = R = 2c I.
    return LQG(dim=2, gamma=gamma, horizon=horizon or 20, state_bound=bound, action_bound=bound,
               Q=2 * scale, R=2 * scale, clip=clip)


def _policy_std(sigma: float, reading: str) -> float:
    if reading == "std":
        return sigma
    if reading == "variance":
        return float(np.sqrt(sigma))
    raise ValueError(f"sigma reading must be 'std' or 'variance', got {reading!r}")


def candidate_settings(grid: SettingsGrid | None = None) -> Iterator[dict[str, Any]]:
    """Every setting of ``grid`` with its theta* and J at each requested point.

    Yields
    ------
    dict
        Keys: ``gamma, reward_scale, sigma_reading, sigma, policy_std, state_bound,
        per_dimension, horizon`` (None = infinite), ``clipped, point, theta_11, theta_star, J, se``
        (``se`` is the Monte Carlo standard error, 0 for exact values; ``theta_star`` is
        NaN for the clipped simulator, whose optimum is not computed here).
    """
    grid = grid or SettingsGrid()
    rng = np.random.default_rng(grid.seed)
    for gamma in grid.gammas:
        for reading in grid.sigma_readings:
            for sigma in grid.sigmas:
                std = _policy_std(sigma, reading)
                for bound in grid.state_bounds:
                    yield from _exact_rows(grid, gamma, reading, sigma, std, bound)
                    yield from _clipped_rows(grid, gamma, reading, sigma, std, bound, rng)


def _rows(base: dict[str, Any], J_summed: float, se: float, grid: SettingsGrid) -> Iterator[dict[str, Any]]:
    for scale in grid.reward_scales:
        for per_dim in grid.per_dimension:
            k = 2 * scale / (2 if per_dim else 1)  # values were computed at scale 0.5, summed
            yield {**base, "reward_scale": scale, "per_dimension": per_dim, "J": k * J_summed, "se": k * se}


def _exact_rows(grid: SettingsGrid, gamma: float, reading: str, sigma: float, std: float,
                bound: float) -> Iterator[dict[str, Any]]:
    base_env = _env(gamma, 0.5, bound, None, clip=False)
    for H in grid.horizons:
        if H is None:
            t_star = float(base_env.optimal_gain()[0, 0])
        else:
            t_star = finite_horizon_optimal_gain(base_env, std, H)
        for point in grid.points:
            K = t_star * np.eye(2) if point == "optimum" else FIXED_POINTS[point]
            if H is None:
                J = base_env.performance(K, std)
            else:
                J = finite_horizon_performance(base_env, K, std, H)
            base = dict(gamma=gamma, sigma_reading=reading, sigma=sigma, policy_std=std, state_bound=bound,
                        horizon=H, clipped=False, point=point, theta_11=float(K[0, 0]), theta_star=t_star)
            yield from _rows(base, J, 0.0, grid)


def _clipped_rows(grid: SettingsGrid, gamma: float, reading: str, sigma: float, std: float, bound: float,
                  rng: np.random.Generator) -> Iterator[dict[str, Any]]:
    for H in grid.clipped_horizons:
        env = _env(gamma, 0.5, bound, H, clip=True)
        for point in grid.points:
            if point == "optimum":
                continue  # the clipped optimum needs a noisy search; not enumerated
            K = FIXED_POINTS[point]
            mean, se = measured_return(env, K, std, grid.mc_trajectories, rng)
            base = dict(gamma=gamma, sigma_reading=reading, sigma=sigma, policy_std=std, state_bound=bound,
                        horizon=H, clipped=True, point=point, theta_11=float(K[0, 0]), theta_star=float("nan"))
            yield from _rows(base, mean, se, grid)


def clipped_return_bound(gamma: float, horizon: int, reward_bound: float) -> float:
    r"""Largest possible :math:`|J_H|` of the clipped simulator: :math:`R_{\max}(1-\gamma^H)/(1-\gamma)`."""
    _check_horizon(horizon)
    return float(reward_bound * (1 - gamma**horizon) / (1 - gamma))


def search_printed_settings(
    grid: SettingsGrid | None = None,
    theta_target: float = PRINTED_THETA_STAR,
    J_target: float = PRINTED_J_STAR,
    rel_tol: float = 1e-3,
    rows: Sequence[dict[str, Any]] | None = None,
) -> list[dict[str, Any]]:
    """Candidate settings reproducing a printed theta* or J within ``rel_tol``.

    A row matches ``theta_target`` if its own optimum ``theta_star`` is within
    ``rel_tol`` (relative) of it, and matches ``J_target`` if its ``J`` is within
    ``rel_tol`` of it (for Monte Carlo rows, or within 4 standard errors). A setting's
    theta* does not depend on the point, the reward scale or the summation, so theta
    matches are reported once per (gamma, sigma reading, state range, horizon).

    Parameters
    ----------
    grid : SettingsGrid, optional
        What to enumerate (default :class:`SettingsGrid()`).
    theta_target, J_target : float
        The printed numbers (Section 5.2.1 by default).
    rel_tol : float
        Relative tolerance (1e-3 = 0.1%).
    rows : sequence of dict, optional
        Precomputed :func:`candidate_settings` rows (to search several targets at once).

    Returns
    -------
    list of dict
        The matching rows, each with ``quantity`` ("theta_star" or "J"), ``target``,
        ``value`` and ``rel_error`` added; sorted by relative error.
    """
    if not rel_tol > 0:
        raise ValueError(f"rel_tol must be > 0, got {rel_tol}")
    rows = list(candidate_settings(grid)) if rows is None else rows
    out: list[dict[str, Any]] = []
    seen: set[tuple[Any, ...]] = set()
    for row in rows:
        t = row["theta_star"]
        key = (row["gamma"], row["policy_std"], row["state_bound"], row["horizon"], row["clipped"])
        if np.isfinite(t) and key not in seen and abs(t - theta_target) <= rel_tol * abs(theta_target):
            seen.add(key)
            out.append({**row, "quantity": "theta_star", "target": theta_target, "value": t,
                        "rel_error": abs(t - theta_target) / abs(theta_target)})
        J = row["J"]
        tol = max(rel_tol * abs(J_target), 4 * row["se"])
        if np.isfinite(J) and abs(J - J_target) <= tol:
            out.append({**row, "quantity": "J", "target": J_target, "value": J,
                        "rel_error": abs(J - J_target) / abs(J_target)})
    return sorted(out, key=lambda r: (r["quantity"], r["rel_error"]))



# ----------------------------------------------------------- the lab library's closed form
#: Initial states listed in the lab library's 2-D LQG (teopir/ifqi, ``ifqi/envs/lqgnd.py``):
#: (x, 0) for x = 1, 2, 5, 7, 10. Read only to evaluate one more reading of J.
LAB_INITIAL_STATES = np.array([[1.0, 0.0], [2.0, 0.0], [5.0, 0.0], [7.0, 0.0], [10.0, 0.0]])


def lab_value_matrix(theta: np.ndarray, weight: float, gamma: float) -> np.ndarray:
    r"""P as the authors' lab library computes it for A = B = I and Q = R = ``weight`` I.

    .. math:: P = (Q + K^\top R K)\,\big(I - \gamma(I + 2K + K\circ K)\big)^{-1}

    with :math:`K\circ K` the *elementwise* square (the library writes ``K ** 2``). For a
    diagonal K this is the exact discounted Lyapunov solution; otherwise it is not.
    The library's reward has no 1/2: cost :math:`s^\top Qs + a^\top Ra`, so
    ``weight = 0.5`` is the thesis's reward and 0.9 the library's default.
    """
    K = np.atleast_2d(np.asarray(theta, dtype=float))
    m = K.shape[0]
    if K.shape != (m, m):
        raise ValueError(f"theta must be a square gain matrix, got shape {K.shape}")
    if not 0 < gamma < 1:
        raise ValueError(f"gamma must be in (0, 1), got {gamma}")
    if not weight > 0:
        raise ValueError(f"weight must be > 0, got {weight}")
    eye, mm = np.eye(m), portable.matmul  # fixed order: these values are printed (safepg.portable)
    return mm(weight * eye + weight * mm(K.T, K), portable.solve(eye - gamma * (eye + 2 * K + K * K), eye))


def lab_performance_moments(theta: np.ndarray, noise_cov: float | np.ndarray, weight: float, gamma: float,
                            state_bound: float, n_x0: int = 100) -> tuple[float, float]:
    r"""Mean and standard deviation of the lab library's Monte Carlo J.

    The library's ``computeJ`` returns

    .. math:: J = -\frac1{n}\sum_{i=1}^{n} x_i^\top P x_i
              - \frac{\operatorname{tr}\big(\Sigma (R + \gamma P)\big)}{1-\gamma},
              \qquad x_i \sim \mathcal U([-b, b]^m)

    with n = 100 fresh initial states per call, so it is a random number. Its exact mean
    and standard deviation follow from :math:`\mathbb E[x_i^2] = b^2/3` and
    :math:`\operatorname{Var}[x_i^2] = 4b^4/45` (independent coordinates).

    Parameters
    ----------
    theta : ndarray (m, m)
        Gain K.
    noise_cov : float or ndarray
        :math:`\Sigma`, what the library receives as the action noise's covariance (a
        scalar means that multiple of I: the library passes sigma itself there).
    weight, gamma : float
        Q = R = weight I, and the discount.
    state_bound : float
        b, the half-width of the initial-state box (2 in the thesis, 10 in the library).
    n_x0 : int
        Initial states per call (100 in the library).
    """
    if int(n_x0) != n_x0 or n_x0 < 1:
        raise ValueError(f"n_x0 must be a positive integer, got {n_x0}")
    if not state_bound > 0:
        raise ValueError(f"state_bound must be > 0, got {state_bound}")
    P = lab_value_matrix(theta, weight, gamma)
    m = P.shape[0]
    S = np.eye(m) * noise_cov if np.ndim(noise_cov) == 0 else np.asarray(noise_cov, dtype=float)
    W = float(portable.trace(portable.matmul(S, weight * np.eye(m) + gamma * P))) / (1 - gamma)
    b2 = state_bound**2
    mean = -float(np.trace(P)) * b2 / 3 - W
    off = P + P.T
    var = np.sum(np.diag(P) ** 2) * 4 * b2**2 / 45 + np.sum(np.triu(off, 1) ** 2) * (b2 / 3) ** 2
    return mean, float(np.sqrt(var / n_x0))


def lab_performance_at_states(theta: np.ndarray, noise_cov: float | np.ndarray, weight: float, gamma: float,
                              states: np.ndarray = LAB_INITIAL_STATES) -> float:
    """The lab library's J averaged over a fixed list of initial states (its ``initial_states``)."""
    P = lab_value_matrix(theta, weight, gamma)
    m = P.shape[0]
    S = np.eye(m) * noise_cov if np.ndim(noise_cov) == 0 else np.asarray(noise_cov, dtype=float)
    W = float(portable.trace(portable.matmul(S, weight * np.eye(m) + gamma * P))) / (1 - gamma)
    x = np.asarray(states, dtype=float)
    return float(-np.mean(np.sum(portable.matmul(x, P) * x, axis=1)) - W)


def lab_readings(
    gammas: Sequence[float] = (0.9, 0.95, 0.99),
    weights: Sequence[float] = (0.5, 0.9, 1.0),
    state_bounds: Sequence[float] = (2.0, 10.0),
    sigma: float = 1.0,
    target: float = PRINTED_J_STAR,
) -> list[dict[str, Any]]:
    """J(theta) of the 2-D task under the lab library's closed form, for every reading.

    Enumerates the discount (the thesis's 0.95, the 0.9 that reproduces theta*, the
    library's 0.99), Q = R = weight I (0.5: the thesis's reward; 0.9: the library's; 1:
    the thesis's Q = R = I without the 1/2), the initial-state box (the thesis's 2, the
    library's 10), sigma or sigma^2 as the noise covariance, and the point: the printed
    theta* = diag(-0.588), the setting's own optimum, and 0. Each row gives the mean and
    standard deviation of the library's Monte Carlo J (100 initial states), its distance to
    ``target`` in standard deviations (``z``), and J over the library's fixed initial states.
    """
    rows = []
    for gamma in gammas:
        k_star = float(LQG(dim=2, gamma=gamma, clip=False).optimal_gain()[0, 0])
        for point, k in (("printed theta*", PRINTED_THETA_STAR), ("own optimum", k_star), ("zero", 0.0)):
            K = k * np.eye(2)
            for weight in weights:
                for cov_name, cov in (("sigma^2", sigma**2), ("sigma", sigma)):
                    if cov_name == "sigma" and sigma == 1.0:
                        continue  # identical to sigma^2 at the printed sigma = 1
                    fixed = lab_performance_at_states(K, cov, weight, gamma)
                    for b in state_bounds:
                        mean, sd = lab_performance_moments(K, cov, weight, gamma, b)
                        rows.append({"gamma": gamma, "point": point, "theta_11": k, "weight": weight, "cov": cov_name,
                                     "state_bound": b, "J_mean": mean, "J_sd": sd, "z": (target - mean) / sd,
                                     "J_fixed_states": fixed})
    return sorted(rows, key=lambda r: abs(r["z"]))


__all__ = [
    "FIXED_POINTS",
    "LAB_INITIAL_STATES",
    "PRINTED_FINAL_COORDINATE",
    "PRINTED_FINAL_SCALAR",
    "PRINTED_J_STAR",
    "PRINTED_THETA_STAR",
    "PRINTED_UPSILON",
    "SettingsGrid",
    "candidate_settings",
    "clipped_return_bound",
    "expected_rewards",
    "finite_horizon_optimal_gain",
    "finite_horizon_performance",
    "horizon_matching_value",
    "lab_performance_at_states",
    "lab_performance_moments",
    "lab_readings",
    "lab_value_matrix",
    "measured_return",
    "search_printed_settings",
    "second_moments",
]
