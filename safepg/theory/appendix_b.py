r"""Appendix B: softmax policies.

The constants :math:`c` and :math:`b` of Theorem B.0.6 and the optimal coordinate step of
Corollary B.0.7.
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from safepg.theory.symbols import A_vol, M_phi, R, alpha, b, c, g, gamma, maximise


def softmax_constants() -> dict[str, sp.Expr]:
    r"""Theorem B.0.6: constants c and b for softmax policies.

    Lemma 3.1 of Pirotta et al. (2013) with Lemma B.0.4 (remainder :math:`\ge -6M_\varphi^2 D^2`,
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


__all__ = ["corollary_b_0_7", "softmax_constants"]
