"""The scorecard's cell texts: percentages, numbers, intervals, differences, closed forms, notes."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import sympy as sp

from safepg import theory


def pct(x: float | None, digits: int = 2) -> str:
    """A ratio as a percentage rounded to ``digits`` decimals (``"-"`` for None)."""
    return "-" if x is None else f"{round(100 * x, digits):g}%"


def num(x: float | None, decimals: int) -> str:
    """A number with ``decimals`` decimals (``"-"`` for None)."""
    return "-" if x is None else f"{x:.{decimals}f}"


def ci_text(ci: Sequence[float | None] | None, fmt: Callable[[float], str]) -> str:
    """An interval as " [lo; hi]" (after a value), each end formatted by ``fmt``; "" without one."""
    if not ci or ci[0] is None or ci[1] is None:
        return ""
    return f" [{fmt(ci[0])}; {fmt(ci[1])}]"


def signed(x: float, decimals: int) -> str:
    """A difference with its sign and ``decimals`` decimals."""
    return f"{x:+.{decimals}f}"


def expr_text(e: Any) -> str:
    """Plain-text form of a printed or derived statement (sympy or LaTeX string)."""
    if isinstance(e, sp.Basic):
        s = sp.sstr(e)
        s = re.sub(r"sqrt\((\w+)\)", r"√\1", s)
        return s.replace("**", "^").replace("*", "·")
    return str(e)


def expr_tex(e: Any) -> str:
    """LaTeX of a statement; "" for a plain-text one (a string without a backslash)."""
    if isinstance(e, sp.Basic):
        return theory.latex(e)
    return str(e) if "\\" in str(e) else ""


def fill(template: str, values: Mapping[str, Any]) -> str:
    """A note's text with its ``{...}`` fields filled from ``values``; a field that cannot be
    filled makes every field read "(not computed)"."""
    try:
        return template.format(**values)
    except (KeyError, ValueError, IndexError):
        return re.sub(r"\{[^}]*\}", "(not computed)", template)
