"""PoKeys engine slots: 1 ms slots, constant frequency inside a slot, direction outputs, counters.

    slot k:    |k ms                                           |(k+1) ms
    dir:       changes here (if the direction bit changed)
    step:      .....|5 us (dir_setup)   |+1ms/n   |+2ms/n ...   n pulses evenly spread
    counter:   += n at the slot start (the pulses the slot commits)
"""

from __future__ import annotations

import numpy as np
import pytest

from cosim.controllers.pokeys import (
    SLOT_NS,
    AxisConfig,
    AxisState,
    EngineConfig,
    EngineState,
    PulseEngine,
    encode_entry,
)
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation

MS = 1_000_000


def _pulses(sim: Simulation, axis: str = "x") -> tuple[list[int], list[int]]:
    t, d = sim.trace.pulses(f"pokeys.{axis}.step")
    return t.tolist(), d.tolist()


def test_buffer_entry_sets_the_pulses_of_the_slot_it_starts(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((25, 3, 0)), encode_entry((0, 1, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=3 * MS)
    t, d = _pulses(sim, "x")
    assert t == [5_000 + k * 40_000 for k in range(25)]  # 25 kHz: evenly spread, first at dir_setup
    assert d == [1] * 25
    assert _pulses(sim, "y")[0] == [5_000, 338_333, 671_666, MS + 5_000]  # pulse k at t0 + (k*1ms)//n
    assert _pulses(sim, "z")[0] == []


def test_pulse_width_and_direction_setup_are_configurable(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(pulse_width_ns=2_000, dir_setup_ns=12_000))
    engine.fill_buffer([encode_entry((2, 0, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=MS)
    assert _pulses(sim)[0] == [12_000, 512_000]
    assert sim.trace.info["pokeys.x.step"].pulse_width == 2_000


def test_direction_bit_activates_the_direction_output_at_the_slot_start(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry(c) for c in [(2, 0, 0), (-2, 0, 0), (0, 0, 0), (3, 0, 0)]])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=5 * MS)
    t, v = sim.trace.edges("pokeys.x.dir")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (MS, 1), (2 * MS, 0)]  # bit follows the entry
    assert _pulses(sim) == ([5_000, 505_000, MS + 5_000, MS + 505_000, 3 * MS + 5_000, 3 * MS + 338_333,
                             3 * MS + 671_666], [1, 1, 0, 0, 1, 1, 1])
    assert engine.status().positions == (3, 0, 0)


def test_direction_bit_on_a_zero_count_still_drives_the_output(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([bytes([0x80, 0, 0])])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=MS)
    assert sim.trace.edges("pokeys.x.dir")[1].tolist() == [0, 1]
    assert _pulses(sim)[0] == []


def test_invert_direction_flips_the_output_not_the_counter(sim: Simulation) -> None:
    axes = (AxisConfig(invert_direction=True), AxisConfig(), AxisConfig())
    engine = PulseEngine(sim, EngineConfig(axes=axes))
    engine.fill_buffer([encode_entry((-4, -4, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=MS)
    assert sim.trace.edges("pokeys.x.dir")[1].tolist() == [1, 0]  # inverted: idle 1, negative 0
    assert sim.trace.edges("pokeys.y.dir")[1].tolist() == [0, 1]
    assert engine.status().positions == (-4, -4, 0)


def test_position_counters_equal_the_pulses_and_are_recorded_per_slot(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    counts = [(k % 26, -(k % 7), 25 - k % 26) for k in range(100)]
    engine.fill_buffer([encode_entry(c) for c in counts])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=101 * MS)
    for a, name in enumerate("xyz"):
        t, v = sim.trace.edges(f"pokeys.{name}.position")
        expected = np.cumsum([c[a] for c in counts])
        assert engine.status().positions[a] == expected[-1] == engine.steps[a].position
        changed = [k for k in range(100) if counts[k][a]]
        assert t[1:].tolist() == [k * MS for k in changed]
        assert v[1:].tolist() == expected[changed].tolist()


def test_stopped_engine_emits_nothing_and_keeps_the_buffer(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((5, 5, 5))] * 10)
    sim.run(until=20 * MS)
    assert _pulses(sim)[0] == [] and engine.buffer.level == 10
    assert engine.status().axis_states == (AxisState.STOPPED,) * 3


def test_state_change_acts_from_the_next_slot_and_the_running_slot_finishes(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((2, 0, 0))] * 10)
    engine.set_state(EngineState.BUFFER)
    sim.call_at(2 * MS + 100_000, 30, lambda: engine.set_state(EngineState.STOPPED))
    sim.run(until=10 * MS)
    assert _pulses(sim)[0] == [5_000, 505_000, MS + 5_000, MS + 505_000, 2 * MS + 5_000, 2 * MS + 505_000]
    assert sim.trace.edges("pokeys.state")[1].tolist() == [0, 2, 0]
    assert engine.buffer.level == 7


def test_empty_buffer_in_buffer_mode_emits_nothing_and_is_an_underrun_when_data_ends_it(sim: Simulation) -> None:
    """Slots 0, 1 have data; 2..5 find the buffer empty; 6 has data again (an underrun of 4 slots); 7.. are the end."""
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((1, 0, 0))] * 2)
    engine.set_state(EngineState.BUFFER)
    sim.call_at(5 * MS + 300_000, 30, lambda: engine.fill_buffer([encode_entry((1, 0, 0))]))
    sim.run(until=12 * MS)
    assert _pulses(sim)[0] == [5_000, MS + 5_000, 6 * MS + 5_000]
    assert [(u.t_start, u.t_end, u.length, u.slots) for u in engine.underruns] == [(2 * MS, 6 * MS, 4 * MS, 4)]
    t, v = sim.trace.edges("pokeys.underrun")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (2 * MS, 1), (6 * MS, 0)]


