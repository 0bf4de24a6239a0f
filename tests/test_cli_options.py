"""``safepg learn``'s option flags against the dataclasses they set (safepg.cli, safepg.option_fields).

The parser is built from the option dataclasses. These tests read the dataclasses on their own
(the defaults ``__init__`` really uses, from its signature; the choices, from the ``Literal``
annotations) and compare every flag with its field, so that a default or a list of choices
typed by hand, a field without a flag, or a wrong reading of a field fails here.
:func:`test_the_check_catches_drift` shows that :func:`drift` reports each kind of disagreement.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import types
import typing
from dataclasses import dataclass
from typing import Any, Literal

import pytest

from safepg.cli import OPTION_GROUPS, OptionFlag, _learn_parser, _method, learn_flags
from safepg.option_fields import option_field, option_fields, parameter_docs, plain
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, SafeStep, Vanilla

#: The flags ``safepg learn`` had before they were generated: users' scripts type them.
FLAGS = ["--estimator", "--baseline", "--score-action", "--bound", "--delta", "--range", "--n-min", "--n-max",
         "--first", "--batch-constants", "--maxima", "--unguarded-step", "--batch-size", "--alpha", "--safe-step",
         "--kind", "--target", "--update"]


def learn_parser() -> argparse.ArgumentParser:
    return _learn_parser(argparse.ArgumentParser(prog="safepg").add_subparsers())


def actions(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {s: a for a in parser._actions for s in a.option_strings}


def declared(owner: type, name: str) -> tuple[Any, tuple[Any, ...], tuple[Any, ...]]:
    """A field's default as ``__init__`` has it (``inspect.Parameter.empty`` if required), its
    ``Literal`` values and its annotation's members: read without safepg.option_fields."""
    default = inspect.signature(owner).parameters[name].default
    hint = typing.get_type_hints(owner)[name]
    union = isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union
    members = typing.get_args(hint) if union else (hint,)
    literal = tuple(v for m in members if typing.get_origin(m) is Literal for v in typing.get_args(m))
    return default, literal, members


def drift(parser: argparse.ArgumentParser, flags: tuple[OptionFlag, ...]) -> list[str]:
    """Each way the parser's flags disagree with the fields they set: default, choices, kind of switch."""
    acts, problems = actions(parser), []
    for o in flags:
        where = f"{o.flag} ({o.owner.__name__}.{o.field})"
        a = acts.get(o.flag)
        if a is None:
            problems.append(f"{where}: no such flag")
            continue
        default, literal, members = declared(o.owner, o.field)
        # A required field, or a flag whose presence makes its object, is None until given.
        want = None if default is inspect.Parameter.empty or o.chooses else default
        if a.default != want or type(a.default) is not type(want):
            problems.append(f"{where}: default {a.default!r}, the field's {want!r}")
        if bool in members:
            switch = argparse.BooleanOptionalAction if want else argparse._StoreTrueAction
            if type(a) is not switch:
                problems.append(f"{where}: a {type(a).__name__}, not a {switch.__name__}")
        elif literal and float in members:  # a choice or a number (ErrorModel.range)
            if a.choices is not None or [a.type(c) for c in literal] != list(literal) or a.type("2.5") != 2.5:
                problems.append(f"{where}: does not take {literal} or a number")
            try:
                a.type("-".join(map(str, literal)) + "?")
            except argparse.ArgumentTypeError:
                pass
            else:
                problems.append(f"{where}: takes what is neither one of {literal} nor a number")
        elif literal and list(a.choices or ()) != list(literal):
            problems.append(f"{where}: choices {a.choices}, the field's {list(literal)}")
        if not a.help:
            problems.append(f"{where}: no help")
    return problems


def test_every_flag_agrees_with_its_dataclass() -> None:
    assert drift(learn_parser(), learn_flags()) == []


def test_the_flags_keep_their_names() -> None:
    assert [o.flag for o in learn_flags()] == FLAGS
    assert set(FLAGS) <= set(actions(learn_parser()))


def _leaf_fields(cls: type, seen: set[type]) -> set[tuple[type, str]]:
    """The plain-valued fields of ``cls`` and of the option objects its fields hold."""
    if cls in seen:
        return set()
    seen.add(cls)
    out = set()
    for f in dataclasses.fields(cls):
        _, _, members = declared(cls, f.name)
        nested = [m for m in members if dataclasses.is_dataclass(m)]
        for m in nested:
            out |= _leaf_fields(m, seen)
        if not nested:
            out.add((cls, f.name))
    return out


def test_every_option_field_has_one_flag() -> None:
    """A field added to an option object, and not to the command line, fails here."""
    seen: set[type] = set()
    fields = _leaf_fields(Adaptive, seen) | _leaf_fields(Vanilla, seen)
    flags = [(o.owner, o.field) for o in learn_flags()]
    assert len(flags) == len(set(flags))
    assert set(flags) == fields


