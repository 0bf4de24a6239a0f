"""The page learner's JavaScript in one piece, and safepg tasks as the TASK objects it reads.

The learner is split by concept (``static/learner.js``: random numbers, bounds, meta-parameters
and the 1-D run; ``lqg_task.js``: the LQG in any dimension; ``lqg2d_wasm.js``: the 2-D LQG's
batch as WebAssembly, compiled from ``wasm/lqg2d_kernel.c``, the same bits in half the time;
``cartpole_task.js``: the cart-pole; ``vector_run.js``: Algorithm 4.1 and vanilla PG on a
vector theta). A page, a
worker and the Node tests load :func:`learner_sources`, their concatenation in dependency
order, which defines the global ``safepgLearner``. :func:`lqg_task_data` and
:func:`cartpole_task_data` turn a safepg task into the ``task`` of the learner's
``Driver({task, runs})``, so that no constant is copied by hand.
"""

from __future__ import annotations

import base64
from typing import Any

import numpy as np

from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.options import Adaptive, FixedStep, Method, SafeStep
from safepg.thesis.explorers.component import static_bytes, static_text

#: The learner's files in the order they must be concatenated (each extends the ones before).
LEARNER_FILES = ("learner.js", "lqg_task.js", "lqg2d_wasm.js", "cartpole_task.js", "vector_run.js")
#: The 2-D LQG's batch as WebAssembly (``make wasm`` compiles it from ``wasm/lqg2d_kernel.c``),
#: carried inline by ``lqg2d_wasm.js`` in place of :data:`WASM_PLACEHOLDER`.
WASM_KERNEL = "lqg2d_kernel.wasm"
WASM_PLACEHOLDER = "@LQG2D_KERNEL_WASM@"


def learner_sources() -> str:
    """The JavaScript learner: :data:`LEARNER_FILES` concatenated, defining ``safepgLearner``.

    Returns
    -------
    str
        Script text; under Node, ``require`` of a file holding it returns ``safepgLearner``.
    """
    kernel = static_bytes(WASM_KERNEL)
    text = "\n".join(static_text(name) for name in LEARNER_FILES)
    return text.replace(WASM_PLACEHOLDER, base64.b64encode(kernel).decode("ascii"), 1)


def _matrix(x: Any, m: int) -> list[float]:
    a = np.asarray(x, dtype=float)
    a = np.eye(m) * float(a) if a.ndim == 0 else a
    return [float(v) for v in a.reshape(m * m)]


def lqg_task_data(env: LQG) -> dict[str, Any]:
    """The learner's TASK for an LQG (``safepgLearner.lqgTask`` gives the same object).

    Parameters
    ----------
    env : LQG
        Any dimension; the 1-D task runs on the 1-D learner of ``learner.js``.

    Returns
    -------
    dict
        ``{"kind": "lqg", "dim", "gamma", "H", "stateBound", "actionBound", "A", "B", "Q", "R"
        (row-major flat lists of dim * dim), "clip", "rewardBound", "featureBound",
        "actionVolume"}``, the last three safepg's bound constants.
    """
    m = int(env.dim)
    return {"kind": "lqg", "dim": m, "gamma": float(env.gamma), "H": int(env.horizon),
            "stateBound": float(env.state_bound), "actionBound": float(env.action_bound),
            **{k: _matrix(getattr(env, k), m) for k in "ABQR"}, "clip": bool(env.clip),
            "rewardBound": float(env.reward_bound), "featureBound": float(env.feature_bound),
            "actionVolume": float(env.action_volume)}


def cartpole_task_data(task: CartPole) -> dict[str, Any]:
    """The learner's TASK for a cart-pole (``safepgLearner.cartpoleTask`` of the same settings).

    Parameters
    ----------
    task : CartPole
        Raw features only (``feature_scale`` None): the page's learner has no normalisation.

    Returns
    -------
    dict
        ``{"kind": "cartpole", "poleLength", "polemassLength" (None: a consistent pole),
        "angleThresholdDeg", "xThreshold", "gamma", "constantsGamma" (None: gamma), "H", "tau",
        "actionBound", "featureBound", "rewardBound", "actionSpaceVolume", "horizonTerm",
        "cartMass", "poleMass", "gravity", "initBound", "integrator"}``.

    Raises
    ------
    ValueError
        With normalised features.
    """
    if task.feature_scale is not None:
        raise ValueError("the page's learner has raw features only: feature_scale must be None")
    opt = lambda v: None if v is None else float(v)  # noqa: E731
    return {"kind": "cartpole", "poleLength": float(task.pole_length), "polemassLength": opt(task.polemass_length),
            "angleThresholdDeg": float(task.angle_threshold_deg), "xThreshold": float(task.x_threshold),
            "gamma": float(task.gamma), "constantsGamma": opt(task.constants_gamma), "H": int(task.horizon),
            "tau": float(task.tau), "actionBound": float(task.action_bound),
            "featureBound": float(task.feature_bound), "rewardBound": float(task.reward_bound),
            "actionSpaceVolume": opt(task.action_space_volume), "horizonTerm": task.horizon_term,
            "cartMass": float(task.cart_mass), "poleMass": float(task.pole_mass), "gravity": float(task.gravity),
            "initBound": float(task.init_bound), "integrator": task.integrator}


def learner_options(method: Method) -> dict[str, Any]:
    """A method's options under the names of the page learner's run configuration (``vector_run.js``).

    The one place where safepg's option objects meet the JavaScript's names: the learner's
    ``constants: "batch"``, ``statistics: "max"`` and ``stepWhenUnsafe`` are the
    :class:`~safepg.options.Departures`, ``nFirst`` is ``Batches.first``, ``alpha: null`` a
    :class:`~safepg.options.SafeStep`.

    Parameters
    ----------
    method : Adaptive or Vanilla

    Returns
    -------
    dict
        ``algorithm``, ``estimator``, ``baseline``, ``score``, ``bound``, ``empiricalRange``,
        ``theoreticalRange``, ``delta``; then ``nMin``, ``nMax``, ``nFirst``, ``constants``,
        ``statistics``, ``stepWhenUnsafe`` (adaptive) or ``batchSize``, ``alpha``, ``step`` (vanilla).
    """
    g = method.gradient
    out: dict[str, Any] = {"estimator": g.estimator, "baseline": g.baseline, "score": g.score_action}
    if isinstance(method, Adaptive):
        e, b, d = method.error, method.batches, method.departures
        return {"algorithm": "adaptive", **out, "bound": e.bound, "empiricalRange": e.empirical_range,
                "theoreticalRange": e.theoretical_range, "delta": e.delta, "nMin": b.n_min, "nMax": b.n_max,
                "nFirst": b.first, "constants": "batch" if d.batch_constants else "bounds",
                "statistics": "max" if d.maxima else "component", "stepWhenUnsafe": d.unguarded_step}
    step = method.step
    se = step.error if isinstance(step, SafeStep) else None
    return {"algorithm": "vanilla", **out, "bound": se.bound if se else "chebyshev",
            "empiricalRange": bool(se and se.empirical_range),
            "theoreticalRange": se.theoretical_range if se else None,
            "delta": se.delta if se else 0.95, "batchSize": method.batch_size,
            "alpha": step.alpha if isinstance(step, FixedStep) else None, "step": step.kind}


__all__ = ["LEARNER_FILES", "cartpole_task_data", "learner_options", "learner_sources", "lqg_task_data"]
