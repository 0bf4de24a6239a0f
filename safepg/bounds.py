r"""Concentration bounds on the per-component gradient estimation error (Section 4.3).

Every bound is written as

.. math:: \epsilon(N) = \frac{d_\delta}{\sqrt N} + \frac{f_\delta}{N},

with f = 0 for Chebyshev and Hoeffding (Assumption 4.3.1) and f > 0 for the
empirical Bernstein bound (Section 4.3.3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from safepg import portable
from safepg.constants import TaskConstants

Bound = Literal["chebyshev", "hoeffding", "bernstein"]
BOUNDS: tuple[Bound, ...] = ("chebyshev", "hoeffding", "bernstein")
#: The gradient's range in Hoeffding's and Bernstein's bounds: ``"lemma"`` (Lemma 4.3.3's
#: bound), ``"empirical"`` (the batch's max - min) or a number.
Range = Literal["lemma", "empirical"] | float


def check_range(range: Range) -> Range:
    """Raise ``ValueError("range ...")`` unless ``range`` is "lemma", "empirical" or a finite number > 0."""
    if isinstance(range, str):
        if range not in ("lemma", "empirical"):
            raise ValueError(f"range must be 'lemma', 'empirical' or a finite number > 0, got {range!r}")
        return range
    if isinstance(range, bool) or not isinstance(range, int | float | np.floating | np.integer) or not (
            np.isfinite(range) and range > 0):
        raise ValueError(f"range must be 'lemma', 'empirical' or a finite number > 0, got {range!r}")
    return float(range)


def check_delta(delta: float) -> float:
    """Validate the worsening probability delta in (0, 1)."""
    if not (isinstance(delta, (int, float, np.floating)) and 0 < delta < 1):
        raise ValueError(f"delta must be in (0, 1), got {delta!r}")
    return float(delta)


@dataclass(frozen=True)
class ErrorBound:
    r"""A bound on the estimation error as a function of the batch size,
    :math:`\epsilon(N) = d_\delta/\sqrt N + f_\delta/N` (Assumption 4.3.1).

    Parameters
    ----------
    d : float
        The coefficient of :math:`1/\sqrt N`, >= 0.
    f : float
        The coefficient of :math:`1/N`, >= 0 (zero for Chebyshev and Hoeffding, positive for
        the empirical Bernstein bound).
    """

    d: float
    f: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.d) and self.d >= 0):
            raise ValueError(f"d must be finite and >= 0, got {self.d}")
        if not (np.isfinite(self.f) and self.f >= 0):
            raise ValueError(f"f must be finite and >= 0, got {self.f}")

    def eps(self, n: float | np.ndarray) -> float | np.ndarray:
        """The error bound at batch size ``n``."""
        n = np.asarray(n, dtype=float)
        out = self.d / np.sqrt(n) + self.f / n
        return float(out) if out.ndim == 0 else out


def reinforce_variance_factor(constants: TaskConstants) -> float:
    r"""Bound on Var[REINFORCE sample] (Lemma 5.4 of Pirotta et al. (2013), Section 4.3.1).

    .. math:: \frac{R^2 M_\phi^2 H (1-\gamma^H)^2}{\sigma^2 (1-\gamma)^2}
    """
    gamma, H = constants.gamma, constants.H
    # Powers and logs through safepg.portable: libm's last bit depends on the CPU.
    root = constants.R * constants.M_phi * (1 - portable.ipow(gamma, H)) / (constants.sigma * (1 - gamma))
    return root * root * H


def gpomdp_variance_factor(constants: TaskConstants) -> float:
    r"""Bound on Var[G(PO)MDP sample] (Lemma 5.5 of Pirotta et al. (2013), Section 4.3.1).

    .. math:: \frac{R^2 M_\phi^2}{\sigma^2(1-\gamma)^2}\Big[\frac{1-\gamma^{2H}}{1-\gamma^2}
              + H\gamma^{2H} - 2\gamma^H\frac{1-\gamma^H}{1-\gamma}\Big]
    """
    gamma, H = constants.gamma, constants.H
    gH, g2H = portable.ipow(gamma, H), portable.ipow(gamma, 2 * H)
    bracket = (1 - g2H) / (1 - gamma * gamma) + H * g2H - 2 * gH * (1 - gH) / (1 - gamma)
    root = constants.R * constants.M_phi / (constants.sigma * (1 - gamma))
    return root * root * bracket


def chebyshev(delta: float, variance: float) -> ErrorBound:
    r"""Chebyshev: :math:`d_\delta = \sqrt{\mathrm{Var}[\tilde\nabla_{\theta_i} J]/\delta}` (4.3.1)."""
    check_delta(delta)
    return ErrorBound(np.sqrt(variance / delta))


def gradient_range_bound(constants: TaskConstants) -> float:
    r"""Lemma 4.3.3: range of a gradient sample, :math:`2 H M_\phi \bar A R / (\sigma^2 (1-\gamma))`."""
    c = constants
    return 2 * c.H * c.M_phi * c.A_bar * c.R / (c.sigma * c.sigma * (1 - c.gamma))


def hoeffding(delta: float, grad_range: float) -> ErrorBound:
    r"""Hoeffding: :math:`d_\delta = \mathbf R\sqrt{\ln(2/\delta)/2}` (Section 4.3.2)."""
    check_delta(delta)
    return ErrorBound(grad_range * np.sqrt(portable.log(2 / delta) / 2))


def bernstein(delta: float, sample_variance: float, grad_range: float) -> ErrorBound:
    r"""Empirical Bernstein (Section 4.3.3):

    .. math:: d_\delta = \sqrt{2 S_N \ln(3/\delta)}, \qquad f_\delta = 3\mathbf R\ln(3/\delta)
    """
    check_delta(delta)
    log3 = portable.log(3 / delta)
    return ErrorBound(np.sqrt(2 * sample_variance * log3), 3 * grad_range * log3)


def error_bound(
    bound: Bound,
    samples: np.ndarray,
    delta: float,
    constants: TaskConstants,
    estimator: str = "gpomdp",
    range: Range = "lemma",
    variance: float | None = None,
    sample_range: float | None = None,
) -> ErrorBound:
    """The bound of Section 4.3 for one gradient component.

    Parameters
    ----------
    bound : {"chebyshev", "hoeffding", "bernstein"}
    samples : ndarray, shape (N,)
        Per-trajectory gradient samples of the component being updated (k).
    delta : float
        Probability of a worsening update, in (0, 1).
    constants : TaskConstants
    estimator : {"reinforce", "gpomdp"}
        Chooses the Chebyshev variance bound.
    range : "lemma", "empirical" or float
        Hoeffding/Bernstein: the gradient's range is Lemma 4.3.3's bound (``"lemma"``),
        max - min of ``samples`` (``"empirical"``, the thesis's "e.r.") or the given number.
    variance, sample_range : float, optional
        Use these in place of the sample variance (ddof = 1) and the range max - min of
        ``samples`` (Bernstein; empirical range), e.g. the largest over all components, as
        the authors' 2-D and cart-pole scripts did.
    """
    check_delta(delta)
    samples = np.asarray(samples, dtype=float)
    if samples.ndim != 1 or samples.size < 2:
        raise ValueError(f"samples must be a 1-D array of at least 2 values, got shape {samples.shape}")
    if bound == "chebyshev":
        if estimator == "reinforce":
            return chebyshev(delta, reinforce_variance_factor(constants))
        if estimator == "gpomdp":
            return chebyshev(delta, gpomdp_variance_factor(constants))
        raise ValueError(f"estimator must be 'reinforce' or 'gpomdp', got {estimator!r}")
    if bound not in ("hoeffding", "bernstein"):
        raise ValueError(f"bound must be one of {BOUNDS}, got {bound!r}")
    if range == "empirical":
        grad_range = float(np.ptp(samples)) if sample_range is None else float(sample_range)
    elif range == "lemma":
        grad_range = gradient_range_bound(constants)
    else:
        grad_range = float(check_range(range))  # a number here: the strings were handled above
    if bound == "hoeffding":
        return hoeffding(delta, grad_range)
    return bernstein(delta, float(np.var(samples, ddof=1)) if variance is None else float(variance), grad_range)


__all__ = ["BOUNDS", "Bound", "ErrorBound", "Range", "bernstein", "chebyshev", "check_delta", "check_range",
           "error_bound", "gpomdp_variance_factor", "gradient_range_bound", "hoeffding", "reinforce_variance_factor"]
