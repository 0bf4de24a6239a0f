"""One key per equal definition: each field's numbers are written as its declared type says.

Over every definition field of every option object, task and of :class:`RunConfig` itself
(not ``name``, not ``warm_start``, which are not part of the definition), both directions:
equal values give equal keys (``1`` and ``1.0`` where a float is declared, ``100.0`` and
``100`` where an int is, ``-0.0`` and ``0.0``), and a changed value gives another key. Before
the numbers were written by their declared type, ``sigma=1`` and ``sigma=1.0`` gave two keys
(the first assertion of :func:`test_equal_numbers_give_one_key` failed).
"""

from __future__ import annotations

import dataclasses
import typing
from typing import Any, Literal

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from safepg.definition import _annotations, as_declared, declared_numbers, to_dict
from safepg.envs.cartpole import CartPole
from safepg.envs.lqg import LQG
from safepg.envs.pendulum import Pendulum
from safepg.options import Adaptive, Batches, Departures, ErrorModel, FixedStep, Gradient, SafeStep, Target, Vanilla
from safepg.runner import RunConfig

BASE = RunConfig("x", task=LQG(), method=Adaptive(), theta0=(-0.5,), sigma=1.0, budget=20_000)

#: A value of each class in the definition, and how it enters a run's definition.
PLACES: dict[type, tuple[Any, Any]] = {
    Gradient: (Gradient(), lambda o: dataclasses.replace(BASE, method=Adaptive(gradient=o))),
    ErrorModel: (ErrorModel(), lambda o: dataclasses.replace(BASE, method=Adaptive(error=o))),
    Batches: (Batches(), lambda o: dataclasses.replace(BASE, method=Adaptive(batches=o))),
    Departures: (Departures(), lambda o: dataclasses.replace(BASE, method=Adaptive(departures=o))),
    FixedStep: (FixedStep(1e-3), lambda o: dataclasses.replace(BASE, method=Vanilla(100, o))),
    SafeStep: (SafeStep(), lambda o: dataclasses.replace(BASE, method=Vanilla(100, o))),
    Target: (Target(1.0), lambda o: dataclasses.replace(BASE, method=Vanilla(100, target=o))),
    Vanilla: (Vanilla(100), lambda o: dataclasses.replace(BASE, method=o)),
    LQG: (LQG(), lambda o: dataclasses.replace(BASE, task=o)),
    CartPole: (CartPole(), lambda o: dataclasses.replace(BASE, task=o, theta0=(0.0,) * 4)),
    Pendulum: (Pendulum(), lambda o: dataclasses.replace(BASE, task=o, theta0=(0.0,) * 3)),
    RunConfig: (BASE, lambda o: o),
}
#: Fields that are not the definition (the name labels the run; a warm start enters by its key).
NOT_DEFINITION = {"name", "warm_start", "warm_start_key"}
#: Fields holding option objects: their own fields are tested through their classes.
NESTED = {"method", "task", "gradient", "error", "batches", "departures", "step", "target"}

FIELDS = [(cls, f.name) for cls in PLACES for f in dataclasses.fields(cls)
          if f.init and f.name not in NOT_DEFINITION | NESTED]


def key(obj: Any) -> str | None:
    """The key of a run defined with ``obj``, or None if ``obj``'s class refuses it."""
    return PLACES[type(obj)][1](obj).key()


def build(cls: type, name: str, value: Any) -> Any:
    """The base value with ``name`` set to ``value``, or None if the class refuses it."""
    try:
        return dataclasses.replace(PLACES[cls][0], **{name: value})
    except (ValueError, TypeError):
        return None


def choices(cls: type, name: str) -> list[Any]:
    """The values a field's Literal (or bool) declares."""
    hint = _annotations(cls).get(name)
    out: list[Any] = []

    def walk(h: Any) -> None:
        if h is bool:
            out.extend([False, True])
        elif typing.get_origin(h) is Literal:
            out.extend(typing.get_args(h))
        else:
            for arg in typing.get_args(h):
                walk(arg)

    walk(hint)
    return out


def numbers(cls: type, name: str) -> st.SearchStrategy[Any]:
    """Numbers (or tuples of them, shaped like the base value's) for a field that declares them."""
    scalar = st.one_of(st.integers(0, 2000), st.floats(-5.0, 5.0, allow_nan=False), st.floats(0.001, 0.999),
                       st.sampled_from([0.0, -0.0, 1.0, 2.0, 100.0, 1e-3, 1e5]))
    if (cls, name) == (LQG, "dim"):  # a matrix of dim x dim: keep it small
        return st.integers(0, 6)
    base = getattr(PLACES[cls][0], name)
    if (cls, name) == (CartPole, "feature_scale"):  # None by default: four numbers when given
        base = (1.0,) * 4
    if isinstance(base, tuple):
        return st.tuples(*[st.one_of(st.floats(0.01, 10.0), st.sampled_from([1.0, 2.0, -0.0, 0.0]))] * len(base))
    return scalar


