"""The settings of the cart-pole sweep: which unstated settings let the adaptive step move on
the doubled pole?

Each :class:`SweepSetting` changes the task (then it has its own baseline policy) or only the
bound constants; :mod:`safepg.thesis.experiments` turns them into the ``cartpole-baseline-*``
and ``cartpole-sweep`` experiments, and :mod:`safepg.thesis.cartpole_sweep` computes the
penalty constant over the whole grid analytically and reads the runs back for the chapter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

#: Trajectories per doubled-pole run of the sweep (both methods: 50 iterations of the
#: vanilla N = 4000) and seeds per setting. Small on purpose, so that the chapter's sweep costs
#: under 4 minutes on 2 cores; ``table-5.4`` is the full-budget protocol at the default setting.
SWEEP_BUDGET = 200_000
SWEEP_SEEDS = 2
#: Cap on a sweep baseline search: 250 iterations of N = 4000 (the thesis needed 72).
SWEEP_BASELINE_CAP = 4000 * 250


@dataclass(frozen=True)
class SweepSetting:
    """One setting of the cart-pole sweep.

    ``task`` overrides the :class:`~safepg.envs.cartpole.CartPole` fields that change what
    is simulated or how vanilla PG learns (so the setting has its own baseline policy);
    ``constants`` overrides only the bound constants (R, M_phi, |A|, horizon term), which
    change nothing but the adaptive method's penalty constant c. ``doubled``: run the
    doubled-pole comparison (False: the baseline search only). ``plausible``: False for
    the counterfactual settings that only locate how small c must be. ``warm_start``: the
    baseline experiment to start from instead of the setting's own (for a discount whose
    own baseline search never reaches 195).
    """

    key: str
    label: str
    task: dict[str, Any] = field(default_factory=dict)
    constants: dict[str, Any] = field(default_factory=dict)
    doubled: bool = True
    plausible: bool = True
    warm_start: str | None = None

    def env(self, doubled: bool, constants: bool = True) -> str:
        """The :func:`make_env` name of this setting's task (with or without the constants)."""
        from safepg.envs.cartpole import CartPole

        base = CartPole.thesis_doubled if doubled else CartPole.thesis
        return base(**self.task, **(self.constants if constants else {})).setting_name()

    @property
    def baseline_experiment(self) -> str:
        """The experiment whose runs are this setting's baseline policies."""
        if self.warm_start is not None:
            return self.warm_start
        return "cartpole-baseline" if not self.task else f"cartpole-baseline-{self.key}"


def _sweep_settings() -> tuple[SweepSetting, ...]:
    from safepg.envs.cartpole import NORMALISED_SCALE

    return (
        SweepSetting("thesis", "ours (default)"),
        SweepSetting("gamma=0.95", "gamma 0.95", {"gamma": 0.95}, doubled=False),
        SweepSetting("gamma=0.995", "gamma 0.995", {"gamma": 0.995}),
        SweepSetting("gamma=0.999", "gamma 0.999", {"gamma": 0.999}),
        SweepSetting("semi-implicit", "semi-implicit Euler", {"integrator": "semi-implicit"}),
        SweepSetting("angle=12", "12 deg termination", {"angle_threshold_deg": 12.0}),
        SweepSetting("tau=0.01", "time step 0.01 s", {"tau": 0.01}),
        SweepSetting("init=0.1", "initial state in [-0.1, 0.1]^4", {"init_bound": 0.1}, doubled=False),
        SweepSetting("normalised", "normalised features",
                     {"feature_scale": NORMALISED_SCALE}, {"feature_bound": 1.0}),
        # The discounts where the safe step can move (c ~ 10^3 - 10^4), adapting the normalised
        # baseline (their own baseline searches stall far below 195).
        SweepSetting("gamma=0.95+normalised", "gamma 0.95, normalised",
                     {"gamma": 0.95, "feature_scale": NORMALISED_SCALE}, {"feature_bound": 1.0},
                     warm_start="cartpole-baseline-normalised"),
        SweepSetting("gamma=0.9+normalised", "gamma 0.9, normalised",
                     {"gamma": 0.9, "feature_scale": NORMALISED_SCALE}, {"feature_bound": 1.0},
                     warm_start="cartpole-baseline-normalised"),
        SweepSetting("M_phi=0.1", "M_phi 0.1", constants={"feature_bound": 0.1}, plausible=False),
        SweepSetting("M_phi=0.03", "M_phi 0.03", constants={"feature_bound": 0.03}, plausible=False),
        SweepSetting("M_phi=0.01", "M_phi 0.01", constants={"feature_bound": 0.01}, plausible=False),
    )


#: The settings of the cart-pole sweep, by key.
CARTPOLE_SWEEP: dict[str, SweepSetting] = {st.key: st for st in _sweep_settings()}
