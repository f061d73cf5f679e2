"""PoKeys emergency input: a 3-axis buffered job is cut at the next slot boundary after the emergency input trips.

    slot          |  s      |  s+1
    *.step        |.........|             every axis: no pulse after the boundary
    emergency     ____|‾‾‾‾‾‾‾‾‾‾‾‾       scripted at ``emergency_at_us`` (1 = emergency, NC wiring)
    state         2 ........|101

Checks: on every axis the last pulse comes within one slot of the emergency edge; state 101.
"""

from __future__ import annotations

from cosim.checks import Duration, EdgeRef, PulseRef, ValueAt
from cosim.controllers.pokeys import AXES, EngineConfig, PulseEngine, uniform_axes
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.controllers.scripted import play
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("emergency_at_us", 150_500, "us", (0, 1_000_000), "when the emergency input trips"),
    Param("max_speed_hz", 25_000, "Hz", (1, 25_000), "maximum speed of every axis"),
)
UNTIL = "500 ms"


def scenario(run: Run) -> None:
    p = run.p
    config = EngineConfig(axes=uniform_axes(max_speed_hz=p.max_speed_hz, accel=500_000, decel=500_000))
    engine = PulseEngine(run.sim, config)
    HostApp(run.sim, engine, to_entries(plan([Move((8_000, -6_000, 4_000))], config.axes)), link="ethernet")
    play(run.sim, [(run.sim.ticks(p.emergency_at_us, "us"), {engine.switches.emergency: 1})])

    edge = EdgeRef("pokeys.emergency", 1)
    for axis in AXES:
        run.check(Duration(edge, PulseRef(f"pokeys.{axis}.step", "last"), max=engine.slot_ticks,
                           name=f"{axis}: no pulse after the slot boundary at which the emergency is seen"))
    run.check(ValueAt("pokeys.state", None, 101, name="engine stopped by the emergency input"))
    run.figure("positions_at_stop", lambda: float(engine.status().positions[0]), "pulses (x)")
