"""The Trio EURO205X in a machine file.

::

    [controller]
    family = "trio"
    servo_period_us = 1000        # SERVO_PERIOD: 250, 500, 1000, 2000
    n_axes = 4
    regist_inputs = [0, 1, 2, 3]  # the registration input (IN channel) of each axis (default: the axis number)
    [controller.axis.3]           # axis parameters by their vendor names, set at power-up
    UNITS = 16
    ATYPE = 35

    [[program]]
    file = "engrave.bas"          # relative to the machine file
    process = 1                   # RUN "ENGRAVE", 1
    base = [3]                    # the BASE group it starts with (default: axis 0)
    job = true                    # a part of the job (default); false for a background process (a watchdog loop)

    [[channel]]                   # characters arriving on a channel for INPUT / GET (\\r ends a line)
    channel = 0
    at = ["10 ms", "20 ms"]
    text = ["12\\r", "y"]

The programs of one machine are compiled together: they share their ``CONSTANT`` and ``GLOBAL``
names, ``RUN`` and ``INCLUDE`` find each other by name. The job (``trio.job``) is the processes
the ``[[program]]`` tables start (and the processes they RUN): it begins when they start and is
done when every one has stopped; a run-time error without ``ON BASICERROR`` stops it (ERROR), a
limit that cancels a move stops it (LIMIT). A deliberately endless background process (a
watchdog loop, a display task) is kept out of the job with ``job = false``.

Ports: ``stepper = { axis = N }`` (the step/direction output), ``laser = { axis = N }`` (the PWM
output of axis 2 or 3), ``switches = { limit_pos = 4, limit_neg = 5, home = 6 }`` (the plant's
switches on these inputs, wired normally closed: the input is OFF while a switch is tripped, as
FWD_IN, REV_IN and DATUM_IN expect).
"""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import Any

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.scenario import Run
from cosim.signals import Signal, SwitchPort
from cosim.timebase import Priority


