"""The PoKeys pulse engine in a machine file, fed by a host that streams a planned job.

::

    [controller]
    family = "pokeys"
    model = "56E"                 # 56E, 56U, 57E, 57CNC
    dir_setup = "5 us"            # direction set-up before the first pulse of a slot
    pulse_width = "5 us"
    [controller.axis.x]           # x, y, z (the 57CNC: x, y, z, a, b, c, u, v)
    max_speed_hz = 24000          # the engine's own limits (internal modes); default from the host's below
    accel = 400000                # pulses/s^2 (decel defaults to accel)
    limit_pos_enabled = true
    steps_per_unit = 400          # the host's motor tuning, for G-code programs
    max_velocity = 50             # units/s
    max_accel = 500               # units/s^2
    [controller.axis.a]           # a 57CNC's a, b, c (degrees) and u, v (units): G-code axes when tuned
    steps_per_unit = 100          # steps/degree
    max_velocity = 90             # degrees/s
    max_accel = 900               # degrees/s^2

    [host]
    link = "usb"                  # usb or ethernet
    prefill = 64                  # slots queued before the start, and the level the host keeps
    units = "mm"                  # machine units of G-code programs: mm or inch
    feed_override = 1.0           # factor on the programmed feeds
    path_mode = "exact_stop"      # before any G61/G64: or "blend" (corners at the junction-deviation speed)
    path_tolerance = 0.05         # junction deviation for blend, and for G64 without P [units]
    arc_tolerance = 0.01          # largest chord error of arcs and splines [units]
    allow_unsupported = false     # true: a word this machine cannot simulate is skipped (listed) instead
    subroutine_path = ["subs"]    # folders of o<name> subroutine files (name.ngc), from the machine file
    tool_change_time = "4 s"      # how long an M6 takes (the job waits)
    tool_change_position = [0, 0, 50]  # machine coordinates the machine goes to for M6 (default: stays)
    pause_time = "2 s"            # how long an M0/M60 (M1 with optional_stop) pause lasts, or
    cycle_start = true            # ... until <engine>.cycle_start rises (a [[stimulus]], the operator)
    optional_stop = false         # M1 pauses
    digital_inputs = 4            # M66 P0..P3 read <engine>.din0..din3, analog_inputs = 4: E0..E3 ain0..ain3
                                  #   (an input a [[stimulus]] drives; one none drives reads 0)
    probe = false                 # the machine has a probe input (G38.n; the probe never trips)
    block_delete = false          # lines starting with / are skipped
    [[host.tool]]                 # the tool table (T, M6, G43, G41/G42, #5400..)
    number = 1
    diameter = 6.0                # [units]
    z_offset = 25.4               # tool length offset [units]

    [[program]]                   # a G-code program (docs/pokeys.md, "G-code jobs") ...
    file = "pocket.nc"

    [[move]]                      # ... or straight moves in pulses, planned under the axes' limits
    target = [12000, -9000, 6000] # pulses, one per axis
    speed_hz = 20000              # optional: limit of the dominant axis

Ports: ``stepper = { axis = "x" }`` and ``switches = { axis = "x" }`` (an axis name or index).
Figures: see :mod:`cosim.machine.families.pokeys_figures`.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

from cosim.controllers.pokeys import AxisConfig, EngineConfig, PulseEngine
from cosim.controllers.pokeys.buffer import Entry
from cosim.controllers.pokeys.gcode import UNITS, HostSetup, Interpreter, Tool, read_file
from cosim.controllers.pokeys.gcodejob import GcodeJob, Piece
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.job import JobWatch
from cosim.controllers.pokeys.limits import AXIS_NAMES
from cosim.controllers.pokeys.models import MODELS
from cosim.controllers.pokeys.pathplan import MODES, HostAxis, PathSettings
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.controllers.pokeys.states import EngineState
from cosim.controllers.pokeys.toolpath import Wait
from cosim.errors import ConfigurationError
from cosim.job import Job, JobState
from cosim.machine.document import Table
from cosim.machine.families.pokeys_figures import declare_figures
from cosim.scenario import Run
from cosim.signals import Signal
from cosim.validate import positive

AXIS_KEYS = ("max_speed_hz", "accel", "decel", "limit_pos_enabled", "limit_neg_enabled", "home_enabled",
             "invert_direction", "invert_homing")
HOST_AXIS_UNITS = {"steps_per_unit": "steps/unit", "max_velocity": "units/s", "max_accel": "units/s^2"}
HOST_AXIS_KEYS = tuple(HOST_AXIS_UNITS)
GCODE_AXES = ("x", "y", "z")
"""The axes every G-code machine tunes; the model's other axes (a 57CNC's a, b, c, u, v) join when tuned."""
GCODE_LETTERS = "ABCUVW"
"""Axis words beyond X, Y, Z (LinuxCNC's)."""
GCODE_KEYS = ("units", "feed_override", "path_mode", "path_tolerance", "arc_tolerance", "allow_unsupported",
              "subroutine_path", "tool_change_time", "tool_change_position", "pause_time", "optional_stop", "probe",
              "block_delete", "tool", "cycle_start", "digital_inputs", "analog_inputs")
DEFAULT_INPUTS = 4
"""M66's digital and analog inputs by default (LinuxCNC's motion module: num_dio = num_aio = 4)."""
MAX_INPUTS = 64
"""The most of either (LinuxCNC's EMCMOT_MAX_DIO / EMCMOT_MAX_AIO)."""
INPUT_DESCRIPTIONS = {"din": "digital input the host reads (G-code M66 P)",
                      "ain": "analog input the host reads (G-code M66 E)",
                      "cycle_start": "the operator's cycle start: its rise ends an M0/M1/M60 pause"}
TOOL_KEYS = ("number", "diameter", "z_offset", "x_offset", "pocket")


class PoKeysFamily:
    """``family = "pokeys"``."""

    name = "pokeys"
    tables: tuple[str, ...] = ("host", "move")

    def __init__(self) -> None:
        self.host_axes: dict[str, dict[str, Any]] = {}
        self.axes_table: Table | None = None

    def controller(self, run: Run, table: Table, *, base: Path) -> PulseEngine:
        model = table.text("model", "56E")
        with table.at("model"):
            defaults = EngineConfig.for_model(model)
        names = [a.name for a in defaults.axes]
        axes = self.axes_table = table.table("axis")
        configured = dict(axes.items())
        for key in configured:
            if key not in names:
                raise axes.error(key, key, f"the axes of a {model}: {', '.join(names)}")
        built = []
        for name, default in zip(names, defaults.axes, strict=True):
            values: dict[str, Any] = {}
            if name in configured:
                axis = configured[name]
                for key in AXIS_KEYS:
                    if axis.has(key):
                        values[key] = axis.raw(key)
                if "accel" in values and "decel" not in values:
                    values["decel"] = values["accel"]
                host = {key: axis.number(key) for key in HOST_AXIS_KEYS if axis.has(key)}
                self.host_axes[name] = host
                with axis.at():
                    for key, value in host.items():
                        positive(value, key, unit=HOST_AXIS_UNITS[key])
                    values.update(_engine_limits(host, values, defaults.device.max_rate_hz))
            with axes.at(name):
                built.append(AxisConfig(**{**_fields(default), **values, "name": name}))
        timing = {k: v for k, v in (("dir_setup_ns", table.raw("dir_setup", None)),
                                    ("pulse_width_ns", table.raw("pulse_width", None))) if v is not None}
        with table.at():
            ns = {k: _ns(v, k) for k, v in timing.items()}
            config = EngineConfig.for_model(model, axes=tuple(built), **ns)
            return PulseEngine(run.sim, config)

    def port(self, controller: PulseEngine, kind: str, table: Table) -> Any:
        raw = table.raw("axis")
        with table.at("axis"):
            names = list(controller.axis_names)
            axis = names.index(raw) if isinstance(raw, str) and raw in names else controller.axis(raw)
            if kind == "stepper":
                return controller.step_dir(axis)
            if kind == "switches":
                return controller.switch_port(axis)
        raise ConfigurationError(f"{table.file}: {table.path}: a PoKeys engine has no {kind} connector "
                                 "(couple stepper or switches)")

    def start(self, run: Run, controller: PulseEngine, programs: list[Table], document: Table, *,
              base: Path) -> None:
        host = document.table("host")
        moves = document.tables("move")
        link = host.text("link", "usb", choices=("usb", "ethernet"))
        prefill = host.integer("prefill", 64, low=1, high=controller.buffer.depth_slots)
        gjob: GcodeJob | None = None
        part = "moves"
        first = Piece([])
        inputs: dict[str, Signal] = {}
        if programs:
            if moves:
                raise ConfigurationError(f"{document.file}: move: a machine runs either a G-code [[program]] or "
                                         "[[move]] tables, not both")
            gjob = self._gcode_job(controller, programs, host, base=base)
            first = gjob.next_piece()
            counts = gjob.counts
            part = str(programs[0].data.get("file"))
            inputs = self._inputs(run, controller, host, document, gjob)
            run.sim.trace.meta["gcode"] = {"file": part, "notes": gjob.notes, "skipped": gjob.skipped,
                                           "end_steps": list(gjob.end_steps), "not_modelled": gjob.not_modelled,
                                           "end": gjob.ending}
            said = self._say(run, controller, gjob, part, 0, 0)
        else:
            for key in GCODE_KEYS:
                if host.has(key):
                    raise ConfigurationError(f"{host.file}: {host.key(key)}: G-code settings need a G-code "
                                             "[[program]]")
            counts = self._move_job(controller, moves)
        engine_job = controller.job = Job(run.sim, controller.name)  # type: ignore[attr-defined]
        ending = (lambda: gjob.ending) if gjob is not None else (lambda: "moves")

        def on_end() -> None:
            if gjob is not None:
                meta: dict[str, Any] = run.sim.trace.meta["gcode"]  # type: ignore[assignment]
                meta.update(end=gjob.ending, end_steps=list(gjob.end_steps))
            self._job_end(engine_job, part, ending(), programs)

        watch = JobWatch(run.sim, controller, slots=len(counts), outputs=first.outputs, on_end=on_end,
                         complete=first.wait is None)

        def next_piece(value: float | None, index: int, bits: tuple[bool, ...]) -> tuple[list[Entry], Wait | None]:
            """The job after a wait (see GcodeJob): its entries from ``index``, told to the job watch."""
            nonlocal said
            assert gjob is not None
            try:
                piece = gjob.next_piece(value)
            except ConfigurationError as exc:
                engine_job.stop(JobState.ERROR, str(exc))
                watch.extend(index, complete=True)
                return [], None
            said = self._say(run, controller, gjob, part, *said)
            entries = to_entries(piece.counts, direction_bits=bits)
            watch.extend(index + len(entries), [(index + i, record) for i, record in piece.outputs],
                         complete=piece.wait is None)
            return entries, piece.wait

        with host.at():
            app = HostApp(run.sim, controller, to_entries(first.counts if gjob is not None else counts), link=link,
                          prefill_slots=prefill, wait=first.wait, next_piece=next_piece, inputs=inputs)
        self._follow_job(run, controller, engine_job, part, ending())
        declare_figures(run, controller, app, watch, counts, gjob)

    @staticmethod
    def _say(run: Run, controller: PulseEngine, gjob: GcodeJob, part: str, notes: int, not_modelled: int
             ) -> tuple[int, int]:
        """The job's notes since the last time (``notes``, ``not_modelled`` said so far) in the run's notes."""
        for note in gjob.notes[notes:]:
            run.note(note)
        if not notes and not not_modelled:
            for line in gjob.skipped:
                run.note(f"skipped: {line}")
        for note in gjob.not_modelled[not_modelled:]:
            run.sim.notes.not_modelled(controller.name, "G-code", note.split(": ", 1)[-1],
                                       where=note.split(": ", 1)[0] if ": " in note else part)
        return len(gjob.notes), len(gjob.not_modelled)

    @staticmethod
    def _inputs(run: Run, controller: PulseEngine, host: Table, document: Table, gjob: GcodeJob
                ) -> dict[str, Signal]:
        """The host's inputs a ``[[stimulus]]`` drives (``<engine>.din<n>``, ``ain<n>``, ``cycle_start``), as signals;
        an input no stimulus drives reads 0 (LinuxCNC: an unconnected motion.digital-in pin)."""
        counts = gjob.interpreter.inputs or {}
        names = [*(f"din{n}" for n in range(counts.get("digital", 0))),
                 *(f"ain{n}" for n in range(counts.get("analog", 0))), "cycle_start"]
        stimuli = document.data.get("stimulus", [])  # read, not taken: build reads them after the family starts
        driven = {str(t.get("signal")) for t in stimuli if isinstance(t, dict)} if isinstance(stimuli, list) else set()
        inputs = {}
        for name in names:
            if f"{controller.name}.{name}" in driven:
                kind = "real" if name.startswith("ain") else "bit"
                inputs[name] = Signal(run.sim, f"{controller.name}.{name}", kind=kind,
                                      description=INPUT_DESCRIPTIONS[name.rstrip("0123456789")])
                controller.host_inputs.append(inputs[name])
        if gjob.setup.cycle_start and "cycle_start" not in inputs:
            run.note(f"{host.file}: host.cycle_start: no [[stimulus]] drives {controller.name}.cycle_start: an M0 "
                     "pause lasts until the run ends")
        return inputs

    @staticmethod
    def _follow_job(run: Run, controller: PulseEngine, job: Job, part: str, ending: str) -> None:
        """The job begins with the run; the engine's limit (100) and emergency (101) stops end it."""
        job.begin(part)

        def on_state(signal: Any) -> None:
            if signal.value == EngineState.STOP_LIMIT:
                job.stop(JobState.LIMIT, f"{controller.name}: stopped by a limit switch (engine state 100)")
            elif signal.value == EngineState.STOP_EMERGENCY:
                job.stop(JobState.EMERGENCY, f"{controller.name}: stopped by the emergency input (engine state 101)")

        controller.state_signal.subscribe(on_state)

    @staticmethod
    def _job_end(job: Job, part: str, ending: str, programs: list[Table]) -> None:
        """The buffer has drained after the job's last slot: done if the program reached its end."""
        if ending or not programs:
            job.finish(part)
        else:
            job.stop(JobState.ERROR, f"{part}: File ended with no percent sign or program end (LinuxCNC's error: "
                                     "end the program with M2, M30 or a % line)")

    def _move_job(self, controller: PulseEngine, tables: list[Table]) -> list[tuple[int, ...]]:
        moves = []
        for table in tables:
            target = table.raw("target")
            speed = table.raw("speed_hz", None)
            accel = table.raw("accel", None)
            with table.at():
                moves.append(Move(tuple(target) if isinstance(target, list) else target, speed_hz=speed, accel=accel))
        return plan(moves, controller.config.axes) if moves else []

    def _gcode_job(self, controller: PulseEngine, programs: list[Table], host: Table, *, base: Path) -> GcodeJob:
        if len(programs) > 1:
            raise ConfigurationError(f"{programs[1].file}: {programs[1].path}: a PoKeys machine runs one G-code "
                                     "program (give one [[program]] table)")
        table = programs[0]
        path = table.file_path("file", base)
        units = host.text("units", "mm", choices=UNITS)
        allow = host.flag("allow_unsupported", False)
        with host.at():
            settings = PathSettings(mode=host.text("path_mode", "exact_stop", choices=MODES),
                                    tolerance=host.number("path_tolerance", Fraction(5, 100)),
                                    arc_tolerance=host.number("arc_tolerance", Fraction(1, 100)),
                                    feed_override=host.number("feed_override", Fraction(1)), units=units)
        axes = []
        assert self.axes_table is not None
        names = controller.axis_names
        extra = tuple(name for name in names[3:] if self.host_axes.get(name))
        for name in (*GCODE_AXES, *extra):
            values = self.host_axes.get(name, {})
            missing = [key for key in HOST_AXIS_KEYS if key not in values]
            if missing:
                needs = (f"on the {', '.join(GCODE_AXES)} axes" if name in GCODE_AXES else
                         f"on a G-code axis {name} ({'degrees' if name in 'abc' else 'units'})")
                raise ConfigurationError(f"{self.axes_table.file}: {self.axes_table.key(name)}.{missing[0]} is "
                                         f"missing (a G-code program needs {', '.join(HOST_AXIS_KEYS)} {needs})")
            with self.axes_table.at(name):
                axes.append(HostAxis(**values, name=name))
        no_axis = {letter: _no_axis(letter, controller, self.axes_table) for letter in GCODE_LETTERS
                   if letter.lower() not in extra}
        with host.at():
            cycle_start = host.flag("cycle_start", False)
            if cycle_start and host.has("pause_time"):
                raise ConfigurationError(f"{host.file}: {host.key('pause_time')}: a pause ends after pause_time or "
                                         "at cycle_start, not both (give one)")
            setup = HostSetup(units=units, tool_change_time=_seconds(host, "tool_change_time"),
                              tool_change_position=_position(host), pause_time=_seconds(host, "pause_time"),
                              optional_stop=host.flag("optional_stop", False),
                              arc_tolerance=host.number("arc_tolerance", Fraction(1, 100)),
                              axes="".join((*GCODE_AXES, *extra)), cycle_start=cycle_start, inputs=True)
            tools = _tools(host)
            search = [(base / str(p)).resolve() for p in _list(host, "subroutine_path")]
            probe = host.flag("probe", False)
            block_delete = host.flag("block_delete", False)
            inputs = {"digital": host.integer("digital_inputs", DEFAULT_INPUTS, low=0, high=MAX_INPUTS),
                      "analog": host.integer("analog_inputs", DEFAULT_INPUTS, low=0, high=MAX_INPUTS)}
        with table.at("file"):
            interpreter = Interpreter(machine_units=units, tools=tools, search_path=search,
                                      allow_unsupported=allow, probe=probe, axes="".join((*GCODE_AXES, *extra)),
                                      no_axis=no_axis, block_delete=block_delete, inputs=inputs)
            return GcodeJob(interpreter, read_file(path), setup, axes, settings=settings,
                            n_axes=len(controller.axis_names),
                            max_pulses_per_slot=controller.device.max_pulses_per_slot)


def _no_axis(letter: str, controller: PulseEngine, axes: Table) -> str:
    """Why a G-code axis word cannot run on this machine: the model has not got the axis, or the file does not
    tune it."""
    device = controller.device
    name = letter.lower()
    if name not in device.axis_names:
        most = max(MODELS.values(), key=lambda m: m.axes)
        hint = f"; a PoKeys{most.name} drives {', '.join(most.axis_names)}" if name in most.axis_names else ""
        return (f"a PoKeys{device.name} has no {letter} axis (its pulse engine drives {device.axes} axes: "
                f"{', '.join(device.axis_names)}{hint})")
    return (f"the {letter} axis of this PoKeys{device.name} is not a G-code axis: give "
            f"{', '.join(HOST_AXIS_KEYS)} in {axes.file}: [{axes.key(name)}]")


def _seconds(host: Table, key: str) -> Fraction:
    if not host.has(key):
        return Fraction(0)
    raw = host.raw(key)
    with host.at(key):
        ticks = _ns(raw, key) if isinstance(raw, str) else None
    if ticks is not None:
        return Fraction(ticks, 10**9)
    with host.at(key):
        return positive(host.number(key), key, unit="s")


def _position(host: Table) -> tuple[Fraction, Fraction, Fraction] | None:
    if not host.has("tool_change_position"):
        return None
    raw = host.raw("tool_change_position")
    if not isinstance(raw, list) or len(raw) != 3 or not all(isinstance(v, int | float) for v in raw):
        raise host.error("tool_change_position", raw, "[x, y, z] in machine units")
    return (Fraction(raw[0]), Fraction(raw[1]), Fraction(raw[2]))


def _list(host: Table, key: str) -> list[str]:
    if not host.has(key):
        return []
    raw = host.raw(key)
    items = [raw] if isinstance(raw, str) else raw
    if not isinstance(items, list) or not all(isinstance(v, str) for v in items):
        raise host.error(key, raw, "a folder or a list of folders (relative to the machine file)")
    return items


def _tools(host: Table) -> list[Tool]:
    tools = []
    for table in host.tables("tool"):
        for key in table.data:
            if key not in TOOL_KEYS:
                raise table.error(key, key, ", ".join(TOOL_KEYS))
        number = table.integer("number", low=1, high=99999)
        with table.at():
            tools.append(Tool(number, z_offset=table.number("z_offset", Fraction(0)),
                              x_offset=table.number("x_offset", Fraction(0)),
                              diameter=table.number("diameter", Fraction(0)), pocket=table.integer("pocket", 0)))
    return tools


def _engine_limits(host: dict[str, Fraction], given: dict[str, Any], model_max_hz: int) -> dict[str, Any]:
    """The engine's max_speed_hz and accel from the host's tuning, where the file does not set them."""
    out: dict[str, Any] = {}
    spu = host.get("steps_per_unit")
    if spu is None:
        return out
    if "max_speed_hz" not in given and "max_velocity" in host:
        out["max_speed_hz"] = min(host["max_velocity"] * spu, Fraction(model_max_hz))
    if "accel" not in given and "max_accel" in host:
        out["accel"] = host["max_accel"] * spu
        if "decel" not in given:
            out["decel"] = out["accel"]
    return out


def _fields(config: AxisConfig) -> dict[str, Any]:
    return {k: getattr(config, k) for k in AXIS_KEYS}


def _ns(value: Any, name: str) -> int:
    from cosim.timebase import TimeBase

    return TimeBase().ticks(value, name=name) if isinstance(value, str) else value


__all__ = ["AXIS_NAMES", "PoKeysFamily"]
