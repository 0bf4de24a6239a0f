"""Short learning runs whose every output bit is printed as a digest (run by test_portable.py).

``python tests/portable_probe.py`` prints one JSON object: for each run, a SHA-256 of every
array of its record and the report quantities (Upsilon-bar, improvement ratio, J at the
checkpoints, the seed-mean interval) as float hex strings. The test runs it in subprocesses
under different CPU settings and compares the outputs.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.envs.pendulum import Pendulum
from safepg.learning import LearningRecord, adaptive_pg, vanilla_pg
from safepg.options import Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep
from safepg.policies import LinearGaussianPolicy
from safepg.stats import mean_ci95


def digest(rec: LearningRecord) -> dict[str, object]:
    h = hashlib.sha256()
    for name in ("batch_size", "alpha", "coordinate", "theta", "J", "J_hat", "grad", "eps", "safe"):
        h.update(np.ascontiguousarray(getattr(rec, name)).tobytes())
    return {"arrays": h.hexdigest(), "upsilon_bar": float.hex(rec.upsilon_bar()),
            "improvement_ratio": float.hex(rec.improvement_ratio()),
            "J_at": {k: float.hex(v) for k, v in rec.J_at((10_000, 50_000)).items()}}


def runs() -> dict[str, list[LearningRecord]]:
    lqg1, lqg2 = LQG.thesis_1d(), LQG.thesis_2d(gamma=0.9)
    bernstein_er = ErrorModel("bernstein", range="empirical")
    return {
        "1d-bernstein-er": [adaptive_pg(lqg1, error=bernstein_er, budget=60_000, rng=s) for s in range(3)],
        "1d-chebyshev-reinforce": [adaptive_pg(lqg1, gradient=Gradient("reinforce"), budget=60_000, rng=s)
                                   for s in range(3)],
        "1d-hoeffding": [adaptive_pg(lqg1, error=ErrorModel("hoeffding"), budget=30_000, rng=0)],
        "1d-vanilla-raw": [vanilla_pg(lqg1, -0.55, 0.5, batch_size=100, step=FixedStep(1e-3),
                                      gradient=Gradient(score_action="raw"), budget=20_000, rng=0)],
        "2d-vanilla-fixed": [vanilla_pg(lqg2, np.zeros(4), batch_size=100, step=FixedStep(1e-6, "coordinate"),
                                        budget=20_000, rng=0)],
        "2d-scalar-step": [vanilla_pg(lqg2, np.zeros(4), batch_size=500, step=SafeStep("scalar"),
                                      budget=20_000, rng=0)],
        "2d-bernstein": [adaptive_pg(lqg2, np.zeros(4), error=bernstein_er, budget=30_000, rng=0)],
        "cartpole-vanilla": [vanilla_pg(CartPole.thesis(), np.zeros(4), batch_size=200, step=FixedStep(0.01),
                                        budget=2_000, rng=0)],
        "cartpole-adaptive": [adaptive_pg(CartPole.thesis_doubled(), np.array([0.5, 1.0, 20.0, 3.0]),
                                          error=bernstein_er, budget=2_000, rng=0)],
        # The pendulum's kernel: its sines past pi/4, the reward's remainder, both estimators.
        "pendulum-adaptive": [adaptive_pg(Pendulum(), np.zeros(3), gradient=Gradient(score_action="raw"),
                                          error=bernstein_er, batches=Batches(n_min=10, first=600),
                                          departures=Departures(batch_constants=True, maxima=True,
                                                                unguarded_step=True), budget=3_000, rng=s)
                              for s in range(2)],
        "pendulum-vanilla": [vanilla_pg(Pendulum(), np.array([0.0, 0.0, 1.0]), batch_size=700,
                                        step=FixedStep(1e-5), gradient=Gradient("reinforce"), budget=1_400, rng=0)],
    }


def significance() -> dict[str, object]:
    """The scorecard's tests on fixed numbers: every p-value, detectable difference and correction bit."""
    from safepg import curve_tests as ct
    from safepg import significance as sg

    rng = np.random.default_rng(11)
    ours, theirs = rng.normal(size=(10, 3)), rng.normal(0.4, 1.0, size=(5, 3))
    tests = [sg.PredictionTest((0.1, 0.12), tuple(ours[:, 0]), resolution=0.01),
             sg.WelchTest(0.3, (0.1, 0.5), 5, tuple(ours[:, 1]), 5e-5, 0.9),
             ct.CurvePredictionTest(theirs[0], ours), ct.PermutationTest(theirs, ours)]
    rejected, level = sg.benjamini_hochberg([t.p_value for t in tests], 0.05)
    return {"p": [float.hex(t.p_value) for t in tests],
            "detectable": [float.hex(t.detectable_difference(0.01)) for t in tests],
            "floor": [float.hex(t.detectable_difference(0.01, float("inf"))) for t in tests],
            "rejected": rejected.tolist(), "level": float.hex(level)}


def main() -> None:
    out: dict[str, object] = {"significance": significance()}
    for name, recs in runs().items():
        out[name] = [digest(r) for r in recs]
        ci = mean_ci95(r.upsilon_bar() for r in recs)
        out[name + ":ci95"] = [float.hex(v) for v in ci["ci95"]] if len(recs) > 1 else None
    returns = Pendulum().episode_returns(LinearGaussianPolicy(np.array([[-1.0, -6.0, -1.5]]), 0.5), 700, 3)
    out["pendulum-returns"] = [hashlib.sha256(np.ascontiguousarray(r).tobytes()).hexdigest() for r in returns]
    lqg2 = LQG.thesis_2d(gamma=0.9)
    out["closed-forms"] = [float.hex(float(v)) for v in (
        *lqg2.optimal_gain().ravel(), lqg2.performance(np.diag([-0.3, -0.5]), 1.0),
        *lqg2.gradient(np.array([[-0.3, 0.05], [0.02, -0.5]]), 1.0))]
    print(json.dumps(out, sort_keys=True))


if __name__ == "__main__":
    main()
