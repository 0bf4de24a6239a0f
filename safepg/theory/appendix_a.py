r"""Appendix A: the Gaussian-policy lemmas behind the penalty constant of Theorem 4.2.3.

The second derivative of the Gaussian density in the parameters (Lemma A.0.1), the
weights of its Taylor remainder, and the Kullback-Leibler divergence of two Gaussians
used with Pinsker's inequality (Lemma A.0.2).
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from safepg.theory.symbols import sigma


@cache
def _gaussian_density_hessian() -> dict[str, sp.Expr]:
    a, th_i, th_j, phi_i, phi_j, rest = sp.symbols("a theta_i theta_j phi_i phi_j mu_rest", real=True)
    mean = th_i * phi_i + th_j * phi_j + rest
    pdf = sp.exp(-((a - mean) ** 2) / (2 * sigma**2)) / (sp.sqrt(2 * sp.pi) * sigma)
    hess = sp.diff(pdf, th_i, th_j)
    z = sp.Symbol("z", real=True)  # z = (a - mu) / sigma
    shape = (z**2 - 1) * sp.exp(-(z**2) / 2)
    claimed = phi_i * phi_j / (sp.sqrt(2 * sp.pi) * sigma**3) * shape
    check = sp.simplify(hess - claimed.subs(z, (a - mean) / sigma))
    crit = sp.solve(sp.diff(shape, z), z)
    sup = sp.Max(*[sp.Abs(shape.subs(z, p)) for p in crit])
    return {
        "hessian": hess,
        "hessian_in_z": claimed,
        "hessian_matches": sp.true if check == 0 else sp.false,
        "shape": shape,
        "critical_points": crit,
        "sup_abs_shape": sp.simplify(sup),
        "shape_limit_infinity": sp.limit(shape, z, sp.oo),
    }


def gaussian_density_hessian() -> dict[str, sp.Expr]:
    r"""Lemma A.0.1's bound on :math:`|\partial^2\pi/\partial\theta_i\partial\theta_j|` for a Gaussian policy.

    .. math:: \frac{\partial^2\mathcal N(a;\theta^T\varphi,\sigma^2)}{\partial\theta_i\partial\theta_j}
              = \frac{\varphi_i\varphi_j}{\sqrt{2\pi}\sigma^3}(z^2-1)e^{-z^2/2},
              \quad z = \frac{a-\theta^T\varphi}{\sigma}

    and :math:`\sup_z|(z^2-1)e^{-z^2/2}| = 1` (critical points 0 and :math:`\pm\sqrt 3`, where the
    value is :math:`2e^{-3/2}`; the shape vanishes at infinity).

    Returns
    -------
    dict
        ``hessian``, ``hessian_in_z``, ``hessian_matches``, ``shape``,
        ``critical_points``, ``sup_abs_shape`` (1), ``shape_limit_infinity`` (0).
    """
    return dict(_gaussian_density_hessian())


def taylor_remainder_weights(m: int = 3) -> dict[str, sp.Expr]:
    r"""Lemma A.0.1's remainder weights :math:`1/(1+I(i=j))` on a full double sum.

    The Lagrange remainder is :math:`\frac12\sum_{i,j}\partial_{ij}\pi\,\Delta_i\Delta_j`
    (equivalently weights :math:`1/(1+I(i=j))` over :math:`i \le j` only). On the full double
    sum, as printed, off-diagonal terms are counted twice, and the printed step
    :math:`\sum_{i,j} a_ia_j/(1+I(i=j)) = (\sum_i a_i)^2` is false: the left side is
    :math:`(\sum a)^2 - \frac12\sum a_i^2`. The correct remainder is bounded by
    :math:`\frac12(\sum_i a_i)^2`, half the printed constant.

    Parameters
    ----------
    m : int
        Number of parameters for the explicit sums.

    Returns
    -------
    dict
        ``printed_weighted_sum``, ``printed_claim`` :math:`(\sum a)^2`,
        ``printed_minus_claim`` (:math:`-\frac12\sum a_i^2`), ``correct_remainder_bound``
        (:math:`\frac12(\sum a)^2`).
    """
    a = sp.symbols(f"a_1:{m + 1}", nonnegative=True)
    weighted = sum(a[i] * a[j] / (2 if i == j else 1) for i in range(m) for j in range(m))
    claim = sum(a) ** 2
    correct = sp.Rational(1, 2) * sum(a[i] * a[j] for i in range(m) for j in range(m))
    return {
        "printed_weighted_sum": weighted,
        "printed_claim": claim,
        "printed_minus_claim": sp.factor(sp.expand(weighted - claim)),
        "correct_remainder_bound": sp.factor(correct),
    }


@cache
def _gaussian_kl() -> dict[str, sp.Expr]:
    from sympy.stats import E, Normal

    mu1, mu2 = sp.symbols("mu_1 mu_2", real=True)
    X = Normal("X", mu1, sigma)

    def logpdf(z: sp.Expr, mu: sp.Expr) -> sp.Expr:
        return -((z - mu) ** 2) / (2 * sigma**2) - sp.log(sp.sqrt(2 * sp.pi) * sigma)

    kl = sp.factor(sp.simplify(E(sp.expand(logpdf(X, mu1) - logpdf(X, mu2)))))
    return {"kl": kl, "two_kl": sp.factor(2 * kl)}


def gaussian_kl() -> dict[str, sp.Expr]:
    r"""Lemma A.0.2: :math:`KL(\mathcal N(\mu_1,\sigma^2)\|\mathcal N(\mu_2,\sigma^2)) = (\mu_1-\mu_2)^2/(2\sigma^2)`.

    With :math:`\mu_1 - \mu_2 = \Delta\theta^T\varphi(s)`, Pinsker
    (:math:`\|p-q\|_1^2 \le 2KL`) gives :math:`\|\pi'-\pi\|_1^2 \le (\Delta\theta^T\varphi)^2/\sigma^2
    \le M_\varphi^2\|\Delta\theta\|_1^2/\sigma^2` (the square of a sum, not the printed sum of squares).

    Returns
    -------
    dict
        ``kl``, ``two_kl``.
    """
    return dict(_gaussian_kl())


__all__ = ["gaussian_density_hessian", "gaussian_kl", "taylor_remainder_weights"]
