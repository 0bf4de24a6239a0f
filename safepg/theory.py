r"""Symbolic derivations of Chapter 4 and Appendix B of the thesis (sympy).

Every public function returns sympy expressions (usually a ``dict`` of named
steps) so that a notebook can render them with :func:`latex`. Nothing here is
typed in from the thesis except the *printed* statements (the ``printed_*``
functions and the ``printed`` field of :data:`ERRATA` records) that the
derivations are compared with; constants such as :math:`13 \pm 3\sqrt{17}` come out
of sympy's algebra.

Shared symbols (thesis notation in brackets):

========== ===========================================================
``g``       :math:`\|\hat\nabla_\theta J_\mu(\theta)\|_\infty` (or :math:`|\nabla_{\theta_k} J|`), > 0
``g1, g2``  :math:`\|\nabla_\theta J\|_1`, :math:`\|\nabla_\theta J\|_2`, > 0
``eps``     estimation error :math:`\epsilon \ge 0`
``c``       penalty constant of Theorem 4.2.3 (or B.0.6), > 0
``b``       linear penalty of Theorem B.0.6, > 0
``d, f``    :math:`d_\delta > 0`, :math:`f_\delta > 0` with :math:`\epsilon(N) = d_\delta/\sqrt N + f_\delta/N`
``N, x``    batch size and :math:`x = \sqrt N`, > 0
``alpha``   step size of the updated coordinate, :math:`\ge 0`
``delta``   worsening probability, in (0, 1)
``R``       reward bound :math:`\max|r|`; ``R_range`` the gradient-sample range :math:`\mathbf R`
``M_phi``   feature bound :math:`M_\varphi`; ``A_vol`` :math:`|\mathcal A|`; ``A_bar`` :math:`\bar A`
``sigma, gamma, H``  policy standard deviation, discount, horizon
========== ===========================================================

The module also records, as structured data, every place where a printed
statement differs from its derivation (:func:`errata`, ``ERRATA``) and the printed
statements that were checked and found correct (:func:`verified`, ``VERIFIED``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Literal

import sympy as sp

# ERRATA and VERIFIED are also available as module attributes (built on first access).
__all__ = [
    "Erratum",
    "Verified",
    "bernstein_descartes",
    "bernstein_n_zero",
    "bernstein_root_beyond_n_zero",
    "bernstein_upsilon",
    "bernstein_upsilon_derivative",
    "chebyshev_d",
    "chebyshev_n_star",
    "coordinate_descent_reduction",
    "corollary_4_2_4",
    "corollary_4_2_5",
    "corollary_4_2_8",
    "corollary_b_0_7",
    "descartes_sign_changes",
    "errata",
    "gaussian_density_hessian",
    "gaussian_kl",
    "gradient_range_bound",
    "hoeffding_d",
    "improvement_bound_approx",
    "improvement_bound_coordinate",
    "latex",
    "maximise",
    "norm_inequality",
    "penalty_constant",
    "penalty_constant_derivation",
    "printed_theorem_4_3_2",
    "scalar_step_bound",
    "scalar_step_comparison",
    "softmax_constants",
    "taylor_remainder_weights",
    "theorem_4_3_2",
    "upsilon",
    "verified",
]

# --------------------------------------------------------------------------- symbols
g = sp.Symbol("g", positive=True)
g1 = sp.Symbol("g_1", positive=True)
g2 = sp.Symbol("g_2", positive=True)
eps = sp.Symbol("epsilon", nonnegative=True)
c = sp.Symbol("c", positive=True)
b = sp.Symbol("b", positive=True)
d = sp.Symbol("d_delta", positive=True)
f = sp.Symbol("f_delta", positive=True)
N = sp.Symbol("N", positive=True)
x = sp.Symbol("x", positive=True)
alpha = sp.Symbol("alpha", nonnegative=True)
delta = sp.Symbol("delta", positive=True)
R = sp.Symbol("R", positive=True)
R_range = sp.Symbol("R_range", positive=True)
M_phi = sp.Symbol("M_phi", positive=True)
sigma = sp.Symbol("sigma", positive=True)
gamma = sp.Symbol("gamma", positive=True)
H = sp.Symbol("H", positive=True, integer=True)
A_vol = sp.Symbol("A_vol", positive=True)
A_bar = sp.Symbol("A_bar", positive=True)
mu_bar = sp.Symbol("mu_bar", nonnegative=True)
var = sp.Symbol("Var", positive=True)
S_N = sp.Symbol("S_N", positive=True)

#: LaTeX names in the thesis's notation, used by :func:`latex`.
LATEX_NAMES: dict[sp.Symbol, str] = {
    g: r"\|\hat\nabla_\theta J\|_\infty",
    g1: r"\|\nabla_\theta J\|_1",
    g2: r"\|\nabla_\theta J\|_2",
    eps: r"\epsilon",
    d: r"d_\delta",
    f: r"f_\delta",
    M_phi: r"M_\varphi",
    A_vol: r"|\mathcal{A}|",
    A_bar: r"\bar{A}",
    R_range: r"\mathbf{R}",
    mu_bar: r"\bar\mu",
    var: r"\mathrm{Var}[\tilde\nabla_{\theta_i} J_\mu(\theta)]",
}


def latex(expr: sp.Basic | str, **kwargs: object) -> str:
    """LaTeX of ``expr`` with the thesis's symbol names (strings pass through).

    Parameters
    ----------
    expr : sympy expression or str
    **kwargs
        Forwarded to :func:`sympy.latex`.
    """
    if isinstance(expr, str):
        return expr
    return sp.latex(expr, symbol_names=LATEX_NAMES, **kwargs)


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Rationalise denominators and simplify (for display and exact comparison)."""
    return sp.simplify(sp.radsimp(sp.simplify(expr)))