class TrioFamily:
    """``family = "trio"``."""

    name = "trio"
    tables: tuple[str, ...] = ("channel",)

    def controller(self, run: Run, table: Table, *, base: Path) -> TrioController:
        with table.at():
            trio = TrioController(run.sim, servo_period_us=table.integer("servo_period_us", 1000),
                                  n_axes=table.integer("n_axes", 4), table_size=table.integer("table_size", 16_000),
                                  encoder_at_atype=table.raw("encoder_at_atype", None))
        inputs = table.raw("regist_inputs", None)
        if inputs is not None:
            with table.at("regist_inputs"):
                if not isinstance(inputs, list) or len(inputs) > len(trio.axes):
                    raise ConfigurationError.out_of_range("value", inputs, f"a list of at most {len(trio.axes)} "
                                                          "input numbers, one per axis")
                for number, channel in enumerate(inputs):
                    trio.io.input(channel)
                    trio.regist_inputs[number] = int(channel)
        axes = table.table("axis")
        for key, axis in axes.items():
            with axes.at(key):
                if not key.isdigit():
                    raise ConfigurationError.out_of_range("axis", key, f"0..{len(trio.axes) - 1}")
                trio.axis(int(key))
            for name, value in axis.data.items():
                axis.raw(name)
                with axis.at(name):
                    trio.set_param(name, value, axis=int(key), where=f"{table.file}: {axis.key(name)}")
        return trio

    def port(self, controller: TrioController, kind: str, table: Table) -> Any:
        if kind == "switches":
            return self._switches(controller, table)
        axis = table.integer("axis", low=0)
        with table.at("axis"):
            if kind == "stepper":
                return controller.step_dir(axis)
            if kind == "laser":
                return controller.pwm_port(axis)
        raise ConfigurationError(f"{table.file}: {table.path}: a Trio controller has no {kind} connector "
                                 "(couple stepper, laser or switches)")

    def _switches(self, controller: TrioController, table: Table) -> SwitchPort:
        """Proxies the coupling sets (1 = tripped), copied inverted to the inputs (normally closed wiring)."""
        table.raw("axis", None)
        proxies: dict[str, Signal | None] = {}
        for role in ("limit_pos", "limit_neg", "home"):
            channel = table.raw(role, None)
            if channel is None:
                proxies[role] = None
                continue
            with table.at(role):
                target = controller.io.input(channel, initial=1)  # wired normally closed: ON until tripped
            proxy = Signal(controller.sim, f"{target.name}.switch", kind="bit",
                           description=f"the plant's {role} switch wired to {target.name} (1 = tripped; the input "
                                       "is OFF while tripped)")
            proxy.subscribe(partial(_wire_normally_closed, target))
            proxies[role] = proxy
        return SwitchPort(limit_pos=proxies["limit_pos"], limit_neg=proxies["limit_neg"], home=proxies["home"])

    def start(self, run: Run, controller: TrioController, programs: list[Table], document: Table, *,
              base: Path) -> None:
        paths = []
        for table in programs:
            paths.append(table.file_path("file", base))
        loaded = []
        if programs:
            with programs[0].at("file"):
                loaded = BasicProgram.load_all(paths)
        for program in loaded:
            program.install(controller)
        for table, program in zip(programs, loaded, strict=True):
            process = table.integer("process", None, low=1, high=5)
            group = table.raw("base", [0])
            in_job = table.flag("job", True)
            with table.at("base"):
                if not isinstance(group, list) or not group:
                    raise ConfigurationError.out_of_range("base", group, "a list of axis numbers, e.g. [2, 3]")
                program.start(controller, process=process, base=tuple(controller.axis(a).number for a in group),
                              job=in_job)
        stimuli = document.data.get("stimulus", [])
        for entry in stimuli if isinstance(stimuli, list) else []:  # the Z markers a stimulus drives exist first
            name = entry.get("signal") if isinstance(entry, dict) else None
            if isinstance(name, str) and name.startswith(f"{controller.device}.axis") and name.endswith(".z_mark"):
                number = name[len(controller.device) + 5:-len(".z_mark")]
                if number.isdigit() and int(number) in controller.axes:
                    controller.axes[int(number)].ensure_z_mark()
        for table in document.tables("channel"):
            self._channel(run, controller, table)
        self._figures(run, controller)

    def _figures(self, run: Run, controller: TrioController) -> None:
        """``axisN_step_pulses`` and ``axisN_late_positions`` of the axes the machine and its programs use.

        Declared before the run for the axes that have a step output (axes 2 and 3, a coupled axis, an
        axis made a stepper in ``[controller.axis.N]``), so ``check-machine`` lists them; after the run, those
        of an axis that never became a stepper nor stepped are dropped, and those of an axis a program made
        a stepper are added: the figures follow the axes used, not the family's defaults.
        """
        sim = run.sim

        def declare(n: int) -> None:
            axis = controller.axes[n]
            if axis.step is not None:
                step = axis.step
                run.figure(f"axis{n}_step_pulses", lambda: float(sum(sim.trace.segments(step.name)["count"])),
                           where=f"the Trio family: axis {n}")
            if axis.gate is not None:
                gate = axis.gate
                run.figure(f"axis{n}_late_positions", lambda: float(len(gate.late)), where=f"the Trio family: axis {n}")

        declared = [n for n, axis in controller.axes.items() if axis.step is not None]
        for n in declared:
            declare(n)

        def used(n: int) -> bool:
            axis = controller.axes[n]
            return axis.step is not None and (axis.stepper or bool((sim.trace.segments(axis.step.name)["count"] != 0)
                                                                   .any()))

        def follow_the_axes_used() -> None:
            for n in declared:
                if not used(n):
                    for name in (f"axis{n}_step_pulses", f"axis{n}_late_positions"):
                        run.figures.pop(name, None)
                        run.figure_declared.pop(name, None)
            for n in controller.axes:
                if n not in declared and used(n):
                    declare(n)

        run.afterwards(follow_the_axes_used)

    def _channel(self, run: Run, controller: TrioController, table: Table) -> None:
        """``[[channel]] channel = n, at = [...], text = [...]``: characters fed to a channel at those instants."""
        number = table.integer("channel", 0, low=0, high=255)
        times, texts = table.raw("at"), table.raw("text")
        with table.at("at"):
            if not isinstance(times, list) or not isinstance(texts, list) or len(times) != len(texts):
                raise ConfigurationError.out_of_range("at, text", (times, texts), "two lists of the same length")
            if not all(isinstance(t, str) for t in texts):
                raise ConfigurationError.out_of_range("text", texts, "a list of strings")
            schedule = [(table.ticks(t), text) for t, text in zip(times, texts, strict=True)]
        channel = controller.channel(number)
        sim = run.sim
        for t, text in schedule:
            sim.call_at(t, Priority.NORMAL, partial(channel.feed, text))


def _wire_normally_closed(target: Signal, source: Signal) -> None:
    target.set(0 if source.value else 1)
