r"""Section 4.3: the adaptive batch size.

The cost-sensitive measure :math:`\Upsilon_\delta` and its maximisation (Theorem 4.3.2),
the error constants :math:`d_\delta` (and :math:`f_\delta`) of the Chebyshev (4.3.1), Hoeffding
(4.3.2) and empirical Bernstein (4.3.3) bounds with the resulting :math:`N_0` and :math:`N^*`,
the range of a gradient sample (Lemma 4.3.3), and Descartes' rule of signs for the
Bernstein case's unique maximiser.
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from safepg.theory.step_size import corollary_4_2_8
from safepg.theory.symbols import (
    A_bar,
    H,
    M_phi,
    N,
    R,
    R_range,
    d,
    delta,
    eps,
    f,
    g,
    gamma,
    mu_bar,
    sigma,
    tidy,
    var,
    x,
)


def upsilon(eps_of_n: sp.Expr, n: sp.Symbol = N) -> sp.Expr:
    r"""Cost-sensitive measure :math:`\Upsilon_\delta(\Lambda^*, N)` (Definition 4.1 with Corollary 4.2.8).

    .. math:: \Upsilon_\delta = \frac{(g - \epsilon(N))^4}{4cN(g + \epsilon(N))^2}
    """
    return corollary_4_2_8()["improvement"].subs(eps, eps_of_n) / n


@cache
def _theorem_4_3_2() -> dict[str, sp.Expr]:
    ups = upsilon(d / sp.sqrt(N))
    deriv = sp.factor(sp.together(sp.diff(ups, N).subs(N, x**2)))
    numerator, denominator = sp.fraction(deriv)
    roots = sorted(sp.solve(numerator, x), key=lambda r: float(r.subs({d: 1, g: 1})))
    if len(roots) != 2:
        raise RuntimeError(f"expected two positive stationary points, got {roots}")
    x0, x_star = roots
    ups_x = ups.subs(N, x**2)
    n0, n_star = sp.factor(sp.expand(x0**2)), sp.factor(sp.expand(x_star**2))
    alpha_star = tidy(corollary_4_2_8()["alpha_star"].subs(eps, d / x_star))
    ups_star = tidy(ups_x.subs(x, x_star))
    improvement_star = tidy(ups_star * n_star)
    second = sp.diff(ups_x, x, 2).subs(x, x_star)
    return {
        "upsilon": ups,
        "derivative": deriv,
        "derivative_numerator": numerator,
        "derivative_denominator": denominator,
        "x_0": x0,
        "x_star": x_star,
        "N_0": n0,
        "N_star": n_star,
        "N_star_over_N_0": tidy(n_star / n0),
        "upsilon_at_N_0": sp.simplify(ups_x.subs(x, x0)),
        "second_derivative_sign_at_x_star": sp.sign(tidy(second)),
        "alpha_star": alpha_star,
        "upsilon_star": ups_star,
        "improvement_star": improvement_star,
        "upsilon_limit_infinity": sp.limit(ups, N, sp.oo),
        "upsilon_limit_zero": sp.limit(ups, N, 0, "+"),
    }


def theorem_4_3_2() -> dict[str, sp.Expr]:
    r"""Theorem 4.3.2 derived: maximise :math:`\Upsilon_\delta` for :math:`\epsilon = d_\delta/\sqrt N`.

    :math:`\partial\Upsilon/\partial N` is computed, :math:`N = x^2` substituted, and the
    numerator factorised and solved for :math:`x > 0`. Its factors are
    :math:`(gx - d)^3` (root :math:`N_0 = d^2/g^2`, where :math:`\epsilon = g`) and
    :math:`g^2x^2 - 3dgx - 2d^2` (one positive root, :math:`x^* = (3+\sqrt{17})d/(2g)`).

    Returns
    -------
    dict
        ``upsilon``, ``derivative`` (in x), its ``derivative_numerator`` /
        ``derivative_denominator``, ``x_0``, ``x_star``, ``N_0``, ``N_star``
        (:math:`(13+3\sqrt{17})d^2/(2g^2)`), ``N_star_over_N_0``, ``upsilon_at_N_0`` (0),
        ``second_derivative_sign_at_x_star`` (-1), ``alpha_star`` (:math:`(13-3\sqrt{17})/(4c)`),
        ``upsilon_star`` (:math:`(4977-1207\sqrt{17})g^4/(128cd^2)`), ``improvement_star``
        (:math:`N^*\Upsilon^* = (393-95\sqrt{17})g^2/(32c)`), and the limits of
        :math:`\Upsilon` at :math:`N\to\infty` (0) and :math:`N\to 0^+` (:math:`\infty`).
    """
    return dict(_theorem_4_3_2())


# ---- Section 4.3.1: Chebyshev
def chebyshev_d() -> dict[str, sp.Expr]:
    r"""Section 4.3.1: :math:`d_\delta` from Chebyshev's sample-mean bound.

    Solves :math:`\delta = \mathrm{Var}/(\epsilon^2 N)` for :math:`\epsilon > 0`, so
    :math:`d_\delta = \epsilon\sqrt N = \sqrt{\mathrm{Var}/\delta}`.

    Returns
    -------
    dict
        ``eps`` (:math:`\epsilon(N)`), ``d``.
    """
    e = sp.Symbol("e", positive=True)
    (sol,) = sp.solve(sp.Eq(delta, var / (e**2 * N)), e)
    return {"eps": sol, "d": sp.simplify(sol * sp.sqrt(N))}


def chebyshev_n_star() -> dict[str, sp.Expr]:
    r"""Section 4.3.1: explicit :math:`N^*` for REINFORCE and G(PO)MDP (Lemmas 5.4/5.5 of Pirotta et al. (2013)).

    The printed error bounds :math:`\epsilon \le \frac{1}{\sqrt N}(\dots)` give :math:`d_\delta`;
    substituting into :func:`theorem_4_3_2`'s :math:`N^*` gives the explicit batch sizes,
    compared with the printed ones.

    Returns
    -------
    dict
        ``d_reinforce``, ``d_gpomdp``, ``N_star_reinforce``, ``N_star_gpomdp`` (derived),
        ``printed_N_star_reinforce``, ``printed_N_star_gpomdp``.
    """
    s17 = sp.sqrt(17)
    bracket = (
        (1 - gamma ** (2 * H)) / (1 - gamma**2) + H * gamma ** (2 * H) - 2 * gamma**H * (1 - gamma**H) / (1 - gamma)
    )
    d_rf = R * M_phi * (1 - gamma**H) / (sigma * (1 - gamma)) * sp.sqrt(H / delta)
    d_pgt = R * M_phi / (sigma * (1 - gamma)) * sp.sqrt(bracket / delta)
    n_star = theorem_4_3_2()["N_star"]
    return {
        "d_reinforce": d_rf,
        "d_gpomdp": d_pgt,
        "N_star_reinforce": n_star.subs(d, d_rf),
        "N_star_gpomdp": n_star.subs(d, d_pgt),
        "printed_N_star_reinforce": (13 + 3 * s17)
        * R**2
        * M_phi**2
        * H
        * (1 - gamma**H) ** 2
        / (2 * delta * sigma**2 * (1 - gamma) ** 2 * g**2),
        "printed_N_star_gpomdp": (13 + 3 * s17)
        * R**2
        * M_phi**2
        * bracket
        / (2 * delta * sigma**2 * (1 - gamma) ** 2 * g**2),
    }


# ---- Section 4.3.2: Hoeffding
def hoeffding_d() -> dict[str, sp.Expr]:
    r"""Section 4.3.2: :math:`d_\delta` from Hoeffding's inequality for a sample mean.

    For N i.i.d. samples of range :math:`\mathbf R`,
    :math:`P(|\bar X_N - E X| \ge \epsilon) \le 2e^{-2N\epsilon^2/\mathbf R^2}`. Setting the
    right side to :math:`\delta` gives :math:`\epsilon = \mathbf R\sqrt{\ln(2/\delta)/(2N)}`, i.e.
    the printed :math:`d_\delta = \mathbf R\sqrt{\ln(2/\delta)/2}`. The *printed* tail
    :math:`2e^{-2\epsilon^2/(N\mathbf R^2)}` would give :math:`\epsilon = d_\delta\sqrt N`,
    growing with N (not of the form of Assumption 4.3.1).

    Returns
    -------
    dict
        ``tail``, ``eps``, ``d`` (correct inequality), ``printed_tail``, ``printed_eps``,
        ``printed_d`` and ``printed_eps_over_eps`` (= N).
    """
    e = sp.Symbol("e", positive=True)
    log_term = sp.Symbol("L", positive=True)  # L = ln(2/delta), i.e. delta = 2 exp(-L)
    tail = 2 * sp.exp(-2 * N * e**2 / R_range**2)
    printed_tail = 2 * sp.exp(-2 * e**2 / (N * R_range**2))
    (sol,) = sp.solve(sp.Eq(tail, 2 * sp.exp(-log_term)), e)
    (psol,) = sp.solve(sp.Eq(printed_tail, 2 * sp.exp(-log_term)), e)
    sol, psol = (s.subs(log_term, sp.log(2 / delta)) for s in (sol, psol))
    return {
        "tail": tail.subs(e, eps),
        "eps": sol,
        "d": sp.simplify(sol * sp.sqrt(N)),
        "printed_tail": printed_tail.subs(e, eps),
        "printed_eps": psol,
        "printed_d": R_range * sp.sqrt(sp.log(2 / delta) / 2),
        "printed_eps_over_eps": sp.simplify(psol / sol),
    }


@cache
def _gradient_range_bound() -> dict[str, sp.Expr]:
    a, mu_rest, theta_i, phi_i = sp.symbols("a mu_rest theta_i phi_i", real=True)
    mean = theta_i * phi_i + mu_rest
    log_pi = -((a - mean) ** 2) / (2 * sigma**2) - sp.log(sp.sqrt(2 * sp.pi) * sigma)
    score = sp.factor(sp.diff(log_pi, theta_i))
    mu = sp.Symbol("mu", real=True)
    score_mu = score.subs(mu_rest, mu - theta_i * phi_i)
    score_range = sp.factor(sp.simplify(score_mu.subs(a, A_bar) - score_mu.subs(a, -A_bar)))
    l = sp.Symbol("l", integer=True, positive=True)
    return_bound = sp.piecewise_fold(sp.summation(gamma ** (l - 1) * R, (l, 1, H)))
    if isinstance(return_bound, sp.Piecewise):  # keep the gamma != 1 branch (gamma < 1)
        return_bound = next(expr for expr, cond in return_bound.args if cond is sp.true)
    return_bound = R * sp.factor(sp.simplify(return_bound / R))
    printed = 2 * H * M_phi * A_bar * R / (sigma**2 * (1 - gamma))
    sup_abs = H * M_phi * (A_bar + mu_bar) / sigma**2 * R * (1 - gamma**H) / (1 - gamma)
    worst_range = 2 * sup_abs
    return {
        "score": score_mu,
        "score_range_fixed_state": score_range,
        "score_range_bound": 2 * M_phi * A_bar / sigma**2,
        "return_bound": return_bound,
        "return_bound_loose": R / (1 - gamma),
        "printed_bound": printed,
        "sup_abs_bound": sup_abs,
        "worst_case_range": worst_range,
        "worst_case_over_printed": sp.factor(sp.simplify(worst_range / printed)),
    }


def gradient_range_bound() -> dict[str, sp.Expr]:
    r"""Lemma 4.3.3 (range of a gradient sample), step by step.

    Steps of the printed proof (REINFORCE, no baseline):

    1. ``score``: :math:`\partial_{\theta_i}\log\mathcal N(a;\theta^T\varphi,\sigma^2) = (a-\mu)\varphi_i/\sigma^2`.
    2. ``score_range_fixed_state``: over :math:`a\in[-\bar A,\bar A]` for a fixed state,
       :math:`2\bar A\varphi_i/\sigma^2`, at most ``score_range_bound`` :math:`2M_\varphi\bar A/\sigma^2`.
    3. ``return_bound``: :math:`|\sum_{l=1}^H\gamma^{l-1}r_l| \le R(1-\gamma^H)/(1-\gamma) \le R/(1-\gamma)`.
    4. ``printed_bound``: H times (2) times (3), :math:`2HM_\varphi\bar AR/(\sigma^2(1-\gamma))`.

    Step 4 multiplies a *range* by a *magnitude*; the range of the product is not
    bounded that way. With :math:`|\theta^T\varphi(s)| \le \bar\mu`,
    :math:`|a - \mu| \le \bar A + \bar\mu`, so a sample is at most ``sup_abs_bound`` in
    magnitude and its range at most ``worst_case_range`` (twice that); the
    construction in :func:`safepg.thesis.lemma_checks.check_lemma_4_3_3` attains it.
    ``worst_case_over_printed`` :math:`=(1-\gamma^H)(1+\bar\mu/\bar A)` exceeds 1 e.g. for
    :math:`H = 20, \gamma = 0.9, \bar\mu > 0.14\bar A`.

    Returns
    -------
    dict
        The expressions named above.
    """
    return dict(_gradient_range_bound())


# ---- Section 4.3.3: empirical Bernstein
def bernstein_upsilon() -> sp.Expr:
    r""":math:`\Upsilon_\delta(\Lambda^*, N)` with :math:`\epsilon(N) = d_\delta/\sqrt N + f_\delta/N` (4.3.3)."""
    return upsilon(d / sp.sqrt(N) + f / N)


def bernstein_n_zero() -> dict[str, sp.Expr]:
    r"""Section 4.3.3: :math:`N_0` solving :math:`\epsilon(N_0) = g` (Assumption 4.2.7 at equality).

    With :math:`x = \sqrt N`: :math:`gx^2 - dx - f = 0`, positive root
    :math:`x_0 = (d + \sqrt{d^2 + 4fg})/(2g)`.

    Returns
    -------
    dict
        ``x_0``, ``N_0`` (derived) and ``printed_N_0``.
    """
    roots = sp.solve(g * x**2 - d * x - f, x)
    positive = [r for r in roots if float(r.subs({d: 1, f: 1, g: 1})) > 0]
    if len(positive) != 1:
        raise RuntimeError(f"expected one positive root, got {roots}")
    x0 = positive[0]
    return {
        "x_0": x0,
        "N_0": x0**2,
        "printed_N_0": ((d + sp.sqrt(d**2 + 4 * f * g)) / (2 * g)) ** 2,
    }


def bernstein_derivative_factors() -> tuple[sp.Expr, sp.Expr]:
    r"""The two factors of the numerator of :math:`\partial\Upsilon_\delta/\partial N` (Section 4.3.3).

    In :math:`x = \sqrt N`, as Section 4.3.3 writes them; :func:`bernstein_upsilon_derivative`
    checks that the derived numerator is their product up to the constant -1.

    Returns
    -------
    (first, second) : tuple of sympy.Expr
        :math:`(dx + f - gx^2)^3` and :math:`2d^2x^2 + 5dfx + 3dgx^3 + 3f^2 + 6fgx^2 - g^2x^4`.
    """
    first = (d * x + f - g * x**2) ** 3
    second = 2 * d**2 * x**2 + 5 * d * f * x + 3 * d * g * x**3 + 3 * f**2 + 6 * f * g * x**2 - g**2 * x**4
    return first, second


@cache
def _bernstein_upsilon_derivative() -> dict[str, sp.Expr]:
    deriv = sp.factor(sp.together(sp.diff(bernstein_upsilon(), N).subs(N, x**2)))
    numerator, denominator = sp.fraction(deriv)
    first, second = bernstein_derivative_factors()
    ratio = sp.factor(sp.cancel(numerator / (first * second)))
    return {
        "derivative": deriv,
        "numerator": numerator,
        "denominator": denominator,
        "printed_first_factor": first,
        "printed_second_factor": second,
        "numerator_over_printed_product": ratio,
    }


def bernstein_upsilon_derivative() -> dict[str, sp.Expr]:
    r"""Section 4.3.3: :math:`\partial\Upsilon_\delta/\partial N` for the empirical Bernstein error.

    With :math:`x = \sqrt N`, sympy factorises the derivative as

    .. math:: -\frac{(dx + f - gx^2)^3\,(2d^2x^2 + 5dfx + 3dgx^3 + 3f^2 + 6fgx^2 - g^2x^4)}
                    {4c\,x^8 (gx^2 + dx + f)^3},

    i.e. the two printed factors up to the constant -1 (``numerator_over_printed_product``).

    Returns
    -------
    dict
        ``derivative``, ``numerator``, ``denominator``, the printed factors
        ``printed_first_factor``/``printed_second_factor`` and
        ``numerator_over_printed_product`` (a constant, -1).
    """
    return dict(_bernstein_upsilon_derivative())


def descartes_sign_changes(coefficients: list[sp.Expr]) -> int:
    """Number of sign changes in a coefficient list (Descartes' rule of signs).

    Zero coefficients are skipped. Raises ``ValueError`` if sympy cannot determine the
    sign of a coefficient from the symbols' assumptions.
    """
    signs = []
    for coef in coefficients:
        s = sp.sign(sp.simplify(coef))
        if s not in (-1, 0, 1):
            raise ValueError(f"coefficients must have a determined sign, got {coef} (sign {s})")
        if s != 0:
            signs.append(int(s))
    return sum(1 for u, v in zip(signs, signs[1:]) if u != v)


@cache
def _bernstein_descartes() -> dict[str, object]:
    _, second = bernstein_derivative_factors()
    coeffs = sp.Poly(second, x).all_coeffs()
    changes = descartes_sign_changes(coeffs)
    coeffs_f0 = sp.Poly(sp.cancel(second.subs(f, 0) / x**2), x).all_coeffs()
    return {
        "coefficients": coeffs,
        "signs": [sp.sign(cf) for cf in coeffs],
        "sign_changes": changes,
        # Descartes: #positive roots = changes - 2k >= 0, so one change means exactly one root
        "positive_roots": changes if changes <= 1 else None,
        "coefficients_f0": coeffs_f0,
        "sign_changes_f0": descartes_sign_changes(coeffs_f0),
    }


def bernstein_descartes() -> dict[str, object]:
    r"""Descartes' rule of signs on the second factor as a polynomial in :math:`x = \sqrt N`.

    Coefficients (descending powers): :math:`-g^2,\ 3dg,\ 2d^2 + 6fg,\ 5df,\ 3f^2`. For
    positive d, f, g their signs are determined (-, +, +, +, +): one sign change, hence
    exactly one positive root. With f = 0 (Chebyshev/Hoeffding) the factor is
    :math:`x^2(-g^2x^2 + 3dgx + 2d^2)`, again one change.

    Returns
    -------
    dict
        ``coefficients``, ``signs``, ``sign_changes`` (1), ``positive_roots`` (1),
        ``coefficients_f0``, ``sign_changes_f0`` (1).
    """
    return dict(_bernstein_descartes())


def bernstein_root_beyond_n_zero() -> dict[str, sp.Expr]:
    r"""The positive root of the second factor lies beyond :math:`\sqrt{N_0}` and is a maximum.

    At :math:`x_0` (where :math:`g x_0^2 = d x_0 + f`) the second factor equals
    :math:`4d^2x_0^2 + 12dfx_0 + 8f^2 > 0`; it tends to :math:`-\infty`, so its only positive
    root :math:`x^*` exceeds :math:`x_0`. For :math:`x > x_0` the first factor is negative,
    so :math:`\partial\Upsilon/\partial N > 0` on :math:`(x_0, x^*)` and :math:`< 0` beyond.

    Returns
    -------
    dict
        ``second_factor_at_x0`` (with g eliminated) and ``is_positive``.
    """
    _, second = bernstein_derivative_factors()
    x0 = sp.Symbol("x_0", positive=True)
    at_x0 = sp.expand(sp.simplify(second.subs(x, x0).subs(g, (d * x0 + f) / x0**2)))
    return {"second_factor_at_x0": at_x0, "is_positive": sp.true if at_x0.is_positive else sp.false}


__all__ = ["bernstein_derivative_factors", "bernstein_descartes", "bernstein_n_zero", "bernstein_root_beyond_n_zero",
           "bernstein_upsilon", "bernstein_upsilon_derivative", "chebyshev_d", "chebyshev_n_star",
           "descartes_sign_changes", "gradient_range_bound", "hoeffding_d", "theorem_4_3_2", "upsilon"]
