"""What a scorecard row is judged on: the prediction interval for one run of a report's entry, the texts
that name an interval, and why a run's improvement ratio carries no information."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from safepg.thesis.scorecard.rules import FROZEN_THETA, in_prediction


def prediction(d: Mapping[str, Any] | None, ratio: bool = False) -> list[float] | None:
    """The 95% prediction interval for one run of a report's entry (None without two seeds); a
    ratio's is cut to [0, 1], where every ratio lies (which changes no verdict on a printed ratio)."""
    pi = (d or {}).get("pi95")
    if not pi or pi[0] is None:
        return None
    return [max(pi[0], 0.0), min(pi[1], 1.0)] if ratio else [float(pi[0]), float(pi[1])]


def pi_text(pi: Sequence[float] | None, fmt: Callable[[float], str], seeds: int | None, then: str = "") -> str:
    """A prediction interval as the page shows it, with what it is (and ``then``, after a semicolon)."""
    if not pi:
        return ""
    return f"[{fmt(pi[0])}; {fmt(pi[1])}]: 95% prediction interval for one run, {seeds} seeds" + \
        (f"; {then}" if then else "")


def ci_judged(ci: Sequence[float] | None, fmt: Callable[[float], str], seeds: int | None) -> str:
    """The interval of our mean as the page shows it, with what it is."""
    if not ci or ci[0] is None:
        return ""
    return f"[{fmt(ci[0])}; {fmt(ci[1])}]: 95% interval of our mean, {seeds} seeds"


def frozen(moved: float | None) -> str:
    """Why a run's improvement ratio carries no information ("" when theta moved)."""
    if moved is None or moved >= FROZEN_THETA:
        return ""
    return (f"θ moved by at most {moved:.1e} over the run (below {FROZEN_THETA:g}): consecutive batch means differ "
            "by noise alone, so the ratio carries no information.")


def ratio_pct(d: Mapping[str, Any] | None) -> list[float] | None:
    """:func:`prediction` of a ratio, in percentage points (the unit the thesis prints)."""
    pi = prediction(d, ratio=True)
    return None if pi is None else [100 * pi[0], 100 * pi[1]]


def one_run_ratio(printed: float, d: Mapping[str, Any] | None) -> bool | None:
    """Rule ``"prediction"`` on an improvement ratio: the printed percentage in our prediction interval."""
    return in_prediction(f"{100 * printed:.6g}", ratio_pct(d))
