"""The PoKeys pulse engine in a machine file, fed by a host that streams a planned job.

::

    [controller]
    family = "pokeys"
    model = "56E"                 # 56E, 56U, 57E, 57CNC
    dir_setup = "5 us"            # direction set-up before the first pulse of a slot
    pulse_width = "5 us"
    [controller.axis.x]           # x, y, z (the 57CNC: up to 8 axes)
    max_speed_hz = 24000
    accel = 400000                # pulses/s^2 (decel defaults to accel)
    limit_pos_enabled = true

    [host]
    link = "usb"                  # usb or ethernet
    prefill = 64                  # slots queued before the start, and the level the host keeps

    [[move]]                      # straight moves, planned into slots under the axes' limits
    target = [12000, -9000, 6000] # pulses, one per axis
    speed_hz = 20000              # optional: limit of the dominant axis

Ports: ``stepper = { axis = "x" }`` and ``switches = { axis = "x" }`` (an axis name or index).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cosim.controllers.pokeys import AxisConfig, EngineConfig, PulseEngine
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.limits import AXIS_NAMES
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.errors import ConfigurationError
from cosim.machine.document import Table
from cosim.scenario import Run

AXIS_KEYS = ("max_speed_hz", "accel", "decel", "limit_pos_enabled", "limit_neg_enabled", "home_enabled",
             "invert_direction", "invert_homing")


class PoKeysFamily:
    """``family = "pokeys"``."""

    name = "pokeys"
    tables: tuple[str, ...] = ("host", "move")

    def controller(self, run: Run, table: Table, *, base: Path) -> PulseEngine:
        model = table.text("model", "56E")
        with table.at("model"):
            defaults = EngineConfig.for_model(model)
        names = [a.name for a in defaults.axes]
        axes = table.table("axis")
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
        if programs:
            raise ConfigurationError(f"{programs[0].file}: program: a PoKeys machine runs [[move]] jobs "
                                     "(G-code programs are not supported yet)")
        host = document.table("host")
        moves = []
        for table in document.tables("move"):
            target = table.raw("target")
            speed = table.raw("speed_hz", None)
            accel = table.raw("accel", None)
            with table.at():
                moves.append(Move(tuple(target) if isinstance(target, list) else target, speed_hz=speed, accel=accel))
        link = host.text("link", "usb", choices=("usb", "ethernet"))
        prefill = host.integer("prefill", 64, low=1, high=controller.buffer.depth_slots)
        with host.at():
            counts = plan(moves, controller.config.axes) if moves else []
            app = HostApp(run.sim, controller, to_entries(counts), link=link, prefill_slots=prefill)
        run.figure("slots", len(counts))
        run.figure("pulses", sum(abs(c) for slot in counts for c in slot))
        run.figure("fill_commands", lambda: len(app.fills))
        run.figure("underruns", lambda: len(controller.underruns))
        ms = run.sim.ticks(1, "ms")
        run.figure("job_done_ms", lambda: (app.t_buffer_mode or 0) / ms + len(counts), "ms")


def _fields(config: AxisConfig) -> dict[str, Any]:
    return {k: getattr(config, k) for k in AXIS_KEYS}


def _ns(value: Any, name: str) -> int:
    from cosim.timebase import TimeBase

    return TimeBase().ticks(value, name=name) if isinstance(value, str) else value


__all__ = ["AXIS_NAMES", "PoKeysFamily"]
