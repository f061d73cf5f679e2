"""PoKeys jogging past a limit: jogging overrides the limit switches, so the axis runs through an enabled limit.

    x.limit_pos   ________|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾      trips at ``limit_at``
    x.step        ...................            pulses go on: limits are ignored while jogging
    state         10 ......................      jogging, never 100

Checks: pulses go on for more than 100 ms after the trip and the engine stays in state 10 (the
jog is stopped at 500 ms). The same input in buffer mode stops the engine (``pokeys_limit``).
"""

from __future__ import annotations

from cosim.checks import Duration, EdgeRef, IntervalsAbove, PulseRef, ValueAt
from cosim.controllers.pokeys import AxisConfig, EngineConfig, EngineState, PulseEngine
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("jog_hz", 10_000, "Hz", (1, 25_000), "jog speed"),
    Param("limit_at", 2_000, "pulses", (1, 100_000), "x position at which limit+ trips"),
)
UNTIL = "600 ms"


def scenario(run: Run) -> None:
    p = run.p
    x = AxisConfig(max_speed_hz=25_000, accel=1_000_000, decel=1_000_000, limit_pos_enabled=True,
                   limit_neg_enabled=True)
    engine = PulseEngine(run.sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig())))
    PositionSwitch(run.sim, engine.steps[0], engine.switches.limit_pos[0], lambda pos: pos >= p.limit_at)
    engine.jog(0, p.jog_hz)
    run.run_until(run.sim.ticks("500 ms"))
    engine.jog(0, 0)  # stop jogging at 500 ms (ramps down)

    run.check(Duration(EdgeRef("pokeys.x.limit_pos", 1), PulseRef("pokeys.x.step", "last"), min=run.sim.ticks("100 ms"),
                       name="pulses go on more than 100 ms after the limit trips"))
    run.check(IntervalsAbove("pokeys.state", int(EngineState.JOGGING), name="never stopped by the limit (state <= 10)"))
    run.check(ValueAt("pokeys.state", None, 10, name="still jogging"))
    run.figure("travel_past_limit", lambda: float(engine.steps[0].position - p.limit_at), "pulses")
