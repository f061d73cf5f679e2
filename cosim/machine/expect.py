"""What a machine file checks without a ``[[check]]`` table: its job, its axes' travel, and what it never did.

**The job.** A controller that reports its job (``controller.job``, :mod:`cosim.job`) gets the check
:class:`~cosim.checks.JobCompleted` and the figure ``job_s`` by default: the run is a PASS only if
every program reached its end, without a limit, emergency or error stop. ``[job]`` changes that::

    [job]
    check = false                 # a program that loops for ever: the job is not checked (a note says so)

    [job]                         # or: the machine demonstrates a stop (HAZARD SHOWN when it happens)
    hazard = "the X axis runs into its positive limit switch"
    stop = "limit"                # optional: the stop that shows it (error, limit, emergency, aborted)

**The travel.** ``[travel]`` gives each axis its travel (soft limits) as ``[low, high]``; a
:class:`~cosim.checks.Travel` check per axis reads its position from the trace::

    [travel]
    x = [0, 300]                  # PoKeys axis x: mm (the host's units) with steps_per_unit, else pulses
    "3" = [0, 300]                # Trio axis 3: user units (DPOS, scaled by UNITS)
    "1" = [-50000, 50000]         # PMAC motor 1: counts (the commanded position)

**What it never did.** After the run, a laser coupled to the controller that never fired (its
drive enable, gate and mark never on together) and a coupled axis that never moved (no step, no
change of its commanded position) each get a warning in the run's notes.

**Signals.** Every signal a ``[[check]]`` or ``[[figure]]`` names is looked up when the machine is
built (:func:`signal_problem`), so ``check-machine`` finds a misspelt one before anything runs.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from cosim.checks import Travel
from cosim.checks.job import ENDS
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.scenario import Run
from cosim.trace import Trace

STOPS = tuple(end for end in ENDS if end != "done")


def declare_job(run: Run, controller: Any, table: Table) -> None:
    """The job check and ``job_s`` of a machine (``[job]`` as in the module docstring)."""
    table.only(["check", "hazard", "stop"], what="the keys of [job]")
    check = table.flag("check", True)
    hazard = table.text("hazard", None)
    stop = table.text("stop", None, choices=STOPS)
    job = getattr(controller, "job", None)
    where = f"{table.file}: job"
    if not check:
        if hazard is not None or stop is not None:
            raise ConfigurationError(f"{table.file}: job: check = false checks nothing: hazard and stop need "
                                     "the job check")
        run.note("job.check = false: whether the job completed is not checked")
        return
    if job is None:
        if hazard is not None or stop is not None:
            raise ConfigurationError(f"{table.file}: job: this {type(controller).__name__} does not report its "
                                     "job (no <device>.job signal), so a job hazard cannot be shown")
        return  # every family reports its job (cosim.job); a controller written before it does not
    if stop is not None and hazard is None:
        raise ConfigurationError(f"{table.file}: job.stop = {stop!r}: a stop is a hazard the machine shows: say "
                                 "which with job.hazard = \"...\"")
    with table.at():
        run.job(controller, shows=hazard, ends=stop, where=where)


def declare_travel(run: Run, family: str, controller: Any, table: Table, document: Table) -> None:
    """One :class:`~cosim.checks.Travel` check per axis of ``[travel]``."""
    for axis in list(table.data):
        value = table.raw(axis)
        with table.at(axis):
            if (not isinstance(value, list) or len(value) != 2
                    or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)):
                raise ConfigurationError.out_of_range("value", value, "[low, high], two numbers")
            signal, scale, unit = _position(family, controller, str(axis), document)
            table.describe(axis, unit=unit, allowed="[low, high]")
            check = Travel(signal, value[0], value[1], scale=scale, unit=unit,
                           name=f"axis {axis} within its travel {value[0]}..{value[1]} {unit}".rstrip())
        run.check(check, where=f"{table.file}: {table.key(axis)}")


def _position(family: str, controller: Any, axis: str, document: Table) -> tuple[str, float, str]:
    """The position signal of ``axis``, its units per travel unit, and the travel unit."""
    if family == "pokeys":
        names = list(controller.axis_names)
        if axis not in names:
            raise ConfigurationError.out_of_range("axis", axis, ", ".join(names))
        tuning = document.data.get("controller", {}).get("axis", {}).get(axis, {})
        steps = tuning.get("steps_per_unit") if isinstance(tuning, dict) else None
        units = document.data.get("host", {}).get("units", "mm")
        signal = f"{controller.name}.{axis}.position"
        if isinstance(steps, int | float) and not isinstance(steps, bool) and steps > 0:
            return signal, steps, str(units)
        return signal, 1, "pulses"
    if family == "trio":
        if not axis.isdigit() or int(axis) not in controller.axes:
            raise ConfigurationError.out_of_range("axis", axis, f"0..{len(controller.axes) - 1}")
        return f"{controller.device}.axis{int(axis)}.dpos", 1, "units"
    if family == "pmac":
        if not axis.isdigit() or int(axis) not in controller.motors:
            known = ", ".join(str(n) for n in sorted(controller.motors)) or "none defined"
            raise ConfigurationError.out_of_range("motor", axis, known)
        return f"pmac.motor{int(axis)}.cmd_pos", 1, "counts"
    raise ConfigurationError(f"[travel] is not known for a {family} controller")


def declare_warnings(run: Run, couplings: Sequence[tuple[str, str, Any]]) -> None:
    """After the run, a note for each coupled laser that never fired and each coupled axis that never moved.

    ``couplings``: ``(kind, plant name, controller port)`` of every coupling of the machine.
    """
    trace = run.sim.trace

    def warn() -> None:
        for kind, plant, port in couplings:
            if kind == "laser" and not _fired(trace, port):
                run.note(f"warning: the laser of plant {plant} never fired: {port.enable.name}, {port.gate.name} and "
                         f"{port.mark_clocks.name} were never on together (no PWM output reached it)")
            elif kind == "stepper" and not _moved(trace, port.step.name, pulses=True):
                run.note(f"warning: the axis of plant {plant} never moved: {port.step.name} made no step pulse")
            elif kind == "servo":
                signal = _servo_position(port)
                if signal is not None and signal in trace.info and not _moved(trace, signal, pulses=False):
                    run.note(f"warning: the axis of plant {plant} never moved: {signal} never changed")

    run.afterwards(warn)


def _fired(trace: Trace, port: Any) -> bool:
    names = [port.enable.name, port.gate.name, port.mark_clocks.name]
    if not all(name in trace.info for name in names):
        return True  # cannot tell: no warning
    times = np.sort(np.concatenate([trace.edges(name)[0] for name in names]))
    times = times[np.concatenate(([True], times[1:] != times[:-1]))] if times.size else times  # np.unique's values
    # (np.unique imports numpy.ma, ~25 ms of start-up)
    if not times.size:
        return False
    on = np.ones(times.size, dtype=bool)
    for name in names:
        values = trace.values_at(name, times)
        on &= np.nan_to_num(values) > 0
    return bool(on.any())


def _moved(trace: Trace, name: str, *, pulses: bool) -> bool:
    if pulses:
        return any(t.size for t, _ in trace.pulse_chunks(name))
    _t, values = trace.edges(name)
    return bool(values.size) and bool(np.nanmax(values) != np.nanmin(values))


def _servo_position(port: Any) -> str | None:
    motor = getattr(port, "motor", None)
    number = getattr(motor, "number", None)
    return None if number is None else f"pmac.motor{number}.cmd_pos"


#: An axis, motor or channel part of a signal name: a kind and its number (``axis3``, ``motor1``, ``cs2``).
_NUMBERED = re.compile(r"([a-z_]+?)(\d+)")


def signal_problem(trace: Trace, name: object, plants: Mapping[str, Any]) -> str | None:
    """Why ``name`` is not a signal a check or figure can read after the run (None: it is, or may be).

    A name declared by the machine is fine; so is one the controller may still declare while it runs
    (the same signal of another numbered axis, motor or channel of a kind it has: ``trio.axis1.step``
    beside ``trio.axis3.step``; not ``pokeys.q.step`` beside ``pokeys.x.step``, whose axes are all
    declared when it is built). A plant output that is not recorded says how to record it; anything
    else gets the close names.
    """
    if not isinstance(name, str):
        return f"a signal name is text, not {name!r}"
    if name in trace.info or name in trace.later:
        return None
    parts = name.split(".")
    numbered = _NUMBERED.fullmatch(parts[1]) if len(parts) == 3 else None
    for known in trace.info:
        other = known.split(".")
        if (numbered is not None and len(other) == 3 and other[0] == parts[0] and other[2] == parts[2]
                and (sibling := _NUMBERED.fullmatch(other[1])) is not None and sibling[1] == numbered[1]):
            return None  # the same signal of another numbered axis or channel: may be declared during the run
    plant_name, _, variable = name.partition(".")
    plant = plants.get(plant_name)
    if plant is not None and variable in plant.variable_names():
        return (f"{name} is an output of plant {plant_name} that is not recorded: record it with "
                f"record = {{ variables = [\"{variable}\"], period = \"1 ms\" }} in [plant.{plant_name}]")
    close = difflib.get_close_matches(name, list(trace.info), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return f"no signal named {name!r} in this machine{hint}"
