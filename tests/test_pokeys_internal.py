"""PoKeys internal controller: position and speed control through the slot buffer, jogging, the 10 ms hazard.

x: max speed 10 kHz (10 pulses/slot), acceleration = deceleration = 1e6 pulses/s^2 (1 pulse/slot^2).

    move_to(100):  pulses per slot  1 2 3 4 5 6 7 8 9 10 9 8 7 6 5 4 3 2 1   (sum 100, slots 0..18)
    buffer level:  10 (the controller stays 10 slots ahead) until slot 18 is produced (at 8 ms), then drains:
                   9 after the 9 ms slot ... 0 after the 18 ms slot
"""

from __future__ import annotations

import numpy as np
import pytest

from cosim.controllers.pokeys import AxisConfig, EngineConfig, EngineState, PulseEngine
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
X = AxisConfig(max_speed_hz=10_000, accel=1_000_000, decel=1_000_000)


def _engine(sim: Simulation) -> PulseEngine:
    return PulseEngine(sim, EngineConfig(axes=(X, X, AxisConfig())))


def _per_slot(sim: Simulation, axis: str = "x") -> list[int]:
    seg = sim.trace.segments(f"pokeys.{axis}.step")
    signed = np.where(seg["dir"] == 1, seg["count"], -seg["count"])
    slots = (seg["t0"] // MS).tolist()
    out = [0] * (max(slots) + 1 if slots else 0)
    for k, c in zip(slots, signed.tolist(), strict=True):
        out[k] = c
    return out


def test_internal_position_move_is_a_trapezoid_quantised_to_slots(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.move_to((100, -37, None))
    sim.run(until=40 * MS)
    assert _per_slot(sim) == [*range(1, 11), *range(9, 0, -1)]
    y = _per_slot(sim, "y")
    assert sum(y) == -37 and max(np.abs(np.diff([0, *y, 0]))) <= 2  # 1 pulse/slot^2 plus the carried remainder
    assert engine.status().positions == (100, -37, 0)
    assert engine.state == EngineState.INTERNAL


def test_internal_modes_use_the_buffer_so_its_level_moves(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.move_to((100, 0, 0))
    sim.run(until=40 * MS)
    t, level = sim.trace.edges("pokeys.buffer_level")
    assert level.max() == engine.config.internal_lookahead_slots == 10
    assert [int(level[t <= k * MS][-1]) for k in (0, 5, 9, 10, 15, 18, 19)] == [10, 10, 9, 8, 3, 0, 0]


def test_internal_speed_control_ramps_to_the_speed_and_reverses(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.run_at((5_000, None, None))
    sim.call_at(10 * MS + 1, Priority.HOST, lambda: engine.run_at((-3_000, None, None)))
    sim.run(until=40 * MS)
    per_slot = _per_slot(sim)
    assert per_slot[:10] == [1, 2, 3, 4, 5, 5, 5, 5, 5, 5]
    # the new speed acts on the slots produced after 10 ms: the 10 already queued (11..20) still run at 5
    assert per_slot[10:30] == [5] * 11 + [4, 3, 2, 1, 0, -1, -2, -3, -3]


def test_speed_is_limited_by_the_axis_maximum(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.run_at((25_000, 0, 0))  # axis maximum is 10 kHz
    engine.run_at((None, -24_000, None))
    sim.run(until=50 * MS)
    assert max(_per_slot(sim)) == 10 and min(_per_slot(sim, "y")) == -10


def test_jogging_uses_the_speed_controller_directly_limited_by_the_axis(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.jog(0, 20_000)
    sim.run(until=30 * MS)
    assert engine.state == EngineState.JOGGING and engine.buffer.level == 0  # jogging bypasses the buffer
    assert _per_slot(sim)[:12] == [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 10, 10]


def _hazard(sim: Simulation, fix: str) -> tuple[int, int]:
    """Internal speed mode at 10 kHz, then buffer mode at 50.5 ms and a +100 move planned from the status."""
    engine = _engine(sim)
    engine.run_at((10_000, 0, 0))
    planned: list[int] = []

    def switch() -> None:
        engine.set_state(EngineState.BUFFER)
        if fix == "clear":
            engine.clear_buffer()
        if fix != "wait":
            start_job()

    def start_job() -> None:
        start = engine.status().positions
        planned.append(start[0] + 100)
        engine.fill_buffer(to_entries(plan([Move((start[0] + 100, 0, 0))], engine.config.axes, start=start)))

    sim.call_at(50 * MS + 500_000, Priority.HOST, switch)
    if fix == "wait":
        sim.call_at(60 * MS + 500_000, Priority.HOST, start_job)
    sim.run(until=120 * MS)
    return planned[0], engine.status().positions[0]


def test_switching_internal_to_buffer_at_once_emits_the_stale_slots(sim: Simulation) -> None:
    planned, final = _hazard(sim, "none")
    assert final - planned == 100  # 10 stale slots of 10 pulses ran before the host's move
    assert _per_slot(sim)[51:61] == [10] * 10


def test_clearing_the_buffer_removes_the_stale_slots(sim: Simulation) -> None:
    planned, final = _hazard(sim, "clear")
    assert final == planned
    assert _per_slot(sim)[51:53] == [1, 2]  # the host's move starts at once


def test_waiting_10_ms_lets_the_stale_slots_run_out_before_planning(sim: Simulation) -> None:
    planned, final = _hazard(sim, "wait")
    assert final == planned
    assert _per_slot(sim)[51:63] == [10] * 10 + [1, 2]


@pytest.mark.parametrize(("call", "message"), [
    (lambda e: e.move_to((1.5, 0, 0)), r"move_to axis x: target position = 1.5 is not allowed"),
    (lambda e: e.run_at((0, 30_000, 0)), r"run_at axis y: speed_hz = 30000 is not allowed \(allowed: -25000..25000"),
    (lambda e: e.jog(5, 100), r"jog: axis = 5 is not allowed \(allowed: 0..2"),
    (lambda e: e.move_to((1, 2)), r"move_to values = 2 is not allowed \(allowed: 3"),
])
def test_bad_internal_commands_are_refused(sim: Simulation, call: object, message: str) -> None:
    engine = _engine(sim)
    with pytest.raises(ConfigurationError, match=message):
        call(engine)  # type: ignore[operator]


def test_internal_commands_are_refused_in_an_error_state(sim: Simulation) -> None:
    engine = _engine(sim)
    engine.switches.emergency.set(1)
    sim.run(until=1)
    with pytest.raises(ConfigurationError, match=r"engine state for move_to = 101 is not allowed"):
        engine.move_to((10, 0, 0))
