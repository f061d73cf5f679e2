"""PoKeys jogging past a limit: jogging overrides the limit switches, so the axis runs through an enabled limit.

    x.limit_pos   ________|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾      trips at ``limit_at``
    x.step        ...................            pulses go on: limits are ignored while jogging
    state         10 ......................      jogging, never 100

The hazard: ``pokeys_limit``'s rules for a limit trip (no pulse after the slot boundary at which
the trip is seen; the engine stopped in state 100) both fail: pulses go on for hundreds of ms and
the engine stays in state 10 (the jog is stopped at 500 ms). Verdict HAZARD SHOWN. The same input
in buffer mode stops the engine (``pokeys_limit``, where the same rules pass).
"""

from __future__ import annotations

from cosim.controllers.pokeys import AxisConfig, EngineConfig, PulseEngine
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.scenario import Param, Run
from cosim.scenarios.pokeys_limit import stop_at_limit

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

    after_pulses, stopped = stop_at_limit(engine)
    shows = "jogging ignores the limit switches: the axis runs through an enabled limit+"
    run.hazard(after_pulses, shows=shows)
    run.hazard(stopped, shows=shows)
    run.figure("travel_past_limit", lambda: float(engine.steps[0].position - p.limit_at), "pulses")
