"""The page learner's vocabulary: a run's options under the option objects' own field names.

The JavaScript learner of the book's pages takes one flat configuration per run. Its names
are the fields of :mod:`safepg.options` and :class:`~safepg.runner.RunConfig`, spelt in
camelCase (``score_action`` is ``scoreAction``, ``n_min`` is ``nMin``). A nested option
object with one possible type (``Adaptive.gradient``) adds its fields to the configuration;
a field that may hold one of several types, or none (``Vanilla.step``, ``Vanilla.target``),
is a name whose value is the type's name (``step: "SafeStep"``), followed by that type's fields.

:func:`option_table` reads this table from the dataclasses themselves (fields, defaults and
the allowed values of their ``Literal`` types). ``static/options.js`` holds it for the page,
written by ``python -m safepg.thesis.explorers.option_names``; a test requires that file to
be what this module writes. :func:`learner_options` flattens a method through the same
table, so no name is spelt twice: changing an option changes the dataclass and this file.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import types
import typing
from pathlib import Path
from typing import Any, Literal

from safepg.definition import OPTION_TYPES, to_dict
from safepg.options import Adaptive, Method, Vanilla

#: The run's own settings beside its method (:class:`~safepg.runner.RunConfig`'s fields that the
#: page learner reads), with the page's defaults: one seed's stream, theta0 = 0 in every component.
RUN_FIELDS: dict[str, dict[str, Any]] = {
    "theta0": {"field": "theta0", "number": True, "list": True, "default": 0.0},
    "sigma": {"field": "sigma", "number": True, "default": 1.0},
    "budget": {"field": "budget", "integer": True, "default": 1_000_000},
    "stopOnDivergence": {"field": "stop_on_divergence", "choices": [True, False], "default": True},
    "seed": {"field": "seed", "integer": True, "default": 0},
}
#: The methods the page learner runs, by the name of their type (a configuration's ``method``).
METHODS = (Adaptive, Vanilla)
#: Where the table is committed, beside the learner's other files.
TABLE_FILE = Path(__file__).with_name("static") / "options.js"


def camel(name: str) -> str:
    """``score_action`` -> ``scoreAction``."""
    head, *rest = name.split("_")
    return head + "".join(part[:1].upper() + part[1:] for part in rest)


def _alternatives(hint: Any) -> tuple[Any, ...]:
    """The members of a union type hint (``X | None`` gives ``(X, NoneType)``), or the hint alone."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        return typing.get_args(hint)
    return (hint,)


def _leaf(hint: Any) -> dict[str, Any]:
    """The allowed values of a field's type hint: ``choices``, ``number``, ``integer``, ``nullable``."""
    out: dict[str, Any] = {}
    for arg in _alternatives(hint):
        if arg is type(None):
            out["nullable"] = True
        elif arg is bool:
            out["choices"] = [True, False]
        elif typing.get_origin(arg) is Literal:
            out.setdefault("choices", []).extend(typing.get_args(arg))
        elif arg is int:
            out["integer"] = True
        elif arg is float:
            out["number"] = True
        else:
            raise TypeError(f"the page learner has no spelling for a field of type {arg!r}")
    return out


def _option_types(hint: Any) -> list[str] | None:
    """The option types a field may hold (None when it holds plain values)."""
    named = [a.__name__ for a in _alternatives(hint) if isinstance(a, type) and OPTION_TYPES.get(a.__name__) is a]
    return named or None


def _default(f: dataclasses.Field[Any]) -> Any:
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return dataclasses.MISSING


