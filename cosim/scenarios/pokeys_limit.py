"""PoKeys limit switch trip: a buffered move runs into the x limit+ switch; stop distance and time reported.

The switch is read at slot starts only, so the slot that is running when the switch trips
finishes, and the engine stops hard (state 100) at the next slot boundary::

    slot          |  s      |  s+1    |
    x.step        |.........|            no pulse after the boundary at which the trip is seen
    x.limit_pos   ____|‾‾‾‾‾‾‾‾‾‾‾‾‾‾    trips at the pulse that reaches ``limit_at``
    state         2 ........|100

Checks: the last pulse and the stop state come within one slot of the trip; figures: the stop
distance past the switch [pulses] and the stop time [us].
"""

from __future__ import annotations

from cosim.checks import Check, Duration, EdgeRef, PulseRef, ValueAt
from cosim.controllers.pokeys import AxisConfig, EngineConfig, PulseEngine
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("speed_hz", 20_000, "Hz", (1, 25_000), "speed of the move towards the switch"),
    Param("limit_at", 5_000, "pulses", (1, 1_000_000), "x position at which limit+ trips"),
    Param("limit_enabled", True, "", None, "limit+ of x enabled (off: the axis runs through)"),
)
UNTIL = "1 s"


def scenario(run: Run) -> None:
    p = run.p
    x = AxisConfig(max_speed_hz=p.speed_hz, accel=1_000_000, decel=1_000_000, limit_pos_enabled=p.limit_enabled)
    engine = PulseEngine(run.sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig())))
    PositionSwitch(run.sim, engine.steps[0], engine.switches.limit_pos[0], lambda pos: pos >= p.limit_at)
    HostApp(run.sim, engine, to_entries(plan([Move((4 * p.limit_at, 0, 0))], engine.config.axes)), link="usb")

    after_pulses, stopped = stop_at_limit(engine)
    run.check(after_pulses)
    run.check(Duration(EdgeRef("pokeys.x.limit_pos", 1, which="first"), EdgeRef("pokeys.state", 100),
                       max=engine.slot_ticks, name="state 100 at that slot boundary"))
    run.check(stopped)

    def trip_t() -> int:
        t, v = run.sim.trace.edges("pokeys.x.limit_pos")
        return int(t[v == 1][0]) if (v == 1).any() else 0

    run.figure("stop_distance_pulses", lambda: engine.steps[0].position - p.limit_at, "pulses")
    us = run.sim.ticks("1 us")
    run.figure("stop_time_us", lambda: (int(run.sim.trace.pulses("pokeys.x.step")[0][-1]) - trip_t()) / us, "us")


def stop_at_limit(engine: PulseEngine) -> tuple[Check, Check]:
    """The rules of a limit trip on x (shared with ``pokeys_jog_limit``, where they fail): no pulse after
    the slot boundary at which the trip is seen, and the engine stopped (state 100) at the end."""
    return (Duration(EdgeRef("pokeys.x.limit_pos", 1, which="first"), PulseRef("pokeys.x.step", "last"),
                     max=engine.slot_ticks, name="no pulse after the slot boundary at which the trip is seen"),
            ValueAt("pokeys.state", None, 100, name="engine stopped by the limit switch"))
