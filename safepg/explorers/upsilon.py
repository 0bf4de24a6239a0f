r"""Upsilon_delta(N) and N* of Section 4.3 for any task, as a kernel-free explorer.

:func:`upsilon_explorer` draws the cost-sensitive improvement

.. math:: \Upsilon_\delta(N) = \frac{(\|\hat\nabla J\|_\infty - \epsilon(N))^4}
                                    {4cN\,(\|\hat\nabla J\|_\infty + \epsilon(N))^2}

against the batch size N for a task's bounds, with sliders for :math:`\delta`, :math:`\sigma` and
:math:`\|\hat\nabla J\|_\infty` and a choice of bound; it marks :math:`N_0` and :math:`N^*` and
prints :math:`N^*`, the step and the guaranteed improvement. The closed forms are recomputed in
the reader's browser (``static/lib.js``, ``static/upsilon_compute.js``); what needs simulation,
the sample variance and the range of the gradient samples of the empirical bounds, comes from
real batches of the task on a grid of :math:`\sigma`, embedded as data.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
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
from safepg.explorers.component import Explorer, Plot, Select, Slider, static_text
from safepg.meta import (
    coordinate_step,
    guaranteed_improvement,
    n_star_closed_form,
    n_star_search,
    n_zero,
    penalty_constant,
    upsilon,
)
from safepg.options import Gradient
from safepg.plotting import ACCENT, MUTED
from safepg.policies import LinearGaussianPolicy

#: The bounds of the selector: (value, label).
BOUND_CHOICES = (
    ("chebyshev-gpomdp", "Chebyshev, G(PO)MDP variance bound"),
    ("chebyshev-reinforce", "Chebyshev, REINFORCE variance bound"),
    ("hoeffding", "Hoeffding, Lemma 4.3.3 range"),
    ("hoeffding-er", "Hoeffding, empirical range"),
    ("bernstein", "Bernstein, Lemma 4.3.3 range"),
    ("bernstein-er", "Bernstein, empirical range"),
)
#: The explorer's heading when none is given.
TITLE = "Upsilon_delta(N): the cost-sensitive improvement (Section 4.3)"


def sample_spread(task: Any, theta: np.ndarray, sigmas: Sequence[float], n: int, seed: int,
                  gradient: Gradient = Gradient()) -> tuple[list[float], list[float]]:
    """The sample variance (ddof 1) and the range of the gradient samples of one batch at each sigma.

    Each batch has ``n`` trajectories of the policy N(theta^T phi, sigma^2) drawn with the seed
    ``seed`` (the task's fused ``gradient_batch``); the component is the one Algorithm 4.1 moves
    there, the largest |mean|.
    """
    gain = np.asarray(theta, dtype=float).reshape(1, -1)
    how = (gradient.estimator, gradient.baseline, gradient.score_action)
    svar, srange = [], []
    for s in sigmas:
        x = task.gradient_batch(LinearGaussianPolicy(gain, float(s)), n, np.random.default_rng(seed), *how)[0]
        k = int(np.argmax(np.abs(x.sum(axis=0) / n)))
        svar.append(float(np.var(x[:, k], ddof=1)))
        srange.append(float(np.ptp(x[:, k])))
    return svar, srange


def upsilon_explorer(task: Any, theta: np.ndarray | float, sigmas: Sequence[float] | np.ndarray, *, n: int = 20_000,
                     seed: int = 0, gradient: Gradient = Gradient(),
                     sigma_slider: tuple[float, float, float, float] = (0.5, 2.0, 0.1, 1.0),
                     g_slider: tuple[float, float, float, float] = (1.0, 60.0, 1.0, 30.0),
                     bound: str = "bernstein-er", title: str = TITLE) -> Explorer:
    r"""Upsilon_delta(N) for ``task``'s bounds: sliders for delta, sigma and ||g||_inf, a bound selector.

    Parameters
    ----------
    task
        A task with the bounds of Assumption 4.2.1 and a fused ``gradient_batch``.
    theta : array_like or float
        The parameters at which the empirical bounds' sample variance and range are measured.
    sigmas : sequence of float
        The sigma grid of those measurements (the page interpolates between its points).
    n, seed : int
        Trajectories of each measured batch, and its seed.
    gradient : Gradient
        The estimator, baseline and score of the measured samples.
    sigma_slider, g_slider : (min, max, step, start)
        The ranges of the sigma and ||g||_inf sliders.
    bound : str
        The bound selected first (one of :data:`BOUND_CHOICES`).
    title : str
        The explorer's heading.

    Returns
    -------
    Explorer
        Its page marks N_0 and N* and prints c, d, f, N_0, N*, the step alpha* and the guaranteed
        improvement; ``compute_py`` computes the same with :mod:`safepg.meta`.
    """
    sigma_grid = np.asarray(sigmas, dtype=float)
    svar, srange = sample_spread(task, np.atleast_1d(np.asarray(theta, dtype=float)), sigma_grid.tolist(), n, seed,
                                 gradient)
    data = {"R": task.reward_bound, "M": task.feature_bound, "Avol": task.action_volume, "Abar": task.action_bound,
            "gamma": task.gamma, "H": task.horizon, "sigmas": sigma_grid.tolist(), "sample_var": svar,
            "emp_range": srange, "points": 200, "accent": ACCENT, "muted": MUTED}

    def bound_for(p: dict[str, Any]) -> tuple[ErrorBound, float]:
        constants = TaskConstants.from_task(task, p["sigma"])
        S = float(np.interp(p["sigma"], sigma_grid, svar))
        er = float(np.interp(p["sigma"], sigma_grid, srange))
        makers: dict[str, Callable[[], ErrorBound]] = {
            "chebyshev-gpomdp": lambda: chebyshev(p["delta"], gpomdp_variance_factor(constants)),
            "chebyshev-reinforce": lambda: chebyshev(p["delta"], reinforce_variance_factor(constants)),
            "hoeffding": lambda: hoeffding(p["delta"], gradient_range_bound(constants)),
            "hoeffding-er": lambda: hoeffding(p["delta"], er),
            "bernstein": lambda: bernstein(p["delta"], S, gradient_range_bound(constants)),
            "bernstein-er": lambda: bernstein(p["delta"], S, er)}
        return makers[p["bound"]](), penalty_constant(constants)

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
        title,
        [Slider("delta", "delta", 0.05, 0.95, 0.05, 0.95), Slider("sigma", "sigma", *sigma_slider),
         Slider("g", "||g||_inf", *g_slider), Select("bound", "bound", BOUND_CHOICES, bound)],
        [Plot("U", "batch size N", "Upsilon_delta(N)", xlog=True)],
        "\n" + static_text("upsilon_compute.js"), compute_py, data)


def pendulum_upsilon_explorer(n: int = 5000, seed: int = 0) -> Explorer:
    """:func:`upsilon_explorer` on :class:`~safepg.envs.pendulum.Pendulum` (the pendulum chapter's):
    the empirical bounds' variance and range from batches of ``n`` episodes at theta = 0 (G(PO)MDP
    with its baseline, the score of the sampled action) on a grid of sigma from 0.5 to 2, and
    ||g||_inf from 50 to 3000, starting at 900, about the gradients the chapter's runs meet."""
    from safepg.envs.pendulum import Pendulum

    return upsilon_explorer(Pendulum(), np.zeros(3), np.round(np.linspace(0.5, 2.0, 7), 2), n=n, seed=seed,
                            gradient=Gradient(score_action="raw"), g_slider=(50.0, 3000.0, 50.0, 900.0),
                            title="Upsilon_delta(N) for the pendulum (Section 4.3)")


__all__ = ["BOUND_CHOICES", "TITLE", "pendulum_upsilon_explorer", "sample_spread", "upsilon_explorer"]
