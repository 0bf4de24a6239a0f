"""A run's definition as data: one canonical dictionary, and the key that hashes it.

A learning run is decided by its task, its method (the option objects of
:mod:`safepg.options`), the starting parameters θ₀, the exploration σ and the budget. Each
of these is a frozen value, and :func:`to_dict` writes any of them as plain JSON data with
its type named, every field present (defaults included):

>>> to_dict(ErrorModel("bernstein", 0.95, "empirical"))
{'type': 'ErrorModel', 'bound': 'bernstein', 'delta': 0.95, 'range': 'empirical'}

:func:`from_dict` builds the value again, so ``from_dict(to_dict(x)) == x``. The run key
(:meth:`safepg.runner.RunConfig.key`), the records' ``config`` and the command line all read
this one dictionary, under the option objects' own field names.

Tasks enter by their fields: a frozen dataclass task (:class:`~safepg.envs.cartpole.CartPole`,
or a researcher's own) by its constructor's fields, and a task that declares
:class:`safepg.tasks.Definition` (:class:`~safepg.envs.lqg.LQG`,
:class:`~safepg.envs.gym_task.GymTask`) by the keyword arguments its ``definition()`` returns;
one that declares :class:`safepg.tasks.FromDefinition` is built again by its ``from_definition``.
A function inside a definition (a feature map, an environment factory) enters by a name that can
be imported again, ``module:qualname``, or by the name given for it: a lambda or a nested
function without one has no name that would change when it changes, and is refused where a
definition must be exact (``exact=True``, the run keys).
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import sys
import types
import typing
from collections.abc import Callable, Mapping
from typing import Any, Literal, cast

import numpy as np

from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.tasks import Definition, FromDefinition, declares

#: The option objects, by the name their dictionaries carry.
OPTION_TYPES: dict[str, type] = {cls.__name__: cls for cls in (Adaptive, Vanilla, Gradient, ErrorModel, Batches,
                                                               Departures, FixedStep, SafeStep, Target)}
#: The core's tasks, by the short name their dictionaries carry (imported when read).
TASK_TYPES: dict[str, str] = {"LQG": "safepg.envs.lqg:LQG", "CartPole": "safepg.envs.cartpole:CartPole",
                              "GymTask": "safepg.envs.gym_task:GymTask", "Pendulum": "safepg.envs.pendulum:Pendulum"}


class UnnamedError(ValueError):
    """A value of a definition that cannot be written down exactly (a lambda, an unnamed task)."""


def function_name(fn: Callable[..., Any]) -> str:
    """``module:qualname`` of a function that :func:`import_name` finds again.

    Raises
    ------
    UnnamedError
        ``fn`` is a lambda or a function defined inside another (no importable name).
    """
    module, qualname = getattr(fn, "__module__", None), getattr(fn, "__qualname__", None)
    if not module or not qualname or "<" in qualname or module == "__main__":
        raise UnnamedError(
            f"{fn!r} has no name a stored run could be found by (a lambda, a nested function or one "
            f"defined in __main__): define it at the top of an importable module, or give it a name "
            f"(the task's name= or features_name=) that you change whenever the function changes")
    return f"{module}:{qualname}"


def import_name(name: str) -> Any:
    """The object ``module:qualname`` names (:func:`function_name`'s inverse)."""
    module, _, qualname = name.partition(":")
    if not module or not qualname:
        raise ValueError(f"name must be 'module:qualname', got {name!r}")
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _type_name(cls: type) -> str:
    """The name a value's dictionary carries: an option's or a core task's class name, else ``module:qualname``."""
    full = f"{cls.__module__}:{cls.__qualname__}"
    if OPTION_TYPES.get(cls.__name__) is cls or TASK_TYPES.get(cls.__name__) == full:
        return cls.__name__
    return full


def _type_of(name: str) -> type:
    if name in OPTION_TYPES:
        return OPTION_TYPES[name]
    cls = import_name(TASK_TYPES.get(name, name))
    if not isinstance(cls, type):
        raise ValueError(f"type must name a class, got {name!r}")
    return cls


#: How a field's numbers are written: as floats, as ints, or as given (a field that declares neither).
NumberKind = Literal["float", "int"] | None


def _number_kind(hint: Any) -> NumberKind:
    """``"float"`` if the annotation admits a float (``float``, ``float | None``, ``tuple[float, ...]``,
    ``np.ndarray | float``, ``Literal[...] | float``), else ``"int"`` if it admits an int, else None."""
    found: set[type] = set()

    def walk(h: Any) -> None:
        if h is float or h is int:
            found.add(h)
        elif typing.get_origin(h) is not Literal:
            for arg in typing.get_args(h):
                walk(arg)

    walk(hint)
    return "float" if float in found else "int" if int in found else None


def _annotations(cls: type) -> dict[str, Any]:
    """The declared annotations of ``cls``'s definition fields, each evaluated on its own.

    A dataclass's fields come from its classes' annotations (through the MRO); a class that writes
    itself with ``definition()`` declares its fields as its ``__init__``'s parameters. Each string
    annotation (``from __future__ import annotations``) is evaluated in its class's module; one that
    does not evaluate (a name imported only for type checking) declares nothing.
    """
    raw: dict[str, tuple[Any, dict[str, Any]]] = {}
    if dataclasses.is_dataclass(cls) and Definition not in cls.__mro__:
        for klass in reversed(cls.__mro__):
            module = vars(sys.modules.get(klass.__module__, types.ModuleType("_")))
            for name, hint in vars(klass).get("__annotations__", {}).items():
                raw[name] = (hint, module)
    else:
        init = inspect.unwrap(cls.__init__)  # type: ignore[misc]
        module = vars(sys.modules.get(init.__module__, types.ModuleType("_")))
        for name, hint in getattr(init, "__annotations__", {}).items():
            raw[name] = (hint, module)
    out = {}
    for name, (hint, module) in raw.items():
        if isinstance(hint, str):
            try:
                hint = eval(hint, dict(module))  # noqa: S307 - the class's own annotation, in its own module
            except Exception:  # a name only imported under TYPE_CHECKING: no declared number kind
                continue
        out[name] = hint
    return out


_DECLARED: dict[type, dict[str, NumberKind]] = {}


def declared_numbers(cls: type) -> dict[str, NumberKind]:
    """How each definition field of ``cls`` writes its numbers, from the field's declared type.

    >>> declared_numbers(Batches)
    {'n_min': 'int', 'n_max': 'int', 'first': 'int'}
    """
    if cls not in _DECLARED:  # read once per class: to_dict runs for every key
        _DECLARED[cls] = {name: kind for name, hint in _annotations(cls).items()
                          if name != "return" and (kind := _number_kind(hint)) is not None}
    return _DECLARED[cls]


def as_declared(value: Any, kind: NumberKind) -> Any:
    """``value`` with its numbers (inside lists, tuples and arrays too) written as ``kind`` says.

    A float field stores a float and an int field an int, so that equal values give one key:
    ``1`` and ``1.0``, ``0.0`` and ``-0.0``, ``100`` and ``100.0`` where an int is declared. A
    number an int field holds that is not a whole number is kept as it is (the class's own
    check refuses it).
    """
    if kind is None or value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.ndarray):
        return as_declared(value.tolist(), kind)
    if isinstance(value, list | tuple):
        return [as_declared(v, kind) for v in value]
    if isinstance(value, int | float | np.integer | np.floating):
        if kind == "float":
            return float(value) + 0.0  # + 0.0 turns -0.0 into 0.0
        if float(value).is_integer():
            return int(value)
    return value