def option_table() -> dict[str, Any]:
    """The table ``static/options.js`` holds.

    Returns
    -------
    dict
        ``{"methods": [...], "run": RUN_FIELDS, "types": {type name: {camelCase name: entry}}}``,
        each entry with ``field`` (the Python name) and either ``types`` (option types it may
        hold, ``nested`` when there is one and it is always present) or the allowed values
        (``choices``, ``number``, ``integer``, ``nullable``), with ``default`` (a type's name
        for an option object; absent when the field is required).
    """
    table: dict[str, dict[str, Any]] = {}

    def visit(cls: type) -> None:
        if cls.__name__ in table:
            return
        hints = typing.get_type_hints(cls)
        entries: dict[str, Any] = {}
        table[cls.__name__] = entries
        for f in dataclasses.fields(cls):
            if not f.init:
                continue
            hint, default = hints[f.name], _default(f)
            named = _option_types(hint)
            entry: dict[str, Any] = {"field": f.name}
            if named is not None:
                nullable = type(None) in _alternatives(hint)
                entry["types"] = named
                entry["nested"] = len(named) == 1 and not nullable
                if nullable:
                    entry["nullable"] = True
                if default is not dataclasses.MISSING:
                    entry["default"] = None if default is None else type(default).__name__
                for name in named:
                    visit(OPTION_TYPES[name])
            else:
                entry.update(_leaf(hint))
                if default is not dataclasses.MISSING:
                    entry["default"] = default
            entries[camel(f.name)] = entry

    for method in METHODS:
        visit(method)
    for method in METHODS:
        _check_unique(table, method.__name__)
    return {"methods": [m.__name__ for m in METHODS], "run": RUN_FIELDS, "types": table}


def _flat_names(table: dict[str, Any], cls: str) -> list[str]:
    """A type's names in a flat configuration; the alternatives of one field count once each."""
    out: list[str] = []
    for name, entry in table[cls].items():
        if entry.get("nested"):
            out += _flat_names(table, entry["types"][0])
            continue
        out.append(name)
        if "types" in entry:
            out += sorted(set().union(*(set(_flat_names(table, t)) for t in entry["types"])))
    return out


def _check_unique(table: dict[str, Any], method: str) -> None:
    """One name, one field: else the page learner could not tell two options apart."""
    flat = _flat_names(table, method) + list(RUN_FIELDS) + ["method"]
    repeated = sorted({n for n in flat if flat.count(n) > 1})
    if repeated:
        raise ValueError(f"{method}'s options flatten to repeated names {repeated}")


def learner_options(method: Method) -> dict[str, Any]:
    """A method as the page learner's configuration: ``method`` (its type's name) and its fields
    under :func:`option_table`'s names.

    Parameters
    ----------
    method : Adaptive or Vanilla

    Returns
    -------
    dict
        For example ``{"method": "Adaptive", "estimator": "gpomdp", "baseline": True,
        "scoreAction": "clipped", "bound": "chebyshev", "delta": 0.95, "range": "lemma",
        "nMin": 100, "nMax": 500000, "first": None, "batchConstants": False, "maxima": False,
        "unguardedStep": False}``.
    """
    table = option_table()["types"]
    out: dict[str, Any] = {"method": type(method).__name__}

    def flatten(data: dict[str, Any]) -> None:
        for name, entry in table[data["type"]].items():
            value = data[entry["field"]]
            if entry.get("nested"):
                flatten(value)
            elif "types" in entry:
                out[name] = None if value is None else value["type"]
                if value is not None:
                    flatten(value)
            else:
                out[name] = value

    flatten(to_dict(method))
    return out


def table_js() -> str:
    """``static/options.js``: the table as the script the learner's files are concatenated with."""
    body = json.dumps(option_table(), indent=1, sort_keys=True)
    return ("// The run options' names, defaults and allowed values, for the page learner (vector_run.js).\n"
            "// Generated from safepg.options by `python -m safepg.thesis.explorers.option_names`: do not edit;\n"
            "// tests/test_option_names.py fails when it is not what that command writes.\n"
            f"\"use strict\";\nsafepgLearner.OPTIONS = {body};\n")


def main() -> None:
    """Write :data:`TABLE_FILE`, or with ``--check`` fail when it is stale."""
    text = table_js()
    if "--check" in sys.argv[1:]:
        if TABLE_FILE.read_text() != text:
            raise SystemExit(f"{TABLE_FILE} is stale: run python -m safepg.thesis.explorers.option_names")
        return
    TABLE_FILE.write_text(text)
    print(f"wrote {TABLE_FILE}")


if __name__ == "__main__":
    main()


__all__ = ["METHODS", "RUN_FIELDS", "TABLE_FILE", "camel", "learner_options", "option_table", "table_js"]
