"""The book's explorers, built on :class:`safepg.thesis.explorers.component.Explorer`.

Each factory returns an explorer whose JavaScript and Python halves compute the same
curves: closed forms in both, precomputed Monte Carlo quantities embedded as data. The
JavaScript halves are ``static/lqg_compute.js`` and ``static/upsilon_compute.js``.
The batch-size explorer, which reruns Algorithm 4.1 in the page, is
:func:`safepg.thesis.explorers.live_learner.live_batch_size_explorer`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from safepg.bounds import (
    ErrorBound,
    bernstein,
    chebyshev,
    gpomdp_variance_factor,
    gradient_range_bound,
    hoeffding,
    reinforce_variance_factor,
)
from safepg.constants import TaskConstants
from safepg.envs.lqg import LQG
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    n_star_closed_form,
    n_star_search,
    n_zero,
    penalty_constant,
    upsilon,
)
from safepg.thesis import plotting
from safepg.thesis.explorers.component import Explorer, Plot, Select, Slider, static_text


def _compute_js(name: str) -> str:
    """The body of a compute function, from ``static/name``, starting on the line after
    ``function(p,data,lib){`` in the page (the newline is part of the body, so of the
    explorer's id)."""
    return "\n" + static_text(name)


# ---------------------------------------------------------------------------- LQG
def lqg_explorer(sigmas: Sequence[float] | None = None, n: int = 20_000, theta_var: float = -0.3,
                 seed: int = 0) -> Explorer:
    """1-D LQG: the closed-form J(theta) as sigma moves (theta* marked), beside the
    per-trajectory variance of the REINFORCE and G(PO)MDP samples (Monte Carlo,
    precomputed on a sigma grid)."""
    from safepg.thesis.analysis import sample_variance

    env = LQG.thesis_1d()
    sigma_grid = np.round(np.linspace(0.2, 2.0, 19), 3) if sigmas is None else np.asarray(sigmas)
    var = sample_variance(env, theta_var, sigma_grid, n, seed)
    data = {"theta_min": -1.2, "theta_max": 0.04, "points": 125, "gamma": env.gamma, "b": env.state_bound,
            "theta_star": float(env.optimal_gain().item()), "sigmas": sigma_grid.tolist(), "theta_var": theta_var,
            "var_reinforce": var["reinforce"].tolist(), "var_gpomdp": var["gpomdp"].tolist(),
            "accent": plotting.ACCENT, "c_rf": plotting.MUTED, "c_gp": plotting.ACCENT}

    def compute_py(p: dict[str, Any]) -> dict[str, Any]:
        th = np.linspace(data["theta_min"], data["theta_max"], data["points"])
        J = [env.performance(t, p["sigma"]) for t in th]
        js = env.performance(data["theta_star"], p["sigma"])
        vr = float(np.interp(p["sigma"], sigma_grid, data["var_reinforce"]))
        vg = float(np.interp(p["sigma"], sigma_grid, data["var_gpomdp"]))
        return {"plots": {"J": {"series": [{"x": th.tolist(), "y": J}],
                                "markers": [{"x": data["theta_star"], "y": js}]},
                          "var": {"series": [{"x": sigma_grid.tolist(), "y": data["var_reinforce"]},
                                             {"x": sigma_grid.tolist(), "y": data["var_gpomdp"]}],
                                  "markers": [{"x": p["sigma"], "y": vr}, {"x": p["sigma"], "y": vg}]}},
                "values": {"J_star": js, "var_reinforce": vr, "var_gpomdp": vg}}

    return Explorer(
        "1-D LQG: expected performance and estimator variance",
        [Slider("sigma", "policy std sigma", 0.2, 2.0, 0.05, 1.0)],
        [Plot("J", "theta", "J(theta)", ymin=-120, ymax=0),
         Plot("var", "sigma", "per-trajectory variance", ylog=True)],
        _compute_js("lqg_compute.js"), compute_py, data)


# ------------------------------------------------------------------------ Upsilon
BOUND_CHOICES = (
    ("chebyshev-gpomdp", "Chebyshev, G(PO)MDP variance bound"),
    ("chebyshev-reinforce", "Chebyshev, REINFORCE variance bound"),
    ("hoeffding", "Hoeffding, Lemma 4.3.3 range"),
    ("hoeffding-er", "Hoeffding, empirical range"),
    ("bernstein", "Bernstein, Lemma 4.3.3 range"),
    ("bernstein-er", "Bernstein, empirical range"),
)


def upsilon_explorer(sigmas: Sequence[float] | None = None, n: int = 20_000, theta: float = 0.0,
                     seed: int = 0) -> Explorer:
    """Upsilon_delta(N) for the 1-D LQG: sliders for delta, sigma and ||g||_inf, and a
    bound selector; marks N_0 and N* and prints N*, the step and the guaranteed
    improvement. The empirical quantities (sample variance and range of the G(PO)MDP
    samples) come from real batches at ``theta`` on a sigma grid."""
    env = LQG.thesis_1d()
    sigma_grid = np.round(np.linspace(0.5, 2.0, 16), 3) if sigmas is None else np.asarray(sigmas)
    from safepg.policies import LinearGaussianPolicy

    svar, srange = [], []
    for s in sigma_grid:
        x = env.gradient_batch(LinearGaussianPolicy(np.array([[theta]]), s), n, np.random.default_rng(seed))[0][:, 0]
        svar.append(float(np.var(x, ddof=1)))
        srange.append(float(np.ptp(x)))
    data = {"R": env.reward_bound, "M": env.feature_bound, "Avol": env.action_volume, "Abar": env.action_bound,
            "gamma": env.gamma, "H": env.horizon, "sigmas": sigma_grid.tolist(), "sample_var": svar,
            "emp_range": srange, "points": 200, "accent": plotting.ACCENT, "muted": plotting.MUTED}

    def bound_for(p: dict[str, Any]) -> tuple[ErrorBound, float]:
        constants = TaskConstants.from_task(env, p["sigma"])
        S = float(np.interp(p["sigma"], sigma_grid, svar))
        er = float(np.interp(p["sigma"], sigma_grid, srange))
        b = p["bound"]
        bd = {"chebyshev-gpomdp": lambda: chebyshev(p["delta"], gpomdp_variance_factor(constants)),
              "chebyshev-reinforce": lambda: chebyshev(p["delta"], reinforce_variance_factor(constants)),
              "hoeffding": lambda: hoeffding(p["delta"], gradient_range_bound(constants)),
              "hoeffding-er": lambda: hoeffding(p["delta"], er),
              "bernstein": lambda: bernstein(p["delta"], S, gradient_range_bound(constants)),
              "bernstein-er": lambda: bernstein(p["delta"], S, er)}[b]()
        return bd, penalty_constant(constants)

    def compute_py(p: dict[str, Any]) -> dict[str, Any]:
        bd, c = bound_for(p)
        g = p["g"]
        n0 = n_zero(g, bd)
        ns = n_star_closed_form(g, bd) if bd.f == 0 else n_star_search(g, bd, c)
        N = np.geomspace(max(1.0, n0), 6 * ns, data["points"])
        e = float(bd.eps(ns))
        U = np.asarray(upsilon(N, g, bd, c, saturate=False))
        return {"plots": {"U": {"series": [{"x": N.tolist(), "y": U.tolist()}],
                                "markers": [{"x": n0, "y": 0.0}, {"x": ns, "y": upsilon(ns, g, bd, c)}]}},
                "values": {"c": c, "d": bd.d, "f": bd.f, "N0": n0, "Nstar": ns,
                           "alpha": coordinate_step(g, e, c), "improvement": guaranteed_improvement(g, e, c)}}

    return Explorer(
        "Upsilon_delta(N): the cost-sensitive improvement (Section 4.3)",
        [Slider("delta", "delta", 0.05, 0.95, 0.05, 0.95), Slider("sigma", "sigma", 0.5, 2.0, 0.1, 1.0),
         Slider("g", "||g||_inf", 1.0, 60.0, 1.0, 30.0),
         Select("bound", "bound", BOUND_CHOICES, "bernstein-er")],
        [Plot("U", "batch size N", "Upsilon_delta(N)", xlog=True)],
        _compute_js("upsilon_compute.js"), compute_py, data)
