r"""Numeric checks of the inequality lemmas of Appendices A and B (and Lemma 4.3.3).

Each ``check_*`` function evaluates an inequality ``lhs <= rhs`` over a grid and/or
random (plus adversarial) draws and returns a :class:`CheckResult` whose
``max_violation`` is the largest ``(lhs - rhs) / scale`` seen: ``<= 0`` means the
inequality held on every draw, ``> 0`` is a counterexample. ``scale`` is the
printed bound's scale (stated in each docstring), so violations are comparable
across draws. Constants can be deliberately broken (``constant=...``) to show that
a check is able to fail.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, overload

import numpy as np
from scipy import integrate

from safepg.estimators import check_estimator
from safepg.rng import RNGLike, as_generator

__all__ = [
    "CheckResult",
    "check_lemma_4_3_3",
    "check_lemma_a01_hessian",
    "check_lemma_a01_taylor",
    "check_lemma_a02",
    "check_lemma_b03",
    "check_lemma_b05",
    "gaussian_hessian",
    "gaussian_pdf",
    "gaussian_second_derivative_shape",
    "softmax_hessian",
    "softmax_probs",
]

SQRT_2PI = math.sqrt(2 * math.pi)
#: Violations up to this (relative) size are floating-point noise.
TOL = 1e-9


@dataclass(frozen=True)
class CheckResult:
    """Outcome of a numeric inequality check.

    Attributes
    ----------
    name : str
        Which inequality (thesis label).
    max_violation : float
        Largest normalised ``lhs - rhs`` over all draws; ``<= 0`` (up to :data:`TOL`) means it holds.
    n_draws : int
    details : dict
        Check-specific diagnostics (worst draw, cross-checks, tight ratios).
    """

    name: str
    max_violation: float
    n_draws: int
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def holds(self) -> bool:
        """True if no draw violated the inequality (beyond :data:`TOL`)."""
        return self.max_violation <= TOL


# --------------------------------------------------------------------------- Gaussian policy
@overload
def gaussian_pdf(a: float, mean: float, sigma: float) -> float: ...


@overload
def gaussian_pdf(a: np.ndarray | float, mean: np.ndarray | float, sigma: np.ndarray | float) -> np.ndarray | float: ...


def gaussian_pdf(a: np.ndarray | float, mean: np.ndarray | float, sigma: np.ndarray | float) -> np.ndarray | float:
    r""":math:`\mathcal N(a; \mu, \sigma^2)`, elementwise (a float for floats)."""
    z = (a - mean) / sigma
    return np.exp(-0.5 * z**2) / (SQRT_2PI * sigma)


def gaussian_second_derivative_shape(z: np.ndarray) -> np.ndarray:
    r""":math:`(z^2 - 1)e^{-z^2/2}/\sqrt{2\pi}`, i.e.
    :math:`\sigma^3\,\partial^2\pi/\partial\theta_i\partial\theta_j / (\varphi_i\varphi_j)`."""
    z = np.asarray(z, dtype=float)
    return (z**2 - 1) * np.exp(-0.5 * z**2) / SQRT_2PI


def gaussian_hessian(a: float, theta: np.ndarray, phi: np.ndarray, sigma: float) -> np.ndarray:
    r"""Hessian in :math:`\theta` of :math:`\mathcal N(a; \theta^T\varphi, \sigma^2)`, shape (m, m).

    .. math:: \partial^2_{ij}\pi = \pi\,\Big(\frac{(a-\mu)^2}{\sigma^4} - \frac{1}{\sigma^2}\Big)\varphi_i\varphi_j
    """
    mean = float(theta @ phi)
    p = gaussian_pdf(a, mean, sigma)
    return p * ((a - mean) ** 2 / sigma**4 - 1 / sigma**2) * np.outer(phi, phi)


def _fd_hessian(fun: Any, theta: np.ndarray, h: float) -> np.ndarray:
    m = theta.size
    out = np.empty((m, m))
    eye = np.eye(m) * h
    for i in range(m):
        for j in range(m):
            out[i, j] = (
                fun(theta + eye[i] + eye[j])
                - fun(theta + eye[i] - eye[j])
                - fun(theta - eye[i] + eye[j])
                + fun(theta - eye[i] - eye[j])
            ) / (4 * h * h)
    return out


def check_lemma_a01_hessian(
    rng: RNGLike = 0,
    n_draws: int = 2000,
    m: int = 3,
    m_phi: float = 2.0,
    constant: float = 1.0,
    sigma_power: float = 3.0,
    sigma_range: tuple[float, float] = (0.2, 3.0),
    n_grid: int = 20001,
) -> CheckResult:
    r"""Lemma A.0.1 (via Lemma 4.1 of Pirotta et al. (2013)):
    :math:`|\partial^2\pi/\partial\theta_i\partial\theta_j| \le |\varphi_i\varphi_j|/(\sqrt{2\pi}\sigma^3)`.

    Checked (i) on a grid of :math:`z = (a-\mu)/\sigma \in [-10, 10]` (the sup of
    :math:`|(z^2-1)e^{-z^2/2}|/\sqrt{2\pi}` is :math:`1/\sqrt{2\pi}`, at z = 0) and (ii) on random
    :math:`(\theta, \varphi, a, \sigma)` with the analytic Hessian (cross-checked against
    finite differences of the density on a few draws). A quarter of the draws put
    the action at the mean, where the bound is attained.

    Parameters
    ----------
    rng : Generator, int or None
    n_draws, m : int
        Number of random draws and parameter dimension.
    m_phi : float
        Features are drawn in :math:`[-M_\varphi, M_\varphi]`.
    constant, sigma_power : float
        The bound tested is ``constant * |phi_i phi_j| / (sqrt(2 pi) sigma**sigma_power)``
        (printed: 1 and 3). A smaller constant, or power 2 with :math:`\sigma < 1`, fails.
    sigma_range : (float, float)
    n_grid : int

    Returns
    -------
    CheckResult
        Violation :math:`(|\partial^2_{ij}\pi| - \text{bound}_{ij})` divided by the printed bound
        :math:`|\varphi_i\varphi_j|/(\sqrt{2\pi}\sigma^3)`.
    """
    gen = as_generator(rng)
    z = np.linspace(-10, 10, n_grid)
    shape = np.abs(gaussian_second_derivative_shape(z))
    grid_max, grid_arg = float(shape.max()), float(z[np.argmax(shape)])

    worst, worst_draw, fd_err = -np.inf, None, 0.0
    for k in range(n_draws):
        sigma = gen.uniform(*sigma_range)
        theta = gen.normal(size=m)
        phi = gen.uniform(-m_phi, m_phi, size=m)
        mean = float(theta @ phi)
        a = mean if k % 4 == 0 else mean + sigma * gen.normal(scale=2.0)
        hess = gaussian_hessian(a, theta, phi, sigma)
        scale = np.abs(np.outer(phi, phi)) / (SQRT_2PI * sigma**3)
        bound = constant * np.abs(np.outer(phi, phi)) / (SQRT_2PI * sigma**sigma_power)
        v = float(np.max((np.abs(hess) - bound) / scale))
        if v > worst:
            worst, worst_draw = v, {"sigma": sigma, "z": (a - mean) / sigma}
        if k < 20:
            fd = _fd_hessian(lambda t, a=a, phi=phi, s=sigma: gaussian_pdf(a, t @ phi, s), theta, 1e-4 * sigma)
            fd_err = max(fd_err, float(np.max(np.abs(fd - hess)) / np.max(scale)))
    # the grid check is sigma-free only for the printed power sigma^3
    grid_violation = grid_max * SQRT_2PI - constant if sigma_power == 3.0 else -np.inf
    return CheckResult(
        "Lemma A.0.1: |d2 pi / dtheta_i dtheta_j| <= |phi_i phi_j| / (sqrt(2 pi) sigma^3)",
        max(worst, grid_violation),
        n_draws,
        {
            "grid_sup_shape": grid_max,
            "grid_argmax_z": grid_arg,
            "sup_shape_exact": 1 / SQRT_2PI,
            "worst_draw": worst_draw,
            "fd_max_rel_error": fd_err,
        },
    )


def check_lemma_a01_taylor(
    rng: RNGLike = 0,
    n_draws: int = 4000,
    m: int = 3,
    m_phi: float = 2.0,
    constant: float = 1.0,
    step_scale: float = 0.05,
) -> CheckResult:
    r"""Lemma A.0.1's statement:
    :math:`\pi_{\theta'} - \pi_\theta - \nabla\pi^T\Delta\theta
    \ge -\text{constant}\cdot M_\varphi^2\|\Delta\theta\|_1^2/(\sqrt{2\pi}\sigma^3)`.

    The printed constant is 1; the correct Taylor remainder (weight 1/2, see
    :func:`safepg.theory.taylor_remainder_weights`) gives 1/2, which is tight: half the
    draws are adversarial (:math:`\varphi_i = M_\varphi\,\mathrm{sign}(\Delta\theta_i)`, action at
    the mean, small step), where the remainder approaches
    :math:`-\frac12 M_\varphi^2\|\Delta\theta\|_1^2/(\sqrt{2\pi}\sigma^3)`. A constant below 1/2 fails.

    Returns
    -------
    CheckResult
        Violation :math:`(-R_1 - \text{constant}\cdot B)/B` with
        :math:`B = M_\varphi^2\|\Delta\theta\|_1^2/(\sqrt{2\pi}\sigma^3)`; ``details["worst_ratio"]`` is
        :math:`\max(-R_1/B)` (close to 1/2).
    """
    gen = as_generator(rng)
    worst, worst_ratio = -np.inf, -np.inf
    for k in range(n_draws):
        sigma = gen.uniform(0.3, 2.0)
        theta = gen.normal(size=m)
        dtheta = gen.normal(size=m) * step_scale * sigma / m_phi
        if k % 2 == 0:
            phi = m_phi * np.sign(dtheta)
            a = float(theta @ phi)
        else:
            phi = gen.uniform(-m_phi, m_phi, size=m)
            a = float(theta @ phi) + sigma * gen.normal()
        mean = float(theta @ phi)
        p0 = gaussian_pdf(a, mean, sigma)
        grad = p0 * (a - mean) / sigma**2 * phi
        remainder = gaussian_pdf(a, float((theta + dtheta) @ phi), sigma) - p0 - grad @ dtheta
        scale = m_phi**2 * np.sum(np.abs(dtheta)) ** 2 / (SQRT_2PI * sigma**3)
        worst = max(worst, (-remainder - constant * scale) / scale)
        worst_ratio = max(worst_ratio, -remainder / scale)
    return CheckResult(
        "Lemma A.0.1: pi' - pi >= grad pi^T dtheta - M^2 ||dtheta||_1^2 / (sqrt(2 pi) sigma^3)",
        float(worst),
        n_draws,
        {"constant": constant, "worst_ratio": float(worst_ratio)},
    )


def _l1_distance(mu1: float, mu2: float, sigma: float) -> float:
    mid = 0.5 * (mu1 + mu2)
    span = abs(mu1 - mu2) + 12 * sigma

    def integrand(a: float) -> float:
        return abs(gaussian_pdf(a, mu1, sigma) - gaussian_pdf(a, mu2, sigma))

    left, _ = integrate.quad(integrand, mid - span, mid, limit=200)
    right, _ = integrate.quad(integrand, mid, mid + span, limit=200)
    return left + right


def _kl_numeric(mu1: float, mu2: float, sigma: float) -> float:
    def integrand(a: float) -> float:
        p = gaussian_pdf(a, mu1, sigma)
        # log p/q in closed form avoids log(0) in the tails
        return p * (((a - mu2) ** 2 - (a - mu1) ** 2) / (2 * sigma**2))

    span = abs(mu1 - mu2) + 12 * sigma
    val, _ = integrate.quad(integrand, mu1 - span, mu1 + span, limit=200)
    return val


def check_lemma_a02(
    rng: RNGLike = 0,
    n_draws: int = 40,
    m: int = 3,
    m_phi: float = 2.0,
    direction: str = "<=",
) -> CheckResult:
    r"""Lemma A.0.2 via Pinsker:
    :math:`\|\pi_{\theta'}-\pi_\theta\|_1^2 \le 2KL = (\Delta\theta^T\varphi)^2/\sigma^2
    \le M_\varphi^2\|\Delta\theta\|_1^2/\sigma^2`.

    The L1 distance and the KL divergence are integrated numerically (scipy
    ``quad``); KL is compared with :math:`(\mu_1-\mu_2)^2/(2\sigma^2)`.

    Parameters
    ----------
    direction : {"<=", ">="}
        ``"<="`` checks Pinsker's direction (holds); ``">="`` the printed proof's
        :math:`\|\pi'-\pi\|^2 \geqslant 2H(\pi'\|\pi)` (fails on every draw).

    Returns
    -------
    CheckResult
        Violation of :math:`L_1^2 \le 2KL` (or its reverse) relative to :math:`2KL`.
        ``details`` has ``statement_violation`` (the lemma's final bound, relative to
        it), ``kl_max_rel_error`` (numeric vs closed form) and
        ``sum_of_squares_max_rel_gap`` (how far the printed
        :math:`\sum_i(\Delta\theta_i\varphi_i)^2/\sigma^2` is from :math:`2KL`).
    """
    if direction not in ("<=", ">="):
        raise ValueError(f"direction must be '<=' or '>=', got {direction!r}")
    gen = as_generator(rng)
    worst = -np.inf
    statement, kl_err, sos_gap = -np.inf, 0.0, 0.0
    for _ in range(n_draws):
        sigma = gen.uniform(0.3, 2.0)
        theta = gen.normal(size=m)
        dtheta = gen.normal(size=m) * gen.choice([0.01, 0.1, 1.0]) * sigma / m_phi
        phi = gen.uniform(-m_phi, m_phi, size=m)
        mu1, mu2 = float((theta + dtheta) @ phi), float(theta @ phi)
        l1 = _l1_distance(mu1, mu2, sigma)
        kl = _kl_numeric(mu1, mu2, sigma)
        kl_exact = (mu1 - mu2) ** 2 / (2 * sigma**2)
        kl_err = max(kl_err, abs(kl - kl_exact) / kl_exact)
        gap = l1**2 - 2 * kl_exact
        worst = max(worst, (gap if direction == "<=" else -gap) / (2 * kl_exact))
        bound = m_phi**2 * np.sum(np.abs(dtheta)) ** 2 / sigma**2
        statement = max(statement, (l1**2 - bound) / bound)
        sos = np.sum((dtheta * phi) ** 2) / sigma**2
        sos_gap = max(sos_gap, abs(sos - 2 * kl_exact) / (2 * kl_exact))
    return CheckResult(
        f"Lemma A.0.2 (Pinsker): ||pi' - pi||_1^2 {direction} 2 KL",
        float(worst),
        n_draws,
        {
            "statement_violation": float(statement),
            "kl_max_rel_error": kl_err,
            "sum_of_squares_max_rel_gap": float(sos_gap),
        },
    )


# --------------------------------------------------------------------------- softmax policy
def softmax_probs(theta: np.ndarray, features: np.ndarray) -> np.ndarray:
    r""":math:`\pi(a) \propto \exp(\theta^T\varphi(s, a))`; ``features`` has shape (n_actions, m)."""
    logits = features @ theta
    w = np.exp(logits - logits.max())
    return w / w.sum()


def softmax_hessian(theta: np.ndarray, features: np.ndarray) -> np.ndarray:
    r"""Hessians :math:`\partial^2\pi(a)/\partial\theta_i\partial\theta_j` for every action, shape (n_actions, m, m).

    As in the proof of Lemma B.0.3:
    :math:`\pi(a)\big(\varphi_i\varphi_j - \varphi_i\bar\varphi_j - \varphi_j\bar\varphi_i + 2\bar\varphi_i\bar\varphi_j
    - E_\pi[\varphi_i\varphi_j]\big)`, with :math:`\bar\varphi = E_\pi[\varphi]`.
    """
    p = softmax_probs(theta, features)
    mean = p @ features
    second = np.einsum("a,ai,aj->ij", p, features, features)
    outer = np.einsum("ai,aj->aij", features, features)
    cross = np.einsum("ai,j->aij", features, mean) + np.einsum("aj,i->aij", features, mean)
    return p[:, None, None] * (outer - cross + 2 * np.outer(mean, mean)[None] - second[None])


def check_lemma_b03(
    rng: RNGLike = 0,
    n_draws: int = 2000,
    n_actions: int = 4,
    m: int = 3,
    m_phi: float = 1.5,
    constant: float = 6.0,
) -> CheckResult:
    r"""Lemma B.0.3 (softmax policies):
    :math:`|\partial^2\pi_\theta(a|s)/\partial\theta_i\partial\theta_j| \le 6M_\varphi^2`.

    Random policies (features in :math:`[-M_\varphi, M_\varphi]^m`, random :math:`\theta`) plus
    adversarial two-action draws (features :math:`\pm M_\varphi`, logit gap chosen to
    maximise :math:`|\sigma''|`, where :math:`|\partial^2\pi| = 4M_\varphi^2\cdot\sqrt3/18 \approx 0.385M_\varphi^2`).
    The analytic Hessian is cross-checked against finite differences.

    Parameters
    ----------
    constant : float
        Bound tested is ``constant * M_phi**2`` (printed 6). Any constant below
        ~0.385 fails.

    Returns
    -------
    CheckResult
        Violation :math:`(\max|\partial^2\pi| - \text{constant}\,M_\varphi^2)/M_\varphi^2`;
        ``details["max_ratio"]`` is :math:`\max|\partial^2\pi|/M_\varphi^2`.
    """
    gen = as_generator(rng)
    max_abs, fd_err = 0.0, 0.0
    # adversarial two-action case: pi_1 = sigmoid(2 M theta), |d2 pi_1| = 4 M^2 |s (1 - s)(1 - 2 s)|,
    # maximal at s = (3 - sqrt 3) / 6
    s_star = (3 - math.sqrt(3)) / 6
    t_star = math.log(s_star / (1 - s_star)) / (2 * m_phi)
    adv = softmax_hessian(np.array([t_star]), np.array([[m_phi], [-m_phi]]))
    max_abs = float(np.max(np.abs(adv)))
    for k in range(n_draws):
        features = gen.uniform(-m_phi, m_phi, size=(n_actions, m))
        if k % 3 == 0:
            features = m_phi * np.sign(features)
        theta = gen.normal(size=m) * gen.choice([0.1, 1.0, 3.0]) / m_phi
        hess = softmax_hessian(theta, features)
        max_abs = max(max_abs, float(np.max(np.abs(hess))))
        if k < 10:
            for a in range(n_actions):
                fd = _fd_hessian(lambda t, a=a, F=features: softmax_probs(t, F)[a], theta, 1e-4)
                fd_err = max(fd_err, float(np.max(np.abs(fd - hess[a]))))
    return CheckResult(
        "Lemma B.0.3: |d2 pi / dtheta_i dtheta_j| <= 6 M_phi^2 (softmax)",
        (max_abs - constant * m_phi**2) / m_phi**2,
        n_draws + 1,
        {
            "max_ratio": max_abs / m_phi**2,
            "adversarial_ratio": float(np.max(np.abs(adv))) / m_phi**2,
            "fd_max_abs_error": fd_err,
        },
    )


def check_lemma_b05(
    rng: RNGLike = 0,
    n_draws: int = 2000,
    n_actions: int = 4,
    m: int = 3,
    m_phi: float = 1.5,
    constant: float = 4.0,
) -> CheckResult:
    r"""Lemma B.0.5 (softmax policies):
    :math:`\|\pi_{\theta'} - \pi_\theta\|_1^2 \le 2KL(\pi_{\theta'}\|\pi_\theta) \le 4M_\varphi\|\Delta\theta\|_1`.

    Returns
    -------
    CheckResult
        Violation :math:`(\|\pi'-\pi\|_1^2 - \text{constant}\,M_\varphi\|\Delta\theta\|_1)`
        divided by :math:`4M_\varphi\|\Delta\theta\|_1`;
        ``details["kl_violation"]`` is the same for :math:`KL \le 2M_\varphi\|\Delta\theta\|_1` and
        ``details["pinsker_violation"]`` for :math:`\|\pi'-\pi\|_1^2 \le 2KL` (relative to 2KL).
    """
    gen = as_generator(rng)
    worst, kl_worst, pinsker_worst = -np.inf, -np.inf, -np.inf
    for _ in range(n_draws):
        features = gen.uniform(-m_phi, m_phi, size=(n_actions, m))
        theta = gen.normal(size=m)
        dtheta = gen.normal(size=m) * gen.choice([0.01, 0.3, 3.0])
        p, q = softmax_probs(theta + dtheta, features), softmax_probs(theta, features)
        kl = float(np.sum(p * np.log(p / q)))
        l1 = float(np.sum(np.abs(p - q)))
        scale = 4 * m_phi * np.sum(np.abs(dtheta))
        worst = max(worst, (l1**2 - constant * m_phi * np.sum(np.abs(dtheta))) / scale)
        kl_worst = max(kl_worst, (kl - scale / 2) / scale)
        if kl > 1e-12:
            pinsker_worst = max(pinsker_worst, (l1**2 - 2 * kl) / (2 * kl))
    return CheckResult(
        "Lemma B.0.5: ||pi' - pi||_1^2 <= 4 M_phi ||dtheta||_1 (softmax)",
        float(worst),
        n_draws,
        {"kl_violation": float(kl_worst), "pinsker_violation": float(pinsker_worst)},
    )


# --------------------------------------------------------------------------- Lemma 4.3.3
def check_lemma_4_3_3(
    horizon: int = 20,
    gamma: float = 0.9,
    sigma: float = 1.0,
    m_phi: float = 2.0,
    a_bar: float = 2.0,
    r_max: float = 4.0,
    mean: float = 1.0,
    estimator: str = "reinforce",
    eta: float = 1e-9,
) -> CheckResult:
    r"""Lemma 4.3.3 against a worst-case construction (no baseline).

    A one-state MDP with feature :math:`\varphi = M_\varphi`, policy mean
    :math:`\mu = \theta M_\varphi` (= ``mean``) and a reward :math:`r(a) \in [-R, R]`. Trajectory 1
    plays the end of :math:`[-\bar A, \bar A]` farthest from :math:`\mu` for H steps, with reward
    :math:`R` times the sign of :math:`a - \mu`; trajectory 2 plays an action :math:`\eta` inside it,
    with the opposite reward (r may be any function of a with :math:`|r| \le R`). The
    per-trajectory REINFORCE (or G(PO)MDP) sample of component 1 is computed from
    the estimator's formula; the range of the two samples tends to
    :math:`2HM_\varphi(\bar A+|\mu|)R(1-\gamma^H)/(\sigma^2(1-\gamma))` (REINFORCE), above the printed
    :math:`2HM_\varphi\bar AR/(\sigma^2(1-\gamma))` when :math:`(1-\gamma^H)(1+|\mu|/\bar A) > 1`.

    Returns
    -------
    CheckResult
        Violation (range - printed bound) / printed bound (``> 0``: the lemma fails).
    """
    check_estimator(estimator)
    disc = gamma ** np.arange(horizon)  # gamma^(l-1), l = 1..H

    def sample(action: float, reward: float) -> float:
        score = (action - mean) * m_phi / sigma**2 * np.ones(horizon)
        rewards = reward * np.ones(horizon)
        if estimator == "reinforce":
            return float(score.sum() * (disc @ rewards))
        to_go = np.cumsum((disc * rewards)[::-1])[::-1]  # sum_{l >= k} gamma^(l-1) r_l
        return float(score @ to_go)

    # the action-space end farther from the mean, and a neighbour just inside it
    end = -a_bar if mean >= 0 else a_bar
    sign = float(np.sign(end - mean))
    s1 = sample(end, r_max * sign)  # score and reward of equal sign: large positive sample
    s2 = sample(end - sign * eta, -r_max * sign)  # opposite reward: large negative sample
    rng_ = abs(s1 - s2)
    printed = 2 * horizon * m_phi * a_bar * r_max / (sigma**2 * (1 - gamma))
    return CheckResult(
        f"Lemma 4.3.3 ({estimator}): range <= 2 H M_phi A_bar R / (sigma^2 (1 - gamma))",
        (rng_ - printed) / printed,
        2,
        {
            "range": rng_,
            "printed_bound": printed,
            "samples": (s1, s2),
            "predicted_ratio_reinforce": (1 - gamma**horizon) * (1 + abs(mean) / a_bar),
        },
    )
