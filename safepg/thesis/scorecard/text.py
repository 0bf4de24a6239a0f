"""The scorecard's cell texts: percentages, numbers, intervals, differences, closed forms, notes."""

from __future__ import annotations

import re
import string
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import Any


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


def _is_sympy(e: Any) -> bool:
    """Whether ``e`` is a sympy expression, without importing sympy (3 s) where nothing made one."""
    sp = sys.modules.get("sympy")
    return sp is not None and isinstance(e, sp.Basic)


def expr_text(e: Any) -> str:
    """Plain-text form of a printed or derived statement (sympy or LaTeX string)."""
    if _is_sympy(e):
        import sympy as sp

        s = sp.sstr(e)
        s = re.sub(r"sqrt\((\w+)\)", r"√\1", s)
        return s.replace("**", "^").replace("*", "·")
    return str(e)


def expr_tex(e: Any) -> str:
    """LaTeX of a statement; "" for a plain-text one (a string without a backslash)."""
    if _is_sympy(e):
        from safepg import theory

        return theory.latex(e)
    return str(e) if "\\" in str(e) else ""


class MissingValueError(KeyError):
    """A note's text names a field its values do not give."""


def template_fields(template: str) -> frozenset[str]:
    """The names of a note's ``{...}`` fields (``"{J_used:.3f}"`` names ``J_used``)."""
    # The field's name is what precedes any attribute, index, conversion or format spec.
    return frozenset(re.split(r"[.\[]", name, maxsplit=1)[0]
                     for _, name, _, _ in string.Formatter().parse(template) if name is not None)


def fill(template: str, values: Mapping[str, Any]) -> str:
    """A note's text with its ``{...}`` fields filled from ``values``.

    Raises
    ------
    MissingValueError
        If ``template`` names a field that ``values`` does not give: a row whose value is
        legitimately absent (runs not in the store) says so by its own sentence, never by a
        note left unfilled.
    """
    missing = template_fields(template) - set(values)
    if missing:
        raise MissingValueError(f"the note {template[:60]!r}... needs {sorted(missing)}, got {sorted(values)}")
    return template.format(**values)
