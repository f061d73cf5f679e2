"""PoKeys internal-to-buffer hazard: switching to buffer mode at once runs the internal controller's stale slots.

Internal speed control runs x at ``speed_hz`` with 10 slots queued ahead. At 50.5 ms the host
switches to buffer mode, reads the position P from the status and queues a move to P + 100. The
10 stale slots still in the buffer run first, so the axis ends 10 x 10 = 100 pulses too far::

    buffer        [10 stale internal slots][host move +100]
    x.position    P ........ P+100 ........ P+200   (the host expected P+100)

``fix``: ``none`` (the hazard), ``clear`` (clear-buffer command at the switch) or ``wait`` (wait
10 ms for the buffer to empty, then read P and plan). ``pokeys_stale_slots_fix`` runs the fix.
The hazard: the healthy rule "x ends at the planned position" fails without a fix, 100 pulses
past it (verdict HAZARD SHOWN; with a fix the hazard is missed).
"""

from __future__ import annotations

from cosim.checks import ValueAt
from cosim.controllers.pokeys import AxisConfig, EngineConfig, EngineState, PulseEngine
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("fix", "none", "", ("none", "clear", "wait"), "what the host does when it switches to buffer mode"),
    Param("speed_hz", 10_000, "Hz", (1_000, 25_000), "internal speed-control speed (multiple of 1 kHz)"),
)
UNTIL = "200 ms"


def scenario(run: Run) -> None:
    run.hazard(stale_slots_run(run), shows="switching to buffer mode at once runs the internal controller's "
                                           "stale slots first: x ends past the position the host planned")


def stale_slots_run(run: Run) -> ValueAt:
    """The run: internal speed mode, switch at 50.5 ms, a +100 move (shared with the fix scenario).

    Returns the healthy rule, "x ends at the planned position", for the caller to declare."""
    p = run.p
    x = AxisConfig(max_speed_hz=25_000, accel=1_000_000, decel=1_000_000)
    engine = PulseEngine(run.sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig())))
    engine.run_at((p.speed_hz, 0, 0))
    run.run_until(run.sim.ticks("50.5 ms"))
    queued = engine.buffer.level
    engine.set_state(EngineState.BUFFER)
    if p.fix == "clear":
        engine.clear_buffer()
    if p.fix == "wait":
        run.run_until(run.sim.ticks("60.5 ms"))
    start = engine.status().positions
    planned = start[0] + 100
    engine.fill_buffer(to_entries(plan([Move((planned, 0, 0))], engine.config.axes, start=start)))
    run.figure("planned_position", planned, "pulses")
    run.figure("stale_slots", queued if p.fix == "none" else 0, "slots")
    run.figure("final_error", lambda: float(engine.status().positions[0] - planned), "pulses")
    return ValueAt("pokeys.x.position", None, planned, name=f"x ends at the planned position {planned}")
