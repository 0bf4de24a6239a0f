r"""Shared symbols of the derivations, their LaTeX names, and the helpers every derivation uses.

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
``mu_bar``  bound on the policy mean :math:`|\theta^T\varphi(s)| \le \bar\mu`, :math:`\ge 0`
``var``     variance of a gradient sample :math:`\mathrm{Var}[\tilde\nabla_{\theta_i} J_\mu(\theta)]`, > 0
``S_N``     sample variance of the empirical Bernstein bound, > 0
========== ===========================================================
"""

from __future__ import annotations

import sympy as sp

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
    text: str = sp.latex(expr, symbol_names=LATEX_NAMES, **kwargs)
    return text


def tidy(expr: sp.Expr) -> sp.Expr:
    """Rationalise denominators and simplify (for display and exact comparison)."""
    return sp.simplify(sp.radsimp(sp.simplify(expr)))


def is_zero(expr: sp.Expr) -> bool:
    """Whether ``expr`` simplifies to 0 (exact comparison of two derivations by their difference)."""
    return bool(sp.simplify(expr) == 0)


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


__all__ = ["A_bar", "A_vol", "H", "LATEX_NAMES", "M_phi", "N", "R", "R_range", "S_N", "alpha", "b", "c", "d", "delta",
           "eps", "f", "g", "g1", "g2", "gamma", "is_zero", "latex", "maximise", "mu_bar", "sigma", "tidy", "var", "x"]