def test_the_defaults_make_the_default_objects() -> None:
    """No flag given: Algorithm 4.1 with every option object's default."""
    parser = argparse.ArgumentParser()
    _learn_parser(parser.add_subparsers())
    assert _method(parser.parse_args(["learn"])) == Adaptive()
    assert _method(parser.parse_args(["learn", "--batch-size", "100", "--alpha", "1e-3"])) == Vanilla(100)
    assert _method(parser.parse_args(["learn", "--batch-size", "100", "--safe-step", "coordinate"])) == Vanilla(
        100, SafeStep())


def test_help_is_the_docstrings() -> None:
    acts = actions(learn_parser())
    assert acts["--maxima"].help == plain(parameter_docs(Departures)["maxima"])
    assert "largest sample variance" in acts["--maxima"].help
    assert acts["--alpha"].help == "FixedStep.alpha: The step size, finite and >= 0."
    text = learn_parser().format_help()  # every help formats (a stray % would raise here)
    assert "(default: 500000)" in text and "(default: 0.95)" in text and "(default: gpomdp)" in text


@dataclass(frozen=True)
class DriftedErrorModel:
    """ErrorModel as it would be after a change the command line did not follow.

    Parameters
    ----------
    bound : str
        One more bound.
    delta : float
        Another default.
    range : "lemma", "empirical" or float
        As ErrorModel's.
    """

    bound: Literal["chebyshev", "hoeffding", "bernstein", "azuma"] = "chebyshev"
    delta: float = 0.9
    range: Literal["lemma", "empirical"] | float = "lemma"


def test_the_check_catches_a_parser_typed_by_hand() -> None:
    """As the command line was: a default, a list of choices and a default's type drift."""
    parser = learn_parser()
    acts = actions(parser)
    acts["--n-max"].default = 400_000
    acts["--bound"].choices = ["chebyshev", "hoeffding"]
    acts["--n-min"].default = 100.0  # equal to the field's 100, but a float where the field holds an int
    assert [p.split(":")[0] for p in drift(parser, learn_flags())] == [
        "--bound (ErrorModel.bound)", "--n-min (Batches.n_min)", "--n-max (Batches.n_max)"]


def test_the_check_catches_a_changed_dataclass_and_the_parser_follows_it(monkeypatch: pytest.MonkeyPatch) -> None:
    # A parser that did not follow the change: another default, one more choice.
    drifted = tuple(o._replace(owner=DriftedErrorModel) if o.owner is ErrorModel else o for o in learn_flags())
    problems = drift(learn_parser(), drifted)
    assert [p.split(":")[0] for p in problems] == ["--bound (DriftedErrorModel.bound)",
                                                   "--delta (DriftedErrorModel.delta)"]
    assert "'azuma'" in problems[0] and "0.9" in problems[1]
    # The command line builds its flags from the dataclass, so it does follow the change.
    monkeypatch.setattr("safepg.cli.OPTION_GROUPS",
                        {DriftedErrorModel if c is ErrorModel else c: n for c, n in OPTION_GROUPS.items()})
    assert learn_flags() == drifted
    assert drift(learn_parser(), drifted) == []


def test_the_check_catches_a_misread_field(monkeypatch: pytest.MonkeyPatch) -> None:
    """The check holds the parser to the default ``__init__`` uses, not to what safepg.option_fields reads."""
    n_max = next(f for f in dataclasses.fields(Batches) if f.name == "n_max")
    monkeypatch.setattr(n_max, "default", 7)  # what the field now says; Batches() still has 500 000
    assert option_field(Batches, "n_max").default == 7 and Batches().n_max == 500_000
    assert [p.split(":")[0] for p in drift(learn_parser(), learn_flags())] == ["--n-max (Batches.n_max)"]


def test_parameter_docs() -> None:
    class Documented:
        """Summary.

        Parameters
        ----------
        a, b : int
            Shared: :math:`N_{min} \\le N`,
            over two lines (:class:`~safepg.options.Batches`).
        c : {"x", "y"}
            ``"x"`` or ``"y"``.

        Returns
        -------
        nothing : None
            Not a parameter.
        """

    assert parameter_docs(Documented) == {"a": "Shared: N_min <= N, over two lines (Batches).",
                                          "b": "Shared: N_min <= N, over two lines (Batches).",
                                          "c": '"x" or "y".'}


def test_every_option_field_is_documented() -> None:
    """The help of every flag is its field's docstring entry: none may be missing."""
    for o in learn_flags():
        assert option_field(o.owner, o.field).help, f"{o.owner.__name__}.{o.field} has no entry under Parameters"


def test_a_field_with_no_reading_is_refused() -> None:
    @dataclass
    class Odd:
        sizes: list

    with pytest.raises(TypeError, match=r"Odd\.sizes: no reading"):
        option_fields(Odd)


def test_fixed_and_safe_steps_keep_their_own_kind_defaults() -> None:
    """--kind is FixedStep's (default scalar); --safe-step chooses a SafeStep, so has none of its own."""
    acts = actions(learn_parser())
    assert acts["--kind"].default == option_field(FixedStep, "kind").default == "scalar"
    assert acts["--safe-step"].default is None and option_field(SafeStep, "kind").default == "coordinate"
