"""The Delta Tau (Turbo) PMAC in a machine file: setup and program files as the user keeps them.

::

    [controller]
    family = "pmac"
    setup = ["setup.pmc"]           # PMAC files read at power-up, in order: I-variables (I10, the
                                    # conversion table I8000.., Ix93/Ix94), M-variable definitions,
                                    # &1 #1->1000X, buffers; before the plants are coupled
    plc_scan_period = "200 us"      # background (PLC 1..31) scan period: the controller's load
    plc_scan_offset = "0 us"        # first background scan
    include_path = ["lib"]          # more folders for #include (after the including file's own)

    [controller.defines]            # values of the files' $(NAME) template macros
    PLC = 3

    [[program]]
    file = "shear.pmc"              # more PMAC files (OPEN PROG / OPEN PLC ... CLOSE), read after the plants

    [[command]]                     # online commands, issued at a time (priority HOST)
    at = "0 ms"
    text = "ENABLE PLC 1 &1 B1 R"
    [[command]]
    at = "80 ms"
    text = "%50"

    [plant.conveyor]
    model = "Conveyor"
    encoder = { channel = "$078018", trigger = "mark" }   # encoder channel, capture trigger = output "mark"
    [plant.servo]
    model = "Servo"
    servo = { motor = 1, bandwidth_hz = 100 }             # motor 1's loop: PID for 100 Hz, DAC -> u_cmd

Ports: ``encoder = { channel, trigger (a plant output, optional), trigger_level (1), name }``,
``servo = { motor, bandwidth_hz, gain_counts_per_s_per_bit and tau_s (the PID's design model;
default: derived from the Servo plant's parameters) }``. Figures: for a triggered time-base entry
its starts, stale starts and last time zero; for each coupled motor the designed loop's margins
and its final position; the number of background scans.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.ect import TriggeredTimeBaseEntry
from cosim.controllers.pmac.ports import EncoderPort, ServoPort
from cosim.controllers.pmac.runtime import CommandLine
from cosim.controllers.pmac.servo import MotorModel
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.scenario import Run
from cosim.timebase import Priority


class PmacFamily:
    """``family = "pmac"``."""

    name = "pmac"
    tables: tuple[str, ...] = ("command",)

    def controller(self, run: Run, table: Table, *, base: Path) -> Pmac:
        pmac = Pmac(run.sim)
        period = table.time("plc_scan_period", None)
        offset = table.time("plc_scan_offset", None)
        with table.at():
            pmac.programs.configure_scan(period=period, offset=offset)
        pmac.defines = _defines(table)
        pmac.include_path = _folders(table, base)
        setup = table.raw("setup", [])
        files = [setup] if isinstance(setup, str) else setup
        if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
            raise table.error("setup", setup, "a file name or a list of file names (PMAC setup files)")
        for index, name in enumerate(files):
            holder = Table({"file": name}, file=table.file, path=f"{table.key('setup')}[{index}]",
                           timebase=table.timebase)
            _load(pmac, holder.file_path("file", base))
        return pmac

    def port(self, controller: Pmac, kind: str, table: Table) -> Any:
        if kind == "encoder":
            channel = table.raw("channel")
            trigger = table.text("trigger", None)
            level = table.integer("trigger_level", 1, low=0, high=1)
            name = table.text("name", None)
            with table.at("channel"):
                address = _address(channel)
            return EncoderPort(controller, address, trigger, level, name)
        if kind == "servo":
            number = table.integer("motor", low=1, high=32)
            bandwidth = float(table.number("bandwidth_hz", 50))
            gain = table.raw("gain_counts_per_s_per_bit", None)
            tau = table.raw("tau_s", None)
            with table.at("motor"):
                motor = controller.motors.get(number)
                if motor is None:
                    known = ", ".join(f"#{n}" for n in sorted(controller.motors)) or "none"
                    raise ConfigurationError(f"motor {number} is not defined (defined: {known}); define it in a "
                                             f"setup file, e.g. &1 #{number}->1X")
            with table.at():
                if (gain is None) != (tau is None):
                    raise ConfigurationError("give both gain_counts_per_s_per_bit and tau_s (the design model), "
                                             "or neither")
                model = MotorModel(gain, tau) if gain is not None and tau is not None else None
                return ServoPort(motor, controller.clock.period_s, bandwidth, model)
        raise ConfigurationError(f"{table.file}: {table.path}: a PMAC has no {kind} connector "
                                 "(couple encoder or servo)")

    def start(self, run: Run, controller: Pmac, programs: list[Table], document: Table, *,
              base: Path) -> None:
        pmac = controller
        for table in programs:
            _load(pmac, table.file_path("file", base))
        schedule: list[tuple[int, CommandLine]] = []
        for table in document.tables("command"):
            t = table.time("at")
            text = table.text("text")
            schedule.append((t, pmac.programs.parse_command(text, source=f"{table.file.name}: {table.path}.text")))
        schedule.sort(key=lambda item: item[0])
        pmac.programs.check_commands([line for _t, line in schedule])
        sim = run.sim
        for t, line in schedule:
            sim.call_at(t, Priority.HOST, lambda line=line: pmac.programs.execute(  # type: ignore[misc]
                line.statements, pmac.programs.host))
        pmac.start()
        _figures(run, pmac)


def _load(pmac: Pmac, path: Path) -> None:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    pmac.load(text, source=path.name, path=path)


def _defines(table: Table) -> dict[str, str]:
    """``[controller.defines]``: the values of ``$(NAME)`` template macros (texts or numbers)."""
    defines = table.table("defines")
    values: dict[str, str] = {}
    for name in list(defines.data):
        value = defines.raw(name)
        if isinstance(value, bool) or not isinstance(value, str | int | float):
            raise defines.error(name, value, "a text or a number (the macro's value)")
        values[str(name)] = str(value)
    return values


def _folders(table: Table, base: Path) -> list[Path]:
    """``include_path``: folders ``#include`` looks in after the including file's own (relative to the machine file)."""
    value = table.raw("include_path", [])
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise table.error("include_path", value, "a folder or a list of folders")
    folders = [(base / n).resolve() for n in names]
    for name, folder in zip(names, folders, strict=True):
        if not folder.is_dir():
            raise table.error("include_path", name, "existing folders (relative to the machine file)")
    return folders


