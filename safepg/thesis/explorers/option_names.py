"""The page learner's vocabulary: a run's options under the option objects' own field names.

The JavaScript learner of the book's pages takes one flat configuration per run. Its names
are the fields of :mod:`safepg.options` and :class:`~safepg.runner.RunConfig`, spelt in
camelCase (``score_action`` is ``scoreAction``, ``n_min`` is ``nMin``). A nested option
object with one possible type (``Adaptive.gradient``) adds its fields to the configuration;
a field that may hold one of several types, or none (``Vanilla.step``, ``Vanilla.target``),
is a name whose value is the type's name (``step: "SafeStep"``), followed by that type's fields.

:func:`option_table` reads this table from the dataclasses themselves (fields, defaults and
the allowed values of their ``Literal`` types) through :mod:`safepg.option_fields`, as the
command line does. ``static/options.js`` holds it for the page, written by ``python -m
safepg.thesis.explorers.option_names``; a test requires that file to be what this module writes.
:func:`learner_options` flattens a method through the same table, so no name is spelt twice:
changing an option changes the dataclass and this file.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from safepg.definition import to_dict
from safepg.option_fields import OptionField, option_fields
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


def _leaf(f: OptionField) -> dict[str, Any]:
    """The allowed values of a plain field: ``choices`` (a bool's are true and false), ``number``,
    ``integer``, ``nullable``."""
    out: dict[str, Any] = {}
    choices = [True, False] * f.boolean + list(f.choices)
    if choices:
        out["choices"] = choices
    for kind in ("integer", "number", "nullable"):
        if getattr(f, kind):
            out[kind] = True
    return out


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
        entries: dict[str, Any] = {}
        table[cls.__name__] = entries
        for f in option_fields(cls):
            entry: dict[str, Any] = {"field": f.name}
            if f.types:
                entry["types"] = [t.__name__ for t in f.types]
                entry["nested"] = len(f.types) == 1 and not f.nullable
                if f.nullable:
                    entry["nullable"] = True
                if not f.required:
                    entry["default"] = None if f.default is None else type(f.default).__name__
                for t in f.types:
                    visit(t)
            else:
                entry.update(_leaf(f))
                if not f.required:
                    entry["default"] = f.default
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
