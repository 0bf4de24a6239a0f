"""The option objects' fields as data: name, default, allowed values and help, read from the dataclasses.

The option objects of :mod:`safepg.options` are the one place where an option's name, its
default, the values it allows (a ``Literal`` annotation) and its meaning (the class docstring's
Parameters section) are written. Whatever else presents the options reads them from there
through :func:`option_fields`: the command line (``safepg learn``'s flags, defaults, choices
and help) and the book's page learner (its table of options), so that changing an option
changes the dataclass alone.

>>> from safepg.options import ErrorModel
>>> [(f.name, f.default, f.choices) for f in option_fields(ErrorModel)][:2]
[('bound', 'chebyshev', ('chebyshev', 'hoeffding', 'bernstein')), ('delta', 0.95, ())]
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import types
import typing
from dataclasses import dataclass
from typing import Any, Literal

from safepg.definition import OPTION_TYPES

#: A field's default when it has none (the field is required): ``dataclasses.MISSING``.
REQUIRED: Any = dataclasses.MISSING


@dataclass(frozen=True)
class OptionField:
    """One constructor field of an option object, as its annotation, default and docstring declare it.

    Parameters
    ----------
    owner : type
        The option object's class.
    name : str
        The field's name.
    default : object
        Its default (a ``default_factory``'s value), or :data:`REQUIRED`.
    choices : tuple
        The values of its ``Literal`` annotation, in their order; empty when it has none.
    boolean : bool
        The field is a ``bool``.
    integer : bool
        It admits an ``int``.
    number : bool
        It admits a ``float``.
    nullable : bool
        It admits None.
    types : tuple of type
        The option objects it may hold (``Vanilla.step``: FixedStep and SafeStep); empty for a plain value.
    help : str
        Its description in the owner's docstring, as plain text (:func:`plain`); empty when undocumented.
    """

    owner: type
    name: str
    default: Any
    choices: tuple[Any, ...] = ()
    boolean: bool = False
    integer: bool = False
    number: bool = False
    nullable: bool = False
    types: tuple[type, ...] = ()
    help: str = ""

    @property
    def required(self) -> bool:
        """Whether the field has no default."""
        return self.default is REQUIRED


def alternatives(hint: Any) -> tuple[Any, ...]:
    """The members of a union type hint (``X | None`` gives ``(X, NoneType)``), or the hint alone."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        return typing.get_args(hint)
    return (hint,)


def _field_default(f: dataclasses.Field[Any]) -> Any:
    """A dataclass field's default, its ``default_factory``'s value, or :data:`REQUIRED`."""
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return REQUIRED


def _read_hint(owner: type, name: str, hint: Any) -> dict[str, Any]:
    """The :class:`OptionField` keywords a type hint decides."""
    out: dict[str, Any] = {"choices": (), "types": ()}
    for arg in alternatives(hint):
        if arg is type(None):
            out["nullable"] = True
        elif arg is bool:
            out["boolean"] = True
        elif typing.get_origin(arg) is Literal:
            out["choices"] += typing.get_args(arg)
        elif arg is int:
            out["integer"] = True
        elif arg is float:
            out["number"] = True
        elif isinstance(arg, type) and OPTION_TYPES.get(arg.__name__) is arg:
            out["types"] += (arg,)
        else:
            # Refused rather than skipped: a reader that skipped it would offer the option without its values.
            raise TypeError(f"{owner.__name__}.{name}: no reading of a field of type {arg!r}")
    return out


def option_fields(cls: type) -> tuple[OptionField, ...]:
    """The constructor fields of an option object, in their order.

    Parameters
    ----------
    cls : type
        A dataclass of :mod:`safepg.options` (or any dataclass whose fields are plain values,
        ``Literal`` choices and option objects).

    Returns
    -------
    tuple of OptionField

    Raises
    ------
    TypeError
        A field's annotation holds a type with no reading here (neither a plain value nor an option object).
    """
    hints = typing.get_type_hints(cls)
    docs = parameter_docs(cls)
    return tuple(OptionField(cls, f.name, _field_default(f), help=docs.get(f.name, ""),
                             **_read_hint(cls, f.name, hints[f.name]))
                 for f in dataclasses.fields(cls) if f.init)


def option_field(cls: type, name: str) -> OptionField:
    """The field ``name`` of the option object ``cls`` (:func:`option_fields`)."""
    for f in option_fields(cls):
        if f.name == name:
            return f
    raise KeyError(f"{cls.__name__} has no field {name!r}")


def _is_rule(line: str) -> bool:
    return len(line.strip()) >= 3 and set(line.strip()) == {"-"}


def parameter_docs(cls: type) -> dict[str, str]:
    """Each name's description in the NumPy-style Parameters section of ``cls``'s docstring, as plain text.

    An entry ``n_min, n_max : int`` gives its description to both names; an entry's description
    is its indented lines joined into one paragraph.

    >>> from safepg.options import ErrorModel
    >>> parameter_docs(ErrorModel)["delta"]
    'The probability of a worsening update, in (0, 1).'
    """
    lines = (inspect.getdoc(cls) or "").splitlines()
    starts = [i for i in range(len(lines) - 1) if lines[i].strip() == "Parameters" and _is_rule(lines[i + 1])]
    if not starts:
        return {}
    out: dict[str, list[str]] = {}
    names: list[str] = []
    body = lines[starts[0] + 2:]
    for i, line in enumerate(body):
        if not line.strip():
            continue
        if i + 1 < len(body) and _is_rule(body[i + 1]):  # the next section's heading
            break
        if line[0].isspace():
            for name in names:
                out[name].append(line.strip())
        else:
            names = [n.strip() for n in line.split(":", 1)[0].split(",")]
            for name in names:
                out[name] = []
    return {name: plain(" ".join(text)) for name, text in out.items()}


#: TeX commands of the docstrings' formulas, as plain text; any other ``\name`` is written ``name``.
_TEX = {"le": " <= ", "ge": " >= ", "leftarrow": " <- ", "hat": "", "nabla": " grad "}


def _tex(formula: str) -> str:
    # A command takes the space after it, so that ``|\hat g_k|`` is ``|g_k|`` and ``M_\phi`` is ``M_phi``.
    text = re.sub(r"\\([A-Za-z]+)\s*", lambda m: _TEX.get(m[1], f"{m[1]} "), formula)
    return re.sub(r"\s+", " ", re.sub(r"[{}]", "", text)).strip()


def plain(text: str) -> str:
    r"""reStructuredText of a docstring as plain text, for a terminal.

    Roles keep their text (``:class:`~safepg.options.Batches``` is ``Batches``), formulas are
    spelt out (``:math:`N_{min} \le N``` is ``N_min <= N``) and literals lose their quotes.

    >>> plain(r"the step :math:`\alpha \hat g_k` (``'coordinate'``, :func:`~safepg.learning.vanilla_pg`)")
    "the step alpha g_k ('coordinate', vanilla_pg)"
    """
    text = re.sub(r":math:`([^`]*)`", lambda m: _tex(m[1]), text)
    text = re.sub(r":[a-z:]+:`~?(?:[\w.]+\.)?([^`.]+)`", r"\1", text)
    text = re.sub(r"``([^`]*)``", r"\1", text)
    return re.sub(r"\s+", " ", text).strip()


__all__ = ["REQUIRED", "OptionField", "alternatives", "option_field", "option_fields",
           "parameter_docs", "plain"]