def to_dict(value: Any, exact: bool = True) -> Any:
    """``value`` as canonical JSON data: numbers, strings, lists and dicts.

    A dataclass (an option object, a task) becomes ``{"type": ..., field: value, ...}`` with
    every constructor field; a value with a ``definition()`` method becomes ``{"type": ...,
    **definition()}``; arrays and tuples become lists; a function becomes its
    :func:`function_name`. A field's numbers are written as its declared type says
    (:func:`declared_numbers`, :func:`as_declared`): equal values give equal data.

    Parameters
    ----------
    value
        What to write.
    exact
        Refuse what cannot be written exactly (a lambda, a task that is neither a dataclass
        nor defines ``definition()``, a NaN). With ``exact=False`` such a value is written as
        ``{"type": "unnamed", "repr": repr(value)}``, which a record may keep but a key may not.

    Raises
    ------
    UnnamedError
        With ``exact``, a value that cannot be written exactly.
    """
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        if math.isnan(value) and exact:
            raise UnnamedError("a definition cannot hold NaN")
        return float(value)
    if isinstance(value, np.ndarray):
        return to_dict(value.tolist(), exact)
    if isinstance(value, list | tuple):
        return [to_dict(v, exact) for v in value]
    if isinstance(value, Mapping):
        return {str(k): to_dict(v, exact) for k, v in sorted(value.items())}
    try:
        if not isinstance(value, type) and declares(type(value), Definition, "definition"):
            fields = value.definition()
        elif dataclasses.is_dataclass(value) and not isinstance(value, type):
            fields = {f.name: getattr(value, f.name) for f in dataclasses.fields(value) if f.init}
        elif callable(value):
            return function_name(value)
        else:
            raise UnnamedError(f"{value!r} is neither a dataclass nor defines definition(): a stored run "
                               f"cannot name it")
        kinds = declared_numbers(type(value))
        return {"type": _type_name(type(value)),
                **{k: to_dict(as_declared(v, kinds.get(k)), exact) for k, v in fields.items()}}
    except UnnamedError:
        if exact:
            raise
        return {"type": "unnamed", "repr": repr(value)}