def _address(value: object) -> int:
    if isinstance(value, str) and value.startswith("$"):
        try:
            number = int(value[1:], 16)
        except ValueError:
            number = -1
    elif isinstance(value, int) and not isinstance(value, bool):
        number = value
    else:
        number = -1
    if not 0 <= number <= 0xFFFFFF:
        raise ConfigurationError.out_of_range("channel", value, "an address $000000..$FFFFFF, e.g. \"$078018\"")
    return number


def _figures(run: Run, pmac: Pmac) -> None:
    entry = next((e for e in pmac.table.entries if isinstance(e, TriggeredTimeBaseEntry)), None)
    if entry is not None:
        run.figure("triggered_starts", lambda: float(len(entry.starts)))
        run.figure("stale_starts", lambda: float(sum(s.stale for s in entry.starts)))
        run.figure("time_zero_counts", lambda: entry.starts[-1].time_zero_pos256 / 256 if entry.starts
                   else float("nan"), "counts")
    for number, motor in pmac.motors.items():
        loop = motor.loop
        if loop is not None:
            run.figure(f"motor{number}_phase_margin", loop.design.phase_margin_deg, "deg")
            run.figure(f"motor{number}_bandwidth", loop.design.bandwidth_hz, "Hz")
        run.figure(f"motor{number}_final_cmd", lambda motor=motor: float(motor.cmd), "counts")  # type: ignore[misc]
    if any(number != 0 for number in pmac.programs.plcs):
        run.figure("plc_scans", lambda: float(pmac.programs.scans))
