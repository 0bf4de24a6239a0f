r"""Symbolic derivations of Chapter 4 and Appendices A-B of the thesis (sympy).

Every public function returns sympy expressions (usually a ``dict`` of named
steps) so that a notebook can render them with :func:`latex`. Constants such as
:math:`13 \pm 3\sqrt{17}` come out of sympy's algebra; the only expressions typed in
from the thesis are the printed ones some derivations return next to their result for
comparison (the ``printed_*`` keys, and :func:`bernstein_derivative_factors`).

Modules (all their public names are available here):

- :mod:`safepg.theory.symbols`: the shared symbols (a table with their thesis notation),
  their LaTeX names and :func:`latex`, and the helpers :func:`tidy`, :func:`is_zero`,
  :func:`maximise`;
- :mod:`safepg.theory.step_size`: Section 4.2, the penalty constant, the improvement
  bounds and Corollaries 4.2.4, 4.2.5 and 4.2.8, and the scalar step of Pirotta et al. (2013)
  (Sections 3.3.2, 5.2.1);
- :mod:`safepg.theory.batch_size`: Section 4.3, :math:`\Upsilon_\delta`, Theorem 4.3.2 and
  the Chebyshev, Hoeffding and empirical Bernstein batch sizes;
- :mod:`safepg.theory.appendix_a`: the Gaussian-policy lemmas A.0.1 and A.0.2;
- :mod:`safepg.theory.appendix_b`: softmax policies, Theorem B.0.6 and Corollary B.0.7.

The statements as printed and the record of which differ from their derivation (errata)
and which were verified belong to the reproduction, :mod:`safepg.thesis.errata`.
"""

from __future__ import annotations

from safepg.theory.appendix_a import gaussian_density_hessian, gaussian_kl, taylor_remainder_weights
from safepg.theory.appendix_b import corollary_b_0_7, softmax_constants
from safepg.theory.batch_size import (
    bernstein_derivative_factors,
    bernstein_descartes,
    bernstein_n_zero,
    bernstein_root_beyond_n_zero,
    bernstein_upsilon,
    bernstein_upsilon_derivative,
    chebyshev_d,
    chebyshev_n_star,
    descartes_sign_changes,
    gradient_range_bound,
    hoeffding_d,
    theorem_4_3_2,
    upsilon,
)
from safepg.theory.step_size import (
    coordinate_descent_reduction,
    corollary_4_2_4,
    corollary_4_2_5,
    corollary_4_2_8,
    improvement_bound_approx,
    improvement_bound_coordinate,
    norm_inequality,
    penalty_constant,
    penalty_constant_derivation,
    scalar_step_bound,
    scalar_step_comparison,
)
from safepg.theory.symbols import (
    LATEX_NAMES,
    S_N,
    A_bar,
    A_vol,
    H,
    M_phi,
    N,
    R,
    R_range,
    alpha,
    b,
    c,
    d,
    delta,
    eps,
    f,
    g,
    g1,
    g2,
    gamma,
    is_zero,
    latex,
    maximise,
    mu_bar,
    sigma,
    tidy,
    var,
    x,
)

__all__ = [
    # symbols (see safepg.theory.symbols)
    "A_bar",
    "A_vol",
    "H",
    "LATEX_NAMES",
    "M_phi",
    "N",
    "R",
    "R_range",
    "S_N",
    "alpha",
    "b",
    "c",
    "d",
    "delta",
    "eps",
    "f",
    "g",
    "g1",
    "g2",
    "gamma",
    "mu_bar",
    "sigma",
    "var",
    "x",
    # helpers and derivations
    "bernstein_derivative_factors",
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
    "gaussian_density_hessian",
    "gaussian_kl",
    "gradient_range_bound",
    "hoeffding_d",
    "improvement_bound_approx",
    "improvement_bound_coordinate",
    "is_zero",
    "latex",
    "maximise",
    "norm_inequality",
    "penalty_constant",
    "penalty_constant_derivation",
    "scalar_step_bound",
    "scalar_step_comparison",
    "softmax_constants",
    "taylor_remainder_weights",
    "theorem_4_3_2",
    "tidy",
    "upsilon",
]
