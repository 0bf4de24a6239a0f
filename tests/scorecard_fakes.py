"""A stand-in for a significance test, for synthetic scorecard rows: its p-value given, its detectable
difference falling as 1/sqrt(seeds) to a floor."""

from __future__ import annotations

import numpy as np


class FakeTest:
    """A test with p-value ``p`` and detectable difference ``floor + spread / sqrt(seeds)``."""

    name = "fake"

    def __init__(self, p: float, spread: float = 1.0, seeds: int = 5, floor: float = 0.1) -> None:
        self.p_value, self.spread, self.seeds, self.floor = p, spread, seeds, floor

    def detectable_difference(self, alpha: float, seeds: float | None = None, power: float = 0.8) -> float:
        k = self.seeds if seeds is None else seeds
        return float(self.floor + self.spread / np.sqrt(k))


def passing() -> FakeTest:
    """Not rejected, and detects 0.1 + 0.1/sqrt(5) < 1 (a relevance of 1 is met)."""
    return FakeTest(0.9, spread=0.1)


def failing() -> FakeTest:
    """Rejected at any level the correction reaches."""
    return FakeTest(1e-9)