NUMBER_FIELDS = [(c, n) for c, n in FIELDS if n in declared_numbers(c) or n in ("theta0", "sigma", "budget")]
CHOICE_FIELDS = [(c, n) for c, n in FIELDS if choices(c, n)]


def test_every_definition_field_is_tested():
    """A field that neither declares numbers nor choices would escape both properties."""
    untested = [f"{c.__name__}.{n}" for c, n in FIELDS if (c, n) not in NUMBER_FIELDS + CHOICE_FIELDS
                and getattr(PLACES[c][0], n) is not None and n not in ("integrator", "horizon_term")]
    assert untested == []
    assert len(NUMBER_FIELDS) > 30 and len(CHOICE_FIELDS) > 10


def _twin(value: Any) -> Any:
    """An equal value of another number type: -0.0 for 0 and 0.0, the other Python type for a whole
    number, NumPy's float64 for any other float."""
    if isinstance(value, tuple):
        return tuple(_twin(v) for v in value)
    if value == 0:
        return -0.0 if not (isinstance(value, float) and np.signbit(value)) else 0
    if float(value).is_integer():
        return float(value) if isinstance(value, int) else int(value)
    return np.float64(value)


@pytest.mark.parametrize(("cls", "name"), NUMBER_FIELDS, ids=[f"{c.__name__}.{n}" for c, n in NUMBER_FIELDS])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(data=st.data())
def test_equal_numbers_give_one_key(cls, name, data):
    value = data.draw(numbers(cls, name))
    twin = _twin(value)
    a, b = build(cls, name, value), build(cls, name, twin)
    assume(a is not None and b is not None)
    assert a == b
    assert key(a) == key(b), f"{cls.__name__}.{name}: {value!r} and {twin!r}"


@pytest.mark.parametrize(("cls", "name"), NUMBER_FIELDS, ids=[f"{c.__name__}.{n}" for c, n in NUMBER_FIELDS])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(data=st.data())
def test_a_changed_number_gives_another_key(cls, name, data):
    strategy = numbers(cls, name)
    first, second = data.draw(strategy), data.draw(strategy)
    assume(np.any(np.asarray(first, dtype=float) != np.asarray(second, dtype=float)))
    a, b = build(cls, name, first), build(cls, name, second)
    assume(a is not None and b is not None)
    assert key(a) != key(b), f"{cls.__name__}.{name}: {first!r} and {second!r}"


@pytest.mark.parametrize(("cls", "name"), CHOICE_FIELDS, ids=[f"{c.__name__}.{n}" for c, n in CHOICE_FIELDS])
def test_every_choice_gives_its_own_key(cls, name):
    built = {repr(v): build(cls, name, v) for v in choices(cls, name)}
    keys = {v: key(o) for v, o in built.items() if o is not None}
    assert len(keys) >= 2
    assert len(set(keys.values())) == len(keys), keys


def test_the_issue_s_examples():
    m = Adaptive(Gradient(), ErrorModel("chebyshev"), Batches(n_min=100, n_max=1000))
    a = RunConfig("x", task=LQG(), theta0=(-0.5,), sigma=1, budget=20000, method=m)
    assert a.key() == dataclasses.replace(a, sigma=1.0).key()
    assert a.key() == dataclasses.replace(a, method=Adaptive(batches=Batches(n_min=100.0, n_max=1000))).key() \
        or Adaptive(batches=Batches(n_min=100.0, n_max=1000)) != m
    assert a.key() == dataclasses.replace(a, method=dataclasses.replace(m, batches=Batches(100.0, 1000.0))).key()
    assert RunConfig("x", task=LQG(A=-0.0)).key() == RunConfig("x", task=LQG(A=0.0)).key()
    assert RunConfig("x", theta0=(-0.0,)).key() == RunConfig("x", theta0=(0.0,)).key()


def test_declared_types_are_written():
    assert to_dict(Batches(np.int64(100), 1000.0)) == {"type": "Batches", "n_min": 100, "n_max": 1000, "first": None}
    assert isinstance(to_dict(FixedStep(1))["alpha"], float)
    assert as_declared([[1, -0.0], (2, 3.5)], "float") == [[1.0, 0.0], [2.0, 3.5]]
    assert as_declared(2.5, "int") == 2.5  # not a whole number: left for the class to refuse
    assert declared_numbers(Batches) == {"n_min": "int", "n_max": "int", "first": "int"}
