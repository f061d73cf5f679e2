"""Checks and figures declared in a machine file (``[[check]]`` and ``[[figure]]`` tables).

A ``[[check]]`` names a check type of :mod:`cosim.checks` and its parameters by their Python
names; times are written with a unit and become ticks of the run's resolution::

    [[check]]
    type = "PulsesPerWindow"
    signal = "pokeys.x.step"
    max_count = 25
    window = "1 ms"
    name = "x: at most 25 pulses per 1 ms slot"

``Duration`` takes its start and end as inline tables: ``{ signal = "laser.gate", value = 1 }``
(a change of a signal, optionally to a value, ``which = "first"`` ...) or ``{ pulse = "x.step" }``.
``EdgeAtPosition.expected`` is a list of ``[count, state]`` pairs.

A ``[[figure]]`` is a key figure of the run: a plant output read at the end, or one recorded
signal reduced to a number::

    [[figure]]
    name = "energy_J"
    output = "laser.energy"   # <plant>.<output>, read when the run ends
    unit = "J"

    [[figure]]
    name = "peak_level"
    signal = "pokeys.buffer_level"
    reduce = "max"            # last, max, min, changes (bit/int/real), pulses (net signed count of a pulse train)
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from cosim import checks as checks_module
from cosim.checks import Check, EdgeRef, PulseRef
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.master import PlantLike
from cosim.trace import Trace

#: Check types by name.
CHECKS: dict[str, type[Check]] = {name: obj for name in checks_module.__all__
                                  if isinstance(obj := getattr(checks_module, name), type)
                                  and issubclass(obj, Check) and obj is not Check}

#: Parameters of each check that are times [ticks] (written with a unit in a machine file).
TIME_FIELDS: dict[str, tuple[str, ...]] = {
    "DirectionSetup": ("setup", "active_delay"),
    "Duration": ("min", "max", "equals", "tol"),
    "EdgeAtPosition": ("tol_time", "times"),
    "IntervalsBelow": ("max_duration", "start", "until"),
    "IntervalsAbove": ("max_duration", "start", "until"),
    "NoUnderrun": ("start", "until"),
    "ValueAt": ("t",),
    "MinPulseSpacing": ("min_spacing",),
    "MaxPulseRate": ("window",),
    "PulsesPerWindow": ("window", "start"),
}

REDUCERS = ("last", "max", "min", "changes", "pulses")


def _optional(annotation: Any) -> bool:
    return type(None) in typing.get_args(annotation)


def check_from_table(table: Table) -> Check:
    """The check a ``[[check]]`` table declares (ConfigurationError naming the file and key)."""
    kind = table.text("type", choices=sorted(CHECKS))
    cls = CHECKS[kind]
    hints = typing.get_type_hints(cls)
    times = TIME_FIELDS.get(kind, ())
    parameters = [f.name for f in dataclasses.fields(cls)]
    table.only(["type", *parameters, "hazard"], what=f"the keys of a {kind} check")
    kwargs: dict[str, Any] = {}
    for field in dataclasses.fields(cls):
        if field.name not in table.data:
            if field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
                if _optional(hints.get(field.name)):
                    kwargs[field.name] = None
                    continue
                raise ConfigurationError(f"{table.file}: {table.key(field.name)} is missing (required by {kind})")
            table.raw(field.name, None)  # mark as a known key of this table
            continue
        value = table.raw(field.name)
        table.describe(field.name, unit="time" if field.name in times else "",
                       allowed="a time with a unit" if field.name in times else _annotation(hints, field.name))
        with table.at(field.name):
            kwargs[field.name] = _convert(value, field.name, kind, times, table)
    with table.at():
        return cls(**kwargs)


def _annotation(hints: Mapping[str, Any], name: str) -> str:
    """A check parameter's type as a user reads it (``int | None`` -> ``int (optional)``)."""
    hint = hints.get(name)
    if hint is None:
        return ""
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    def named(kind: Any) -> str:
        if typing.get_args(kind):
            return str(kind).replace("typing.", "").replace("collections.abc.", "")
        return str(getattr(kind, "__name__", kind))

    text = " or ".join(named(a) for a in args) if args and typing.get_origin(hint) in (typing.Union, types.UnionType) \
        else named(hint)
    return text + (" (optional)" if _optional(hint) else "")


def _convert(value: Any, name: str, kind: str, times: tuple[str, ...], table: Table) -> Any:
    if name in times:
        return [table.ticks(v) for v in value] if isinstance(value, list) else table.ticks(value)
    if kind == "Duration" and name in ("start", "end"):
        return _ref(value)
    if kind == "EdgeAtPosition" and name == "expected":
        if not isinstance(value, list) or not all(isinstance(p, list) and len(p) == 2 for p in value):
            raise ConfigurationError.out_of_range("expected", value, "a list of [count, state] pairs")
        return [tuple(p) for p in value]
    return value


def _ref(value: Any) -> EdgeRef | PulseRef:
    if not isinstance(value, dict):
        raise ConfigurationError.out_of_range("value", value, "an inline table { signal = ..., value = ... } "
                                              "or { pulse = ... }")
    if "pulse" in value:
        extra = set(value) - {"pulse", "which"}
        if extra:
            raise ConfigurationError.out_of_range("keys of a pulse reference", sorted(extra), "pulse, which")
        return PulseRef(value["pulse"], **({"which": value["which"]} if "which" in value else {}))
    extra = set(value) - {"signal", "value", "which"}
    if extra or "signal" not in value:
        raise ConfigurationError.out_of_range("keys of an edge reference", sorted(value), "signal, value, which")
    return EdgeRef(**value)


def figure_from_table(table: Table, plants: Mapping[str, PlantLike]) -> tuple[str, Callable[[Trace], float], str]:
    """``(name, value(trace), unit)`` of a ``[[figure]]`` table (``plants``: the machine's, by name)."""
    table.only(["name", "unit", "output", "signal", "reduce"], what="the keys of a figure")
    name = table.text("name")
    unit = table.text("unit", "")
    output = table.text("output", None)
    signal = table.text("signal", None)
    reduce = table.text("reduce", "last", choices=REDUCERS)
    if (output is None) == (signal is None):
        raise ConfigurationError(f"{table.file}: {table.path}: give either output (<plant>.<output>, read when "
                                 "the run ends) or signal (a recorded signal, with reduce)")
    if output is not None:
        plant_name, _, variable = output.partition(".")
        if plant_name not in plants:
            raise table.error("output", output, f"<plant>.<output> of a plant of the machine "
                                                f"({', '.join(plants) or 'none'})")
        plant = plants[plant_name]
        with table.at("output"):
            if variable not in plant.variable_names():
                raise ConfigurationError.out_of_range("output", variable, ", ".join(plant.variable_names()))
        return name, lambda _trace: float(plant.read(variable)), unit
    assert signal is not None

    def value(trace: Trace) -> float:
        if reduce == "pulses":
            _t, direction = trace.pulses(signal)
            return float(np.where(direction == 1, 1, -1).sum())
        _t, v = trace.edges(signal)
        if reduce == "changes":
            return float(np.count_nonzero(v[1:] != v[:-1]))
        if not v.size:
            return float("nan")
        return float({"last": v[-1], "max": v.max(), "min": v.min()}[reduce])

    return name, value, unit
