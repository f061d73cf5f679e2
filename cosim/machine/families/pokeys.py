"""The PoKeys pulse engine in a machine file, fed by a host that streams a planned job.

::

    [controller]
    family = "pokeys"
    model = "56E"                 # 56E, 56U, 57E, 57CNC
    dir_setup = "5 us"            # direction set-up before the first pulse of a slot
    pulse_width = "5 us"
    [controller.axis.x]           # x, y, z (the 57CNC: up to 8 axes)
    max_speed_hz = 24000          # the engine's own limits (internal modes); default from the host's below
    accel = 400000                # pulses/s^2 (decel defaults to accel)
    limit_pos_enabled = true
    steps_per_unit = 400          # the host's motor tuning, for G-code programs
    max_velocity = 50             # units/s
    max_accel = 500               # units/s^2

    [host]
    link = "usb"                  # usb or ethernet
    prefill = 64                  # slots queued before the start, and the level the host keeps
    units = "mm"                  # machine units of G-code programs: mm or inch
    feed_override = 1.0           # factor on the programmed feeds
    path_mode = "exact_stop"      # or "blend": corners at the junction-deviation speed
    path_tolerance = 0.05         # junction deviation for blend [units]
    arc_tolerance = 0.01          # largest chord error of arcs [units]
    allow_unsupported = false     # true: an unsupported word skips its line (listed) instead of an error

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
from cosim.controllers.pokeys.gcode import UNITS, load_program
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.job import JobWatch
from cosim.controllers.pokeys.limits import AXIS_NAMES
from cosim.controllers.pokeys.pathplan import MODES, HostAxis, PathSettings, PlannedJob, plan_toolpath
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.machine.families.pokeys_figures import declare_figures
from cosim.scenario import Run
from cosim.validate import positive

AXIS_KEYS = ("max_speed_hz", "accel", "decel", "limit_pos_enabled", "limit_neg_enabled", "home_enabled",
             "invert_direction", "invert_homing")
HOST_AXIS_UNITS = {"steps_per_unit": "steps/unit", "max_velocity": "units/s", "max_accel": "units/s^2"}
HOST_AXIS_KEYS = tuple(HOST_AXIS_UNITS)
GCODE_AXES = ("x", "y", "z")


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
        job: PlannedJob | None = None
        if programs:
            if moves:
                raise ConfigurationError(f"{document.file}: move: a machine runs either a G-code [[program]] or "
                                         "[[move]] tables, not both")
            job = self._gcode_job(controller, programs, host, base=base)
            counts = job.counts
            run.sim.trace.meta["gcode"] = {"file": str(programs[0].data.get("file")), "notes": list(job.notes),
                                           "skipped": list(job.skipped), "end_steps": list(job.end_steps)}
            for note in [*job.notes, *(f"skipped: {line}" for line in job.skipped)]:
                run.note(note)
        else:
            for key in ("units", "feed_override", "path_mode", "path_tolerance", "arc_tolerance",
                        "allow_unsupported"):
                if host.has(key):
                    raise ConfigurationError(f"{host.file}: {host.key(key)}: G-code settings need a G-code "
                                             "[[program]]")
            counts = self._move_job(controller, moves)
        with host.at():
            app = HostApp(run.sim, controller, to_entries(counts), link=link, prefill_slots=prefill)
        watch = JobWatch(run.sim, controller, slots=len(counts), outputs=job.outputs if job else ())
        declare_figures(run, controller, app, watch, counts, job)

    def _move_job(self, controller: PulseEngine, tables: list[Table]) -> list[tuple[int, ...]]:
        moves = []
        for table in tables:
            target = table.raw("target")
            speed = table.raw("speed_hz", None)
            accel = table.raw("accel", None)
            with table.at():
                moves.append(Move(tuple(target) if isinstance(target, list) else target, speed_hz=speed, accel=accel))
        return plan(moves, controller.config.axes) if moves else []

    def _gcode_job(self, controller: PulseEngine, programs: list[Table], host: Table, *, base: Path) -> PlannedJob:
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
        for name in GCODE_AXES:
            values = self.host_axes.get(name, {})
            missing = [key for key in HOST_AXIS_KEYS if key not in values]
            if missing:
                raise ConfigurationError(f"{self.axes_table.file}: {self.axes_table.key(name)}.{missing[0]} is "
                                         f"missing (a G-code program needs {', '.join(HOST_AXIS_KEYS)} on the "
                                         f"{', '.join(GCODE_AXES)} axes)")
            with self.axes_table.at(name):
                axes.append(HostAxis(**values, name=name))
        with table.at("file"):
            toolpath = load_program(path, units=units, allow_unsupported=allow)
        return plan_toolpath(toolpath, axes, settings=settings, n_axes=len(controller.axis_names),
                             max_pulses_per_slot=controller.device.max_pulses_per_slot)


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