def _is_zero(expr: sp.Expr) -> bool:
    return sp.simplify(expr) == 0


# --------------------------------------------------------------------------- Section 4.2
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

    Lemma 3.1 of [24] has the penalties
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
        "matches_printed": sp.true if _is_zero(total - penalty_constant()) else sp.false,
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
    r"""Bound (3.7) of [24] for the scalar step :math:`\Lambda = \alpha I`:
    :math:`\alpha\|\nabla J\|_2^2 - c\,\alpha^2\|\nabla J\|_1^2`."""
    return alpha * g2**2 - c * alpha**2 * g1**2


def maximise(bound: sp.Expr, var: sp.Symbol = alpha) -> tuple[sp.Expr, sp.Expr]:
    """Maximise a bound that is concave in ``var`` by solving d/dvar = 0.

    Parameters
    ----------
    bound : sympy.Expr
    var : sympy.Symbol

    Returns
    -------
    (argmax, max) : tuple of sympy.Expr
        Simplified. Raises ``ValueError`` unless exactly one stationary point has a
        second derivative sympy can prove negative.
    """
    second = sp.diff(bound, var, 2)
    points = [p for p in sp.solve(sp.Eq(sp.diff(bound, var), 0), var) if sp.simplify(second.subs(var, p)).is_negative]
    if len(points) != 1:
        raise ValueError(f"bound must have exactly one provable maximiser in {var}, got {points}")
    arg = sp.factor(sp.simplify(points[0]))
    return arg, sp.factor(sp.simplify(bound.subs(var, arg)))


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
    r"""Corollary 4.2.5: coordinate step vs the scalar step of [24].

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


# --------------------------------------------------------------------------- Section 4.3
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
    alpha_star = _tidy(corollary_4_2_8()["alpha_star"].subs(eps, d / x_star))
    ups_star = _tidy(ups_x.subs(x, x_star))
    improvement_star = _tidy(ups_star * n_star)
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
        "N_star_over_N_0": _tidy(n_star / n0),
        "upsilon_at_N_0": sp.simplify(ups_x.subs(x, x0)),
        "second_derivative_sign_at_x_star": sp.sign(_tidy(second)),
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


def printed_theorem_4_3_2() -> dict[str, sp.Expr]:
    r"""The statements of Theorem 4.3.2 and its proof *as printed* (for comparison only).

    Returns
    -------
    dict
        ``N_0``, ``N_star``, ``alpha_star``, ``upsilon_star``
        (:math:`(4977-1207\sqrt{17})g^4/(32d^2)`), ``improvement_star``
        (:math:`(393-95\sqrt{17})g^2/8`), ``improvement_lower`` (:math:`0.16 g^2`) and
        ``upsilon_proof`` (the garbled :math:`\Upsilon_\delta` of the proof,
        :math:`(g - \frac{d/\sqrt N}{4c})^4 / (4c(g + \frac{d/\sqrt N}{2})^2 N)`).
    """
    s17 = sp.sqrt(17)
    return {
        "N_0": d**2 / g**2,
        "N_star": (13 + 3 * s17) * d**2 / (2 * g**2),
        "alpha_star": (13 - 3 * s17) / (4 * c),
        "upsilon_star": (4977 - 1207 * s17) * g**4 / (32 * d**2),
        "improvement_star": (393 - 95 * s17) / 8 * g**2,
        "improvement_lower": sp.Rational(16, 100) * g**2,
        "upsilon_proof": (g - (d / sp.sqrt(N)) / (4 * c)) ** 4 / (4 * c * (g + (d / sp.sqrt(N)) / 2) ** 2 * N),
    }


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
    r"""Section 4.3.1: explicit :math:`N^*` for REINFORCE and G(PO)MDP (Lemmas 5.4/5.5 of [24]).

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


def _printed_bernstein_factors() -> tuple[sp.Expr, sp.Expr]:
    first = (d * x + f - g * x**2) ** 3
    second = 2 * d**2 * x**2 + 5 * d * f * x + 3 * d * g * x**3 + 3 * f**2 + 6 * f * g * x**2 - g**2 * x**4
    return first, second


