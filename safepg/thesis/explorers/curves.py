"""The book's explorers, built on :class:`safepg.explorers.component.Explorer`.

Each factory returns an explorer whose JavaScript and Python halves compute the same
curves: closed forms in both, precomputed Monte Carlo quantities embedded as data. The
JavaScript halves are ``static/lqg_compute.js`` and the core's ``upsilon_compute.js``
(:mod:`safepg.explorers.upsilon`, for any task; here on the 1-D LQG).
The batch-size explorer, which reruns Algorithm 4.1 in the page, is
:func:`safepg.thesis.explorers.live_learner.live_batch_size_explorer`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from safepg.envs.lqg import LQG
from safepg.explorers.component import Explorer, Plot, Slider
from safepg.explorers.upsilon import upsilon_explorer as core_upsilon_explorer
from safepg.thesis import plotting
from safepg.thesis.explorers.component import static_text


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
def upsilon_explorer(sigmas: Sequence[float] | None = None, n: int = 20_000, theta: float = 0.0,
                     seed: int = 0) -> Explorer:
    """Upsilon_delta(N) for the 1-D LQG (:func:`safepg.explorers.upsilon.upsilon_explorer`): sliders
    for delta, sigma and ||g||_inf, and a bound selector; marks N_0 and N* and prints N*, the step
    and the guaranteed improvement. The empirical quantities (sample variance and range of the
    G(PO)MDP samples) come from real batches at ``theta`` on a sigma grid."""
    sigma_grid = np.round(np.linspace(0.5, 2.0, 16), 3) if sigmas is None else np.asarray(sigmas)
    return core_upsilon_explorer(LQG.thesis_1d(), theta, sigma_grid, n=n, seed=seed)
