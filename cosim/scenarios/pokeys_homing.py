"""PoKeys homing: search at 10 % of max speed, back off at 1 % until the switch releases, counter reset, stop.

The x axis starts ``start_pulses`` above its home switch (which covers x <= 0)::

    x.home        __________|‾‾‾‾‾‾‾‾‾‾‾‾‾|______
    x.step        ..........  (search -)    . . (back +)      none after the reset
    axis_state    12 ..................13...............10
    x.position    counts down ......................... 0   (the axis stays where the switch released)

Checks: the counter is 0 and the engine is in state 20; the axis stands where the switch released
(no return to 0). Figures: homing time and the final counter.
"""

from __future__ import annotations

from cosim.checks import ValueAt
from cosim.controllers.pokeys import AxisConfig, EngineConfig, PulseEngine
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("max_speed_hz", 25_000, "Hz", (1, 25_000), "maximum speed of x"),
    Param("start_pulses", 1_000, "pulses", (0, 1_000_000), "distance from the home switch at the start"),
    Param("homing_speed_pct", 10, "%", (1, 100), "search speed"),
    Param("homing_return_pct", 1, "%", (1, 100), "back-off speed"),
)
UNTIL = "2 s"


def scenario(run: Run) -> None:
    p = run.p
    x = AxisConfig(max_speed_hz=p.max_speed_hz, home_enabled=True)
    engine = PulseEngine(run.sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig()),
                                               homing_speed_pct=p.homing_speed_pct,
                                               homing_return_pct=p.homing_return_pct))
    engine.set_position(0, p.start_pulses)
    PositionSwitch(run.sim, engine.steps[0], engine.switches.home[0], lambda step: p.start_pulses + step <= 0)
    engine.start_homing([0])

    run.check(ValueAt("pokeys.x.position", None, 0, name="position counter reset to 0"))
    run.check(ValueAt("pokeys.state", None, 20, name="homing finished (state 20)"))
    run.check(ValueAt("pokeys.x.step", None, 1 - p.start_pulses,
                      name="the axis stays where the switch released (no move back to 0)"))

    def homing_ms() -> float:
        t, v = run.sim.trace.edges("pokeys.state")
        return float(t[v == 20][0]) / 1e6 if (v == 20).any() else float("nan")

    run.figure("homing_time_ms", homing_ms, "ms")
    run.figure("final_counter", lambda: float(engine.status().positions[0]), "pulses")
