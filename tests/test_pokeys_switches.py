"""PoKeys switches: read at slot starts; an enabled tripped limit or the emergency input is a hard stop.

    slot:      |3 ms              |4 ms              |5 ms
    x.step:    | . . . . . . . . .| (none)
    limit:          trips at 3.5 ms ^ seen at 4 ms -> state 100, no pulse from 4 ms on
    last pulse: 3 ms + 5 us + 9 * 100 us = 3.905 ms

Inputs are normally closed: level 1 = tripped (the emergency input: 1 = emergency unless polarity 1).
"""

from __future__ import annotations

from cosim.controllers.pokeys import (
    AxisConfig,
    AxisState,
    EngineConfig,
    EngineState,
    PulseEngine,
    encode_entry,
)
from cosim.controllers.scripted import play
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
LIMITS_ON = AxisConfig(limit_pos_enabled=True, limit_neg_enabled=True)


def _engine(sim: Simulation, **config: object) -> PulseEngine:
    engine = PulseEngine(sim, EngineConfig(axes=(LIMITS_ON, LIMITS_ON, LIMITS_ON), **config))  # type: ignore[arg-type]
    engine.fill_buffer([encode_entry((10, 4, 0))] * 20)
    engine.set_state(EngineState.BUFFER)
    return engine


def _last_pulse(sim: Simulation, axis: str = "x") -> int:
    return int(sim.trace.pulses(f"pokeys.{axis}.step")[0][-1])


def test_limit_trip_stops_pulses_at_the_next_slot_boundary(sim: Simulation) -> None:
    engine = _engine(sim)
    play(sim, [(3 * MS + 500_000, {engine.switches.limit_pos[0]: 1})])
    sim.run(until=10 * MS)
    assert _last_pulse(sim) == 3 * MS + 5_000 + 9 * 100_000
    assert _last_pulse(sim, "y") == 3 * MS + 5_000 + 3 * 250_000  # every axis stops (hard stop)
    assert sim.trace.edges("pokeys.state")[0].tolist()[-1] == 4 * MS
    status = engine.status()
    assert status.engine_state == EngineState.STOP_LIMIT == 100
    assert status.axis_states == (AxisState.LIMIT, AxisState.ERROR, AxisState.ERROR)
    assert status.limit_pos == 0b001 and status.positions == (40, 16, 0)


def test_switch_change_at_a_slot_start_is_seen_only_if_it_comes_before_the_slot(sim: Simulation) -> None:
    engine = _engine(sim)
    # a plant event at 4 ms runs before the slot (PLANT_EVENT < SLOT): seen at 4 ms
    play(sim, [(4 * MS, {engine.switches.limit_neg[1]: 1})], priority=Priority.PLANT_EVENT)
    sim.run(until=10 * MS)
    assert _last_pulse(sim) == 3 * MS + 905_000


def test_switch_set_by_the_host_at_a_slot_start_is_seen_one_slot_later(sim: Simulation) -> None:
    engine = _engine(sim)
    play(sim, [(4 * MS, {engine.switches.limit_neg[1]: 1})], priority=Priority.HOST)  # after the slot
    sim.run(until=10 * MS)
    assert _last_pulse(sim) == 4 * MS + 905_000


def test_a_pulse_short_trip_between_slot_starts_is_not_seen(sim: Simulation) -> None:
    engine = _engine(sim)
    z_limit = engine.switches.limit_pos[2]
    play(sim, [(3 * MS + 100_000, {z_limit: 1}), (3 * MS + 900_000, {z_limit: 0})])
    sim.run(until=10 * MS)
    assert engine.state == EngineState.BUFFER and _last_pulse(sim) == 9 * MS + 905_000


def test_disabled_limit_switch_is_ignored(sim: Simulation) -> None:
    axes = (AxisConfig(limit_pos_enabled=True), AxisConfig(), AxisConfig())
    engine = PulseEngine(sim, EngineConfig(axes=axes))
    engine.fill_buffer([encode_entry((1, 0, 0))] * 10)
    engine.set_state(EngineState.BUFFER)
    play(sim, [(2 * MS + 1, {engine.switches.limit_neg[0]: 1, engine.switches.limit_pos[1]: 1}),
               (5 * MS + 1, {engine.switches.limit_pos[0]: 1})])
    sim.run(until=10 * MS)
    assert engine.state == EngineState.STOP_LIMIT
    assert _last_pulse(sim) == 5 * MS + 5_000


def test_emergency_input_stops_every_mode_with_state_101(sim: Simulation) -> None:
    engine = _engine(sim)
    play(sim, [(2 * MS + 700_000, {engine.switches.emergency: 1})])
    sim.run(until=10 * MS)
    assert _last_pulse(sim) == 2 * MS + 905_000
    assert engine.state == EngineState.STOP_EMERGENCY == 101
    assert engine.status().axis_states == (AxisState.ERROR,) * 3 and engine.status().emergency


