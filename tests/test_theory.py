"""Symbolic derivations of Chapter 4 / Appendix B against the printed statements."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

import safepg.theory as T
from safepg import meta
from safepg.bounds import ErrorBound, gradient_range_bound, hoeffding, reinforce_variance_factor
from safepg.constants import TaskConstants
from safepg.thesis import errata

S17 = sp.sqrt(17)
pos = st.floats(min_value=1e-2, max_value=1e2, allow_nan=False)
K1 = TaskConstants(R=4.0, M_phi=2.0, action_volume=4.0, A_bar=2.0, gamma=0.9, H=20, sigma=1.0)
K1_SUBS = {T.R: 4, T.M_phi: 2, T.A_vol: 4, T.A_bar: 2, T.gamma: sp.Rational(9, 10), T.H: 20, T.sigma: 1}


def eq(a: sp.Expr, b: sp.Expr) -> bool:
    return sp.simplify(a - b) == 0


# --------------------------------------------------------------------------- Section 4.2
def test_penalty_constant_from_lemma_4_2_2():
    der = T.penalty_constant_derivation()
    assert der["matches_printed"] is sp.true
    assert eq(der["c"], T.penalty_constant())
    assert float(T.penalty_constant().subs(K1_SUBS)) == pytest.approx(meta.penalty_constant(K1), rel=1e-14)
    # the correct Taylor remainder halves only the |A| term
    half = T.penalty_constant_derivation(sp.Rational(1, 2))
    assert half["matches_printed"] is sp.false
    expected = T.R * T.M_phi**2 / ((1 - T.gamma) ** 2 * T.sigma**2) * (
        T.A_vol / (2 * sp.sqrt(2 * sp.pi) * T.sigma) + T.gamma / (2 * (1 - T.gamma))
    )
    assert eq(half["c"], expected)


def test_corollary_4_2_4():
    cor = T.corollary_4_2_4()
    assert eq(cor["alpha_star"], 1 / (2 * T.c))
    assert eq(cor["improvement"], T.g**2 / (4 * T.c))


def test_norm_inequality_general_m():
    ni = T.norm_inequality()
    assert ni["identity_holds"] is sp.true
    assert ni["summand_nonnegative"] is sp.true


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(min_value=-1e3, max_value=1e3, allow_nan=False), min_size=1, max_size=12))
def test_norm_inequality_numeric(v):
    a = np.abs(np.array(v))
    assert a.max() * a.sum() >= (a**2).sum() * (1 - 1e-12) - 1e-300


def test_corollary_4_2_5():
    cor = T.corollary_4_2_5()
    assert eq(cor["scalar_alpha_star"], T.g2**2 / (2 * T.c * T.g1**2))
    assert eq(cor["scalar_improvement"], T.g2**4 / (4 * T.c * T.g1**2))
    gi = sp.Symbol("g_inf", positive=True)
    assert eq(cor["difference"], (gi * T.g1 - T.g2**2) * (gi * T.g1 + T.g2**2) / (4 * T.c * T.g1**2))


def test_corollary_4_2_8():
    cor = T.corollary_4_2_8()
    assert eq(cor["alpha_star"], (T.g - T.eps) ** 2 / (2 * T.c * (T.g + T.eps) ** 2))
    assert eq(cor["improvement"], (T.g - T.eps) ** 4 / (4 * T.c * (T.g + T.eps) ** 2))
    assert eq(cor["alpha_star"].subs(T.eps, 0), T.corollary_4_2_4()["alpha_star"])
    assert eq(cor["selection_derivative"], 4 * T.eps * (T.g - T.eps) / (T.g + T.eps) ** 3)


def test_coordinate_descent_reduction_reproduces_corollaries():
    red = T.coordinate_descent_reduction()
    r = sp.Symbol("r", positive=True)
    assert eq(red["value"].subs({T.b: 0, r: T.g}), T.g**2 / (4 * T.c))
    rate = (T.g - T.eps) ** 2 / (T.g + T.eps)
    cor = T.corollary_4_2_8()
    assert eq(red["value"].subs({T.b: 0}).subs(r, rate), cor["improvement"])
    assert eq(red["S_star"].subs({T.b: 0}).subs(r, rate) / (T.g + T.eps), cor["alpha_star"])
    assert eq(red["value"].subs(r, T.g), T.corollary_b_0_7()["improvement"])


@settings(max_examples=100, deadline=None)
@given(
    st.lists(st.floats(min_value=-10, max_value=10, allow_nan=False), min_size=2, max_size=6),
    st.lists(st.floats(min_value=0, max_value=1, allow_nan=False), min_size=6, max_size=6),
    st.floats(min_value=0.1, max_value=10),
)
def test_no_diagonal_step_beats_the_coordinate_step(grad, lam, c):
    grad = np.array(grad)
    lam = np.array(lam[: grad.size])
    bound = lam @ grad**2 - c * np.sum(lam * np.abs(grad)) ** 2
    assert bound <= np.max(np.abs(grad)) ** 2 / (4 * c) * (1 + 1e-12) + 1e-12


# --------------------------------------------------------------------------- Theorem 4.3.2
def test_theorem_4_3_2_matches_printed_where_printed_is_right():
    t, p = T.theorem_4_3_2(), errata.printed_theorem_4_3_2()
    assert eq(t["N_0"], p["N_0"])
    assert eq(t["N_star"], p["N_star"])
    assert eq(t["alpha_star"], p["alpha_star"])
    assert eq(t["x_star"], (3 + S17) * T.d / (2 * T.g))
    assert t["upsilon_at_N_0"] == 0
    assert t["second_derivative_sign_at_x_star"] == -1
    assert t["upsilon_limit_infinity"] == 0 and t["upsilon_limit_zero"] == sp.oo
    assert eq(t["N_star_over_N_0"], (13 + 3 * S17) / 2)


def test_theorem_4_3_2_derivative_factors():
    t = T.theorem_4_3_2()
    num = t["derivative_numerator"]
    expected = -((T.g * T.x - T.d) ** 3) * (T.g**2 * T.x**2 - 3 * T.d * T.g * T.x - 2 * T.d**2)
    assert eq(num, expected)


def test_theorem_4_3_2_printed_upsilon_star_and_improvement_miss_4c():
    t, p = T.theorem_4_3_2(), errata.printed_theorem_4_3_2()
    assert eq(t["upsilon_star"], (4977 - 1207 * S17) * T.g**4 / (128 * T.c * T.d**2))
    assert eq(t["improvement_star"], (393 - 95 * S17) * T.g**2 / (32 * T.c))
    assert eq(p["upsilon_star"] / t["upsilon_star"], 4 * T.c)
    assert eq(p["improvement_star"] / t["improvement_star"], 4 * T.c)
    # printed internal consistency: N* x printed Upsilon* = printed improvement
    assert eq(p["N_star"] * p["upsilon_star"], p["improvement_star"])
    assert float((393 - 95 * S17) / 8) == pytest.approx(0.163121, abs=1e-6)
    assert float((393 - 95 * S17) / 32) == pytest.approx(0.0407802, abs=1e-7)


def test_theorem_4_3_2_garbled_upsilon_pinned():
    t, p = T.theorem_4_3_2(), errata.printed_theorem_4_3_2()
    point = {T.g: 1, T.d: 1, T.c: 1, T.N: 4}
    assert sp.nsimplify(t["upsilon"].subs(point)) == sp.Rational(1, 576)
    assert sp.nsimplify(p["upsilon_proof"].subs(point)) == sp.Rational(2401, 102400)
    # with c = 1/4 the printed numerator is right but the denominator is not
    assert not eq(p["upsilon_proof"], t["upsilon"])


@settings(max_examples=40, deadline=None)
@given(pos, pos, pos)
def test_n_star_maximises_upsilon_on_a_dense_grid(d, g, c):
    t = T.theorem_4_3_2()
    subs = {T.d: d, T.g: g, T.c: c}
    n_star = float(t["N_star"].subs(subs))
    n0 = float(t["N_0"].subs(subs))
    ups = sp.lambdify(T.N, t["upsilon"].subs(subs), "numpy")
    grid = np.geomspace(n0 * (1 + 1e-9), n0 * 1e3, 200_001)
    vals = ups(grid)
    best = grid[np.argmax(vals)]
    assert best == pytest.approx(n_star, rel=1e-3)
    assert ups(n_star) >= vals.max() * (1 - 1e-12)
    assert 0 <= meta.n_star_closed_form(g, ErrorBound(d)) - n_star < 1 + 1e-9 * n_star  # the ceiling
    # alpha at N* is the constant of the theorem
    alpha = meta.coordinate_step(g, d / math.sqrt(n_star), c)
    assert alpha == pytest.approx(float(t["alpha_star"].subs(subs)), rel=1e-9)


# --------------------------------------------------------------------------- Sections 4.3.1-4.3.2
def test_chebyshev():
    ch = T.chebyshev_d()
    assert eq(ch["d"], sp.sqrt(T.var / T.delta))
    assert eq(ch["eps"], ch["d"] / sp.sqrt(T.N))
    ns = T.chebyshev_n_star()
    assert eq(ns["N_star_reinforce"], ns["printed_N_star_reinforce"])
    assert eq(ns["N_star_gpomdp"], ns["printed_N_star_gpomdp"])
    # the printed REINFORCE error bound squares to the variance factor used in safepg.bounds
    d2 = float((ns["d_reinforce"] ** 2 * T.delta).subs(K1_SUBS))
    assert d2 == pytest.approx(reinforce_variance_factor(K1), rel=1e-12)


def test_hoeffding():
    h = T.hoeffding_d()
    assert eq(h["d"], h["printed_d"])
    assert eq(h["printed_eps_over_eps"], T.N)
    assert float(h["d"].subs({T.R_range: 3, T.delta: sp.Rational(1, 10)})) == pytest.approx(hoeffding(0.1, 3.0).d)
    # the correct tail bounds the exact binomial deviation probability (range 1)
    n, e = 50, 0.2
    exact = stats.binom.cdf(n * (0.5 - e), n, 0.5) + stats.binom.sf(math.ceil(n * (0.5 + e)) - 1, n, 0.5)
    assert exact <= float(h["tail"].subs({T.N: n, T.eps: e, T.R_range: 1}))


def test_gradient_range_bound_lemma_4_3_3():
    r = T.gradient_range_bound()
    a, mu, phi = sp.Symbol("a", real=True), sp.Symbol("mu", real=True), sp.Symbol("phi_i", real=True)
    assert eq(r["score"], (a - mu) * phi / T.sigma**2)
    assert eq(r["score_range_fixed_state"], 2 * T.A_bar * phi / T.sigma**2)
    assert eq(r["return_bound"], T.R * (1 - T.gamma**T.H) / (1 - T.gamma))
    assert float(r["printed_bound"].subs(K1_SUBS)) == pytest.approx(gradient_range_bound(K1))
    ratio = r["worst_case_over_printed"]
    assert eq(ratio, (1 - T.gamma**T.H) * (1 + T.mu_bar / T.A_bar))
    at = {T.gamma: sp.Rational(9, 10), T.H: 20, T.A_bar: 2}
    assert float(ratio.subs(at).subs(T.mu_bar, 0)) < 1 < float(ratio.subs(at).subs(T.mu_bar, 1))


# --------------------------------------------------------------------------- Section 4.3.3
def test_bernstein_n_zero():
    bn = T.bernstein_n_zero()
    assert eq(bn["N_0"], bn["printed_N_0"])
    eps_at = T.d / bn["x_0"] + T.f / bn["x_0"] ** 2
    assert eq(eps_at, T.g)


def test_bernstein_derivative_factorisation_pinned():
    bd = T.bernstein_upsilon_derivative()
    assert bd["numerator_over_printed_product"] == -1
    first, second = bd["printed_first_factor"], bd["printed_second_factor"]
    assert eq(bd["numerator"], -first * second)
    assert eq(bd["denominator"], 4 * T.c * T.x**8 * (T.g * T.x**2 + T.d * T.x + T.f) ** 3)


def test_bernstein_descartes_exactly_one_positive_root():
    dc = T.bernstein_descartes()
    assert dc["signs"] == [-1, 1, 1, 1, 1]
    assert dc["sign_changes"] == 1 and dc["positive_roots"] == 1
    assert dc["sign_changes_f0"] == 1
    root = T.bernstein_root_beyond_n_zero()
    assert root["is_positive"] is sp.true
    x0 = sp.Symbol("x_0", positive=True)
    assert eq(root["second_factor_at_x0"], 4 * T.d**2 * x0**2 + 12 * T.d * T.f * x0 + 8 * T.f**2)


def test_descartes_sign_changes_needs_determined_signs():
    assert T.descartes_sign_changes([1, 0, -2, 3]) == 2
    with pytest.raises(ValueError, match="coefficients"):
        T.descartes_sign_changes([T.d - T.g, 1])


@settings(max_examples=30, deadline=None)
@given(pos, pos, pos)
def test_bernstein_root_is_the_grid_maximiser(d, f, g):
    bound = ErrorBound(d, f)
    root = meta.n_star_bernstein_root(g, bound)
    n0 = meta.n_zero(g, bound)
    assert root > n0
    grid = np.geomspace(n0 * (1 + 1e-9), n0 * 1e4, 200_001)
    vals = meta.upsilon(grid, g, bound, 1.0)
    assert grid[np.argmax(vals)] == pytest.approx(root, rel=1e-3)
    # and the sympy root of the second factor agrees
    second = T.bernstein_upsilon_derivative()["printed_second_factor"].subs({T.d: d, T.f: f, T.g: g})
    roots = [complex(r) for r in sp.Poly(second, T.x).nroots()]
    pos_roots = [r.real for r in roots if abs(r.imag) < 1e-9 * abs(r) and r.real > 0]
    assert len(pos_roots) == 1
    assert pos_roots[0] ** 2 == pytest.approx(root, rel=1e-8)


# --------------------------------------------------------------------------- scalar steps
def test_scalar_steps_3_3_2_and_5_2_1():
    sc = T.scalar_step_comparison()
    assert sc["ratio_3_3_2"] == 1
    assert sc["ratio_improvement_3_3_2"] == 1
    assert sc["bound_3_7_minus_derived"] == 0
    assert sc["ratio_5_2_1"] == sp.Rational(1, 4)
    grad = np.array([3.0, -1.0, 0.5])
    num = float(sc["derived_alpha"].subs(K1_SUBS).subs({T.g2: np.linalg.norm(grad), T.g1: np.abs(grad).sum()}))
    assert num == pytest.approx(meta.scalar_step(grad, 0.0, meta.penalty_constant(K1)), rel=1e-12)


# --------------------------------------------------------------------------- Appendices A, B
def test_gaussian_hessian_and_sup():
    gh = T.gaussian_density_hessian()
    assert gh["hessian_matches"] is sp.true
    assert gh["sup_abs_shape"] == 1
    assert set(gh["critical_points"]) == {0, sp.sqrt(3), -sp.sqrt(3)}
    assert gh["shape_limit_infinity"] == 0


def test_taylor_remainder_weights():
    tw = T.taylor_remainder_weights(3)
    a = sp.symbols("a_1:4", nonnegative=True)
    assert eq(tw["printed_minus_claim"], -sum(v**2 for v in a) / 2)
    assert eq(tw["correct_remainder_bound"], sum(a) ** 2 / 2)


def test_gaussian_kl():
    mu1, mu2 = sp.symbols("mu_1 mu_2", real=True)
    assert eq(T.gaussian_kl()["kl"], (mu1 - mu2) ** 2 / (2 * T.sigma**2))


def test_softmax_appendix_b():
    sc = T.softmax_constants()
    assert eq(sc["c"], sc["printed_c"])
    assert eq(sc["b"], sc["printed_b"])
    cb = T.corollary_b_0_7()
    assert eq(cb["alpha_star"], cb["printed_alpha_star"])
    assert eq(cb["improvement"], cb["printed_improvement"])


# --------------------------------------------------------------------------- records
EXPECTED_ERRATA = {
    "thm_4_3_2_upsilon_proof",
    "thm_4_3_2_upsilon_star",
    "thm_4_3_2_improvement",
    "hoeffding_exponent",
    "range_definition",
    "lemma_4_3_3_range",
    "algorithm_4_1_step_line",
    "algorithm_4_1_stopping",
    "algorithm_4_1_min_batch",
    "lemma_a_0_2_pinsker",
    "lemma_a_0_1_taylor",
    "lemma_4_2_2_q_sign",
    "thm_4_2_6_probability",
    "scalar_step_5_2_1",
    "ref_theorem_4_3_2_in_4_3",
    "ref_corollary_4_2_5_in_4_2_2",
    "ref_theorem_3_3",
    "ref_assumption_3_1",
    "thm_4_3_2_N1",
}


def test_errata_records():
    errs = errata.ERRATA
    ids = [e.id for e in errs]
    assert len(ids) == len(set(ids))
    assert set(ids) == EXPECTED_ERRATA
    for e in errs:
        assert e.affects_experiments in ("no", "yes", "possibly")
        assert e.kind in ("formula", "proof", "statement", "algorithm", "reference", "discrepancy")
        assert e.explanation and e.location and e.impact
        if isinstance(e.printed, sp.Basic) and isinstance(e.corrected, sp.Basic):
            assert not eq(e.printed, e.corrected), e.id
        T.latex(e.printed), T.latex(e.corrected)


def test_verified_records():
    recs = errata.VERIFIED
    ids = [v.id for v in recs]
    assert len(ids) == len(set(ids))
    n_equal = 0
    for v in recs:
        assert v.relation in ("equal", "proportional", "supports")
        if v.relation == "equal":
            assert eq(v.printed, v.derived), v.id
            n_equal += 1
        elif v.relation == "proportional":
            ratio = sp.simplify(v.derived / v.printed)
            assert ratio.free_symbols == set(), v.id
        T.latex(v.printed), T.latex(v.derived)
    assert n_equal >= 20


def test_latex_uses_thesis_names():
    s = T.latex(T.theorem_4_3_2()["N_star"])
    assert r"d_\delta" in s and r"\hat\nabla" in s and "17" in s
    assert T.latex("already latex") == "already latex"
