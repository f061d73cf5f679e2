"""The Python half of an exported FMU: what the C entry point (``fmu_src/export/``) calls.

The C layer loads Python, imports this module and calls :func:`instantiate` with the FMU's
resources folder; every later FMI call that needs the machine becomes one method call of the
returned :class:`Slave`, which answers with an FMI status (0 OK ... 4 fatal) and never raises:
errors go to the importer's log through the C function whose address it was given. Values travel
through memory both sides see (one double per value reference, kept here, read and written by
the C getters and setters without calling Python).

Time: the importer's float time is mapped to the machine's integer ticks here, at the boundary
only: ``tick = round((t - start) / resolution)``; the times it reports back are ``start + tick *
resolution``.
"""

from __future__ import annotations

import ctypes
import json
import traceback
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

from cosim.errors import CosimError

OK, WARNING, DISCARD, ERROR, FATAL = range(5)
#: The kind byte of a value reference (fmu_src/export/machine.h): type | causality.
KIND = {"Float64": 1, "Int32": 2, "Boolean": 3}
INPUT, OUTPUT = 0x10, 0x20
#: Slots of the step results (machine.h: SR_LAST_TIME, SR_EVENT, SR_EARLY, SR_TERMINATE).
LAST_TIME, EVENT, EARLY, TERMINATE = range(4)
RESOURCES = "cosim"  # the FMU's own folder inside resources/
LogFunction = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)


