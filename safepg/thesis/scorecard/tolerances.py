"""The tolerances of the rules (:data:`~safepg.thesis.scorecard.rules.RULES`) on printed numbers:
half a unit of the last printed digit (:func:`half_unit`) and the checks built on it."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from safepg.thesis.scorecard.rules import RATIO_POINTS


def half_unit(printed: str) -> float:
    """Half a unit of the last printed digit of a number as printed.

    ``"-0.59"`` -> 0.005, ``"1.4e-06"`` -> 5e-08, ``"72"`` -> 0.5, ``"2500"`` -> 50 (the
    trailing zeros of an integer are read as not significant, as in "N ~ 2500").

    Raises
    ------
    ValueError
        If ``printed`` is not a number.
    """
    m = re.fullmatch(r"\s*[-+]?(\d*)(?:\.(\d+))?(?:[eE]([-+]?\d+))?\s*", printed)
    if m is None or not (m.group(1) or m.group(2)):
        raise ValueError(f"printed must be a number as printed, got {printed!r}")
    integer, decimals, exponent = m.group(1), m.group(2), int(m.group(3) or 0)
    if decimals:
        unit = 10.0 ** -len(decimals)
    else:
        stripped = integer.rstrip("0")
        unit = 10.0 ** (len(integer) - len(stripped)) if stripped else 1.0
    return 0.5 * unit * 10.0**exponent


def within_rounding(ours: float, printed: str) -> bool:
    """Rule ``"rounded"``: |ours - printed| <= half a unit of its last digit (exact for 0)."""
    value = float(printed)
    if value == 0:
        return ours == 0
    return abs(ours - value) <= half_unit(printed) * (1 + 1e-9)


def intervals_overlap(a: Sequence[float], b: Sequence[float]) -> bool:
    """Rule ``"ci-overlap"``: two closed intervals [lo, hi] (either order of ends) overlap."""
    lo_a, hi_a = sorted(a)
    lo_b, hi_b = sorted(b)
    return lo_a <= hi_b and lo_b <= hi_a


def in_prediction(printed: str, pi: Sequence[float | None] | None, values: Sequence[float] = ()) -> bool | None:
    """Rule ``"prediction"``: the printed value in our 95% prediction interval for one run, widened by
    half a unit of its last digit. A printed 0 must be exactly 0 in every seed (``values``). None when
    there is no interval (fewer than two seeds)."""
    value = float(printed)
    if value == 0 and len(values):
        return bool(np.all(np.asarray(values) == 0))
    if not pi or pi[0] is None or pi[1] is None:
        return None
    lo, hi = sorted((float(pi[0]), float(pi[1])))
    h = half_unit(printed)
    return lo - h <= value <= hi + h


def within_points(ours: float, thesis: float, points: float = RATIO_POINTS) -> bool:
    """Rule ``"ratio-points"``: two ratios in [0, 1] within ``points`` percentage points."""
    return abs(ours - thesis) * 100 <= points + 1e-9


def is_slip(output: float, printed: str) -> bool:
    """The printed value is neither the rounding nor the truncation of the authors' output: they
    differ by more than one unit of its last printed digit (37.4 for 37.64; -0.014676 for -0.0136766)."""
    return abs(output - float(printed)) > 2 * half_unit(printed) * (1 + 1e-9)


def order_of_magnitude(x: float) -> int:
    """floor(log10 |x|): the k of "of the order of 10^k"."""
    if not x:
        raise ValueError(f"x must be non-zero, got {x!r}")
    return math.floor(math.log10(abs(x)))
