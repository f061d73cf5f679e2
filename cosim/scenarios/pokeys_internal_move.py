"""PoKeys internal position control: a trapezoid quantised to 1 ms slots, produced through the slot buffer.

``move_to`` x and y; every slot's speed is within ``accel`` of the previous one and at most the
maximum speed, and the ramp down lands exactly on the target. The internal controller keeps 10
slots queued in the buffer, so the buffer level moves in this mode too::

    x pulses/slot   /‾‾‾‾‾‾‾‾‾‾‾\\          ramp, cruise at max speed, ramp down
    buffer_level    10 ‾‾‾‾‾‾‾‾‾‾‾‾\\_0

Checks: at most ``max_speed_hz``/1000 pulses per slot, the targets reached exactly, the buffer
never more than 10 slots deep, and the move no longer than the continuous trapezoid plus 2 slots.
"""

from __future__ import annotations

from math import ceil

from cosim.checks import Duration, IntervalsAbove, PulseRef, PulsesPerWindow, ValueAt
from cosim.controllers.pokeys import EngineConfig, PulseEngine, uniform_axes
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("target_x", 10_000, "pulses", (-1_000_000, 1_000_000), "x target"),
    Param("target_y", -4_000, "pulses", (-1_000_000, 1_000_000), "y target"),
    Param("max_speed_hz", 20_000, "Hz", (1_000, 25_000), "maximum speed (multiple of 1 kHz)"),
    Param("accel", 200_000, "pulses/s^2", (1, 100_000_000), "acceleration and deceleration"),
)
UNTIL = "2 s"


def scenario(run: Run) -> None:
    p = run.p
    config = EngineConfig(axes=uniform_axes(max_speed_hz=p.max_speed_hz, accel=p.accel, decel=p.accel))
    engine = PulseEngine(run.sim, config)
    engine.move_to((p.target_x, p.target_y, None))

    per_slot = p.max_speed_hz // 1000
    for axis, target in (("x", p.target_x), ("y", p.target_y)):
        run.check(PulsesPerWindow(f"pokeys.{axis}.step", per_slot, engine.slot_ticks,
                                  name=f"{axis}: at most {per_slot} pulses per slot (max speed)"))
        run.check(ValueAt(f"pokeys.{axis}.position", None, target, name=f"{axis}: target {target} reached"))
    run.check(IntervalsAbove("pokeys.buffer_level", config.internal_lookahead_slots,
                             name="internal controller keeps at most 10 slots queued"))
    distance, v, a = abs(p.target_x), p.max_speed_hz, p.accel
    ideal_s = distance / v + v / a if distance * a >= v * v else 2 * (distance / a) ** 0.5
    bound = (ceil(ideal_s * 1000) + 2) * engine.slot_ticks
    run.check(Duration(PulseRef("pokeys.x.step", "first"), PulseRef("pokeys.x.step", "last"), max=bound,
                       name="x move within the continuous trapezoid time + 2 slots"))
    run.figure("ideal_move_ms", ideal_s * 1000, "ms")
    run.figure("peak_buffer_level", lambda: float(run.sim.trace.edges("pokeys.buffer_level")[1].max()), "slots")