def from_dict(data: Any) -> Any:
    """The value :func:`to_dict` wrote: ``from_dict(to_dict(x)) == x``.

    Lists come back as tuples inside option objects and tasks (their fields are tuples or
    scalars); a task's class rebuilds it from its fields, so a class may turn lists back into
    arrays itself.
    """
    if isinstance(data, list):
        return [from_dict(v) for v in data]
    if not isinstance(data, dict):
        return data
    if "type" not in data:
        return {k: from_dict(v) for k, v in data.items()}
    if data["type"] == "unnamed":
        raise UnnamedError(f"this definition was written without an exact task ({data.get('repr')}): it "
                           f"cannot be built again")
    cls = _type_of(data["type"])
    kwargs = {k: _field_value(v) for k, v in data.items() if k != "type"}
    if declares(cls, FromDefinition, "from_definition"):
        return cast(type[FromDefinition], cls).from_definition(**kwargs)  # declared: the class inherits it
    return cls(**kwargs)


def _field_value(data: Any) -> Any:
    value = from_dict(data)
    return tuple(value) if isinstance(value, list) else value


def run_definition(task: Any, method: Adaptive | Vanilla, theta0: Any, sigma: float, budget: int,
                   stop_on_divergence: bool, warm_start: str | None = None, exact: bool = True) -> dict[str, Any]:
    """A learning run's whole definition: what a record's ``config`` holds and a run key hashes.

    ``{"task", "method", "theta0", "sigma", "budget", "stop_on_divergence", "warm_start"}``;
    ``warm_start`` is the key of the run whose final parameters start this one (its
    ``theta0`` is then None: the start comes from that run).
    """
    return {"task": to_dict(task, exact), "method": to_dict(method, exact),
            "theta0": None if warm_start is not None else to_dict(as_declared(np.ravel(theta0), "float"), exact),
            "sigma": to_dict(as_declared(sigma, "float"), exact), "budget": int(budget),
            "stop_on_divergence": bool(stop_on_divergence),
            "warm_start": warm_start}


__all__ = ["NumberKind", "OPTION_TYPES", "TASK_TYPES", "UnnamedError", "as_declared", "declared_numbers", "from_dict",
           "function_name", "import_name", "run_definition", "to_dict"]