class Slave:
    """One FMU instance: the machine, its value table and the FMI call states it answers for.

    Parameters
    ----------
    resources : Path
        The FMU's ``resources`` folder.
    token : str
        The instantiation token (GUID) the importer read from the model description.
    fmi_version : {2, 3}
    event_mode_used, early_return_allowed : bool
        What the importer said at instantiation (FMI 3.0; False for FMI 2.0).
    log : callable
        ``log(status, category, message)``: to the importer's logger.
    logging_on : bool
        Debug logging (``logEvents`` messages).
    """

    def __init__(self, resources: Path, token: str, *, fmi_version: int, event_mode_used: bool,
                 early_return_allowed: bool, log: Callable[[int, str, str], None], logging_on: bool) -> None:
        self.resources = resources
        self.fmi_version = fmi_version
        self.event_mode_used = event_mode_used and fmi_version == 3
        self.early_return_allowed = early_return_allowed and fmi_version == 3
        self.log = log
        self.logging_on = logging_on
        self.description = json.loads((resources / RESOURCES / "machine.json").read_text())
        if token != self.description["token"]:
            raise CosimError(f"instantiation token {token!r} does not match this FMU's {self.description['token']!r} "
                             "(the model description and the resources come from different exports)")
        variables = self.description["variables"]
        self.n = 1 + len(variables)
        self.values = (ctypes.c_double * self.n)()
        self.kinds = (ctypes.c_ubyte * self.n)()
        self.step = (ctypes.c_double * 4)()
        self.kinds[0] = KIND["Float64"]  # time
        for vr, variable in enumerate(variables, start=1):
            self.kinds[vr] = KIND[variable["type"]] | (INPUT if variable["causality"] == "input" else OUTPUT)
        self.machine: Any = None
        self._build()

    # -- the machine ---------------------------------------------------------------------------------
    def _build(self) -> None:
        from cosim.fmu_export.machine import ExportedMachine

        if self.machine is not None:
            self.machine.close()
            self.machine = None
        folder = self.resources / RESOURCES
        machine = ExportedMachine(self.description["document"], file=Path(self.description["file"]),
                                  base=folder / "machine")
        self.machine = machine
        declared = [(v["name"], v["type"]) for v in self.description["variables"]]
        built = [(p.name, p.fmi_type) for p in (*machine.outputs, *machine.inputs)]
        if declared != built:
            raise CosimError(f"the machine built here has the variables {built}, the FMU declares {declared}: "
                             "export it again with this cosim")
        self.n_outputs = len(machine.outputs)
        self.resolution = machine.sim.timebase.resolution_s
        self.start = Fraction(0)
        for i, port in enumerate(machine.inputs):
            self.values[1 + self.n_outputs + i] = port.start
        self._write(machine.values())

    def _write(self, outputs: list[float]) -> None:
        self.values[0] = float(self.start + self.machine.now * self.resolution)
        for i, value in enumerate(outputs, start=1):
            self.values[i] = value

    def _inputs(self) -> list[float]:
        first = 1 + self.n_outputs
        return [self.values[first + i] for i in range(len(self.machine.inputs))]

    def _tick(self, t: float) -> int:
        return round((Fraction(t) - self.start) / self.resolution)

    def _time(self, tick: int) -> float:
        return float(self.start + tick * self.resolution)

    def _warnings(self) -> None:
        while self.machine.warnings:
            self.log(WARNING, "logStatusWarning", self.machine.warnings.pop(0))

    # -- the calls of the C layer ----------------------------------------------------------------------
    def values_address(self) -> int:
        return ctypes.addressof(self.values)

    def kinds_address(self) -> int:
        return ctypes.addressof(self.kinds)

    def step_address(self) -> int:
        return ctypes.addressof(self.step)

    def n_values(self) -> int:
        return self.n

    def set_debug_logging(self, on: int) -> int:
        return self._call(self._set_debug_logging, on)

    def enter_initialization(self, start: float, stop_defined: int, stop: float) -> int:
        return self._call(self._enter_initialization, start, stop_defined, stop)

    def exit_initialization(self) -> int:
        return self._call(self._exit_initialization)

    def do_step(self, t: float, h: float) -> int:
        return self._call(self._do_step, t, h)

    def update_discrete_states(self) -> int:
        return self._call(self._update_discrete_states)

    def terminate(self) -> int:
        return OK

    def reset(self) -> int:
        return self._call(self._build)

    def free(self) -> None:
        if self.machine is not None:
            self._call(self.machine.close)
            self.machine = None

    def _call(self, method: Callable[..., object], *args: Any) -> int:
        """Run one call; an error becomes a logged message and an FMI status, never an exception."""
        try:
            method(*args)
        except CosimError as exc:
            self.log(ERROR, "logStatusError", str(exc))
            return ERROR
        except Exception as exc:  # a bug: say where, the importer goes on
            self.log(ERROR, "logStatusError", f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}")
            return ERROR
        return OK

    def _set_debug_logging(self, on: int) -> None:
        self.logging_on = bool(on)

    def _enter_initialization(self, start: float, stop_defined: int, stop: float) -> None:
        self.start = Fraction(start)
        self._write(self.machine.values())

    def _exit_initialization(self) -> None:
        machine = self.machine
        machine.apply_inputs(self._inputs())
        machine.advance(machine.now)
        self._write(machine.values())
        self._warnings()

    def _do_step(self, t: float, h: float) -> None:
        machine = self.machine
        if self._tick(t) != machine.now:
            raise CosimError(f"doStep from t = {t!r} s, but the FMU is at {self._time(machine.now)!r} s "
                             f"(tick {machine.now}): a step starts where the last one ended")
        target = round((Fraction(t) + Fraction(h) - self.start) / self.resolution)
        if target < machine.now:
            raise CosimError(f"doStep with a negative step size h = {h!r} s")
        machine.apply_inputs(self._inputs())
        event = machine.advance(target, early_return=self.early_return_allowed)
        reached = machine.now
        handle = event and self.event_mode_used
        self._write(machine.values(left=handle))
        self.step[LAST_TIME] = self._time(reached)
        self.step[EVENT] = float(handle)
        self.step[EARLY] = float(reached < target)
        self.step[TERMINATE] = 0.0
        if event and self.logging_on:
            self.log(OK, "logEvents", f"event at t = {self._time(reached)!r} s (tick {reached})"
                     + (": early return" if reached < target else ""))
        self._warnings()

    def _update_discrete_states(self) -> None:
        machine = self.machine
        machine.apply_inputs(self._inputs())
        machine.advance(machine.now)
        self._write(machine.values())
        self.step[EVENT] = 0.0
        self._warnings()


def instantiate(resources: str, name: str, token: str, fmi_version: int, event_mode_used: int,
                early_return_allowed: int, logging_on: int, log_address: int, instance: int) -> Slave | None:
    """Create the machine of one FMU instance; None after a logged error (called by the C layer).

    Parameters
    ----------
    resources : str
        The FMU's resources folder (a path).
    name, token : str
        Instance name and instantiation token.
    fmi_version : int
    event_mode_used, early_return_allowed, logging_on : int
        The importer's flags (0 or 1).
    log_address, instance : int
        The C function ``machine_py_log(instance, status, category, message)`` and its instance.
    """
    log_function = LogFunction(log_address)

    def log(status: int, category: str, message: str) -> None:
        log_function(instance, status, category.encode(), message.encode(errors="replace"))

    try:
        return Slave(Path(resources), token, fmi_version=fmi_version, event_mode_used=bool(event_mode_used),
                     early_return_allowed=bool(early_return_allowed), log=log, logging_on=bool(logging_on))
    except CosimError as exc:
        log(ERROR, "logStatusError", f"{name}: {exc}")
    except Exception as exc:
        log(ERROR, "logStatusError", f"{name}: {type(exc).__name__}: {exc}\n{traceback.format_exc()}")
    return None
