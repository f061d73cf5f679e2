"""The ``[export]`` table of a machine file: the inputs and outputs the machine offers as an FMU.

::

    [export]
    plants = "outside"            # inside (default): the machine's plants run in the FMU
    step = "1 ms"                 # the default communication step (DefaultExperiment)
    outputs = [
        "trio.axis3.step",        # a recorded signal by its trace name (a step output: its pulse count)
        "trio.axis3.gate",        # bits are event-bearing: an importer sees each edge at its instant
        { signal = "trio.axis3.fifo_level", name = "fifo", event = true },
        { signal = "pokeys.buffer_level", below = 1, name = "buffer_empty" },   # a comparator: a Boolean
        "laser.energy",           # PLANT.VARIABLE of a plant inside, read at every communication point
    ]
    inputs = ["pokeys.x.limit_pos", { signal = "pokeys.emergency", name = "estop", start = 0 }]

:func:`read_spec` reads the table before the machine is built (it decides whether the plants are
built); :func:`resolve_ports` checks every name against the built machine and fixes each port's FMI
type. Every refusal names the file, the key, the value and what is allowed.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.signals import Signal
from cosim.trace import Trace

#: FMI variable names (structured naming: identifiers joined by dots).
_VARIABLE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
#: FMI types of the trace kinds; a pulse train is offered as its signed pulse count.
FMI_TYPE = {"bit": "Boolean", "int": "Int32", "real": "Float64", "pulse": "Int32"}
PLANTS = ("inside", "outside")
INT32 = (-(2**31), 2**31 - 1)


@dataclass(frozen=True)
class Port:
    """One FMU variable of an exported machine.

    Parameters
    ----------
    name : str
        The FMU variable's name (the signal's name unless the machine file gives one).
    source : str
        The trace signal, or ``PLANT.VARIABLE`` for a plant's variable.
    kind : {'bit', 'int', 'real', 'pulse', 'plant'}
        Where the value comes from: a trace signal of that kind, or a plant read.
    fmi_type : {'Boolean', 'Int32', 'Float64'}
    event : bool
        Outputs: a change is an event (FMI 3.0 early return and event mode at its instant).
    below, above : float, optional
        Outputs: a comparator on the source (the output is True while the value is below / above).
    start : float
        Inputs: the value before the importer sets one; outputs: the value at t = 0.
    unit, description : str
    """

    name: str
    source: str
    kind: str
    fmi_type: str
    event: bool = False
    below: float | None = None
    above: float | None = None
    start: float = 0.0
    unit: str = ""
    description: str = ""


@dataclass(frozen=True)
class ExportSpec:
    """What the ``[export]`` table asks for (names not yet checked against the machine).

    Parameters
    ----------
    plants : {'inside', 'outside'}
    step : str or int
        Default communication step (a time with a unit, or ticks).
    outputs, inputs : tuple of Table
        One table per entry (a bare string ``"x"`` is read as ``{ signal = "x" }``).
    """

    plants: str
    step: str | int
    outputs: tuple[Table, ...]
    inputs: tuple[Table, ...]


def read_spec(document: dict[str, Any], *, file: Path) -> ExportSpec:
    """Read the ``[export]`` table of a machine document (ConfigurationError if it is missing or wrong)."""
    if not isinstance(document.get("export"), dict):
        raise ConfigurationError(f"{file}: export: the machine file has no [export] table; it names the FMU's "
                                 "outputs and inputs, e.g. [export] outputs = [\"trio.axis3.gate\"] "
                                 "(see docs/export.md)")
    table = Table(document["export"], file=file, path="export")
    plants = table.text("plants", "inside", choices=PLANTS)
    step = table.raw("step", "1 ms")
    if isinstance(step, bool) or not isinstance(step, str | int):
        raise table.error("step", step, "a time with a unit, e.g. \"1 ms\"")
    raw_outputs, raw_inputs = table.raw("outputs", None), table.raw("inputs", [])
    table.finish()  # a misspelt key first: "outptus" is better said as such than as "outputs is missing"
    outputs = _entries(table, "outputs", raw_outputs, required=True)
    inputs = _entries(table, "inputs", raw_inputs, required=False)
    return ExportSpec(plants=plants, step=step, outputs=outputs, inputs=inputs)


def _entries(table: Table, key: str, raw: Any, *, required: bool) -> tuple[Table, ...]:
    if raw is None or (required and raw == []):
        raise ConfigurationError(f"{table.file}: export.{key} is missing (required: a list of signal names, "
                                 "e.g. [\"trio.axis3.gate\", \"trio.axis3.step\"])")
    if not isinstance(raw, list):
        raise table.error(key, raw, "a list of signal names or tables {signal = \"...\", name = \"...\"}")
    out = []
    for i, entry in enumerate(raw):
        data = {"signal": entry} if isinstance(entry, str) else entry
        if not isinstance(data, dict):
            raise ConfigurationError.out_of_range(f"export.{key}[{i}]", entry,
                                                  "a signal name or a table {signal = \"...\", ...}",
                                                  where=str(table.file))
        out.append(Table(data, file=table.file, path=f"export.{key}[{i}]", timebase=table.timebase))
    return tuple(out)


def resolve_ports(spec: ExportSpec, *, trace: Trace, inputs: Sequence[Signal], plants: Sequence[Any],
                  stimulated: Sequence[str] = ()) -> tuple[list[Port], list[Port]]:
    """Check every exported name against the built machine; the output and input ports.

    Parameters
    ----------
    spec : ExportSpec
    trace : Trace
        The built machine's trace (its declared signals are the outputs one may export).
    inputs : sequence of Signal
        The controller's inputs (``controller.inputs()``): the signals one may export as inputs.
    plants : sequence of PlantLike
        The plants inside (empty when they are outside).
    stimulated : sequence of str
        Signals a ``[[stimulus]]`` drives (they cannot be FMU inputs too).
    """
    outputs = [_output(t, trace, plants) for t in spec.outputs]
    by_name = {s.name: s for s in inputs}
    ports_in = []
    for table in spec.inputs:
        source = table.text("signal")
        if source not in by_name:
            close = difflib.get_close_matches(source, list(by_name), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigurationError(f"{table.file}: {table.key('signal')}: {source!r} is not an input of this "
                                     f"controller{hint} (its inputs: {', '.join(by_name) or 'none'})")
        if source in stimulated:
            raise ConfigurationError(f"{table.file}: {table.key('signal')}: {source} is driven by a [[stimulus]] "
                                     "of the machine file; an FMU input is driven by the importer: drop one of them")
        signal = by_name[source]
        info = trace.info[source]
        start = table.raw("start", signal.value)
        with table.at("start"):
            start = _start(start, info.kind)
        ports_in.append(Port(name=_name(table, source), source=source, kind=info.kind, fmi_type=FMI_TYPE[info.kind],
                             start=start, unit=info.unit, description=info.description))
        table.finish()
    _unique([*outputs, *ports_in], spec)
    return outputs, ports_in


def _output(table: Table, trace: Trace, plants: Sequence[Any]) -> Port:
    source = table.text("signal")
    name = _name(table, source)
    below = table.raw("below", None)
    above = table.raw("above", None)
    event_given = table.has("event")
    event = table.flag("event", False)
    if source in trace.info:
        info = trace.info[source]
        kind, fmi_type, unit, description = info.kind, FMI_TYPE[info.kind], info.unit, info.description
        event = event if event_given else kind == "bit"
        if kind == "pulse" and event:
            raise table.error("event", True, "false for a step output (it changes at every pulse)")
    else:
        plant, _, variable = source.partition(".")
        found = [p for p in plants if p.name == plant]
        if not found or variable not in found[0].variable_names():
            raise ConfigurationError(f"{table.file}: {table.key('signal')}: {source!r} is not a signal of this "
                                     f"machine{_hint(source, trace, plants)}")
        if event:
            raise table.error("event", True, "false for a plant variable (plants are read at communication points)")
        value = found[0].read(variable)
        kind = "plant"
        fmi_type = "Boolean" if isinstance(value, bool) else "Int32" if isinstance(value, int) else "Float64"
        unit, description = "", f"{plant} {variable} (read at every communication point)"
    if below is not None or above is not None:
        for key, bound in (("below", below), ("above", above)):
            if bound is not None and (isinstance(bound, bool) or not isinstance(bound, int | float)):
                raise table.error(key, bound, "a number")
        if kind not in ("int", "real"):
            raise table.error("below" if below is not None else "above", below if below is not None else above,
                              "only on an int or real signal")
        fmi_type = "Boolean"
        event = event if event_given else True
        what = " and ".join(f"{k} {v}" for k, v in (("below", below), ("above", above)) if v is not None)
        description, unit = f"{source} {what}", ""
    table.finish()
    return Port(name=name, source=source, kind=kind, fmi_type=fmi_type, event=event,
                below=None if below is None else float(below), above=None if above is None else float(above),
                unit=unit, description=description)


def default_name(source: str) -> str:
    """The FMU variable name of a signal without ``name =``: the signal's, with a numbered part joined
    to the one before it by ``_`` (``trio.in.8`` -> ``trio.in_8``), since FMI names are identifiers."""
    return re.sub(r"\.(?=[0-9])", "_", source)


def _name(table: Table, source: str) -> str:
    name = table.text("name", default_name(source))
    if not _VARIABLE.match(name) or name == "time":
        raise table.error("name", name, "an FMU variable name: identifiers joined by dots, not 'time'")
    return name


def _start(value: Any, kind: str) -> float:
    if isinstance(value, bool) or kind == "bit":
        if value not in (0, 1, True, False):
            raise ConfigurationError.out_of_range("value", value, "0 or 1 (true or false)")
        return float(bool(value))
    if not isinstance(value, int | float):
        raise ConfigurationError.out_of_range("value", value, "a number")
    if kind == "int" and (value != int(value) or not INT32[0] <= value <= INT32[1]):
        raise ConfigurationError.out_of_range("value", value, f"an integer in {INT32[0]}..{INT32[1]}")
    return float(value)


def _hint(source: str, trace: Trace, plants: Sequence[Any]) -> str:
    known = list(trace.info) + [f"{p.name}.{v}" for p in plants for v in p.variable_names()]
    close = difflib.get_close_matches(source, known, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    signals = ", ".join(trace.info)
    plant_text = (" or PLANT.VARIABLE of a plant inside: " + ", ".join(p.name for p in plants)) if plants else ""
    return f"{hint} (outputs are recorded signals: {signals}{plant_text})"


def _unique(ports: list[Port], spec: ExportSpec) -> None:
    seen: set[str] = set()
    for port in ports:
        if port.name in seen:
            file = (spec.outputs or spec.inputs)[0].file
            raise ConfigurationError(f"{file}: export: two variables are named {port.name!r}; give one of them "
                                     "another name = \"...\"")
        seen.add(port.name)