@cache
def _bernstein_upsilon_derivative() -> dict[str, sp.Expr]:
    deriv = sp.factor(sp.together(sp.diff(bernstein_upsilon(), N).subs(N, x**2)))
    numerator, denominator = sp.fraction(deriv)
    first, second = _printed_bernstein_factors()
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
    _, second = _printed_bernstein_factors()
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
    _, second = _printed_bernstein_factors()
    x0 = sp.Symbol("x_0", positive=True)
    at_x0 = sp.expand(sp.simplify(second.subs(x, x0).subs(g, (d * x0 + f) / x0**2)))
    return {"second_factor_at_x0": at_x0, "is_positive": sp.true if at_x0.is_positive else sp.false}


# --------------------------------------------------------------------------- Section 3.3.2 / 5.2.1
def scalar_step_comparison() -> dict[str, sp.Expr]:
    r"""Printed scalar step sizes of [24] vs :math:`\|g\|_2^2/(2c\|g\|_1^2)` with c of Theorem 4.2.3.

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


# --------------------------------------------------------------------------- Appendix A
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


# --------------------------------------------------------------------------- Appendix B
def softmax_constants() -> dict[str, sp.Expr]:
    r"""Theorem B.0.6: constants c and b for softmax policies.

    Lemma 3.1 of [24] with Lemma B.0.4 (remainder :math:`\ge -6M_\varphi^2 D^2`,
    :math:`D = \|\Lambda\nabla J\|_1`), Lemma B.0.5 (:math:`\|\pi'-\pi\|_\infty^2 \le 4M_\varphi D`),
    :math:`\sum_a|Q| \le |\mathcal A|R/(1-\gamma)` and :math:`\|Q\|_\infty \le R/(1-\gamma)`.

    Returns
    -------
    dict
        ``c``, ``b`` (derived), ``printed_c``, ``printed_b``.
    """
    q_inf = R / (1 - gamma)
    c_soft = 6 * M_phi**2 * A_vol * q_inf / (1 - gamma)
    b_soft = gamma / (2 * (1 - gamma) ** 2) * 4 * M_phi * q_inf
    return {
        "c": c_soft,
        "b": b_soft,
        "printed_c": 6 * M_phi**2 * A_vol * R / (1 - gamma) ** 2,
        "printed_b": 2 * gamma * M_phi * R / (1 - gamma) ** 3,
    }


@cache
def _corollary_b_0_7() -> dict[str, sp.Expr]:
    bound = alpha * g**2 - c * alpha**2 * g**2 - b * alpha * g
    a_star, value = maximise(bound)
    return {
        "bound": bound,
        "alpha_star": a_star,
        "improvement": value,
        "printed_alpha_star": (1 - b / g) / (2 * c),
        "printed_improvement": (g - b) ** 2 / (4 * c),
    }


def corollary_b_0_7() -> dict[str, sp.Expr]:
    r"""Corollary B.0.7: maximise :math:`\alpha g^2 - c\alpha^2g^2 - b\alpha g` (:math:`\Lambda = \alpha e_k`).

    Returns
    -------
    dict
        ``bound``, ``alpha_star`` (:math:`(1 - b/g)/(2c)`), ``improvement``
        (:math:`(g-b)^2/(4c)`), and the printed versions.
    """
    return dict(_corollary_b_0_7())


# --------------------------------------------------------------------------- errata / verified
Affects = Literal["no", "yes", "possibly"]


@dataclass(frozen=True)
class Erratum:
    """A printed statement that differs from its derivation.

    Attributes
    ----------
    id : str
    location : str
        Thesis section / equation.
    printed, corrected : sympy.Expr or str
        Expressions where possible, LaTeX (or plain text) strings otherwise.
    explanation : str
        One line.
    affects_experiments : {"no", "yes", "possibly"}
    impact : str
        Why (not) the experiments are affected.
    kind : str
        ``"formula"``, ``"proof"``, ``"statement"``, ``"algorithm"``, ``"reference"`` or
        ``"discrepancy"`` (printed text vs the settings the experiments used).
    """

    id: str
    location: str
    printed: sp.Basic | str
    corrected: sp.Basic | str
    explanation: str
    affects_experiments: Affects
    impact: str
    kind: str


@dataclass(frozen=True)
class Verified:
    """A printed statement checked against its derivation and found correct.

    Attributes
    ----------
    id, location : str
    printed : sympy.Expr or str
    derived : sympy.Expr or str
    method : str
        How it was checked (function name, test).
    relation : {"equal", "proportional", "supports"}
        ``"equal"``: ``simplify(printed - derived) == 0``; ``"proportional"``: their ratio
        is a constant (stated in ``method``); ``"supports"``: ``derived`` is the quantity
        that proves the printed claim (explained in ``method``).
    """

    id: str
    location: str
    printed: sp.Basic | str
    derived: sp.Basic | str
    method: str
    relation: Literal["equal", "proportional", "supports"] = "equal"


@cache
def _errata() -> tuple[Erratum, ...]:
    t = theorem_4_3_2()
    p = printed_theorem_4_3_2()
    hd = hoeffding_d()
    rng = gradient_range_bound()
    sc = scalar_step_comparison()
    return (
        Erratum(
            "thm_4_3_2_upsilon_proof",
            "Appendix A, proof of Theorem 4.3.2 (expression of Upsilon_delta(Lambda*, N))",
            p["upsilon_proof"],
            t["upsilon"],
            "The printed Upsilon divides d/sqrt(N) by 4c in the numerator and by 2 in the denominator; "
            "substituting eps = d/sqrt(N) into Corollary 4.2.8 gives neither (Section 4.3.3 prints it correctly).",
            "no",
            "Only the displayed formula; N* and alpha* of the theorem are derived from the correct one.",
            "formula",
        ),
        Erratum(
            "thm_4_3_2_upsilon_star",
            "Appendix A, proof of Theorem 4.3.2 (Upsilon*)",
            p["upsilon_star"],
            t["upsilon_star"],
            "Upsilon at N* is (4977 - 1207 sqrt 17) g^4 / (128 c d^2): the printed value lacks the factor 1/(4c).",
            "no",
            "Upsilon* is not used by the algorithm.",
            "formula",
        ),
        Erratum(
            "thm_4_3_2_improvement",
            "Theorem 4.3.2 (statement, Section 4.3) and its proof (N* Upsilon*)",
            p["improvement_star"],
            t["improvement_star"],
            "The guaranteed improvement N* Upsilon* is (393 - 95 sqrt 17) g^2 / (32 c), about 0.0408 g^2 / c, "
            "not (393 - 95 sqrt 17) g^2 / 8 >= 0.16 g^2 (the 1/(4c) of Corollary 4.2.8 was dropped).",
            "no",
            "The algorithm uses N* and alpha*, both correct; only the stated size of the guarantee is off.",
            "formula",
        ),
        Erratum(
            "hoeffding_exponent",
            "Section 4.3.2 (Hoeffding's bound)",
            hd["printed_tail"],
            hd["tail"],
            "Hoeffding's tail for a mean of N samples of range R is 2 exp(-2 N eps^2 / R^2); the printed "
            "exponent -2 eps^2 / (N R^2) would make eps grow like sqrt(N). The printed d_delta is the correct one.",
            "no",
            "d_delta = R sqrt(ln(2/delta)/2) as printed follows from the correct inequality.",
            "formula",
        ),
        Erratum(
            "range_definition",
            "Section 4.3.2 (definition of the range R)",
            r"\mathbf{R} = |\sup(\tilde\nabla_{\theta_i} J_\mu(\theta))|",
            r"\mathbf{R} = \sup\tilde\nabla_{\theta_i} J_\mu(\theta) - \inf\tilde\nabla_{\theta_i} J_\mu(\theta)"
            r"\ \le 2\sup|\tilde\nabla_{\theta_i} J_\mu(\theta)|",
            "Hoeffding's and Bernstein's bounds need the range (sup - inf) of the sample, "
            "not the magnitude of its supremum.",
            "no",
            "The empirical-range variants use max - min (the range); for the rigorous variants see lemma_4_3_3_range.",
            "statement",
        ),
        Erratum(
            "lemma_4_3_3_range",
            "Lemma 4.3.3 and its proof (Appendix A)",
            rng["printed_bound"],
            rng["worst_case_range"],
            "The proof multiplies the range of the score (2 M Abar / sigma^2, fixed state) by the return magnitude; "
            "the range of the product can reach 2 H M (Abar + |theta^T phi|) R (1 - gamma^H) / (sigma^2 (1 - gamma)) "
            "(no baseline; a baseline can double it), so the bound fails 'for all theta' "
            "(e.g. H = 20, gamma = 0.9, |theta^T phi| > 0.14 Abar). The printed value bounds sup|sample| only when "
            "|theta^T phi| <= Abar.",
            "possibly",
            "The rigorous-range Hoeffding/Bernstein runs of Table 5.2 take R from this lemma; the LQG's actual "
            "sample range is far smaller (the thesis calls the bound very loose), so their safety is likely "
            "unaffected, "
            "but it is not guaranteed by the lemma.",
            "statement",
        ),
        Erratum(
            "algorithm_4_1_step_line",
            "Algorithm 4.1 (step-size line)",
            r"\epsilon \leftarrow \frac{d_\delta/\sqrt{N}}"
            r"{2c(\|\hat\nabla_\theta J_\mu(\theta)\|_\infty - \epsilon)^2}",
            r"\epsilon \leftarrow d_\delta/\sqrt{N};\quad \alpha \leftarrow "
            r"\frac{(\|\hat\nabla_\theta J_\mu(\theta)\|_\infty - \epsilon)^2}"
            r"{2c(\|\hat\nabla_\theta J_\mu(\theta)\|_\infty + \epsilon)^2}",
            "Two lines were merged: eps is set to d/sqrt(N) and alpha, used in the next line but never set, "
            "follows Corollary 4.2.8 (as the text after the algorithm says).",
            "no",
            "The text after the algorithm and Corollary 4.2.8 fix the intended computation.",
            "algorithm",
        ),
        Erratum(
            "algorithm_4_1_stopping",
            "Algorithm 4.1 (while condition and update order)",
            r"\textbf{while } \epsilon < |\hat\nabla_\theta J_\mu(\theta)|\textbf{ do } \dots "
            r"\theta_k \leftarrow \theta_k + \alpha\hat\nabla_{\theta_k} J_\mu(\theta)",
            r"\textbf{while } \epsilon < \|\hat\nabla_\theta J_\mu(\theta)\|_\infty;"
            r"\ \alpha = 0 \text{ if } \epsilon \ge \|\hat\nabla_\theta J_\mu(\theta)\|_\infty",
            "The condition should compare eps with ||g||_inf (Assumption 4.2.7); it is tested only after the update, "
            "so a batch violating 4.2.7 still moves theta: Corollary 4.2.8's step "
            "(g - eps)^2 / (2c (g + eps)^2) stays positive for eps > g (the saturated bound of Theorem 4.2.6 "
            "is maximised by alpha = 0).",
            "possibly",
            "At most the last update of a run that stops on Assumption 4.2.7 (runs in Chapter 5 stop on a "
            "trajectory budget instead).",
            "algorithm",
        ),
        Erratum(
            "algorithm_4_1_min_batch",
            "Algorithm 4.1 (batch-size clipping)",
            r"N \leftarrow \max\{2, \min\{N, \bar N\}\}",
            r"N \leftarrow \max\{N_{\min}, \min\{N, \bar N\}\},\ N_{\min} = 100",
            "The printed algorithm clips at 2; the authors' experiments start at and clip to N_min = 100 "
            "(SETTINGS.md).",
            "yes",
            "The published curves were produced with N_min = 100.",
            "discrepancy",
        ),
        Erratum(
            "lemma_a_0_2_pinsker",
            "Appendix A, proof of Lemma A.0.2",
            r"\sup_s\|\pi_{\theta'}-\pi_\theta\|_\infty^2 \geqslant \sup_s 2H(\pi_{\theta'}\|\pi_\theta) "
            r"= \sup_s\frac{1}{\sigma^2}\sum_i(\nabla_{\theta_i}J\,\alpha_i\varphi_i(s))^2 "
            r"\geqslant \frac{M_\varphi^2\|\Lambda\nabla_\theta J\|_1^2}{\sigma^2}",
            r"\sup_s\|\pi_{\theta'}-\pi_\theta\|_1^2 \leqslant \sup_s 2H(\pi_{\theta'}\|\pi_\theta) "
            r"= \sup_s\frac{1}{\sigma^2}\Big(\sum_i\nabla_{\theta_i}J\,\alpha_i\varphi_i(s)\Big)^2 "
            r"\leqslant \frac{M_\varphi^2\|\Lambda\nabla_\theta J\|_1^2}{\sigma^2}",
            "Pinsker gives ||p - q||_1^2 <= 2 KL (both inequalities are reversed in print), the per-state norm is "
            "L1, and 2 KL = (Delta theta^T phi)^2 / sigma^2 is a squared sum, not a sum of squares.",
            "no",
            "The lemma's statement (<=) is correct and is what Theorem 4.2.3 uses.",
            "proof",
        ),
        Erratum(
            "lemma_a_0_1_taylor",
            "Appendix A, proof of Lemma A.0.1 (Taylor remainder)",
            r"R_1 = \sum_{i=1}^m\sum_{j=1}^m \partial_{ij}\pi\,\frac{\Delta\theta_i\Delta\theta_j}{1+I(i=j)},\quad "
            r"\sum_{i,j}\frac{a_ia_j}{1+I(i=j)} = \Big(\sum_i a_i\Big)^2",
            r"R_1 = \frac12\sum_{i=1}^m\sum_{j=1}^m \partial_{ij}\pi\,\Delta\theta_i\Delta\theta_j "
            r"\geqslant -\frac{M_\varphi^2\|\Lambda\nabla_\theta J\|_1^2}{2\sqrt{2\pi}\sigma^3}",
            "With weights 1/(1 + I(i=j)) on the full double sum the off-diagonal terms are counted twice, and the "
            "following '=' is false (the sum is (sum a)^2 - sum a_i^2 / 2). The correct remainder gives half the "
            "printed constant, so the lemma holds but is loose by a factor 2.",
            "no",
            "The printed constant is valid (conservative); c would shrink to R M^2/((1-gamma)^2 sigma^2) "
            "(|A|/(2 sqrt(2 pi) sigma) + gamma/(2(1-gamma))).",
            "proof",
        ),
        Erratum(
            "lemma_4_2_2_q_sign",
            "Lemma 4.2.2 (statement) and its proof, term (2)",
            r"\frac{1}{\sqrt{2\pi}\sigma}\int_S d_\mu^{\pi_\theta}(s)\int_A Q^{\pi_\theta}(s,a)\,da\,ds,"
            r"\quad \|Q^{\pi_\theta}\|_\infty = \sup_{s,a} Q^{\pi_\theta}(s,a)",
            r"\frac{1}{\sqrt{2\pi}\sigma}\int_S d_\mu^{\pi_\theta}(s)\int_A |Q^{\pi_\theta}(s,a)|\,da\,ds,"
            r"\quad \|Q^{\pi_\theta}\|_\infty = \sup_{s,a} |Q^{\pi_\theta}(s,a)|",
            "Lemma A.0.1 is a lower bound on pi' - pi; multiplying it by Q(s,a) < 0 reverses it, so the remainder "
            "must be weighted by |Q|. With negative rewards (the LQG) the printed penalty would become a bonus.",
            "no",
            "Theorem 4.2.3 (whose c the experiments use) bounds |Q| <= R/(1-gamma) and is correct.",
            "statement",
        ),
        Erratum(
            "thm_4_2_6_probability",
            "Theorem 4.2.6, Corollary 4.2.8, Theorem 4.3.2 (confidence (1 - delta)^m)",
            (1 - delta) ** sp.Symbol("m", positive=True, integer=True),
            1 - sp.Symbol("m", positive=True, integer=True) * delta,
            "The m per-component events are computed from the same trajectories and are not independent; "
            "without independence the union bound gives only 1 - m delta, which is <= (1 - delta)^m.",
            "no",
            "The probability is not used by the algorithm; for the 1-D LQG (m = 1) both are 1 - delta.",
            "statement",
        ),
        Erratum(
            "scalar_step_5_2_1",
            "Section 5.2.1 (scalar step size of [24])",
            sc["printed_alpha_5_2_1"],
            sc["derived_alpha"],
            "The printed alpha-hat* has ||g/2||_2^2 = ||g||_2^2 / 4 (and an unbalanced parenthesis); Section 3.3.2 "
            "and the maximisation of bound (3.7) give ||g||_2^2, i.e. four times the printed step.",
            "possibly",
            "No code for Section 5.2 was published; if the printed formula was used, the scalar baseline of "
            "Figures 5.5-5.6 ran with a step four times too small.",
            "formula",
        ),
        Erratum(
            "ref_theorem_4_3_2_in_4_3",
            "Section 4.3, text after Figure 4.1",
            "such as the one proposed with Theorem 4.3.2",
            "such as the one proposed with Corollary 4.2.8",
            "The adaptive step that is kept small against bad estimates is Corollary 4.2.8's; Theorem 4.3.2 is "
            "the constant-step result being contrasted.",
            "no",
            "Cross-reference only.",
            "reference",
        ),
        Erratum(
            "ref_corollary_4_2_5_in_4_2_2",
            "Section 4.2.2, before Corollary 4.2.8",
            "The derivation of the optimal step size is similar to the one of Corollary 4.2.5",
            "The derivation of the optimal step size is similar to the one of Corollary 4.2.4",
            "Corollary 4.2.4 derives the optimal step; 4.2.5 compares improvements.",
            "no",
            "Cross-reference only.",
            "reference",
        ),
        Erratum(
            "ref_theorem_3_3",
            "Section 4.2.1 (after Theorem 4.2.3) and Appendix A, proof of Theorem 4.2.6",
            "the bound from Theorem 3.3",
            "the bound from Theorem 4.2.3",
            "There is no Theorem 3.3 in the thesis; the bound meant is Theorem 4.2.3 (likely the paper's numbering).",
            "no",
            "Cross-reference only.",
            "reference",
        ),
        Erratum(
            "ref_assumption_3_1",
            "Appendix A, proof of Lemma A.0.1",
            "Lemma 4.1 from [24] and Assumption 3.1",
            "Lemma 4.1 from [24] and Assumption 4.2.1",
            "The feature bound is Assumption 4.2.1.",
            "no",
            "Cross-reference only.",
            "reference",
        ),
        Erratum(
            "thm_4_3_2_N1",
            "Appendix A, proof of Theorem 4.3.2",
            r"\Upsilon_\delta(\Lambda^*, N_1) = 0",
            r"\Upsilon_\delta(\Lambda^*, N_0) = 0",
            "N_1 is not defined; the zero of Upsilon is at N_0.",
            "no",
            "Typo only.",
            "reference",
        ),
    )


def errata() -> list[Erratum]:
    """Every printed statement found to differ from its derivation (see :class:`Erratum`)."""
    return list(_errata())


@cache
def _verified() -> tuple[Verified, ...]:
    t = theorem_4_3_2()
    p = printed_theorem_4_3_2()
    c424 = corollary_4_2_4()
    c425 = corollary_4_2_5()
    c428 = corollary_4_2_8()
    cheb = chebyshev_d()
    cns = chebyshev_n_star()
    hd = hoeffding_d()
    bn = bernstein_n_zero()
    bd = bernstein_descartes()
    sc = scalar_step_comparison()
    soft = softmax_constants()
    b07 = corollary_b_0_7()
    gh = gaussian_density_hessian()
    g_inf = sp.Symbol("g_inf", positive=True)
    return (
        Verified(
            "thm_4_2_3_c",
            "Theorem 4.2.3 (constant c)",
            penalty_constant(),
            penalty_constant_derivation()["c"],
            "penalty_constant_derivation: Lemma 3.1 of [24] + Lemmas A.0.1, A.0.2, |Q| <= R/(1-gamma)",
        ),
        Verified("cor_4_2_4_alpha", "Corollary 4.2.4", 1 / (2 * c), c424["alpha_star"], "maximise d/dalpha = 0"),
        Verified(
            "cor_4_2_4_improvement",
            "Corollary 4.2.4",
            g**2 / (4 * c),
            c424["improvement"],
            "maximise; coordinate_descent_reduction for optimality over all diagonal Lambda >= 0",
        ),
        Verified(
            "cor_4_2_5_scalar_step",
            "Corollary 4.2.5 / [24]",
            g2**2 / (2 * c * g1**2),
            c425["scalar_alpha_star"],
            "maximise alpha ||g||_2^2 - c alpha^2 ||g||_1^2",
        ),
        Verified(
            "cor_4_2_5_inequality",
            "Corollary 4.2.5",
            sp.Ge(g_inf**2 / (4 * c), g2**4 / (4 * c * g1**2)),
            c425["difference"],
            "norm_inequality: symbolic proof for general m",
            relation="supports",
        ),
        Verified(
            "cor_4_2_8_alpha",
            "Corollary 4.2.8",
            (g - eps) ** 2 / (2 * c * (g + eps) ** 2),
            c428["alpha_star"],
            "maximise",
        ),
        Verified(
            "cor_4_2_8_improvement",
            "Corollary 4.2.8",
            (g - eps) ** 4 / (4 * c * (g + eps) ** 2),
            c428["improvement"],
            "maximise",
        ),
        Verified(
            "sec_4_2_2_selection",
            "Section 4.2.2 (k = argmax |g_i|)",
            "monotone non-decreasing in |g_k|",
            c428["selection_derivative"],
            "derivative 4 eps (g - eps) / (g + eps)^3 >= 0",
            relation="supports",
        ),
        Verified(
            "cor_4_2_8_actual_update",
            "Theorem 4.2.6 / Corollary 4.2.8 for the update actually made",
            improvement_bound_approx(),
            alpha * g * (g - eps) - c * alpha**2 * g**2,
            "The theorem is stated for theta + Lambda grad J; Algorithm 4.1 moves along the estimate. For the "
            "chosen coordinate (|g_k| >= eps) the valid bound alpha |g|(|g| - eps) - c alpha^2 g^2 exceeds the "
            "printed one by alpha eps (g - eps) + c alpha^2 eps (2g + eps) >= 0, so the guarantee holds.",
            relation="supports",
        ),
        Verified("thm_4_3_2_N0", "Section 4.3 / Theorem 4.3.2 (N_0)", p["N_0"], t["N_0"], "theorem_4_3_2"),
        Verified(
            "thm_4_3_2_N_star",
            "Theorem 4.3.2 (N*)",
            p["N_star"],
            t["N_star"],
            "theorem_4_3_2: roots of dUpsilon/dN, N = x^2",
        ),
        Verified(
            "thm_4_3_2_alpha",
            "Theorem 4.3.2 (alpha*, constant step)",
            p["alpha_star"],
            t["alpha_star"],
            "theorem_4_3_2",
        ),
        Verified(
            "thm_4_3_2_N_star_feasible",
            "Section 4.3 (N* >= N_0 always)",
            "N^* \\geq N_0",
            t["N_star_over_N_0"],
            "ratio (13 + 3 sqrt 17)/2 > 1",
            relation="supports",
        ),
        Verified(
            "fig_4_1_shape",
            "Section 4.3, Figure 4.1 text",
            "Upsilon -> infinity as N -> 0, -> 0 as N -> infinity, N_0 a zero (global minimum)",
            sp.Tuple(t["upsilon_limit_zero"], t["upsilon_limit_infinity"], t["upsilon_at_N_0"]),
            "theorem_4_3_2 limits",
            relation="supports",
        ),
        Verified("chebyshev_d", "Section 4.3.1", sp.sqrt(var / delta), cheb["d"], "chebyshev_d"),
        Verified(
            "chebyshev_N_star_reinforce",
            "Section 4.3.1 (REINFORCE N*)",
            cns["printed_N_star_reinforce"],
            cns["N_star_reinforce"],
            "N* of Theorem 4.3.2 with the printed d (consistency; [24]'s Lemma 5.4 itself not re-derived)",
        ),
        Verified(
            "chebyshev_N_star_gpomdp",
            "Section 4.3.1 (G(PO)MDP N*)",
            cns["printed_N_star_gpomdp"],
            cns["N_star_gpomdp"],
            "as above, Lemma 5.5 of [24]",
        ),
        Verified("hoeffding_d", "Section 4.3.2", hd["printed_d"], hd["d"], "hoeffding_d (from the correct tail)"),
        Verified(
            "bernstein_d_f",
            "Section 4.3.3",
            "d = sqrt(2 S_N ln(3/delta)), f = 3 R ln(3/delta)",
            sp.sqrt(2 * S_N * sp.log(3 / delta) / N) + 3 * R_range * sp.log(3 / delta) / N,
            "eps(N) = d/sqrt(N) + f/N read off the printed bound",
            relation="supports",
        ),
        Verified(
            "bernstein_S_N",
            "Section 4.3.3 (S_N with 1/N)",
            r"S_N = \frac{1}{N}\sum_i (X_i - \bar X_N)^2",
            "the printed bound sqrt(2 S_N ln(3/delta)/N) + 3R ln(3/delta)/N is the empirical Bernstein bound of "
            "Audibert, Munos & Szepesvari (2009, Thm 1) / Mnih, Szepesvari & Audibert (2008), stated with the "
            "1/N sample variance; Maurer & Pontil's bound (unbiased variance) has ln(2/delta) and 7/(3(N-1))",
            "literature comparison; the reference list is not in the extracted text, so [15]'s identity is "
            "unchecked. Using ddof = 1 (SETTINGS.md) only enlarges d (conservative).",
            relation="supports",
        ),
        Verified("bernstein_N0", "Section 4.3.3 (N_0)", bn["printed_N_0"], bn["N_0"], "bernstein_n_zero"),
        Verified(
            "bernstein_factors",
            "Section 4.3.3 (factors of dUpsilon/dN)",
            sp.Mul(*_printed_bernstein_factors(), evaluate=False),
            bernstein_upsilon_derivative()["numerator"],
            "bernstein_upsilon_derivative: numerator = -1 x (printed product)",
            relation="proportional",
        ),
        Verified(
            "bernstein_descartes",
            "Section 4.3.3 (unique root)",
            "one root",
            sp.Integer(bd["sign_changes"]),
            "bernstein_descartes + bernstein_root_beyond_n_zero (the root exceeds N_0 and is the maximum)",
            relation="supports",
        ),
        Verified(
            "scalar_step_3_3_2",
            "Section 3.3.2 (alpha* of [24])",
            sc["printed_alpha_3_3_2"],
            sc["derived_alpha"],
            "scalar_step_comparison: ratio 1",
        ),
        Verified(
            "scalar_improvement_3_3_2",
            "Section 3.3.2 (improvement of [24])",
            sc["printed_improvement_3_3_2"],
            sc["derived_improvement"],
            "scalar_step_comparison: ratio 1",
        ),
        Verified(
            "bound_3_7",
            "Section 3.3.2, bound (3.7)",
            sc["printed_bound_3_7"],
            scalar_step_bound().subs(c, penalty_constant()),
            "same c as Theorem 4.2.3",
        ),
        Verified(
            "lemma_a_0_1_hessian",
            "Lemma A.0.1 (|d2 pi| <= |phi_i phi_j| / (sqrt(2 pi) sigma^3))",
            1 / (sp.sqrt(2 * sp.pi)),
            gh["sup_abs_shape"] / sp.sqrt(2 * sp.pi),
            "gaussian_density_hessian + lemma_checks.check_lemma_a01_hessian",
        ),
        Verified(
            "lemma_a_0_1_statement",
            "Lemma A.0.1 (statement)",
            M_phi**2 / (sp.sqrt(2 * sp.pi) * sigma**3),
            M_phi**2 / (2 * sp.sqrt(2 * sp.pi) * sigma**3),
            "valid (the correct remainder gives half the constant); lemma_checks.check_lemma_a01_taylor",
            relation="supports",
        ),
        Verified(
            "lemma_a_0_2_statement",
            "Lemma A.0.2 (statement)",
            M_phi**2 / sigma**2,
            gaussian_kl()["two_kl"],
            "Pinsker with 2 KL = (Delta theta^T phi)^2 / sigma^2 <= M^2 ||Delta theta||_1^2 / sigma^2; "
            "lemma_checks.check_lemma_a02",
            relation="supports",
        ),
        Verified(
            "lemma_b_0_3",
            "Lemma B.0.3 (softmax second derivative <= 6 M^2)",
            6 * M_phi**2,
            "sup over draws ~0.385 M^2",
            "lemma_checks.check_lemma_b03 (valid, conservative)",
            relation="supports",
        ),
        Verified(
            "lemma_b_0_5",
            "Lemma B.0.5 (||pi' - pi||^2 <= 4 M ||Delta theta||_1)",
            4 * M_phi,
            "KL <= 2 M ||Delta theta||_1",
            "lemma_checks.check_lemma_b05",
            relation="supports",
        ),
        Verified("thm_b_0_6_c", "Theorem B.0.6 (c)", soft["printed_c"], soft["c"], "softmax_constants"),
        Verified("thm_b_0_6_b", "Theorem B.0.6 (b)", soft["printed_b"], soft["b"], "softmax_constants"),
        Verified("cor_b_0_7_alpha", "Corollary B.0.7", b07["printed_alpha_star"], b07["alpha_star"], "maximise"),
        Verified(
            "cor_b_0_7_improvement", "Corollary B.0.7", b07["printed_improvement"], b07["improvement"], "maximise"
        ),
    )


def verified() -> list[Verified]:
    """Printed statements checked against their derivation and found correct (see :class:`Verified`)."""
    return list(_verified())


def __getattr__(name: str) -> object:
    # ERRATA / VERIFIED are computed on first access (a few seconds of sympy), not at import.
    if name == "ERRATA":
        return errata()
    if name == "VERIFIED":
        return verified()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
