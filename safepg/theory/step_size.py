r"""Section 4.2: the adaptive step size (coordinate descent) of a Gaussian policy.

The penalty constant :math:`c` of Theorem 4.2.3 and its assembly from Lemma 4.2.2, the
improvement bounds for one coordinate with an exact (Theorem 4.2.3) or estimated (Theorem
4.2.6) gradient, their maximisers (Corollaries 4.2.4, 4.2.8), the comparison with the
scalar step of Pirotta et al. (2013) (Corollary 4.2.5, Sections 3.3.2 and 5.2.1) and why a single
coordinate is optimal among all diagonal steps.
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from safepg.theory.symbols import A_vol, M_phi, R, alpha, b, c, eps, g, g1, g2, gamma, is_zero, maximise, sigma


def penalty_constant() -> sp.Expr:
    r"""Penalty constant :math:`c` of Theorem 4.2.3 (also Algorithm 4.1, Theorem 4.3.2).

    Returns
    -------
    sympy.Expr
        :math:`\frac{R M_\varphi^2}{(1-\gamma)^2\sigma^2}\big(\frac{|\mathcal A|}{\sqrt{2\pi}\sigma}
        + \frac{\gamma}{2(1-\gamma)}\big)`, as printed.
    """
    return (
        R
        * M_phi**2
        / ((1 - gamma) ** 2 * sigma**2)
        * (A_vol / (sp.sqrt(2 * sp.pi) * sigma) + gamma / (2 * (1 - gamma)))
    )


def penalty_constant_derivation(remainder_factor: sp.Expr | int = 1) -> dict[str, sp.Expr]:
    r"""Assemble :math:`c` from the proof of Lemma 4.2.2 and Theorem 4.2.3 (Appendix A).

    Lemma 3.1 of Pirotta et al. (2013) has the penalties
    :math:`\frac{1}{1-\gamma}\int d_\mu\int(\pi'-\pi)Q` and
    :math:`\frac{\gamma}{2(1-\gamma)^2}\|\pi'-\pi\|_\infty^2\|Q\|_\infty`. Lemma A.0.1 bounds the
    Taylor remainder of :math:`\pi'-\pi` by :math:`K\,D^2`, :math:`K = M_\varphi^2/(\sqrt{2\pi}\sigma^3)`,
    :math:`D = \|\Lambda\nabla J\|_1`; Lemma A.0.2 gives :math:`\|\pi'-\pi\|_\infty^2 \le M_\varphi^2 D^2/\sigma^2`;
    :math:`\int_{\mathcal A}|Q| \le |\mathcal A| R/(1-\gamma)` and :math:`\|Q\|_\infty \le R/(1-\gamma)`.

    Parameters
    ----------
    remainder_factor : sympy.Expr
        Multiplies Lemma A.0.1's constant: 1 as printed, 1/2 with the correct Taylor
        remainder (see :func:`taylor_remainder_weights`).

    Returns
    -------
    dict
        ``K_taylor``, ``term_taylor`` and ``term_pinsker`` (coefficients of :math:`D^2`),
        ``c`` (their sum, simplified) and ``matches_printed`` (``sympy.true`` iff equal to
        :func:`penalty_constant`).
    """
    q_inf = R / (1 - gamma)
    k_taylor = sp.sympify(remainder_factor) * M_phi**2 / (sp.sqrt(2 * sp.pi) * sigma**3)
    term_taylor = k_taylor * A_vol * q_inf / (1 - gamma)
    term_pinsker = gamma / (2 * (1 - gamma) ** 2) * M_phi**2 / sigma**2 * q_inf
    total = term_taylor + term_pinsker
    return {
        "K_taylor": k_taylor,
        "term_taylor": term_taylor,
        "term_pinsker": term_pinsker,
        "c": total,
        "matches_printed": sp.true if is_zero(total - penalty_constant()) else sp.false,
    }


def improvement_bound_coordinate(alpha: sp.Expr = alpha, grad_k: sp.Expr = g, c: sp.Expr = c) -> sp.Expr:
    r"""Theorem 4.2.3's bound when only coordinate k moves (:math:`\Lambda = \alpha e_k e_k^T`).

    .. math:: \nabla J^T\Lambda\nabla J - c\|\Lambda\nabla J\|_1^2 = \alpha g_k^2 - c\,\alpha^2 g_k^2
    """
    return alpha * grad_k**2 - c * alpha**2 * grad_k**2


def improvement_bound_approx(
    alpha: sp.Expr = alpha, grad_k: sp.Expr = g, eps: sp.Expr = eps, c: sp.Expr = c
) -> sp.Expr:
    r"""Theorem 4.2.6's bound for a single coordinate with :math:`|\hat g_k| \ge \epsilon`.

    .. math:: \alpha(|\hat g_k| - \epsilon)^2 - c\,\alpha^2(|\hat g_k| + \epsilon)^2
    """
    return alpha * (grad_k - eps) ** 2 - c * alpha**2 * (grad_k + eps) ** 2


def scalar_step_bound(alpha: sp.Expr = alpha) -> sp.Expr:
    r"""Bound (3.7) of Pirotta et al. (2013) for the scalar step :math:`\Lambda = \alpha I`:
    :math:`\alpha\|\nabla J\|_2^2 - c\,\alpha^2\|\nabla J\|_1^2`."""
    return alpha * g2**2 - c * alpha**2 * g1**2



@cache
def _corollary_4_2_4() -> dict[str, sp.Expr]:
    a_star, value = maximise(improvement_bound_coordinate())
    return {"bound": improvement_bound_coordinate(), "alpha_star": a_star, "improvement": value}


def corollary_4_2_4() -> dict[str, sp.Expr]:
    r"""Corollary 4.2.4: maximise :math:`\alpha g^2 - c\alpha^2 g^2` over :math:`\alpha`.

    Returns
    -------
    dict
        ``bound``, ``alpha_star`` (:math:`1/(2c)`), ``improvement`` (:math:`g^2/(4c)`).
        That one coordinate (the largest :math:`|g_i|`) is optimal among all diagonal
        :math:`\Lambda \ge 0` is shown by :func:`coordinate_descent_reduction`.
    """
    return dict(_corollary_4_2_4())


@cache
def _norm_inequality() -> dict[str, sp.Expr]:
    i = sp.Idx("i")
    m = sp.Symbol("m", integer=True, positive=True)
    a = sp.IndexedBase("a")  # a_i = |g_i| >= 0
    g_inf = sp.Symbol("G", positive=True)  # G = max_i a_i
    gap = g_inf * sp.Sum(a[i], (i, 1, m)) - sp.Sum(a[i] ** 2, (i, 1, m))
    as_sum = sp.Sum(a[i] * (g_inf - a[i]), (i, 1, m))
    # each summand a_i (G - a_i) is a product of two non-negative numbers
    a_i, s_i = sp.Symbol("a_i", nonnegative=True), sp.Symbol("s_i", nonnegative=True)  # s_i = G - a_i
    summand_nonneg = (a_i * s_i).is_nonnegative
    identity = sp.simplify(gap - as_sum) == 0
    return {
        "gap": gap,
        "gap_as_sum": as_sum,
        "identity_holds": sp.true if identity else sp.false,
        "summand_nonnegative": sp.true if summand_nonneg else sp.false,
    }


def norm_inequality() -> dict[str, sp.Expr]:
    r"""Symbolic proof, for any dimension m, of :math:`\|g\|_\infty\|g\|_1 \ge \|g\|_2^2` (Corollary 4.2.5).

    With :math:`a_i = |g_i|` and :math:`G = \max_i a_i`,

    .. math:: G\sum_i a_i - \sum_i a_i^2 = \sum_i a_i (G - a_i),

    and each summand is a product of two non-negative numbers.

    Returns
    -------
    dict
        ``gap``, ``gap_as_sum``, ``identity_holds`` and ``summand_nonnegative``
        (``sympy.true`` when proved).
    """
    return dict(_norm_inequality())


@cache
def _corollary_4_2_5() -> dict[str, sp.Expr]:
    a_star, value = maximise(scalar_step_bound())
    coord = corollary_4_2_4()["improvement"].subs(g, sp.Symbol("g_inf", positive=True))
    g_inf = sp.Symbol("g_inf", positive=True)
    # coordinate improvement - scalar improvement = (G^2 g1^2 - g2^4) / (4 c g1^2) >= 0 since G g1 >= g2^2
    diff = sp.factor(sp.simplify(coord - value))
    return {
        "scalar_bound": scalar_step_bound(),
        "scalar_alpha_star": a_star,
        "scalar_improvement": value,
        "coordinate_improvement": coord,
        "difference": diff,
        "difference_numerator": sp.factor((g_inf * g1 - g2**2) * (g_inf * g1 + g2**2)),
        **{k: v for k, v in norm_inequality().items() if k in ("gap", "gap_as_sum")},
    }


def corollary_4_2_5() -> dict[str, sp.Expr]:
    r"""Corollary 4.2.5: coordinate step vs the scalar step of Pirotta et al. (2013).

    The scalar bound :math:`\alpha\|g\|_2^2 - c\alpha^2\|g\|_1^2` is maximised at
    :math:`\alpha^* = \|g\|_2^2/(2c\|g\|_1^2)` with value :math:`\|g\|_2^4/(4c\|g\|_1^2)`. The
    difference to Corollary 4.2.4's :math:`\|g\|_\infty^2/(4c)` is
    :math:`(\|g\|_\infty\|g\|_1 - \|g\|_2^2)(\|g\|_\infty\|g\|_1 + \|g\|_2^2)/(4c\|g\|_1^2) \ge 0`
    by :func:`norm_inequality`.

    Returns
    -------
    dict
        ``scalar_bound``, ``scalar_alpha_star``, ``scalar_improvement``,
        ``coordinate_improvement`` (with ``g_inf`` :math:`=\|g\|_\infty`), ``difference``,
        ``difference_numerator``, and the norm-inequality ``gap``/``gap_as_sum``.
    """
    return dict(_corollary_4_2_5())


@cache
def _corollary_4_2_8() -> dict[str, sp.Expr]:
    bound = improvement_bound_approx()
    a_star, value = maximise(bound)
    ratio = (g - eps) ** 2 / (g + eps) ** 2
    return {
        "bound": bound,
        "alpha_star": a_star,
        "improvement": value,
        "selection_objective": ratio,
        "selection_derivative": sp.factor(sp.diff(ratio, g)),
    }


def corollary_4_2_8() -> dict[str, sp.Expr]:
    r"""Theorem 4.2.6 / Corollary 4.2.8: maximise :math:`\alpha(g-\epsilon)^2 - c\alpha^2(g+\epsilon)^2`.

    Returns
    -------
    dict
        ``alpha_star`` :math:`=(g-\epsilon)^2/(2c(g+\epsilon)^2)`, ``improvement``
        :math:`=(g-\epsilon)^4/(4c(g+\epsilon)^2)`, and the selection rule of Section 4.2.2:
        ``selection_objective`` :math:`(g-\epsilon)^2/(g+\epsilon)^2` and its derivative in g,
        :math:`4\epsilon(g-\epsilon)/(g+\epsilon)^3 \ge 0` for :math:`g \ge \epsilon` (so k = argmax
        :math:`|\hat g_i|`).
    """
    return dict(_corollary_4_2_8())


@cache
def _coordinate_descent_reduction() -> dict[str, sp.Expr]:
    s = sp.Symbol("S", nonnegative=True)
    rate = sp.Symbol("r", positive=True)
    # any Lambda = diag(alpha_i) >= 0: with u_i = alpha_i * (upper gradient)_i and S = sum u_i,
    # the bound is sum_i u_i r_i - c S^2 - b S <= r_max S - c S^2 - b S (equality: all weight on argmax r_i)
    reduced = rate * s - c * s**2 - b * s
    s_star, value = maximise(reduced, s)
    return {"reduced_bound": reduced, "S_star": s_star, "value": value}


def coordinate_descent_reduction() -> dict[str, sp.Expr]:
    r"""Why a single coordinate is optimal (Corollaries 4.2.4, 4.2.8, B.0.7).

    For :math:`\Lambda = \mathrm{diag}(\alpha_i) \ge 0` write the bound as
    :math:`\sum_i \alpha_i l_i^2 - c(\sum_i \alpha_i u_i)^2 - b\sum_i\alpha_i u_i`
    (lower/upper gradient magnitudes :math:`l_i \le u_i`). With :math:`s_i = \alpha_i u_i`,
    :math:`S = \sum_i s_i` and rates :math:`r_i = l_i^2/u_i`, it equals
    :math:`\sum_i s_i r_i - cS^2 - bS \le r_{\max}S - cS^2 - bS`, with equality when all
    the weight is on the coordinate of largest rate. The reduced bound is then
    maximised over S.

    Returns
    -------
    dict
        ``reduced_bound`` :math:`rS - cS^2 - bS`, ``S_star`` :math:`(r-b)/(2c)`, ``value``
        :math:`(r-b)^2/(4c)`. Set b = 0 and r = g (4.2.4) or :math:`r=(g-\epsilon)^2/(g+\epsilon)`
        (4.2.8); :math:`\alpha_k = S^*/u_k`.
    """
    return dict(_coordinate_descent_reduction())


# --------------------------------------------------------------------------- Section 3.3.2 / 5.2.1
def scalar_step_comparison() -> dict[str, sp.Expr]:
    r"""Printed scalar step sizes of Pirotta et al. (2013) vs :math:`\|g\|_2^2/(2c\|g\|_1^2)` with c of Theorem 4.2.3.

    Returns
    -------
    dict
        ``derived_alpha`` and ``derived_improvement`` (from :func:`corollary_4_2_5` with c
        substituted); ``printed_bound_3_7``, ``printed_alpha_3_3_2`` and
        ``printed_improvement_3_3_2`` (Section 3.3.2); ``printed_alpha_5_2_1``
        (Section 5.2.1, with :math:`\|\hat g/2\|_2^2 = \|\hat g\|_2^2/4`); and the ratios of the
        printed to the derived step (1 for 3.3.2, 1/4 for 5.2.1).
    """
    cc = penalty_constant()
    cor = corollary_4_2_5()
    derived_alpha = cor["scalar_alpha_star"].subs(c, cc)
    derived_improvement = cor["scalar_improvement"].subs(c, cc)
    s2p = sp.sqrt(2 * sp.pi)
    denom = 2 * A_vol * (1 - gamma) + s2p * sigma * gamma
    printed_bound = alpha * g2**2 - alpha**2 * R * M_phi**2 * g1**2 / ((1 - gamma) ** 2 * sigma**2) * (
        A_vol / (s2p * sigma) + gamma / (2 * (1 - gamma))
    )
    p332 = g2**2 * (1 - gamma) ** 3 * sigma**3 * s2p / (R * M_phi**2 * g1**2 * denom)
    imp332 = g2**4 * (1 - gamma) ** 3 * sigma**3 * s2p / (2 * R * M_phi**2 * g1**2 * denom)
    p521 = (
        (1 - gamma) ** 3
        * s2p
        * sigma**3
        * (g2 / 2) ** 2
        / ((gamma * s2p * sigma + 2 * (1 - gamma) * A_vol) * R * M_phi**2 * g1**2)
    )
    return {
        "derived_alpha": derived_alpha,
        "derived_improvement": derived_improvement,
        "printed_bound_3_7": printed_bound,
        "bound_3_7_minus_derived": sp.simplify(printed_bound - scalar_step_bound().subs(c, cc)),
        "printed_alpha_3_3_2": p332,
        "printed_improvement_3_3_2": imp332,
        "printed_alpha_5_2_1": p521,
        "ratio_3_3_2": sp.simplify(p332 / derived_alpha),
        "ratio_improvement_3_3_2": sp.simplify(imp332 / derived_improvement),
        "ratio_5_2_1": sp.simplify(p521 / derived_alpha),
    }


__all__ = ["coordinate_descent_reduction", "corollary_4_2_4", "corollary_4_2_5", "corollary_4_2_8",
           "improvement_bound_approx", "improvement_bound_coordinate", "norm_inequality", "penalty_constant",
           "penalty_constant_derivation", "scalar_step_bound", "scalar_step_comparison"]
