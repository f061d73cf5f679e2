"""The Trio EURO205X in a machine file.

::

    [controller]
    family = "trio"
    servo_period_us = 1000        # SERVO_PERIOD: 250, 500, 1000, 2000
    n_axes = 4
    [controller.axis.3]           # axis parameters by their vendor names, set at power-up
    UNITS = 16
    ATYPE = 35

    [[program]]
    file = "engrave.bas"          # relative to the machine file
    process = 1                   # RUN "ENGRAVE", 1
    base = [3]                    # the BASE group it starts with (default: axis 0)

Ports: ``stepper = { axis = N }`` (ATYPE=35 step/direction output), ``laser = { axis = N }``
(the PWM output of axis 2 or 3).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.scenario import Run


class TrioFamily:
    """``family = "trio"``."""

    name = "trio"
    tables: tuple[str, ...] = ()

    def controller(self, run: Run, table: Table, *, base: Path) -> TrioController:
        with table.at():
            trio = TrioController(run.sim, servo_period_us=table.integer("servo_period_us", 1000),
                                  n_axes=table.integer("n_axes", 4), table_size=table.integer("table_size", 16_000),
                                  encoder_at_atype=table.raw("encoder_at_atype", None))
        axes = table.table("axis")
        for key, axis in axes.items():
            with axes.at(key):
                if not key.isdigit():
                    raise ConfigurationError.out_of_range("axis", key, f"0..{len(trio.axes) - 1}")
                trio.axis(int(key))
            for name, value in axis.data.items():
                axis.raw(name)
                with axis.at(name):
                    trio.set_param(name, value, axis=int(key))
        return trio

    def port(self, controller: TrioController, kind: str, table: Table) -> Any:
        axis = table.integer("axis", low=0)
        with table.at("axis"):
            if kind == "stepper":
                return controller.step_dir(axis)
            if kind == "laser":
                return controller.pwm_port(axis)
        raise ConfigurationError(f"{table.file}: {table.path}: a Trio controller has no {kind} connector "
                                 "(couple stepper or laser)")

    def start(self, run: Run, controller: TrioController, programs: list[Table], document: Table, *,
              base: Path) -> None:
        for table in programs:
            path = table.file_path("file", base)
            table.integer("process", 1, low=0, high=21)
            group = table.raw("base", [0])
            with table.at("file"):
                program = BasicProgram.load(path)
            with table.at("base"):
                if not isinstance(group, list) or not group:
                    raise ConfigurationError.out_of_range("base", group, "a list of axis numbers, e.g. [2, 3]")
                program.start(controller, base=tuple(controller.axis(a).number for a in group))
        sim = run.sim
        for n, axis in controller.axes.items():
            if axis.step is not None:
                step = axis.step
                run.figure(f"axis{n}_step_pulses", lambda step=step: float(sum(  # type: ignore[misc]
                    sim.trace.segments(step.name)["count"])))
            if axis.gate is not None:
                gate = axis.gate
                run.figure(f"axis{n}_late_positions", lambda gate=gate: float(len(gate.late)))  # type: ignore[misc]