def test_emergency_polarity_1_means_a_low_input_is_an_emergency(sim: Simulation) -> None:
    engine = _engine(sim, emergency_polarity=1)
    assert engine.switches.emergency.value == 1  # healthy level
    play(sim, [(1 * MS + 1, {engine.switches.emergency: 0})])
    sim.run(until=5 * MS)
    assert engine.state == EngineState.STOP_EMERGENCY and _last_pulse(sim) == MS + 905_000


def test_disabled_emergency_input_is_ignored(sim: Simulation) -> None:
    engine = _engine(sim, emergency_enabled=False)
    play(sim, [(1 * MS + 1, {engine.switches.emergency: 1})])
    sim.run(until=5 * MS)
    assert engine.state == EngineState.BUFFER


def test_stop_is_kept_until_the_host_sets_a_state_and_trips_again_while_the_switch_is_open(sim: Simulation) -> None:
    engine = _engine(sim)
    play(sim, [(MS + 1, {engine.switches.limit_pos[0]: 1})])
    sim.call_at(4 * MS + 1, Priority.HOST, lambda: engine.set_state(EngineState.BUFFER))
    sim.run(until=8 * MS)
    assert sim.trace.edges("pokeys.state")[1].tolist() == [0, 2, 100, 2, 100]
    assert _last_pulse(sim) == MS + 905_000  # no pulse in the retried slot either


def test_jogging_ignores_the_limit_switches(sim: Simulation) -> None:
    axes = (LIMITS_ON, LIMITS_ON, LIMITS_ON)
    engine = PulseEngine(sim, EngineConfig(axes=axes))
    engine.switches.limit_neg[0].set(1)
    engine.jog(0, 5_000)
    sim.run(until=20 * MS)
    assert engine.state == EngineState.JOGGING
    assert engine.status().positions[0] > 0


def test_jogging_off_a_limit_then_a_limit_stop_in_buffer_mode(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(axes=(LIMITS_ON, LIMITS_ON, LIMITS_ON)))
    PositionSwitch(sim, engine.steps[0], engine.switches.limit_neg[0], lambda p: p <= -5, position=-10)
    engine.jog(0, 5_000)  # limits ignored: drive off the switch
    sim.call_at(30 * MS + 1, Priority.HOST, lambda: engine.set_state(EngineState.STOPPED))
    sim.run(until=31 * MS)
    assert engine.switches.limit_neg[0].value == 0 and engine.state == EngineState.STOPPED
    engine.fill_buffer([encode_entry((-5, 0, 0))] * 20)
    engine.set_state(EngineState.BUFFER)
    sim.run(until=60 * MS)
    assert engine.state == EngineState.STOP_LIMIT


def test_jogging_does_not_ignore_the_emergency_input(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(axes=(LIMITS_ON, LIMITS_ON, LIMITS_ON)))
    engine.switches.limit_pos[0].set(1)
    engine.jog(0, 5_000)
    play(sim, [(10 * MS + 1, {engine.switches.emergency: 1})])
    sim.run(until=20 * MS)
    assert engine.state == EngineState.STOP_EMERGENCY
    assert _last_pulse(sim) < 11 * MS


def test_limit_stops_the_internal_controller_at_the_next_slot_start(sim: Simulation) -> None:
    """run_at 10 kHz at 1 pulse/slot^2 ramps 1, 2, 3, 4, 5, 6 pulses in the slots 0..5 ms; a trip at 5 ms + 1 is
    seen at 6 ms."""
    x = AxisConfig(limit_pos_enabled=True, accel=1_000_000, decel=1_000_000)
    engine = PulseEngine(sim, EngineConfig(axes=(x, LIMITS_ON, LIMITS_ON)))
    engine.run_at((10_000, 0, 0))
    play(sim, [(5 * MS + 1, {engine.switches.limit_pos[0]: 1})])
    sim.run(until=20 * MS)
    assert engine.state == EngineState.STOP_LIMIT
    t = sim.trace.pulses("pokeys.x.step")[0]
    assert t.size == 1 + 2 + 3 + 4 + 5 + 6  # pulses in every slot up to the one the trip falls in, none after
    assert int(t[-1]) == 5 * MS + 5_000 + (5 * MS) // 6


def test_limit_stops_an_idle_engine_too(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(axes=(LIMITS_ON, LIMITS_ON, LIMITS_ON)))
    play(sim, [(5 * MS + 1, {engine.switches.limit_pos[0]: 1})])
    sim.run(until=20 * MS)
    assert engine.state == EngineState.STOP_LIMIT
    assert sim.trace.edges("pokeys.state")[0].tolist() == [0, 6 * MS]
    assert sim.trace.pulses("pokeys.x.step")[0].size == 0