def test_empty_slots_before_the_first_data_after_the_last_or_ended_by_a_state_change_are_no_underrun(
        sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.set_state(EngineState.BUFFER)  # empty from 0 ms: the job has not started
    sim.call_at(3 * MS + 1, 30, lambda: engine.fill_buffer([encode_entry((1, 0, 0))]))
    sim.call_at(6 * MS + 1, 30, lambda: engine.set_state(EngineState.STOPPED))  # empty 5..6 ms, then stopped
    sim.call_at(7 * MS + 1, 30, lambda: engine.fill_buffer([encode_entry((2, 0, 0))]))
    sim.call_at(7 * MS + 1, 30, lambda: engine.set_state(EngineState.BUFFER))  # data at 8 ms, none after
    sim.run(until=20 * MS)
    assert _pulses(sim)[0] == [4 * MS + 5_000, 8 * MS + 5_000, 8 * MS + 505_000]
    assert engine.underruns == [] and sim.trace.edges("pokeys.underrun")[1].tolist() == [0]


def test_state_codes_are_recorded_on_the_state_signal(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.set_state(EngineState.BUFFER)
    engine.set_state(1)
    engine.set_state(EngineState.JOGGING)
    engine.set_state(0)
    assert sim.trace.edges("pokeys.state")[1].tolist() == [0, 2, 1, 10, 0]
    assert SLOT_NS == MS


@pytest.mark.parametrize("state", [11, 20, 21, 100, 101, 3])
def test_only_host_states_can_be_set(sim: Simulation, state: int) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=rf"engine state = {state} is not allowed \(allowed: 0 stopped"):
        engine.set_state(state)


def test_reconfigure_applies_switch_enables_direction_inversion_and_limits_from_now_on(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.switches.limit_pos[1].set(1)  # tripped, but not enabled
    engine.fill_buffer([encode_entry((2, 0, 0))] * 10)
    engine.set_state(EngineState.BUFFER)
    y_on = (AxisConfig(invert_direction=True), AxisConfig(limit_pos_enabled=True), AxisConfig())
    sim.call_at(3 * MS + 100_000, 30, lambda: engine.reconfigure(EngineConfig(axes=y_on)))
    sim.run(until=10 * MS)
    assert sim.trace.edges("pokeys.state")[1].tolist() == [0, 2, 100]  # the enabled limit is seen at 4 ms
    assert sim.trace.edges("pokeys.state")[0].tolist()[-1] == 4 * MS
    assert sim.trace.edges("pokeys.x.dir")[0].tolist() == [0, 3 * MS + 100_000]  # inverted at once: idle level 1
    assert engine.status().positions == (8, 0, 0) and engine.config.axes[1].limit_pos_enabled


@pytest.mark.parametrize(("fields", "message"), [
    ({"model": "57E"}, r"reconfigure model = '57E' is not allowed \(allowed: '56E' \(fixed when the engine"),
    ({"pulse_width_ns": 2_000}, r"reconfigure pulse_width_ns = 2000 is not allowed \(allowed: 5000 \(fixed"),
])
def test_reconfigure_keeps_the_model_and_the_pulse_width(sim: Simulation, fields: dict[str, object],
                                                         message: str) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=message):
        engine.reconfigure(EngineConfig(**fields))  # type: ignore[arg-type]


def test_reconfigured_emergency_polarity_keeps_a_healthy_input_healthy(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.set_state(EngineState.BUFFER)
    engine.reconfigure(EngineConfig(emergency_polarity=1))
    assert engine.switches.emergency.value == 1  # healthy for polarity 1 (low = emergency)
    sim.call_at(2 * MS + 1, 30, lambda: engine.switches.emergency.set(0))
    sim.run(until=5 * MS)
    assert engine.state == EngineState.STOP_EMERGENCY and sim.trace.edges("pokeys.state")[0].tolist()[-1] == 3 * MS
